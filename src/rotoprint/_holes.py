"""Filling the holes of a mesh: boundary loops found from the topology and triangulated.

A *hole* is a closed loop of boundary edges (edges used by one face). The loops are walked
along the boundary half-edges in the direction their own face runs them; the fill runs each
loop the other way, so every filled edge ends up used twice, in opposite directions, and the
fill is wound consistently with the faces around it (outward where they are outward).

How a loop is triangulated (in this order):

1. it is projected on its best-fit plane (the least-squares plane of its vertices, normal
   from an SVD), oriented by the loop's Newell normal;
2. if the projection is a simple polygon, it is cut by ear clipping into ``n - 2`` triangles
   on the loop's own vertices. For a *planar* loop (every vertex within ``PLANAR_TOL_REL`` of
   the mesh's diagonal from the plane) this is exact: the fill lies in the loop's plane and
   covers exactly the polygon. For a non-planar loop it is a triangulation whose projection
   tiles the projected polygon;
3. otherwise (the projection crosses itself), it is a fan from the loop's centroid (one new
   vertex, ``n`` triangles), provided every fan triangle faces the way the loop runs (the
   loop is star-shaped about its centroid seen along its normal);
4. otherwise the loop is not filled: the per-layer chords close what it leaves open.

Which loops are filled is decided in :func:`find_and_fill` (see :data:`FILL_POLICY`).
"""

from __future__ import annotations

import numpy as np

from ._dataclass import dataclass

__all__ = ["FilledHole", "HoleReport", "find_and_fill", "FILL_POLICY"]

#: A loop is planar when every vertex lies within this fraction of the mesh's bounding-box
#: diagonal from the loop's best-fit plane.
PLANAR_TOL_REL: float = 1e-9
#: A loop whose fill would have more than this fraction of the area of the faces of its shell
#: is an intentionally open surface (a sheet, a single triangle, a ribbon) and is not filled.
MAX_FILL_AREA_FRACTION: float = 0.5
#: Loops with more edges than this are left to the per-layer chords (ear clipping is
#: quadratic in the loop length).
MAX_LOOP_EDGES: int = 20_000

#: Ear clipping gives up after this many ear tests per vertex (typical loops need 1 to 3).
EAR_TESTS_PER_VERTEX: int = 64

FILL_POLICY = (
    "every closed loop of boundary edges is filled, unless its fill would exceed "
    f"{MAX_FILL_AREA_FRACTION:g} of its shell's area (an open sheet), it has more than "
    f"{MAX_LOOP_EDGES} edges, its edges do not form a consistently wound closed walk, or it can be "
    "triangulated neither in its best-fit plane nor as a fan from its centroid without folding over"
)


@dataclass(frozen=True)
class FilledHole:
    """One boundary loop that was filled: its edge count, the area of the fill (mm^2),
    whether it was planar, and how it was triangulated (``'ear-clipping'`` or
    ``'centroid-fan'``)."""

    edges: int
    area_mm2: float
    planar: bool
    method: str

    def to_json(self) -> dict:
        return {"edges": self.edges, "area_mm2": self.area_mm2, "planar": self.planar, "method": self.method}


@dataclass(frozen=True)
class HoleReport:
    """What hole filling did: the loops filled, and the boundary edges left open (why)."""

    filled: tuple[FilledHole, ...] = ()
    left_open_loops: int = 0  # closed loops not filled (sheet rule or too long)
    left_open_edges: int = 0  # boundary edges left open (in those loops or in no closed walk)
    enabled: bool = True

    @property
    def filled_edges(self) -> int:
        return sum(h.edges for h in self.filled)

    @property
    def filled_area_mm2(self) -> float:
        return float(sum(h.area_mm2 for h in self.filled))

    def to_json(self, max_loops: int = 50) -> dict:
        largest = sorted(self.filled, key=lambda h: -h.area_mm2)[:max_loops]
        return {
            "enabled": self.enabled,
            "policy": FILL_POLICY,
            "filled": len(self.filled),
            "filled_edges": self.filled_edges,
            "filled_area_mm2": self.filled_area_mm2,
            "largest_filled": [h.to_json() for h in largest],
            "left_open_loops": self.left_open_loops,
            "left_open_edges": self.left_open_edges,
        }


# ---------------------------------------------------------------------- loops
def boundary_loops(faces: np.ndarray, boundary_sides: np.ndarray) -> tuple[list[np.ndarray], int]:
    """Closed walks of boundary half-edges.

    Parameters
    ----------
    faces : (F, 3) int64
    boundary_sides : (F, 3) bool
        Side ``k`` of face ``f`` (vertex ``k`` to ``k + 1``) lies on an edge used once.

    Returns
    -------
    loops : list of (n,) int64
        Vertex indices in the order the faces run the edges; a vertex where the boundary
        touches itself splits the walk into separate simple loops.
    stray : int
        Boundary half-edges in no closed walk (the boundary is inconsistently wound there).
    """
    f_idx, k_idx = np.nonzero(boundary_sides)
    if f_idx.size == 0:
        return [], 0
    a = faces[f_idx, k_idx]
    b = faces[f_idx, (k_idx + 1) % 3]
    order = np.argsort(a, kind="stable")
    a, b = a[order], b[order]
    # outgoing half-edges of vertex v: positions lo[v]..hi[v] of the sorted list
    verts, first = np.unique(a, return_index=True)
    start_of = dict(zip(verts.tolist(), first.tolist()))
    count_of = dict(zip(verts.tolist(), np.diff(np.append(first, len(a))).tolist()))
    used = np.zeros(len(a), bool)
    next_free = dict(start_of)  # next candidate outgoing half-edge per vertex
    a_l, b_l = a.tolist(), b.tolist()

    def take(v: int) -> int:
        s = start_of.get(v)
        if s is None:
            return -1
        end = s + count_of[v]
        i = next_free[v]
        while i < end and used[i]:
            i += 1
        next_free[v] = i
        return i if i < end else -1

    loops: list[np.ndarray] = []
    stray = 0
    for h0 in range(len(a_l)):
        if used[h0]:
            continue
        path = [a_l[h0]]
        pos = {a_l[h0]: 0}
        used[h0] = True
        v = b_l[h0]
        while True:
            if v in pos:  # closed a cycle: cut it off, keep walking from v
                p = pos[v]
                cyc = path[p:]
                loops.append(np.asarray(cyc, np.int64))
                for w in cyc:
                    del pos[w]
                del path[p:]
                if not path:
                    break  # the walk is used up; v is again its tip otherwise
            h = take(v)
            if h < 0:  # dead end: what is left of the walk closes nowhere
                stray += len(path)
                break
            used[h] = True
            pos[v] = len(path)
            path.append(v)
            v = b_l[h]
    return loops, stray


# ---------------------------------------------------------------------- triangulation
def _newell(p: np.ndarray) -> np.ndarray:
    q = np.roll(p, -1, axis=0)
    return np.array([
        np.sum((p[:, 1] - q[:, 1]) * (p[:, 2] + q[:, 2])),
        np.sum((p[:, 2] - q[:, 2]) * (p[:, 0] + q[:, 0])),
        np.sum((p[:, 0] - q[:, 0]) * (p[:, 1] + q[:, 1])),
    ])


def _plane(p: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Best-fit plane of ``(n, 3)`` points: a ``(2, 3)`` in-plane basis whose normal follows the
    points' Newell normal, the ``(3,)`` normal, and the largest distance from the plane."""
    c = p.mean(axis=0)
    _, _, vt = np.linalg.svd(p - c, full_matrices=False)
    n = vt[2]
    newell = _newell(p)
    if np.dot(n, newell) < 0:
        n = -n
    e1 = vt[0]
    e2 = np.cross(n, e1)
    dev = float(np.abs((p - c) @ n).max())
    return np.stack([e1, e2]), n, dev


def _simple(xy: np.ndarray) -> bool:
    """``(n, 2)`` closed polygon without self-crossings or repeated points."""
    from shapely.geometry import LinearRing

    if len(np.unique(xy, axis=0)) != len(xy):
        return False
    try:
        return bool(LinearRing(xy).is_simple)
    except Exception:  # noqa: BLE001 - shapely refuses some degenerate rings
        return False


def ear_clip(xy: np.ndarray) -> np.ndarray | None:
    """Ear clipping of a simple counter-clockwise ``(n, 2)`` polygon.

    Returns ``(n - 2, 3) int64`` corner indices, counter-clockwise, or ``None`` when no ear
    can be found (a polygon that is not simple, or not counter-clockwise), or when the search
    takes more than ``EAR_TESTS_PER_VERTEX * n`` ear tests (a bound on crafted spirals).
    """
    n = len(xy)
    if n < 3:
        return None
    if n == 3:
        return np.array([[0, 1, 2]], np.int64)
    x = xy[:, 0].copy()
    y = xy[:, 1].copy()
    prv = np.roll(np.arange(n), 1)
    nxt = np.roll(np.arange(n), -1)
    alive = np.ones(n, bool)

    def cross(i: int) -> float:
        a, c = prv[i], nxt[i]
        return (x[i] - x[a]) * (y[c] - y[i]) - (y[i] - y[a]) * (x[c] - x[i])

    reflex = np.array([cross(i) <= 0 for i in range(n)])
    out = np.empty((n - 2, 3), np.int64)
    m = 0
    i = 0
    remaining = n
    misses = 0
    budget = EAR_TESTS_PER_VERTEX * n
    while remaining > 3:
        budget -= 1
        if budget < 0:
            return None
        a, c = prv[i], nxt[i]
        is_ear = False
        if not reflex[i]:
            cand = np.flatnonzero(alive & reflex)
            cand = cand[(cand != a) & (cand != c) & (cand != i)]
            if cand.size:
                px, py = x[cand], y[cand]
                # inside or on the triangle (a, i, c), counter-clockwise
                d1 = (x[i] - x[a]) * (py - y[a]) - (y[i] - y[a]) * (px - x[a])
                d2 = (x[c] - x[i]) * (py - y[i]) - (y[c] - y[i]) * (px - x[i])
                d3 = (x[a] - x[c]) * (py - y[c]) - (y[a] - y[c]) * (px - x[c])
                is_ear = not np.any((d1 >= 0) & (d2 >= 0) & (d3 >= 0))
            else:
                is_ear = True
        if is_ear:
            out[m] = (a, i, c)
            m += 1
            alive[i] = False
            nxt[a], prv[c] = c, a
            remaining -= 1
            reflex[a] = cross(a) <= 0
            reflex[c] = cross(c) <= 0
            misses = 0
            i = c
            continue
        misses += 1
        if misses > remaining:
            # No strict ear: clip a collinear vertex (a zero-area link) if there is one.
            alive_idx = np.flatnonzero(alive)
            flat = [j for j in alive_idx if cross(int(j)) == 0]
            if not flat:
                return None
            j = int(flat[0])
            a, c = prv[j], nxt[j]
            out[m] = (a, j, c)
            m += 1
            alive[j] = False
            nxt[a], prv[c] = c, a
            remaining -= 1
            reflex[a] = cross(a) <= 0
            reflex[c] = cross(c) <= 0
            misses = 0
            i = c
            continue
        i = nxt[i]
    rest = np.flatnonzero(alive)
    j = int(rest[0])
    out[m] = (prv[j], j, nxt[j])
    return out


def _triangle_area_sum(p: np.ndarray, tri: np.ndarray) -> float:
    v0, v1, v2 = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
    return float(0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1).sum())


def triangulate_loop(points: np.ndarray, planar_tol_mm: float) -> tuple[np.ndarray, np.ndarray | None, bool, str]:
    """Triangulate one hole (see the module doc).

    Parameters
    ----------
    points : (n, 3) float64
        The loop's vertices in the order the *fill* runs them.
    planar_tol_mm : float

    Returns
    -------
    tri : (T, 3) int64 or None
        ``None`` when the loop cannot be filled without folding over (left to the chords).
        Otherwise corner indices into ``points`` (index ``n`` is the added centroid, if any), wound
        the way the fill runs the loop.
    centroid : (3,) float64 or None
        The added vertex of a centroid fan.
    planar : bool
    method : str
    """
    basis, normal, dev = _plane(points)
    planar = dev <= planar_tol_mm
    xy = (points - points.mean(axis=0)) @ basis.T
    # basis rows e1, e2 with e1 x e2 = normal, normal along the fill's Newell normal: CCW
    area2 = float(np.sum(xy[:, 0] * np.roll(xy[:, 1], -1) - np.roll(xy[:, 0], -1) * xy[:, 1]))
    if area2 > 0 and _simple(xy):
        tri = ear_clip(xy)
        if tri is not None:
            return tri, None, planar, "ear-clipping"
    n = len(points)
    c = points.mean(axis=0)
    i = np.arange(n)
    tri = np.stack([i, (i + 1) % n, np.full(n, n)], axis=1)
    # The fan is used only when every triangle faces the way the loop runs (the loop is
    # star-shaped around its centroid, seen along its normal); otherwise it would fold over.
    p = np.vstack([points, c])
    nrm = np.cross(p[tri[:, 1]] - p[tri[:, 0]], p[tri[:, 2]] - p[tri[:, 0]])
    if not np.all(nrm @ normal > 0):
        return None, None, planar, "none"
    return tri, c, planar, "centroid-fan"


# ---------------------------------------------------------------------- policy
def find_and_fill(vertices: np.ndarray, faces: np.ndarray, boundary_sides: np.ndarray, shell: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray, HoleReport]:
    """Fill the holes of a mesh whose faces are consistently wound.

    Parameters
    ----------
    vertices : (V, 3) float64
    faces : (F, 3) int64
    boundary_sides : (F, 3) bool
        Sides on edges used by one face.
    shell : (F,) int64
        Connected shell of every face.

    Returns
    -------
    vertices : (V', 3) float64
        ``vertices`` followed by any centroid added by a fan.
    faces : (F', 3) int64
        ``faces`` followed by the fill triangles.
    report : HoleReport
    """
    loops, stray = boundary_loops(faces, boundary_sides)
    if not loops:
        return vertices, faces, HoleReport(left_open_edges=stray)
    diag = float(np.linalg.norm(vertices.max(0) - vertices.min(0))) or 1.0
    planar_tol = PLANAR_TOL_REL * diag
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    face_area = 0.5 * np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)
    shell_area = np.bincount(shell, weights=face_area)
    # the shell of a loop: the shell of the face owning its first half-edge
    owner = {}
    f_idx, k_idx = np.nonzero(boundary_sides)
    for f, k in zip(f_idx.tolist(), k_idx.tolist()):
        owner[(int(faces[f, k]), int(faces[f, (k + 1) % 3]))] = f
    new_vertices: list[np.ndarray] = []
    new_faces: list[np.ndarray] = []
    filled: list[FilledHole] = []
    left_loops = 0
    left_edges = stray
    n_v = vertices.shape[0]
    for loop in loops:
        n = len(loop)
        if n > MAX_LOOP_EDGES:
            left_loops += 1
            left_edges += n
            continue
        fill_order = loop[::-1]  # the fill runs the loop against its faces
        pts = vertices[fill_order]
        tri, centroid, planar, method = triangulate_loop(pts, planar_tol)
        if tri is None:
            left_loops += 1
            left_edges += n
            continue
        if centroid is not None:
            all_pts = np.vstack([pts, centroid])
            idx = np.append(fill_order, n_v)
        else:
            all_pts, idx = pts, fill_order
        area = _triangle_area_sum(all_pts, tri)
        s = shell[owner[(int(loop[0]), int(loop[1 % n]))]]
        if n < 3 or area > MAX_FILL_AREA_FRACTION * shell_area[s]:
            left_loops += 1
            left_edges += n
            continue
        if centroid is not None:
            new_vertices.append(centroid[None, :])
            n_v += 1
        new_faces.append(idx[tri])
        filled.append(FilledHole(edges=n, area_mm2=area, planar=bool(planar), method=method))
    report = HoleReport(filled=tuple(filled), left_open_loops=left_loops, left_open_edges=left_edges)
    if not new_faces:
        return vertices, faces, report
    if new_vertices:
        vertices = np.vstack([vertices, *new_vertices])
    return vertices, np.vstack([faces, *new_faces]), report
