"""Widths on the section: from samples at most ``spacing`` apart along the boundary, the
distance along the inward normal to the other side of the wall and along the outward normal
across the gap (:func:`sample_widths_chained`, which measures only what the findings need:
exactly below the need, and up to ``max_mm`` for the smallest); :func:`measure_widths` runs
the crossing search, the chains, the classification and the sampling in one call."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .chains import _RUNS_FROM, _RUN_MIN_LEN_MM, _RUN_MIN_SEGS, _chain_runs, chain_components, chain_successors
from .classify import classify_segments
from .crossings import split_at_crossings
from .grid import _cell_index, _cell_size, _clip_x, _dda_start, _hit, _span
from .pointhash import _keys


#: Margin (mm) by which the strip a segment's rays sweep is grown before testing it clear.
_STRIP_MARGIN_MM = 1e-6


#: :func:`sample_widths_chained` lists the segments in cells this many times the ray grid's.
_GATHER_CELL = 1.0


#: ... and walks a strip's cells row by row when its bounding box holds more than this many.
_GATHER_BOX = 12


#: ... and only for segments with at least this many samples (shorter ones cast their rays;
#: 1: every segment gathers, segments being listed whole).
_GATHER_MIN = 1


@njit(cache=True, nogil=True)
def _run_clear(r, sgn, Lr, run, ptr, mem, sx, sy, ex, ey, nx, ny, spacing, ent, par, start, xmin, ymin, h, ncx, ncy):  # pragma: no cover - jit
    """Whether no segment outside run ``r`` meets the rectangle (in the frame of the run's first
    direction) holding every ray its samples cast on side ``sgn`` up to ``Lr``, grown by
    ``_STRIP_MARGIN_MM``: then none of those rays hits anything (the run cannot see itself).
    Returns 1 clear, 2 not clear or not worth testing."""
    a = ptr[r]
    b = ptr[r + 1]
    k0 = mem[a]
    L0 = math.hypot(ex[k0] - sx[k0], ey[k0] - sy[k0])
    tx = (ex[k0] - sx[k0]) / L0
    ty = (ey[k0] - sy[k0]) / L0
    qx = -ty
    qy = tx
    ox = sx[k0]
    oy = sy[k0]
    a_lo = np.inf
    a_hi = -np.inf
    c_lo = np.inf
    c_hi = -np.inf
    nrays = 0
    for j in range(a, b):
        k = mem[j]
        L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
        m = max(1, int(math.ceil(L / spacing)))
        nrays += m
        for e in range(2):
            f = (0.5 / m) if e == 0 else ((m - 0.5) / m)
            px = sx[k] + f * (ex[k] - sx[k])
            py = sy[k] + f * (ey[k] - sy[k])
            for o in range(2):
                X = px + o * Lr * sgn * nx[k]
                Y = py + o * Lr * sgn * ny[k]
                u = (X - ox) * tx + (Y - oy) * ty
                v = (X - ox) * qx + (Y - oy) * qy
                a_lo = min(a_lo, u)
                a_hi = max(a_hi, u)
                c_lo = min(c_lo, v)
                c_hi = max(c_hi, v)
    a_lo -= _STRIP_MARGIN_MM
    a_hi += _STRIP_MARGIN_MM
    c_lo -= _STRIP_MARGIN_MM
    c_hi += _STRIP_MARGIN_MM
    q0x = ox + a_lo * tx + c_lo * qx
    q0y = oy + a_lo * ty + c_lo * qy
    q1x = ox + a_lo * tx + c_hi * qx
    q1y = oy + a_lo * ty + c_hi * qy
    q2x = ox + a_hi * tx + c_hi * qx
    q2y = oy + a_hi * ty + c_hi * qy
    q3x = ox + a_hi * tx + c_lo * qx
    q3y = oy + a_hi * ty + c_lo * qy
    gc0 = max(0, int(math.floor((min(q0x, q1x, q2x, q3x) - xmin) / h)))
    gc1 = min(ncx - 1, int(math.floor((max(q0x, q1x, q2x, q3x) - xmin) / h)))
    gr0 = max(0, int(math.floor((min(q0y, q1y, q2y, q3y) - ymin) / h)))
    gr1 = min(ncy - 1, int(math.floor((max(q0y, q1y, q2y, q3y) - ymin) / h)))
    if (gc1 - gc0 + 1) * (gr1 - gr0 + 1) > nrays * (int(Lr / h) + 2):
        return 2  # the rays are cheaper
    for gr in range(gr0, gr1 + 1):
        for gc in range(gc0, gc1 + 1):
            cell = gr * ncx + gc
            for pc in range(start[cell], start[cell + 1]):
                if run[par[pc]] == r:
                    continue
                a0 = ent[pc, 0]
                b0 = ent[pc, 1]
                a1 = ent[pc, 2]
                b1 = ent[pc, 3]
                ua_ = (a0 - ox) * tx + (b0 - oy) * ty
                ub_ = (a1 - ox) * tx + (b1 - oy) * ty
                if max(ua_, ub_) < a_lo or min(ua_, ub_) > a_hi:
                    continue
                va_ = (a0 - ox) * qx + (b0 - oy) * qy
                vb_ = (a1 - ox) * qx + (b1 - oy) * qy
                if max(va_, vb_) < c_lo or min(va_, vb_) > c_hi:
                    continue
                e0 = a1 - a0
                e1 = b1 - b0
                w0 = e0 * (q0y - b0) - e1 * (q0x - a0)
                w1 = e0 * (q1y - b0) - e1 * (q1x - a0)
                w2 = e0 * (q2y - b0) - e1 * (q2x - a0)
                w3 = e0 * (q3y - b0) - e1 * (q3x - a0)
                if min(w0, w1, w2, w3) <= 0.0 <= max(w0, w1, w2, w3):
                    return 2
    return 1


@njit(cache=True, nogil=True)
def sample_widths(sx, sy, ex, ey, nx, ny, keep, spacing, max_mm, tmin, cell_mm, need_wall, need_gap):  # pragma: no cover - jit
    """:func:`sample_widths_chained` without chain order (no run is tested as a whole)."""
    return sample_widths_chained(sx, sy, ex, ey, nx, ny, keep, spacing, max_mm, tmin, cell_mm, need_wall, need_gap, np.full(sx.shape[0], -1, np.int64))


@njit(cache=True, nogil=True)
def _seg_cells(sx, sy, ex, ey, keep, run, x0, y0, h, ncx, ncy):  # pragma: no cover - jit
    """The kept segments listed whole in the cells of side ``h`` they touch (grown by a
    rounding margin; row by row when their box spans several rows and columns, else the
    cells of their box), in cell order: start x, y, end x, y, segment and its ``run`` per
    entry, and the CSR ``start`` of every cell."""
    n = sx.shape[0]
    ncell = ncx * ncy
    count = np.zeros(ncell + 1, np.int64)
    pad = 1e-9 * h
    inv = 1.0 / h
    box = np.empty((n, 4), np.int64)  # first and last cell column, row
    for k in range(n):
        if not keep[k]:
            continue
        a0 = sx[k]
        b0 = sy[k]
        a1 = ex[k]
        b1 = ey[k]
        cx0 = _cell_index((min(a0, a1) - pad - x0) * inv, ncx)
        cx1 = _cell_index((max(a0, a1) + pad - x0) * inv, ncx)
        cy0 = _cell_index((min(b0, b1) - pad - y0) * inv, ncy)
        cy1 = _cell_index((max(b0, b1) + pad - y0) * inv, ncy)
        box[k, 0] = cx0
        box[k, 1] = cx1
        box[k, 2] = cy0
        box[k, 3] = cy1
        if cx0 == cx1 or cy0 == cy1:
            for cy in range(cy0, cy1 + 1):
                for cx in range(cx0, cx1 + 1):
                    count[cy * ncx + cx + 1] += 1
        else:
            for cy in range(cy0, cy1 + 1):
                c0, c1 = _span(a0, b0, a1, b1, cy, x0, y0, h, ncx, pad)
                for cx in range(max(c0, cx0), min(c1, cx1) + 1):
                    count[cy * ncx + cx + 1] += 1
    for i in range(ncell):
        count[i + 1] += count[i]
    tot = count[ncell]
    ent = np.empty((tot, 4))
    par = np.empty(tot, np.int64)
    fill = count[:-1].copy()
    for k in range(n):
        if not keep[k]:
            continue
        a0 = sx[k]
        b0 = sy[k]
        a1 = ex[k]
        b1 = ey[k]
        cx0 = box[k, 0]
        cx1 = box[k, 1]
        cy0 = box[k, 2]
        cy1 = box[k, 3]
        for cy in range(cy0, cy1 + 1):
            c0 = cx0
            c1 = cx1
            if cx0 != cx1 and cy0 != cy1:
                c0, c1 = _span(a0, b0, a1, b1, cy, x0, y0, h, ncx, pad)
                c0 = max(c0, cx0)
                c1 = min(c1, cx1)
            for cx in range(c0, c1 + 1):
                c = cy * ncx + cx
                w = fill[c]
                ent[w, 0] = a0
                ent[w, 1] = b0
                ent[w, 2] = a1
                ent[w, 3] = b1
                par[w] = k
                fill[c] = w + 1
    return ent, par, count


@njit(cache=True, nogil=True, inline="always")
def _walk(ox, oy, dx, dy, own, best, tmin, ent, par, run, start, xmin, ymin, h, ncx, ncy):  # pragma: no cover - jit
    """:func:`_ray` on the entries of :func:`_seg_cells` (``start``: each cell's first),
    skipping the segments whose ``run`` is ``own``."""
    cx, cy, stx, sty, tmx, tmy, tdx, tdy = _dda_start(ox, oy, dx, dy, xmin, ymin, h)
    hit = False
    while True:
        if 0 <= cx < ncx and 0 <= cy < ncy:
            c = cy * ncx + cx
            for pc in range(start[c], start[c + 1]):
                if run[par[pc]] == own:  # its own segment, or its run (which it cannot see)
                    continue
                t = _hit(ox, oy, dx, dy, ent[pc, 0], ent[pc, 1], ent[pc, 2], ent[pc, 3], tmin, best)
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
def sample_widths_chained(sx, sy, ex, ey, nx, ny, keep, spacing, max_mm, tmin, cell_mm, need_wall, need_gap, succ):  # pragma: no cover - jit
    """Samples along the kept segments (at most ``spacing`` apart, at least one per segment)
    with their wall width (from the sample along the inward normal ``+n`` to the first other
    boundary segment) and gap width (along ``-n``), measuring only what the check uses: every width below ``need_wall`` (``need_gap``) exactly, and the
    smallest width up to ``max_mm``; any other width may come back as ``inf``.

    A ray looks no further than ``max(need, smallest width found so far)``. A segment with
    fewer than ``_GATHER_MIN`` samples casts each ray through the cells it crosses (a 2-D DDA,
    :func:`_walk`, as the reference that casts every ray) and keeps its samples. The rays of a longer segment
    are parallel: per side, the segments that meet the strip its rays sweep (from the first
    to the last sample, up to the ray length when the segment comes, grown by
    ``_STRIP_MARGIN_MM``; tested exactly: its axes, then the segment's normal) are gathered
    once from the cells the strip covers (segments are listed whole, :func:`_seg_cells`;
    one listed in several of those cells is tested once). Each is tested against the rays
    whose sample lies within its extent along the segment, by the ray arithmetic
    (:func:`~.grid._hit`, on the segments' ends; every segment a ray hits within its length
    meets the strip, so each ray gets the nearest hit the reference finds); then
    the rays, in order, keep the hits within their own length. A side whose strip meets
    nothing casts no rays; a segment clear on both sides gives no samples at all (none of
    them could be a finding or the thinnest). Samples keep their order.

    With the chain order ``succ`` (:func:`chain_successors`; all -1: none), the segments are
    cut into runs (:func:`_chain_runs`) that cannot see themselves: a run of at least
    ``_RUN_MIN_SEGS`` segments is tested once per side, when its first segment in index
    order comes, by :func:`_run_clear` (the rectangle holding all its rays up to the ray
    length then, which only shrinks later); a clear side casts no rays. Rays skip the
    segments of their own run.

    Returns ``(P,)`` x, y, inward normal x, y, length each stands for, wall and gap widths.
    """
    n = sx.shape[0]
    seglen = np.empty(n)
    total = 0
    nk = 0
    xlo = np.inf
    xhi = -np.inf
    ylo = np.inf
    yhi = -np.inf
    for k in range(n):
        xlo = min(xlo, sx[k], ex[k])
        xhi = max(xhi, sx[k], ex[k])
        ylo = min(ylo, sy[k], ey[k])
        yhi = max(yhi, sy[k], ey[k])
        if keep[k]:
            L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
            seglen[k] = L
            total += max(1, int(math.ceil(L / spacing)))
            nk += 1
    bx = np.empty(total)
    by = np.empty(total)
    ux = np.empty(total)
    uy = np.empty(total)
    ln = np.empty(total)
    wall = np.empty(total)
    gap = np.empty(total)
    if total == 0:
        return bx, by, ux, uy, ln, wall, gap
    # the segments are listed whole in cells of side hc (the hit arithmetic is the
    # reference's: on a segment's ends)
    h = _cell_size(xhi - xlo, yhi - ylo, nk, cell_mm)
    hc = h * _GATHER_CELL
    xmin = xlo - hc
    ymin = ylo - hc
    ncx = int((xhi + hc - xmin) / hc) + 1
    ncy = int((yhi + hc - ymin) / hc) + 1
    inv = 1.0 / hc
    # runs of chained segments turning little: tested as a whole, once per side, when the
    # first of their segments comes (the ray length only shrinks after that)
    run, rptr, rmem = _chain_runs(sx, sy, ex, ey, keep, succ, _RUN_MIN_LEN_MM)
    nrun = rptr.shape[0] - 1
    rstate = np.zeros((nrun, 2), np.int8)  # 0 untested, 1 clear, 2 not clear
    ent, par, start = _seg_cells(sx, sy, ex, ey, keep, run, xmin, ymin, hc, ncx, ncy)
    low = np.array([max_mm, max_mm])  # smallest wall, gap found so far
    need = np.array([min(need_wall, max_mm), min(need_gap, max_mm)])
    skip = np.zeros(2, np.bool_)
    cand0 = np.empty(n, np.int64)  # the entries of the segments the wall strip meets
    cand1 = np.empty(n, np.int64)  # ... and the gap strip
    seen = np.full(n, -1, np.int64)  # the last segment whose strips tested this one
    ncand = np.zeros(2, np.int64)
    mg = _STRIP_MARGIN_MM
    pad = 1e-9 * hc
    tbest = np.empty(64)  # per sample of a segment, its nearest hit
    p = 0
    for k in range(n):
        if not keep[k]:
            continue
        L = seglen[k]
        m = max(1, int(math.ceil(L / spacing)))
        skip[0] = False
        skip[1] = False
        r = run[k]
        own = r
        if r >= 0 and rptr[r + 1] - rptr[r] >= _RUN_MIN_SEGS:
            for side in range(2):
                if rstate[r, side] == 0:
                    sgn = 1.0 if side == 0 else -1.0
                    rstate[r, side] = _run_clear(r, sgn, max(need[side], low[side]), run, rptr, rmem, sx, sy, ex, ey, nx, ny, spacing, ent, par, start, xmin, ymin, hc, ncx, ncy)
                skip[side] = rstate[r, side] == 1
            if skip[0] and skip[1]:
                continue
        if m < _GATHER_MIN:
            # a short segment: each of its few rays walks the cells it crosses (a 2-D DDA),
            # stopping as soon as its nearest hit lies before the next cell
            for j in range(m):
                f = (j + 0.5) / m
                bx[p] = sx[k] + f * (ex[k] - sx[k])
                by[p] = sy[k] + f * (ey[k] - sy[k])
                ux[p] = nx[k]
                uy[p] = ny[k]
                ln[p] = L / m
                p += 1
            for i in range(p - m, p):
                for side in range(2):
                    if skip[side]:
                        if side == 0:
                            wall[i] = np.inf
                        else:
                            gap[i] = np.inf
                        continue
                    sgn = 1.0 if side == 0 else -1.0
                    best = max(need[side], low[side])
                    t = _walk(bx[i], by[i], sgn * ux[i], sgn * uy[i], own, best, tmin, ent, par, run, start, xmin, ymin, hc, ncx, ncy)
                    if t < low[side]:
                        low[side] = t
                    if side == 0:
                        wall[i] = t
                    else:
                        gap[i] = t
            continue
        # the strips: along the segment from its first to its last sample, across it (in
        # the frame of the inward normal) from 0 to the ray length on each side, each grown
        # by the margin
        tx = (ex[k] - sx[k]) / L
        ty = (ey[k] - sy[k]) / L
        ox = sx[k]
        oy = sy[k]
        f = 0.5 / m
        ax = sx[k] + f * (ex[k] - sx[k])
        ay = sy[k] + f * (ey[k] - sy[k])
        f = (m - 0.5) / m
        zx = sx[k] + f * (ex[k] - sx[k])
        zy = sy[k] + f * (ey[k] - sy[k])
        a_lo = (ax - ox) * tx + (ay - oy) * ty
        a_hi = (zx - ox) * tx + (zy - oy) * ty
        if a_lo > a_hi:
            a_lo, a_hi = a_hi, a_lo
        a_lo -= mg
        a_hi += mg
        vx = nx[k]
        vy = ny[k]
        # per side, the strip across [c_lo, c_hi] (inward normal frame) and its corners
        # (along, across) = (lo, lo), (lo, hi), (hi, hi), (hi, lo)
        skip0 = skip[0]
        skip1 = skip[1]
        cw_lo = -mg
        cw_hi = need[0] if skip0 else max(need[0], low[0]) + mg
        cg_lo = -need[1] if skip1 else -max(need[1], low[1]) - mg
        cg_hi = mg
        w0x = ox + a_lo * tx + cw_lo * vx
        w0y = oy + a_lo * ty + cw_lo * vy
        w1x = ox + a_lo * tx + cw_hi * vx
        w1y = oy + a_lo * ty + cw_hi * vy
        w2x = ox + a_hi * tx + cw_hi * vx
        w2y = oy + a_hi * ty + cw_hi * vy
        w3x = ox + a_hi * tx + cw_lo * vx
        w3y = oy + a_hi * ty + cw_lo * vy
        g0x = ox + a_lo * tx + cg_lo * vx
        g0y = oy + a_lo * ty + cg_lo * vy
        g1x = ox + a_lo * tx + cg_hi * vx
        g1y = oy + a_lo * ty + cg_hi * vy
        g2x = ox + a_hi * tx + cg_hi * vx
        g2y = oy + a_hi * ty + cg_hi * vy
        g3x = ox + a_hi * tx + cg_lo * vx
        g3y = oy + a_hi * ty + cg_lo * vy
        # both strips together: the rectangle along [a_lo, a_hi], across [v_lo, v_hi]; its
        # cells (those of its bounding box, or row by row when the box holds many)
        v_lo = -mg if skip1 else cg_lo
        v_hi = mg if skip0 else cw_hi
        r0x = ox + a_lo * tx + v_lo * vx
        r0y = oy + a_lo * ty + v_lo * vy
        r1x = ox + a_lo * tx + v_hi * vx
        r1y = oy + a_lo * ty + v_hi * vy
        r2x = ox + a_hi * tx + v_hi * vx
        r2y = oy + a_hi * ty + v_hi * vy
        r3x = ox + a_hi * tx + v_lo * vx
        r3y = oy + a_hi * ty + v_lo * vy
        gr0 = max(0, int(math.floor((min(r0y, r1y, r2y, r3y) - pad - ymin) * inv)))
        gr1 = min(ncy - 1, int(math.floor((max(r0y, r1y, r2y, r3y) + pad - ymin) * inv)))
        bc0 = max(0, int(math.floor((min(r0x, r1x, r2x, r3x) - pad - xmin) * inv)))
        bc1 = min(ncx - 1, int(math.floor((max(r0x, r1x, r2x, r3x) + pad - xmin) * inv)))
        by_rows = (gr1 - gr0 + 1) * (bc1 - bc0 + 1) > _GATHER_BOX
        n0 = 0
        n1 = 0
        # its own segment is skipped as already seen, the rest of its run (which it cannot
        # see) by its run
        seen[k] = k
        lone = r < 0 or rptr[r + 1] - rptr[r] == 1
        for gr in range(gr0, gr1 + 1):
            gc0 = bc0
            gc1 = bc1
            if by_rows:
                # the rectangle's x extent within the row of cells
                y0 = ymin + gr * hc - pad
                y1 = y0 + hc + 2.0 * pad
                lo = np.inf
                hi = -np.inf
                lo, hi = _clip_x(r0x, r0y, r1x, r1y, y0, y1, lo, hi)
                lo, hi = _clip_x(r1x, r1y, r2x, r2y, y0, y1, lo, hi)
                lo, hi = _clip_x(r2x, r2y, r3x, r3y, y0, y1, lo, hi)
                lo, hi = _clip_x(r3x, r3y, r0x, r0y, y0, y1, lo, hi)
                if lo > hi:
                    continue
                gc0 = max(bc0, int(math.floor((lo - pad - xmin) * inv)))
                gc1 = min(bc1, int(math.floor((hi + pad - xmin) * inv)))
            for pc in range(start[gr * ncx + gc0], start[gr * ncx + gc1 + 1]):
                q = par[pc]
                if seen[q] == k:  # listed in an earlier cell of the strip
                    continue
                seen[q] = k
                if not lone and run[q] == own:
                    continue
                # separating axes: the strips' own (along, across), then the segment's normal
                ax_ = ent[pc, 0]
                ay_ = ent[pc, 1]
                bx_ = ent[pc, 2]
                by_ = ent[pc, 3]
                ua_ = (ax_ - ox) * tx + (ay_ - oy) * ty
                ub_ = (bx_ - ox) * tx + (by_ - oy) * ty
                if max(ua_, ub_) < a_lo or min(ua_, ub_) > a_hi:
                    continue
                va_ = (ax_ - ox) * vx + (ay_ - oy) * vy
                vb_ = (bx_ - ox) * vx + (by_ - oy) * vy
                vmin = min(va_, vb_)
                vmax = max(va_, vb_)
                e0 = bx_ - ax_
                e1 = by_ - ay_
                if not skip0 and vmax >= cw_lo and vmin <= cw_hi:
                    s0 = e0 * (w0y - ay_) - e1 * (w0x - ax_)
                    s1 = e0 * (w1y - ay_) - e1 * (w1x - ax_)
                    s2 = e0 * (w2y - ay_) - e1 * (w2x - ax_)
                    s3 = e0 * (w3y - ay_) - e1 * (w3x - ax_)
                    if min(s0, s1, s2, s3) <= 0.0 <= max(s0, s1, s2, s3):
                        cand0[n0] = pc
                        n0 += 1
                if not skip1 and vmax >= cg_lo and vmin <= cg_hi:
                    s0 = e0 * (g0y - ay_) - e1 * (g0x - ax_)
                    s1 = e0 * (g1y - ay_) - e1 * (g1x - ax_)
                    s2 = e0 * (g2y - ay_) - e1 * (g2x - ax_)
                    s3 = e0 * (g3y - ay_) - e1 * (g3x - ax_)
                    if min(s0, s1, s2, s3) <= 0.0 <= max(s0, s1, s2, s3):
                        cand1[n1] = pc
                        n1 += 1
        if n0 == 0:
            skip[0] = True
        if n1 == 0:
            skip[1] = True
        ncand[0] = n0
        ncand[1] = n1
        if skip[0] and skip[1]:
            continue
        for j in range(m):
            f = (j + 0.5) / m
            bx[p] = sx[k] + f * (ex[k] - sx[k])
            by[p] = sy[k] + f * (ey[k] - sy[k])
            ux[p] = nx[k]
            uy[p] = ny[k]
            ln[p] = L / m
            p += 1
        # per side: each candidate segment is tested against the rays whose sample lies within
        # its extent along the segment (the rays are normal to it), giving each ray the
        # nearest hit up to the strip's length; the rays then take, in order, the hits within
        # their own length (which shrinks with the smallest width found)
        if m > tbest.shape[0]:
            tbest = np.empty(2 * m)
        scale = m / L
        for side in range(2):
            out = wall if side == 0 else gap
            if skip[side]:
                for i in range(p - m, p):
                    out[i] = np.inf
                continue
            for j in range(m):
                tbest[j] = np.inf
            sgn = 1.0 if side == 0 else -1.0
            Lr = max(need[side], low[side])
            for c in range(ncand[side]):
                pc = cand0[c] if side == 0 else cand1[c]
                a0 = ent[pc, 0]
                b0 = ent[pc, 1]
                a1 = ent[pc, 2]
                b1 = ent[pc, 3]
                j0 = 0
                j1 = m - 1
                if m > 1:
                    ua_ = (a0 - ox) * tx + (b0 - oy) * ty
                    ub_ = (a1 - ox) * tx + (b1 - oy) * ty
                    j0 = max(0, int(math.ceil((min(ua_, ub_) - mg) * scale - 0.5)))
                    j1 = min(m - 1, int(math.floor((max(ua_, ub_) + mg) * scale - 0.5)))
                for j in range(j0, j1 + 1):
                    i = p - m + j
                    t = _hit(bx[i], by[i], sgn * ux[i], sgn * uy[i], a0, b0, a1, b1, tmin, min(Lr, tbest[j]))
                    if t < tbest[j]:
                        tbest[j] = t
            for j in range(m):
                t = tbest[j]
                if t <= max(need[side], low[side]):
                    if t < low[side]:
                        low[side] = t
                else:
                    t = np.inf
                out[p - m + j] = t
    return bx[:p], by[:p], ux[:p], uy[:p], ln[:p], wall[:p], gap[:p]


@njit(cache=True, nogil=True)
def measure_widths(start, end, cell_mm, near_mm, evenodd, side_eps, spacing, max_mm, tmin, need_wall, need_gap):  # pragma: no cover - jit
    """The whole width measurement of one section (``(S, 2)`` segment starts and ends, model
    mm) in one call: :func:`split_at_crossings`, :func:`chain_components`,
    :func:`classify_segments` and :func:`sample_widths` (see there for what is measured).

    Returns the samples ``(P,)`` x, y, inward normal x, y, the boundary length each stands
    for, and their wall and gap widths."""
    sx = np.ascontiguousarray(start[:, 0])
    sy = np.ascontiguousarray(start[:, 1])
    ex = np.ascontiguousarray(end[:, 0])
    ey = np.ascontiguousarray(end[:, 1])
    sx, sy, ex, ey, _, join_s, join_e = split_at_crossings(sx, sy, ex, ey, cell_mm, near_mm)
    ks = _keys(sx, sy)
    ke = _keys(ex, ey)
    comp, ncomp = chain_components(sx, sy, ex, ey, join_s, join_e, ks, ke)
    keep, nx, ny = classify_segments(sx, sy, ex, ey, comp, ncomp, evenodd, side_eps)
    if sx.shape[0] < _RUNS_FROM:
        return sample_widths(sx, sy, ex, ey, nx, ny, keep, spacing, max_mm, tmin, cell_mm, need_wall, need_gap)
    succ = chain_successors(sx, sy, ex, ey, join_s, join_e, ks, ke)
    return sample_widths_chained(sx, sy, ex, ey, nx, ny, keep, spacing, max_mm, tmin, cell_mm, need_wall, need_gap, succ)
