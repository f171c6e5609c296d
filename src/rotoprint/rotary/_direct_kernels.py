"""Circular-fibre fill for the direct rotary slicer: the numba kernel and its numpy reference.

Inputs are in the part's *local* frame (mm): the platform frame rotated so that the part's
centre line is +X; the whole cross-section lies at ``x > 0``. A nozzle's track is the circle
``x^2 + y^2 = r^2``; the drop of firing ``i`` lands at local angle ``psi0 - direction * i * dphi``
(``psi0 = phi_k - angle``, unwrapped, as :func:`rotoprint.rotary.exact.firing_range` uses).

Rules (exact, no tolerance decides a case):

- *Radial half-open rule*: a point ``p`` counts as outside the track when ``|p|^2 >= r^2``
  (as if the track were shrunk by an infinitesimal amount). A segment crosses the track at
  every change of that predicate along it: once when its end points differ, twice when both
  are outside and the segment dips inside (``|p|`` is convex along a segment), never when
  both are inside. Shared end points of two segments are bit-identical, so a vertex on a track
  is counted consistently by the two segments meeting there.
- *Winding along the arc*: since the part lies in ``x > 0``, the winding number on the ray at
  angle ``pi`` is zero, so the winding number of a drop is the signed count of crossings on the
  arc between that ray and the drop. In firing order it is a prefix sum: a crossing at the
  continuous firing index ``u_c`` counts for every firing ``i >= u_c`` (a drop exactly on the
  boundary takes the state just after it in firing order), with sign ``-direction`` for a
  crossing that leaves the circle and ``+direction`` for one that enters it.
- Crossings before the image count for every firing, those after it for none.

Writing (the jit kernel): a scanline sweep of the spans' ends in firing order keeps a row state by
image column, and each row holding ink is written whole from it (contiguous stores); the rows
without ink and the columns beside the ink are zeroed by the same sweep, so the image is
allocated uninitialised and stored once.

Optional thinning (density equalisation): firing ``i`` of track ``m`` is kept when
``floor((i + 1) * frac[m] + offset[m]) > floor(i * frac[m] + offset[m])`` (an ordered, even
pattern on the absolute firing index: exactly ``frac`` of the firings over any run).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._thin_kernels import thin_floors_jit

__all__ = ["direct_fill_jit", "direct_fill_numpy", "KERNELS", "QMIN_WIDEN"]

#: Relative widening of a segment's smallest squared radius when picking candidate tracks (the
#: exact predicate then decides; this only has to keep every track that may cross).
QMIN_WIDEN = 1e-9
#: Firing rows per tile of the direct fill's writes (measured: 1440 dpi, 0 deg, the sphere's layer).
FILL_TILE = 128


@njit(cache=True, nogil=True, inline="always")
def _seg_setup(x0, y0, x1, y1):  # pragma: no cover - jit
    dx = x1 - x0
    dy = y1 - y0
    A = dx * dx + dy * dy
    B = x0 * dx + y0 * dy
    qa = x0 * x0 + y0 * y0
    qb = x1 * x1 + y1 * y1
    if B < 0.0 and B + A > 0.0:
        cr = x0 * dy - y0 * dx
        qmin = cr * cr / A
    else:
        qmin = qa if qa < qb else qb
    qmax = qa if qa > qb else qb
    return dx, dy, A, B, qa, qb, qmin, qmax


@njit(cache=True, nogil=True, inline="always")
def _firing_pos(x0, y0, dx, dy, t, psi0, dphi, direction, i0, n_f):  # pragma: no cover - jit
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    px = x0 + t * dx
    py = y0 + t * dy
    psi = math.atan2(py, px)
    u = direction * (psi0 - psi) / dphi - i0
    if u <= 0.0:
        return 0
    if u >= n_f:
        return n_f
    return int(math.ceil(u))


@njit(cache=True, nogil=True, inline="always")
def _zero_rows(out, r0, r1, c0, c1):  # pragma: no cover - jit
    """``out[r0:r1]`` zeroed outside columns ``c0 .. c1 - 1`` (whole rows when ``c0 >= c1``)."""
    n_c = out.shape[1]
    if c0 >= c1:
        out[r0:r1, :] = 0
        return
    if c0 > 0:
        out[r0:r1, :c0] = 0
    if c1 < n_c:
        out[r0:r1, c1:] = 0


@njit(cache=True, nogil=True, inline="always")
def _copy_rows(out, r0, r1, c0, c1, state):  # pragma: no cover - jit
    for r in range(r0, r1):
        row = out[r, c0:c1]
        src = state[c0:c1]
        for c in range(c1 - c0):
            row[c] = src[c]


@njit(cache=True, nogil=True, inline="always")
def _thin_rows(out, r0, r1, i0, c0, c1, fc, oc, state, level):  # pragma: no cover - jit
    f = fc[c0:c1]
    o = oc[c0:c1]
    s = state[c0:c1]
    # the state is 0 or ``level``, so ``level if keep else s`` is ``s | keep * level``: in that form the
    # loop vectorises on AVX2 too (the select did only with AVX-512's masks: 14 x slower on an AVX2 EPYC)
    for r in range(r0, r1):
        i = float(r + i0)
        row = out[r, c0:c1]
        for c in range(c1 - c0):
            # kept_jit's test with one floor: for a real a and an integer k, k > floor(a) exactly when k > a
            row[c] = s[c] | (np.uint8(np.floor((i + 1.0) * f[c] + o[c]) > i * f[c] + o[c]) * level)


#: The fixed-point rows (:func:`_thin_rows_fixed`) are exact for firing indices below this in magnitude
#: (the float64 rule's rounding stays within one 2^-32 unit there); beyond it the float rows are used.
FIXED_MAX_FIRING = 1 << 20
_TWO32 = 4294967296.0


@njit(cache=True, nogil=True, inline="always")
def _fixed_track(f, o):  # pragma: no cover - jit
    """``(F, P, H)`` uint32 of a thinned track (``0 < f < 1``, ``0 <= o < 1``): ``F = round(f 2^32)``,
    ``H = F >> 1`` and ``P = O + F - H`` (mod 2^32, ``O = round(o 2^32)``), so that firing ``i``'s
    ``R = i F + P`` (mod 2^32, as int32) is ``2^32 frac((i + 1) f + o) - H``: kept when ``|R| < H``."""
    F = min(int(math.floor(f * _TWO32 + 0.5)), 4294967295)
    O = int(math.floor(o * _TWO32 + 0.5)) & 0xFFFFFFFF
    H = F >> 1
    return np.uint32(F), np.uint32((O + F - H) & 0xFFFFFFFF), np.uint32(H)


@njit(cache=True, nogil=True, inline="always")
def _thin_rows_fixed(out, r0, r1, i0, c0, c1, fc, oc, Fc, Pc, Hc, state, level):  # pragma: no cover - jit
    """:func:`_thin_rows`' bytes (the same float64 rule), decided in 32-bit fixed point, 8 columns a vector
    on AVX2 (against 4 float64): firing ``i`` of a column is kept when ``frac((i + 1) f + o) < f``, which
    is the rule's ``floor((i + 1) f + o) > floor(i f + o)``. The fixed phase ``Q = (i + 1) F + O``
    (mod 2^32) is within ``|i + 1| / 2 + 1/2`` units (2^-32) of the exact one (``|i + 1| + 1/2`` where
    ``F`` is clamped, ``f`` within 2^-33 of 1) and the rule's float64 values within 3/4 of a unit of
    theirs (``|i| < FIXED_MAX_FIRING``); the fixed test keeps ``Q`` in ``(0, 2 H)``, the kept interval
    ``[0, F)`` to a unit at each end. So the two decide alike unless ``Q`` lies within ``|i| + 8`` units
    of an end of it (the worst case needs about ``|i| + 5``; helper-57 measured at most ``|i| + 1``); each
    row tracks the least such distance over its columns and, when one is that near, decides those
    columns by the float64 rule.
    Columns without a thinned track hold ``F = H = 0``, ``P = 2^31``: never kept, never near."""
    f = fc[c0:c1]
    o = oc[c0:c1]
    F = Fc[c0:c1]
    P = Pc[c0:c1]
    H = Hc[c0:c1]
    s = state[c0:c1]
    n = c1 - c0
    for r in range(r0, r1):
        i = r + i0
        iu = np.uint32(i & 0xFFFFFFFF)
        d = np.uint32(abs(i) + 8)
        row = out[r, c0:c1]
        near = np.uint32(0xFFFFFFFF)
        for c in range(n):
            a = np.uint32(abs(np.int32(np.uint32(iu * F[c]) + P[c])))
            row[c] = s[c] | (np.uint8(a < H[c]) * level)
            near = min(near, np.uint32(abs(np.int32(a - H[c]))))
        if near <= d:
            fi = float(i)
            for c in range(n):
                a = np.uint32(abs(np.int32(np.uint32(iu * F[c]) + P[c])))
                if np.uint32(abs(np.int32(a - H[c]))) <= d:
                    row[c] = s[c] | (np.uint8(np.floor((fi + 1.0) * f[c] + o[c]) > fi * f[c] + o[c]) * level)


@njit(cache=True, nogil=True)
def _scanline_fill(sp_lo, sp_hi, sp_end, start, cols, frac, offs, thinned, n_ev, i0, n_f, level, out):  # pragma: no cover - jit
    """Write the spans of the tracks kept whole (``frac >= 1``) and, when ``thinned``, of the thinned
    ones (``0 < frac < 1``, at most one per image column) in firing order: span ends are events that
    update a row state by image column (inside counts, the byte of the whole tracks, the share and
    phase of the thinned track inside); each row holding ink is written whole from the state, a
    thinned column by thin_print's rule (``kept_jit``'s float64 expression, the same floors).
    Every byte of ``out`` is written (0 outside the rows' ink), so ``out`` may come uninitialised:
    the image is stored once rather than zeroed whole and then written (6 % of a 1440 dpi pass)."""
    n_tr = cols.shape[0]
    n_c = out.shape[1]
    ev_row = np.empty(n_ev, np.int64)
    ev_trk = np.empty(n_ev, np.int64)
    ev_step = np.empty(n_ev, np.int64)
    e = 0
    for m in range(n_tr):
        f = frac[m]
        if f < 1.0 and not (thinned and f > 0.0):
            continue
        for z in range(start[m] + m, sp_end[m]):
            ev_row[e] = sp_lo[z]
            ev_trk[e] = m
            ev_step[e] = 1
            ev_row[e + 1] = sp_hi[z]
            ev_trk[e + 1] = m
            ev_step[e + 1] = -1
            e += 2
    order = np.argsort(ev_row, kind="mergesort")
    cnt = np.zeros(n_c, np.int64)
    state = np.zeros(n_c, np.uint8)
    fc = np.zeros(n_c, np.float64)
    oc = np.zeros(n_c, np.float64)
    # the thinned tracks' fixed-point terms (_thin_rows_fixed), when every firing index and phase allows them
    fixed = thinned and abs(i0) < FIXED_MAX_FIRING and abs(i0 + n_f) < FIXED_MAX_FIRING
    tF = np.zeros(n_tr, np.uint32)
    tP = np.zeros(n_tr, np.uint32)
    tH = np.zeros(n_tr, np.uint32)
    if fixed:
        for m in range(n_tr):
            f = frac[m]
            if 0.0 < f < 1.0:
                if not 0.0 <= offs[m] < 1.0:
                    fixed = False
                    break
                tF[m], tP[m], tH[m] = _fixed_track(f, offs[m])
    Fc = np.zeros(n_c, np.uint32)
    Pc = np.full(n_c, np.uint32(0x80000000))
    Hc = np.zeros(n_c, np.uint32)
    n_in = 0  # columns holding a whole track
    n_thin = 0  # columns holding a thinned track
    lo = n_c  # the rows are written on columns lo .. hi - 1, which hold every column inside (the rest stay 0)
    hi = 0
    shrink = False
    e = 0
    row = ev_row[order[0]]
    _zero_rows(out, 0, min(row, n_f), 0, 0)
    while row < n_f:
        while e < n_ev and ev_row[order[e]] == row:
            k = order[e]
            m = ev_trk[k]
            c = cols[m]
            if frac[m] >= 1.0:
                was = cnt[c] > 0
                cnt[c] += ev_step[k]
                now = cnt[c] > 0
                if now != was:
                    state[c] = level if now else 0
                    n_in += 1 if now else -1
            elif ev_step[k] > 0:  # a thinned column's track is the only thinned one there: inside or not
                fc[c] = frac[m]
                oc[c] = offs[m]
                Fc[c] = tF[m]
                Pc[c] = tP[m]
                Hc[c] = tH[m]
                n_thin += 1
            else:
                fc[c] = 0.0
                oc[c] = 0.0
                Fc[c] = 0
                Pc[c] = 0x80000000
                Hc[c] = 0
                n_thin -= 1
            if ev_step[k] > 0:
                lo = min(lo, c)
                hi = max(hi, c + 1)
            else:
                shrink = True
            e += 1
        nxt = ev_row[order[e]] if e < n_ev else n_f
        if nxt > n_f:
            nxt = n_f
        if shrink:
            while lo < hi and cnt[lo] == 0 and fc[lo] == 0.0:
                lo += 1
            while hi > lo and cnt[hi - 1] == 0 and fc[hi - 1] == 0.0:
                hi -= 1
            shrink = False
        if n_thin and fixed:
            _thin_rows_fixed(out, row, nxt, i0, lo, hi, fc, oc, Fc, Pc, Hc, state, level)
            _zero_rows(out, row, nxt, lo, hi)
        elif n_thin:
            _thin_rows(out, row, nxt, i0, lo, hi, fc, oc, state, level)
            _zero_rows(out, row, nxt, lo, hi)
        elif n_in:
            _copy_rows(out, row, nxt, lo, hi, state)
            _zero_rows(out, row, nxt, lo, hi)
        elif nxt > row:
            _zero_rows(out, row, nxt, 0, 0)
        row = nxt


@njit(cache=True, nogil=True, inline="always")
def _track_spans(sx0, sy0, sx1, sy1, r2, psi0, dphi, direction, i0, n_f, evenodd):  # pragma: no cover - jit
    """The inside spans of every track (passes 1-3 of the fill): track ``m``'s spans are
    ``sp_lo[z] .. sp_hi[z] - 1`` (firing rows, sorted, disjoint) for ``z`` in ``start[m] + m ..
    sp_end[m] - 1``. ``r2`` ascending; the rules of the module doc."""
    n_seg = sx0.shape[0]
    n_tr = r2.shape[0]
    lo_idx = np.empty(n_seg, np.int64)
    hi_idx = np.empty(n_seg, np.int64)
    per = np.zeros(n_tr + 1, np.int64)
    # pass 1: candidate tracks per segment (2 crossings at most each), by a difference array
    for s in range(n_seg):
        dx, dy, A, B, qa, qb, qmin, qmax = _seg_setup(sx0[s], sy0[s], sx1[s], sy1[s])
        if A == 0.0:
            lo_idx[s] = 0
            hi_idx[s] = 0
            continue
        j0 = np.searchsorted(r2, qmin * (1.0 - QMIN_WIDEN), side="right")
        j1 = np.searchsorted(r2, qmax, side="right")
        if j1 < j0:
            j1 = j0
        lo_idx[s] = j0
        hi_idx[s] = j1
        if j0 < j1:
            per[j0] += 2
            per[j1] -= 2
    start = np.empty(n_tr + 1, np.int64)
    acc = 0
    run = 0
    for m in range(n_tr):
        run += per[m]
        start[m] = acc
        acc += run
    start[n_tr] = acc
    pos = np.empty(acc, np.int64)
    sgn = np.empty(acc, np.int8)
    cur = start[:n_tr].copy()
    leave = -direction
    enter = direction
    # pass 2: the crossings, as the first firing they count for, and their signs
    for s in range(n_seg):
        j0 = lo_idx[s]
        j1 = hi_idx[s]
        if j0 >= j1:
            continue
        x0 = sx0[s]
        y0 = sy0[s]
        dx, dy, A, B, qa, qb, qmin, qmax = _seg_setup(x0, y0, sx1[s], sy1[s])
        dip = B < 0.0 and B + A > 0.0
        for m in range(j0, j1):
            rr = r2[m]
            ia = qa < rr
            ib = qb < rr
            if ia and ib:
                continue
            if not ia and not ib and not (dip and qmin < rr):
                continue
            C = qa - rr
            D = B * B - A * C
            if D < 0.0:
                D = 0.0
            sq = math.sqrt(D)
            k = cur[m]
            if not ib:  # an exit: the larger root
                tp = (-B + sq) / A if B <= 0.0 else C / (-B - sq)
                pos[k] = _firing_pos(x0, y0, dx, dy, tp, psi0[m], dphi, direction, i0, n_f)
                sgn[k] = leave
                k += 1
            if not ia:  # an entry: the smaller root
                tm = (-B - sq) / A if B >= 0.0 else C / (-B + sq)
                pos[k] = _firing_pos(x0, y0, dx, dy, tm, psi0[m], dphi, direction, i0, n_f)
                sgn[k] = enter
                k += 1
            cur[m] = k
    # pass 3: per track, sort its crossings and list its inside spans (at most one more than its crossings)
    sp_lo = np.empty(acc + n_tr, np.int64)
    sp_hi = np.empty(acc + n_tr, np.int64)
    sp_end = np.empty(n_tr, np.int64)
    for m in range(n_tr):
        a = start[m]
        b = cur[m]
        z0 = a + m
        sp_end[m] = z0
        if a == b:
            continue
        for q in range(a + 1, b):  # insertion sort: tracks hold few crossings
            p = pos[q]
            g = sgn[q]
            z = q - 1
            while z >= a and pos[z] > p:
                pos[z + 1] = pos[z]
                sgn[z + 1] = sgn[z]
                z -= 1
            pos[z + 1] = p
            sgn[z + 1] = g
        w = 0
        prev = 0
        ns = z0
        for q in range(a, b + 1):
            i = pos[q] if q < b else n_f
            inside = (w & 1) != 0 if evenodd else w != 0
            if inside and i > prev:
                sp_lo[ns] = prev
                sp_hi[ns] = i
                ns += 1
            if q < b:
                w += sgn[q]
                prev = i
        sp_end[m] = ns
    return sp_lo, sp_hi, sp_end, start


@njit(cache=True, nogil=True, inline="always")
def _isect(alo, ahi, na, blo, bhi, nb, olo, ohi):  # pragma: no cover - jit
    """Intersection of two sorted disjoint half-open span lists into ``olo, ohi``; returns its length."""
    i = 0
    j = 0
    n = 0
    while i < na and j < nb:
        lo = alo[i] if alo[i] > blo[j] else blo[j]
        hi = ahi[i] if ahi[i] < bhi[j] else bhi[j]
        if hi > lo:
            olo[n] = lo
            ohi[n] = hi
            n += 1
        if ahi[i] < bhi[j]:
            i += 1
        else:
            j += 1
    return n


@njit(cache=True, nogil=True, inline="always")
def _diff(alo, ahi, na, blo, bhi, nb, olo, ohi):  # pragma: no cover - jit
    """``a`` minus ``b`` (sorted disjoint half-open span lists) into ``olo, ohi``; returns its length."""
    n = 0
    j = 0
    for i in range(na):
        lo = alo[i]
        hi = ahi[i]
        while j < nb and bhi[j] <= lo:
            j += 1
        q = j
        while lo < hi and q < nb and blo[q] < hi:
            if blo[q] > lo:
                olo[n] = lo
                ohi[n] = blo[q]
                n += 1
            if bhi[q] > lo:
                lo = bhi[q]
            q += 1
        if hi > lo:
            olo[n] = lo
            ohi[n] = hi
            n += 1
    return n


@njit(cache=True, nogil=True, inline="always")
def _region(t, lo, hi, end, start, c_lo, c_hi, c_end, c_start, n_cut, olo, ohi, tlo, thi):  # pragma: no cover - jit
    """Track ``t``'s inside spans minus every cut's, into ``olo, ohi``; returns their number."""
    z0 = start[t] + t
    n = end[t] - z0
    for z in range(n):
        olo[z] = lo[z0 + z]
        ohi[z] = hi[z0 + z]
    for g in range(n_cut):
        if n == 0:
            break
        w0 = c_start[g, t] + t
        nb = c_end[g, t] - w0
        if nb == 0:
            continue
        n = _diff(olo, ohi, n, c_lo[g, w0:], c_hi[g, w0:], nb, tlo, thi)
        for z in range(n):
            olo[z] = tlo[z]
            ohi[z] = thi[z]
    return n


@njit(cache=True, nogil=True, inline="always")
def _restore_edges(sp_lo, sp_hi, sp_end, start, sx0, cx0, cy0, cx1, cy1, cut_at, r2, psi0, cols, edge_m, edge_v, gain, phase,
                   dphi, direction, i0, n_f, evenodd, level, out):  # pragma: no cover - jit
    """Pass 6, the edge restore (:mod:`._direct_edge`): thinned track ``edge_m[t]``'s firings inside
    the region (its spans minus every cut's) where one of its virtual tracks ``edge_v[t]`` is not,
    written where the restore pattern (``gain[t]``, ``phase[t]``) fires. Returns the drops written."""
    n_t = edge_m.shape[0]
    n_s = edge_v.shape[1]
    n_tr = r2.shape[0]
    n_cut = cut_at.shape[0] - 1
    cap = 1
    for g in range(n_cut):  # the cuts' spans on every track ((cut, span) arrays; sizes first: cuts are few and small)
        a = cut_at[g]
        b = cut_at[g + 1]
        l1, h1, e1, s1 = _track_spans(cx0[a:b], cy0[a:b], cx1[a:b], cy1[a:b], r2, psi0, dphi, direction, i0, n_f, evenodd)
        cap = max(cap, l1.shape[0])
    c_lo = np.zeros((n_cut, cap), np.int64)
    c_hi = np.zeros((n_cut, cap), np.int64)
    c_end = np.zeros((n_cut, n_tr), np.int64)
    c_start = np.zeros((n_cut, n_tr), np.int64)
    for g in range(n_cut):
        a = cut_at[g]
        b = cut_at[g + 1]
        l1, h1, e1, s1 = _track_spans(cx0[a:b], cy0[a:b], cx1[a:b], cy1[a:b], r2, psi0, dphi, direction, i0, n_f, evenodd)
        c_lo[g, :l1.shape[0]] = l1
        c_hi[g, :l1.shape[0]] = h1
        c_end[g] = e1
        c_start[g] = s1[:n_tr]
    # work lists: a track's spans number at most its crossings + 1, a difference adds one per cut span
    w = 2 * (sp_lo.shape[0] + n_cut * cap) + 4
    a_lo = np.empty(w, np.int64)
    a_hi = np.empty(w, np.int64)
    b_lo = np.empty(w, np.int64)
    b_hi = np.empty(w, np.int64)
    t_lo = np.empty(w, np.int64)
    t_hi = np.empty(w, np.int64)
    u_lo = np.empty(w, np.int64)
    u_hi = np.empty(w, np.int64)
    gf = np.empty(FILL_TILE + 1, np.float64)
    restored = 0
    for t in range(n_t):
        g_t = gain[t]
        if not g_t > 0.0:
            continue
        m = edge_m[t]
        n_a = _region(m, sp_lo, sp_hi, sp_end, start, c_lo, c_hi, c_end, c_start, n_cut, a_lo, a_hi, t_lo, t_hi)
        if n_a == 0:
            continue
        # the region spans of m inside every virtual track's region
        for z in range(n_a):
            u_lo[z] = a_lo[z]
            u_hi[z] = a_hi[z]
        n_u = n_a
        for s in range(n_s):
            if n_u == 0:
                break
            n_b = _region(edge_v[t, s], sp_lo, sp_hi, sp_end, start, c_lo, c_hi, c_end, c_start, n_cut, b_lo, b_hi, t_lo, t_hi)
            n_u = _isect(u_lo, u_hi, n_u, b_lo, b_hi, n_b, t_lo, t_hi)
            for z in range(n_u):
                u_lo[z] = t_lo[z]
                u_hi[z] = t_hi[z]
        # the zone: the region spans of m minus those; the restore pattern on it, one floor per firing
        n_z = _diff(a_lo, a_hi, n_a, u_lo, u_hi, n_u, b_lo, b_hi)
        col = cols[m]
        o = phase[t]
        for z in range(n_z):
            r = b_lo[z]
            while r < b_hi[z]:
                n = min(FILL_TILE, b_hi[z] - r)
                thin_floors_jit(gf, float(r + i0), n, g_t, o)
                for q in range(n):
                    if gf[q + 1] > gf[q] and out[r + q, col] != level:
                        out[r + q, col] = level
                        restored += 1
                r += n
    return restored


@njit(cache=True, nogil=True)
def _direct_fill(sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs, dphi, direction, i0, n_f, evenodd, level, out,
                 cx0, cy0, cx1, cy1, cut_at, edge_m, edge_v, gain, phase):  # pragma: no cover - jit
    n_tr = r2.shape[0]
    sp_lo, sp_hi, sp_end, start = _track_spans(sx0, sy0, sx1, sy1, r2, psi0, dphi, direction, i0, n_f, evenodd)
    # pass 4: a scanline sweep (_scanline_fill) of the tracks kept whole (frac >= 1) and the thinned
    # ones (0 < frac < 1) unless two thinned tracks share an image column (then pass 5 writes those):
    # each row that holds ink is written whole from a row state (byte stores down columns cost 2-4 x more)
    per_col = np.zeros(out.shape[1], np.int64)
    thinned = True
    for m in range(n_tr):
        if 0.0 < frac[m] < 1.0:
            per_col[cols[m]] += 1
            if per_col[cols[m]] > 1:
                thinned = False
    n_ev = 0
    for m in range(n_tr):
        if frac[m] >= 1.0 or (thinned and frac[m] > 0.0):
            n_ev += 2 * (sp_end[m] - start[m] - m)
    if n_ev:  # it writes every byte of out (0 where no ink)
        _scanline_fill(sp_lo, sp_hi, sp_end, start, cols, frac, offs, thinned, n_ev, i0, n_f, level, out)
    else:
        out[:] = 0
    # pass 5: the thinned tracks' spans tile by tile of FILL_TILE firing rows, so that the (tile, N) block
    # of the image stays in cache while every track writes its column piece (a whole-column walk misses it each row)
    cursor = np.empty(n_tr, np.int64)
    for m in range(n_tr):
        cursor[m] = start[m] + m
    gf = np.empty(FILL_TILE + 1, np.float64)
    for r0 in range(0, n_f if not thinned else 0, FILL_TILE):  # (with ``thinned`` pass 4 wrote every thinned track)
        r1 = min(r0 + FILL_TILE, n_f)
        for m in range(n_tr):
            z = cursor[m]
            end = sp_end[m]
            if z == end:
                continue
            f = frac[m]
            if f >= 1.0 or thinned or not f > 0.0:
                continue
            col = cols[m]
            o = offs[m]
            while z < end and sp_lo[z] < r1:
                lo = max(sp_lo[z], r0)
                hi = min(sp_hi[z], r1)
                if hi > lo:  # thinned: one floor per firing (thin_floors_jit: the rule of thin_print)
                    thin_floors_jit(gf, float(lo + i0), hi - lo, f, o)
                    for t in range(hi - lo):
                        if gf[t + 1] > gf[t]:
                            out[lo + t, col] = level
                if sp_hi[z] > r1:
                    break
                z += 1
            cursor[m] = z
    if edge_m.shape[0]:
        _restore_edges(sp_lo, sp_hi, sp_end, start, sx0, cx0, cy0, cx1, cy1, cut_at, r2, psi0, cols, edge_m, edge_v, gain, phase,
                       dphi, direction, i0, n_f, evenodd, level, out)
    return out


def _prep(sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs):
    f64 = [np.ascontiguousarray(a, dtype=np.float64) for a in (sx0, sy0, sx1, sy1, r2, psi0, frac, offs)]
    return (*f64[:6], np.ascontiguousarray(cols, dtype=np.int64), f64[6], f64[7])


def _cut_arrays(cuts):
    """Cut sections ``[(4, S_g)]`` as four concatenated ``(sum S_g,)`` arrays and the ``(G + 1,)`` group bounds."""
    cuts = [np.asarray(c, np.float64).reshape(4, -1) for c in cuts]
    at = np.zeros(len(cuts) + 1, np.int64)
    at[1:] = np.cumsum([c.shape[1] for c in cuts], dtype=np.int64)
    cat = np.concatenate(cuts, axis=1) if cuts else np.zeros((4, 0))
    return [np.ascontiguousarray(x) for x in cat], at


def _with_virtual(r2, psi0, cols, frac, offs, edge):
    """The track arrays with the edge restore's virtual tracks merged in by radius (share 0: never
    written), the restore's indices into them and its (cut, edge_m, edge_v, gain, phase) arguments."""
    cuts, thin, d_mm, gain, phase = edge
    thin = np.asarray(thin, np.int64)
    d_mm = np.asarray(d_mm, np.float64)
    n, n_t, n_s = r2.size, thin.size, d_mm.size
    rv = np.sqrt(r2[thin])[:, None] + d_mm[None, :]
    rr = np.concatenate([r2, (rv * rv).ravel()])
    order = np.argsort(rr, kind="stable")
    inv = np.empty_like(order)
    inv[order] = np.arange(order.size)
    def cat(a, fill=None):
        return np.ascontiguousarray(np.concatenate([a, np.repeat(a[thin], n_s) if fill is None else np.full(n_t * n_s, fill)])[order])
    arrays = (np.ascontiguousarray(rr[order]), cat(psi0), cat(cols), cat(frac, 0.0), cat(offs, 0.0))
    c, at = _cut_arrays(cuts)
    return arrays, (*c, at, np.ascontiguousarray(inv[thin]), np.ascontiguousarray(inv[n:].reshape(n_t, n_s)),
                    np.ascontiguousarray(gain, np.float64), np.ascontiguousarray(phase, np.float64))


_NO_EDGE = (np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(1, np.int64), np.zeros(0, np.int64),
            np.zeros((0, 1), np.int64), np.zeros(0), np.zeros(0))


def direct_fill_jit(sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs, *, dphi, direction, i0, n_f, n_cols, fill, level, edge=None,
                    out=None):
    """``(n_f, n_cols) uint8`` print image of one swathe (see the module doc for the rules).

    ``sx0..sy1``: ``(S,) float64`` segment ends in the local frame; ``r2``: ``(M,) float64``
    squared track radii, ascending; ``psi0``: ``(M,)`` local angle of each track's nozzle at
    firing 0; ``cols``: ``(M,) int64`` the image column (nozzle) of each track; ``frac``,
    ``offs``: ``(M,)`` thinning (1.0 keeps every drop). Row ``b`` is firing ``i0 + b``.
    ``edge``: the edge restore (:mod:`._direct_edge`), ``(cuts, thin, d_mm, gain, phase)``: cut
    sections ``[(4, S_g) float64]`` (local ``x0, y0, x1, y1``), the ``(T,) int64`` indices of the
    tracks restored (thinned), the ``(S,)`` radial offsets (mm) looked at, the ``(T,)`` restore
    rates and phases; None: no restore. ``out``: the ``(n_f, n_cols) uint8`` C-contiguous array to
    write (every byte, whatever it held: :class:`rotoprint._buffers.ReusedBuffers`), else a new one.
    """
    if out is None:
        out = np.empty((n_f, n_cols), np.uint8)  # _direct_fill writes every byte
    elif out.shape != (n_f, n_cols) or out.dtype != np.uint8 or not out.flags.c_contiguous or not out.flags.writeable:
        raise ValueError(f"out must be a writeable C-contiguous ({n_f}, {n_cols}) uint8 array, got {out.shape} {out.dtype}")
    if not np.isfinite(frac).all():  # a NaN share would make span events the kernel did not count room for
        raise ValueError("frac must be finite")
    args = _prep(sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs)
    rest = _NO_EDGE
    if edge is not None and np.size(edge[1]):
        tracks, rest = _with_virtual(*args[4:], edge)
        args = (*args[:4], *tracks)
    return _direct_fill(*args, float(dphi), int(direction), int(i0), int(n_f), fill == "evenodd", np.uint8(level), out, *rest)


def direct_fill_numpy(sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs, *, dphi, direction, i0, n_f, n_cols, fill, level, edge=None):
    """The pure-numpy reference of :func:`direct_fill_jit` (same contract, same result; the edge
    restore by :func:`._direct_edge.edge_restore_numpy`)."""
    if edge is not None and np.size(edge[1]):
        from ._direct_edge import edge_restore_numpy

        out = direct_fill_numpy(sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs, dphi=dphi, direction=direction, i0=i0, n_f=n_f,
                                n_cols=n_cols, fill=fill, level=level)
        cuts, thin, d_mm, gain, phase = edge
        thin = np.asarray(thin, np.int64)
        r2 = np.asarray(r2, np.float64)
        edge_restore_numpy(np.stack([sx0, sy0, sx1, sy1]), cuts, np.sqrt(r2[thin]), np.asarray(psi0)[thin], np.asarray(cols)[thin],
                           gain, phase, d_mm, dphi=dphi, direction=direction, i0=i0, n_f=n_f, fill=fill, level=level, out=out,
                           fill_numpy=direct_fill_numpy)
        return out
    sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs = _prep(sx0, sy0, sx1, sy1, r2, psi0, cols, frac, offs)
    n_tr = r2.shape[0]
    out = np.zeros((n_f, n_cols), np.uint8)
    dx = sx1 - sx0
    dy = sy1 - sy0
    A = dx * dx + dy * dy
    B = sx0 * dx + sy0 * dy
    qa = sx0 * sx0 + sy0 * sy0
    qb = sx1 * sx1 + sy1 * sy1
    dip = (B < 0.0) & (B + A > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        cr = sx0 * dy - sy0 * dx
        qmin = np.where(dip, cr * cr / A, np.minimum(qa, qb))
    qmax = np.maximum(qa, qb)
    ok = A != 0.0
    j0 = np.searchsorted(r2, qmin * (1.0 - QMIN_WIDEN), side="right")
    j1 = np.maximum(np.searchsorted(r2, qmax, side="right"), j0)
    cnt = np.where(ok, j1 - j0, 0)
    total = int(cnt.sum())
    diff = np.zeros((n_tr, n_f + 1), np.int32)
    if total:
        s = np.repeat(np.arange(cnt.size), cnt)
        first = np.repeat(np.cumsum(cnt) - cnt, cnt)
        m = j0[s] + (np.arange(total) - first)
        rr = r2[m]
        ia = qa[s] < rr
        ib = qb[s] < rr
        live = ~(ia & ib) & ~(~ia & ~ib & ~(dip[s] & (qmin[s] < rr)))
        s, m, rr, ia, ib = s[live], m[live], rr[live], ia[live], ib[live]
        As, Bs = A[s], B[s]
        C = qa[s] - rr
        D = np.maximum(Bs * Bs - As * C, 0.0)
        sq = np.sqrt(D)
        with np.errstate(divide="ignore", invalid="ignore"):
            tp = np.where(Bs <= 0.0, (-Bs + sq) / As, C / (-Bs - sq))
            tm = np.where(Bs >= 0.0, (-Bs - sq) / As, C / (-Bs + sq))

        def firing(t, sel):
            t = np.clip(t[sel], 0.0, 1.0)
            ss = s[sel]
            px = sx0[ss] + t * dx[ss]
            py = sy0[ss] + t * dy[ss]
            u = direction * (psi0[m[sel]] - np.arctan2(py, px)) / dphi - i0
            return np.where(u <= 0.0, 0, np.where(u >= n_f, n_f, np.ceil(np.clip(u, 0.0, n_f)))).astype(np.int64)

        exits = ~ib
        entries = ~ia
        np.add.at(diff, (m[exits], firing(tp, exits)), -direction)
        np.add.at(diff, (m[entries], firing(tm, entries)), direction)
    w = np.cumsum(diff[:, :n_f], axis=1)
    inside = (w & 1).astype(bool) if fill == "evenodd" else w != 0
    ia_abs = np.arange(n_f, dtype=np.float64)[None, :] + i0
    keep = np.floor((ia_abs + 1) * frac[:, None] + offs[:, None]) > np.floor(ia_abs * frac[:, None] + offs[:, None])
    keep |= frac[:, None] >= 1.0
    val = np.where(inside & keep, np.uint8(level), np.uint8(0)).astype(np.uint8)
    if n_tr:  # tracks of one image column (never two in practice) are combined by maximum
        np.maximum.at(out.T, cols, val)
    return out


KERNELS = {"jit": direct_fill_jit, "numpy": direct_fill_numpy}
