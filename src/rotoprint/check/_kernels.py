"""Jit kernels of the printability check (numba). Inputs are validated by the callers in
:mod:`rotoprint.check.core`; everything here takes contiguous float64 / int64 / uint8 arrays.

Geometry is done in model millimetres on the exact cross-section (the slicer's segments):

- :func:`classify_segments` keeps the segments that are on the boundary of the filled region
  (the winding number is non-zero on exactly one side) and gives each its inward normal, so
  overlapping shells and inside-out shells are handled by the fill rule, not by orientation;
- :func:`cast_rays` measures, from sample points along the boundary, the distance along the
  inward normal to the next boundary (the local wall width) and along the outward normal (the
  local gap width). For two parallel sides this is the exact width, at any angle to the grid.

The raster kernels (:func:`paint_chords`, :func:`chord_presence`, :func:`chord_extreme`) work
on the device image in pixel indices ``(col, row)``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

_PARALLEL_EPS = 1e-15


# ---------------------------------------------------------------- bucketing helpers


@njit(cache=True, nogil=True)
def _bands(sy, ey, y0, hb, nb):  # pragma: no cover - jit
    """CSR of segment indices per horizontal band of height ``hb`` starting at ``y0``."""
    n = sy.shape[0]
    count = np.zeros(nb + 1, np.int64)
    for k in range(n):
        a = min(sy[k], ey[k])
        b = max(sy[k], ey[k])
        i0 = max(0, min(nb - 1, int(math.floor((a - y0) / hb))))
        i1 = max(0, min(nb - 1, int(math.floor((b - y0) / hb))))
        for i in range(i0, i1 + 1):
            count[i + 1] += 1
    for i in range(nb):
        count[i + 1] += count[i]
    idx = np.empty(count[nb], np.int64)
    fill = count[:-1].copy()
    for k in range(n):
        a = min(sy[k], ey[k])
        b = max(sy[k], ey[k])
        i0 = max(0, min(nb - 1, int(math.floor((a - y0) / hb))))
        i1 = max(0, min(nb - 1, int(math.floor((b - y0) / hb))))
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


@njit(cache=True, nogil=True, parallel=True)
def classify_segments(sx, sy, ex, ey, evenodd, eps):  # pragma: no cover - jit
    """Boundary flag ``(S,) bool`` and inward unit normal ``(S,)``, ``(S,)`` of each segment.

    A segment is on the boundary when the fill rule puts material on exactly one side of its
    midpoint (the winding number is evaluated ``eps`` mm to its left and to its right; a
    coincident segment of a touching shell makes both sides material).
    Zero-length segments are never boundary.
    """
    n = sx.shape[0]
    is_b = np.zeros(n, np.bool_)
    nx = np.zeros(n)
    ny = np.zeros(n)
    if n == 0:
        return is_b, nx, ny
    ymin = min(sy.min(), ey.min())
    ymax = max(sy.max(), ey.max())
    nb = max(1, min(1 << 16, n // 4))
    hb = max((ymax - ymin) / nb, 1e-12) * (1.0 + 1e-12)
    start, idx = _bands(sy, ey, ymin, hb, nb)
    for k in prange(n):
        dx = ex[k] - sx[k]
        dy = ey[k] - sy[k]
        L = math.hypot(dx, dy)
        if L == 0.0:
            continue
        lx = -dy / L
        ly = dx / L
        mx = 0.5 * (sx[k] + ex[k])
        my = 0.5 * (sy[k] + ey[k])
        qx = mx + eps * lx
        qy = my + eps * ly
        rx = mx - eps * lx
        ry = my - eps * ly
        wl = _winding(qx, qy, sx, sy, ex, ey, start, idx, ymin, hb, nb)
        wr = _winding(rx, ry, sx, sy, ex, ey, start, idx, ymin, hb, nb)
        if evenodd:
            inl = (wl & 1) != 0
            inr = (wr & 1) != 0
        else:
            inl = wl != 0
            inr = wr != 0
        if inl != inr:
            is_b[k] = True
            if inl:
                nx[k] = lx
                ny[k] = ly
            else:
                nx[k] = -lx
                ny[k] = -ly
    return is_b, nx, ny


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


@njit(cache=True, nogil=True)
def _cells(sx, sy, ex, ey, keep, x0, y0, h, ncx, ncy):  # pragma: no cover - jit
    """CSR of (piece start x, y, end x, y, parent segment) per square cell of side ``h``:
    every kept segment is cut into pieces no longer than ``h`` and each piece is listed in the
    cells its bounding box touches (at most four, nine on cell corners)."""
    n = sx.shape[0]
    npieces = 0
    for k in range(n):
        if keep[k]:
            L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
            npieces += max(1, int(math.ceil(L / h)))
    px0 = np.empty(npieces)
    py0 = np.empty(npieces)
    px1 = np.empty(npieces)
    py1 = np.empty(npieces)
    par = np.empty(npieces, np.int64)
    p = 0
    for k in range(n):
        if not keep[k]:
            continue
        L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
        m = max(1, int(math.ceil(L / h)))
        for j in range(m):
            f0 = j / m
            f1 = (j + 1) / m
            px0[p] = sx[k] + f0 * (ex[k] - sx[k])
            py0[p] = sy[k] + f0 * (ey[k] - sy[k])
            px1[p] = ex[k] if j == m - 1 else sx[k] + f1 * (ex[k] - sx[k])
            py1[p] = ey[k] if j == m - 1 else sy[k] + f1 * (ey[k] - sy[k])
            par[p] = k
            p += 1
    ncell = ncx * ncy
    count = np.zeros(ncell + 1, np.int64)
    for q in range(2):
        if q == 1:
            for i in range(ncell):
                count[i + 1] += count[i]
            idx = np.empty(count[ncell], np.int64)
            fill = count[:-1].copy()
        for p in range(npieces):
            pad = 1e-9 * h
            cx0 = max(0, min(ncx - 1, int(math.floor((min(px0[p], px1[p]) - pad - x0) / h))))
            cx1 = max(0, min(ncx - 1, int(math.floor((max(px0[p], px1[p]) + pad - x0) / h))))
            cy0 = max(0, min(ncy - 1, int(math.floor((min(py0[p], py1[p]) - pad - y0) / h))))
            cy1 = max(0, min(ncy - 1, int(math.floor((max(py0[p], py1[p]) + pad - y0) / h))))
            for cy in range(cy0, cy1 + 1):
                for cx in range(cx0, cx1 + 1):
                    c = cy * ncx + cx
                    if q == 0:
                        count[c + 1] += 1
                    else:
                        idx[fill[c]] = p
                        fill[c] += 1
    return px0, py0, px1, py1, par, count, idx


@njit(cache=True, nogil=True)
def split_at_crossings(sx, sy, ex, ey, cell_mm):  # pragma: no cover - jit
    """Cut every segment where another one crosses or touches its interior, so that each piece
    is wholly on the boundary of the filled region or wholly inside it (overlapping shells).

    Returns the pieces ``(Q,)`` start x, y, end x, y and the ``(Q,) int64`` segment each comes
    from, in segment order.
    """
    n = sx.shape[0]
    keep = np.ones(n, np.bool_)
    if n == 0:
        return sx.copy(), sy.copy(), ex.copy(), ey.copy(), np.arange(0, dtype=np.int64)
    h = max(cell_mm, 1e-9)
    xmin = min(sx.min(), ex.min()) - h
    ymin = min(sy.min(), ey.min()) - h
    xmax = max(sx.max(), ex.max()) + h
    ymax = max(sy.max(), ey.max()) + h
    while ((xmax - xmin) / h + 1) * ((ymax - ymin) / h + 1) > 4e6:
        h *= 2.0
    ncx = int((xmax - xmin) / h) + 1
    ncy = int((ymax - ymin) / h) + 1
    px0, py0, px1, py1, par, start, idx = _cells(sx, sy, ex, ey, keep, xmin, ymin, h, ncx, ncy)
    cap = 64
    rec_s = np.empty(cap, np.int64)
    rec_t = np.empty(cap)
    m = 0
    for c in range(ncx * ncy):
        for a in range(start[c], start[c + 1]):
            pa = idx[a]
            A = par[pa]
            for b in range(a + 1, start[c + 1]):
                pb = idx[b]
                B = par[pb]
                if A == B:
                    continue
                # parents' own parametrisation: exact same numbers for every cell
                d0x = ex[A] - sx[A]
                d0y = ey[A] - sy[A]
                d1x = ex[B] - sx[B]
                d1y = ey[B] - sy[B]
                den = d0x * d1y - d0y * d1x
                if den == 0.0:
                    continue
                wx = sx[B] - sx[A]
                wy = sy[B] - sy[A]
                ta = (wx * d1y - wy * d1x) / den
                tb = (wx * d0y - wy * d0x) / den
                if ta < 0.0 or ta > 1.0 or tb < 0.0 or tb > 1.0:
                    continue
                for q in range(2):
                    seg_id = A if q == 0 else B
                    t = ta if q == 0 else tb
                    if t <= 1e-12 or t >= 1.0 - 1e-12:
                        continue
                    if m == cap:
                        cap *= 2
                        ns = np.empty(cap, np.int64)
                        nt = np.empty(cap)
                        ns[:m] = rec_s[:m]
                        nt[:m] = rec_t[:m]
                        rec_s = ns
                        rec_t = nt
                    rec_s[m] = seg_id
                    rec_t[m] = t
                    m += 1
    # pieces: every segment from 0 to 1 through its sorted cut parameters
    cuts_n = np.zeros(n + 1, np.int64)
    for i in range(m):
        cuts_n[rec_s[i] + 1] += 1
    for i in range(n):
        cuts_n[i + 1] += cuts_n[i]
    ts = np.empty(m)
    fill = cuts_n[:-1].copy()
    for i in range(m):
        ts[fill[rec_s[i]]] = rec_t[i]
        fill[rec_s[i]] += 1
    total = n + m
    ox0 = np.empty(total)
    oy0 = np.empty(total)
    ox1 = np.empty(total)
    oy1 = np.empty(total)
    opar = np.empty(total, np.int64)
    q = 0
    for k in range(n):
        cs = np.sort(ts[cuts_n[k] : cuts_n[k + 1]])
        prev = 0.0
        px = sx[k]
        py = sy[k]
        for j in range(cs.shape[0] + 1):
            t = cs[j] if j < cs.shape[0] else 1.0
            if j < cs.shape[0] and t - prev <= 1e-12:
                continue  # the same cut found twice (several cells, several crossers)
            if j == cs.shape[0]:
                qx = ex[k]
                qy = ey[k]
            else:
                qx = sx[k] + t * (ex[k] - sx[k])
                qy = sy[k] + t * (ey[k] - sy[k])
            ox0[q] = px
            oy0[q] = py
            ox1[q] = qx
            oy1[q] = qy
            opar[q] = k
            q += 1
            px = qx
            py = qy
            prev = t
    return ox0[:q], oy0[:q], ox1[:q], oy1[:q], opar[:q]


@njit(cache=True, nogil=True, parallel=True)
def cast_rays(bx, by, ux, uy, seg, sx, sy, ex, ey, keep, max_mm, tmin, cell_mm):  # pragma: no cover - jit
    """Distance from every sample along ``+u`` (into the material: wall width) and ``-u``
    (out of it: gap width) to the first other boundary segment, or ``inf`` beyond ``max_mm``.

    Segments are cut into pieces no longer than ``cell_mm`` and listed in a uniform grid of
    cells of that size; every ray walks the cells it crosses in order (a 2-D DDA) and stops as
    soon as its nearest hit lies before the cell it would enter next.

    Returns ``(P,) float64`` wall widths and ``(P,) float64`` gap widths.
    """
    P = bx.shape[0]
    wall = np.full(P, np.inf)
    gap = np.full(P, np.inf)
    if P == 0:
        return wall, gap
    xmin = min(sx.min(), ex.min()) - cell_mm
    ymin = min(sy.min(), ey.min()) - cell_mm
    xmax = max(sx.max(), ex.max()) + cell_mm
    ymax = max(sy.max(), ey.max()) + cell_mm
    h = max(cell_mm, 1e-9)
    while ((xmax - xmin) / h + 1) * ((ymax - ymin) / h + 1) > 4e6:
        h *= 2.0
    ncx = int((xmax - xmin) / h) + 1
    ncy = int((ymax - ymin) / h) + 1
    px0, py0, px1, py1, par, start, idx = _cells(sx, sy, ex, ey, keep, xmin, ymin, h, ncx, ncy)
    for i in prange(P):
        for side in range(2):
            sgn = 1.0 if side == 0 else -1.0
            dx = sgn * ux[i]
            dy = sgn * uy[i]
            ox = bx[i]
            oy = by[i]
            cx = int(math.floor((ox - xmin) / h))
            cy = int(math.floor((oy - ymin) / h))
            if dx > 0.0:
                stx = 1
                tmx = (xmin + (cx + 1) * h - ox) / dx
                tdx = h / dx
            elif dx < 0.0:
                stx = -1
                tmx = (xmin + cx * h - ox) / dx
                tdx = -h / dx
            else:
                stx = 0
                tmx = np.inf
                tdx = np.inf
            if dy > 0.0:
                sty = 1
                tmy = (ymin + (cy + 1) * h - oy) / dy
                tdy = h / dy
            elif dy < 0.0:
                sty = -1
                tmy = (ymin + cy * h - oy) / dy
                tdy = -h / dy
            else:
                sty = 0
                tmy = np.inf
                tdy = np.inf
            best = max_mm
            hit = False
            while True:
                if 0 <= cx < ncx and 0 <= cy < ncy:
                    c = cy * ncx + cx
                    for j in range(start[c], start[c + 1]):
                        p = idx[j]
                        if par[p] == seg[i]:
                            continue
                        e0 = px1[p] - px0[p]
                        e1 = py1[p] - py0[p]
                        den = dx * e1 - dy * e0
                        if abs(den) <= _PARALLEL_EPS * (abs(e0) + abs(e1)):
                            continue
                        w0 = px0[p] - ox
                        w1 = py0[p] - oy
                        t = (w0 * e1 - w1 * e0) / den
                        if t <= tmin or t > best:
                            continue
                        s = (w0 * dy - w1 * dx) / den
                        if s < 0.0 or s > 1.0:
                            continue
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
            if hit:
                if side == 0:
                    wall[i] = best
                else:
                    gap[i] = best
    return wall, gap


# ---------------------------------------------------------------- raster kernels


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
