"""Exact planar geometry shared by the CAD readers: arcs kept to a tolerance, strokes, the
layer object, its measures (area, narrowest track and gap) and its oriented segments.

Arcs become chords whose sagitta is at most the tolerance: a circle of radius ``r`` with
tolerance ``tol`` gets ``n = ceil(2 pi / (2 acos(1 - tol / r)))`` sides with the vertices on
the circle (inscribed polygon), so every point of the polygon is within ``tol`` of the true
arc. Straight edges are kept exactly as the file gives them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import shapely
from shapely.geometry import LineString, MultiPolygon, Polygon
from shapely.geometry.base import BaseGeometry

from ...errors import CadError
from ...ranges import COORD_MM

__all__ = ["MIN_TOLERANCE_MM", "PlanarLayer", "arc_points", "circle_polygon", "stroke", "segments_for_arc", "as_multipolygon",
           "LENGTH_UNITS_MM", "length_unit_mm", "narrowest_mm", "check_valid", "check_extent", "MAX_SPAN_MM"]

#: Millimetres per unit of the length units a layer may be given in.
LENGTH_UNITS_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "um": 1e-3, "in": 25.4, "inch": 25.4, "mil": 0.0254,
                   "thou": 0.0254, "ft": 304.8, "pt": 25.4 / 72, "px": 25.4 / 96}
#: At most this many vertices per layer after arcs are split (a tolerance far below the
#: features would otherwise make millions).
MAX_VERTICES = 2_000_000
#: The finest arc tolerance accepted (mm): 0.1 um, far below any drop, and a bound on the
#: vertices a circle can make (157 for a 1 mm pad, 2 200 for a 200 mm disc).
MIN_TOLERANCE_MM = 1e-4
#: Boundary samples of the ray test for the narrowest track and gap.
MAX_RAY_SAMPLES = 20_000
#: The widest layer (mm): every coordinate lies within rotoprint.ranges.COORD_MM, as a mesh's.
MAX_SPAN_MM = COORD_MM.hi - COORD_MM.lo


def check_extent(region: BaseGeometry, *, path=None, hint: str = "") -> None:
    """A :class:`CadError` unless every coordinate of ``region`` is finite and within
    :data:`rotoprint.ranges.COORD_MM` (mm); the message gives the size the layer would have.
    An empty region passes (it has no coordinates)."""
    if region.is_empty:
        return
    x0, y0, x1, y1 = (float(v) for v in region.bounds)
    ok = all(math.isfinite(v) and COORD_MM.lo <= v <= COORD_MM.hi for v in (x0, y0, x1, y1))
    if ok and math.isfinite(region.area):
        return
    raise CadError(f"the layer would be {x1 - x0:.3g} x {y1 - y0:.3g} mm, from ({x0:.3g}, {y0:.3g}) to "
                   f"({x1:.3g}, {y1:.3g}) mm; a layer must lie {COORD_MM.text()}{hint}", path=path)


def length_unit_mm(unit: str, *, path=None) -> float:
    """Millimetres per ``unit`` (one of :data:`LENGTH_UNITS_MM`); a :class:`CadError` otherwise."""
    try:
        return LENGTH_UNITS_MM[str(unit).strip().lower()]
    except KeyError:
        raise CadError(f"unit {unit!r} is not a length; use one of {', '.join(LENGTH_UNITS_MM)}", path=path) from None


def segments_for_arc(radius: float, sweep_rad: float, tol: float) -> int:
    """Chords for an arc of ``radius`` over ``sweep_rad`` with a sagitta of at most ``tol``.

    Examples
    --------
    >>> segments_for_arc(1.0, 2 * math.pi, 0.01)  # 2 acos(0.99) = 0.284 rad per chord
    23
    """
    sweep = abs(float(sweep_rad))
    if not (math.isfinite(radius) and math.isfinite(sweep)):
        raise CadError(f"an arc's radius ({radius:g}) or sweep ({sweep:g} rad) is not a finite number")
    if radius <= 0 or sweep == 0:
        return 1
    if tol >= radius:
        step = math.pi / 2
    else:
        x = tol / radius  # 1 - x rounds to 1 for a far larger radius: acos(1 - x) ~ sqrt(2 x) there
        step = 2.0 * math.acos(1.0 - x) if x > 1e-8 else 2.0 * math.sqrt(2.0 * x)
    chords = sweep / step - 1e-12 if step > 0 else math.inf
    n = max(1, math.ceil(chords)) if chords <= MAX_VERTICES else math.inf
    if n > MAX_VERTICES:
        raise CadError(f"an arc of radius {radius:g} mm at a tolerance of {tol:g} mm needs {chords:.3g} chords "
                       f"(limit {MAX_VERTICES:,}); use a larger tolerance")
    return n


def arc_points(cx: float, cy: float, r: float, a0: float, sweep: float, tol: float) -> np.ndarray:
    """``(n + 1, 2) float64`` points on the arc from angle ``a0`` over ``sweep`` (radians,
    counter-clockwise positive), ends included, chords within ``tol`` of the arc."""
    n = segments_for_arc(r, sweep, tol)
    t = a0 + sweep * np.arange(n + 1) / n
    pts = np.stack([cx + r * np.cos(t), cy + r * np.sin(t)], 1)
    return pts


def circle_polygon(cx: float, cy: float, r: float, tol: float) -> Polygon:
    """A disc as the inscribed polygon with chords within ``tol`` of the circle."""
    if not r > 0:
        raise CadError(f"a circle needs a positive radius, got {r:g}")
    pts = arc_points(cx, cy, r, 0.0, 2 * math.pi, tol)[:-1]
    if len(pts) < 8:
        pts = arc_points(cx, cy, r, 0.0, 2 * math.pi, min(tol, r * (1 - math.cos(math.pi / 8))))[:-1]
    return Polygon(pts)


def quad_segs(width: float, tol: float) -> int:
    """Shapely ``quad_segs`` for round caps and joins of a stroke of ``width`` within ``tol``."""
    return max(2, segments_for_arc(width / 2, math.pi / 2, tol))


def stroke(points, width: float, tol: float) -> Polygon | MultiPolygon:
    """The region swept by a disc of diameter ``width`` along the polyline ``points``
    (round caps and joins, arcs within ``tol``); a single point gives a disc."""
    pts = np.asarray(points, np.float64)
    if not width > 0:
        raise CadError(f"a stroke needs a positive width, got {width:g}")
    if len(pts) == 1 or np.allclose(pts, pts[0], atol=0, rtol=0):
        return circle_polygon(float(pts[0, 0]), float(pts[0, 1]), width / 2, tol)
    return LineString(pts).buffer(width / 2, quad_segs=quad_segs(width, tol))


def as_multipolygon(g: BaseGeometry) -> MultiPolygon:
    """Only the polygons of ``g`` (lines and points of a boolean result dropped)."""
    if g.is_empty:
        return MultiPolygon()
    if isinstance(g, Polygon):
        return MultiPolygon([g])
    if isinstance(g, MultiPolygon):
        return g
    polys = [p for p in shapely.get_parts(g) if isinstance(p, Polygon) and not p.is_empty]
    out = []
    for p in polys:
        out.extend(as_multipolygon(p).geoms)
    return MultiPolygon(out)


def check_valid(poly: Polygon, what: str, *, path=None) -> Polygon:
    """``poly`` unchanged if it is a valid simple polygon; otherwise a :class:`CadError` naming
    ``what`` and where (a self-intersecting contour)."""
    if poly.is_valid:
        return poly
    reason = shapely.is_valid_reason(poly)
    raise CadError(f"{what} is not a simple closed contour: {reason}", path=path)


@dataclass(frozen=True, eq=False)
class PlanarLayer:
    """A planar region read from a CAD file, in millimetres, with its named terminals.

    Attributes
    ----------
    region : MultiPolygon
        The dark area (clear polarity, holes and overlaps resolved), mm.
    terminals : dict of str to Polygon
        Named pads (Gerber net ``TO.N``, pin ``TO.P`` or aperture attribute ``TA.Terminal``).
    source : str
        File name.
    fmt : str
        ``gerber``, ``excellon``, ``dxf`` or ``svg``.
    tolerance_mm : float
        Largest distance of an arc's chords from the arc.
    """

    region: MultiPolygon
    terminals: dict = field(default_factory=dict)
    source: str = ""
    fmt: str = ""
    tolerance_mm: float = 0.0
    counts: dict = field(default_factory=dict)

    @property
    def area_mm2(self) -> float:
        return float(self.region.area)

    @property
    def regions(self) -> int:
        return len(self.region.geoms)

    @property
    def holes(self) -> int:
        return int(sum(len(p.interiors) for p in self.region.geoms))

    def vertices(self) -> int:
        return int(shapely.get_num_coordinates(self.region))

    def transformed(self, *, mirror_x: bool = False, rotate_deg: float = 0.0, translate_mm=(0.0, 0.0),
                    scale: float = 1.0) -> PlanarLayer:
        """Scaled, then mirrored (``x -> -x``, a bottom layer seen from the top), rotated about
        the origin, then translated: region and terminals alike."""
        a = math.radians(rotate_deg)
        c, s = math.cos(a), math.sin(a)
        m = -1.0 if mirror_x else 1.0
        # [x', y'] = R @ diag(m, 1) @ scale [x, y] + t
        M = [scale * m * c, -scale * s, scale * m * s, scale * c, float(translate_mm[0]), float(translate_mm[1])]
        from shapely import affinity

        def tr(g):
            out = affinity.affine_transform(g, M)
            return shapely.orient_polygons(out) if mirror_x else out

        reg = as_multipolygon(tr(self.region))
        terms = {k: tr(v) for k, v in self.terminals.items()}
        return PlanarLayer(reg, terms, self.source, self.fmt, self.tolerance_mm, dict(self.counts))

    def bounds_mm(self) -> tuple[float, float, float, float]:
        if self.region.is_empty:
            raise CadError("the layer has no area (nothing dark in it)", path=self.source or None)
        return tuple(float(v) for v in self.region.bounds)

    def oriented_rings(self) -> list[np.ndarray]:
        """Closed rings, exteriors counter-clockwise and holes clockwise (the slicer's
        orientation: nonzero winding gives the region), each ``(n + 1, 2) float64``."""
        g = shapely.orient_polygons(self.region, exterior_cw=False)
        rings = []
        for p in as_multipolygon(g).geoms:
            rings.append(np.asarray(p.exterior.coords, np.float64))
            rings.extend(np.asarray(r.coords, np.float64) for r in p.interiors)
        return rings

    def info(self) -> dict:
        track, track_at = narrowest_mm(self.region, inward=True, min_mm=2 * self.tolerance_mm)
        gap, gap_at = narrowest_mm(self.region, inward=False, min_mm=2 * self.tolerance_mm)
        if self.region.is_empty:  # an empty layer (a header and an end) has no bounds: null, never NaN
            bounds, size = None, None
        else:
            b = [float(v) for v in self.region.bounds]
            bounds, size = {"min": [b[0], b[1]], "max": [b[2], b[3]]}, [b[2] - b[0], b[3] - b[1]]
        return {
            "file": self.source, "format": self.fmt, "area_mm2": self.area_mm2,
            "bounds_mm": bounds, "size_mm": size,
            "regions": self.regions, "holes": self.holes, "vertices": self.vertices(),
            "narrowest_track_mm": track, "narrowest_track_at_mm": track_at,
            "narrowest_gap_mm": gap, "narrowest_gap_at_mm": gap_at,
            "tolerance_mm": self.tolerance_mm, "terminals": {k: list(v.bounds) for k, v in self.terminals.items()},
            "counts": self.counts,
        }


def narrowest_mm(region: MultiPolygon, *, inward: bool, samples: int = MAX_RAY_SAMPLES,
                 min_mm: float = 0.0) -> tuple[float | None, list | None]:
    """Narrowest track (``inward``) or gap of a region, by rays along the boundary normals.

    From points spread along every boundary edge (never at a vertex), a ray along the edge's
    inward (track) or outward (gap) normal runs to the first other boundary crossing; the
    shortest ray is the narrowest track or gap, exact for straight parallel edges and for
    discs (a diameter). A gap ray that leaves the region's bounding box finds nothing.

    Parameters
    ----------
    region : MultiPolygon
        Exterior rings counter-clockwise or not: orientation is normalised here.
    inward : bool
    samples : int
        About this many rays over the whole boundary (at least one per edge).
    min_mm : float
        Rays this short or shorter are ignored (notches of chord noise where two arcs'
        polygons meet; the layer passes twice its tolerance).

    Returns
    -------
    width_mm : float or None
        None when no ray closes (an empty region, or no gap).
    at_mm : list of 2 float, or None
        The ray's midpoint.
    """
    if region.is_empty:
        return None, None
    g = shapely.orient_polygons(region, exterior_cw=False)
    edges_a, edges_b = [], []
    for p in as_multipolygon(g).geoms:
        for ring in (p.exterior, *p.interiors):
            c = np.asarray(ring.coords, np.float64)
            edges_a.append(c[:-1])
            edges_b.append(c[1:])
    a = np.concatenate(edges_a)
    b = np.concatenate(edges_b)
    d = b - a
    ln = np.hypot(d[:, 0], d[:, 1])
    keep = ln > 0
    a, d, ln = a[keep], d[keep], ln[keep]
    total = float(ln.sum())
    per = np.maximum(1, np.floor(ln / total * samples)).astype(np.int64)
    idx = np.repeat(np.arange(len(a)), per)
    # parameters strictly inside each edge: (k + 0.5) / per
    start = np.concatenate([[0], np.cumsum(per)[:-1]])
    k = np.arange(idx.size) - np.repeat(start, per)
    t = (k + 0.5) / per[idx]
    pts = a[idx] + d[idx] * t[:, None]
    u = d[idx] / ln[idx, None]
    # counter-clockwise exterior: the interior is on the left, normal (-uy, ux)
    n = np.stack([-u[:, 1], u[:, 0]], 1) * (1.0 if inward else -1.0)
    x0, y0, x1, y1 = region.bounds
    L = 2.0 * math.hypot(x1 - x0, y1 - y0) + 1.0
    eps = 1e-9 * L
    p0 = pts + n * eps
    p1 = pts + n * L
    rays = shapely.linestrings(np.stack([p0, p1], 1))
    ea, eb = np.concatenate(edges_a), np.concatenate(edges_b)
    tree = shapely.STRtree(shapely.linestrings(np.stack([ea, eb], 1)))
    ri, ei = tree.query(rays, predicate="intersects")
    # ray p0 + t (p1 - p0), edge ea + s (eb - ea): solve for t (Cramer's rule)
    r = p1[ri] - p0[ri]
    e = eb[ei] - ea[ei]
    q = ea[ei] - p0[ri]
    den = r[:, 0] * e[:, 1] - r[:, 1] * e[:, 0]
    ok = den != 0
    t = np.where(ok, (q[:, 0] * e[:, 1] - q[:, 1] * e[:, 0]) / np.where(ok, den, 1.0), np.inf)
    dist = np.full(len(pts), np.inf)
    np.minimum.at(dist, ri, eps + t * (L - eps))
    # features narrower than the chords' own noise (twice the tolerance) are not features
    dist[dist <= min_mm] = np.inf
    j = int(np.argmin(dist))
    if not np.isfinite(dist[j]):
        return None, None
    w = float(dist[j])
    mid = pts[j] + n[j] * w / 2
    return w, [float(mid[0]), float(mid[1])]


def fill_rings(rings: list[np.ndarray], rule: str = "evenodd") -> MultiPolygon:
    """The region filled by closed rings under a fill rule, exactly.

    The rings' edges are noded into faces (:func:`shapely.polygonize`); a face is filled
    when its winding number (sum of the orientations of the rings around one of its points)
    is odd (``evenodd``) or not zero (``nonzero``), and the filled faces are unioned.

    Parameters
    ----------
    rings : list of (n, 2) float64
        Closed or not (the last point joins the first).
    rule : {'evenodd', 'nonzero'}

    Returns
    -------
    MultiPolygon
    """
    rings = [np.asarray(r, np.float64) for r in rings if len(r) >= 3]
    if not rings:
        return MultiPolygon()
    closed = [r if np.array_equal(r[0], r[-1]) else np.vstack([r, r[:1]]) for r in rings]
    lines = shapely.linestrings(closed) if len({len(c) for c in closed}) == 1 else [LineString(c) for c in closed]
    noded = shapely.union_all(lines)
    faces = [f for f in shapely.get_parts(shapely.polygonize(shapely.get_parts(noded))) if f.area > 0]
    if not faces:
        return MultiPolygon()
    rep = shapely.point_on_surface(faces)
    px, py = shapely.get_x(rep), shapely.get_y(rep)
    wind = np.zeros(len(faces), np.int64)
    for c in closed:
        wind += winding_numbers(c, px, py)
    keep = (wind % 2 == 1) if rule == "evenodd" else (wind != 0)
    filled = [f for f, k in zip(faces, keep) if k]
    return as_multipolygon(shapely.union_all(filled)) if filled else MultiPolygon()


def winding_numbers(ring: np.ndarray, px: np.ndarray, py: np.ndarray, *, chunk: int = 2_000_000) -> np.ndarray:
    """``(P,) int64`` winding number of the closed ring ``(n + 1, 2)`` around each point
    (crossing rule: an edge crossing the point's rightward ray upwards counts +1, downwards
    -1; a point exactly on an edge is not meant to be asked)."""
    a = ring[:-1]
    b = ring[1:]
    px = np.asarray(px, np.float64)
    py = np.asarray(py, np.float64)
    out = np.zeros(px.size, np.int64)
    step = max(1, chunk // max(1, len(a)))
    for s in range(0, px.size, step):
        x = px[s:s + step, None]
        y = py[s:s + step, None]
        left = (b[None, :, 0] - a[None, :, 0]) * (y - a[None, :, 1]) - (x - a[None, :, 0]) * (b[None, :, 1] - a[None, :, 1])
        up = (a[None, :, 1] <= y) & (b[None, :, 1] > y) & (left > 0)
        down = (a[None, :, 1] > y) & (b[None, :, 1] <= y) & (left < 0)
        out[s:s + step] = up.sum(1) - down.sum(1)
    return out
