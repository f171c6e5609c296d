"""The validated triangle mesh every stage works on, with its topology.

A :class:`Mesh` is built from raw triangles by :meth:`Mesh.from_triangles`, which

1. merges vertices with bit-identical coordinates (``-0.0`` and ``0.0`` are one),
2. drops faces that repeat a vertex (they have no area and no orientation),
3. counts zero-area triangles (kept: they carry no area but link their neighbours),
4. makes the winding of every connected shell consistent across its manifold edges,
4b. fills the holes (closed loops of boundary edges; see :mod:`rotoprint._holes` for the
   triangulation and the policy) with triangles wound like the faces around them, and makes
   the winding consistent again over the repaired shells (``fill_holes=False`` skips this),
5. orients shells by the *nesting rule* (shells with at least 4 faces, and open on at most
   ``MAX_OPEN_SIDE_FRACTION`` of their sides; a volume sign means nothing for the rest): a shell that no other shell contains is a solid
   and must enclose positive volume, so a top-level shell with negative volume is turned
   outside-in together with every shell nested in it; nested shells keep their orientation
   relative to their container (an inward shell inside a solid is a cavity, an outward one a
   second solid, which the nonzero fill rule unions). ``orient="keep"`` skips 4 and 5.

A shell is *nested* in another when every one of its sample vertices has a generalized
winding number of magnitude above 1/2 with respect to the other.
"""

from __future__ import annotations

import dataclasses
from functools import cached_property

import numpy as np

from ._dataclass import dataclass, field
from .constants import DEGENERATE_AREA_REL, MAX_COORDINATE_MM, MAX_OPEN_SIDE_FRACTION
from .errors import MeshError
from ._holes import HoleReport, find_and_fill

__all__ = ["Mesh", "MeshReport", "winding_number"]

_SAMPLE_VERTICES = 32


@dataclass(frozen=True)
class MeshReport:
    """What loading found and repaired. Counts are of triangles unless named otherwise."""

    triangles_in: int
    collapsed_dropped: int
    degenerate: int
    faces_reoriented: int
    shells: int
    shells_flipped: int
    open_edges: int
    nonmanifold_edges: int
    orientation_conflicts: int
    holes: HoleReport = field(default_factory=HoleReport)

    @property
    def watertight(self) -> bool:
        return self.open_edges == 0 and self.nonmanifold_edges == 0 and self.orientation_conflicts == 0


@dataclass(frozen=True, eq=False)
class Mesh:
    """A triangle mesh in millimetres.

    Attributes
    ----------
    vertices : (V, 3) float64
    faces : (F, 3) int64
        Indices into ``vertices``; consistently wound, outward for solids (see module doc).
    source : str or None
        Where the mesh came from (a path, or a description).
    report : MeshReport
    """

    vertices: np.ndarray
    faces: np.ndarray
    source: str | None = None
    report: MeshReport = field(default=None)  # type: ignore[assignment]

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_triangles(cls, triangles: np.ndarray, *, source: str | None = None, orient: str = "auto",
                       fill_holes: bool = True, _owned: bool = False) -> Mesh:
        """Build a mesh from ``(N, 3, 3)`` float triangles (see the module doc for the steps).

        ``fill_holes``: fill the mesh's boundary loops (step 4b; only with ``orient="auto"``).

        ``_owned``: the caller hands the array over, so it may be modified in place (and
        freed once the vertices are merged, when it comes inside a one-element list)."""
        if _owned and isinstance(triangles, list) and len(triangles) == 1:
            triangles = triangles.pop()
        tri = np.asarray(triangles, dtype=np.float64)
        if tri.ndim != 3 or tri.shape[1:] != (3, 3):
            raise MeshError(f"triangles must have shape (N, 3, 3), got {tri.shape}", path=source)
        if tri.shape[0] == 0:
            raise MeshError("mesh holds no triangles", path=source)
        if not np.isfinite(tri).all():
            raise MeshError("mesh has NaN or infinite coordinates", path=source)
        biggest = float(np.abs(tri).max())
        if biggest > MAX_COORDINATE_MM:
            raise MeshError(f"a coordinate reaches {biggest:.3g} mm; the largest supported is {MAX_COORDINATE_MM:g} mm "
                            "(check --units, --scale and --translate)", path=source)
        if orient not in ("auto", "keep"):
            raise MeshError(f"orient must be 'auto' or 'keep', got {orient!r}")
        n_in = tri.shape[0]
        flat = tri.reshape(-1, 3)
        if _owned and flat.base is not None and flat.flags.c_contiguous:
            flat += 0.0  # folds -0.0 into 0.0 so the two merge (in place: the array is ours)
        else:
            flat = flat + 0.0
        del tri, triangles
        vertices, inverse = _unique_rows(flat)
        del flat
        faces = inverse.reshape(-1, 3)
        collapsed = (faces[:, 0] == faces[:, 1]) | (faces[:, 1] == faces[:, 2]) | (faces[:, 2] == faces[:, 0])
        faces = faces[~collapsed]
        if faces.shape[0] == 0:
            raise MeshError("every triangle is collapsed to a line or a point", path=source)
        diag2 = float(np.sum((vertices.max(0) - vertices.min(0)) ** 2)) or 1.0
        area2 = _double_areas(vertices, faces)
        degenerate = int(collapsed.sum() + np.count_nonzero(area2 <= 2 * DEGENERATE_AREA_REL * diag2))

        n_reoriented = n_shells_flipped = 0
        holes = HoleReport(enabled=fill_holes and orient == "auto")
        topo = _Topology(faces, vertices.shape[0])
        if orient == "auto":
            faces, n_reoriented = _make_winding_consistent(faces, topo)
            if n_reoriented:
                topo = _Topology(faces, vertices.shape[0])
            if fill_holes and topo.boundary_edge.any():
                n_before = faces.shape[0]
                vertices, faces, holes = find_and_fill(vertices, faces, topo.boundary_edge[topo.face_edges], topo.shell)
                if faces.shape[0] != n_before:
                    topo = _Topology(faces, vertices.shape[0])
                    faces, n_again = _make_winding_consistent(faces, topo)
                    n_reoriented += n_again
                    if n_again:
                        topo = _Topology(faces, vertices.shape[0])
            elif not fill_holes:
                holes = HoleReport(enabled=False)
            faces, n_shells_flipped = _orient_shells(vertices, faces, topo)
            if n_shells_flipped:
                topo = _Topology(faces, vertices.shape[0])
        report = MeshReport(
            triangles_in=n_in,
            collapsed_dropped=int(collapsed.sum()),
            degenerate=degenerate,
            faces_reoriented=n_reoriented,
            shells=topo.n_shells,
            shells_flipped=n_shells_flipped,
            open_edges=int(np.count_nonzero(topo.edge_face_count == 1)),
            nonmanifold_edges=int(np.count_nonzero(topo.edge_face_count > 2)),
            orientation_conflicts=topo.orientation_conflicts,
            holes=holes,
        )
        mesh = cls(vertices=vertices, faces=faces, source=source, report=report)
        object.__setattr__(mesh, "_topology", topo)
        return mesh

    # ------------------------------------------------------------------ properties
    @property
    def triangles(self) -> np.ndarray:
        """``(F, 3, 3) float64`` vertex coordinates per face."""
        return self.vertices[self.faces]

    @cached_property
    def topology(self) -> _Topology:
        topo = self.__dict__.get("_topology")
        return topo if topo is not None else _Topology(self.faces, self.vertices.shape[0])

    @property
    def bounds(self) -> np.ndarray:
        """``(2, 3) float64``: minimum and maximum corner, mm."""
        return np.stack([self.vertices.min(0), self.vertices.max(0)])

    @cached_property
    def volume_mm3(self) -> float:
        """Signed enclosed volume (positive for a solid); meaningful when watertight."""
        return float(_signed_volumes(self.vertices, self.faces, np.zeros(len(self.faces), np.int64), 1)[0])

    @property
    def watertight(self) -> bool:
        return self.report.watertight

    def transformed(self, matrix: np.ndarray) -> Mesh:
        """A copy moved by a ``(4, 4)`` affine (a mirroring one keeps faces outward)."""
        T = np.asarray(matrix, dtype=np.float64)
        v = self.vertices @ T[:3, :3].T + T[:3, 3]
        faces = self.faces[:, ::-1].copy() if np.linalg.det(T[:3, :3]) < 0 else self.faces
        out = dataclasses.replace(self, vertices=v, faces=faces)
        if faces is self.faces:
            object.__setattr__(out, "_topology", self.topology)
        return out

    def info(self) -> dict:
        """A JSON-ready summary: counts, bounds, shells, open edges, volume."""
        r = self.report
        b = self.bounds
        return {
            "source": self.source,
            "triangles": r.triangles_in,
            "faces_used": int(self.faces.shape[0]),
            "vertices": int(self.vertices.shape[0]),
            "bounds_mm": {"min": b[0].tolist(), "max": b[1].tolist()},
            "size_mm": (b[1] - b[0]).tolist(),
            "shells": r.shells,
            "open_edges": r.open_edges,
            "nonmanifold_edges": r.nonmanifold_edges,
            "watertight": r.watertight,
            "watertight_as_read": r.watertight and not r.holes.filled,
            "volume_mm3": self.volume_mm3,
            "volume_exact": r.watertight,
            "degenerate_triangles": r.degenerate,
            "collapsed_triangles_dropped": r.collapsed_dropped,
            "faces_reoriented": r.faces_reoriented,
            "shells_flipped": r.shells_flipped,
            "orientation_conflicts": r.orientation_conflicts,
            "holes": r.holes.to_json(),
        }


# ---------------------------------------------------------------------- topology
class _Topology:
    """Undirected edges and their use by faces.

    ``edges`` (E, 2) int64 sorted vertex pairs; ``face_edges`` (F, 3) int64, the edge of face
    side k (from vertex k to vertex k+1); ``edge_face_count`` (E,) int64; ``shell`` (F,) int64.
    """

    def __init__(self, faces: np.ndarray, n_vertices: int) -> None:
        a = faces
        b = np.roll(faces, -1, axis=1)
        lo = np.minimum(a, b)
        hi = np.maximum(a, b)
        key = lo * np.int64(n_vertices) + hi
        del lo, hi
        from ._accel import native

        self.forward = (a < b)  # (F, 3): side k runs from the lower to the higher vertex index
        fwd = self.forward.ravel()
        if native is not None:
            # Edges by hashing (only the distinct keys sorted), the sides of every edge in one
            # pass: the same edges, numbering and pairs as the sorting path below (tested).
            flat = np.ascontiguousarray(key.ravel())
            first_pos = np.empty(flat.shape[0], np.int64)
            inverse = np.empty(flat.shape[0], np.int64)
            n_e = native.merge_keys(flat, first_pos, inverse)
            uniq = flat[first_pos[:n_e]]
            del first_pos, flat
            order = np.argsort(uniq)
            uniq = uniq[order]
            rank = np.empty(n_e, np.int64)
            rank[order] = np.arange(n_e)
            np.take(rank, inverse, out=inverse)
            del rank, order
            counts = np.bincount(inverse, minlength=n_e)
            s1, s2 = np.empty(n_e, np.int64), np.empty(n_e, np.int64)
            native.first_two(inverse, n_e, s1, s2)
            pair_edges = np.flatnonzero(counts == 2)
            s1, s2 = s1[pair_edges], s2[pair_edges]
        else:
            uniq, inverse, counts = _unique_inverse(key.ravel())
            # Manifold pairs: sides of two faces on one edge used exactly twice.
            order = np.argsort(inverse, kind="stable")
            e_sorted = inverse[order]
            first = np.flatnonzero((e_sorted[:-1] == e_sorted[1:]) & (counts[e_sorted[:-1]] == 2))
            s1, s2 = order[first], order[first + 1]
            pair_edges = e_sorted[first]
        self.edges = np.stack([uniq // n_vertices, uniq % n_vertices], axis=1)
        self.face_edges = inverse.reshape(-1, 3)
        self.edge_face_count = counts
        self.boundary_edge = self.edge_face_count == 1
        self.pair_faces = np.stack([s1 // 3, s2 // 3], axis=1)
        self.pair_same_direction = fwd[s1] == fwd[s2]
        self.orientation_conflicts = int(np.count_nonzero(self.pair_same_direction))
        # Edges where a cross-section chain may end: not used by exactly two faces, or by two
        # faces wound the same way (their chains do not link).
        suspect = self.edge_face_count != 2
        if self.orientation_conflicts:
            suspect[pair_edges[self.pair_same_direction]] = True
        self.suspect_edges = suspect
        # Shells: faces connected through any shared edge (manifold or not), numbered by
        # their lowest face index.
        self.shell, self.n_shells = shell_labels(self.face_edges, self.edges.shape[0])


def shell_labels(face_edges: np.ndarray, n_edges: int) -> tuple[np.ndarray, int]:
    """Connected shells: faces sharing an edge are one shell.

    Parameters
    ----------
    face_edges : (F, 3) int64
        Edge index of every face side, in ``[0, n_edges)``.
    n_edges : int

    Returns
    -------
    labels : (F,) int64
        Shell of every face; shells are numbered in the order of their lowest face index.
    n_shells : int
    """
    from ._accel import native

    fe = np.ascontiguousarray(face_edges, dtype=np.int64)
    if native is not None:
        labels = np.empty(fe.shape[0], np.int64)
        n = native.shell_labels(fe, int(n_edges), labels)
        return labels, int(n)
    return shell_labels_scipy(fe, n_edges)


def shell_labels_scipy(face_edges: np.ndarray, n_edges: int) -> tuple[np.ndarray, int]:
    """Reference of :func:`shell_labels` (scipy's connected components over faces and edges)."""
    from scipy import sparse
    from scipy.sparse import csgraph

    n_f = face_edges.shape[0]
    rows = np.repeat(np.arange(n_f), 3)
    g = sparse.coo_matrix((np.ones(3 * n_f, np.int8), (rows, n_f + face_edges.ravel())), shape=(n_f + n_edges,) * 2)
    _, labels = csgraph.connected_components(g, directed=False)
    _, shell = np.unique(labels[:n_f], return_inverse=True)
    return shell.astype(np.int64), int(shell.max()) + 1


class PrebuiltTopology:
    """The part of a topology the slicer needs, shipped to worker processes so that they do
    not rebuild it: ``face_edges`` (F, 3) int64 and ``suspect_edges`` (E,) bool."""

    def __init__(self, face_edges: np.ndarray, suspect_edges: np.ndarray) -> None:
        self.face_edges = face_edges
        self.suspect_edges = suspect_edges


def _double_areas(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    from ._accel import native

    if native is not None:
        out = np.empty(faces.shape[0], np.float64)
        native.double_areas(np.ascontiguousarray(vertices, np.float64), np.ascontiguousarray(faces, np.int64), out)
        return out
    return _double_areas_numpy(vertices, faces)


def _double_areas_numpy(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    v0, v1, v2 = (vertices[faces[:, k]] for k in range(3))
    return np.linalg.norm(np.cross(v1 - v0, v2 - v0), axis=1)


def _unique_inverse(keys: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``np.unique(keys, return_inverse=True, return_counts=True)`` for 1-D int64, one sort."""
    order = np.argsort(keys)
    sk = keys[order]
    new = np.empty(len(sk), bool)
    new[:1] = True
    np.not_equal(sk[1:], sk[:-1], out=new[1:])
    ids = np.cumsum(new) - 1
    inverse = np.empty(len(keys), np.int64)
    inverse[order] = ids
    starts = np.flatnonzero(new)
    counts = np.diff(np.append(starts, len(sk)))
    return sk[starts], inverse, counts


def _unique_rows(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Unique ``(N, 3) float64`` rows (sorted) and the inverse: bit-identical rows merge.

    With the C extension: merged by hashing, then only the distinct rows sorted; the result
    is that of :func:`_unique_rows_numpy` (tested)."""
    from ._accel import native

    if native is None or not rows.flags.c_contiguous or rows.dtype != np.float64:
        return _unique_rows_numpy(rows)
    first = np.empty(rows.shape[0], np.int64)
    ids = np.empty(rows.shape[0], np.int64)
    u = native.merge_rows(rows, first, ids)
    distinct = rows[first[:u]]
    del first
    order = np.lexsort(distinct.T[::-1])
    rank = np.empty(u, np.int64)
    rank[order] = np.arange(u)
    np.take(rank, ids, out=ids)
    return distinct[order], ids


def _unique_rows_numpy(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`_unique_rows`: one lexsort over all rows."""
    order = np.lexsort(rows.T[::-1])
    sr = rows[order]
    new = np.empty(len(sr), bool)
    new[:1] = True
    np.any(sr[1:] != sr[:-1], axis=1, out=new[1:])
    ids = np.cumsum(new) - 1
    inverse = np.empty(len(rows), np.int64)
    inverse[order] = ids
    return sr[new], inverse


def _make_winding_consistent(faces: np.ndarray, topo: _Topology) -> tuple[np.ndarray, int]:
    """Flip faces so that neighbours across manifold edges traverse the edge oppositely."""
    if topo.orientation_conflicts == 0:
        return faces, 0
    from scipy import sparse
    from scipy.sparse import csgraph

    n_f = faces.shape[0]
    pf = topo.pair_faces
    parity = topo.pair_same_direction.astype(np.int8)
    # A virtual root joins one face of every component so that one BFS covers them all.
    comp_n, comp = csgraph.connected_components(
        sparse.coo_matrix((np.ones(len(pf)), (pf[:, 0], pf[:, 1])), shape=(n_f, n_f)), directed=False
    )
    roots = np.unique(comp, return_index=True)[1]
    rows = np.concatenate([pf[:, 0], pf[:, 1], np.full(len(roots), n_f)])
    cols = np.concatenate([pf[:, 1], pf[:, 0], roots])
    data = np.concatenate([parity + 1, parity + 1, np.ones(len(roots), np.int8)]).astype(np.int8)
    g = sparse.csr_matrix((data, (rows, cols)), shape=(n_f + 1, n_f + 1))
    g.sum_duplicates()
    bfs, pred = csgraph.breadth_first_order(g, n_f, directed=False, return_predecessors=True)
    nodes = bfs[1:]
    par = pred[nodes]
    gs = g.maximum(g.T).tocsr()
    edge_par = (np.asarray(gs[nodes, np.where(par == n_f, nodes, par)]).ravel() - 1).astype(np.int8)
    edge_par[par == n_f] = 0
    acc = np.zeros(n_f + 1, np.int8)
    up = np.full(n_f + 1, n_f, np.int64)
    acc[nodes] = edge_par
    up[nodes] = par
    # Pointer doubling: acc[x] becomes the parity of the whole path from x to the root.
    while True:
        nxt = up[up]
        done = np.all(up[nodes] == n_f)
        if done:
            break
        acc = acc ^ np.where(up != n_f, acc[up], 0).astype(np.int8)
        up = np.where(up != n_f, nxt, n_f)
    flip = acc[:n_f].astype(bool)
    # Keep the majority of each component as it was: fewer faces change.
    flipped_share = np.bincount(comp, weights=flip, minlength=comp_n)
    comp_size = np.bincount(comp, minlength=comp_n)
    invert = flipped_share > comp_size / 2
    flip ^= invert[comp]
    out = faces.copy()
    out[flip] = out[flip][:, ::-1]
    return out, int(flip.sum())


def _signed_volumes(vertices: np.ndarray, faces: np.ndarray, labels: np.ndarray, n: int) -> np.ndarray:
    c = vertices.mean(axis=0)
    v0, v1, v2 = (vertices[faces[:, k]] - c for k in range(3))
    six_v = np.einsum("ij,ij->i", v0, np.cross(v1, v2))
    return np.bincount(labels, weights=six_v, minlength=n) / 6.0


def winding_number(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Generalized winding number of ``(P, 3)`` points w.r.t. ``(T, 3, 3)`` triangles.

    The solid angle ``Omega`` of each triangle seen from a point is Van Oosterom and
    Strackee's ``tan(Omega / 2) = a . (b x c) / (|a||b||c| + (a . b)|c| + (b . c)|a| +
    (c . a)|b|)`` (``a, b, c`` the corners relative to the point); the winding number is
    their sum over ``4 pi``.

    Parameters
    ----------
    points : (P, 3) float array
        Query points, mm.
    triangles : (T, 3, 3) float array
        Triangle corners, mm; counter-clockwise seen from outside for an outward mesh.

    Returns
    -------
    (P,) float64
        1 inside a closed outward mesh, 0 outside, -1 inside an inward one; fractional for
        open meshes, undefined (any value) for points on the surface.

    Examples
    --------
    >>> from rotoprint.testing import box_mesh
    >>> m = box_mesh((2.0, 2.0, 2.0))
    >>> np.round(winding_number(np.array([[1.0, 1.0, 1.0], [3.0, 1.0, 1.0]]), m.vertices[m.faces]), 12).tolist()
    [1.0, 0.0]
    """
    pts = np.asarray(points, dtype=np.float64)
    triangles = np.asarray(triangles, dtype=np.float64)
    out = np.zeros(len(pts))
    chunk = max(1, 2_000_000 // max(1, len(triangles)))
    for s in range(0, len(pts), chunk):
        a = triangles[None, :, 0, :] - pts[s : s + chunk, None, :]
        b = triangles[None, :, 1, :] - pts[s : s + chunk, None, :]
        c = triangles[None, :, 2, :] - pts[s : s + chunk, None, :]
        la, lb, lc = (np.linalg.norm(x, axis=2) for x in (a, b, c))
        det = np.einsum("ptk,ptk->pt", a, np.cross(b, c))
        den = la * lb * lc + np.einsum("ptk,ptk->pt", a, b) * lc + np.einsum("ptk,ptk->pt", b, c) * la
        den += np.einsum("ptk,ptk->pt", c, a) * lb
        out[s : s + chunk] = np.arctan2(det, den).sum(axis=1) / (2 * np.pi)
    return out


def _orient_shells(vertices: np.ndarray, faces: np.ndarray, topo: _Topology) -> tuple[np.ndarray, int]:
    """Apply the nesting rule of the module doc; returns the faces and shells flipped."""
    n = topo.n_shells
    vol = _signed_volumes(vertices, faces, topo.shell, n)
    # Only shells that mostly enclose something have a meaningful volume sign.
    open_sides = np.bincount(topo.shell, weights=topo.boundary_edge[topo.face_edges].sum(axis=1), minlength=n)
    sides = np.bincount(topo.shell, minlength=n) * 3.0
    enclosing = (sides >= 12) & (open_sides <= MAX_OPEN_SIDE_FRACTION * sides)
    negative = np.flatnonzero((vol < 0) & enclosing)
    if negative.size == 0:
        return faces, 0
    lo = np.full((n, 3), np.inf)
    hi = np.full((n, 3), -np.inf)
    fv_min = vertices[faces].min(axis=1)
    fv_max = vertices[faces].max(axis=1)
    for k in range(3):
        np.minimum.at(lo[:, k], topo.shell, fv_min[:, k])
        np.maximum.at(hi[:, k], topo.shell, fv_max[:, k])
    shell_faces = [np.flatnonzero(topo.shell == s) for s in range(n)] if n <= 4096 else None

    def faces_of(s: int) -> np.ndarray:
        return shell_faces[s] if shell_faces is not None else np.flatnonzero(topo.shell == s)

    def nested_in(inner: int, outer: int) -> bool:
        if inner == outer or np.any(lo[inner] < lo[outer]) or np.any(hi[inner] > hi[outer]):
            return False
        vids = np.unique(faces[faces_of(inner)])
        if len(vids) > _SAMPLE_VERTICES:
            vids = vids[np.linspace(0, len(vids) - 1, _SAMPLE_VERTICES).astype(int)]
        w = winding_number(vertices[vids], vertices[faces[faces_of(outer)]])
        return bool(np.all(np.abs(w) > 0.5))

    flip_shell = np.zeros(n, bool)
    for s in negative:
        if any(nested_in(s, t) for t in range(n) if t != s):
            continue  # a cavity (or a solid) inside another shell: keep relative orientation
        flip_shell[s] = True
        for t in range(n):
            if t != s and nested_in(t, s):
                flip_shell[t] = True
    if not flip_shell.any():
        return faces, 0
    out = faces.copy()
    f = flip_shell[topo.shell]
    out[f] = out[f][:, ::-1]
    return out, int(flip_shell.sum())
