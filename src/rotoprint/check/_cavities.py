"""Enclosed cavities (resin traps): empty space shut in on every side by the part.

The empty space of each layer is taken as runs per pixel row (the complement of the layer's
material runs, see :func:`rotoprint.check._kernels.fill_runs`), joined within the layer by
4-neighbours (the dual of the 8-neighbours material islands use, so that empty space never
leaks through a diagonal between two material pixels) and to the layer below where the same
pixel is empty in both. A connected body of empty space is **open** when it reaches the edge
of the device field in some layer, or the top of the part (everything above the last layer is
open); the others are shut in: uncured resin that cannot drain (DLP), support or air sealed in
(inkjet). The platform closes the space below the first layer.

The work follows the runs, not the image, and is streamed: only the last layer's empty runs
and one record per body are kept. :class:`CavityTracker` is the public face; the kernel is
:func:`cavity_layer`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def empty_runs(rs, r0, r1, W):  # pragma: no cover - jit
    """The empty runs of a layer given its material runs (``rs`` CSR row starts ``(H+1,)``,
    ``r0, r1`` columns ``[r0, r1)`` sorted per row): ``(H+1,)`` row starts and ``(E,)``
    first and end columns, in raster order."""
    H = rs.shape[0] - 1
    n = 0
    for j in range(H):
        c = 0
        for k in range(rs[j], rs[j + 1]):
            if r0[k] > c:
                n += 1
            if r1[k] > c:
                c = r1[k]
        if c < W:
            n += 1
    es = np.empty(H + 1, np.int64)
    e0 = np.empty(n, np.int64)
    e1 = np.empty(n, np.int64)
    n = 0
    for j in range(H):
        es[j] = n
        c = 0
        for k in range(rs[j], rs[j + 1]):
            if r0[k] > c:
                e0[n] = c
                e1[n] = r0[k]
                n += 1
            if r1[k] > c:
                c = r1[k]
        if c < W:
            e0[n] = c
            e1[n] = W
            n += 1
    es[H] = n
    return es, e0, e1


@njit(cache=True, nogil=True)
def _find(parent, i):  # pragma: no cover - jit
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, nogil=True)
def _union(parent, a, b):  # pragma: no cover - jit
    a = _find(parent, a)
    b = _find(parent, b)
    if a != b:
        if a < b:
            parent[b] = a
        else:
            parent[a] = b


@njit(cache=True, nogil=True)
def cavity_layer(es, e0, e1, W, ps, p0, p1, pcomp, npc):  # pragma: no cover - jit
    """One layer's empty runs ``es, e0, e1`` (:func:`empty_runs`) as bodies of empty space,
    joined to those of the layer below (its empty runs ``ps, p0, p1`` and the body of each,
    ``pcomp`` in ``0..npc-1``; ``npc = 0`` and empty arrays for the first layer).

    Returns ``comp`` ``(E,)`` the layer's own component of each run (4-neighbours, ``0..C-1``
    in raster order), per component ``(7, C) float64`` statistics (pixels, sums of rows and of
    columns, first and last row, first and last column) and ``(C,) bool`` whether it touches
    the field's edge, then the group of each component ``(C,)`` and of each body below
    ``(npc,)``: components and bodies below with the same group are one body now (groups
    ``0..G-1``), and ``G``.
    """
    H = es.shape[0] - 1
    n = e0.shape[0]
    parent = np.arange(n)
    for j in range(1, H):
        q = es[j - 1]
        qe = es[j]
        for k in range(es[j], es[j + 1]):
            while q < qe and e1[q] <= e0[k]:
                q += 1
            t = q
            while t < qe and e0[t] < e1[k]:
                _union(parent, k, t)
                t += 1
    comp = np.full(n, -1, np.int64)
    root_c = np.full(n, -1, np.int64)
    nc = 0
    for k in range(n):
        r = _find(parent, k)
        if root_c[r] < 0:
            root_c[r] = nc
            nc += 1
        comp[k] = root_c[r]
    st = np.zeros((7, nc))
    for c in range(nc):
        st[3, c] = H
        st[4, c] = -1
        st[5, c] = W
        st[6, c] = -1
    edge = np.zeros(nc, np.bool_)
    for j in range(H):
        for k in range(es[j], es[j + 1]):
            c = comp[k]
            L = e1[k] - e0[k]
            st[0, c] += L
            st[1, c] += float(j) * L
            st[2, c] += 0.5 * float(e0[k] + e1[k] - 1) * L
            st[3, c] = min(st[3, c], j)
            st[4, c] = max(st[4, c], j)
            st[5, c] = min(st[5, c], e0[k])
            st[6, c] = max(st[6, c], e1[k] - 1)
            if j == 0 or j == H - 1 or e0[k] == 0 or e1[k] == W:
                edge[c] = True
    # join to the bodies below: nodes 0..nc-1 the components, nc..nc+npc-1 the bodies below
    gp = np.arange(nc + npc)
    if npc > 0:
        for j in range(H):
            q = ps[j]
            qe = ps[j + 1]
            for k in range(es[j], es[j + 1]):
                while q < qe and p1[q] <= e0[k]:
                    q += 1
                t = q
                while t < qe and p0[t] < e1[k]:
                    _union(gp, comp[k], nc + pcomp[t])
                    t += 1
    grp = np.full(nc + npc, -1, np.int64)
    root_g = np.full(nc + npc, -1, np.int64)
    ng = 0
    for v in range(nc + npc):
        r = _find(gp, v)
        if root_g[r] < 0:
            root_g[r] = ng
            ng += 1
        grp[v] = root_g[r]
    return comp, st, edge, grp[:nc].copy(), grp[nc:].copy(), ng


class CavityTracker:
    """Bodies of empty space followed layer by layer; :meth:`step` returns the bodies that
    end shut in (their record) as the layer above closes them.

    A record: ``first_layer``, ``last_layer``, ``pixels`` (summed over the layers), mean
    ``row`` and ``col`` (pixel indices), and the pixel box ``row0, row1, col0, col1``.
    """

    def __init__(self, width: int, height: int) -> None:
        self.W = int(width)
        self.H = int(height)
        self.prev: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.prev_bodies: list[dict] = []  # the bodies present in the last layer, by dense index
        self.pcomp = np.zeros(0, np.int64)

    def step(self, rs: np.ndarray, r0: np.ndarray, r1: np.ndarray, layer: int) -> list[dict]:
        es, e0, e1 = empty_runs(rs, r0, r1, self.W)
        if self.prev is None:
            ps = np.zeros(self.H + 1, np.int64)
            p0 = p1 = np.zeros(0, np.int64)
            pcomp = np.zeros(0, np.int64)
        else:
            ps, p0, p1 = self.prev
            pcomp = self.pcomp
        comp, st, edge, gc, gb, ng = cavity_layer(es, e0, e1, self.W, ps, p0, p1, pcomp, len(self.prev_bodies))
        bodies: list[dict | None] = [None] * ng
        # the bodies below merge into their group's body
        for b, g in zip(self.prev_bodies, gb.tolist()):
            cur = bodies[g]
            bodies[g] = b if cur is None else _merge(cur, b)
        has = np.zeros(ng, np.bool_)
        has[gc] = True
        ended = [g for g in range(ng) if bodies[g] is not None and not has[g]]
        for c, g in enumerate(gc.tolist()):
            rec = {
                "first_layer": layer,
                "last_layer": layer,
                "pixels": float(st[0, c]),
                "srow": float(st[1, c]),
                "scol": float(st[2, c]),
                "row0": int(st[3, c]),
                "row1": int(st[4, c]),
                "col0": int(st[5, c]),
                "col1": int(st[6, c]),
                "open": bool(edge[c]),
            }
            cur = bodies[g]
            bodies[g] = rec if cur is None else _merge(cur, rec)
        out = []
        for g in ended:
            b = bodies[g]
            if not b["open"]:
                out.append(_public(b))
        # the bodies present now, densely numbered in the order of their groups
        live = np.flatnonzero(has)
        dense = np.full(ng, -1, np.int64)
        dense[live] = np.arange(len(live))
        self.prev_bodies = [bodies[g] for g in live.tolist()]
        self.pcomp = dense[gc][comp]
        self.prev = (es, e0, e1)
        return out

    def finish(self) -> list[dict]:
        """Bodies present in the last layer are open to what lies above the part: none ends
        shut in. Returns ``[]`` (kept for symmetry with :meth:`step`)."""
        self.prev = None
        self.prev_bodies = []
        return []


def _merge(a: dict, b: dict) -> dict:
    return {
        "first_layer": min(a["first_layer"], b["first_layer"]),
        "last_layer": max(a["last_layer"], b["last_layer"]),
        "pixels": a["pixels"] + b["pixels"],
        "srow": a["srow"] + b["srow"],
        "scol": a["scol"] + b["scol"],
        "row0": min(a["row0"], b["row0"]),
        "row1": max(a["row1"], b["row1"]),
        "col0": min(a["col0"], b["col0"]),
        "col1": max(a["col1"], b["col1"]),
        "open": a["open"] or b["open"],
    }


def _public(b: dict) -> dict:
    n = b["pixels"]
    return {
        "first_layer": b["first_layer"],
        "last_layer": b["last_layer"],
        "pixels": n,
        "row": b["srow"] / n,
        "col": b["scol"] / n,
        "row0": b["row0"],
        "row1": b["row1"],
        "col0": b["col0"],
        "col1": b["col1"],
    }
