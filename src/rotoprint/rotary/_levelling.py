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

The two convolutions (``g * (w h)`` and ``N = g * w``) may run on a grid ``f`` cells coarse
(``_levelling_kernels``: restriction ``Q^T``, the adjoint of bilinear interpolation ``Q``, and
:func:`levelling_kernel` with ``factor=f``): the operator ``Q G Q^T / f^2`` is symmetric and
passes a constant, so the exchange stays pairwise (the volume is conserved exactly) and ``N = 1``
inside a wide wet area.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import fft as sfft

__all__ = ["levelling_kernel", "level_window", "convolve_rows"]


def _interp_response(k: np.ndarray, cell_um: float, factor: int) -> np.ndarray:
    """Response of the restriction ``Q^T`` (and of the interpolation ``Q``) between the deposit
    grid of ``cell_um`` cells and a grid ``factor`` times coarser, one axis, over ``factor``:
    the Fourier sum of the bilinear weights a coarse node gives the cells around it (at
    offsets ``(m + 1/2) / f - 1/2`` coarse cells, ``_levelling_kernels``), 1 at ``k = 0``.

    For an odd ``factor`` this is ``T(k)^2``, ``T`` the box of ``factor`` cells; for an even
    one it is not (``cos^3(k cell / 2)`` at ``factor = 2``, where ``T^2 = cos^2``), so it is
    summed rather than assumed.
    """
    if factor == 1:
        return np.ones_like(k)
    f = int(factor)
    off = (np.arange(-f, 2 * f) + 0.5) / f - 0.5  # every offset with a weight > 0 (|o| < 1)
    w = np.maximum(0.0, 1.0 - np.abs(off))
    return (w[None, :] * np.cos(np.multiply.outer(k * (cell_um * f), off))).sum(axis=1) / f


def levelling_kernel(dt_um4: float, gx_um: float, gy_um: float, halo_lengths: float, factor: int = 1) -> np.ndarray:
    """The truncated, renormalised levelling kernel, ``(2 hy + 1, 2 hx + 1) float64``.

    Parameters
    ----------
    dt_um4 : float
        ``D t = sigma h0^3 t / (3 eta)``, um^4 (> 0).
    gx_um, gy_um : float
        Grid cell, um.
    halo_lengths : float
        Truncation radius in levelling lengths ``L = (D t)^(1/4)``.
    factor : int
        The kernel of the coarse grid whose cell is ``factor`` cells (``>= 1``): sampled at
        its spacing and divided, wavenumber by wavenumber, by the response of the restriction
        and interpolation around it (``T^4`` per axis, ``_levelling_kernels``), so that the
        round trip ``Q G Q^T`` passes the long waves as the fine kernel does. ``1``: the fine
        grid's kernel itself.

    Returns
    -------
    (2 hy + 1, 2 hx + 1) float64
        Symmetric in both axes (exactly), sums to 1; ``hx = ceil(halo_lengths L / (factor
        gx_um))``, likewise ``hy``.
    """
    length_um = dt_um4 ** 0.25
    cx, cy = gx_um * factor, gy_um * factor
    hx = max(1, math.ceil(halo_lengths * length_um / cx))
    hy = max(1, math.ceil(halo_lengths * length_um / cy))
    # sample the continuous kernel on a grid wide enough that its periodic images are
    # negligible (the tail at 4 halos is far below rounding)
    mx = sfft.next_fast_len(max(64, 4 * (2 * hx + 1)))
    my = sfft.next_fast_len(max(64, 4 * (2 * hy + 1)))
    kx = 2.0 * math.pi * sfft.rfftfreq(mx, d=cx)
    ky = 2.0 * math.pi * sfft.fftfreq(my, d=cy)
    k2 = ky[:, None] ** 2 + kx[None, :] ** 2
    spec = np.exp(-dt_um4 * k2 * k2)
    if factor > 1:
        ty, tx = _interp_response(ky, gy_um, factor), _interp_response(kx, gx_um, factor)
        spec /= (ty[:, None] * tx[None, :]) ** 2
    g = sfft.irfft2(spec, s=(my, mx))
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


def convolve_rows(arrays: list[np.ndarray], kernel: np.ndarray, window_cells: int) -> list[np.ndarray]:
    """Each array convolved with ``kernel`` (zero beyond its edges), in row windows of at
    most about ``window_cells`` cells (a core strip and ``hy`` halo rows each side: the same
    cells as one window over the whole array, to rounding).

    Parameters
    ----------
    arrays : list of (R, C) float64
    kernel : (2 hy + 1, 2 hx + 1) float64
        Even in both axes (:func:`levelling_kernel`).
    window_cells : int

    Returns
    -------
    list of (R, C) float64
    """
    hy, hx = (kernel.shape[0] - 1) // 2, (kernel.shape[1] - 1) // 2
    rows, cols = arrays[0].shape
    core = max(2 * hy, int(window_cells) // (cols + 2 * hx) - 2 * hy, 1)
    outs = [np.empty_like(a) for a in arrays]
    spectra: dict[tuple[int, int], np.ndarray] = {}
    for r0 in range(0, rows, core):
        r1 = min(rows, r0 + core)
        e0, e1 = max(0, r0 - hy), min(rows, r1 + hy)
        shape = (sfft.next_fast_len(e1 - e0 + 2 * hy, real=True), sfft.next_fast_len(cols + 2 * hx, real=True))
        kf = spectra.get(shape)
        if kf is None:
            kp = np.zeros(shape, np.float64)
            kp[: kernel.shape[0], : kernel.shape[1]] = kernel
            kf = spectra[shape] = sfft.rfft2(kp, workers=1)
        for a, o in zip(arrays, outs):
            o[r0:r1] = _conv_same(a[e0:e1], kf, shape, hy, hx)[r0 - e0: r1 - e0]
    return outs
