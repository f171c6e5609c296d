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

What the check runs per layer is two calls: :func:`layer_widths` (the crossing search, chains,
classification, then :func:`sample_widths`, which measures only the widths the findings need,
and the selections against the thresholds and the image) and :func:`layer_islands` (the
layer's material as runs per row by the slicer's own fill, :func:`fill_runs`, and islands by
union-find over the runs, :func:`island_runs`). :func:`boundary_samples` with
:func:`cast_rays` (every width), :func:`runs_to_image` and :func:`paint_chords` are the plain
references the tests compare them with.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..slicing._kernels import bucket_crossings

_PARALLEL_EPS = 1e-15
#: Segments shorter than this (mm) are rounding slivers (e.g. of an open mesh's gap closing):
#: they are not sampled, their direction being noise.
_MIN_LEN_MM = 1e-9
#: Up to this many segments the crossing search tests every pair (no grid to build).
_FEW = 256
#: Margin (mm) by which the strip a segment's rays sweep is grown before testing it clear.
_STRIP_MARGIN_MM = 1e-6
#: Runs of chained segments tested as a whole (:func:`_chain_runs`): at most this many
#: segments, each at least this long, every direction within acos(_RUN_COS) = 35 degrees of
#: the first one; runs of fewer than _RUN_MIN_SEGS segments are not tested as a whole.
_RUN_MAX = 48
_RUN_MIN_LEN_MM = 1e-5
_RUN_COS = 0.8191520442889918
_RUN_MIN_SEGS = 3
#: Sections with fewer segments than this are searched and measured without runs (finding
#: the chains costs more than it saves).
_RUNS_FROM = 16384
#: The crossing search's cells are at least this times the side of a square per segment
#: (:func:`_split_cell_size`).
_SPLIT_CELL = 0.75
#: :func:`simplify_section` replaces at most this many chained segments by one chord.
_SIMPLIFY_SPAN = 64
#: :func:`sample_widths_chained` lists the segments in cells this many times the ray grid's.
_GATHER_CELL = 1.0
#: ... and walks a strip's cells row by row when its bounding box holds more than this many.
_GATHER_BOX = 12
#: ... and only for segments with at least this many samples (shorter ones cast their rays;
#: 1: every segment gathers, segments being listed whole).
_GATHER_MIN = 1


# ---------------------------------------------------------------- bucketing helpers


@njit(cache=True, nogil=True, inline="always")
def _cell_index(v, n):  # pragma: no cover - jit
    """``floor(v)`` clamped to ``0 .. n - 1``, the float clamped before the int conversion (a
    float past int64, from a width of 1e19 mm, would wrap to any index); NaN gives 0."""
    if not v > 0.0:
        return 0
    if v >= n - 1:
        return n - 1
    return int(v)


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
def _clip_x(ax, ay, bx, by, y0, y1, lo, hi):  # pragma: no cover - jit
    """``lo, hi`` widened by the x extent of the edge from ``(ax, ay)`` to ``(bx, by)`` within
    the band ``y0 <= y <= y1`` (unchanged when the edge misses the band)."""
    if max(ay, by) < y0 or min(ay, by) > y1:
        return lo, hi
    if ay == by:
        return min(lo, ax, bx), max(hi, ax, bx)
    f0 = min(1.0, max(0.0, (y0 - ay) / (by - ay)))
    f1 = min(1.0, max(0.0, (y1 - ay) / (by - ay)))
    x0 = ax + f0 * (bx - ax)
    x1 = ax + f1 * (bx - ax)
    return min(lo, x0, x1), max(hi, x0, x1)


@njit(cache=True, nogil=True, inline="always")
def _rows(ay, by, y0, h, ncy, pad):  # pragma: no cover - jit
    """The first and last row of cells of side ``h`` (from ``y0``) that the y extent of a
    segment, grown by ``pad``, touches."""
    r0 = _cell_index((min(ay, by) - pad - y0) / h, ncy)
    r1 = _cell_index((max(ay, by) + pad - y0) / h, ncy)
    return r0, r1


@njit(cache=True, nogil=True, inline="always")
def _span(ax, ay, bx, by, gr, x0, y0, h, ncx, pad):  # pragma: no cover - jit
    """The first and last column of the cells in row ``gr`` (cells of side ``h`` from
    ``(x0, y0)``) that the segment from ``(ax, ay)`` to ``(bx, by)``, grown by ``pad``,
    touches; first > last when it misses the row."""
    yb = y0 + gr * h - pad
    lo, hi = _clip_x(ax, ay, bx, by, yb, yb + h + 2.0 * pad, np.inf, -np.inf)
    if lo > hi:
        return 0, -1
    c0 = _cell_index((lo - pad - x0) / h, ncx)
    c1 = _cell_index((hi + pad - x0) / h, ncx)
    return c0, c1


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
def _cell_size(w, h, n, cell_mm):  # pragma: no cover - jit
    """Cell side for ``n`` segments over a ``w`` x ``h`` mm box: ``cell_mm``, or larger so that
    there are not many more cells than segments (and never more than four million)."""
    c = max(cell_mm, 1e-9, math.sqrt(max(w * h, 0.0) / (4.0 * max(n, 1))))
    while (w / c + 1) * (h / c + 1) > 4e6:
        c *= 2.0
    return c


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
def split_at_crossings_grid(sx, sy, ex, ey, cell_mm, near_mm):  # pragma: no cover - jit
    """:func:`split_at_crossings` by the grid alone (every pair of segments sharing a cell),
    the reference for the search by runs."""
    return _split(sx, sy, ex, ey, cell_mm, near_mm, False)


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


@njit(cache=True, nogil=True)
def _find(parent, i):  # pragma: no cover - jit
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, nogil=True)
def _union(parent, a, b):  # pragma: no cover - jit
    """Join the sets of ``a`` and ``b``; the smaller root stays root."""
    a = _find(parent, a)
    b = _find(parent, b)
    if a != b:
        if a < b:
            parent[b] = a
        else:
            parent[a] = b


@njit(cache=True, nogil=True)
def chain_components(sx, sy, ex, ey, join_s, join_e, key_s, key_e):  # pragma: no cover - jit
    """Label the pieces joined end to start at ordinary joints (bit-identical points flagged
    joinable at both sides): ``(Q,) int64`` labels ``0..k-1`` and ``k``. Along such a chain
    nothing crosses or touches, so the fill rule's verdict is the same for all its pieces.
    ``key_s``, ``key_e`` are ``(Q,) int64`` hashes of the start and end points."""
    n = sx.shape[0]
    parent = np.arange(n)
    # hash table of start keys (open addressing), each slot heading a list of the starts
    # with that key
    bits = 1
    while (1 << bits) < 2 * n:
        bits += 1
    size = 1 << bits
    slot_key = np.empty(size, np.int64)
    slot_head = np.full(size, -1, np.int64)
    nxt = np.full(n, -1, np.int64)
    shift = np.uint64(64 - bits)
    mul = np.uint64(0x9E3779B97F4A7C15)
    mask = size - 1
    for i in range(n):
        k = key_s[i]
        h = np.int64((np.uint64(k) * mul) >> shift)
        while slot_head[h] >= 0 and slot_key[h] != k:
            h = (h + 1) & mask
        if slot_head[h] < 0:
            slot_key[h] = k
        nxt[i] = slot_head[h]
        slot_head[h] = i
    for i in range(n):
        if not join_e[i]:
            continue
        k = key_e[i]
        h = np.int64((np.uint64(k) * mul) >> shift)
        while slot_head[h] >= 0 and slot_key[h] != k:
            h = (h + 1) & mask
        o = slot_head[h]
        while o >= 0:
            if join_s[o] and sx[o] == ex[i] and sy[o] == ey[i]:
                a = _find(parent, i)
                b = _find(parent, o)
                if a != b:
                    parent[a] = b
            o = nxt[o]
    lab = np.empty(n, np.int64)
    root_lab = np.full(n, -1, np.int64)
    k = 0
    for i in range(n):
        r = _find(parent, i)
        if root_lab[r] < 0:
            root_lab[r] = k
            k += 1
        lab[i] = root_lab[r]
    return lab, k


@njit(cache=True, nogil=True, inline="always")
def _dda_start(ox, oy, dx, dy, xmin, ymin, h):  # pragma: no cover - jit
    """A ray's start in a grid of cells of side ``h`` from ``(xmin, ymin)``: its cell, its
    steps, the ray lengths to the next cell boundary in x and y and between boundaries."""
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
    return cx, cy, stx, sty, tmx, tmy, tdx, tdy


@njit(cache=True, nogil=True, inline="always")
def _hit(ox, oy, dx, dy, a0, b0, a1, b1, tmin, tmax):  # pragma: no cover - jit
    """Distance along unit ``(dx, dy)`` from ``(ox, oy)`` to the segment ``(a0, b0)``-
    ``(a1, b1)`` when it is in ``(tmin, tmax]``, else ``inf`` (parallel, missed or out of
    range). The one hit test of every ray kernel."""
    e0 = a1 - a0
    e1 = b1 - b0
    den = dx * e1 - dy * e0
    if abs(den) <= _PARALLEL_EPS * (abs(e0) + abs(e1)):
        return np.inf
    w0 = a0 - ox
    w1 = b0 - oy
    t = (w0 * e1 - w1 * e0) / den
    if t <= tmin or t > tmax:
        return np.inf
    sp = (w0 * dy - w1 * dx) / den
    if sp < 0.0 or sp > 1.0:
        return np.inf
    return t


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
def chain_successors(sx, sy, ex, ey, join_s, join_e, key_s, key_e):  # pragma: no cover - jit
    """The next piece along each chain: ``(Q,) int64``, the one piece whose start is this
    piece's end (bit-identical point, an ordinary joint at both sides), or -1 (a chain end, a
    cut, or a point where several pieces start or end). Keys as :func:`chain_components`."""
    n = sx.shape[0]
    succ = np.full(n, -1, np.int64)
    if n == 0:
        return succ
    bits = 1
    while (1 << bits) < 2 * n:
        bits += 1
    size = 1 << bits
    slot_key = np.empty(size, np.int64)
    slot_head = np.full(size, -1, np.int64)
    nxt = np.full(n, -1, np.int64)
    shift = np.uint64(64 - bits)
    mul = np.uint64(0x9E3779B97F4A7C15)
    mask = size - 1
    for i in range(n):
        k = key_s[i]
        h = np.int64((np.uint64(k) * mul) >> shift)
        while slot_head[h] >= 0 and slot_key[h] != k:
            h = (h + 1) & mask
        if slot_head[h] < 0:
            slot_key[h] = k
        nxt[i] = slot_head[h]
        slot_head[h] = i
    npred = np.zeros(n, np.int64)
    for i in range(n):
        if not join_e[i]:
            continue
        k = key_e[i]
        h = np.int64((np.uint64(k) * mul) >> shift)
        while slot_head[h] >= 0 and slot_key[h] != k:
            h = (h + 1) & mask
        o = slot_head[h]
        found = -1
        cnt = 0
        while o >= 0:
            if join_s[o] and sx[o] == ex[i] and sy[o] == ey[i]:
                found = o
                cnt += 1
            o = nxt[o]
        if cnt == 1 and found != i:
            succ[i] = found
            npred[found] += 1
    for i in range(n):
        if succ[i] >= 0 and npred[succ[i]] != 1:
            succ[i] = -1
    return succ


@njit(cache=True, nogil=True)
def _chain_runs(sx, sy, ex, ey, keep, succ, min_len):  # pragma: no cover - jit
    """Cut the chains (``succ`` from :func:`chain_successors`) of kept segments into runs of
    at most ``_RUN_MAX`` consecutive segments, each at least ``min_len`` mm long, whose
    directions all lie within ``_RUN_COS`` (35 degrees) of the run's first: any two differ by
    less than 90 degrees, so no normal ray from a point of the run meets the run again.

    Returns the run of every segment (-1: none), and the runs' members in chain order (CSR:
    ``ptr``, ``mem``)."""
    n = sx.shape[0]
    run = np.full(n, -1, np.int64)
    has_pred = np.zeros(n, np.bool_)
    chained = False
    for k in range(n):
        if succ[k] >= 0 and keep[k]:
            has_pred[succ[k]] = True
            chained = True
    ptr = np.zeros(n + 1, np.int64)
    mem = np.empty(n, np.int64)
    if not chained:  # no chain order: every kept segment is a run of its own, in index order
        nr = 0
        for k in range(n):
            if keep[k]:
                run[k] = nr
                mem[nr] = k
                nr += 1
                ptr[nr] = nr
        return run, ptr[: nr + 1], mem[:nr]
    nr = 0
    pos = 0
    for sweep in range(2):  # chain heads first, then what is left (closed chains)
        for k0 in range(n):
            if not keep[k0] or run[k0] >= 0 or (sweep == 0 and has_pred[k0]):
                continue
            k = k0
            while k >= 0 and keep[k] and run[k] < 0:
                L0 = max(math.hypot(ex[k] - sx[k], ey[k] - sy[k]), 1e-300)
                t0x = (ex[k] - sx[k]) / L0
                t0y = (ey[k] - sy[k]) / L0
                cnt = 0
                while k >= 0 and keep[k] and run[k] < 0 and cnt < _RUN_MAX:
                    L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
                    if L < min_len and cnt > 0:
                        break
                    if cnt > 0 and ((ex[k] - sx[k]) * t0x + (ey[k] - sy[k]) * t0y) < _RUN_COS * L:
                        break
                    run[k] = nr
                    mem[pos] = k
                    pos += 1
                    cnt += 1
                    k = succ[k]
                    if L < min_len:
                        break  # a tiny segment is a run of its own
                nr += 1
                ptr[nr] = pos
    return run, ptr[: nr + 1], mem[:pos]


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
    """The samples of :func:`boundary_samples` with the widths of :func:`cast_rays`, measuring
    only what the check uses: every width below ``need_wall`` (``need_gap``) exactly, and the
    smallest width up to ``max_mm``; any other width may come back as ``inf``.

    A ray looks no further than ``max(need, smallest width found so far)``. A segment with
    fewer than ``_GATHER_MIN`` samples casts each ray through the cells it crosses (a 2-D DDA,
    :func:`_walk`, as :func:`cast_rays`) and keeps its samples. The rays of a longer segment
    are parallel: per side, the segments that meet the strip its rays sweep (from the first
    to the last sample, up to the ray length when the segment comes, grown by
    ``_STRIP_MARGIN_MM``; tested exactly: its axes, then the segment's normal) are gathered
    once from the cells the strip covers (segments are listed whole, :func:`_seg_cells`;
    one listed in several of those cells is tested once). Each is tested against the rays
    whose sample lies within its extent along the segment, by the arithmetic of
    :func:`cast_rays` (on the segments' ends; every segment a ray hits within its length
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
    """:func:`chord_presence` on the image given as runs (:func:`fill_runs`, ``H`` x ``W``):
    the same pixel centres (those of the window in the bounding box of the chord's rectangle,
    where the others cannot be), material where a run covers the pixel."""
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


# ---------------------------------------------------------------- runs and islands


@njit(cache=True, nogil=True)
def fill_runs(ua, va, ub, vb, n_fib, n_samp, evenodd):  # pragma: no cover - jit
    """The slicer's fibre fill (:func:`rotoprint.slicing._kernels.fill_jit`, same crossings,
    same rule) as maximal runs instead of an image: ``(n_fib + 1,) int64`` CSR row starts and
    ``(R,) int64`` first and past-the-end columns of each run of material, rows in order and
    columns increasing. Work is proportional to the crossings, not to the image."""
    start, pos, sgn, jlo, jhi = bucket_crossings(ua, va, ub, vb, n_fib, n_samp)
    acc = pos.shape[0]
    rs = np.zeros(n_fib + 1, np.int64)
    r0 = np.empty(acc, np.int64)  # a row's runs are at most its crossings
    r1 = np.empty(acc, np.int64)
    nr = 0
    for j in range(jlo, jhi):
        rs[j] = nr
        a = start[j]
        b = start[j + 1]
        if a == b:
            continue
        w = 0
        prev = 0
        for k in range(a, b + 1):
            i = pos[k] if k < b else n_samp
            inside = (w & 1) != 0 if evenodd else w != 0
            if inside and i > prev:
                if nr > rs[j] and r1[nr - 1] == prev:
                    r1[nr - 1] = i  # touching spans make one run
                else:
                    r0[nr] = prev
                    r1[nr] = i
                    nr += 1
            if k < b:
                w += sgn[k]
                prev = i
    rs[jhi:] = nr
    return rs, r0[:nr].copy(), r1[:nr].copy()


@njit(cache=True, nogil=True)
def runs_to_image(rs, r0, r1, H, W):  # pragma: no cover - jit
    """``(H, W) uint8`` image (255 in the runs), for tests."""
    out = np.zeros((H, W), np.uint8)
    for j in range(H):
        for k in range(rs[j], rs[j + 1]):
            out[j, r0[k] : r1[k]] = 255
    return out


@njit(cache=True, nogil=True)
def island_runs(rs, r0, r1, ps, p0, p1):  # pragma: no cover - jit
    """Islands of a layer given as runs (``rs, r0, r1``, see :func:`fill_runs`) over the layer
    below (``ps, p0, p1``): the 8-connected regions of material none of whose pixels has
    material directly below.

    Returns, per island in raster order of its first pixel: ``(I,)`` pixel count, sums of the
    rows and of the columns of its pixels (float64), first and last row, first and last
    column; and ``(R,) int64`` the island (``0..I-1``) of every run, ``-1`` if supported.
    """
    H = rs.shape[0] - 1
    n = r0.shape[0]
    parent = np.arange(n)
    sup = np.zeros(n, np.bool_)
    # the rows that hold runs
    jlo = np.searchsorted(rs, 1) - 1 if n else 0
    jhi = np.searchsorted(rs, n) if n else 0
    for j in range(max(jlo, 0), jhi):
        # support: overlap with a run of the layer below in the same row (both sorted)
        q = ps[j]
        qe = ps[j + 1]
        for k in range(rs[j], rs[j + 1]):
            while q < qe and p1[q] <= r0[k]:
                q += 1
            if q < qe and p0[q] < r1[k]:
                sup[k] = True
        # 8-connection with the runs of the row above: columns within one
        if j == 0:
            continue
        q = rs[j - 1]
        qe = rs[j]
        for k in range(rs[j], rs[j + 1]):
            while q < qe and r1[q] < r0[k]:  # ends more than one column left of k
                q += 1
            t = q
            while t < qe and r0[t] <= r1[k]:
                _union(parent, k, t)
                t += 1
    root_sup = np.zeros(n, np.bool_)
    for k in range(n):
        if sup[k]:
            root_sup[_find(parent, k)] = True
    isl = np.full(n, -1, np.int64)
    root_isl = np.full(n, -1, np.int64)
    ni = 0
    # raster order of the first pixel: the first run of each component, runs in raster order
    for k in range(n):
        r = _find(parent, k)
        if root_sup[r]:
            continue
        if root_isl[r] < 0:
            root_isl[r] = ni
            ni += 1
        isl[k] = root_isl[r]
    cnt = np.zeros(ni, np.int64)
    srow = np.zeros(ni)
    scol = np.zeros(ni)
    rlo = np.full(ni, H, np.int64)
    rhi = np.full(ni, -1, np.int64)
    clo = np.full(ni, np.iinfo(np.int64).max, np.int64)
    chi = np.full(ni, -1, np.int64)
    for j in range(max(jlo, 0), jhi):
        for k in range(rs[j], rs[j + 1]):
            i = isl[k]
            if i < 0:
                continue
            L = r1[k] - r0[k]
            cnt[i] += L
            srow[i] += float(j) * L
            scol[i] += 0.5 * float(r0[k] + r1[k] - 1) * L
            rlo[i] = min(rlo[i], j)
            rhi[i] = max(rhi[i], j)
            clo[i] = min(clo[i], r0[k])
            chi[i] = max(chi[i], r1[k] - 1)
    return cnt, srow, scol, rlo, rhi, clo, chi, isl


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
    """:func:`group_chords` on the canvas ``buf`` (a flat ``int32`` buffer of zeros, used as
    ``Hc`` x ``Wc`` when it is that large, else a new canvas is made), which is left all
    zeros again: one buffer serves every call of a job, nothing is allocated or cleared in
    proportion to the canvas."""
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
    """Per region (``g`` from :func:`group_chords`): its narrowest chord (the first one of
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
def _keys(x, y):  # pragma: no cover - jit
    """``(n,) int64`` hashes of points from their exact bits (equal points, equal keys)."""
    return x.view(np.int64) * np.int64(-7046029254386353131) ^ y.view(np.int64)


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


@njit(cache=True, nogil=True)
def section_runs(start, end, m, n_fib, n_samp, evenodd):  # pragma: no cover - jit
    """:func:`fill_runs` of a section in model mm (``(S, 2)`` starts and ends) through the
    ``(2, 3)`` model-to-pixel affine ``m``, evaluated with the slicer's operations in the
    slicer's order (``(m00 x + m01 y) + m02``), so the crossings are the image's."""
    n = start.shape[0]
    ua = np.empty(n)
    va = np.empty(n)
    ub = np.empty(n)
    vb = np.empty(n)
    for k in range(n):
        ua[k] = (m[0, 0] * start[k, 0] + m[0, 1] * start[k, 1]) + m[0, 2]
        va[k] = (m[1, 0] * start[k, 0] + m[1, 1] * start[k, 1]) + m[1, 2]
        ub[k] = (m[0, 0] * end[k, 0] + m[0, 1] * end[k, 1]) + m[0, 2]
        vb[k] = (m[1, 0] * end[k, 0] + m[1, 1] * end[k, 1]) + m[1, 2]
    return fill_runs(ua, va, ub, vb, n_fib, n_samp, evenodd)


@njit(cache=True, nogil=True)
def _below(width, lim):  # pragma: no cover - jit
    n = 0
    for i in range(width.shape[0]):
        if width[i] < lim:
            n += 1
    out = np.empty(n, np.int64)
    n = 0
    for i in range(width.shape[0]):
        if width[i] < lim:
            out[n] = i
            n += 1
    return out


@njit(cache=True, nogil=True)
def _argmin_finite(width):  # pragma: no cover - jit
    """Index of the first smallest finite width, or -1 (as ``np.argmin`` on finite data)."""
    best = np.inf
    k = -1
    for i in range(width.shape[0]):
        if width[i] < best:
            best = width[i]
            k = i
    return k


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
def emit_groups(idx, width, sgn, bx, by, ux, uy, ln, m2p, grow, buf):  # pragma: no cover - jit
    """Everything a finding needs for the samples ``idx``: their chords ``(n, 4)`` in pixel
    indices, their regions (:func:`group_chords` on a canvas padded by ``grow + 1``), and
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


@njit(cache=True, nogil=True)
def _island_stats(rs, r0, r1, ps, p0, p1, below):  # pragma: no cover - jit
    """:func:`island_runs` when ``below`` (else no islands) as ``(7, I)`` per island (pixels,
    mean row, mean column, first and last row, first and last column) and the island of
    every run (-1: supported)."""
    if below and r0.shape[0] > 0:
        cnt, srow, scol, rlo, rhi, clo, chi, isl = island_runs(rs, r0, r1, ps, p0, p1)
    else:
        cnt = np.zeros(0, np.int64)
        srow = np.zeros(0)
        scol = np.zeros(0)
        rlo = rhi = clo = chi = cnt
        isl = np.full(r0.shape[0], -1, np.int64)
    ni = cnt.shape[0]
    st = np.empty((7, ni))
    for i in range(ni):
        st[0, i] = cnt[i]
        st[1, i] = srow[i] / cnt[i]
        st[2, i] = scol[i] / cnt[i]
        st[3, i] = rlo[i]
        st[4, i] = rhi[i]
        st[5, i] = clo[i]
        st[6, i] = chi[i]
    return st, isl


@njit(cache=True, nogil=True)
def layer_islands(start, end, m, n_fib, n_samp, evenodd, ps, p0, p1, below):  # pragma: no cover - jit
    """:func:`section_runs` of a layer and, when ``below`` (the runs ``ps, p0, p1`` of the
    layer below are given), its :func:`island_runs`, in one call: the runs, ``(7, I)`` per
    island (pixels, mean row, mean column, first and last row, first and last column) and the
    island of every run (-1: supported)."""
    rs, r0, r1 = section_runs(start, end, m, n_fib, n_samp, evenodd)
    st, isl = _island_stats(rs, r0, r1, ps, p0, p1, below)
    return rs, r0, r1, st, isl


@njit(cache=True, nogil=True)
def check_layer(start, end, wstart, wend, uv, H, W, evenodd, ps, p0, p1, below, cell_mm, near_mm, side_eps, spacing, max_mm, tmin, need_wall, need_gap, min_wall, min_gap, raster_lim, p2m, m2p, pmax):  # pragma: no cover - jit
    """The whole check of one layer in one call, without the image: the layer's material as
    runs (:func:`section_runs` of the section ``start, end``, equal to the slicer's image), the
    widths and selections of :func:`layer_widths` measured on ``wstart, wend`` (the section,
    or the section simplified by :func:`simplify_section`) with the raster tests on the runs
    (:func:`chord_presence_runs`), and the islands of :func:`layer_islands` (when ``below``).

    Returns ``S, iw, ig, thin, narrow, vanished, closed`` as :func:`layer_widths`, then the
    runs ``rs, r0, r1``, and ``st, isl`` as :func:`layer_islands`."""
    rs, r0, r1 = section_runs(start, end, uv, H, W, evenodd)
    if wstart.shape[0] > 0:
        bx, by, ux, uy, ln, wall, gap = measure_widths(wstart, wend, cell_mm, near_mm, evenodd, side_eps, spacing, max_mm, tmin, need_wall, need_gap)
    else:
        bx = by = ux = uy = ln = wall = gap = np.zeros(0)
    iw = _argmin_finite(wall)
    ig = _argmin_finite(gap)
    thin = _below(wall, min_wall)
    narrow = _below(gap, min_gap)
    vanished = _absent_runs(_below(wall, raster_lim), 1.0, bx, by, ux, uy, wall, rs, r0, r1, H, W, 255, p2m, m2p, pmax)
    closed = _absent_runs(_below(gap, raster_lim), -1.0, bx, by, ux, uy, gap, rs, r0, r1, H, W, 0, p2m, m2p, pmax)
    S = np.empty((7, bx.shape[0]))
    S[0] = bx
    S[1] = by
    S[2] = ux
    S[3] = uy
    S[4] = ln
    S[5] = wall
    S[6] = gap
    st, isl = _island_stats(rs, r0, r1, ps, p0, p1, below)
    return S, iw, ig, thin, narrow, vanished, closed, rs, r0, r1, st, isl


# ---------------------------------------------------------------- section simplification


@njit(cache=True, nogil=True)
def _greedy_emit(px, py, a, b, tol, out_s, out_e, m):  # pragma: no cover - jit
    """Write to ``out_s[m:], out_e[m:]`` the chords of the polyline ``px[a..b], py[a..b]``
    (``b`` included) that a greedy pass keeps, and return the new count: from each kept
    point, the farthest point (at most ``_SIMPLIFY_SPAN`` on) such that every point in between lies within ``tol`` of the chord
    to it and no farther from the kept point than the chord's end (so it projects onto the
    chord). The directions a chord may take form a wedge narrowed by each point passed (the
    tangents from the kept point to the point's ``tol`` disc): one pass, no trigonometry."""
    i = a
    while i < b:
        ax = px[i]
        ay = py[i]
        # wedge of allowed directions (lo: clockwise bound, hi: counter-clockwise), open at first
        lox = loy = hix = hiy = 0.0
        wedge = False
        dmax2 = 0.0
        tol2 = tol * tol
        j = i + 1
        c = i + 1
        vx = px[c] - ax
        vy = py[c] - ay
        d2 = vx * vx + vy * vy
        while True:
            # the chord i..c is valid; can it reach c + 1?
            if c >= b or c + 1 - i > _SIMPLIFY_SPAN:
                break
            # point c (at vx, vy from i, d2 = its distance squared) joins the points in
            # between: narrow the wedge by the tangents to its disc (the direction to it
            # turned by -/+ asin(tol / d), scaled by d)
            if d2 > dmax2:
                dmax2 = d2
            if d2 > tol2:
                cs = math.sqrt(d2 - tol2)
                lx = cs * vx + tol * vy
                ly = -tol * vx + cs * vy
                hx = cs * vx - tol * vy
                hy = tol * vx + cs * vy
                if not wedge:
                    lox, loy, hix, hiy = lx, ly, hx, hy
                    wedge = True
                else:
                    if lox * ly - loy * lx > 0.0:  # the new bound is counter-clockwise of lo
                        lox, loy = lx, ly
                    if hix * hy - hiy * hx < 0.0:  # the new bound is clockwise of hi
                        hix, hiy = hx, hy
                    if lox * hiy - loy * hix < 0.0:
                        break  # empty wedge: no chord past c
            qx = px[c + 1] - ax
            qy = py[c + 1] - ay
            q2 = qx * qx + qy * qy
            if q2 < dmax2:
                break
            if wedge and (lox * qy - loy * qx < 0.0 or qx * hiy - qy * hix < 0.0):
                break
            c += 1
            j = c
            vx = qx
            vy = qy
            d2 = q2
        out_s[m, 0] = px[i]
        out_s[m, 1] = py[i]
        out_e[m, 0] = px[j]
        out_e[m, 1] = py[j]
        m += 1
        i = j
    return m


@njit(cache=True, nogil=True)
def simplify_section(start, end, start_edge, end_edge, tol, pos):  # pragma: no cover - jit
    """The section ``(S, 2)`` starts and ends (model mm) with its chains simplified: chained
    segments (one ends on the mesh edge the next starts on, bit-identical joint, neither edge
    shared by another segment) are replaced by chords along which every dropped joint lies
    within ``tol`` mm (and between the chord's ends). Joints are never moved, chains are never
    joined to others, a closed chain keeps at least three chords (a loop smaller than the
    tolerance is kept whole rather than flattened to nothing), and segments that do not chain
    (gap closing, non-manifold edges) are kept as they are, so every point of the result lies within ``tol`` of the section and
    every point of the section within ``tol`` of the result.

    ``pos`` is an ``int32`` buffer of entries all -1, and is left so (one buffer serves every
    layer of a job); it needs ``max(edge) + 1`` entries.

    Returns ``(S', 2)`` starts and ends, ``S' <= S``, chain by chain in order, and 0; or, when
    ``pos`` is too short, two empty arrays and the length it needs.
    """
    n = start.shape[0]
    top = -1
    for i in range(n):
        top = max(top, start_edge[i], end_edge[i])
    if top >= pos.shape[0]:
        return np.empty((0, 2)), np.empty((0, 2)), top + 1
    succ = np.full(n, -1, np.int32)
    npred = np.zeros(n, np.int32)
    dup = False
    for i in range(n):
        e = start_edge[i]
        if e >= 0:
            if pos[e] != -1:
                pos[e] = -2  # two segments start on this edge: neither is chained to
            else:
                pos[e] = i
    for i in range(n):
        e = end_edge[i]
        if e >= 0:
            j = pos[e]
            if j >= 0 and j != i and start[j, 0] == end[i, 0] and start[j, 1] == end[i, 1]:
                succ[i] = j
                npred[j] += 1
    for i in range(n):
        e = start_edge[i]
        if e >= 0:
            pos[e] = -1
    for i in range(n):
        j = succ[i]
        if j >= 0 and npred[j] > 1:
            dup = True
    if dup:  # two segments end where one starts: break both
        for i in range(n):
            j = succ[i]
            if j >= 0 and npred[j] > 1:
                succ[i] = -1
        for j in range(n):
            if npred[j] > 1:
                npred[j] = 0
    # walk the chains: open ones from their heads, then the cycles
    px = np.empty(n + 1)
    py = np.empty(n + 1)
    seen = np.zeros(n, np.bool_)
    out_s = np.empty((n, 2))
    out_e = np.empty((n, 2))
    m = 0
    for phase in range(2):
        for h in range(n):
            if seen[h] or (phase == 0 and npred[h] > 0):
                continue
            # points of the chain from h
            k = 0
            i = h
            while True:
                seen[i] = True
                px[k] = start[i, 0]
                py[k] = start[i, 1]
                k += 1
                j = succ[i]
                if j < 0 or j == h:  # an open chain's end, or back to a cycle's start
                    px[k] = end[i, 0]
                    py[k] = end[i, 1]
                    break
                i = j
            # k segments, points 0..k (a cycle's last point is its first: it is kept)
            m0 = m
            m = _greedy_emit(px, py, 0, k, tol, out_s, out_e, m)
            if j == h and m - m0 < 3 and k >= 3:
                # a loop within the tolerance of a line would become a sliver with no inside
                # (out and back): it is kept as it is
                m = m0
                for q in range(k):
                    out_s[m, 0] = px[q]
                    out_s[m, 1] = py[q]
                    out_e[m, 0] = px[q + 1]
                    out_e[m, 1] = py[q + 1]
                    m += 1
    return out_s[:m], out_e[:m], 0
