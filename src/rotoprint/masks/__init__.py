"""DLP masks: exact coverage anti-aliasing, the paper's smoothing and ERM, first-layer
inset, inversion and mirroring, and the exposure check of thin features.

All functions are pure: arrays in, arrays out.
"""

from .coverage import coverage_fraction, coverage_mask, fraction_to_grey, fraction_to_grey_summed, segments_area_px
from .ops import (
    SMOOTH_KERNEL,
    erm_shift,
    first_layer_offsets_um,
    inset_mask,
    invert_mask,
    mirror_mask,
    smooth_mask,
)
from .exposure import FeatureExposure, exposure_table, feature_exposure, format_exposure_table, narrowest_kept_um
from .pipeline import FIRST_LAYER_OFFSET_MAX_UM, MODES, Mask, MaskOptions, check_first_layer_offset, iter_masks, render_layer

__all__ = [
    "coverage_fraction",
    "coverage_mask",
    "fraction_to_grey",
    "fraction_to_grey_summed",
    "segments_area_px",
    "smooth_mask",
    "erm_shift",
    "invert_mask",
    "mirror_mask",
    "inset_mask",
    "first_layer_offsets_um",
    "SMOOTH_KERNEL",
    "MODES",
    "FIRST_LAYER_OFFSET_MAX_UM",
    "check_first_layer_offset",
    "MaskOptions",
    "Mask",
    "iter_masks",
    "render_layer",
    "FeatureExposure",
    "feature_exposure",
    "exposure_table",
    "format_exposure_table",
    "narrowest_kept_um",
]
