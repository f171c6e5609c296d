"""The loops of :func:`rotoprint.rotary.equalise.track_fractions` (numba kernels).

The footprint matrix ``K`` ``(M tracks, n_g grid points)`` is given as a band: ``band`` ``(M, W)
float64`` holds row ``k``'s entries (ascending columns from ``start[k]``, ``(M,) int64``), zero
beyond them; the profile arrays are ``n_g + W`` long (the tail: scratch that the band's zeros
reach). A zero entry adds exactly 0.0 to a finite, non-negative sum, so the band gives the sums of
the sparse matrix's entries alone. Every loop here does the same float64 operations in the same order as the numpy / scipy
expression it replaces, so the shares are identical to theirs bit for bit:

- the profile ``t = K^T u`` is ``scipy.sparse``'s ``csr_matvec`` over ``K.T.tocsr()``: each
  grid point sums, from 0.0, its tracks' ``K * u`` in ascending track order, which is the
  order a scatter over the tracks in turn adds them (:func:`profile_jit`);
- the footprint average ``K t`` sums each row from 0.0 in ascending columns (``csr_matvec``
  over ``K``), four rows at a time (:func:`_footprint_means`);
- the running mean is ``numpy.cumsum`` (sequential) of the profile on the printed range,
  differenced over the window (:func:`level_at_jit`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["profile_jit", "level_at_jit", "settle_jit", "drop_round_jit"]


@njit(cache=True, nogil=True)
def profile_jit(band, start, f, w, t):  # pragma: no cover - jit
    """``t[:] = K^T (f w)`` (``t`` ``(n_g + W,) float64``, overwritten; ``f``, ``w`` ``(M,)``)."""
    m, wd = band.shape
    t[:] = 0.0
    for k in range(m):
        u = f[k] * w[k]
        b = start[k]
        for s in range(wd):
            t[b + s] = t[b + s] + band[k, s] * u


@njit(cache=True, nogil=True, inline="always")
def _footprint_means(band, start, t, out):  # pragma: no cover - jit
    """``out[k] = sum_s band[k, s] t[start[k] + s]``, from 0.0 in ascending ``s`` (four rows at
    a time: independent sums, each in its own order)."""
    m, wd = band.shape
    m4 = m - m % 4
    for k in range(0, m4, 4):
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        a3 = 0.0
        b0, b1, b2, b3 = start[k], start[k + 1], start[k + 2], start[k + 3]
        for s in range(wd):
            a0 = a0 + band[k, s] * t[b0 + s]
            a1 = a1 + band[k + 1, s] * t[b1 + s]
            a2 = a2 + band[k + 2, s] * t[b2 + s]
            a3 = a3 + band[k + 3, s] * t[b3 + s]
        out[k] = a0
        out[k + 1] = a1
        out[k + 2] = a2
        out[k + 3] = a3
    for k in range(m4, m):
        a = 0.0
        b = start[k]
        for s in range(wd):
            a = a + band[k, s] * t[b + s]
        out[k] = a


@njit(cache=True, nogil=True, inline="always")
def _level_at(t, printed, a_i, b_i, n_w, s_k, c, lev):  # pragma: no cover - jit
    """``lev[k]`` = the running mean of ``t`` (0 outside ``printed``) at grid point ``s_k[k]``:
    ``(c[b] - c[a]) / n_w``, ``c`` the cumulative sum from 0 (``(n_g + 1,)`` scratch)."""
    c[0] = 0.0
    acc = 0.0
    for g in range(c.size - 1):
        x = t[g] if printed[g] else 0.0
        acc = x if g == 0 else acc + x
        c[g + 1] = acc
    for k in range(s_k.size):
        s = s_k[k]
        lev[k] = (c[b_i[s]] - c[a_i[s]]) / float(n_w[s])


@njit(cache=True, nogil=True)
def level_at_jit(band, start, f, w, printed, a_i, b_i, n_w, s_k, t, c, lev):  # pragma: no cover - jit
    """The running mean of the profile of shares ``f`` at each track's grid point, into ``lev`` ``(M,)``
    (``t`` ``(n_g + W,)``, ``c`` ``(n_g + 1,)`` scratch)."""
    profile_jit(band, start, f, w, t)
    _level_at(t, printed, a_i, b_i, n_w, s_k, c, lev)


@njit(cache=True, nogil=True)
def settle_jit(band, start, k_sum, w, target, lo_k, hi_f, n_fp, n_lv, printed, a_i, b_i, n_w, s_k, up,
               f, t, c, lev):  # pragma: no cover - jit
    """The updates of ``track_fractions``' settling, in place on ``f`` ``(M,) float64``.

    ``n_fp`` footprint-scale updates ``f <- clip(f * (target / max(seen, 1e-300)), lo_k, hi_f)``,
    ``seen = (K t) / max(k_sum, 1e-300)``, ``t = K^T (f w)``; then ``n_lv`` mm-scale ones
    ``f <- clip(f * (up ? g : min(1, g)), lo_k, hi_f)``, ``g = target / max(level, 1e-300)``
    (``up`` ``(M,) bool``). ``t``, ``c``, ``lev``: scratch as in :func:`level_at_jit`.
    """
    m = f.size
    for _ in range(n_fp):
        profile_jit(band, start, f, w, t)
        _footprint_means(band, start, t, lev)
        for k in range(m):
            acc = lev[k]
            ks = k_sum[k]
            seen = acc / (ks if ks > 1e-300 else 1e-300)
            x = f[k] * (target / (seen if seen > 1e-300 else 1e-300))
            lo = lo_k[k]
            hi = hi_f[k]
            x = x if x > lo else lo
            f[k] = x if x < hi else hi
    for _ in range(n_lv):
        level_at_jit(band, start, f, w, printed, a_i, b_i, n_w, s_k, t, c, lev)
        for k in range(m):
            lv = lev[k]
            g = target / (lv if lv > 1e-300 else 1e-300)
            if not up[k]:
                g = g if g < 1.0 else 1.0
            x = f[k] * g
            lo = lo_k[k]
            hi = hi_f[k]
            x = x if x > lo else lo
            f[k] = x if x < hi else hi


@njit(cache=True, nogil=True)
def drop_round_jit(need, r_s, hi_f, g_lim):  # pragma: no cover - jit
    """One round of leaving whole tracks out, in place on ``hi_f`` ``(M,) float64`` (0: left out):
    over the kept tracks in radial order, the excess ``need`` ``(M,)`` is error-diffused, and a
    track with ``need > 0`` is left out when the debt reaches 1/2 and the gap from the last kept
    track to the next kept one after it is at most ``g_lim`` mm. Returns the tracks left out."""
    m = r_s.size
    nxt = np.full(m, np.inf)  # radius of the next kept track after each
    prev = -1
    for k in range(m):
        if hi_f[k] > 0:
            if prev >= 0:
                nxt[prev] = r_s[k]
            prev = k
    debt = 0.0
    last = -np.inf
    out = 0
    for k in range(m):
        if not hi_f[k] > 0:
            continue
        nk = need[k]
        if nk > 0:
            debt += nk
        else:
            debt = 0.0
        if nk > 0 and debt >= 0.5 and nxt[k] - last <= g_lim:
            hi_f[k] = 0.0
            debt -= 1.0
            out += 1
        else:
            last = r_s[k]
    return out
