"""DXF outlines and tracks into exact polygons, read with ezdxf.

- Closed contours (closed LWPOLYLINE/POLYLINE without width, CIRCLE, closed SPLINE or
  ELLIPSE, and chains of LINE, ARC and open polylines whose ends meet) are filled by the
  even-odd rule: an outline inside an outline is a hole.
- A polyline with a width (constant ``const_width`` or equal start and end widths) is a track:
  the polyline stroked with that width (round ends and joins), closed or open.
- Bulges (arcs in polylines), ARC, CIRCLE, ELLIPSE and SPLINE become chords within the
  tolerance.
- Units: the header's ``$INSUNITS`` (unitless files: ``units``, default mm). Blocks (INSERT)
  are exploded; other entities (text, dimensions, hatches) are counted and ignored.

Refused: a chain that does not close (an unclosed contour, with its two open ends named), a
closed contour that crosses itself, a polyline with varying width.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import MultiLineString, Polygon

from ...errors import CadError
from ..inputs import check_input_file
from ._geometry import PlanarLayer, arc_points, as_multipolygon, check_extent, check_valid, fill_rings, length_unit_mm, stroke

__all__ = ["read_dxf", "INSUNITS_MM"]

#: ``$INSUNITS`` codes (AutoCAD) to millimetres; 0 is unitless.
INSUNITS_MM = {1: 25.4, 2: 304.8, 3: 1_609_344.0, 4: 1.0, 5: 10.0, 6: 1000.0, 7: 1e6, 8: 25.4e-6, 9: 0.0254,
               10: 914.4, 11: 1e-7, 12: 1e-6, 13: 1e-3, 14: 100.0, 15: 1e4, 16: 1e5, 17: 1e12, 18: 1.495978707e14,
               19: 9.4607e18, 20: 3.0857e19, 21: 304.8006096, 22: 25.4000508, 23: 914.4018288, 24: 1_609_347.2187}
MAX_FILE_BYTES = 256 * 1024 * 1024
MAX_INSERT_DEPTH = 16
#: Ends of a chain closer than this (mm) are joined.
JOIN_MM = 1e-6


def _bulge_points(p1, p2, bulge: float, tol: float) -> np.ndarray:
    """Points from ``p1`` to ``p2`` (``p1`` included, ``p2`` not) along a polyline bulge."""
    p1 = np.asarray(p1, np.float64)
    p2 = np.asarray(p2, np.float64)
    if bulge == 0:
        return p1[None, :]
    theta = 4.0 * math.atan(bulge)  # included angle, counter-clockwise when > 0
    chord = p2 - p1
    c = float(np.hypot(*chord))
    if c == 0:
        return p1[None, :]
    r = c / (2.0 * abs(math.sin(theta / 2)))
    mid = (p1 + p2) / 2
    n = np.array([-chord[1], chord[0]]) / c
    # centre on the left of the chord for a counter-clockwise arc of less than 180 deg
    d = r * math.cos(theta / 2) * (1 if theta > 0 else -1)
    centre = mid + n * d
    a0 = math.atan2(p1[1] - centre[1], p1[0] - centre[0])
    pts = arc_points(float(centre[0]), float(centre[1]), r, a0, theta, tol)
    pts[0] = p1
    return pts[:-1]


def _poly_path(points, closed: bool, tol: float) -> np.ndarray:
    """``points``: ``(x, y, bulge)`` -> the path's points (closing point appended when closed)."""
    out = []
    n = len(points)
    last = n if closed else n - 1
    for i in range(last):
        x1, y1, b = points[i]
        x2, y2, _ = points[(i + 1) % n]
        out.append(_bulge_points((x1, y1), (x2, y2), b, tol))
    out.append(np.array([[points[0][0], points[0][1]] if closed else [points[-1][0], points[-1][1]]], np.float64))
    return np.concatenate(out)


def _explode(msp, depth=0):
    for e in msp:
        if e.dxftype() == "INSERT":
            if depth >= MAX_INSERT_DEPTH:
                raise CadError(f"blocks nested more than {MAX_INSERT_DEPTH} deep")
            yield from _explode(list(e.virtual_entities()), depth + 1)
        else:
            yield e


def _dxf_problem(exc: Exception) -> str:
    """ezdxf's reason in words of the file: without the class name it may start with
    (``DXFStructureError: missing ENDSEC tag.``) and without the path it may repeat."""
    text = " ".join(str(exc).split()).rstrip(".")
    if type(exc) is OSError and text.endswith("is not a DXF file"):
        return "no DXF header (empty, or another kind of file)"
    for prefix in (type(exc).__name__ + ":", "DXFStructureError:", "DXFError:"):
        if text.startswith(prefix):
            text = text[len(prefix):].strip()
    if isinstance(exc, UnicodeDecodeError):
        return f"not text in its declared encoding (byte {exc.start})"
    return text or "its structure is broken (truncated?)"


_EXTENT_HINT = " (check the coordinates and $INSUNITS or --units)"


def _declares(p: Path, name: bytes, chunk_bytes: int = 1 << 20) -> bool:
    """Whether the file's bytes hold ``name`` (read in chunks, never whole)."""
    tail = b""
    with open(p, "rb") as fh:
        while block := fh.read(chunk_bytes):
            if name in tail + block:
                return True
            tail = block[-(len(name) - 1):]
    return False


def read_dxf(path: str | Path, *, tolerance_mm: float, units: str | None = None) -> PlanarLayer:
    """Read a DXF file's model space into its exact region.

    Parameters
    ----------
    path : str or Path
    tolerance_mm : float
        Largest distance of chords from arcs, circles, ellipses and splines, mm.
    units : str, optional
        Unit of the coordinates, overriding ``$INSUNITS`` (which unitless files lack; default mm).

    Returns
    -------
    PlanarLayer

    Raises
    ------
    CadError
        Not a DXF file, an unclosed contour, a self-intersecting contour, a varying width, or a
        ``$INSUNITS`` that is not a length.
    """
    import ezdxf

    p = Path(path)
    check_input_file(p, what="DXF file", limit_bytes=MAX_FILE_BYTES)  # regular, bounded: never a blocking read
    try:
        doc = ezdxf.readfile(p)
    except StopIteration:  # ezdxf's tag reader ran out of tags inside a section: the file ends early
        raise CadError("not a readable DXF file: it ends inside a section (truncated)", path=p) from None
    except (ezdxf.DXFError, OSError, UnicodeDecodeError, ValueError, IndexError, KeyError, TypeError, AttributeError,
            AssertionError) as exc:
        raise CadError(f"not a readable DXF file: {_dxf_problem(exc)}", path=p) from None
    if units is not None:
        scale = length_unit_mm(units, path=p)
    else:
        # ezdxf gives a file without $INSUNITS (no HEADER section at all, as minimal R12 writers make) its
        # own default, metres: only a $INSUNITS the file itself declares counts, else unitless (mm)
        code = int(doc.header.get("$INSUNITS", 0) or 0) if _declares(p, b"$INSUNITS") else 0
        if code == 0:
            scale = 1.0
        elif code in INSUNITS_MM:
            scale = INSUNITS_MM[code]
        else:
            raise CadError(f"$INSUNITS = {code} is not a length unit (known codes 0-24)", path=p)
    tol = float(tolerance_mm) / scale  # in file units
    rings: list[np.ndarray] = []
    strokes = []
    pieces = []
    ignored: dict[str, int] = {}
    counts = {"contours": 0, "tracks": 0, "chained": 0}
    try:
        entities = list(_explode(doc.modelspace()))
    except CadError as exc:
        raise CadError(exc.problem, path=p) from None
    for e in entities:
        t = e.dxftype()
        try:
            if t in ("LWPOLYLINE", "POLYLINE"):
                if t == "LWPOLYLINE":
                    raw = list(e.get_points("xyseb"))
                    closed = bool(e.closed)
                    cw = float(e.dxf.get("const_width", 0.0) or 0.0)
                    pts = [(float(x), float(y), float(b)) for x, y, s, w, b in raw]
                    widths = {cw} if cw > 0 else {float(s) for _, _, s, _, _ in raw[: len(raw) if closed else -1]} | \
                        {float(w) for _, _, _, w, _ in raw[: len(raw) if closed else -1]}
                else:
                    if e.is_3d_polyline or e.is_poly_face_mesh or e.is_polygon_mesh:
                        ignored[t + " (3-D)"] = ignored.get(t + " (3-D)", 0) + 1
                        continue
                    vs = list(e.vertices)
                    closed = bool(e.is_closed)
                    pts = [(float(v.dxf.location.x), float(v.dxf.location.y), float(v.dxf.get("bulge", 0.0))) for v in vs]
                    d0 = float(e.dxf.get("default_start_width", 0.0) or 0.0)
                    d1 = float(e.dxf.get("default_end_width", 0.0) or 0.0)
                    widths = {float(v.dxf.get("start_width", d0)) for v in vs} | {float(v.dxf.get("end_width", d1)) for v in vs}
                if len(pts) < 2:
                    continue
                widths = {w for w in widths} or {0.0}
                path_pts = _poly_path(pts, closed, tol)
                if max(widths) > 0:
                    if len(widths) > 1:
                        raise CadError(f"{t} (handle {e.dxf.handle}) has varying widths {sorted(widths)}; only a constant "
                                       "width is a track", path=p)
                    w = widths.pop()
                    strokes.append(stroke(path_pts * scale, w * scale, tolerance_mm))
                    counts["tracks"] += 1
                elif closed:
                    rings.append(path_pts * scale)
                    counts["contours"] += 1
                else:
                    pieces.append(path_pts * scale)
            elif t == "CIRCLE":
                c = e.dxf.center
                if not (math.isfinite(e.dxf.radius) and e.dxf.radius > 0):
                    raise CadError(f"CIRCLE (handle {e.dxf.handle}) has radius {e.dxf.radius:g}; a circle needs a positive "
                                   "radius", path=p)
                pts = arc_points(c.x, c.y, e.dxf.radius, 0.0, 2 * math.pi, tol)
                rings.append(pts * scale)
                counts["contours"] += 1
            elif t == "ARC":
                c = e.dxf.center
                a0 = math.radians(e.dxf.start_angle)
                sweep = math.radians((e.dxf.end_angle - e.dxf.start_angle) % 360.0) or 2 * math.pi
                pieces.append(arc_points(c.x, c.y, e.dxf.radius, a0, sweep, tol) * scale)
            elif t == "LINE":
                s, en = e.dxf.start, e.dxf.end
                pieces.append(np.array([[s.x, s.y], [en.x, en.y]], np.float64) * scale)
            elif t in ("SPLINE", "ELLIPSE"):
                pts = np.array([(v.x, v.y) for v in e.flattening(tol)], np.float64) * scale
                if len(pts) >= 2 and np.hypot(*(pts[0] - pts[-1])) <= JOIN_MM:
                    rings.append(pts)
                    counts["contours"] += 1
                else:
                    pieces.append(pts)
            else:
                ignored[t] = ignored.get(t, 0) + 1
        except CadError:
            raise
        except (ValueError, ArithmeticError, RecursionError, IndexError, TypeError, AttributeError) as exc:
            # a degenerate entity (a zero radius, a spline whose knots make a singular system, an
            # ellipse too large to flatten): its handle named, the library's reason after it
            reason = " ".join(str(exc).split())[:120] or type(exc).__name__
            raise CadError(f"{t} (handle {e.dxf.get('handle', '?')}) cannot be made into geometry: {reason}", path=p) from None
    if pieces:
        q = 1.0 / JOIN_MM
        merged = shapely.line_merge(MultiLineString([np.round(pc * q) / q for pc in pieces]))
        for ln in shapely.get_parts(merged):
            c = np.asarray(ln.coords, np.float64)
            if not ln.is_ring:
                raise CadError(f"unclosed contour: a chain of lines and arcs runs from ({c[0, 0]:.6g}, {c[0, 1]:.6g}) "
                               f"to ({c[-1, 0]:.6g}, {c[-1, 1]:.6g}) mm without closing (give it a width to make it a "
                               "track)", path=p)
            rings.append(c)
            counts["chained"] += 1
    if rings:  # far or non-finite coordinates refused before any polygon is built of them
        check_extent(shapely.multipoints(np.concatenate(rings)), path=p, hint=_EXTENT_HINT)
    for i, r in enumerate(rings):
        check_valid(Polygon(r), f"closed contour {i} (starting at ({r[0, 0]:.6g}, {r[0, 1]:.6g}) mm)", path=p)
    region = fill_rings(rings, "evenodd")
    if strokes:
        region = as_multipolygon(shapely.union_all([region, *strokes]))
    region = as_multipolygon(shapely.orient_polygons(region, exterior_cw=False))
    counts["ignored"] = ignored
    check_extent(region, path=p, hint=_EXTENT_HINT)
    return PlanarLayer(region=region, terminals={}, source=str(p), fmt="dxf", tolerance_mm=float(tolerance_mm), counts=counts)
