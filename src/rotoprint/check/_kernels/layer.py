"""The whole check of one layer in one call (:func:`check_layer`): the layer's material as runs,
the widths measured on the (simplified) section, the selections against the thresholds, the
raster tests on the runs, and the islands over the layer below."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from .raster import _absent_runs
from .runs import _island_stats, section_runs
from .widths import measure_widths


class LayerParams(NamedTuple):
    """What :func:`check_layer` needs that is fixed for a job (model mm unless named).

    ``uv`` is the slicer's ``(2, 3) float64`` model-to-pixel affine (its fill's crossings are
    recomputed as runs), ``height, width`` the grid in pixels, ``evenodd`` the fill rule;
    ``cell_mm`` the ray cells' smallest side, ``near_mm`` the distance under which segments of
    different chains are classified one by one, ``side_eps_mm`` the side offset at which the
    fill rule is evaluated, ``spacing_mm`` the largest distance between samples, ``max_mm`` the
    width up to which the smallest is measured, ``tmin_mm`` the nearest hit a ray counts;
    ``need_wall_mm, need_gap_mm`` the widths measured exactly below them, ``min_wall_mm,
    min_gap_mm`` the thresholds, ``raster_lim_mm`` the width below which chords are tested
    against the raster; ``p2m, m2p`` the grid's ``(2, 3) float64`` affines, ``pitch_mm`` the
    larger pixel pitch (the chords' half length along the boundary in the raster test).
    """

    uv: np.ndarray
    height: int
    width: int
    evenodd: bool
    cell_mm: float
    near_mm: float
    side_eps_mm: float
    spacing_mm: float
    max_mm: float
    tmin_mm: float
    need_wall_mm: float
    need_gap_mm: float
    min_wall_mm: float
    min_gap_mm: float
    raster_lim_mm: float
    p2m: np.ndarray
    m2p: np.ndarray
    pitch_mm: float


class LayerResult(NamedTuple):
    """What :func:`check_layer` finds in one layer.

    ``samples`` is ``(7, P) float64``: per boundary sample its x, y (mm), inward normal x, y,
    the boundary length it stands for, its wall and its gap width (``inf``: none below what
    was measured). ``thinnest``, ``narrowest`` index the smallest wall and gap (-1: none);
    ``thin``, ``narrow`` ``(n,) int64`` the samples of walls below the minimum wall and gaps
    below the minimum gap, ``vanished``, ``closed`` those (below the raster limit) whose chord
    holds no material / no empty pixel centre. ``rs, r0, r1`` are the layer's runs of material
    (``(H + 1,)`` row starts into ``(R,)`` first and past-last columns, int64), ``islands``
    ``(7, I) float64`` per island (pixels, mean row, mean column, first and last row, first
    and last column) and ``island_of_run`` ``(R,) int64`` the island of every run (-1:
    supported).
    """

    samples: np.ndarray
    thinnest: int
    narrowest: int
    thin: np.ndarray
    narrow: np.ndarray
    vanished: np.ndarray
    closed: np.ndarray
    rs: np.ndarray
    r0: np.ndarray
    r1: np.ndarray
    islands: np.ndarray
    island_of_run: np.ndarray


def check_layer(section, measured, below_runs, below: bool, params: LayerParams) -> LayerResult:
    """The whole check of one layer, without its image.

    Parameters
    ----------
    section : tuple of (S, 2) float64
        The section's segment starts and ends (model mm): the layer's material as runs is its
        fill (:func:`~.runs.section_runs`, equal to the slicer's image).
    measured : tuple of (M, 2) float64
        The segments the widths are measured on: the section, or the section simplified by
        :func:`~.simplify.simplify_section`.
    below_runs : tuple of int64 arrays
        The runs ``(ps, p0, p1)`` of the layer below (empty when ``below`` is false).
    below : bool
        Look for islands over ``below_runs`` (false on the first layer, or islands off).
    params : LayerParams

    Returns
    -------
    LayerResult
    """
    p = params
    out = _check_layer(
        section[0], section[1], measured[0], measured[1], p.uv, p.height, p.width, p.evenodd, below_runs[0], below_runs[1], below_runs[2], below,
        p.cell_mm, p.near_mm, p.side_eps_mm, p.spacing_mm, p.max_mm, p.tmin_mm, p.need_wall_mm, p.need_gap_mm, p.min_wall_mm, p.min_gap_mm,
        p.raster_lim_mm, p.p2m, p.m2p, p.pitch_mm,
    )
    return LayerResult(*out)


@njit(cache=True, nogil=True)
def _below(width, lim):  # pragma: no cover - jit
    n = 0
    for i in range(width.shape[0]):
        if width[i] < lim:
            n += 1
    out = np.empty(n, np.int64)
    n = 0
    for i in range(width.shape[0]):
        if width[i] < lim:
            out[n] = i
            n += 1
    return out


@njit(cache=True, nogil=True)
def _argmin_finite(width):  # pragma: no cover - jit
    """Index of the first smallest finite width, or -1 (as ``np.argmin`` on finite data)."""
    best = np.inf
    k = -1
    for i in range(width.shape[0]):
        if width[i] < best:
            best = width[i]
            k = i
    return k


@njit(cache=True, nogil=True)
def _check_layer(start, end, wstart, wend, uv, H, W, evenodd, ps, p0, p1, below, cell_mm, near_mm, side_eps, spacing, max_mm, tmin, need_wall, need_gap, min_wall, min_gap, raster_lim, p2m, m2p, pmax):  # pragma: no cover - jit
    """:func:`check_layer` with its parameters spread out (numba takes arrays and scalars):
    the fields of :class:`LayerResult`, in order. The runs are :func:`section_runs` of
    ``start, end``; the widths are measured on ``wstart, wend``, the raster tests made on the
    runs (:func:`~.raster.chord_presence_runs`), the islands found when ``below``."""
    rs, r0, r1 = section_runs(start, end, uv, H, W, evenodd)
    if wstart.shape[0] > 0:
        bx, by, ux, uy, ln, wall, gap = measure_widths(wstart, wend, cell_mm, near_mm, evenodd, side_eps, spacing, max_mm, tmin, need_wall, need_gap)
    else:
        bx = by = ux = uy = ln = wall = gap = np.zeros(0)
    iw = _argmin_finite(wall)
    ig = _argmin_finite(gap)
    thin = _below(wall, min_wall)
    narrow = _below(gap, min_gap)
    vanished = _absent_runs(_below(wall, raster_lim), 1.0, bx, by, ux, uy, wall, rs, r0, r1, H, W, 255, p2m, m2p, pmax)
    closed = _absent_runs(_below(gap, raster_lim), -1.0, bx, by, ux, uy, gap, rs, r0, r1, H, W, 0, p2m, m2p, pmax)
    S = np.empty((7, bx.shape[0]))
    S[0] = bx
    S[1] = by
    S[2] = ux
    S[3] = uy
    S[4] = ln
    S[5] = wall
    S[6] = gap
    st, isl = _island_stats(rs, r0, r1, ps, p0, p1, below)
    return S, iw, ig, thin, narrow, vanished, closed, rs, r0, r1, st, isl
