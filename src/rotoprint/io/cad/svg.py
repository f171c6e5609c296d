"""SVG drawings into exact polygons, read with svgelements.

Every shape (path, rect, circle, ellipse, polygon, polyline, line) with its transforms
applied: its fill (``fill-rule`` nonzero or evenodd, exact winding numbers) and its stroke
(``stroke-width`` through the transforms, ``stroke-linecap`` butt/round/square,
``stroke-linejoin`` miter/round/bevel with ``stroke-miterlimit``) are dark; ``fill="none"`` and
``stroke="none"`` are not. Arcs and Bézier curves become chords within the tolerance.

Units: svgelements resolves the document to CSS pixels (96 per inch; ``width="30mm"`` with a
``viewBox`` maps user units to millimetres), so coordinates are ``px * 25.4 / 96`` mm; ``units``
overrides that (the pixel is then that unit). Y is flipped (SVG's Y runs down the page).

Refused: ``width``/``height`` in a unit that is not a length, a page (``width``, ``height``,
``viewBox``) or a drawing beyond the layer bound (:data:`rotoprint.ranges.COORD_MM`; the message
gives the size in mm it would be), transforms nested more than :data:`MAX_TRANSFORM_DEPTH`
deep, elements nested more than :data:`MAX_ELEMENT_DEPTH` deep, and a shape whose geometry
cannot be read (malformed path data, a ``points`` list or a length that is not numbers, a NaN,
a point beyond the layer bound: :mod:`._svgcheck`), naming the element. A shape that draws
nothing (one point, empty ``d``) is counted in ``counts["empty"]``.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import shapely
from shapely.errors import GEOSException
from shapely.geometry import LinearRing, LineString

from ...errors import CadError
from ..inputs import check_input_file
from ...ranges import COORD_MM
from ._svgcheck import check_shape_attributes, element_name
from ._geometry import MAX_SPAN_MM, PlanarLayer, as_multipolygon, check_extent, fill_rings, length_unit_mm, segments_for_arc

__all__ = ["read_svg", "MAX_TRANSFORM_DEPTH", "MAX_ELEMENT_DEPTH"]

MAX_FILE_BYTES = 64 * 1024 * 1024
MAX_TRANSFORM_DEPTH = 32
MAX_ELEMENT_DEPTH = 256
_SVG_LENGTH = re.compile(r"^\s*([+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)\s*([a-zA-Z%]*)\s*$")
_SVG_NS = "http://www.w3.org/2000/svg"
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_NOT_FINITE = re.compile(r"(?<![a-zA-Z])(nan|inf(inity)?)(?![a-zA-Z])", re.IGNORECASE)
_SVG_UNITS = {"", "px", "mm", "cm", "in", "pt", "pc", "q", "%", "em", "ex"}
#: CSS pixels per absolute CSS unit (relative ones, % em ex, are not checked for size).
_SVG_ABSOLUTE_PX = {"": 1.0, "px": 1.0, "mm": 96 / 25.4, "cm": 96 / 2.54, "in": 96.0, "pt": 96 / 72, "pc": 16.0,
                    "q": 96 / 25.4 / 4}


def _check_page(el, path: Path, mm_per_px: float) -> None:
    """The root ``<svg>``'s ``width``, ``height`` and ``viewBox``: lengths, and a page that
    fits the layer bound (:data:`MAX_SPAN_MM`); a refusal gives the size in mm it would be.
    A viewBox sizes the page (its user unit the pixel) only where no absolute width or
    height does."""
    sized = {}
    for k in ("width", "height"):
        v = el.get(k)
        if v is None:
            continue
        m = _SVG_LENGTH.match(v)
        if not m or m.group(2).lower() not in _SVG_UNITS:
            raise CadError(f"{k}={v!r} of the <svg> element is not a length", path=path)
        unit = m.group(2).lower()
        if unit in _SVG_ABSOLUTE_PX:  # the reader's millimetres: CSS pixels times the pixel's size
            size_mm = float(m.group(1)) * _SVG_ABSOLUTE_PX[unit] * mm_per_px
            _check_page_size(f"{k}={v!r}", size_mm, path)
            sized[k] = size_mm
    vb = el.get("viewBox")
    if vb is None:
        return
    try:
        nums = [float(t) for t in vb.replace(",", " ").split()]
    except ValueError:
        nums = []
    if len(nums) != 4 or not all(math.isfinite(v) for v in nums):
        raise CadError(f"viewBox={vb!r} of the <svg> element is not four finite numbers", path=path)
    for k, v, lo in (("width", nums[2], nums[0]), ("height", nums[3], nums[1])):
        if k not in sized:  # the viewBox's user unit is the pixel: its extent is the page's
            _check_page_size(f"viewBox={vb!r} ({k})", (abs(lo) + abs(v)) * mm_per_px, path)


def _check_page_size(what: str, size_mm: float, path: Path) -> None:
    if not (math.isfinite(size_mm) and abs(size_mm) <= MAX_SPAN_MM):
        raise CadError(f"{what} of the <svg> element makes the page {size_mm:.3g} mm; a layer must fit in "
                       f"{MAX_SPAN_MM:g} mm (coordinates {COORD_MM.text()})", path=path)


def _precheck(path: Path, mm_per_px: float) -> None:
    depth = 0
    tdepth = [0]
    worst = 0
    try:
        for ev, el in ET.iterparse(path, events=("start", "end")):
            if ev == "start":
                depth += 1
                tf = el.get("transform")
                t = tdepth[-1] + (1 if tf else 0)
                if tf and (_NOT_FINITE.search(tf) or not all(math.isfinite(float(v)) for v in _NUMBER.findall(tf))):
                    raise CadError(f"transform={tf[:80]!r} of a <{el.tag.rpartition('}')[2]}> holds a number that is "
                                   "not finite", path=path)
                tdepth.append(t)
                worst = max(worst, t)
                if depth > MAX_ELEMENT_DEPTH:
                    raise CadError(f"elements are nested more than {MAX_ELEMENT_DEPTH} deep", path=path)
                if t > MAX_TRANSFORM_DEPTH:
                    raise CadError(f"transforms are nested more than {MAX_TRANSFORM_DEPTH} deep; flatten the "
                                   "groups before reading", path=path)
                if depth == 1:
                    _check_page(el, path, mm_per_px)
                ns, _, tag = el.tag.rpartition("}")
                if ns in ("", "{" + _SVG_NS):
                    check_shape_attributes(tag, el.attrib, path)
            else:
                depth -= 1
                tdepth.pop()
                el.clear()
    except ET.ParseError as exc:
        raise CadError(f"not a readable SVG (XML) file: {exc}", path=path) from None


def _chords(x: float) -> float:
    """``ceil(x)``, at least 1, for a finite ``x`` within the chord limit; ``x`` itself
    (infinite, NaN or huge: refused by the caller) otherwise."""
    return max(1, math.ceil(x)) if x <= 1_000_000 else x


def _negative_size(el) -> str | None:
    """The first of ``r``, ``rx``, ``ry``, ``width``, ``height`` or ``stroke-width`` an element
    gives as a negative length (an error in SVG: the element is not drawn by a browser,
    svgelements would draw its mirror image), as ``name=value``."""
    for k in ("r", "rx", "ry", "width", "height", "stroke-width"):
        v = el.values.get(k)
        m = _SVG_LENGTH.match(str(v)) if isinstance(v, str) else None
        if m and float(m.group(1)) < 0:
            return f"{k}={v!r}"
    return None


def _flatten(sub, tol: float) -> tuple[np.ndarray, bool]:
    """One subpath's points (px) and whether it closes."""
    from svgelements import Arc, Close, CubicBezier, Line, Move, QuadraticBezier

    pts: list[tuple[float, float]] = []
    closed = False
    for seg in sub:
        if isinstance(seg, Move):
            pts.append((seg.end.x, seg.end.y))
        elif isinstance(seg, Close):
            closed = True
            if seg.start is not None:
                pts.append((seg.end.x, seg.end.y))
        elif isinstance(seg, Line):
            pts.append((seg.end.x, seg.end.y))
        else:
            if isinstance(seg, Arc):
                r = max(abs(seg.rx), abs(seg.ry))
                rmin = max(min(abs(seg.rx), abs(seg.ry)), 1e-12)
                n = segments_for_arc(r * r / rmin, seg.sweep, tol)
            elif isinstance(seg, CubicBezier):
                c = [np.array([q.x, q.y]) for q in (seg.start, seg.control1, seg.control2, seg.end)]
                m = max(np.hypot(*(c[0] - 2 * c[1] + c[2])), np.hypot(*(c[1] - 2 * c[2] + c[3])))
                n = _chords(math.sqrt(6 * m / (8 * tol)))
            elif isinstance(seg, QuadraticBezier):
                c = [np.array([q.x, q.y]) for q in (seg.start, seg.control, seg.end)]
                m = np.hypot(*(c[0] - 2 * c[1] + c[2]))
                n = _chords(math.sqrt(2 * m / (8 * tol)))
            else:
                raise CadError(f"unsupported path segment {type(seg).__name__}")
            if not n <= 1_000_000:  # a NaN count is refused too
                raise CadError(f"a curve needs {n:.3g} chords at this tolerance; use a larger tolerance")
            for t in np.arange(1, n + 1) / n:
                q = seg.point(float(t))
                pts.append((q.x, q.y))
    a = np.asarray(pts, np.float64)
    if len(a):
        keep = np.ones(len(a), bool)
        keep[1:] = np.any(np.diff(a, axis=0) != 0, axis=1)
        a = a[keep]
    return a, closed


def _stroke(points: np.ndarray, closed: bool, width: float, values: dict, tol: float):
    cap = {"butt": "flat", "round": "round", "square": "square"}.get(str(values.get("stroke-linecap", "butt")).strip(), "flat")
    join = {"miter": "mitre", "round": "round", "bevel": "bevel"}.get(str(values.get("stroke-linejoin", "miter")).strip(), "mitre")
    try:
        limit = float(values.get("stroke-miterlimit", 4.0))
    except (TypeError, ValueError):
        limit = 4.0
    qs = max(2, segments_for_arc(width / 2, math.pi / 2, tol))
    if closed and len(points) >= 3:
        ring = points if not np.array_equal(points[0], points[-1]) else points[:-1]
        if len(ring) >= 3:
            return LinearRing(ring).buffer(width / 2, quad_segs=qs, join_style=join, mitre_limit=limit)
    if len(points) == 1:
        if cap == "flat":
            return shapely.Polygon()
        return shapely.Point(points[0]).buffer(width / 2, quad_segs=qs, cap_style=cap)
    return LineString(points).buffer(width / 2, quad_segs=qs, cap_style=cap, join_style=join, mitre_limit=limit)


def _check_coordinates(el, subs, path: Path) -> None:
    """A :class:`CadError` naming the element where a point (transforms applied) is not
    finite: a coordinate of 1e308 times the page's scale overflows, and GEOS left the shape
    out. A finite one beyond the layer bound is :func:`check_extent`'s (it gives the size)."""
    for a, _ in subs:
        if not np.all(np.isfinite(a)):
            name = element_name(str(el.values.get("tag", type(el).__name__.lower())), el.values.get("id"))
            raise CadError(f"{name} has a point beyond the float range (transforms applied); a layer must lie "
                           f"{COORD_MM.text()}", path=path)


def read_svg(path: str | Path, *, tolerance_mm: float, units: str | None = None) -> PlanarLayer:
    """Read an SVG drawing's filled and stroked area into its exact region (mm, Y up).

    Parameters
    ----------
    path : str or Path
    tolerance_mm : float
        Largest distance of chords from arcs and curves, mm.
    units : str, optional
        Unit of svgelements' CSS pixel (default ``px``: 1/96 in).

    Returns
    -------
    PlanarLayer

    Raises
    ------
    CadError
        Not an SVG, deeply nested transforms, or a size that is not a length.
    """
    import svgelements as se

    p = Path(path)
    check_input_file(p, what="SVG file", limit_bytes=MAX_FILE_BYTES)  # regular, bounded: never a blocking read
    # svgelements' own CSS pixel per mm (it converts "mm" with this factor)
    mm_per_px = length_unit_mm(units, path=p) if units else 1.0 / float(se.Length("1mm").value(ppi=96.0))
    _precheck(p, mm_per_px)
    tol = float(tolerance_mm) / mm_per_px
    try:
        doc = se.SVG.parse(str(p), reify=True, ppi=96.0)
    except RecursionError:  # <use> elements that refer to themselves, or one another in a loop
        raise CadError("not a readable SVG file: its <use> references loop (an element uses itself)", path=p) from None
    except (ValueError, TypeError, ET.ParseError, IndexError, ZeroDivisionError) as exc:
        raise CadError(f"not a readable SVG file: {exc}", path=p) from None
    try:
        parts = []
        counts = {"fills": 0, "strokes": 0, "empty": 0}
        for el in doc.elements():
            if not isinstance(el, se.Shape) or isinstance(el, se.Text):
                continue
            if str(el.values.get("visibility", "visible")) == "hidden" or str(el.values.get("display", "")) == "none":
                continue
            bad = _negative_size(el)
            if bad is not None:
                raise CadError(f"<{el.values.get('tag', type(el).__name__.lower())}> {bad} is a negative length", path=p)
            path_ = se.Path(el)
            subs = [_flatten(s, tol) for s in path_.as_subpaths()]
            subs = [(a, c) for a, c in subs if len(a)]
            _check_coordinates(el, subs, p)
            if not subs:
                counts["empty"] += 1
                continue
            fill = el.fill
            drawn = len(parts)
            if fill is not None and fill.value is not None and fill.alpha != 0:
                rule = "evenodd" if str(el.values.get("fill-rule", "nonzero")).strip() == "evenodd" else "nonzero"
                reg = fill_rings([a for a, _ in subs], rule)
                if not reg.is_empty:
                    parts.append(reg)
                    counts["fills"] += 1
            stroke = el.stroke
            w = float(getattr(el, "implicit_stroke_width", None) or el.stroke_width or 0.0)
            if stroke is not None and stroke.value is not None and stroke.alpha != 0 and w > 0:
                for a, c in subs:
                    g = _stroke(a, c, w, el.values, tol)
                    if not g.is_empty:
                        parts.append(g)
                counts["strokes"] += 1
            if len(parts) == drawn:  # a shape that draws nothing: no area filled, no stroke
                counts["empty"] += 1
        region = as_multipolygon(shapely.union_all(parts)) if parts else as_multipolygon(shapely.Polygon())
        from shapely import affinity

        region = as_multipolygon(affinity.affine_transform(region, [mm_per_px, 0, 0, -mm_per_px, 0, 0]))
        region = as_multipolygon(shapely.orient_polygons(region, exterior_cw=False))
    except CadError:
        raise
    except (GEOSException, ValueError, ArithmeticError) as exc:
        # coordinates beyond the float range (1e999 reads as inf) or degenerate: GEOS cannot node them
        reason = " ".join(str(exc).split())[:120] or type(exc).__name__
        raise CadError(f"its shapes cannot be made into geometry (coordinates not finite, or degenerate): {reason}",
                       path=p) from None
    check_extent(region, path=p, hint=" (check the coordinates, transforms and --units)")
    return PlanarLayer(region=region, terminals={}, source=str(p), fmt="svg", tolerance_mm=float(tolerance_mm), counts=counts)
