"""Drop deposition on a fine grid: the numba kernels and their numpy references.

Grid: cell ``(r, c)`` has its centre at ``(c + 0.5, r + 0.5)`` in grid units; a cell is
``gx_um`` wide and ``gy_um`` high. A drop at ``(u, v)`` (grid units) with footprint radius
``a_um`` and spherical-cap height ``h_um`` (sphere radius ``R = (a^2 + h^2) / 2h``) puts on
cell ``(r, c)`` the weight ``max(0, sqrt(R^2 - rho^2) - (R - h))``, ``rho`` the distance in um
from the drop to the cell centre; the weights of a drop are normalised to sum to its volume
divided by the cell area, so every drop's volume is deposited exactly (to rounding), whatever
the grid. A drop whose footprint misses every cell centre puts its whole volume on the cell
it lands in.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["drop_norms_jit", "deposit_strip_jit", "drop_norms_numpy", "deposit_strip_numpy", "interior_rows_jit"]


@njit(cache=True, nogil=True)
def _weight(du: float, dv: float, a: float, rs: float, h: float) -> float:
    rho2 = du * du + dv * dv
    if rho2 >= a * a:
        return 0.0
    return math.sqrt(rs * rs - rho2) - (rs - h)


@njit(cache=True, nogil=True)
def drop_norms_jit(u, v, a_um, rs_um, h_um, gx_um, gy_um):
    """``(M,) float64`` sum of each drop's cap weights over all cell centres of its footprint."""
    m = u.size
    out = np.zeros(m, np.float64)
    for d in range(m):
        a = a_um[d]
        c0 = int(math.floor(u[d] - a / gx_um - 0.5))
        c1 = int(math.ceil(u[d] + a / gx_um - 0.5))
        r0 = int(math.floor(v[d] - a / gy_um - 0.5))
        r1 = int(math.ceil(v[d] + a / gy_um - 0.5))
        s = 0.0
        for r in range(r0, r1 + 1):
            dv = (r + 0.5 - v[d]) * gy_um
            for c in range(c0, c1 + 1):
                s += _weight((c + 0.5 - u[d]) * gx_um, dv, a, rs_um[d], h_um[d])
        out[d] = s
    return out


@njit(cache=True, nogil=True)
def deposit_strip_jit(u, v, vol_um3, a_um, rs_um, h_um, norm, gx_um, gy_um, row0, out):
    """Add the drops' thickness (um) to ``out`` ``(rows, cols) float64``, whose row 0 is grid
    row ``row0``; cells outside ``out`` are skipped (their share is another strip's)."""
    rows, cols = out.shape
    area = gx_um * gy_um
    for d in range(u.size):
        a = a_um[d]
        if norm[d] <= 0.0:  # footprint smaller than a cell: all on the landing cell
            r = int(math.floor(v[d])) - row0
            c = int(math.floor(u[d]))
            if 0 <= r < rows and 0 <= c < cols:
                out[r, c] += vol_um3[d] / area
            continue
        scale = vol_um3[d] / (area * norm[d])
        c0 = max(int(math.floor(u[d] - a / gx_um - 0.5)), 0)
        c1 = min(int(math.ceil(u[d] + a / gx_um - 0.5)), cols - 1)
        r0 = max(int(math.floor(v[d] - a / gy_um - 0.5)), row0)
        r1 = min(int(math.ceil(v[d] + a / gy_um - 0.5)), row0 + rows - 1)
        for r in range(r0, r1 + 1):
            dv = (r + 0.5 - v[d]) * gy_um
            for c in range(c0, c1 + 1):
                w = _weight((c + 0.5 - u[d]) * gx_um, dv, a, rs_um[d], h_um[d])
                if w > 0.0:
                    out[r - row0, c] += w * scale


def _weights_numpy(ud, vd, a, rs, h, gx_um, gy_um):
    c = np.arange(math.floor(ud - a / gx_um - 0.5), math.ceil(ud + a / gx_um - 0.5) + 1)
    r = np.arange(math.floor(vd - a / gy_um - 0.5), math.ceil(vd + a / gy_um - 0.5) + 1)
    du = (c + 0.5 - ud) * gx_um
    dv = (r + 0.5 - vd) * gy_um
    rho2 = dv[:, None] ** 2 + du[None, :] ** 2
    w = np.where(rho2 < a * a, np.sqrt(np.maximum(rs * rs - rho2, 0.0)) - (rs - h), 0.0)
    return r, c, w


def drop_norms_numpy(u, v, a_um, rs_um, h_um, gx_um, gy_um):
    """Reference of :func:`drop_norms_jit` (one drop at a time, for tests)."""
    return np.array([_weights_numpy(u[d], v[d], a_um[d], rs_um[d], h_um[d], gx_um, gy_um)[2].sum() for d in range(u.size)])


def deposit_strip_numpy(u, v, vol_um3, a_um, rs_um, h_um, norm, gx_um, gy_um, row0, out):
    """Reference of :func:`deposit_strip_jit` (one drop at a time, for tests)."""
    rows, cols = out.shape
    area = gx_um * gy_um
    for d in range(u.size):
        if norm[d] <= 0.0:
            r, c = int(math.floor(v[d])) - row0, int(math.floor(u[d]))
            if 0 <= r < rows and 0 <= c < cols:
                out[r, c] += vol_um3[d] / area
            continue
        r, c, w = _weights_numpy(u[d], v[d], a_um[d], rs_um[d], h_um[d], gx_um, gy_um)
        rr = r - row0
        okr = (rr >= 0) & (rr < rows)
        okc = (c >= 0) & (c < cols)
        if okr.any() and okc.any():
            out[np.ix_(rr[okr], c[okc])] += w[np.ix_(okr, okc)] * (vol_um3[d] / (area * norm[d]))


@njit(cache=True, nogil=True)
def interior_rows_jit(dmask, core0, core1, thr_um, gx_um, gy_um, out):
    """The interior of rows ``core0..core1`` of ``dmask`` ``(R, C) bool`` into ``out``
    ``(core1 - core0, C) bool``: cells of ``dmask`` whose centre is at least ``thr_um`` from
    the nearest centre of a cell of ``dmask`` that is False, as ``scipy.ndimage``'s
    ``distance_transform_edt(dmask, sampling=(gy_um, gx_um)) >= thr_um`` (the same
    arithmetic, ``sqrt((dy gy)^2 + (dx gx)^2)``, where it decides; only cells within
    ``dmask`` count).

    Each column's nearest False row (above or below) is found by two scans over the rows; a
    cell is then interior unless a column within ``thr_um`` holds a False cell nearer than
    ``thr_um``. Memory: one ``int32`` per cell of ``dmask`` and two per column.
    """
    rows, cols = dmask.shape
    big = rows + 1  # no False cell in this column of the window
    dv = np.empty((rows, cols), np.int32)
    last = np.full(cols, -big, np.int64)
    for r in range(rows):
        for c in range(cols):
            if not dmask[r, c]:
                last[c] = r
            dv[r, c] = r - last[c] if last[c] > -big else big
    for c in range(cols):
        last[c] = -1
    for r in range(rows - 1, -1, -1):
        for c in range(cols):
            if not dmask[r, c]:
                last[c] = r
            if last[c] >= 0 and last[c] - r < dv[r, c]:
                dv[r, c] = last[c] - r
    kx = int(math.ceil(thr_um / gx_um)) + 1
    t2 = thr_um * thr_um
    lo2, hi2 = t2 * (1.0 - 1e-9), t2 * (1.0 + 1e-9)
    for r in range(core0, core1):
        o = r - core0
        for c in range(cols):
            if not dmask[r, c]:
                out[o, c] = False
                continue
            ok = True
            for c2 in range(max(0, c - kx), min(cols - 1, c + kx) + 1):
                d = dv[r, c2]
                if d >= big:
                    continue
                dy = d * gy_um
                dx = (c2 - c) * gx_um
                q = dy * dy + dx * dx
                if q < lo2 or (q <= hi2 and math.sqrt(q) < thr_um):
                    ok = False
                    break
            out[o, c] = ok
