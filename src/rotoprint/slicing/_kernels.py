"""Jit-compiled fibre fill (numba); same contract as :mod:`._fill`, one pass, no temporaries
beyond the per-fibre difference row."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _fill_kernel(ua, va, ub, vb, n_fib, n_samp, evenodd, diff, out):  # pragma: no cover - jit
    for s in range(ua.shape[0]):
        v0 = va[s]
        v1 = vb[s]
        if v0 == v1:
            continue
        if v0 < v1:
            sign = -1
            lu, lv, hu, hv = ua[s], v0, ub[s], v1
        else:
            sign = 1
            lu, lv, hu, hv = ub[s], v1, ua[s], v0
        j0 = math.ceil(lv) if lv > 0.0 else 0
        if j0 >= n_fib:
            continue
        if hv <= 0.0:
            continue
        j1 = math.ceil(hv) if hv < n_fib else n_fib
        slope = (hu - lu) / (hv - lv)
        for j in range(j0, j1):
            u = lu + (j - lv) * slope
            if u <= 0.0:
                i = 0
            elif u >= n_samp:
                i = n_samp
            else:
                i = math.ceil(u)
            diff[j, i] += sign
    for j in range(n_fib):
        acc = 0
        for i in range(n_samp):
            acc += diff[j, i]
            if evenodd:
                out[j, i] = 255 if (acc & 1) else 0
            else:
                out[j, i] = 255 if acc != 0 else 0
    return out


def fill_jit(ua, va, ub, vb, n_fib: int, n_samp: int, rule: str) -> np.ndarray:
    """``(n_fib, n_samp) uint8`` image, 255 inside; see :func:`._fill.fill_numpy`."""
    diff = np.zeros((n_fib, n_samp + 1), np.int32)
    out = np.empty((n_fib, n_samp), np.uint8)
    as64 = [np.ascontiguousarray(x, dtype=np.float64) for x in (ua, va, ub, vb)]
    return _fill_kernel(*as64, n_fib, n_samp, rule == "evenodd", diff, out)
