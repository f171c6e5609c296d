"""Fibre fill in pure numpy: the reference path the jit kernel is tested against.

Coordinates are in *fibre frame* pixel units: ``v`` across fibres (fibre ``j`` is the line
``v = j``), ``u`` along them (sample ``i`` at ``u = i``). A segment crosses fibre ``j`` when
``min(v) <= j < max(v)`` (half-open, so a vertex on a fibre is counted once by the two
segments that meet there), and its crossing at ``u_c`` counts for every sample with
``u_c <= i``. The winding number of a sample is the sum of the signs of the crossings that
count for it; crossings before the image count for every sample, those after it for none.
"""

from __future__ import annotations

import numpy as np

FILL_RULES = ("nonzero", "evenodd")


def winding_numpy(ua: np.ndarray, va: np.ndarray, ub: np.ndarray, vb: np.ndarray, n_fib: int, n_samp: int) -> np.ndarray:
    """``(n_fib, n_samp) int32`` winding numbers of the sample points."""
    ua, va, ub, vb = (np.asarray(x, dtype=np.float64) for x in (ua, va, ub, vb))
    keep = va != vb
    ua, va, ub, vb = ua[keep], va[keep], ub[keep], vb[keep]
    sign = np.where(va > vb, 1, -1).astype(np.int32)
    swap = va > vb
    lo_u = np.where(swap, ub, ua)
    lo_v = np.where(swap, vb, va)
    hi_u = np.where(swap, ua, ub)
    hi_v = np.where(swap, va, vb)
    j0 = np.clip(np.ceil(lo_v), 0, n_fib).astype(np.int64)
    j1 = np.clip(np.ceil(hi_v), 0, n_fib).astype(np.int64)
    count = np.maximum(j1 - j0, 0)
    total = int(count.sum())
    diff = np.zeros((n_fib, n_samp + 1), np.int32)
    if total:
        seg = np.repeat(np.arange(len(count)), count)
        first = np.repeat(np.cumsum(count) - count, count)
        j = j0[seg] + (np.arange(total) - first)
        slope = (hi_u[seg] - lo_u[seg]) / (hi_v[seg] - lo_v[seg])
        u = lo_u[seg] + (j - lo_v[seg]) * slope
        i = np.ceil(np.clip(u, -1.0, n_samp + 1.0)).astype(np.int64)
        i = np.clip(i, 0, n_samp)
        np.add.at(diff, (j, i), sign[seg])
    return np.cumsum(diff[:, :n_samp], axis=1, dtype=np.int32)


def fill_numpy(ua, va, ub, vb, n_fib: int, n_samp: int, rule: str) -> np.ndarray:
    """``(n_fib, n_samp) uint8`` image, 255 where the fill rule says inside."""
    w = winding_numpy(ua, va, ub, vb, n_fib, n_samp)
    inside = (w & 1).astype(bool) if rule == "evenodd" else w != 0
    return inside.astype(np.uint8) * np.uint8(255)


def fill_fast(ua, va, ub, vb, n_fib: int, n_samp: int, rule: str) -> np.ndarray:
    """:func:`fill_numpy`'s image by the fast kernel: the C extension's ``fill`` when it is
    built (no numba import, no compile on a first run), else the numba kernel
    :func:`rotoprint.slicing._kernels.fill_jit` (the two give the same bytes)."""
    from .._accel import native

    if native is None:
        from ._kernels import fill_jit

        return fill_jit(ua, va, ub, vb, n_fib, n_samp, rule)
    out = np.zeros((n_fib, n_samp), np.uint8)
    if n_fib and n_samp:
        a = [np.ascontiguousarray(x, dtype=np.float64) for x in (ua, va, ub, vb)]
        if not len(a[0]) == len(a[1]) == len(a[2]) == len(a[3]):
            raise ValueError("the four coordinate arrays must have one length")
        native.fill(*a, int(n_fib), int(n_samp), rule == "evenodd", out)
    return out
