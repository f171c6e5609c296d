"""Kernels on the device raster, in pixel indices ``(col, row)``: painting chords
(:func:`paint_chords`, the overlays), whether a chord holds a pixel centre of material or of
empty space in the layer's runs (:func:`chord_presence_runs`), and the peak or lowest grey
along chords (:func:`chord_extreme`, the exposure test)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def paint_chords(ac, ar, bc, br, out, value):  # pragma: no cover - jit
    """Set ``out[row, col] = value`` on the pixels nearest to points every quarter pixel along
    each chord from ``(ac, ar)`` to ``(bc, br)`` (pixel indices), both ends included."""
    H, W = out.shape
    for i in range(ac.shape[0]):
        L = math.hypot(bc[i] - ac[i], br[i] - ar[i])
        m = max(1, int(math.ceil(L * 4.0)))
        for j in range(m + 1):
            f = j / m
            c = int(math.floor(ac[i] + f * (bc[i] - ac[i]) + 0.5))
            r = int(math.floor(ar[i] + f * (br[i] - ar[i]) + 0.5))
            if 0 <= r < H and 0 <= c < W:
                out[r, c] = value
    return out


@njit(cache=True, nogil=True)
def _runs_at(rs, r0, r1, r, c):  # pragma: no cover - jit
    """Whether pixel ``(r, c)`` is in a run of row ``r`` (runs sorted, disjoint)."""
    for k in range(rs[r], rs[r + 1]):
        if c < r0[k]:
            return False
        if c < r1[k]:
            return True
    return False


@njit(cache=True, nogil=True)
def chord_presence_runs(bx, by, ux, uy, width, rs, r0, r1, H, W, want, p2m, m2p, half_along):  # pragma: no cover - jit
    """For every chord (from ``(bx, by)`` along unit ``(ux, uy)`` for ``width`` mm), whether some
    pixel centre lying in the strip ``0 <= across <= width``, ``|along| <= half_along`` about it
    has ``image == want`` (255: the wall is in the raster; 0: the gap is open in the raster),
    the image given as runs (:func:`~.runs.fill_runs`, ``H`` x ``W``): the pixel centres of the
    window in the bounding box of the chord's rectangle (the others cannot be in it), material
    where a run covers the pixel. ``p2m`` and ``m2p`` are the ``(2, 3)`` pixel-to-model and
    model-to-pixel affines. (The tests compare it with the same test on the image.)"""
    n = bx.shape[0]
    out = np.zeros(n, np.bool_)
    wm = want != 0
    # pixel_to_model's inverse (the pixels whose centres can be in a rectangle)
    det = p2m[0, 0] * p2m[1, 1] - p2m[0, 1] * p2m[1, 0]
    i00 = p2m[1, 1] / det
    i01 = -p2m[0, 1] / det
    i10 = -p2m[1, 0] / det
    i11 = p2m[0, 0] / det
    for i in range(n):
        w = width[i]
        mx = bx[i] + 0.5 * w * ux[i]
        my = by[i] + 0.5 * w * uy[i]
        mc = m2p[0, 0] * mx + m2p[0, 1] * my + m2p[0, 2]
        mr = m2p[1, 0] * mx + m2p[1, 1] * my + m2p[1, 2]
        c0 = int(math.floor(mc)) - 2
        r0_ = int(math.floor(mr)) - 2
        # the chord's rectangle in pixel indices (its corners by the inverse of p2m), grown
        # by a rounding margin: only the window's pixels in its bounding box can pass the
        # test below
        tx = -uy[i] * half_along
        ty = ux[i] * half_along
        plo = qlo = np.inf
        phi = qhi = -np.inf
        for k in range(4):
            cx_ = bx[i] + (w * ux[i] if k >= 2 else 0.0) + (tx if k == 0 or k == 3 else -tx)
            cy_ = by[i] + (w * uy[i] if k >= 2 else 0.0) + (ty if k == 0 or k == 3 else -ty)
            pc = i00 * (cx_ - p2m[0, 2]) + i01 * (cy_ - p2m[1, 2])
            pr = i10 * (cx_ - p2m[0, 2]) + i11 * (cy_ - p2m[1, 2])
            plo = min(plo, pc)
            phi = max(phi, pc)
            qlo = min(qlo, pr)
            qhi = max(qhi, pr)
        pad = 1e-6 * (1.0 + abs(plo) + abs(phi) + abs(qlo) + abs(qhi))
        cs = max(0, c0, int(math.ceil(plo - pad)))
        ce = min(W, c0 + 6, int(math.floor(phi + pad)) + 1)
        found = False
        for r in range(max(0, r0_, int(math.ceil(qlo - pad))), min(H, r0_ + 6, int(math.floor(qhi + pad)) + 1)):
            if found:
                break
            for c in range(cs, ce):
                qx = p2m[0, 0] * c + p2m[0, 1] * r + p2m[0, 2] - bx[i]
                qy = p2m[1, 0] * c + p2m[1, 1] * r + p2m[1, 2] - by[i]
                across = qx * ux[i] + qy * uy[i]
                along = -qx * uy[i] + qy * ux[i]
                if across >= 0.0 and across <= w and abs(along) <= half_along:
                    if _runs_at(rs, r0, r1, r, c) == wm:
                        found = True
                        break
        out[i] = found
    return out


@njit(cache=True, nogil=True)
def chord_extreme(ac, ar, bc, br, grey, take_max):  # pragma: no cover - jit
    """Maximum (``take_max``) or minimum of ``grey`` over the pixels nearest to points every
    quarter pixel along each chord (pixel indices); ``(n,) float64``."""
    H, W = grey.shape
    n = ac.shape[0]
    out = np.empty(n)
    for i in range(n):
        L = math.hypot(bc[i] - ac[i], br[i] - ar[i])
        m = max(1, int(math.ceil(L * 4.0)))
        best = -1.0 if take_max else 1e9
        for j in range(m + 1):
            f = j / m
            c = int(math.floor(ac[i] + f * (bc[i] - ac[i]) + 0.5))
            r = int(math.floor(ar[i] + f * (br[i] - ar[i]) + 0.5))
            v = float(grey[r, c]) if (0 <= r < H and 0 <= c < W) else 0.0
            if take_max:
                if v > best:
                    best = v
            elif v < best:
                best = v
        out[i] = best
    return out


@njit(cache=True, nogil=True)
def _absent_runs(cand, sgn, bx, by, ux, uy, width, rs, r0, r1, H, W, want, p2m, m2p, half_along):  # pragma: no cover - jit
    """The candidates whose chord has no pixel centre with ``image == want``
    (:func:`chord_presence_runs` on the image as runs)."""
    n = cand.shape[0]
    cx = np.empty(n)
    cy = np.empty(n)
    dx = np.empty(n)
    dy = np.empty(n)
    w = np.empty(n)
    for q in range(n):
        i = cand[q]
        cx[q] = bx[i]
        cy[q] = by[i]
        dx[q] = sgn * ux[i]
        dy[q] = sgn * uy[i]
        w[q] = width[i]
    present = chord_presence_runs(cx, cy, dx, dy, w, rs, r0, r1, H, W, want, p2m, m2p, half_along)
    m = 0
    for q in range(n):
        if not present[q]:
            m += 1
    out = np.empty(m, np.int64)
    m = 0
    for q in range(n):
        if not present[q]:
            out[m] = cand[q]
            m += 1
    return out
