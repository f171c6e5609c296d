"""Exposure models for DLP masks: what the projector shows for a layer's binary image.

A model turns a layer's binary image ``(H, W) uint8`` (255 material) into the grey mask the
projector shows, ``(H, W) uint8``; the paper's smoothing is :func:`rotoprint.masks.smooth_mask`.
(Coverage masks are made from the exact outline, not from the binary image: the check's
exposure of coverage masks is in :mod:`rotoprint.masks.exposure`.)
"""

from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from ..masks.ops import smooth_mask

__all__ = ["MASK_MODELS", "mask_model", "binary_mask", "smooth_mask"]


def binary_mask(image: np.ndarray) -> np.ndarray:
    """The binary image itself: every material pixel at full exposure."""
    return image


MASK_MODELS = {"binary": binary_mask, "smooth": smooth_mask}


def mask_model(name: str):
    """The exposure model called ``name`` (one of :data:`MASK_MODELS`)."""
    try:
        return MASK_MODELS[name]
    except KeyError:
        raise ConfigError(f"mask model must be one of {', '.join(MASK_MODELS)}, got {name!r}") from None
