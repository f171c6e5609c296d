"""Enclosed cavities (resin traps): empty space shut in on every side by the part.

The empty space of each layer is taken as runs per pixel row (the complement of the layer's
material runs, see :func:`rotoprint.check._kernels.runs.fill_runs`), joined within the layer by
4-neighbours (the dual of the 8-neighbours material islands use, so that empty space never
leaks through a diagonal between two material pixels) and to the layer below where the same
pixel is empty in both. A connected body of empty space is **open** when it reaches the edge
of the device field in some layer, or the top of the part (everything above the last layer is
open); the others are shut in: uncured resin that cannot drain (DLP), support or air sealed in
(inkjet). The platform closes the space below the first layer.

The work follows the runs, not the image, and is streamed: only the last layer's empty runs
and one record per body are kept. :class:`CavityTracker` is the public face; the kernel is
:func:`cavity_step`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._kernels.unionfind import _relabel, _union


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


#: Rows of a body record (:func:`cavity_step`).
_FIRST, _LAST, _PIX, _SROW, _SCOL, _ROW0, _ROW1, _COL0, _COL1, _OPEN = range(10)


@njit(cache=True, nogil=True)
def cavity_step(rs, r0, r1, W, ps, p0, p1, pcomp, bodies, layer):  # pragma: no cover - jit
    """One layer of the cavity search, in one call.

    ``rs, r0, r1`` are the layer's material runs; ``ps, p0, p1`` the empty runs of the layer
    below, ``pcomp`` the body (``0..B-1``) of each and ``bodies`` their ``(10, B) float64``
    records (first and last layer, pixels, sums of rows and of columns, first and last row,
    first and last column, open: 1.0 if any part reaches the field's edge); for the first
    layer empty arrays and ``B = 0``.

    The layer's empty runs are joined by 4-neighbours within the layer and to the empty runs
    below that share a pixel; the bodies so joined merge. Returns the layer's empty runs
    ``es, e0, e1``, the body of each ``(E,)``, the records of the bodies present in this layer
    ``(10, B')``, and those of the bodies that ended in the layer below shut in ``(10, K)``.
    """
    es, e0, e1 = empty_runs(rs, r0, r1, W)
    H = es.shape[0] - 1
    n = e0.shape[0]
    nb = bodies.shape[1]
    # a layer with at most one material run per row has no hole: all its empty space reaches
    # the field's edge. If nothing below is shut in either, the layer is one open body.
    trivial = True
    for j in range(H):
        if rs[j + 1] - rs[j] > 1:
            trivial = False
            break
    if trivial:
        for b in range(nb):
            if bodies[_OPEN, b] == 0.0:
                trivial = False
                break
    if trivial:
        live = np.zeros((10, 1))
        live[_FIRST, 0] = layer
        live[_LAST, 0] = layer
        live[_OPEN, 0] = 1.0
        return es, e0, e1, np.zeros(n, np.int64), live, np.zeros((10, 0))
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
    comp, nc = _relabel(parent, np.zeros(0, np.bool_))
    # groups: the layer's components (0..nc-1) and the bodies below (nc..nc+nb-1) joined
    gp = np.arange(nc + nb)
    if nb > 0:
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
    grp, ng = _relabel(gp, np.zeros(0, np.bool_))
    agg = np.empty((10, ng))
    for g in range(ng):
        agg[_FIRST, g] = np.inf
        agg[_LAST, g] = -np.inf
        agg[_PIX, g] = 0.0
        agg[_SROW, g] = 0.0
        agg[_SCOL, g] = 0.0
        agg[_ROW0, g] = np.inf
        agg[_ROW1, g] = -np.inf
        agg[_COL0, g] = np.inf
        agg[_COL1, g] = -np.inf
        agg[_OPEN, g] = 0.0
    has = np.zeros(ng, np.bool_)
    for b in range(nb):
        g = grp[nc + b]
        agg[_FIRST, g] = min(agg[_FIRST, g], bodies[_FIRST, b])
        agg[_LAST, g] = max(agg[_LAST, g], bodies[_LAST, b])
        agg[_PIX, g] += bodies[_PIX, b]
        agg[_SROW, g] += bodies[_SROW, b]
        agg[_SCOL, g] += bodies[_SCOL, b]
        agg[_ROW0, g] = min(agg[_ROW0, g], bodies[_ROW0, b])
        agg[_ROW1, g] = max(agg[_ROW1, g], bodies[_ROW1, b])
        agg[_COL0, g] = min(agg[_COL0, g], bodies[_COL0, b])
        agg[_COL1, g] = max(agg[_COL1, g], bodies[_COL1, b])
        agg[_OPEN, g] = max(agg[_OPEN, g], bodies[_OPEN, b])
    for j in range(H):
        for k in range(es[j], es[j + 1]):
            g = grp[comp[k]]
            has[g] = True
            L = e1[k] - e0[k]
            agg[_FIRST, g] = min(agg[_FIRST, g], layer)
            agg[_LAST, g] = layer
            agg[_PIX, g] += L
            agg[_SROW, g] += float(j) * L
            agg[_SCOL, g] += 0.5 * float(e0[k] + e1[k] - 1) * L
            agg[_ROW0, g] = min(agg[_ROW0, g], j)
            agg[_ROW1, g] = max(agg[_ROW1, g], j)
            agg[_COL0, g] = min(agg[_COL0, g], e0[k])
            agg[_COL1, g] = max(agg[_COL1, g], e1[k] - 1)
            if j == 0 or j == H - 1 or e0[k] == 0 or e1[k] == W:
                agg[_OPEN, g] = 1.0
    dense = np.full(ng, -1, np.int64)
    nlive = 0
    nend = 0
    for g in range(ng):
        if has[g]:
            dense[g] = nlive
            nlive += 1
        elif agg[_OPEN, g] == 0.0:
            nend += 1
    live = np.empty((10, nlive))
    ended = np.empty((10, nend))
    q = 0
    for g in range(ng):
        if has[g]:
            live[:, dense[g]] = agg[:, g]
        elif agg[_OPEN, g] == 0.0:
            ended[:, q] = agg[:, g]
            q += 1
    bcomp = np.empty(n, np.int64)
    for k in range(n):
        bcomp[k] = dense[grp[comp[k]]]
    return es, e0, e1, bcomp, live, ended


class CavityTracker:
    """Bodies of empty space followed layer by layer; :meth:`step` returns the bodies that
    end shut in as the layer above closes them.

    A record: ``first_layer``, ``last_layer``, ``pixels`` (summed over the layers), mean
    ``row`` and ``col`` (pixel indices), and the pixel box ``row0, row1, col0, col1``.
    """

    def __init__(self, width: int, height: int) -> None:
        self.W = int(width)
        self.H = int(height)
        self.prev = (np.zeros(self.H + 1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64))
        self.pcomp = np.zeros(0, np.int64)
        self.bodies = np.zeros((10, 0))

    def step(self, rs: np.ndarray, r0: np.ndarray, r1: np.ndarray, layer: int) -> list[dict]:
        es, e0, e1, self.pcomp, self.bodies, ended = cavity_step(rs, r0, r1, self.W, *self.prev, self.pcomp, self.bodies, float(layer))
        self.prev = (es, e0, e1)
        out = []
        for b in ended.T.tolist():
            n = b[_PIX]
            out.append(
                {
                    "first_layer": int(b[_FIRST]),
                    "last_layer": int(b[_LAST]),
                    "pixels": n,
                    "row": b[_SROW] / n,
                    "col": b[_SCOL] / n,
                    "row0": int(b[_ROW0]),
                    "row1": int(b[_ROW1]),
                    "col0": int(b[_COL0]),
                    "col1": int(b[_COL1]),
                }
            )
        return out
