"""Chords grouped into findings: chords of one kind closer than ``grow`` pixels join one
region (:func:`group_chords_in` on a canvas), with per region its narrowest chord, length and
box (:func:`group_stats`, :func:`emit_groups`)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _sort_pixels(pr, Hc, Wc):  # pragma: no cover - jit
    """``pr`` (flat pixel indices ``row * Wc + col``, distinct) in increasing order: counted
    into rows, then sorted within each row by insertion (a row holds few). The same as
    ``np.sort``, which numba sorts several times slower."""
    m = pr.shape[0]
    start = np.zeros(Hc + 1, np.int64)
    for q in range(m):
        start[pr[q] // Wc + 1] += 1
    for r in range(Hc):
        start[r + 1] += start[r]
    fill = start[:Hc].copy()
    out = np.empty(m, np.int64)
    for q in range(m):
        r = pr[q] // Wc
        out[fill[r]] = pr[q]
        fill[r] += 1
    for r in range(Hc):
        for q in range(start[r] + 1, start[r + 1]):
            v = out[q]
            t = q - 1
            while t >= start[r] and out[t] > v:
                out[t + 1] = out[t]
                t -= 1
            out[t + 1] = v
    return out


@njit(cache=True, nogil=True)
def group_chords_in(ac, ar, bc, br, c0, r0, Hc, Wc, grow, buf):  # pragma: no cover - jit
    """Group chords (pixel indices) into regions: each chord is painted on the pixels
    nearest to points every quarter pixel along it (:func:`~.raster.paint_chords`) on a canvas
    of ``Hc`` x ``Wc`` pixels whose origin is pixel ``(c0, r0)``, the paint is dilated by
    ``grow`` pixels (square), and the 8-connected regions are numbered in raster order of
    their first pixel. A chord belongs to the region of the pixel nearest to its start. Work
    follows the painted pixels, not the canvas. Returns ``(n,) int64`` regions and their
    number.

    The canvas is ``buf`` (a flat ``int32`` buffer of zeros, used as ``Hc`` x ``Wc`` when it
    is that large, else a new canvas is made), which is left all zeros again: one buffer
    serves every call of a job, nothing is allocated or cleared in proportion to the canvas."""
    n = ac.shape[0]
    if buf.shape[0] >= Hc * Wc:
        canvas = buf[: Hc * Wc].reshape((Hc, Wc))  # 0 empty, -1 painted, -2 dilated, k > 0 region k - 1
    else:
        canvas = np.zeros((Hc, Wc), np.int32)
    pr = np.empty(Hc * Wc, np.int64)  # painted pixels, each once (not touched beyond them)
    m_ = 0
    for i in range(n):
        a_c = ac[i] - c0
        a_r = ar[i] - r0
        b_c = bc[i] - c0
        b_r = br[i] - r0
        L = math.hypot(b_c - a_c, b_r - a_r)
        m = max(1, int(math.ceil(L * 4.0)))
        for j in range(m + 1):
            f = j / m
            c = int(math.floor(a_c + f * (b_c - a_c) + 0.5))
            r = int(math.floor(a_r + f * (b_r - a_r) + 0.5))
            if 0 <= r < Hc and 0 <= c < Wc and canvas[r, c] != -1:
                canvas[r, c] = -1
                pr[m_] = r * Wc + c
                m_ += 1
    pr = _sort_pixels(pr[:m_], Hc, Wc)
    nd = 0
    dil = np.empty(m_ * (2 * grow + 1) * (2 * grow + 1), np.int64)  # the dilated pixels, to clear
    for q in range(m_):
        r = pr[q] // Wc
        c = pr[q] % Wc
        for rr in range(max(0, r - grow), min(Hc, r + grow + 1)):
            for cc in range(max(0, c - grow), min(Wc, c + grow + 1)):
                if canvas[rr, cc] == 0:
                    canvas[rr, cc] = -2
                    dil[nd] = rr * Wc + cc
                    nd += 1
    stack = np.empty(m_ + nd + 1, np.int64)
    ng = 0
    # the first painted pixel of a region in raster order is the first pixel of its
    # dilation shifted by (grow, grow): regions are found in raster order
    for q in range(m_):
        r = pr[q] // Wc
        c = pr[q] % Wc
        if canvas[r, c] > 0:
            continue
        ng += 1
        canvas[r, c] = ng
        sp = 1
        stack[0] = pr[q]
        while sp > 0:
            sp -= 1
            v = stack[sp]
            vr = v // Wc
            vc = v % Wc
            for rr in range(max(0, vr - 1), min(Hc, vr + 2)):
                for cc in range(max(0, vc - 1), min(Wc, vc + 2)):
                    if canvas[rr, cc] < 0:
                        canvas[rr, cc] = ng
                        stack[sp] = rr * Wc + cc
                        sp += 1
    g = np.empty(n, np.int64)
    for i in range(n):
        sc = np.int64(math.floor(ac[i] + 0.5)) - c0
        sr = np.int64(math.floor(ar[i] + 0.5)) - r0
        g[i] = canvas[sr, sc] - 1
    for q in range(m_):
        canvas[pr[q] // Wc, pr[q] % Wc] = 0
    for q in range(nd):
        canvas[dil[q] // Wc, dil[q] % Wc] = 0
    return g, ng


@njit(cache=True, nogil=True)
def group_stats(g, ng, w, ln, x0, y0, x1, y1):  # pragma: no cover - jit
    """Per region (``g`` from :func:`group_chords_in`): its narrowest chord (the first one of
    that width), the summed lengths ``ln``, and the bounding box of the chords' ends."""
    worst = np.full(ng, -1, np.int64)
    length = np.zeros(ng)
    lo_x = np.full(ng, np.inf)
    lo_y = np.full(ng, np.inf)
    hi_x = np.full(ng, -np.inf)
    hi_y = np.full(ng, -np.inf)
    for i in range(g.shape[0]):
        k = g[i]
        if worst[k] < 0 or w[i] < w[worst[k]]:
            worst[k] = i
        length[k] += ln[i]
        lo_x[k] = min(lo_x[k], min(x0[i], x1[i]))
        lo_y[k] = min(lo_y[k], min(y0[i], y1[i]))
        hi_x[k] = max(hi_x[k], max(x0[i], x1[i]))
        hi_y[k] = max(hi_y[k], max(y0[i], y1[i]))
    return worst, length, lo_x, lo_y, hi_x, hi_y


@njit(cache=True, nogil=True)
def emit_groups(idx, width, sgn, bx, by, ux, uy, ln, m2p, grow, buf):  # pragma: no cover - jit
    """Everything a finding needs for the samples ``idx``: their chords ``(n, 4)`` in pixel
    indices, their regions (:func:`group_chords_in` on a canvas padded by ``grow + 1``), and
    ``(10, regions)`` per region (:func:`group_stats`): the narrowest width, the middle of
    that chord in model mm and in pixels, the length, and the bounding box (x0, y0, x1, y1)."""
    n = idx.shape[0]
    w = np.empty(n)
    x0 = np.empty(n)
    y0 = np.empty(n)
    x1 = np.empty(n)
    y1 = np.empty(n)
    mx = np.empty(n)
    my = np.empty(n)
    l_ = np.empty(n)
    ch = np.empty((n, 4))
    ac = np.empty(n)
    ar = np.empty(n)
    bc = np.empty(n)
    br = np.empty(n)
    for q in range(n):
        i = idx[q]
        wi = width[i]
        dx = sgn * ux[i]
        dy = sgn * uy[i]
        w[q] = wi
        x0[q] = bx[i]
        y0[q] = by[i]
        x1[q] = bx[i] + wi * dx
        y1[q] = by[i] + wi * dy
        mx[q] = bx[i] + 0.5 * wi * dx
        my[q] = by[i] + 0.5 * wi * dy
        l_[q] = ln[i]
        ac[q] = m2p[0, 0] * x0[q] + m2p[0, 1] * y0[q] + m2p[0, 2]
        ar[q] = m2p[1, 0] * x0[q] + m2p[1, 1] * y0[q] + m2p[1, 2]
        bc[q] = m2p[0, 0] * x1[q] + m2p[0, 1] * y1[q] + m2p[0, 2]
        br[q] = m2p[1, 0] * x1[q] + m2p[1, 1] * y1[q] + m2p[1, 2]
        ch[q, 0] = ac[q]
        ch[q, 1] = ar[q]
        ch[q, 2] = bc[q]
        ch[q, 3] = br[q]
    pad = grow + 1
    c0 = int(math.floor(min(ac.min(), bc.min()) + 0.5)) - pad
    r0 = int(math.floor(min(ar.min(), br.min()) + 0.5)) - pad
    c1 = int(math.floor(max(ac.max(), bc.max()) + 0.5)) + pad + 1
    r1 = int(math.floor(max(ar.max(), br.max()) + 0.5)) + pad + 1
    g, ng = group_chords_in(ac, ar, bc, br, c0, r0, r1 - r0, c1 - c0, grow, buf)
    worst, length, lo_x, lo_y, hi_x, hi_y = group_stats(g, ng, w, l_, x0, y0, x1, y1)
    st = np.empty((10, ng))  # per region: width, x, y, col, row (its narrowest chord), length, bbox
    for k in range(ng):
        j = worst[k]
        st[0, k] = w[j]
        st[1, k] = mx[j]
        st[2, k] = my[j]
        st[3, k] = m2p[0, 0] * mx[j] + m2p[0, 1] * my[j] + m2p[0, 2]
        st[4, k] = m2p[1, 0] * mx[j] + m2p[1, 1] * my[j] + m2p[1, 2]
        st[5, k] = length[k]
        st[6, k] = lo_x[k]
        st[7, k] = lo_y[k]
        st[8, k] = hi_x[k]
        st[9, k] = hi_y[k]
    return ch, g, st
