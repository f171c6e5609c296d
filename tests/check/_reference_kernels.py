"""Plain references of the check's kernels, used only by the tests: every width by casting
every ray over a uniform grid (:func:`cast_rays` from :func:`boundary_samples`), the raster
tests on the image instead of runs (:func:`chord_presence`, :func:`layer_widths`), the runs
with their islands (:func:`layer_islands`), runs back to an image (:func:`runs_to_image`),
chord grouping without a reused canvas (:func:`group_chords`) and the crossing search by the
grid alone (:func:`split_at_crossings_grid`). The fast kernels in
:mod:`rotoprint.check._kernels` are tested equal to these.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from rotoprint.check._kernels.crossings import _split
from rotoprint.check._kernels.grid import _cell_size, _dda_start, _hit, _span
from rotoprint.check._kernels.groups import group_chords_in
from rotoprint.check._kernels.layer import _argmin_finite, _below
from rotoprint.check._kernels.runs import _island_stats, section_runs
from rotoprint.check._kernels.widths import measure_widths


@njit(cache=True, nogil=True)
def boundary_samples(sx, sy, ex, ey, nx, ny, keep, spacing):  # pragma: no cover - jit
    """Sample points along the kept segments, at most ``spacing`` mm apart, at least one per
    segment: ``(P,)`` x, y, inward normal x, y, segment index, and the length each stands for."""
    n = sx.shape[0]
    total = 0
    for k in range(n):
        if keep[k]:
            L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
            total += max(1, int(math.ceil(L / spacing)))
    bx = np.empty(total)
    by = np.empty(total)
    ux = np.empty(total)
    uy = np.empty(total)
    seg = np.empty(total, np.int64)
    ln = np.empty(total)
    p = 0
    for k in range(n):
        if not keep[k]:
            continue
        L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
        m = max(1, int(math.ceil(L / spacing)))
        for j in range(m):
            f = (j + 0.5) / m
            bx[p] = sx[k] + f * (ex[k] - sx[k])
            by[p] = sy[k] + f * (ey[k] - sy[k])
            ux[p] = nx[k]
            uy[p] = ny[k]
            seg[p] = k
            ln[p] = L / m
            p += 1
    return bx, by, ux, uy, seg, ln


@njit(cache=True, nogil=True, inline="always")
def _rows(ay, by, y0, h, ncy, pad):  # pragma: no cover - jit
    """The first and last row of cells of side ``h`` (from ``y0``) that the y extent of a
    segment, grown by ``pad``, touches."""
    r0 = max(0, min(ncy - 1, int(math.floor((min(ay, by) - pad - y0) / h))))
    r1 = max(0, min(ncy - 1, int(math.floor((max(ay, by) + pad - y0) / h))))
    return r0, r1


@njit(cache=True, nogil=True)
def _cells(sx, sy, ex, ey, keep, x0, y0, h, ncx, ncy):  # pragma: no cover - jit
    """CSR ``start, idx`` of the kept segments per square cell of side ``h``: each segment,
    whole, is listed in every cell its line (grown by a rounding margin) touches, row by row."""
    ncell = ncx * ncy
    count = np.zeros(ncell + 1, np.int64)
    pad = 1e-9 * h
    idx = np.empty(0, np.int64)
    fill = count[:-1]
    for q in range(2):
        if q == 1:
            for i in range(ncell):
                count[i + 1] += count[i]
            idx = np.empty(count[ncell], np.int64)
            fill = count[:-1].copy()
        for k in range(sx.shape[0]):
            if not keep[k]:
                continue
            r0, r1 = _rows(sy[k], ey[k], y0, h, ncy, pad)
            for cy in range(r0, r1 + 1):
                c0, c1 = _span(sx[k], sy[k], ex[k], ey[k], cy, x0, y0, h, ncx, pad)
                for cx in range(c0, c1 + 1):
                    c = cy * ncx + cx
                    if q == 0:
                        count[c + 1] += 1
                    else:
                        idx[fill[c]] = k
                        fill[c] += 1
    return count, idx


@njit(cache=True, nogil=True)
def split_at_crossings_grid(sx, sy, ex, ey, cell_mm, near_mm):  # pragma: no cover - jit
    """:func:`split_at_crossings` by the grid alone (every pair of segments sharing a cell),
    the reference for the search by runs."""
    return _split(sx, sy, ex, ey, cell_mm, near_mm, False)


@njit(cache=True, nogil=True)
def _ray(ox, oy, dx, dy, own, best, tmin, sx, sy, ex, ey, start, idx, xmin, ymin, h, ncx, ncy):  # pragma: no cover - jit
    """Distance along unit ``(dx, dy)`` from ``(ox, oy)`` to the first segment (not ``own``)
    hit beyond ``tmin`` and at most ``best``; ``inf`` if none. The ray walks the cells it
    crosses in order (a 2-D DDA; a segment listed in several is tested again, to the same
    result) and stops as soon as its nearest hit lies before the cell it would enter next."""
    cx, cy, stx, sty, tmx, tmy, tdx, tdy = _dda_start(ox, oy, dx, dy, xmin, ymin, h)
    hit = False
    while True:
        if 0 <= cx < ncx and 0 <= cy < ncy:
            c = cy * ncx + cx
            for j in range(start[c], start[c + 1]):
                k = idx[j]
                if k == own:
                    continue
                t = _hit(ox, oy, dx, dy, sx[k], sy[k], ex[k], ey[k], tmin, best)
                if t <= best:
                    best = t
                    hit = True
        else:
            break
        texit = min(tmx, tmy)
        if texit >= best:
            break
        if tmx < tmy:
            cx += stx
            tmx += tdx
        else:
            cy += sty
            tmy += tdy
    return best if hit else np.inf


@njit(cache=True, nogil=True)
def _grid(sx, sy, ex, ey, keep, cell_mm):  # pragma: no cover - jit
    nk = 0
    for k in range(keep.shape[0]):
        if keep[k]:
            nk += 1
    h = _cell_size(max(sx.max(), ex.max()) - min(sx.min(), ex.min()), max(sy.max(), ey.max()) - min(sy.min(), ey.min()), nk, cell_mm)
    xmin = min(sx.min(), ex.min()) - h
    ymin = min(sy.min(), ey.min()) - h
    xmax = max(sx.max(), ex.max()) + h
    ymax = max(sy.max(), ey.max()) + h
    ncx = int((xmax - xmin) / h) + 1
    ncy = int((ymax - ymin) / h) + 1
    return h, xmin, ymin, ncx, ncy


@njit(cache=True, nogil=True)
def cast_rays(bx, by, ux, uy, seg, sx, sy, ex, ey, keep, max_mm, tmin, cell_mm):  # pragma: no cover - jit
    """Distance from every sample along ``+u`` (into the material: wall width) and ``-u``
    (out of it: gap width) to the first other boundary segment, or ``inf`` beyond ``max_mm``:
    every width up to ``max_mm``, the reference for :func:`sample_widths`.

    Segments are listed, whole, in a uniform grid of cells of about ``cell_mm`` (larger for
    few segments, :func:`_cell_size`); every ray walks the cells it crosses (:func:`_ray`).

    Returns ``(P,) float64`` wall widths and ``(P,) float64`` gap widths.
    """
    P = bx.shape[0]
    wall = np.full(P, np.inf)
    gap = np.full(P, np.inf)
    if P == 0:
        return wall, gap
    h, xmin, ymin, ncx, ncy = _grid(sx, sy, ex, ey, keep, cell_mm)
    start, idx = _cells(sx, sy, ex, ey, keep, xmin, ymin, h, ncx, ncy)
    for i in range(P):
        wall[i] = _ray(bx[i], by[i], ux[i], uy[i], seg[i], max_mm, tmin, sx, sy, ex, ey, start, idx, xmin, ymin, h, ncx, ncy)
        gap[i] = _ray(bx[i], by[i], -ux[i], -uy[i], seg[i], max_mm, tmin, sx, sy, ex, ey, start, idx, xmin, ymin, h, ncx, ncy)
    return wall, gap


@njit(cache=True, nogil=True)
def chord_presence(bx, by, ux, uy, width, image, want, p2m, m2p, half_along):  # pragma: no cover - jit
    """For every chord (from ``(bx, by)`` along unit ``(ux, uy)`` for ``width`` mm), whether some
    pixel centre lying in the strip ``0 <= across <= width``, ``|along| <= half_along`` about it
    has ``image == want`` (255: the wall is in the raster; 0: the gap is open in the raster).

    ``p2m`` and ``m2p`` are the ``(2, 3)`` pixel-to-model and model-to-pixel affines.
    """
    n = bx.shape[0]
    H, W = image.shape
    out = np.zeros(n, np.bool_)
    for i in range(n):
        w = width[i]
        mx = bx[i] + 0.5 * w * ux[i]
        my = by[i] + 0.5 * w * uy[i]
        mc = m2p[0, 0] * mx + m2p[0, 1] * my + m2p[0, 2]
        mr = m2p[1, 0] * mx + m2p[1, 1] * my + m2p[1, 2]
        c0 = int(math.floor(mc)) - 2
        r0 = int(math.floor(mr)) - 2
        found = False
        for r in range(max(0, r0), min(H, r0 + 6)):
            if found:
                break
            for c in range(max(0, c0), min(W, c0 + 6)):
                qx = p2m[0, 0] * c + p2m[0, 1] * r + p2m[0, 2] - bx[i]
                qy = p2m[1, 0] * c + p2m[1, 1] * r + p2m[1, 2] - by[i]
                across = qx * ux[i] + qy * uy[i]
                along = -qx * uy[i] + qy * ux[i]
                if across >= 0.0 and across <= w and abs(along) <= half_along:
                    if (image[r, c] != 0) == (want != 0):
                        found = True
                        break
        out[i] = found
    return out


@njit(cache=True, nogil=True)
def runs_to_image(rs, r0, r1, H, W):  # pragma: no cover - jit
    """``(H, W) uint8`` image (255 in the runs), for tests."""
    out = np.zeros((H, W), np.uint8)
    for j in range(H):
        for k in range(rs[j], rs[j + 1]):
            out[j, r0[k] : r1[k]] = 255
    return out


@njit(cache=True, nogil=True)
def group_chords(ac, ar, bc, br, c0, r0, Hc, Wc, grow):  # pragma: no cover - jit
    """Group chords (pixel indices) into regions: each chord is painted on the pixels
    nearest to points every quarter pixel along it (:func:`paint_chords`) on a canvas of
    ``Hc`` x ``Wc`` pixels whose origin is pixel ``(c0, r0)``, the paint is dilated by
    ``grow`` pixels (square), and the 8-connected regions are numbered in raster order of
    their first pixel. A chord belongs to the region of the pixel nearest to its start.

    Work follows the painted pixels, not the canvas. Returns ``(n,) int64`` regions and
    their number."""
    return group_chords_in(ac, ar, bc, br, c0, r0, Hc, Wc, grow, np.zeros(0, np.int32))


@njit(cache=True, nogil=True)
def _absent(cand, sgn, bx, by, ux, uy, width, image, want, p2m, m2p, half_along):  # pragma: no cover - jit
    """The candidates whose chord has no pixel centre with ``image == want``
    (:func:`chord_presence`)."""
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
    present = chord_presence(cx, cy, dx, dy, w, image, want, p2m, m2p, half_along)
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


@njit(cache=True, nogil=True)
def layer_widths(start, end, image, cell_mm, near_mm, evenodd, side_eps, spacing, max_mm, tmin, need_wall, need_gap, min_wall, min_gap, raster_lim, p2m, m2p, pmax):  # pragma: no cover - jit
    """:func:`measure_widths` (as the rows of one ``(7, P)`` array) and what the check selects
    from it, in one call: the index of
    the thinnest wall and of the narrowest gap (-1: none below ``max_mm``), the samples of
    walls below ``min_wall`` and gaps below ``min_gap``, and, among walls and gaps below
    ``raster_lim``, those the image loses (no material / no empty pixel centre across them,
    :func:`chord_presence`)."""
    bx, by, ux, uy, ln, wall, gap = measure_widths(start, end, cell_mm, near_mm, evenodd, side_eps, spacing, max_mm, tmin, need_wall, need_gap)
    iw = _argmin_finite(wall)
    ig = _argmin_finite(gap)
    thin = _below(wall, min_wall)
    narrow = _below(gap, min_gap)
    vanished = _absent(_below(wall, raster_lim), 1.0, bx, by, ux, uy, wall, image, 255, p2m, m2p, pmax)
    closed = _absent(_below(gap, raster_lim), -1.0, bx, by, ux, uy, gap, image, 0, p2m, m2p, pmax)
    S = np.empty((7, bx.shape[0]))
    S[0] = bx
    S[1] = by
    S[2] = ux
    S[3] = uy
    S[4] = ln
    S[5] = wall
    S[6] = gap
    return S, iw, ig, thin, narrow, vanished, closed


@njit(cache=True, nogil=True)
def layer_islands(start, end, m, n_fib, n_samp, evenodd, ps, p0, p1, below):  # pragma: no cover - jit
    """:func:`section_runs` of a layer and, when ``below`` (the runs ``ps, p0, p1`` of the
    layer below are given), its :func:`island_runs`, in one call: the runs, ``(7, I)`` per
    island (pixels, mean row, mean column, first and last row, first and last column) and the
    island of every run (-1: supported)."""
    rs, r0, r1 = section_runs(start, end, m, n_fib, n_samp, evenodd)
    st, isl = _island_stats(rs, r0, r1, ps, p0, p1, below)
    return rs, r0, r1, st, isl
