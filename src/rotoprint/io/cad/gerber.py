"""Gerber (RS-274X, X2/X3) copper and outline layers into exact polygons, read with gerbonara.

Every graphic object becomes a shapely polygon in millimetres: flashes of circle, rectangle,
obround, polygon and macro apertures (a macro's exposure-off primitives clear only inside the
macro), draws and arcs with a circular aperture (round caps), and regions (G36/G37, straight
and circular segments; cut-ins allowed). Objects are combined in file order with their
polarity: dark (LPD) adds, clear (LPC) removes what was drawn before. Arcs are chords within
the tolerance; straight edges are exact.

Terminals: every flashed pad with a net (``TO.N``) adds to the terminal named by the net, a
pad with a pin (``TO.P`` ``L1,1``) is also the terminal ``L1.1``, and a flash of an aperture
with the attribute ``%TATerminal,NAME*%`` is the terminal ``NAME``.

Refused, with the file and the line named where gerbonara says it: an undefined aperture, a
draw with a non-circular aperture, a region contour that does not end where it starts, or one
that crosses itself; before it reads: a %SR step and repeat of more than one copy (gerbonara
draws the block once), a polygon of other than 3 to 12 vertices, Excellon repeat codes beyond
:data:`MAX_REPEATS` (:data:`MAX_REPEATED_HOLES` in all); after: a file without its end
statement (M02, M30: cut short), an empty one.
"""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import Polygon

from ...errors import CadError
from ._geometry import PlanarLayer, arc_points, as_multipolygon, check_extent, circle_polygon, stroke

__all__ = ["read_gerber", "read_excellon"]

#: The largest Gerber or Excellon file read (bytes).
MAX_FILE_BYTES = 256 * 1024 * 1024
#: The formats' names in messages, bare and with their article.
_NAME = {"gerber": "Gerber", "excellon": "Excellon"}
_A_NAME = {"gerber": "a Gerber", "excellon": "an Excellon"}


def _check_size(path: Path) -> None:
    """A regular file (never a FIFO or device the library would block on) within the size bound."""
    from ..inputs import check_input_file

    check_input_file(path, what="layer file", limit_bytes=MAX_FILE_BYTES)


def _arcpoly_polygon(prim, tol: float) -> Polygon:
    """An ``ArcPoly`` (closed outline of straight and circular segments) as a polygon."""
    pts: list[np.ndarray] = []
    for p1, p2, (clockwise, centre) in prim.segments:
        p1 = np.asarray(p1, np.float64)
        p2 = np.asarray(p2, np.float64)
        if clockwise is None:
            pts.append(p1[None, :])
            continue
        c = np.asarray(centre, np.float64)
        r1 = float(np.hypot(*(p1 - c)))
        r2 = float(np.hypot(*(p2 - c)))
        a0 = math.atan2(p1[1] - c[1], p1[0] - c[0])
        a1 = math.atan2(p2[1] - c[1], p2[0] - c[0])
        if clockwise:
            sweep = -((a0 - a1) % (2 * math.pi))
        else:
            sweep = (a1 - a0) % (2 * math.pi)
        if sweep == 0.0:
            sweep = -2 * math.pi if clockwise else 2 * math.pi
        arc = arc_points(float(c[0]), float(c[1]), max(r1, r2), a0, sweep, tol)
        # radius from r1 to r2 along the arc, so that the arc ends exactly at p2
        rr = np.linspace(r1, r2, len(arc))
        t = a0 + sweep * np.arange(len(arc)) / (len(arc) - 1)
        arc = np.stack([c[0] + rr * np.cos(t), c[1] + rr * np.sin(t)], 1)
        arc[0], arc[-1] = p1, p2
        pts.append(arc[:-1])
    ring = np.concatenate(pts) if pts else np.zeros((0, 2))
    return Polygon(ring) if len(ring) >= 3 else Polygon()


def _primitive_polygon(prim, tol: float):
    from gerbonara import graphic_primitives as gp

    if isinstance(prim, gp.Circle):
        return circle_polygon(prim.x, prim.y, prim.r, tol)
    if isinstance(prim, gp.Rectangle):
        c, s = math.cos(prim.rotation), math.sin(prim.rotation)
        hw, hh = prim.w / 2, prim.h / 2
        corners = np.array([[-hw, -hh], [hw, -hh], [hw, hh], [-hw, hh]])
        R = np.array([[c, -s], [s, c]])
        return Polygon(corners @ R.T + np.array([prim.x, prim.y]))
    if isinstance(prim, gp.Line):
        if prim.width <= 0:
            return Polygon()
        return stroke([(prim.x1, prim.y1), (prim.x2, prim.y2)], prim.width, tol)
    if isinstance(prim, gp.Arc):
        if prim.width <= 0:
            return Polygon()
        r = math.hypot(prim.x1 - prim.cx, prim.y1 - prim.cy)
        a0 = math.atan2(prim.y1 - prim.cy, prim.x1 - prim.cx)
        a1 = math.atan2(prim.y2 - prim.cy, prim.x2 - prim.cx)
        sweep = -((a0 - a1) % (2 * math.pi)) if prim.clockwise else (a1 - a0) % (2 * math.pi)
        if sweep == 0.0:
            sweep = 2 * math.pi
        # chords of the centreline kept within tol at the stroke's outer edge
        rr = r + prim.width / 2
        pts = arc_points(prim.cx, prim.cy, r, a0, sweep, tol * r / rr if rr > 0 else tol)
        pts[-1] = (prim.x2, prim.y2)
        return stroke(pts, prim.width, tol)
    if isinstance(prim, gp.ArcPoly):
        return _arcpoly_polygon(prim, tol)
    raise CadError(f"unsupported graphic primitive {type(prim).__name__}")


def _combine(items):
    """``items``: ``(polygon, dark)`` in order -> the region (dark adds, clear removes)."""
    acc = Polygon()
    run: list = []
    run_dark = True
    for g, dark in items:
        if dark != run_dark and run:
            u = shapely.union_all(run)
            acc = acc.union(u) if run_dark else acc.difference(u)
            run = []
        run_dark = dark
        if not g.is_empty:
            run.append(g)
    if run:
        u = shapely.union_all(run)
        acc = acc.union(u) if run_dark else acc.difference(u)
    return acc


def _region_polygon(obj, idx: int, tol: float, path: Path) -> Polygon:
    from gerbonara.utils import MM

    out = obj.outline
    if len(out) < 3:
        raise CadError(f"region {idx} has {len(out)} points; a contour needs at least 3", path=path)
    scale = 1.0 if obj.unit == MM else 25.4
    gap = math.dist(out[0], out[-1]) * scale
    if gap > 1e-6:
        raise CadError(f"region {idx} is an unclosed contour: it ends at ({out[-1][0] * scale:.6g}, "
                       f"{out[-1][1] * scale:.6g}) mm, {gap:.6g} mm from where it starts "
                       f"({out[0][0] * scale:.6g}, {out[0][1] * scale:.6g}) mm", path=path)
    prims = list(obj.to_primitives(unit=MM))
    poly = _arcpoly_polygon(prims[0], tol)
    if not poly.is_valid:
        # a cut-in (the contour touching itself to make a hole) is allowed: its repaired area is
        # the contour's own (shoelace) area; a crossing makes lobes that cancel in the shoelace
        fixed = shapely.make_valid(poly)
        ring = np.asarray(poly.exterior.coords)
        shoelace = 0.5 * abs(float(np.sum(ring[:-1, 0] * ring[1:, 1] - ring[1:, 0] * ring[:-1, 1])))
        area = as_multipolygon(fixed).area
        if not math.isclose(area, shoelace, rel_tol=1e-9, abs_tol=1e-12):
            where = shapely.is_valid_reason(poly)
            raise CadError(f"region {idx} is self-intersecting ({where})", path=path)
        poly = shapely.union_all(list(as_multipolygon(fixed).geoms))
    return poly


def _object_shape(obj, idx: int, tol: float, path: Path):
    """The object's own shape (clear parts of a macro aperture removed), mm."""
    from gerbonara import graphic_objects as go
    from gerbonara.utils import MM

    if isinstance(obj, go.Region):
        return _region_polygon(obj, idx, tol, path)
    try:
        prims = list(obj.to_primitives(unit=MM))
    except ValueError as exc:
        raise CadError(f"object {idx} ({type(obj).__name__}): {exc}", path=path) from None
    own = obj.polarity_dark
    return _combine([(_primitive_polygon(p, tol), p.polarity_dark == own) for p in prims])


def _terminal_names(obj) -> list[str]:
    names = []
    attrs = getattr(obj, "attrs", None)
    attrs = attrs if isinstance(attrs, dict) else {}
    if ".N" in attrs and attrs[".N"] and attrs[".N"][0]:
        names.append(str(attrs[".N"][0]))
    if ".P" in attrs and len(attrs[".P"]) >= 2:
        names.append(f"{attrs['.P'][0]}.{attrs['.P'][1]}")
    ap = getattr(obj, "aperture", None)
    for k, v in (getattr(ap, "attrs", None) or ()):
        if k == "Terminal" and v:
            names.append(str(v[0]))
    return names


def _check_not_empty(path: Path, parsed, kind: str) -> None:
    """A file without one graphic object is a layer only when it states its units (a header
    and an end, as a CAD tool writes an empty paste or drill layer); an empty file, or text in
    which the lenient parser found no statement at all, is refused."""
    name = _NAME[kind]
    with open(path, "rb") as fh:  # bounded: _check_size passed
        blank = not fh.read().strip()
    if blank:
        raise CadError(f"no {name} content (empty)", path=path)
    if getattr(parsed.import_settings, "unit", None) is None:
        made = "nothing drawn" if kind == "gerber" else "nothing drilled"
        raise CadError(f"no {name} units and {made} (truncated, or not {_A_NAME[kind]} file)", path=path)


#: The statements a whole file ends with: Gerber's M02 (M00, deprecated, also stops the
#: file), Excellon's end of program M30 (or M00).
_ENDS = {"gerber": (b"M02*", b"M00*"), "excellon": (b"M30", b"M00")}


#: At most this many holes one Excellon R repeat code adds, and this many all of them: the
#: reader adds every repeated hole one by one, so the counts are bounded before it reads.
MAX_REPEATS = 10_000
MAX_REPEATED_HOLES = 1_000_000
#: A Gerber polygon aperture (%ADD..P) or macro polygon (primitive 5) has 3 to 12 vertices.
POLYGON_VERTICES = (3, 12)

_SR = re.compile(rb"%\s*SR\s*X(\d+)\s*Y(\d+)")
_AD_POLYGON = re.compile(rb"%\s*ADD\d+\s*P\s*,\s*[^X*%]*X\s*([-+0-9.eE]+)")
_AM_BLOCK = re.compile(rb"%\s*AM[^*%]*\*([^%]*)%")
_AM_POLYGON = re.compile(rb"(?:^|\*)\s*5\s*,[^,*]*,\s*([-+0-9.eE]+)\s*,")
_EXC_REPEAT = re.compile(rb"^\s*R(\d+)", re.MULTILINE)


def _line_of(data: bytes, pos: int) -> int:
    return data.count(b"\n", 0, pos) + 1


def _check_expansions(data: bytes, path: Path, kind: str) -> None:
    """What the file declares before the reader expands it: step-and-repeat and repeat-hole
    counts, polygon vertex counts (a huge one would be built vertex by vertex)."""
    if kind == "excellon":
        total = 0
        for m in _EXC_REPEAT.finditer(data):
            n = int(m.group(1))
            total += n
            if n > MAX_REPEATS or total > MAX_REPEATED_HOLES:
                raise CadError(f"line {_line_of(data, m.start())}: R{n} repeats a hole {n:,} times ({total:,} repeated "
                               f"holes so far); at most {MAX_REPEATS:,} per code and {MAX_REPEATED_HOLES:,} in all are "
                               "read", path=path)
        return
    for m in _SR.finditer(data):
        # gerbonara (1.x) opens the block with an empty list and tests it for truth, so no
        # object is ever collected and the block is drawn once: a panel would be read as one
        # board. Refused rather than read wrong (and before a huge count is expanded).
        nx, ny = int(m.group(1)), int(m.group(2))
        if nx * ny > 1:
            raise CadError(f"line {_line_of(data, m.start())}: %SR step and repeat of {nx:,} x {ny:,} copies is not "
                           "read (the Gerber reader would draw one copy); export the panel flattened", path=path)
    lo, hi = POLYGON_VERTICES
    found = [(m.start(), m.group(1), "polygon aperture") for m in _AD_POLYGON.finditer(data)]
    for block in _AM_BLOCK.finditer(data):
        found += [(block.start(), m.group(1), "macro polygon (primitive 5)")
                  for m in _AM_POLYGON.finditer(block.group(1))]
    for pos, raw, what in found:
        try:
            n = float(raw)
        except ValueError:
            continue  # not a number: the reader says what is wrong with it
        if not lo <= n <= hi:
            raise CadError(f"line {_line_of(data, pos)}: a {what} of {raw.decode(errors='replace')} vertices; a "
                           f"Gerber polygon has {lo} to {hi}", path=path)


def _check_ends(path: Path, kind: str) -> None:
    """A file cut short (a copy or download that stopped, a tool that crashed while writing)
    lacks its end statement; what it lacks would not be printed, so it is refused."""
    with open(path, "rb") as fh:
        size = fh.seek(0, 2)
        fh.seek(max(0, size - 256))
        tail = fh.read().rstrip()
    lines = [ln.strip() for ln in tail.splitlines()]
    while kind == "excellon" and len(lines) > 1 and lines[-1] in (b"%", b""):  # a rewind-stop '%' after M30
        lines.pop()
    last = lines[-1] if lines else b""
    if not any(last.endswith(e) for e in _ENDS[kind]):
        want = " or ".join(e.decode() for e in _ENDS[kind])
        raise CadError(f"no {want} end statement at its end: the file is cut short (truncated) or not fully written",
                       path=path)


def _read(path: Path, tol: float, kind: str) -> PlanarLayer:
    from gerbonara import ExcellonFile, GerberFile
    from gerbonara import graphic_objects as go

    path = Path(path)
    _check_size(path)
    if not tol > 0:
        raise CadError(f"the arc tolerance must be > 0 mm, got {tol!r}", path=path)
    with open(path, "rb") as fh:  # bounded: _check_size passed
        _check_expansions(fh.read(), path, kind)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            f = GerberFile.open(path) if kind == "gerber" else ExcellonFile.open(path)
        except UnicodeDecodeError:
            raise CadError(f"not {_A_NAME[kind]} text file (not ASCII/UTF-8)", path=path) from None
        except (SyntaxError, ValueError, KeyError, IndexError, TypeError, AttributeError, AssertionError) as exc:
            msg = str(exc).replace(str(path) + ":", "line ").strip() or type(exc).__name__
            raise CadError(f"not a readable {_NAME[kind]} file: {msg}", path=path) from None
    if not f.objects:
        _check_not_empty(path, f, kind)
    _check_ends(path, kind)
    items = []
    terms: dict[str, list] = {}
    counts = {"flashes": 0, "draws": 0, "arcs": 0, "regions": 0}
    from gerbonara.utils import MM

    chain: list = []  # consecutive draws of one aperture and polarity, end to start: one stroke

    def flush():
        if chain:
            pts, width, dark = chain[0], chain[1], chain[2]
            items.append((stroke(np.asarray(pts), width, tol) if width > 0 else Polygon(), dark))
            chain.clear()

    for idx, obj in enumerate(f.objects):
        if isinstance(obj, go.Line):
            counts["draws"] += 1
            try:
                (prim,) = [q for q in obj.to_primitives(unit=MM)]
            except ValueError as exc:
                raise CadError(f"object {idx} (draw): {exc}", path=path) from None
            dark = bool(obj.polarity_dark)
            if chain and chain[1] == prim.width and chain[2] == dark and chain[0][-1] == (prim.x1, prim.y1):
                chain[0].append((prim.x2, prim.y2))
            else:
                flush()
                chain.extend([[(prim.x1, prim.y1), (prim.x2, prim.y2)], prim.width, dark])
            continue
        flush()
        shape = _object_shape(obj, idx, tol, path)
        items.append((shape, bool(obj.polarity_dark)))
        if isinstance(obj, go.Flash):
            counts["flashes"] += 1
            if obj.polarity_dark:
                for n in _terminal_names(obj):
                    terms.setdefault(n, []).append(shape)
        elif isinstance(obj, go.Region):
            counts["regions"] += 1
            attrs = getattr(obj, "attrs", None)
            attrs = attrs if isinstance(attrs, dict) else {}
            if ".P" in attrs and obj.polarity_dark:
                for n in _terminal_names(obj):
                    terms.setdefault(n, []).append(shape)
        elif isinstance(obj, go.Arc):
            counts["arcs"] += 1
    flush()
    region = as_multipolygon(_combine(items))
    region = as_multipolygon(shapely.orient_polygons(region, exterior_cw=False))
    check_extent(region, path=path, hint=" (check the coordinates and the %FS and %MO statements)" if kind == "gerber"
                 else " (check the coordinates and the units: METRIC or INCH)")
    terminals = {k: shapely.union_all(v) for k, v in terms.items()}
    counts["warnings"] = [str(w.message) for w in caught][:20]
    return PlanarLayer(region=region, terminals=terminals, source=str(path), fmt=kind, tolerance_mm=tol, counts=counts)


def read_gerber(path: str | Path, *, tolerance_mm: float) -> PlanarLayer:
    """Read a Gerber layer into its exact region.

    Parameters
    ----------
    path : str or Path
        RS-274X file (``.gbr``, ``.gtl``, ...), in mm or inch (its ``%MO`` statement).
    tolerance_mm : float
        Largest distance of arc chords from the arcs (circles, round caps, G02/G03).

    Returns
    -------
    PlanarLayer
        Region in mm, terminals named by net, pin or ``TA.Terminal`` attribute.

    Raises
    ------
    CadError
        Undefined aperture, unreadable statement, unclosed or self-intersecting region.
    """
    return _read(Path(path), float(tolerance_mm), "gerber")


def read_excellon(path: str | Path, *, tolerance_mm: float) -> PlanarLayer:
    """Read an Excellon drill file: every hit a disc of its tool's diameter, every routed
    slot a stroke of it. Units from the file (``METRIC``/``INCH``).

    Parameters
    ----------
    path : str or Path
    tolerance_mm : float
        Largest distance of the discs' chords from their circles.

    Returns
    -------
    PlanarLayer
        The drilled area (the holes themselves), mm.

    Raises
    ------
    CadError
        Unreadable statement or undefined tool.
    """
    return _read(Path(path), float(tolerance_mm), "excellon")
