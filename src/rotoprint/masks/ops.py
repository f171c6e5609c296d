"""Mask operations: the paper's edge smoothing, ERM shift, inversion, mirroring, and the
first-layer (elephant-foot) inset. Plain functions on ``(H, W) uint8`` arrays; none of them
changes its input.
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError, ImageError

__all__ = [
    "smooth_mask",
    "erm_shift",
    "invert_mask",
    "mirror_mask",
    "inset_mask",
    "first_layer_offsets_um",
    "SMOOTH_KERNEL",
]

#: PIL's ``ImageFilter.SMOOTH``: this kernel divided by 13, the paper's edge smoothing.
SMOOTH_KERNEL = np.array([[1, 1, 1], [1, 5, 1], [1, 1, 1]], dtype=np.int32)


def _check_mask(mask: np.ndarray, name: str = "mask") -> np.ndarray:
    m = np.asarray(mask)
    if m.ndim != 2 or m.dtype != np.uint8:
        raise ImageError(f"{name} must be a 2-D uint8 array, got {m.ndim}-D {m.dtype}")
    return m


def smooth_mask(mask: np.ndarray) -> np.ndarray:
    """The paper's edge smoothing: PIL ``ImageFilter.SMOOTH``, reproduced bit for bit.

    Every pixel not on the image border becomes ``round(sum(kernel * window) / 13)`` with
    the kernel ``[[1, 1, 1], [1, 5, 1], [1, 1, 1]]`` (a sum never ends in .5 since 13 is
    odd); border pixels are copied unchanged, as PIL does.

    Parameters
    ----------
    mask : (H, W) uint8

    Returns
    -------
    (H, W) uint8

    Examples
    --------
    >>> m = np.zeros((5, 5), np.uint8); m[:, 2] = 255   # a one-pixel wall
    >>> smooth_mask(m)[2].tolist()                      # its peak drops to 7/13
    [0, 59, 137, 59, 0]
    """
    m = _check_mask(mask)
    out = m.copy()
    h, w = m.shape
    if h < 3 or w < 3:
        return out
    a = m.astype(np.int32)
    s = np.zeros((h - 2, w - 2), np.int32)
    for dr in range(3):
        for dc in range(3):
            s += SMOOTH_KERNEL[dr, dc] * a[dr : dr + h - 2, dc : dc + w - 2]
    out[1:-1, 1:-1] = ((2 * s + 13) // 26).astype(np.uint8)
    return out


def erm_shift(mask: np.ndarray, *, shift_px: tuple[int, int] = (1, 1), fill: int = 0) -> np.ndarray:
    """The second ERM copy: ``mask`` moved ``shift_px = (cols, rows)`` (right and down for
    positive values), vacated pixels set to ``fill``.

    Parameters
    ----------
    mask : (H, W) uint8
    shift_px : (int, int)
        ``(cols, rows)``; a shift as large as the mask leaves only ``fill``.
    fill : int
        Grey level of the vacated pixels.

    Returns
    -------
    (H, W) uint8 ndarray
        A new array; ``mask`` is not changed.

    Raises
    ------
    ImageError
        ``mask`` is not a 2-D uint8 array.

    Examples
    --------
    >>> erm_shift(np.array([[255, 0], [0, 0]], np.uint8)).tolist()
    [[0, 0], [0, 255]]
    """
    m = _check_mask(mask)
    dx, dy = (int(v) for v in shift_px)
    out = np.full_like(m, fill)
    h, w = m.shape
    if abs(dx) >= w or abs(dy) >= h:
        return out
    src_r = slice(max(0, -dy), h - max(0, dy))
    src_c = slice(max(0, -dx), w - max(0, dx))
    dst_r = slice(max(0, dy), h - max(0, -dy))
    dst_c = slice(max(0, dx), w - max(0, -dx))
    out[dst_r, dst_c] = m[src_r, src_c]
    return out


def invert_mask(mask: np.ndarray) -> np.ndarray:
    """``255 - mask``: black becomes exposure (for projectors that want it that way).

    Parameters
    ----------
    mask : (H, W) uint8

    Returns
    -------
    (H, W) uint8 ndarray
        A new array.

    Raises
    ------
    ImageError
        ``mask`` is not a 2-D uint8 array.
    """
    return np.subtract(np.uint8(255), _check_mask(mask))


def mirror_mask(mask: np.ndarray, *, mirror_x: bool = False, mirror_y: bool = False) -> np.ndarray:
    """Flip left-right (``mirror_x``) and/or top-bottom (``mirror_y``); a contiguous copy.

    Parameters
    ----------
    mask : (H, W) uint8
    mirror_x : bool
        Reverse the column order.
    mirror_y : bool
        Reverse the row order.

    Returns
    -------
    (H, W) uint8 ndarray
        C-contiguous; with neither flip, ``mask`` itself when it is already contiguous.

    Raises
    ------
    ImageError
        ``mask`` is not a 2-D uint8 array.
    """
    m = _check_mask(mask)
    if mirror_x:
        m = m[:, ::-1]
    if mirror_y:
        m = m[::-1, :]
    return np.ascontiguousarray(m)


def inset_mask(mask: np.ndarray, *, inset_mm: float, pitch_x_mm: float, pitch_y_mm: float) -> np.ndarray:
    """Move every edge of a mask inward by ``inset_mm`` (elephant-foot compensation).

    The signed distance of each pixel centre to the edge is estimated from the mask: for a
    pixel of grey level ``g`` (``0 < g < 255``) it is ``(g / 255 - 0.5)`` pixels (exact for
    a straight edge along the pixel grid, as coverage masks have); for a full pixel it is
    the Euclidean distance to the nearest non-full pixel plus that pixel's own estimate.
    The new grey level is ``clip(d - inset + 0.5 px, 0, 1)``. On binary masks (0/255) the
    edge is taken halfway between pixel centres, so the error is at most half a pixel; on
    coverage masks it is exact for grid-aligned edges and within half a pixel otherwise.

    Parameters
    ----------
    mask : (H, W) uint8
    inset_mm : float
        >= 0. Zero returns a copy.
    pitch_x_mm, pitch_y_mm : float
        Pixel size across columns and rows.

    Returns
    -------
    (H, W) uint8
        Binary in, binary out (a pixel stays when its estimated distance exceeds the inset).
    """
    from scipy import ndimage

    m = _check_mask(mask)
    if not (np.isfinite(inset_mm) and inset_mm >= 0):
        raise ConfigError(f"inset must be a finite number of mm >= 0, got {inset_mm}")
    if inset_mm == 0 or not m.any():
        return m.copy()
    pitch = 0.5 * (pitch_x_mm + pitch_y_mm)
    full = m == 255
    if full.all():
        return m.copy()
    g = m.astype(np.float64) / 255.0
    dist, (ir, ic) = ndimage.distance_transform_edt(full, sampling=(pitch_y_mm, pitch_x_mm), return_indices=True)
    sd_mm = np.where(full, dist + (g[ir, ic] - 0.5) * pitch, (g - 0.5) * pitch)
    binary = bool(np.isin(m, (0, 255)).all())
    if binary:
        return np.where(sd_mm > inset_mm, 255, 0).astype(np.uint8) & np.where(m > 0, 255, 0).astype(np.uint8)
    new = np.clip((sd_mm - inset_mm) / pitch + 0.5, 0.0, 1.0)
    new = np.minimum(new, g)
    return np.floor(new * 255.0 + 0.5).astype(np.uint8)


def first_layer_offsets_um(n_layers: int, *, first_layers: int, first_layer_offset_um: float) -> np.ndarray:
    """``(n_layers,) float64`` inset per layer: ``first_layer_offset_um`` on layer 0, fading
    linearly to zero over ``first_layers`` layers (layer ``i < N`` gets ``offset * (N - i) / N``).

    Parameters
    ----------
    n_layers : int
    first_layers : int
        ``N`` above, >= 0; 0 gives no inset on any layer.
    first_layer_offset_um : float
        Inset of layer 0, a finite number >= 0.

    Returns
    -------
    (n_layers,) float64 ndarray
        Inset in micrometres; zero from layer ``N`` on.

    Raises
    ------
    ConfigError
        ``first_layers < 0``, or ``first_layer_offset_um`` is negative or not finite.

    Examples
    --------
    >>> first_layer_offsets_um(5, first_layers=4, first_layer_offset_um=100).tolist()
    [100.0, 75.0, 50.0, 25.0, 0.0]
    """
    if first_layers < 0:
        raise ConfigError(f"first layers must be >= 0, got {first_layers}")
    if not (np.isfinite(first_layer_offset_um) and first_layer_offset_um >= 0):
        raise ConfigError(f"first-layer offset must be a finite number of um >= 0, got {first_layer_offset_um}")
    i = np.arange(n_layers, dtype=np.float64)
    if first_layers == 0:
        return np.zeros(n_layers)
    return np.where(i < first_layers, first_layer_offset_um * (first_layers - i) / first_layers, 0.0)
