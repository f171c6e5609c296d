"""Thinning of a print image by kept shares: the numba kernel of
:func:`rotoprint.rotary.equalise.thin_print`.

Track ``k`` keeps firing ``i`` (absolute index ``i + first_firing``) when ``floor((i + 1) f_k +
o_k) > floor(i f_k + o_k)``: the same float64 expression as the numpy reference, evaluated only
at the sites that print (most of a pass's image is empty), so the result is identical.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["thin_levels_jit"]


@njit(cache=True, nogil=True)
def thin_levels_jit(levels, first_firing, f, o, out):
    """``out[b, k] = levels[b, k]`` where firing ``b`` of track ``k`` is kept, else 0.

    levels, out : (F, N) uint8; first_firing : int; f, o : (N,) float64 (share, phase).
    """
    n_f, n = levels.shape
    for b in range(n_f):
        i = float(b + first_firing)
        for k in range(n):
            v = levels[b, k]
            if v == 0:
                out[b, k] = 0
                continue
            fk = f[k]
            ok = o[k]
            if math.floor((i + 1.0) * fk + ok) > math.floor(i * fk + ok):
                out[b, k] = v
            else:
                out[b, k] = 0
