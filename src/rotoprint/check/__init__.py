"""Printability: walls and gaps below a device's minimum, features the raster loses, islands,
exposure, and the smallest wall and gap a device prints for sure. See ``docs/check.md``."""

from ._exposure import MASK_MODELS, mask_model, smooth_mask
from .core import KINDS, CheckReport, Finding, LayerCheck, check_layers, check_printability, compare_orientations, join_regions
from .limits import default_minimum_mm, device_limits, rotary_tracks
from .options import CheckOptions, CheckSettings
from .overlay import overlay_image

__all__ = [
    "check_printability",
    "CheckOptions",
    "CheckSettings",
    "check_layers",
    "compare_orientations",
    "join_regions",
    "CheckReport",
    "Finding",
    "LayerCheck",
    "KINDS",
    "device_limits",
    "default_minimum_mm",
    "rotary_tracks",
    "overlay_image",
    "MASK_MODELS",
    "mask_model",
    "smooth_mask",
]
