"""Thinning of a print image by kept shares: the one rule of
:func:`rotoprint.rotary.equalise.thin_print`, shared by every kernel that thins.

Track ``k`` keeps firing ``i`` (absolute index) when ``floor((i + 1) f_k + o_k) > floor(i f_k +
o_k)``: an ordered, even pattern, exactly ``f_k`` of the firings over any run. Every thinning
kernel evaluates this same float64 expression, so the exact transform thinning while it samples
(:func:`rotoprint.rotary._exact_kernels.windows_sample_thin_numba`), the direct slicer thinning
while it fills and :func:`thin_levels_jit` on a finished image give identical images. Along a
track the floor of firing ``i + 1`` is the next firing's own floor, so a run of firings needs one
floor per firing (:func:`thin_floors_jit`), not two.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["kept_jit", "thin_floors_jit", "kept_numpy", "thin_levels_jit", "thin_phases", "GOLDEN"]


@njit(cache=True, nogil=True, inline="always")
def kept_jit(i, f, o):  # pragma: no cover - jit
    """Whether firing ``i`` (float64, absolute index) of a track with share ``f`` and phase ``o`` is kept."""
    return np.floor((i + 1.0) * f + o) > np.floor(i * f + o)


#: ``0.0, 1.0, .., RAMP_LEN - 1`` (float64): :func:`thin_floors_jit` adds these to its first firing instead of
#: converting each loop index to a float (a packed int64 -> float64 conversion needs AVX-512: with it the loop
#: vectorises on AVX2 machines too; the sums are the same exact integers).
RAMP_LEN = 256
_RAMP = np.arange(RAMP_LEN, dtype=np.float64)


@njit(cache=True, nogil=True, inline="always")
def thin_floors_jit(g, first, n, f, o):  # pragma: no cover - jit
    """``g[t] = floor((first + t) f + o)`` for ``t = 0 .. n`` (``n + 1`` values; ``first`` float64).

    Firing ``first + t`` is kept exactly when ``g[t + 1] > g[t]`` (the rule of :func:`kept_jit`:
    ``(first + t) + 1.0`` is the float ``first + (t + 1)``, both exact).
    """
    ramp = _RAMP
    for base in range(0, n + 1, RAMP_LEN):
        fb = first + base  # (first + base) + t == first + (base + t): integers, exact in float64
        m = min(RAMP_LEN, n + 1 - base)
        dst = g[base:base + m]
        for t in range(m):
            dst[t] = np.floor((fb + ramp[t]) * f + o)


def kept_numpy(i, f, o):
    """:func:`kept_jit` on arrays (broadcast): ``i`` float64 absolute firing indices, ``f``, ``o`` shares and phases."""
    i = np.asarray(i, np.float64)
    return np.floor((i + 1.0) * f + o) > np.floor(i * f + o)


@njit(cache=True, nogil=True)
def thin_levels_jit(levels, first_firing, f, o, out):  # pragma: no cover - jit
    """``out[b, k] = levels[b, k]`` where firing ``b`` of track ``k`` is kept, else 0.

    levels, out : (F, N) uint8; first_firing : int; f, o : (N,) float64 (share, phase).
    """
    n_f, n = levels.shape
    for b in range(n_f):
        i = float(b + first_firing)
        src = levels[b]
        dst = out[b]
        for k in range(n):  # (a product, not a select: the same bytes, and the loop vectorises on AVX2 too)
            dst[k] = src[k] * np.uint8(kept_jit(i, f[k], o[k]))


#: The golden-ratio step of the phases between nozzles (:func:`thin_phases`).
GOLDEN = 0.6180339887498949


def thin_phases(nozzles, pass_index: int) -> np.ndarray:
    """Phases ``o_k = ((k + 7919 p) * golden) mod 1`` (float64) of nozzles ``k`` in pass ``p``.

    ``nozzles``: the nozzle count ``N`` (phases of ``0 .. N - 1``) or an int array of nozzles.
    """
    k = np.arange(nozzles) if np.ndim(nozzles) == 0 else np.asarray(nozzles)
    return np.mod((k + 7919 * int(pass_index)) * GOLDEN, 1.0)
