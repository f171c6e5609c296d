"""Error diffusion along each track of a print image: the numba kernel and its numpy reference.

For every nozzle column ``k`` the sites that print (``mask[b, k]``) are visited in firing order;
each wants ``want[k]`` levels (a real number in ``[0, levels]``); the level printed is the
nearest whole level to ``want + carried error`` (clamped to ``lo..levels``) and the difference
is carried to the next printing site of the same track. Over any run of sites the printed
levels sum to the wanted ones within one level.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["diffuse_jit", "diffuse_numpy"]


@njit(cache=True, nogil=True)
def diffuse_jit(mask, want, levels, lo, out):
    f, n = mask.shape
    for k in range(n):
        err = 0.0
        w = want[k]
        for b in range(f):
            if not mask[b, k]:
                continue
            v = w + err
            q = math.floor(v + 0.5)
            if q < lo:
                q = lo
            if q > levels:
                q = levels
            out[b, k] = q
            err = v - q


def diffuse_numpy(mask, want, levels, lo, out):
    f, n = mask.shape
    for k in range(n):
        err = 0.0
        for b in np.flatnonzero(mask[:, k]):
            v = want[k] + err
            q = min(max(math.floor(v + 0.5), lo), levels)
            out[b, k] = q
            err = v - q
