"""The loops of :func:`rotoprint.rotary.interlace.plan_passes` (numba kernels).

The pass planner judges thousands of candidate offsets; per candidate it needs the largest gap
between neighbouring tracks of the union of the passes and the radial film profile of one
pass's tracks. Both kernels give the numpy expressions' results bit for bit:

- :func:`max_gaps_jit`: the largest difference between neighbouring sorted radii inside
  ``[lo, hi]`` is a difference of the same two floats whichever way the radii are ordered, so a
  merge of the fixed passes' sorted radii with each candidate's sorted radii gives numpy's
  ``max(diff(sort(...)))`` exactly (no sum is involved);
- :func:`profile_add_jit`: ``numpy.bincount`` with weights sums each bin from 0.0 in input
  order; the kernel sums each row's touched bins in a scratch array in the same order, then
  adds each bin's sum to the profile once, as ``t += bincount(...)`` does. The weights (a
  power, which numpy may compute with other rounding than the C library) stay numpy's.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["max_gap", "inside_sorted", "candidate_gaps", "candidate_radii_jit", "sorted_gaps_jit", "max_gaps_jit", "max_gaps_numpy", "profile_add_jit", "profile_add_numpy"]


@njit(cache=True, nogil=True, inline="always")
def _merged_max_gap(rest, s, n):  # pragma: no cover - jit
    # the largest difference of neighbours in the merge of sorted rest and sorted s[:n] (0.0 below two values)
    n_r = rest.shape[0]
    i = 0
    j = 0
    prev = 0.0
    have = False
    g = 0.0
    while i < n_r or j < n:
        if j >= n or (i < n_r and rest[i] <= s[j]):
            v = rest[i]
            i += 1
        else:
            v = s[j]
            j += 1
        if have and v - prev > g:
            g = v - prev
        prev = v
        have = True
    return g


@njit(cache=True, nogil=True)
def max_gaps_jit(rest, rows, lo, hi, out):  # pragma: no cover - jit
    """``out[c]``: the largest gap between neighbouring values of ``rest`` and ``rows[c]`` inside ``[lo, hi]``.

    rest : (R,) float64, sorted, every value inside ``[lo, hi]``; rows : (C, M) float64 (NaN:
    absent); out : (C,) float64. Fewer than two values inside: 0.0.
    """
    n_c, m = rows.shape
    buf = np.empty(m, np.float64)
    for c in range(n_c):
        n = 0
        for i in range(m):
            v = rows[c, i]
            if v >= lo and v <= hi:
                buf[n] = v
                n += 1
        out[c] = _merged_max_gap(rest, np.sort(buf[:n]), n)


def max_gaps_numpy(rest, rows, lo, hi):
    """:func:`max_gaps_jit` in numpy (the reference): ``(C,) float64``."""
    r = np.concatenate([np.broadcast_to(rest, (rows.shape[0], rest.shape[0])), rows], axis=1)
    rr = np.sort(np.where((r >= lo) & (r <= hi), r, np.nan), axis=1)
    if rr.shape[1] < 2:
        return np.zeros(rr.shape[0])
    g = np.diff(rr, axis=1)
    return np.where(np.isfinite(g), g, 0.0).max(axis=1)


@njit(cache=True, nogil=True)
def profile_add_jit(t, idx, k):  # pragma: no cover - jit
    """``t += bincount(idx[s][ok], k[s][ok], minlength=len(t))`` for each row ``s`` in turn,
    ``ok`` where ``0 <= idx < len(t)`` and ``k > 0``.

    t : (G,) float64, updated; idx : (S, M) int64; k : (S, M) float64.
    """
    n_g = t.shape[0]
    n_s, m = idx.shape
    acc = np.zeros(n_g, np.float64)
    for s in range(n_s):
        for i in range(m):
            b = idx[s, i]
            if b >= 0 and b < n_g and k[s, i] > 0:
                acc[b] += k[s, i]
        for i in range(m):
            b = idx[s, i]
            if b >= 0 and b < n_g and k[s, i] > 0:
                t[b] += acc[b]  # the bin's whole sum, once: later hits of the bin add 0.0
                acc[b] = 0.0


@njit(cache=True, nogil=True)
def profile_base_jit(r, grid0, step, a_mm, idx, base):  # pragma: no cover - jit
    """The grid points near each track and their cap base, elementwise as numpy computes them:
    ``idx[s, m] = floor((r_m - grid0) / step) + s - reach`` (``reach = (S - 1) / 2``) and
    ``base[s, m] = max(1 - x^2, 0)``, ``x = (grid0 + idx[s, m] step - r_m) / a_mm``.

    r : (M,) float64; idx : (S, M) int64 and base : (S, M) float64, written. The power of the
    base stays numpy's (its SIMD pow is not libm's on every machine)."""
    n_s, m = idx.shape
    reach = (n_s - 1) // 2
    for k in range(m):
        i0 = np.int64(np.floor((r[k] - grid0) / step))
        for s in range(n_s):
            i = i0 + (s - reach)
            idx[s, k] = i
            x = (grid0 + i * step - r[k]) / a_mm
            base[s, k] = max(1.0 - x * x, 0.0)


def profile_base_numpy(r, grid0, step, a_mm, idx, base):
    """:func:`profile_base_jit` in numpy (the reference)."""
    n_s = idx.shape[0]
    idx[:] = np.floor((r - grid0) / step).astype(np.int64) + np.arange(-(n_s // 2), n_s // 2 + 1)[:, None]
    x = (grid0 + idx * step - r) / a_mm
    base[:] = np.clip(1.0 - x * x, 0.0, None)
    return idx, base


def profile_add_numpy(t, idx, k):
    """:func:`profile_add_jit` in numpy (the reference)."""
    for s in range(idx.shape[0]):
        ok = (idx[s] >= 0) & (idx[s] < t.shape[0]) & (k[s] > 0)
        t += np.bincount(idx[s][ok], weights=k[s][ok], minlength=t.shape[0])
    return t


@njit(cache=True, nogil=True)
def shortfall_terms_jit(fixed, profiles, win, target, out):  # pragma: no cover - jit
    """The terms :func:`rotoprint.rotary.interlace.plan_passes`' ``score`` averages, elementwise
    as numpy computes them: for ``t = fixed + profiles[c]``, its running sum ``C`` (``C[0] = 0``,
    ``C[i + 1] = C[i] + t[i]``, as ``cumsum`` of the padded row), the local mean ``(C[hi_i] -
    C[lo_i]) / (hi_i - lo_i)`` over ``lo_i = max(0, i - win)``, ``hi_i = min(G, i + win + 1)``,
    and ``out[c, i] = max(0, 1 - t_i / max(target * local_i, 1e-300)) ** 2``.

    fixed : (G,) float64; profiles, out : (P, G) float64.
    """
    # The rows whose window lies whole inside (lo = i - win, hi = i + win + 1) in one loop over shifted
    # slices with the constant width 2 win + 1 (it vectorises: no index converted to a float), the
    # rows near the ends with their widths made once.
    n_p, n_g = profiles.shape
    t = np.empty(n_g, np.float64)
    c = np.empty(n_g + 1, np.float64)
    den = np.empty(n_g, np.float64)
    for i in range(n_g):
        den[i] = float(min(n_g, i + win + 1) - max(0, i - win))
    a = min(n_g, win + 1)  # rows i < a: lo = 0
    b = max(a, n_g - win - 1)  # rows a <= i < b: the whole window inside
    w = float(2 * win + 1)
    for p in range(n_p):
        c[0] = 0.0
        for i in range(n_g):
            t[i] = fixed[i] + profiles[p, i]
            c[i + 1] = c[i] + t[i]
        o = out[p]
        for i in range(a):
            _shortfall_term(c, t, o, i, min(n_g, i + win + 1), 0, den[i], target)
        c_hi = c[a + win + 1:]
        c_lo = c[a - win:]
        t_in = t[a:b]
        o_in = o[a:b]
        for j in range(b - a):
            v = max(0.0, 1.0 - t_in[j] / max(target * ((c_hi[j] - c_lo[j]) / w), 1e-300))
            o_in[j] = v * v
        for i in range(b, n_g):
            _shortfall_term(c, t, o, i, min(n_g, i + win + 1), max(0, i - win), den[i], target)


@njit(cache=True, nogil=True, inline="always")
def _shortfall_term(c, t, o, i, hi, lo, den, target):  # pragma: no cover - jit
    v = max(0.0, 1.0 - t[i] / max(target * ((c[hi] - c[lo]) / den), 1e-300))
    o[i] = v * v


@njit(cache=True, nogil=True, inline="always")
def _candidate_sorted(d, x, y, band_lo, band_hi, ex, ey, lo, hi, order, key, srt):  # pragma: no cover - jit
    # srt[:n] = the sorted radii hypot(x + d ex, y + d ey) inside their band and [lo, hi]; returns n. `order`
    # is kept from the call before and re-sorted by insertion (the offsets move the radii little and alike)
    m = x.shape[0]
    inf = np.inf
    dx = d * ex
    dy = d * ey
    for k in range(m):
        r = np.hypot(x[k] + dx, y[k] + dy)
        key[k] = r if (r >= band_lo[k] and r < band_hi[k] and r >= lo and r <= hi) else inf
    for i in range(1, m):  # insertion sort of order by key
        o = order[i]
        v = key[o]
        j = i - 1
        while j >= 0 and key[order[j]] > v:
            order[j + 1] = order[j]
            j -= 1
        order[j + 1] = o
    n = 0
    while n < m and key[order[n]] < inf:
        srt[n] = key[order[n]]
        n += 1
    return n


@njit(cache=True, nogil=True)
def candidate_gaps_jit(rest, x, y, band_lo, band_hi, ex, ey, cand, lo, hi, out):  # pragma: no cover - jit
    """:func:`max_gaps_jit` of the tracks of one pass at each candidate offset: ``out[c]`` the
    largest gap over ``[lo, hi]`` of ``rest`` with the radii ``hypot(x + d ex, y + d ey)``
    (``d = cand[c]``) of the tracks inside their band (``band_lo <= r < band_hi``), as the
    planner's ``radii`` computes them (the same float operations).

    rest : (R,) float64, sorted, inside; x, y, band_lo, band_hi : (M,) float64; cand, out : (C,) float64.
    The tracks' order is kept from one candidate to the next and re-sorted by insertion (the
    offsets move the radii little and alike: nearly sorted).
    """
    m = x.shape[0]
    order = np.arange(m)
    key = np.empty(m, np.float64)
    srt = np.empty(m, np.float64)
    for c in range(cand.shape[0]):
        n = _candidate_sorted(cand[c], x, y, band_lo, band_hi, ex, ey, lo, hi, order, key, srt)
        out[c] = _merged_max_gap(rest, srt, n)


@njit(cache=True, nogil=True)
def candidate_radii_jit(x, y, band_lo, band_hi, ex, ey, cand, lo, hi, rows, counts):  # pragma: no cover - jit
    """The sorted radii :func:`candidate_gaps_jit` merges, kept: ``rows[c, :counts[c]]`` those of
    candidate ``cand[c]``. rows : (C, M) float64; counts : (C,) int64."""
    m = x.shape[0]
    order = np.arange(m)
    key = np.empty(m, np.float64)
    for c in range(cand.shape[0]):
        counts[c] = _candidate_sorted(cand[c], x, y, band_lo, band_hi, ex, ey, lo, hi, order, key, rows[c])


@njit(cache=True, nogil=True)
def sorted_gaps_jit(rest, rows, counts, out):  # pragma: no cover - jit
    """``out[c]``: the largest gap of ``rest`` merged with ``rows[c, :counts[c]]`` (both sorted)."""
    for c in range(rows.shape[0]):
        out[c] = _merged_max_gap(rest, rows[c], counts[c])


#: Candidate sets whose sorted radii :func:`candidate_gaps` keeps (each ``(C, M)`` float64).
KEPT_CANDIDATE_SETS = 8


def candidate_gaps(rest, tracks, cand, lo, hi, *, kept=None, key=None):
    """:func:`candidate_gaps_jit` of ``cand`` ``(C,) float64`` for the tracks ``(x, y, band_lo,
    band_hi, ex, ey)``: ``(C,) float64``. With a dict ``kept`` and a ``key`` naming the candidate
    set (the coordinate descent tries one set again and again against other fixed passes), the
    set's sorted radii are made once (:func:`candidate_radii_jit`) and only merged with ``rest``
    afterwards (:func:`sorted_gaps_jit`): the same values. The key names the candidates only (they
    are checked); ``tracks``, ``lo`` and ``hi`` must be those the set was kept with (one
    ``plan_passes`` call keeps its own ``kept``)."""
    x, y, band_lo, band_hi, ex, ey = tracks
    cand = np.ascontiguousarray(cand, np.float64)
    out = np.empty(cand.shape[0])
    if kept is None or key is None or (key not in kept and len(kept) >= KEPT_CANDIDATE_SETS):
        candidate_gaps_jit(rest, x, y, band_lo, band_hi, ex, ey, cand, float(lo), float(hi), out)
        return out
    if key not in kept:
        rows, counts = np.empty((cand.shape[0], x.shape[0])), np.empty(cand.shape[0], np.int64)
        candidate_radii_jit(x, y, band_lo, band_hi, ex, ey, cand, float(lo), float(hi), rows, counts)
        kept[key] = (cand.copy(), rows, counts)
    c0, rows, counts = kept[key]
    if not np.array_equal(c0, cand):
        raise ValueError("candidate_gaps: another candidate set under a kept key")
    sorted_gaps_jit(rest, rows, counts, out)
    return out


def max_gap(rest, rows, lo, hi):
    """Largest gap over ``[lo, hi]`` of the union of ``rest`` (sorted, inside) with each row of ``rows`` ``(C, M)``: ``(C,) float64``."""
    out = np.empty(rows.shape[0])
    max_gaps_jit(rest, np.ascontiguousarray(rows, np.float64), float(lo), float(hi), out)
    return out


def inside_sorted(r, lo, hi):
    """The values of ``r`` inside ``[lo, hi]``, sorted."""
    return np.sort(r[(r >= lo) & (r <= hi)])
