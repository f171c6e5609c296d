"""Uniform cells over a section and the ray primitives on them: the x-extent of a segment
clipped to a band, the cells a segment spans, the cell size for a segment count, a ray's
grid walk set-up (DDA) and the ray-segment hit test."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


_PARALLEL_EPS = 1e-15


@njit(cache=True, nogil=True, inline="always")
def _cell_index(v, n):  # pragma: no cover - jit
    """``floor(v)`` clamped to ``0 .. n - 1``, the float clamped before the int conversion (a
    float past int64, from a width of 1e19 mm, would wrap to any index); NaN gives 0."""
    if not v > 0.0:
        return 0
    if v >= n - 1:
        return n - 1
    return int(v)


@njit(cache=True, nogil=True, inline="always")
def _clip_x(ax, ay, bx, by, y0, y1, lo, hi):  # pragma: no cover - jit
    """``lo, hi`` widened by the x extent of the edge from ``(ax, ay)`` to ``(bx, by)`` within
    the band ``y0 <= y <= y1`` (unchanged when the edge misses the band)."""
    if max(ay, by) < y0 or min(ay, by) > y1:
        return lo, hi
    if ay == by:
        return min(lo, ax, bx), max(hi, ax, bx)
    f0 = min(1.0, max(0.0, (y0 - ay) / (by - ay)))
    f1 = min(1.0, max(0.0, (y1 - ay) / (by - ay)))
    x0 = ax + f0 * (bx - ax)
    x1 = ax + f1 * (bx - ax)
    return min(lo, x0, x1), max(hi, x0, x1)


@njit(cache=True, nogil=True, inline="always")
def _span(ax, ay, bx, by, gr, x0, y0, h, ncx, pad):  # pragma: no cover - jit
    """The first and last column of the cells in row ``gr`` (cells of side ``h`` from
    ``(x0, y0)``) that the segment from ``(ax, ay)`` to ``(bx, by)``, grown by ``pad``,
    touches; first > last when it misses the row."""
    yb = y0 + gr * h - pad
    lo, hi = _clip_x(ax, ay, bx, by, yb, yb + h + 2.0 * pad, np.inf, -np.inf)
    if lo > hi:
        return 0, -1
    c0 = _cell_index((lo - pad - x0) / h, ncx)
    c1 = _cell_index((hi + pad - x0) / h, ncx)
    return c0, c1


@njit(cache=True, nogil=True)
def _cell_size(w, h, n, cell_mm):  # pragma: no cover - jit
    """Cell side for ``n`` segments over a ``w`` x ``h`` mm box: ``cell_mm``, or larger so that
    there are not many more cells than segments (and never more than four million)."""
    c = max(cell_mm, 1e-9, math.sqrt(max(w * h, 0.0) / (4.0 * max(n, 1))))
    while (w / c + 1) * (h / c + 1) > 4e6:
        c *= 2.0
    return c


@njit(cache=True, nogil=True, inline="always")
def _dda_start(ox, oy, dx, dy, xmin, ymin, h):  # pragma: no cover - jit
    """A ray's start in a grid of cells of side ``h`` from ``(xmin, ymin)``: its cell, its
    steps, the ray lengths to the next cell boundary in x and y and between boundaries."""
    cx = int(math.floor((ox - xmin) / h))
    cy = int(math.floor((oy - ymin) / h))
    if dx > 0.0:
        stx = 1
        tmx = (xmin + (cx + 1) * h - ox) / dx
        tdx = h / dx
    elif dx < 0.0:
        stx = -1
        tmx = (xmin + cx * h - ox) / dx
        tdx = -h / dx
    else:
        stx = 0
        tmx = np.inf
        tdx = np.inf
    if dy > 0.0:
        sty = 1
        tmy = (ymin + (cy + 1) * h - oy) / dy
        tdy = h / dy
    elif dy < 0.0:
        sty = -1
        tmy = (ymin + cy * h - oy) / dy
        tdy = -h / dy
    else:
        sty = 0
        tmy = np.inf
        tdy = np.inf
    return cx, cy, stx, sty, tmx, tmy, tdx, tdy


@njit(cache=True, nogil=True, inline="always")
def _hit(ox, oy, dx, dy, a0, b0, a1, b1, tmin, tmax):  # pragma: no cover - jit
    """Distance along unit ``(dx, dy)`` from ``(ox, oy)`` to the segment ``(a0, b0)``-
    ``(a1, b1)`` when it is in ``(tmin, tmax]``, else ``inf`` (parallel, missed or out of
    range). The one hit test of every ray kernel."""
    e0 = a1 - a0
    e1 = b1 - b0
    den = dx * e1 - dy * e0
    if abs(den) <= _PARALLEL_EPS * (abs(e0) + abs(e1)):
        return np.inf
    w0 = a0 - ox
    w1 = b0 - oy
    t = (w0 * e1 - w1 * e0) / den
    if t <= tmin or t > tmax:
        return np.inf
    sp = (w0 * dy - w1 * dx) / den
    if sp < 0.0 or sp > 1.0:
        return np.inf
    return t
