"""Exposure models for DLP masks, used by the check until :mod:`rotoprint.masks` is wired in.

A model turns a layer's binary image ``(H, W) uint8`` (255 material) into the grey mask the
projector shows, ``(H, W) uint8``. The check only needs that function: the lead merges the
real masks (coverage anti-aliasing, smoothing, ERM) by passing their function instead.
"""

from __future__ import annotations

import numpy as np
from PIL import Image, ImageFilter

from ..errors import ConfigError

__all__ = ["MASK_MODELS", "mask_model", "binary_mask", "smooth_mask"]


def binary_mask(image: np.ndarray) -> np.ndarray:
    """The binary image itself: every material pixel at full exposure."""
    return image


def smooth_mask(image: np.ndarray) -> np.ndarray:
    """The paper's edge smoothing: PIL ``ImageFilter.SMOOTH``, kernel
    ``[[1, 1, 1], [1, 5, 1], [1, 1, 1]] / 13``, on the binary image.

    Examples
    --------
    >>> im = np.zeros((5, 5), np.uint8); im[:, 2] = 255     # a one-pixel line
    >>> int(smooth_mask(im)[2, 2])                          # (5 + 1 + 1) / 13 of 255
    137
    """
    return np.asarray(Image.fromarray(image).filter(ImageFilter.SMOOTH), dtype=np.uint8)


MASK_MODELS = {"binary": binary_mask, "smooth": smooth_mask}


def mask_model(name: str):
    """The exposure model called ``name`` (one of :data:`MASK_MODELS`)."""
    try:
        return MASK_MODELS[name]
    except KeyError:
        raise ConfigError(f"mask model must be one of {', '.join(MASK_MODELS)}, got {name!r}") from None
