"""Levelling on a coarse grid: restriction to and interpolation from it (numba kernels).

The coarse grid has a node per ``f x f`` block of deposit cells, its centre at the block's
centre, and one ghost node beyond each edge (node index ``= block index + 1``), so every
deposit cell lies between four nodes. Deposit cell ``(r, c)`` sits at coarse coordinate
``((r + 0.5) / f - 0.5, (c + 0.5) / f - 0.5)``; :func:`prolong_combine_jit` reads the coarse
fields there by bilinear interpolation ``Q`` and :func:`restrict_wet_jit` applies its adjoint
``Q^T`` (each wet cell spreads its value over the four nodes with the same weights). With
``f = 1`` both are the identity (on the nodes 1..n).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ._deposit_kernels import bin_add, bin_flush, column_products, neumaier_add, radial_bin

__all__ = ["axis_weights", "restrict_wet_jit", "prolong_combine_jit", "film_stats_jit"]


def axis_weights(n: int, f: int) -> tuple[np.ndarray, np.ndarray]:
    """For cells ``0..n-1`` of one axis, the lower coarse node ``(n,) int64`` (ghost-shifted)
    and the weight ``t`` of the upper one ``(n,) float64`` (the lower has ``1 - t``)."""
    u = (np.arange(n, dtype=np.float64) + 0.5) / f - 0.5
    i0 = np.floor(u)
    return i0.astype(np.int64) + 1, u - i0


@njit(cache=True, nogil=True, inline="always")
def _node_weight(cell, f):
    """Cell ``cell``'s lower coarse node (ghost-shifted) and the upper node's weight, as
    :func:`axis_weights` gives for a whole axis."""
    u = (cell + 0.5) / f - 0.5
    fy = math.floor(u)
    return int(fy) + 1, u - fy


@njit(cache=True, nogil=True, inline="always")
def _corner_weights(ty, tx):
    """The bilinear weights of the four nodes around a cell: (lower, lower), (lower, upper),
    (upper, lower), (upper, upper) in (row, column)."""
    return (1.0 - ty) * (1.0 - tx), (1.0 - ty) * tx, ty * (1.0 - tx), ty * tx


@njit(cache=True, nogil=True)
def restrict_wet_jit(film, row0, f, cx0, ctx, h_c, w_c):
    """Add ``Q^T`` of the wet film (``film > 0``) to ``h_c`` and of the wet indicator to
    ``w_c`` (both ``(Rc + 2, Cc + 2) float64``); ``film`` ``(rows, cols) float64`` holds grid
    rows ``row0..``; ``cx0, ctx`` from :func:`axis_weights` for the columns."""
    rows, cols = film.shape
    for i in range(rows):
        iy, ty = _node_weight(row0 + i, f)
        for j in range(cols):
            h = film[i, j]
            if h > 0.0:
                a = cx0[j]
                tx = ctx[j]
                w00, w01, w10, w11 = _corner_weights(ty, tx)
                h_c[iy, a] += w00 * h
                h_c[iy, a + 1] += w01 * h
                h_c[iy + 1, a] += w10 * h
                h_c[iy + 1, a + 1] += w11 * h
                w_c[iy, a] += w00
                w_c[iy, a + 1] += w01
                w_c[iy + 1, a] += w10
                w_c[iy + 1, a + 1] += w11


@njit(cache=True, nogil=True)
def prolong_combine_jit(film, row0, f, cx0, ctx, n_c, g_c, out):
    """The levelled film ``h (1 - N) + G`` on the wet cells of ``film`` (0 on dry ones) into
    ``out`` (the shape of ``film``), ``N`` and ``G`` interpolated (``Q``) from the coarse
    ``n_c`` and ``g_c``."""
    rows, cols = film.shape
    for i in range(rows):
        iy, ty = _node_weight(row0 + i, f)
        for j in range(cols):
            h = film[i, j]
            if h > 0.0:
                a = cx0[j]
                tx = ctx[j]
                w00, w01, w10, w11 = _corner_weights(ty, tx)
                n = w00 * n_c[iy, a] + w01 * n_c[iy, a + 1] + w10 * n_c[iy + 1, a] + w11 * n_c[iy + 1, a + 1]
                g = w00 * g_c[iy, a] + w01 * g_c[iy, a + 1] + w10 * g_c[iy + 1, a] + w11 * g_c[iy + 1, a + 1]
                out[i, j] = h * (1.0 - n) + g
            else:
                out[i, j] = 0.0


@njit(cache=True, nogil=True)
def film_stats_jit(lv, inter_bits, row0, geo, half_mean, acc, bins_sum, bins_n):
    """Accumulate the figures of film rows ``lv`` ``(rows, cols) float64`` (grid rows
    ``row0..``) without temporaries: ``acc`` ``(7,) float64`` holds the sum of every cell and
    its compensation, the interior's sum and its compensation, its thinnest, its cell count
    and its cells below ``half_mean``; ``bins_sum``, ``bins_n`` ``(B,)`` the interior per 1 mm
    of platform radius. ``inter_bits`` ``(rows, ceil(cols / 8)) uint8``: the interior mask
    packed as ``np.packbits`` (big-endian bits) packs it; ``geo`` ``(10,) float64``: grid
    origin ``ox, oy``, cells per pixel ``nx, ny``, the placement's inner radius, pitches, height
    (px) and ``cos, sin`` of its angle (the radius as ``Placement.to_platform`` computes it).
    Sums are compensated (Neumaier), so they do not depend on how the rows are split.
    """
    rows, cols = lv.shape
    ox, oy, nx, ny = geo[0], geo[1], geo[2], geo[3]
    r_in, px, py, hpx, ca, sa = geo[4], geo[5], geo[6], geo[7], geo[8], geo[9]
    # the accumulators in locals (registers), written back at the end; the radial bin's
    # arithmetic (radial_bin) with its per-column products computed once, and the bin being added to kept
    # in registers until the bin changes: the same operations in the same order
    a0, a1, a2, a3, a4, a5, a6 = acc[0], acc[1], acc[2], acc[3], acc[4], acc[5], acc[6]
    cax, sax = column_products(cols, ox, nx, r_in, px, ca, sa)
    cb = -1
    cs = 0.0
    cn = 0
    for i in range(rows):
        row = (i + row0 + 0.5 - oy) / ny
        yl = (hpx / 2.0 - row) * py
        say = sa * yl
        cay = ca * yl
        for j in range(cols):
            t = lv[i, j]
            a0, a1 = neumaier_add(a0, a1, t)  # a1 keeps what the sum lost
            if (inter_bits[i, j >> 3] >> (7 - (j & 7))) & 1:
                a2, a3 = neumaier_add(a2, a3, t)
                if t < a4:
                    a4 = t
                a5 += 1.0
                if t < half_mean:
                    a6 += 1.0
                cb, cs, cn = bin_add(radial_bin(cax[j] - say, sax[j] + cay), cb, cs, cn, bins_sum, bins_n, t)
    bin_flush(cb, cs, cn, bins_sum, bins_n)
    acc[0], acc[1], acc[2], acc[3], acc[4], acc[5], acc[6] = a0, a1, a2, a3, a4, a5, a6
