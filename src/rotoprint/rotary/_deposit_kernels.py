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

__all__ = ["deposit_strip_jit", "deposit_strip_numpy", "interior_rows_jit", "strip_stats_jit", "pair_counts_jit",
           "radial_cell_counts_jit"]


@njit(cache=True, nogil=True, inline="always")
def _box(ud, vd, a, gx_um, gy_um):
    """The footprint's box of cells: ``c0, c1, r0, r1`` (inclusive)."""
    c0 = int(math.floor(ud - a / gx_um - 0.5))
    c1 = int(math.ceil(ud + a / gx_um - 0.5))
    r0 = int(math.floor(vd - a / gy_um - 0.5))
    r1 = int(math.ceil(vd + a / gy_um - 0.5))
    return c0, c1, r0, r1


@njit(cache=True, nogil=True, inline="always")
def _box_weights(ud, vd, a, rs, h, gx_um, gy_um, c0, c1, r0, r1, du2, rho, buf):
    """The cap's weight ``sqrt(rs^2 - rho^2) - (rs - h)`` (0 where ``rho^2 >= a^2``) of every cell
    centre of the box into ``buf`` (row-major), branch-free and in one flat loop (``rho^2``
    first), so that it vectorises (AVX2 too)."""
    nc = c1 - c0 + 1
    n = (r1 - r0 + 1) * nc
    for j in range(nc):
        du = (c0 + j + 0.5 - ud) * gx_um
        du2[j] = du * du
    for i in range(r1 - r0 + 1):
        dv = (r0 + i + 0.5 - vd) * gy_um
        dv2 = dv * dv
        rrow = rho[i * nc: (i + 1) * nc]
        for j in range(nc):
            rrow[j] = du2[j] + dv2
    a2 = a * a
    rs2 = rs * rs
    cap = rs - h
    for k in range(n):
        rho2 = rho[k]
        w = math.sqrt(rs2 - rho2) - cap
        buf[k] = w if rho2 < a2 else 0.0


@njit(cache=True, nogil=True, inline="always")
def _box_add(ud, vd, vol, s, c0, c1, r0, r1, buf, area, row0, out):
    """Add a drop's weights ``buf`` (norm ``s``) to ``out``, as :func:`deposit_strip_jit` says."""
    rows, cols = out.shape
    if s <= 0.0:  # footprint smaller than a cell: all on the landing cell
        r = int(math.floor(vd)) - row0
        c = int(math.floor(ud))
        if 0 <= r < rows and 0 <= c < cols:
            out[r, c] += vol / area
        return
    nc = c1 - c0 + 1
    scale = vol / (area * s)
    cs, ce = max(c0, 0), min(c1, cols - 1) + 1
    if ce <= cs:
        return
    for r in range(max(r0, row0), min(r1, row0 + rows - 1) + 1):
        # views indexed from 0 (no negative-index wrap); the cell is rewritten with itself
        # where the weight is not > 0 (a select, not a branch: the loop vectorises)
        wrow = buf[(r - r0) * nc + cs - c0: (r - r0) * nc + ce - c0]
        orow = out[r - row0, cs:ce]
        for j in range(ce - cs):
            w = wrow[j]
            o = orow[j]
            orow[j] = o + w * scale if w > 0.0 else o


@njit(cache=True, nogil=True)
def deposit_strip_jit(u, v, vol_um3, a_um, rs_um, h_um, gx_um, gy_um, row0, out):
    """Add the drops' thickness (um) to ``out`` ``(rows, cols) float64``, whose row 0 is grid
    row ``row0``; cells outside ``out`` are skipped (their share is another strip's). Each
    drop's weights are summed over every cell centre of its footprint (its norm, row by row)
    and kept in a buffer, then the cells inside ``out`` get their share.

    Drops go four at a time: their weights first, then their four norms summed in one loop
    (four independent chains of additions, each in the order of its cells), then their shares
    added to ``out`` drop by drop, in order."""
    area = gx_um * gy_um
    nmax = 0
    ncmax = 0
    for d in range(u.size):
        c0, c1, r0, r1 = _box(u[d], v[d], a_um[d], gx_um, gy_um)
        nmax = max(nmax, (r1 - r0 + 1) * (c1 - c0 + 1))
        ncmax = max(ncmax, c1 - c0 + 1)
    du2 = np.empty(ncmax, np.float64)
    rho = np.empty(nmax, np.float64)
    b0 = np.empty(nmax, np.float64)
    b1 = np.empty(nmax, np.float64)
    b2 = np.empty(nmax, np.float64)
    b3 = np.empty(nmax, np.float64)
    nd = u.size
    d = 0
    while d + 4 <= nd:
        x0, x1, y0, y1 = _box(u[d], v[d], a_um[d], gx_um, gy_um)
        _box_weights(u[d], v[d], a_um[d], rs_um[d], h_um[d], gx_um, gy_um, x0, x1, y0, y1, du2, rho, b0)
        p0, p1, q0, q1 = _box(u[d + 1], v[d + 1], a_um[d + 1], gx_um, gy_um)
        _box_weights(u[d + 1], v[d + 1], a_um[d + 1], rs_um[d + 1], h_um[d + 1], gx_um, gy_um, p0, p1, q0, q1,
                     du2, rho, b1)
        e0, e1, f0, f1 = _box(u[d + 2], v[d + 2], a_um[d + 2], gx_um, gy_um)
        _box_weights(u[d + 2], v[d + 2], a_um[d + 2], rs_um[d + 2], h_um[d + 2], gx_um, gy_um, e0, e1, f0, f1,
                     du2, rho, b2)
        g0, g1, k0, k1 = _box(u[d + 3], v[d + 3], a_um[d + 3], gx_um, gy_um)
        _box_weights(u[d + 3], v[d + 3], a_um[d + 3], rs_um[d + 3], h_um[d + 3], gx_um, gy_um, g0, g1, k0, k1,
                     du2, rho, b3)
        n0 = (y1 - y0 + 1) * (x1 - x0 + 1)
        n1 = (q1 - q0 + 1) * (p1 - p0 + 1)
        n2 = (f1 - f0 + 1) * (e1 - e0 + 1)
        n3 = (k1 - k0 + 1) * (g1 - g0 + 1)
        m = min(min(n0, n1), min(n2, n3))
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        s3 = 0.0
        for k in range(m):
            s0 += b0[k]
            s1 += b1[k]
            s2 += b2[k]
            s3 += b3[k]
        for k in range(m, n0):
            s0 += b0[k]
        for k in range(m, n1):
            s1 += b1[k]
        for k in range(m, n2):
            s2 += b2[k]
        for k in range(m, n3):
            s3 += b3[k]
        _box_add(u[d], v[d], vol_um3[d], s0, x0, x1, y0, y1, b0, area, row0, out)
        _box_add(u[d + 1], v[d + 1], vol_um3[d + 1], s1, p0, p1, q0, q1, b1, area, row0, out)
        _box_add(u[d + 2], v[d + 2], vol_um3[d + 2], s2, e0, e1, f0, f1, b2, area, row0, out)
        _box_add(u[d + 3], v[d + 3], vol_um3[d + 3], s3, g0, g1, k0, k1, b3, area, row0, out)
        d += 4
    while d < nd:
        x0, x1, y0, y1 = _box(u[d], v[d], a_um[d], gx_um, gy_um)
        _box_weights(u[d], v[d], a_um[d], rs_um[d], h_um[d], gx_um, gy_um, x0, x1, y0, y1, du2, rho, b0)
        s0 = 0.0
        for k in range((y1 - y0 + 1) * (x1 - x0 + 1)):
            s0 += b0[k]
        _box_add(u[d], v[d], vol_um3[d], s0, x0, x1, y0, y1, b0, area, row0, out)
        d += 1


def _weights_numpy(ud, vd, a, rs, h, gx_um, gy_um):
    c = np.arange(math.floor(ud - a / gx_um - 0.5), math.ceil(ud + a / gx_um - 0.5) + 1)
    r = np.arange(math.floor(vd - a / gy_um - 0.5), math.ceil(vd + a / gy_um - 0.5) + 1)
    du = (c + 0.5 - ud) * gx_um
    dv = (r + 0.5 - vd) * gy_um
    rho2 = dv[:, None] ** 2 + du[None, :] ** 2
    w = np.where(rho2 < a * a, np.sqrt(np.maximum(rs * rs - rho2, 0.0)) - (rs - h), 0.0)
    return r, c, w


def deposit_strip_numpy(u, v, vol_um3, a_um, rs_um, h_um, gx_um, gy_um, row0, out):
    """Reference of :func:`deposit_strip_jit` (one drop at a time, for tests)."""
    rows, cols = out.shape
    area = gx_um * gy_um
    for d in range(u.size):
        r, c, w = _weights_numpy(u[d], v[d], a_um[d], rs_um[d], h_um[d], gx_um, gy_um)
        norm = w.sum()
        if norm <= 0.0:
            r, c = int(math.floor(v[d])) - row0, int(math.floor(u[d]))
            if 0 <= r < rows and 0 <= c < cols:
                out[r, c] += vol_um3[d] / area
            continue
        rr = r - row0
        okr = (rr >= 0) & (rr < rows)
        okc = (c >= 0) & (c < cols)
        if okr.any() and okc.any():
            out[np.ix_(rr[okr], c[okc])] += w[np.ix_(okr, okc)] * (vol_um3[d] / (area * norm))


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
    ``thr_um``. Memory: one ``int32`` per cell of ``dmask`` and three per column.
    """
    rows, cols = dmask.shape
    big = rows + 1  # no False cell in this column of the window
    dv = np.empty((rows, cols), np.int32)
    last = np.full(cols, -big, np.int64)
    # both scans branch-free (selects), so that they vectorise (AVX2 too)
    for r in range(rows):
        for c in range(cols):
            lc = last[c] if dmask[r, c] else r
            last[c] = lc
            dv[r, c] = r - lc if lc > -big else big
    for c in range(cols):
        last[c] = -1
    for r in range(rows - 1, -1, -1):
        for c in range(cols):
            lc = last[c] if dmask[r, c] else r
            last[c] = lc
            cur = dv[r, c]
            e = lc - r
            dv[r, c] = e if (lc >= 0 and e < cur) else cur
    kx = int(math.ceil(thr_um / gx_um)) + 1
    t2 = thr_um * thr_um
    lo2, hi2 = t2 * (1.0 - 1e-9), t2 * (1.0 + 1e-9)
    # The test of a column c2 = c + o, d = dv[r, c2], is a function of (d, o) alone, and q grows
    # with d: so it is "d < dmin[o]", dmin[o] the first d the test passes (found with the test's
    # own arithmetic; at most big, which always passes). The cells' loop is then integers only.
    dmin = np.empty(2 * kx + 1, np.int32)
    for o in range(-kx, kx + 1):
        d = 0
        while d < big:
            dy = d * gy_um
            dx = o * gx_um
            q = dy * dy + dx * dx
            if not (q < lo2 or (q <= hi2 and math.sqrt(q) < thr_um)):
                break
            d += 1
        dmin[o + kx] = d
    # a row at a time, one offset at a time: "some column of the window fails" for every cell
    # of the row, over whole rows (vectorises), not cell by cell with an early exit
    slack = np.empty(cols, np.int32)  # min over the window of dv - dmin: < 0 where a column fails
    for r in range(core0, core1):
        drow = dv[r]
        for c in range(cols):
            slack[c] = drow[c] - dmin[kx]
        for o in range(-kx, kx + 1):
            th = dmin[o + kx]
            lo, hi = max(0, -o), min(cols, cols - o)
            if hi <= lo:
                continue
            src = drow[lo + o: hi + o]  # views, indexed from 0: no negative-index wrap, the loop vectorises
            dst = slack[lo:hi]
            for c in range(hi - lo):
                dst[c] = min(dst[c], src[c] - th)
        orow = out[r - core0]
        mrow = dmask[r]
        for c in range(cols):
            orow[c] = mrow[c] & (slack[c] >= 0)


@njit(cache=True, nogil=True, inline="always")
def radial_bin(x, y):
    """``floor(hypot(x, y))`` as an int, without libm's ``hypot`` (slow) where it cannot decide:
    ``sqrt(x * x + y * y)`` is within a few ulp of ``hypot`` (finite, not tiny, arguments: radii
    in mm), so where its floor is the same 1e-12 (relative) either side, that is the floor of
    ``hypot``; near an integer ``hypot`` itself decides."""
    r = math.sqrt(x * x + y * y)
    lo = math.floor(r * (1.0 - 1e-12))
    if lo == math.floor(r * (1.0 + 1e-12)):
        return int(lo)
    return int(math.floor(math.hypot(x, y)))


@njit(cache=True, nogil=True, inline="always")
def neumaier_add(a, c, t):  # pragma: no cover - jit
    """``a + t`` compensated (Neumaier): returns the sum and ``c`` plus what the sum lost."""
    s = a + t
    if abs(a) >= abs(t):
        c += (a - s) + t
    else:
        c += (t - s) + a
    return s, c


@njit(cache=True, nogil=True, inline="always")
def column_products(cols, ox, nx, r_in, px, ca, sa):  # pragma: no cover - jit
    """``ca * xl`` and ``sa * xl`` ``(cols,) float64`` of each film column's model x (the radius of
    :func:`radial_bin`'s argument as ``Placement.to_platform`` computes it)."""
    cax = np.empty(cols, np.float64)
    sax = np.empty(cols, np.float64)
    for j in range(cols):
        xl = r_in + ((j + 0.5 - ox) / nx) * px
        cax[j] = ca * xl
        sax[j] = sa * xl
    return cax, sax


@njit(cache=True, nogil=True, inline="always")
def bin_add(b, cb, cs, cn, bins_sum, bins_n, t):  # pragma: no cover - jit
    """Add ``t`` to radial bin ``b`` through the bin held in registers (``cb``, its sum ``cs`` and
    count ``cn``; ``cb`` -1: none), written back to ``bins_sum``, ``bins_n`` when the bin changes
    (bins outside ``0..B-1`` skipped): the same additions in the same order on every bin. Returns
    the new ``cb, cs, cn``; the caller writes the last one back (:func:`bin_flush`)."""
    if b != cb:
        bin_flush(cb, cs, cn, bins_sum, bins_n)
        cb = b if 0 <= b < bins_sum.size else -1
        if cb >= 0:
            cs = bins_sum[cb]
            cn = bins_n[cb]
    if cb >= 0:
        cs += t
        cn += 1
    return cb, cs, cn


@njit(cache=True, nogil=True, inline="always")
def bin_flush(cb, cs, cn, bins_sum, bins_n):  # pragma: no cover - jit
    if cb >= 0:
        bins_sum[cb] = cs
        bins_n[cb] = cn


@njit(cache=True, nogil=True)
def strip_stats_jit(film, des, inter, row0, geo, stride, acc, cnt, bins_sum, bins_n, samples):
    """Accumulate the figures of film rows ``film`` ``(rows, cols) float64`` (grid rows
    ``row0..``) in one pass, without temporaries; returns the samples written.

    ``des``, ``inter`` ``(rows, cols) bool``: the design's and the interior's cells (the band
    is ``des`` less ``inter``). ``acc`` ``(7,) float64``: the sum of every cell, of the design's
    and of the interior's (each with its compensation, Neumaier: the sums do not depend on how
    the rows are split), the interior's thinnest. ``cnt`` ``(6,) int64``: design cells, covered
    design cells, interior cells, uncovered interior cells, band cells, uncovered band cells.
    ``bins_sum``, ``bins_n`` ``(B,)``: the interior per 1 mm of platform radius (``geo`` as in
    ``_levelling_kernels.film_stats_jit``: the radius as ``Placement.to_platform`` computes it).
    With ``stride > 0`` every ``stride``-th covered interior cell of the strip (row-major) is
    written to ``samples`` (at least ``rows * cols // stride + 1`` long).
    """
    rows, cols = film.shape
    ox, oy, nx, ny = geo[0], geo[1], geo[2], geo[3]
    r_in, px, py, hpx, ca, sa = geo[4], geo[5], geo[6], geo[7], geo[8], geo[9]
    # the accumulators in locals (registers), written back at the end: each sum compensated
    # (Neumaier: acc[i + 1] keeps what acc[i] lost), the same operations in the same order as before
    a0, a1, a2, a3, a4, a5, a6 = acc[0], acc[1], acc[2], acc[3], acc[4], acc[5], acc[6]
    n0, n1, n2, n3, n4, n5 = cnt[0], cnt[1], cnt[2], cnt[3], cnt[4], cnt[5]
    # the 1 mm radial bin floor(hypot(x, y)) of a cell (radial_bin) with its per-column products computed once, and the bin
    # being added to kept in registers until the bin changes (the same additions in the same
    # order on every bin)
    cax, sax = column_products(cols, ox, nx, r_in, px, ca, sa)
    cb = -1
    cs = 0.0
    cn = 0
    k = 0
    ns = 0
    for i in range(rows):
        row = (i + row0 + 0.5 - oy) / ny
        yl = (hpx / 2.0 - row) * py
        say = sa * yl
        cay = ca * yl
        for j in range(cols):
            t = film[i, j]
            a0, a1 = neumaier_add(a0, a1, t)
            if not des[i, j]:
                continue
            a2, a3 = neumaier_add(a2, a3, t)
            n0 += 1
            if t > 0.0:
                n1 += 1
            if not inter[i, j]:
                n4 += 1
                if t <= 0.0:
                    n5 += 1
                continue
            n2 += 1
            if t <= 0.0:
                n3 += 1
            elif stride > 0:
                if k % stride == 0:
                    samples[ns] = t
                    ns += 1
                k += 1
            a4, a5 = neumaier_add(a4, a5, t)
            if t < a6:
                a6 = t
            cb, cs, cn = bin_add(radial_bin(cax[j] - say, sax[j] + cay), cb, cs, cn, bins_sum, bins_n, t)
    bin_flush(cb, cs, cn, bins_sum, bins_n)
    acc[0], acc[1], acc[2], acc[3], acc[4], acc[5], acc[6] = a0, a1, a2, a3, a4, a5, a6
    cnt[0], cnt[1], cnt[2], cnt[3], cnt[4], cnt[5] = n0, n1, n2, n3, n4, n5
    return ns


@njit(cache=True, nogil=True)
def pair_counts_jit(film_a, film_b, des, out):
    """``out`` ``(2,) int64`` += the design cells (``des``) film ``a`` covers and ``b`` does
    not, and those ``b`` covers and ``a`` does not."""
    rows, cols = des.shape
    for i in range(rows):
        for j in range(cols):
            if des[i, j]:
                ca = film_a[i, j] > 0.0
                cb = film_b[i, j] > 0.0
                if ca and not cb:
                    out[0] += 1
                elif cb and not ca:
                    out[1] += 1


@njit(cache=True, nogil=True)
def radial_cell_counts_jit(mask, geo, lo_mm, bin_mm, out):
    """``out`` ``(B,) int64`` += the True cells of ``mask`` ``(rows, cols) bool`` per radial
    bin ``floor((r - lo_mm) / bin_mm)`` (bins outside ``0..B-1`` skipped), ``r`` a cell
    centre's platform radius (``geo`` as in :func:`strip_stats_jit`)."""
    rows, cols = mask.shape
    ox, oy, nx, ny = geo[0], geo[1], geo[2], geo[3]
    r_in, px, py, hpx, ca, sa = geo[4], geo[5], geo[6], geo[7], geo[8], geo[9]
    nb = out.size
    # the per-column products once; the bin by a guarded sqrt as in radial_bin ((h - lo) / bin
    # is monotone in h, so where the bounds either side agree, hypot's bin is theirs); the
    # current bin's count in a register
    cax, sax = column_products(cols, ox, nx, r_in, px, ca, sa)
    cb = -1
    cn = 0
    for i in range(rows):
        yl = (hpx / 2.0 - (i + 0.5 - oy) / ny) * py
        say = sa * yl
        cay = ca * yl
        for j in range(cols):
            if mask[i, j]:
                x = cax[j] - say
                y = sax[j] + cay
                r = math.sqrt(x * x + y * y)
                fb = math.floor((r * (1.0 - 1e-12) - lo_mm) / bin_mm)
                if fb != math.floor((r * (1.0 + 1e-12) - lo_mm) / bin_mm):
                    fb = math.floor((math.hypot(x, y) - lo_mm) / bin_mm)
                b = int(fb)
                if b != cb:
                    if cb >= 0:
                        out[cb] = cn
                    cb = b if 0 <= b < nb else -1
                    if cb >= 0:
                        cn = out[cb]
                if cb >= 0:
                    cn += 1
    if cb >= 0:
        out[cb] = cn
