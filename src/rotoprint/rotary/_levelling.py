"""Levelling of a wet film under surface tension: the kernel and its application to one strip.

The linearised thin-film (lubrication) equation ``dh/dt = -(sigma h0^3 / (3 eta)) lap^2 h``
multiplies the thickness map's Fourier mode ``k`` by ``exp(-D t |k|^4)`` with
``D = sigma h0^3 / (3 eta)`` (Orchard 1962). Its kernel in space, ``g``, is real, even in
``x`` and ``y`` and sums to 1; it has negative side lobes (about -5.6 % of its peak) and a
tail that falls off as ``exp(-c (rho / L)^(4/3))``, ``L = (D t)^(1/4)``. We truncate it to a
box of ``+-halo`` cells (``halo = ceil(halo_lengths * L / cell)``) and renormalise it: the
truncated kernel *is* the model, so a strip computed with a window of ``2 halo`` more rows on
each side gives the same cells as the whole grid at once (to rounding), whatever the strips.

Within the wetted film only (a dry cell stays dry: the contact line is pinned) the flow is an
exchange between pairs of wet cells: cells ``i`` and ``j`` trade ``g(j - i) (h_i - h_j)``, so

    ``h'_j = w_j [ h_j (1 - N_j) + sum_i g(j - i) w_i h_i ]``,  ``N_j = sum_i g(j - i) w_i``,

``w`` the wet indicator. Each pair's trade is equal and opposite (``g`` is even), so the volume is
conserved exactly; a flat film stays flat up to its pinned edge (no flow into dry cells: what
would go there stays, ``1 - N``); inside a wide wet area ``N = 1`` and this is the plain spectral
filter ``g * h``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as sfft

__all__ = ["levelling_kernel", "level_window"]


def levelling_kernel(dt_um4: float, gx_um: float, gy_um: float, halo_lengths: float) -> np.ndarray:
    """The truncated, renormalised levelling kernel, ``(2 hy + 1, 2 hx + 1) float64``.

    Parameters
    ----------
    dt_um4 : float
        ``D t = sigma h0^3 t / (3 eta)``, um^4 (> 0).
    gx_um, gy_um : float
        Grid cell, um.
    halo_lengths : float
        Truncation radius in levelling lengths ``L = (D t)^(1/4)``.

    Returns
    -------
    (2 hy + 1, 2 hx + 1) float64
        Symmetric in both axes (exactly), sums to 1.
    """
    length_um = dt_um4 ** 0.25
    hx = max(1, math.ceil(halo_lengths * length_um / gx_um))
    hy = max(1, math.ceil(halo_lengths * length_um / gy_um))
    # sample the continuous kernel on a grid wide enough that its periodic images are
    # negligible (the tail at 4 halos is far below rounding)
    mx = sfft.next_fast_len(max(64, 4 * (2 * hx + 1)))
    my = sfft.next_fast_len(max(64, 4 * (2 * hy + 1)))
    kx = 2.0 * math.pi * sfft.rfftfreq(mx, d=gx_um)
    ky = 2.0 * math.pi * sfft.fftfreq(my, d=gy_um)
    k2 = ky[:, None] ** 2 + kx[None, :] ** 2
    g = sfft.irfft2(np.exp(-dt_um4 * k2 * k2), s=(my, mx))
    g = np.roll(np.roll(g, hy, axis=0), hx, axis=1)[: 2 * hy + 1, : 2 * hx + 1]
    # one quadrant (the average of the four), mirrored: exactly even in x and y
    q = 0.25 * (g[hy:, hx:] + g[hy::-1, hx:] + g[hy:, hx::-1] + g[hy::-1, hx::-1])
    q = np.concatenate([q[:0:-1], q], axis=0)
    g = np.concatenate([q[:, :0:-1], q], axis=1)
    return g / g.sum()


def _conv_same(a: np.ndarray, kernel_f: np.ndarray, shape: tuple[int, int], hy: int, hx: int) -> np.ndarray:
    """Circular convolution of ``a`` (zero-padded to ``shape``) with the kernel whose rfft2
    (centred at ``(hy, hx)``) is ``kernel_f``; output aligned with ``a``."""
    f = sfft.rfft2(a, s=shape, workers=1)
    f *= kernel_f
    out = sfft.irfft2(f, s=shape, workers=1, overwrite_x=True)
    return out[hy: hy + a.shape[0], hx: hx + a.shape[1]]


def level_window(film: np.ndarray, kernel: np.ndarray, core_rows: slice) -> np.ndarray:
    """Levelled thickness of the ``core_rows`` of a window.

    Parameters
    ----------
    film : (R, C) float64
        As-landed thickness, um, of a window that reaches ``hy`` rows beyond the core on each
        side (rows beyond the grid are zero: dry); columns are the whole grid.
    kernel : (2 hy + 1, 2 hx + 1) float64
        From :func:`levelling_kernel`.
    core_rows : slice
        The window's rows to return; at least ``hy`` rows from either end of the window unless
        that end is the grid's.

    Returns
    -------
    (core rows, C) float64
        Dry cells are 0.
    """
    hy, hx = (kernel.shape[0] - 1) // 2, (kernel.shape[1] - 1) // 2
    rows, cols = film.shape
    # zero columns beyond the grid: dry (no flow across)
    shape = (sfft.next_fast_len(rows + 2 * hy, real=True), sfft.next_fast_len(cols + 2 * hx, real=True))
    kp = np.zeros(shape, np.float64)
    kp[: kernel.shape[0], : kernel.shape[1]] = kernel
    kf = sfft.rfft2(kp, workers=1)
    del kp
    wet = film > 0.0
    h = np.where(wet, film, 0.0)
    n = _conv_same(wet.astype(np.float64), kf, shape, hy, hx)[core_rows]
    gh = _conv_same(h, kf, shape, hy, hx)[core_rows]
    hc = h[core_rows]
    return np.where(wet[core_rows], hc * (1.0 - n) + gh, 0.0)
