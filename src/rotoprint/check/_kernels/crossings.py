"""The crossing search: a section's segments split where they cross or touch
(:func:`split_at_crossings`), pairs found by every pair (few segments), by runs of chained
segments (:func:`_run_pairs`, large sections) or by a uniform grid (:func:`_grid_pairs`)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .chains import _RUNS_FROM, _RUN_COS, _RUN_MIN_LEN_MM, _chain_runs, chain_successors
from .grid import _cell_index, _cell_size
from .pointhash import _keys


#: Up to this many segments the crossing search tests every pair (no grid to build).
_FEW = 256


#: The crossing search's cells are at least this times the side of a square per segment
#: (:func:`_split_cell_size`).
_SPLIT_CELL = 0.75


@njit(cache=True, nogil=True)
def _split_cell_size(w, h, n, cell_mm):  # pragma: no cover - jit
    """Cell side of the crossing search's grid for ``n`` segments over a ``w`` x ``h`` mm box:
    :func:`_cell_size`, or ``_SPLIT_CELL`` times the side of a square per segment if larger
    (each pair of pieces is tested once, so a few more per cell cost less than listing long
    segments in more cells)."""
    return max(_cell_size(w, h, n, cell_mm), _SPLIT_CELL * math.sqrt(max(w * h, 0.0) / max(n, 1)))


@njit(cache=True, nogil=True, inline="always")
def _rec(rec_s, rec_t, m, seg_id, t):  # pragma: no cover - jit
    """Record cut ``t`` of segment ``seg_id`` as the ``m``-th if the buffers hold it; returns
    ``m + 1`` either way (the caller searches again with larger buffers when they overflow)."""
    if m < rec_s.shape[0]:
        rec_s[m] = seg_id
        rec_t[m] = t
    return m + 1


@njit(cache=True, nogil=True)
def _pt_seg_d2(px, py, ax, ay, bx, by):  # pragma: no cover - jit
    dx = bx - ax
    dy = by - ay
    ll = dx * dx + dy * dy
    t = 0.0 if ll == 0.0 else max(0.0, min(1.0, ((px - ax) * dx + (py - ay) * dy) / ll))
    qx = ax + t * dx - px
    qy = ay + t * dy - py
    return qx * qx + qy * qy


@njit(cache=True, nogil=True)
def _isolate(touch_s, touch_e, A, B):  # pragma: no cover - jit
    touch_s[A] = True
    touch_e[A] = True
    touch_s[B] = True
    touch_e[B] = True


@njit(cache=True, nogil=True)
def _near(sx, sy, ex, ey, A, B, d):  # pragma: no cover - jit
    """Whether segments ``A`` and ``B`` (not crossing) come within ``d`` of each other away
    from a shared end."""
    if d <= 0.0:
        return False
    if min(sx[A], ex[A]) - d > max(sx[B], ex[B]) or min(sx[B], ex[B]) - d > max(sx[A], ex[A]):
        return False
    if min(sy[A], ey[A]) - d > max(sy[B], ey[B]) or min(sy[B], ey[B]) - d > max(sy[A], ey[A]):
        return False
    if (sx[A] == ex[B] and sy[A] == ey[B]) or (ex[A] == sx[B] and ey[A] == sy[B]):
        return False  # neighbours in a chain
    d2 = d * d
    return (
        _pt_seg_d2(sx[A], sy[A], sx[B], sy[B], ex[B], ey[B]) < d2
        or _pt_seg_d2(ex[A], ey[A], sx[B], sy[B], ex[B], ey[B]) < d2
        or _pt_seg_d2(sx[B], sy[B], sx[A], sy[A], ex[A], ey[A]) < d2
        or _pt_seg_d2(ex[B], ey[B], sx[A], sy[A], ex[A], ey[A]) < d2
    )


@njit(cache=True, nogil=True, inline="always")
def _pair(A, B, sx, sy, ex, ey, bx0, bx1, by0, by1, near_mm, tol, touch_s, touch_e, rec_s, rec_t, m):  # pragma: no cover - jit
    """Test segments ``A < B`` of :func:`split_at_crossings` (boxes grown by the near
    distance): record the cuts each makes in the other (``_rec``) and flag the ends that are
    no ordinary joints. Returns the new count of cuts, recorded as far as the buffers
    ``rec_s, rec_t`` hold.

    The search by runs calls this; the grid search (:func:`_grid_pairs`) keeps the same test
    written out in its loop, recording into fixed buffers (called or inlined there, the pair
    tests took several times as long). ``test_split_by_runs_equals_the_grid`` holds the two
    to the same results."""
    if bx0[A] > bx1[B] or bx0[B] > bx1[A] or by0[A] > by1[B] or by0[B] > by1[A]:
        return m
    d0x = ex[A] - sx[A]
    d0y = ey[A] - sy[A]
    d1x = ex[B] - sx[B]
    d1y = ey[B] - sy[B]
    wx = sx[B] - sx[A]
    wy = sy[B] - sy[A]
    den = d0x * d1y - d0y * d1x
    l0 = d0x * d0x + d0y * d0y
    l1 = d1x * d1x + d1y * d1y
    if l0 == 0.0 or l1 == 0.0:
        return m
    if abs(den) <= 1e-12 * math.sqrt(l0 * l1):
        # parallel: only collinear overlaps matter
        if abs(wx * d0y - wy * d0x) > 1e-12 * (l0 + wx * wx + wy * wy):
            if _near(sx, sy, ex, ey, A, B, near_mm):
                _isolate(touch_s, touch_e, A, B)
            return m
        # B's ends along A: an overlap of positive length, or just a joint
        u0 = (wx * d0x + wy * d0y) / l0
        u1 = ((ex[B] - sx[A]) * d0x + (ey[B] - sy[A]) * d0y) / l0
        if min(max(u0, u1), 1.0) - max(min(u0, u1), 0.0) <= tol:
            return m  # end to end (a straight run of a chain) or apart
        for q in range(2):
            X = A if q == 0 else B
            Y = B if q == 0 else A
            dx = ex[X] - sx[X]
            dy = ey[X] - sy[X]
            ll = dx * dx + dy * dy
            for r in range(2):  # Y's ends on X
                yx = sx[Y] if r == 0 else ex[Y]
                yy = sy[Y] if r == 0 else ey[Y]
                t = ((yx - sx[X]) * dx + (yy - sy[X]) * dy) / ll
                if tol < t < 1.0 - tol:
                    m = _rec(rec_s, rec_t, m, X, t)
                    if r == 0:
                        touch_s[Y] = True
                    else:
                        touch_e[Y] = True
                elif -tol <= t <= 1.0 + tol:
                    # ends meet on an overlap: neither end is an ordinary joint
                    ty = 0.0 if r == 0 else 1.0
                    if t <= tol:
                        touch_s[X] = True
                    else:
                        touch_e[X] = True
                    if ty == 0.0:
                        touch_s[Y] = True
                    else:
                        touch_e[Y] = True
        return m
    ta = (wx * d1y - wy * d1x) / den
    tb = (wx * d0y - wy * d0x) / den
    if ta < -tol or ta > 1.0 + tol or tb < -tol or tb > 1.0 + tol:
        if _near(sx, sy, ex, ey, A, B, near_mm):
            _isolate(touch_s, touch_e, A, B)
        return m
    ia = tol < ta < 1.0 - tol
    ib = tol < tb < 1.0 - tol
    if not ia and not ib:
        return m  # a shared vertex: an ordinary joint
    if ia:
        m = _rec(rec_s, rec_t, m, A, ta)
    elif ta <= tol:
        touch_s[A] = True
    else:
        touch_e[A] = True
    if ib:
        m = _rec(rec_s, rec_t, m, B, tb)
    elif tb <= tol:
        touch_s[B] = True
    else:
        touch_e[B] = True
    return m


@njit(cache=True, nogil=True)
def split_at_crossings(sx, sy, ex, ey, cell_mm, near_mm):  # pragma: no cover - jit
    """Cut every segment where another one crosses, touches or overlaps its interior, so that
    each piece is wholly on the boundary of the filled region or wholly inside it (overlapping
    or touching shells).

    Returns the pieces ``(Q,)`` start x, y, end x, y, the ``(Q,) int64`` segment each comes
    from, and ``(Q,) bool`` flags saying whether the piece's start / end is an ordinary chain
    joint (not a cut, and touching no other segment), in segment order. Segments of other
    chains that come within ``near_mm`` without meeting (coincident faces of touching shells,
    to rounding) are not ordinary at either end, so the classification looks at each of them.
    """
    return _split(sx, sy, ex, ey, cell_mm, near_mm, True)


@njit(cache=True, nogil=True)
def _rects_apart(P, Q):  # pragma: no cover - jit
    """Whether two rectangles (``(4, 2)`` corners in order) are separated along one of their
    sides' directions (separating axes; rectangles that only touch are not apart)."""
    for which in range(2):
        R = P if which == 0 else Q
        for side in range(2):
            axx = R[side + 1, 0] - R[side, 0]
            axy = R[side + 1, 1] - R[side, 1]
            p_lo = np.inf
            p_hi = -np.inf
            q_lo = np.inf
            q_hi = -np.inf
            for c in range(4):
                v = P[c, 0] * axx + P[c, 1] * axy
                p_lo = min(p_lo, v)
                p_hi = max(p_hi, v)
                w = Q[c, 0] * axx + Q[c, 1] * axy
                q_lo = min(q_lo, w)
                q_hi = max(q_hi, w)
            if p_hi < q_lo or q_hi < p_lo:
                return True
    return False


@njit(cache=True, nogil=True)
def _run_pairs(sx, sy, ex, ey, bx0, bx1, by0, by1, near_mm, tol, touch_s, touch_e, rec_s, rec_t):  # pragma: no cover - jit
    """The pair tests of :func:`split_at_crossings` by runs: the segments are cut into runs of
    consecutive chained segments (:func:`chain_successors`, :func:`_chain_runs`) whose
    directions stay within 35 degrees of the first and whose segments are long enough that
    two segments of a run with one between are more than the near distance apart along the
    first direction. Such a run neither crosses, touches nor comes near itself (neighbours
    share their end exactly and meet at it: the pair test finds nothing, see the tests), so
    only pairs of segments of different runs whose boxes (grown by the near distance) overlap
    are tested, runs paired by a sweep over their boxes.

    Returns ``False`` (nothing done) when the runs are not at least 8 segments long on average
    (the grid is the better search), else ``True``; and the number of cuts, recorded as far
    as ``rec_s, rec_t`` hold."""
    n = sx.shape[0]
    ones = np.ones(n, np.bool_)
    succ = chain_successors(sx, sy, ex, ey, ones, ones, _keys(sx, sy), _keys(ex, ey))
    min_len = max(_RUN_MIN_LEN_MM, 2.0 * max(near_mm, 0.0) / _RUN_COS)
    run, ptr, mem = _chain_runs(sx, sy, ex, ey, ones, succ, min_len)
    nu = ptr.shape[0] - 1
    m = 0
    if 8 * nu > n:
        return False, m
    ux0 = np.full(nu, np.inf)
    ux1 = np.full(nu, -np.inf)
    uy0 = np.full(nu, np.inf)
    uy1 = np.full(nu, -np.inf)
    for u in range(nu):
        for a in range(ptr[u], ptr[u + 1]):
            k = mem[a]
            ux0[u] = min(ux0[u], bx0[k])
            ux1[u] = max(ux1[u], bx1[k])
            uy0[u] = min(uy0[u], by0[k])
            uy1[u] = max(uy1[u], by1[k])
    # each run's rectangle in the frame of its first direction (a run is thin across it: an
    # arc's sagitta), grown by the near distance and a rounding margin
    grow = max(near_mm, 0.0) + 1e-9
    rc = np.empty((nu, 4, 2))  # corners
    for u in range(nu):
        k0 = mem[ptr[u]]
        L0 = max(math.hypot(ex[k0] - sx[k0], ey[k0] - sy[k0]), 1e-300)
        tx = (ex[k0] - sx[k0]) / L0
        ty = (ey[k0] - sy[k0]) / L0
        if L0 <= 1e-300:
            tx = 1.0
            ty = 0.0
        a_lo = np.inf
        a_hi = -np.inf
        c_lo = np.inf
        c_hi = -np.inf
        for a in range(ptr[u], ptr[u + 1]):
            k = mem[a]
            for e in range(2):
                X = (sx[k] if e == 0 else ex[k]) - sx[k0]
                Y = (sy[k] if e == 0 else ey[k]) - sy[k0]
                al = X * tx + Y * ty
                ac = -X * ty + Y * tx
                a_lo = min(a_lo, al)
                a_hi = max(a_hi, al)
                c_lo = min(c_lo, ac)
                c_hi = max(c_hi, ac)
        a_lo -= grow
        a_hi += grow
        c_lo -= grow
        c_hi += grow
        for q in range(4):
            al = a_lo if q == 0 or q == 1 else a_hi
            ac = c_lo if q == 0 or q == 3 else c_hi
            rc[u, q, 0] = sx[k0] + al * tx - ac * ty
            rc[u, q, 1] = sy[k0] + al * ty + ac * tx
    # each run's segments by the low edge of their boxes in x and in y
    ordx = mem.copy()
    ordy = mem.copy()
    for u in range(nu):
        a0 = ptr[u]
        a1 = ptr[u + 1]
        if a1 - a0 > 1:
            seg = mem[a0:a1]
            ordx[a0:a1] = seg[np.argsort(bx0[seg], kind="mergesort")]
            ordy[a0:a1] = seg[np.argsort(by0[seg], kind="mergesort")]
    order = np.argsort(ux0, kind="mergesort")
    for ii in range(nu):
        U = order[ii]
        for jj in range(ii + 1, nu):
            V = order[jj]
            if ux0[V] > ux1[U]:
                break
            if uy0[V] > uy1[U] or uy0[U] > uy1[V]:
                continue
            if _rects_apart(rc[U], rc[V]):
                continue
            # the pairs of the two runs whose boxes overlap along the axis both runs spread
            # over most (a sweep over the two sorted lists; each such pair once)
            along_x = (ux1[U] - ux0[U]) + (ux1[V] - ux0[V]) >= (uy1[U] - uy0[U]) + (uy1[V] - uy0[V])
            LA = ordx[ptr[U] : ptr[U + 1]] if along_x else ordy[ptr[U] : ptr[U + 1]]
            LB = ordx[ptr[V] : ptr[V + 1]] if along_x else ordy[ptr[V] : ptr[V + 1]]
            lo = bx0 if along_x else by0
            hi = bx1 if along_x else by1
            nA = LA.shape[0]
            nB = LB.shape[0]
            i = 0
            j = 0
            while i < nA and j < nB:
                a = LA[i]
                b = LB[j]
                if lo[a] <= lo[b]:
                    q = j
                    while q < nB and lo[LB[q]] <= hi[a]:
                        B0 = LB[q]
                        m = _pair(min(a, B0), max(a, B0), sx, sy, ex, ey, bx0, bx1, by0, by1, near_mm, tol, touch_s, touch_e, rec_s, rec_t, m)
                        q += 1
                    i += 1
                else:
                    q = i
                    while q < nA and lo[LA[q]] <= hi[b]:
                        A0 = LA[q]
                        m = _pair(min(A0, b), max(A0, b), sx, sy, ex, ey, bx0, bx1, by0, by1, near_mm, tol, touch_s, touch_e, rec_s, rec_t, m)
                        q += 1
                    j += 1
    return True, m


@njit(cache=True, nogil=True)
def _split_cells(sx, sy, ex, ey, x0, y0, h, ncx, ncy, grow):  # pragma: no cover - jit
    """The cells of the grid search (square, side ``h``, from ``x0, y0``): every segment is
    cut into pieces no longer than ``h`` and each piece is listed in the cells its box, grown
    by ``grow`` mm, touches (as in :func:`_cells`). Returns the CSR ``start, ent`` of the
    entries per cell, each entry ``4 * segment + 2 * (the cell is the first column the piece
    is listed in) + (the cell is its first row)``: two pieces in a cell are listed together
    in an earlier cell too unless their entries' low bits together make 3."""
    n = sx.shape[0]
    pm = np.empty(n, np.int64)
    npieces = 0
    for k in range(n):
        dx = ex[k] - sx[k]
        dy = ey[k] - sy[k]
        mk = max(1, int(math.ceil(math.sqrt(dx * dx + dy * dy) / h)))
        pm[k] = mk
        npieces += mk
    cr = np.empty((npieces, 4), np.int64)  # each piece's first and last cell column and row
    ncell = ncx * ncy
    start = np.zeros(ncell + 1, np.int64)
    pad = 1e-9 * h + grow
    ih = 1.0 / h
    p = 0
    for k in range(n):
        mk = pm[k]
        for j in range(mk):
            if mk == 1:
                ax = sx[k]
                ay = sy[k]
                bx = ex[k]
                by = ey[k]
            else:
                f0 = j / mk
                f1 = (j + 1) / mk
                ax = sx[k] + f0 * (ex[k] - sx[k])
                ay = sy[k] + f0 * (ey[k] - sy[k])
                bx = ex[k] if j == mk - 1 else sx[k] + f1 * (ex[k] - sx[k])
                by = ey[k] if j == mk - 1 else sy[k] + f1 * (ey[k] - sy[k])
            # (truncation is the floor here: the negatives it rounds up are clamped to 0)
            cx0 = _cell_index((min(ax, bx) - pad - x0) * ih, ncx)
            cx1 = _cell_index((max(ax, bx) + pad - x0) * ih, ncx)
            cy0 = _cell_index((min(ay, by) - pad - y0) * ih, ncy)
            cy1 = _cell_index((max(ay, by) + pad - y0) * ih, ncy)
            cr[p, 0] = cx0
            cr[p, 1] = cx1
            cr[p, 2] = cy0
            cr[p, 3] = cy1
            for cy in range(cy0, cy1 + 1):
                for cx in range(cx0, cx1 + 1):
                    start[cy * ncx + cx + 1] += 1
            p += 1
    for i in range(ncell):
        start[i + 1] += start[i]
    ent = np.empty(start[ncell], np.int64)
    fill = start[:-1].copy()
    p = 0
    for k in range(n):
        for j in range(pm[k]):
            cx0 = cr[p, 0]
            cy0 = cr[p, 2]
            for cy in range(cy0, cr[p, 3] + 1):
                for cx in range(cx0, cr[p, 1] + 1):
                    c = cy * ncx + cx
                    ent[fill[c]] = 4 * k + (2 if cx == cx0 else 0) + (1 if cy == cy0 else 0)
                    fill[c] += 1
            p += 1
    return start, ent


@njit(cache=True, nogil=True)
def _grid_pairs(sx, sy, ex, ey, bx0, bx1, by0, by1, start, ent, near_mm, tol, touch_s, touch_e, rec_s, rec_t):  # pragma: no cover - jit
    """The pair tests of the grid search (:func:`_split_cells`): every pair of segments with
    pieces in a common cell and overlapping boxes (grown by the near distance), each pair of
    pieces once, in the first cell both are listed in (the later of their first columns, the
    later of their first rows). The test is :func:`_pair`'s, step for step, written out here
    (called, or inlined, it was several times slower). Returns the number of cuts, recorded
    as far as ``rec_s, rec_t`` hold (the caller searches again with larger buffers when they
    overflow)."""
    m = 0
    for c in range(start.shape[0] - 1):
        a0 = start[c]
        a1 = start[c + 1]
        if a1 - a0 < 2:
            continue
        swept = a1 - a0 > 32
        if swept:
            # a crowded cell: its entries by the left edge of their segment's box, each pair
            # looked at only while the boxes can overlap in x (a sweep)
            cell = ent[a0:a1]
            ent[a0:a1] = cell[np.argsort(bx0[cell >> 2], kind="mergesort")]
        for a in range(a0, a1):
            ea = ent[a]
            A0 = ea >> 2
            for b in range(a + 1, a1):
                eb = ent[b]
                B0 = eb >> 2
                if swept and bx0[B0] > bx1[A0]:
                    break  # this and every later box start right of A's box
                if (ea | eb) & 3 != 3 or A0 == B0:
                    continue  # listed together in an earlier cell, or one segment
                A = min(A0, B0)  # the lower segment first
                B = max(A0, B0)
                if bx0[A] > bx1[B] or bx0[B] > bx1[A] or by0[A] > by1[B] or by0[B] > by1[A]:
                    continue
                d0x = ex[A] - sx[A]
                d0y = ey[A] - sy[A]
                d1x = ex[B] - sx[B]
                d1y = ey[B] - sy[B]
                wx = sx[B] - sx[A]
                wy = sy[B] - sy[A]
                den = d0x * d1y - d0y * d1x
                l0 = d0x * d0x + d0y * d0y
                l1 = d1x * d1x + d1y * d1y
                if l0 == 0.0 or l1 == 0.0:
                    continue
                if abs(den) <= 1e-12 * math.sqrt(l0 * l1):
                    # parallel: only collinear overlaps matter
                    if abs(wx * d0y - wy * d0x) > 1e-12 * (l0 + wx * wx + wy * wy):
                        if _near(sx, sy, ex, ey, A, B, near_mm):
                            _isolate(touch_s, touch_e, A, B)
                        continue
                    # B's ends along A: an overlap of positive length, or just a joint
                    u0 = (wx * d0x + wy * d0y) / l0
                    u1 = ((ex[B] - sx[A]) * d0x + (ey[B] - sy[A]) * d0y) / l0
                    if min(max(u0, u1), 1.0) - max(min(u0, u1), 0.0) <= tol:
                        continue  # end to end (a straight run of a chain) or apart
                    for q in range(2):
                        X = A if q == 0 else B
                        Y = B if q == 0 else A
                        dx = ex[X] - sx[X]
                        dy = ey[X] - sy[X]
                        ll = dx * dx + dy * dy
                        for r in range(2):  # Y's ends on X
                            yx = sx[Y] if r == 0 else ex[Y]
                            yy = sy[Y] if r == 0 else ey[Y]
                            t = ((yx - sx[X]) * dx + (yy - sy[X]) * dy) / ll
                            if tol < t < 1.0 - tol:
                                if m < rec_s.shape[0]:
                                    rec_s[m] = X
                                    rec_t[m] = t
                                m += 1
                                if r == 0:
                                    touch_s[Y] = True
                                else:
                                    touch_e[Y] = True
                            elif -tol <= t <= 1.0 + tol:
                                # ends meet on an overlap: neither end is an ordinary joint
                                if t <= tol:
                                    touch_s[X] = True
                                else:
                                    touch_e[X] = True
                                if r == 0:
                                    touch_s[Y] = True
                                else:
                                    touch_e[Y] = True
                    continue
                ta = (wx * d1y - wy * d1x) / den
                tb = (wx * d0y - wy * d0x) / den
                if ta < -tol or ta > 1.0 + tol or tb < -tol or tb > 1.0 + tol:
                    if _near(sx, sy, ex, ey, A, B, near_mm):
                        _isolate(touch_s, touch_e, A, B)
                    continue
                ia = tol < ta < 1.0 - tol
                ib = tol < tb < 1.0 - tol
                if not ia and not ib:
                    continue  # a shared vertex: an ordinary joint
                if ia:
                    if m < rec_s.shape[0]:
                        rec_s[m] = A
                        rec_t[m] = ta
                    m += 1
                elif ta <= tol:
                    touch_s[A] = True
                else:
                    touch_e[A] = True
                if ib:
                    if m < rec_s.shape[0]:
                        rec_s[m] = B
                        rec_t[m] = tb
                    m += 1
                elif tb <= tol:
                    touch_s[B] = True
                else:
                    touch_e[B] = True
    return m


@njit(cache=True, nogil=True)
def _split(sx, sy, ex, ey, cell_mm, near_mm, use_runs):  # pragma: no cover - jit
    """:func:`split_at_crossings`, by runs (``use_runs``, when it pays) or by the grid."""
    n = sx.shape[0]
    tol = 1e-12
    touch_s = np.zeros(n, np.bool_)
    touch_e = np.zeros(n, np.bool_)
    rec_s = np.empty(64, np.int64)
    rec_t = np.empty(64)
    m = 0
    done = False
    g = max(near_mm, 0.0)
    # the segments' boxes grown by the near distance, and the section's box (one pass)
    bx0 = np.empty(n)
    bx1 = np.empty(n)
    by0 = np.empty(n)
    by1 = np.empty(n)
    xlo = ylo = np.inf
    xhi = yhi = -np.inf
    for k in range(n):
        lo = min(sx[k], ex[k])
        hi = max(sx[k], ex[k])
        bx0[k] = lo - g
        bx1[k] = hi + g
        xlo = min(xlo, lo)
        xhi = max(xhi, hi)
        lo = min(sy[k], ey[k])
        hi = max(sy[k], ey[k])
        by0[k] = lo - g
        by1[k] = hi + g
        ylo = min(ylo, lo)
        yhi = max(yhi, hi)
    if use_runs and n >= _RUNS_FROM:
        cap = n + 64
        while True:  # cuts are few: buffers for as many as segments, more if they overflow
            rec_s = np.empty(cap, np.int64)
            rec_t = np.empty(cap)
            done, m = _run_pairs(sx, sy, ex, ey, bx0, bx1, by0, by1, near_mm, tol, touch_s, touch_e, rec_s, rec_t)
            if m <= cap:
                break
            cap = m
    if n > 0 and not done:
        wx = xhi - xlo
        wy = yhi - ylo
        h = _split_cell_size(wx, wy, n, cell_mm)
        if n <= _FEW:
            h = max(h, 2.0 * max(wx, wy), 1e-9)  # few segments: one cell holds them all (every pair)
        xmin = xlo - h
        ymin = ylo - h
        xmax = xhi + h
        ymax = yhi + h
        ncx = int((xmax - xmin) / h) + 1
        ncy = int((ymax - ymin) / h) + 1
        # pieces are listed in every cell their box grown by the near distance touches: two
        # segments that cross, touch or come within it share a cell
        start, ent = _split_cells(sx, sy, ex, ey, xmin, ymin, h, ncx, ncy, g)
        cap = n + 64
        while True:  # cuts are few: buffers for as many as segments, more if they overflow
            rec_s = np.empty(cap, np.int64)
            rec_t = np.empty(cap)
            m = _grid_pairs(sx, sy, ex, ey, bx0, bx1, by0, by1, start, ent, near_mm, tol, touch_s, touch_e, rec_s, rec_t)
            if m <= cap:
                break
            cap = m
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
    js = np.empty(total, np.bool_)
    je = np.empty(total, np.bool_)
    q = 0
    for k in range(n):
        if cuts_n[k + 1] == cuts_n[k]:
            ox0[q] = sx[k]
            oy0[q] = sy[k]
            ox1[q] = ex[k]
            oy1[q] = ey[k]
            opar[q] = k
            js[q] = not touch_s[k]
            je[q] = not touch_e[k]
            q += 1
            continue
        cs = np.sort(ts[cuts_n[k] : cuts_n[k + 1]])
        prev = 0.0
        px = sx[k]
        py = sy[k]
        first = True
        for j in range(cs.shape[0] + 1):
            t = cs[j] if j < cs.shape[0] else 1.0
            if j < cs.shape[0] and t - prev <= tol:
                continue  # the same cut found twice (several cells, several crossers)
            last = j == cs.shape[0]
            if last:
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
            js[q] = first and not touch_s[k]
            je[q] = last and not touch_e[k]
            q += 1
            px = qx
            py = qy
            prev = t
            first = False
    return ox0[:q], oy0[:q], ox1[:q], oy1[:q], opar[:q], js[:q], je[:q]
