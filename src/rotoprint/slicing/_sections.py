"""Cross-sections of a mesh by horizontal planes, as oriented segments between mesh edges.

The exact rule for a vertex on the plane: a vertex with ``z >= z_plane`` counts as above,
so the plane behaves as if it were lowered by an infinitesimal amount. Every triangle then
has all three vertices on one side (no segment) or exactly two sides crossing; horizontal
faces lying in the plane produce nothing, and a vertex on the plane is the end of the
segments of the faces below it, never of those beside it. No epsilon is involved.

A face side ``k`` runs from vertex ``k`` to ``k+1``. The segment of a face starts on its side
that runs from above to below and ends on its side that runs from below to above; for an
outward-wound solid, material is then to the left of every segment seen from above (outer
loops counter-clockwise). The crossing point of a mesh edge is computed from the edge's
lower and upper vertex only, so both faces of an edge get the bit-identical point.
"""

from __future__ import annotations

import threading

import numpy as np

from .._dataclass import dataclass
from ..mesh import Mesh


@dataclass(frozen=True)
class Segments:
    """A layer's cross-section: ``(S, 2) float64`` start and end XY, and the mesh edge each
    end lies on (``(S,) int64``, -1 for a gap-closing segment)."""

    start: np.ndarray
    end: np.ndarray
    start_edge: np.ndarray
    end_edge: np.ndarray

    def __len__(self) -> int:
        return int(self.start.shape[0])


class FaceSweep:
    """Faces crossing successive planes, found incrementally for increasing heights.

    Threads may share a sweep: each step of its one position is taken under a lock (a thread of
    its own goes faster with :meth:`fork`, which starts its own position)."""

    def __init__(self, mesh: Mesh) -> None:
        fz = mesh.vertices[:, 2][mesh.faces]
        self.zmin = fz.min(axis=1)
        self.zmax = fz.max(axis=1)
        self.order = np.argsort(self.zmin, kind="stable")
        self.zmin_sorted = self.zmin[self.order]
        self._ptr = 0
        self._active = np.empty(0, np.int64)
        self._last_z = -np.inf
        self._lock = threading.Lock()

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        del state["_lock"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._lock = threading.Lock()

    def fork(self) -> FaceSweep:
        """A sweep over the same faces from the start, sharing the (read-only) face bounds."""
        other = object.__new__(FaceSweep)
        other.zmin, other.zmax, other.order, other.zmin_sorted = self.zmin, self.zmax, self.order, self.zmin_sorted
        other._ptr = 0
        other._active = np.empty(0, np.int64)
        other._last_z = -np.inf
        other._lock = threading.Lock()
        return other

    def faces_at(self, z: float) -> np.ndarray:
        """Indices of faces with ``zmin < z <= zmax`` (the faces the plane crosses)."""
        with self._lock:
            if z < self._last_z:
                self._ptr, self._active = 0, np.empty(0, np.int64)
            stop = int(np.searchsorted(self.zmin_sorted, z, side="left"))
            new = self.order[self._ptr : stop]
            act = np.concatenate([self._active, new])
            act = act[self.zmax[act] >= z]
            self._ptr, self._active, self._last_z = stop, act, z
            return act


def section(mesh: Mesh, faces_idx: np.ndarray, z: float) -> Segments:
    """Oriented segments of the faces ``faces_idx`` (all crossing ``z``) at height ``z``
    (the C kernel, or the jit kernel where it is not built; :func:`section_numpy` is the
    reference both are tested against)."""
    from .._accel import native

    faces_idx = np.ascontiguousarray(faces_idx, np.int64)
    if native is not None:
        V = np.ascontiguousarray(mesh.vertices, np.float64)
        F = np.ascontiguousarray(mesh.faces, np.int64)
        FE = np.ascontiguousarray(mesh.topology.face_edges, np.int64)
        n = faces_idx.shape[0]
        start, end = np.empty((n, 2)), np.empty((n, 2))
        se, ee = np.empty(n, np.int64), np.empty(n, np.int64)
        native.section(V, F, FE, faces_idx, float(z), start, end, se, ee)
        return Segments(start=start, end=end, start_edge=se, end_edge=ee)
    from ._kernels import section_kernel

    start, end, se, ee = section_kernel(mesh.vertices, mesh.faces, mesh.topology.face_edges, faces_idx, float(z))
    return Segments(start=start, end=end, start_edge=se, end_edge=ee)


def section_numpy(mesh: Mesh, faces_idx: np.ndarray, z: float) -> Segments:
    """Oriented segments of the faces ``faces_idx`` (all crossing ``z``) at height ``z``."""
    V = mesh.vertices
    tri = mesh.faces[faces_idx]
    above = V[tri, 2] >= z
    nxt = np.roll(above, -1, axis=1)
    k_up = np.argmax(~above & nxt, axis=1)
    k_down = np.argmax(above & ~nxt, axis=1)
    rows = np.arange(tri.shape[0])

    def crossing(k: np.ndarray, going_up: bool) -> np.ndarray:
        a = tri[rows, k]
        b = tri[rows, (k + 1) % 3]
        lo, hi = (a, b) if going_up else (b, a)
        plo, phi = V[lo], V[hi]
        t = (z - plo[:, 2]) / (phi[:, 2] - plo[:, 2])
        return plo[:, :2] + t[:, None] * (phi[:, :2] - plo[:, :2])

    fe = mesh.topology.face_edges[faces_idx]
    return Segments(
        start=crossing(k_down, False),
        end=crossing(k_up, True),
        start_edge=fe[rows, k_down],
        end_edge=fe[rows, k_up],
    )
