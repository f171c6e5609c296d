"""The geometry attributes of SVG shapes, checked before svgelements reads them.

svgelements (and a browser) draw a shape whose geometry cannot be parsed only up to the
error, or not at all: ``<rect width="abc">``, ``<path d="M 1 1 L 5 x 5 Z">``, a ``nan`` in a
path or ``points`` list all left a shape out of a sensor layer without a word. Here each is one
:class:`~rotoprint.errors.CadError` naming the element (its ``id`` where it has one) and the
attribute. A shape that parses but has no geometry (``<polygon points="5,5"/>``, an empty
``d``) is legitimate SVG that draws nothing: the reader counts it (``counts["empty"]``).
"""

from __future__ import annotations

import math
import re

from ...errors import CadError

__all__ = ["check_shape_attributes", "element_name"]

_LENGTH = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([a-zA-Z%]*)\s*$")
_UNITS = {"", "px", "mm", "cm", "in", "pt", "pc", "q", "%", "em", "ex"}
_NUM = r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_TOKEN = re.compile(rf"\s*,?\s*(?:([MmZzLlHhVvCcSsQqTtAa])|({_NUM}))")
_FLAG = re.compile(r"\s*,?\s*([01])")
_SEP = re.compile(r"[\s,]*")
#: Numbers per segment of each path command (an arc's two flags included).
_ARITY = {"m": 2, "z": 0, "l": 2, "h": 1, "v": 1, "c": 6, "s": 4, "q": 4, "t": 2, "a": 7}
#: The length attributes of each basic shape (SVG 1.1 / 2; ``auto`` allowed for rx, ry).
_LENGTHS = {"rect": ("x", "y", "width", "height", "rx", "ry"), "circle": ("cx", "cy", "r"),
            "ellipse": ("cx", "cy", "rx", "ry"), "line": ("x1", "y1", "x2", "y2")}


def element_name(tag: str, el_id: str | None) -> str:
    """``<path id="trace1">`` or ``<path>``."""
    return f'<{tag} id="{el_id}">' if el_id else f"<{tag}>"


def _short(v: str) -> str:
    return repr(v if len(v) <= 60 else v[:57] + "...")


def _number(text: str, what: str) -> float:
    v = float(text)
    if not math.isfinite(v):
        raise ValueError(f"{what} {text!r} is not a finite number")
    return v


def _check_path_data(d: str) -> None:
    """A ValueError naming the first fault of SVG path data ``d`` (its grammar, arities and
    finiteness); empty data is allowed (it draws nothing)."""
    pos, n, cmd, args, first = 0, len(d), None, 0, True
    while True:
        pos = _SEP.match(d, pos).end()
        if pos >= n:
            break
        if cmd is not None and cmd in "aA" and args % 7 in (3, 4):  # an arc's flags: one digit, maybe unseparated
            m = _FLAG.match(d, pos)
            if not m:
                raise ValueError(f"arc flag expected at character {pos + 1} ({d[pos:pos + 12]!r})")
            args += 1
            pos = m.end()
            continue
        m = _TOKEN.match(d, pos)
        if not m:
            raise ValueError(f"character {pos + 1} ({d[pos:pos + 12]!r}) is not path data")
        if m.group(1):
            if cmd is not None:
                _check_arity(cmd, args)
            cmd, args = m.group(1), 0
            if first and cmd not in "Mm":
                raise ValueError(f"path data starts with {cmd!r}, not a moveto (M or m)")
            first = False
        else:
            if cmd is None:
                raise ValueError("path data starts with a number, not a moveto (M or m)")
            if cmd in "Zz":
                raise ValueError(f"a number after {cmd!r} at character {pos + 1}")
            _number(m.group(2), "number")
            args += 1
        pos = m.end()
    if cmd is not None:
        _check_arity(cmd, args)


def _check_arity(cmd: str, args: int) -> None:
    k = _ARITY[cmd.lower()]
    if k and (args == 0 or args % k):
        raise ValueError(f"{cmd!r} takes numbers in groups of {k}, got {args}")


def check_shape_attributes(tag: str, attrib: dict, path) -> None:
    """A :class:`CadError` where a shape's geometry attribute cannot be read.

    Parameters
    ----------
    tag : str
        Local tag name (``path``, ``rect``, ...); other tags are not checked.
    attrib : dict
        The element's attributes (ElementTree's ``el.attrib``).
    path : Path
        The file, for the message.
    """
    name = element_name(tag, attrib.get("id"))
    if tag == "path":
        d = attrib.get("d")
        if d is not None:
            try:
                _check_path_data(d)
            except ValueError as exc:
                raise CadError(f"{name} d={_short(d)}: {exc}", path=path) from None
    elif tag in ("polygon", "polyline"):
        pts = attrib.get("points")
        if pts is not None:
            toks = [t for t in re.split(r"[\s,]+", pts.strip()) if t]
            try:
                for t in toks:
                    if not re.fullmatch(_NUM, t):
                        raise ValueError(f"{t!r} is not a number")
                    _number(t, "coordinate")
                if len(toks) % 2:
                    raise ValueError(f"an odd number of coordinates ({len(toks)}): the last point has no y")
            except ValueError as exc:
                raise CadError(f"{name} points={_short(pts)}: {exc}", path=path) from None
    for k in _LENGTHS.get(tag, ()):
        v = attrib.get(k)
        if v is None or (k in ("rx", "ry") and v.strip() == "auto"):
            continue
        m = _LENGTH.match(v)
        if not m or m.group(2).lower() not in _UNITS or not math.isfinite(float(m.group(1))):
            raise CadError(f"{name} {k}={_short(v)} is not a length", path=path)
