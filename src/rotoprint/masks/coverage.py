"""Exact area coverage: each pixel's grey level is the fraction of its area inside the slice.

The slice is given as closed, oriented segments in continuous pixel coordinates ``(col,
row)`` (the centre of pixel ``(c, r)`` at ``(c, r)``), as :meth:`SliceJob.pixel_segments`
returns them. For every pixel the integral of the winding number over the pixel is computed
analytically (signed trapezoid areas accumulated per pixel row, then summed along the row);
for a polygon this is exact up to floating-point rounding (about 1e-12 of a pixel).

Overlapping shells (nonzero rule, winding 2 where two shells overlap) are handled by clamping
``|integral|`` to 1 per pixel. This is exact for every pixel except those crossed by the
boundaries of *two* shells that overlap inside that pixel; there the result overstates the
union's coverage by the overlap's area inside the pixel, so the error is at most one pixel
area per such pixel (and zero for pixels fully inside either shell). A shell wound the wrong
way (winding -1) counts as material like under the nonzero rule; where +1 and -1 regions
share a pixel they cancel within that pixel (the mesh loader re-orients shells, so this needs
an inconsistently wound mesh that repair could not fix). Even-odd filling is not supported.
"""

from __future__ import annotations

import numpy as np

from .._resources import check_raster_fits
from ..errors import ConfigError, GeometryError

__all__ = [
    "coverage_fraction",
    "coverage_mask",
    "accumulate_numpy",
    "segments_area_px",
    "fraction_to_grey",
    "fraction_to_grey_summed",
    "coverage_window",
    "BACKENDS",
]

BACKENDS = ("jit", "numpy")

#: Coverage within this of 0 or 1 is set to 0 or 1: the running sums along a row leave
#: residues of about 1e-16 per term where contributions cancel (outside or deep inside).
COVERAGE_SNAP: float = 1e-12


def _check_segments(start_px, end_px) -> tuple[np.ndarray, np.ndarray]:
    s = np.ascontiguousarray(start_px, dtype=np.float64)
    e = np.ascontiguousarray(end_px, dtype=np.float64)
    if s.ndim != 2 or s.shape[1:] != (2,) or s.shape != e.shape:
        raise GeometryError(
            f"segments must be two (S, 2) arrays of the same shape, got {s.shape} and {e.shape}"
        )
    if not (np.isfinite(s).all() and np.isfinite(e).all()):
        raise GeometryError("segment coordinates must be finite")
    return s, e


def _check_shape(shape) -> tuple[int, int]:
    try:
        h, w = (int(v) for v in shape)
    except (TypeError, ValueError):
        raise ConfigError(f"shape must be (height, width), got {shape!r}") from None
    if h <= 0 or w <= 0:
        raise ConfigError(f"shape must be positive (height, width), got {shape!r}")
    return h, w


def accumulate_numpy(x0, y0, x1, y1, height: int, width: int) -> np.ndarray:
    """Pure-numpy reference of the accumulation kernel: ``(height, width + 1) float64``.

    Same contract as ``_coverage_kernels.accumulate_jit`` (see that module's doc).

    Parameters
    ----------
    x0, y0, x1, y1 : (S,) float64
        Segment ends in continuous pixel coordinates (centre of pixel ``(c, r)`` at
        ``(c, r)``); not validated here.
    height, width : int
        Raster size.

    Returns
    -------
    (height, width + 1) float64 ndarray
        Per-row differences: the cumulative sum along a row of the first ``width`` columns
        is the signed winding integral over each pixel.
    """
    x0, y0, x1, y1 = (np.asarray(v, dtype=np.float64) + 0.5 for v in (x0, y0, x1, y1))
    acc = np.zeros((height, width + 1), np.float64)
    keep = y0 != y1
    x0, y0, x1, y1 = x0[keep], y0[keep], x1[keep], y1[keep]
    sign = np.where(y0 < y1, 1.0, -1.0)
    swap = y0 > y1
    xa = np.where(swap, x1, x0)
    ya = np.where(swap, y1, y0)
    xb = np.where(swap, x0, x1)
    yb = np.where(swap, y0, y1)
    vis = (yb > 0) & (ya < height)
    xa, ya, xb, yb, sign = xa[vis], ya[vis], xb[vis], yb[vis], sign[vis]
    if xa.size == 0:
        return acc
    r0 = np.where(ya > 0, np.floor(ya), 0).astype(np.int64)
    r1 = np.where(yb < height, np.ceil(yb), height).astype(np.int64)
    n = np.maximum(r1 - r0, 0)
    seg = np.repeat(np.arange(len(n)), n)
    r = r0[seg] + (np.arange(seg.size) - np.repeat(np.cumsum(n) - n, n))
    ya_s, yb_s, xa_s, xb_s = ya[seg], yb[seg], xa[seg], xb[seg]
    slope = (xb_s - xa_s) / (yb_s - ya_s)
    top = np.maximum(ya_s, r.astype(np.float64))
    bot = np.minimum(yb_s, r + 1.0)
    ok = bot > top
    seg, r, top, bot, ya_s, yb_s, xa_s, xb_s, slope = (
        v[ok] for v in (seg, r, top, bot, ya_s, yb_s, xa_s, xb_s, slope)
    )
    xt = np.where(top == ya_s, xa_s, np.where(top == yb_s, xb_s, xa_s + (top - ya_s) * slope))
    xbm = np.where(bot == yb_s, xb_s, xa_s + (bot - ya_s) * slope)
    d = sign[seg] * (bot - top)
    a = np.minimum(xt, xbm)
    b = np.maximum(xt, xbm)
    fa, fb = np.floor(a), np.floor(b)
    flat = acc.reshape(-1)
    row_base = r * (width + 1)
    left_of_image = fb < 0
    np.add.at(flat, row_base[left_of_image], d[left_of_image])
    inside = ~left_of_image & (fa < width)
    a, b, d, fa, fb, row_base = (v[inside] for v in (a, b, d, fa, fb, row_base))
    k0 = np.maximum(fa, 0).astype(np.int64)
    k1 = np.minimum(fb, width - 1).astype(np.int64)
    np.add.at(flat, row_base + k1 + 1, d)
    m = k1 - k0 + 1
    piece = np.repeat(np.arange(len(m)), m)
    k = k0[piece] + (np.arange(piece.size) - np.repeat(np.cumsum(m) - m, m))
    pa, pb, kf = a[piece], b[piece], k.astype(np.float64)
    length = pb - pa
    point = length <= 0
    left = np.clip(np.minimum(pb, kf) - pa, 0.0, None)
    lo = np.maximum(pa, kf)
    hi = np.minimum(pb, kf + 1.0)
    mid = np.where(hi > lo, (hi - lo) * (kf + 1.0 - 0.5 * (lo + hi)), 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(point, np.clip(kf + 1.0 - pa, 0.0, 1.0), (left + mid) / np.where(point, 1.0, length))
    c = d[piece] * frac
    np.add.at(flat, row_base[piece] + k, c)
    np.add.at(flat, row_base[piece] + k + 1, -c)
    return acc


def coverage_fraction(start_px, end_px, shape, *, backend: str = "jit") -> np.ndarray:
    """Fraction of every pixel's area inside the closed region the segments bound.

    Parameters
    ----------
    start_px, end_px : (S, 2) float64
        Oriented segments ``(col, row)`` in continuous pixel coordinates; the centre of
        pixel ``(c, r)`` is at ``(c, r)``. Together they must form closed loops.
    shape : (int, int)
        ``(height, width)`` of the raster.
    backend : {'jit', 'numpy'}
        The numba kernel or the pure-numpy reference; they agree to about 1e-12.

    Returns
    -------
    (H, W) float64
        Values in ``[0, 1]``; ``min(|integral of the winding number|, 1)`` per pixel (see
        the module doc for overlapping shells); within ``COVERAGE_SNAP`` (1e-12) of 0 or 1
        it is snapped to 0 or 1.

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])  # centres of 4 pixels
    >>> coverage_fraction(sq, np.roll(sq, -1, axis=0), (3, 3)).round(3).tolist()
    [[0.25, 0.5, 0.25], [0.5, 1.0, 0.5], [0.25, 0.5, 0.25]]
    """
    if backend not in BACKENDS:
        raise ConfigError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    s, e = _check_segments(start_px, end_px)
    h, w = _check_shape(shape)
    check_raster_fits(w, h, 8 + 8 + 1, what="coverage raster")
    if backend == "numpy":
        acc = accumulate_numpy(s[:, 0], s[:, 1], e[:, 0], e[:, 1], h, w)
        v = np.minimum(np.abs(np.cumsum(acc[:, :w], axis=1)), 1.0)
        v[v < COVERAGE_SNAP] = 0.0
        v[v > 1.0 - COVERAGE_SNAP] = 1.0
        return v
    from ._coverage_kernels import accumulate_jit, resolve_jit

    acc = np.zeros((h, w + 1), np.float64)
    accumulate_jit(
        np.ascontiguousarray(s[:, 0]), np.ascontiguousarray(s[:, 1]),
        np.ascontiguousarray(e[:, 0]), np.ascontiguousarray(e[:, 1]), h, w, acc,
    )
    return resolve_jit(acc, w, COVERAGE_SNAP, np.empty((h, w), np.float64))


def fraction_to_grey(fraction: np.ndarray) -> np.ndarray:
    """``(H, W) float`` fractions in [0, 1] to ``(H, W) uint8`` grey levels, round half up.

    Each grey level is within 0.5 / 255 of ``255 * fraction``.

    Parameters
    ----------
    fraction : array_like of float
        Coverage fractions, any shape; values outside [0, 1] are clipped.

    Returns
    -------
    uint8 ndarray
        ``floor(255 * fraction + 0.5)``, the shape of ``fraction``.
    """
    f = np.asarray(fraction, dtype=np.float64)
    return np.floor(np.clip(f, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)


def fraction_to_grey_summed(fraction: np.ndarray) -> np.ndarray:
    """``(H, W)`` fractions to ``uint8`` grey levels whose sum is the exact one to half a level.

    Sum-preserving rounding, deterministic: fractions within ``COVERAGE_SNAP`` of 0 or 1 are 0
    or 255; every other pixel, in row-major order, gets ``q = floor(x + carry + 0.5)`` with
    ``x = 255 * fraction`` and the rounding error carried so far, then ``carry += x - q``
    (the pure-numpy reference of the jit and C kernels, same operations). Each level is
    within one of ``x`` (1/255 of a pixel) and ``|sum(q) - sum(x)| <= 1/2``: the grey-sum
    area is the exact area to half a level of one pixel, whatever the number of edge pixels.

    Parameters
    ----------
    fraction : (H, W) array_like of float
        Coverage fractions in [0, 1] (values outside are clipped).

    Returns
    -------
    (H, W) uint8 ndarray

    Examples
    --------
    >>> fraction_to_grey_summed(np.full((1, 4), 0.5 / 255)).tolist()  # nearest: all 1, sum 4
    [[1, 0, 1, 0]]
    """
    f = np.clip(np.asarray(fraction, dtype=np.float64), 0.0, 1.0)
    out = np.where(f > 1.0 - COVERAGE_SNAP, 255, 0).astype(np.uint8)
    flat = out.reshape(-1)
    x = f.reshape(-1) * 255.0
    edge = np.flatnonzero((f.reshape(-1) >= COVERAGE_SNAP) & (f.reshape(-1) <= 1.0 - COVERAGE_SNAP))
    carry = 0.0
    for i, xi in zip(edge.tolist(), x[edge].tolist()):
        q = float(np.floor(xi + carry + 0.5))
        q = min(max(q, 0.0), 255.0)
        carry += xi - q
        flat[i] = int(q)
    return out


def coverage_mask(start_px, end_px, shape, *, backend: str = "jit") -> np.ndarray:
    """``(H, W) uint8`` mask of grey levels ``255 * coverage`` rounded so that their sum is
    the exact area to half a level (:func:`fraction_to_grey_summed`); see
    :func:`coverage_fraction`.

    Parameters
    ----------
    start_px, end_px : (S, 2) float64
        Oriented segments ``(col, row)`` in continuous pixel coordinates, forming closed loops.
    shape : (int, int)
        ``(height, width)`` of the mask.
    backend : {'jit', 'numpy'}
        The numba kernels (working in the segments' bounding window) or the pure-numpy
        reference followed by :func:`fraction_to_grey_summed` (they can differ by one level
        in a pixel where the two coverages, equal to about 1e-12, round apart).

    Returns
    -------
    (H, W) uint8 ndarray

    Raises
    ------
    ConfigError
        Unknown ``backend``, or ``shape`` is not two positive integers.
    GeometryError
        ``start_px`` and ``end_px`` are not two ``(S, 2)`` arrays of the same shape, or hold
        a non-finite coordinate.
    RasterTooLargeError
        The raster would not fit in the available memory.

    Examples
    --------
    >>> import numpy as np
    >>> sq = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    >>> m = coverage_mask(sq, np.roll(sq, -1, axis=0), (3, 3))  # exact: 63.75, 127.5, 255
    >>> m.tolist(), int(m.sum()) == 4 * 255  # a square of 4 pixels: its grey sum is exact
    ([[64, 127, 64], [128, 255, 127], [64, 127, 64]], True)
    """
    if backend != "jit":
        return fraction_to_grey_summed(coverage_fraction(start_px, end_px, shape, backend=backend))
    h, w = _check_shape(shape)
    check_raster_fits(w, h, 8 + 1, what="coverage raster")
    out = np.zeros((h, w), np.uint8)
    r0, c0, win, tail = coverage_window(start_px, end_px, (h, w))
    if win.size:
        out[r0 : r0 + win.shape[0], c0 : c0 + win.shape[1]] = win
        if tail is not None:
            out[r0 : r0 + win.shape[0], c0 + win.shape[1] :] = tail[:, None]
    return out


def coverage_window(start_px, end_px, shape) -> tuple[int, int, np.ndarray, np.ndarray | None]:
    """The part of :func:`coverage_mask` that can be non-zero: its bounding window.

    Parameters
    ----------
    start_px, end_px : (S, 2) float64
        Oriented segments, as for :func:`coverage_mask`.
    shape : (int, int)
        ``(height, width)`` of the whole mask.

    Returns
    -------
    r0, c0 : int
        Row and column of the window's first pixel in the mask.
    window : (hh, ww) uint8 ndarray
        The mask's pixels ``[r0 : r0 + hh, c0 : c0 + ww]``; every pixel outside the window's
        rows is 0, and so is every pixel left of it.
    tail : (hh,) uint8 ndarray or None
        The level of the pixels right of the window in each of its rows (their total
        winding): None when they are all 0, as for closed loops.

    Raises
    ------
    ConfigError, GeometryError, RasterTooLargeError
        As :func:`coverage_mask`.
    """
    s, e = _check_segments(start_px, end_px)
    h, w = _check_shape(shape)
    empty = (0, 0, np.zeros((0, 0), np.uint8), None)
    if s.shape[0] == 0:
        return empty
    # Work in the segments' bounding window only: rows outside it have no crossings, and
    # columns left of it are fully inside or outside per row, which the kernel handles by
    # folding everything left of the window into its first column.
    ys = np.concatenate([s[:, 1], e[:, 1]])
    xs = np.concatenate([s[:, 0], e[:, 0]])
    r0 = int(max(0, np.floor(ys.min() + 0.5)))
    r1 = int(min(h, np.floor(ys.max() + 0.5) + 1))
    c0 = int(max(0, np.floor(xs.min() + 0.5)))
    c1 = int(min(w, np.floor(xs.max() + 0.5) + 1))
    if r1 <= r0 or c1 <= c0:
        # nothing crosses the image rows, or all of it lies left or right of the image
        if r1 > r0 and c0 >= w:
            return empty
        if r1 > r0:  # all left of the image: whole rows may be inside
            c0, c1 = 0, w
        else:
            return empty
    hh, ww = r1 - r0, c1 - c0
    check_raster_fits(ww + 1, hh, 8 + 1, what="coverage window")
    args = (np.ascontiguousarray(s[:, 0] - c0), np.ascontiguousarray(s[:, 1] - r0),
            np.ascontiguousarray(e[:, 0] - c0), np.ascontiguousarray(e[:, 1] - r0))
    from .._accel import native

    if native is not None:
        win = np.empty((hh, ww), np.uint8)
        tail = np.empty(hh, np.uint8)
        native.coverage(*args, hh, ww, win, tail)
    else:
        from ._coverage_kernels import accumulate_jit, resolve_grey_jit, resolve_nearest_jit

        acc = np.zeros((hh, ww + 1), np.float64)
        accumulate_jit(*args, hh, ww, acc)
        win = resolve_grey_jit(acc, ww, COVERAGE_SNAP, np.empty((hh, ww), np.uint8))
        # right of the window every row carries its total winding (0 for closed loops)
        tail = resolve_nearest_jit(np.ascontiguousarray(acc.sum(axis=1, keepdims=True)), 1, np.empty((hh, 1), np.uint8))[:, 0]
    if c1 >= w or not tail.any():
        tail = None
    return r0, c0, win, tail


def segments_area_px(start_px, end_px) -> float:
    """Signed area (square pixels) the closed segments bound: shoelace sum over segments.

    Positive for loops counter-clockwise in ``(col, row)`` axes (clockwise as an image is
    viewed, rows down).

    Parameters
    ----------
    start_px, end_px : (S, 2) float64
        Segment start and end points ``(col, row)``.

    Returns
    -------
    float
        ``0.5 * sum(x0 * y1 - x1 * y0)``, in square pixels.

    Raises
    ------
    GeometryError
        ``start_px`` and ``end_px`` are not two ``(S, 2)`` arrays of the same shape, or hold
        a non-finite coordinate.
    """
    s, e = _check_segments(start_px, end_px)
    return float(0.5 * np.sum(s[:, 0] * e[:, 1] - e[:, 0] * s[:, 1]))
