"""Which segments of a section bound the filled region: the winding number on each side by
the fill rule (:func:`classify_segments`), so overlapping and inside-out shells are handled by
the rule, not by orientation; each boundary segment gets its inward normal."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .grid import _cell_index


#: Segments shorter than this (mm) are rounding slivers (e.g. of an open mesh's gap closing):
#: they are not sampled, their direction being noise.
_MIN_LEN_MM = 1e-9


@njit(cache=True, nogil=True)
def _bands(sy, ey, y0, hb, nb):  # pragma: no cover - jit
    """CSR of segment indices per horizontal band of height ``hb`` starting at ``y0``."""
    n = sy.shape[0]
    count = np.zeros(nb + 1, np.int64)
    for k in range(n):
        a = min(sy[k], ey[k])
        b = max(sy[k], ey[k])
        i0 = _cell_index((a - y0) / hb, nb)
        i1 = _cell_index((b - y0) / hb, nb)
        for i in range(i0, i1 + 1):
            count[i + 1] += 1
    for i in range(nb):
        count[i + 1] += count[i]
    idx = np.empty(count[nb], np.int64)
    fill = count[:-1].copy()
    for k in range(n):
        a = min(sy[k], ey[k])
        b = max(sy[k], ey[k])
        i0 = _cell_index((a - y0) / hb, nb)
        i1 = _cell_index((b - y0) / hb, nb)
        for i in range(i0, i1 + 1):
            idx[fill[i]] = k
            fill[i] += 1
    return count, idx


@njit(cache=True, nogil=True)
def _winding(qx, qy, sx, sy, ex, ey, start, idx, y0, hb, nb):  # pragma: no cover - jit
    """Winding number of the closed segment set about ``(qx, qy)`` (crossings of the ray +x)."""
    b = int(math.floor((qy - y0) / hb))
    if b < 0 or b >= nb:
        return 0
    w = 0
    for j in range(start[b], start[b + 1]):
        k = idx[j]
        ay = sy[k]
        by = ey[k]
        if ay <= qy < by:
            xi = sx[k] + (qy - ay) * (ex[k] - sx[k]) / (by - ay)
            if xi > qx:
                w += 1
        elif by <= qy < ay:
            xi = sx[k] + (qy - ay) * (ex[k] - sx[k]) / (by - ay)
            if xi > qx:
                w -= 1
    return w


@njit(cache=True, nogil=True)
def classify_segments(sx, sy, ex, ey, comp, ncomp, evenodd, eps):  # pragma: no cover - jit
    """Boundary flag ``(S,) bool`` and inward unit normal ``(S,)``, ``(S,)`` of each segment.

    A segment is on the boundary when the fill rule puts material on exactly one side of it:
    the winding number is evaluated ``eps`` mm to the left and to the right of the midpoint of
    the longest segment of each chain ``comp`` (labels ``0..ncomp-1`` from
    :func:`chain_components`), and the verdict, material left or right, holds for the whole
    chain. A coincident segment of a touching shell makes both sides material. Slivers
    shorter than ``_MIN_LEN_MM`` are never boundary.
    """
    n = sx.shape[0]
    is_b = np.zeros(n, np.bool_)
    nx = np.zeros(n)
    ny = np.zeros(n)
    if n == 0:
        return is_b, nx, ny
    rep = np.full(ncomp, -1, np.int64)
    rep_len = np.zeros(ncomp)
    for k in range(n):
        L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
        if L > rep_len[comp[k]]:
            rep_len[comp[k]] = L
            rep[comp[k]] = k
    ymin = min(sy.min(), ey.min())
    ymax = max(sy.max(), ey.max())
    nq = 0
    for c in range(ncomp):
        if rep[c] >= 0:
            nq += 1
    # bands pay off with many queries; a few chains need only a few
    nb = max(1, min(1 << 16, n // 4, 4 * nq))
    hb = max((ymax - ymin) / nb, 1e-12) * (1.0 + 1e-12)
    start, idx = _bands(sy, ey, ymin, hb, nb)
    verdict = np.zeros(ncomp, np.int64)  # 0 none, 1 material left, -1 material right
    for c in range(ncomp):
        k = rep[c]
        if k < 0:
            continue
        dx = ex[k] - sx[k]
        dy = ey[k] - sy[k]
        L = math.hypot(dx, dy)
        lx = -dy / L
        ly = dx / L
        mx = 0.5 * (sx[k] + ex[k])
        my = 0.5 * (sy[k] + ey[k])
        wl = _winding(mx + eps * lx, my + eps * ly, sx, sy, ex, ey, start, idx, ymin, hb, nb)
        wr = _winding(mx - eps * lx, my - eps * ly, sx, sy, ex, ey, start, idx, ymin, hb, nb)
        if evenodd:
            inl = (wl & 1) != 0
            inr = (wr & 1) != 0
        else:
            inl = wl != 0
            inr = wr != 0
        if inl != inr:
            verdict[c] = 1 if inl else -1
    for k in range(n):
        v = verdict[comp[k]]
        if v == 0:
            continue
        dx = ex[k] - sx[k]
        dy = ey[k] - sy[k]
        L = math.hypot(dx, dy)
        if L == 0.0:
            continue
        if L <= _MIN_LEN_MM:
            continue  # a rounding sliver: its direction means nothing
        is_b[k] = True
        nx[k] = -v * dy / L
        ny[k] = v * dx / L
    return is_b, nx, ny
