"""Material colours of the build's composites and report."""

from __future__ import annotations

import numpy as np

__all__ = ["MATERIAL_COLOURS", "material_colour", "composite_image"]

#: RGB per material in composites (others get a colour from a fixed cycle).
MATERIAL_COLOURS = {"plaster": (214, 200, 170), "silver": (90, 96, 110), "epoxy": (230, 160, 40), "polyamide": (60, 160, 90)}
_CYCLE = [(200, 80, 80), (80, 120, 200), (150, 90, 180), (40, 170, 170)]


def material_colour(name: str, order: list[str]) -> tuple[int, int, int]:
    """RGB of material ``name``: from ``MATERIAL_COLOURS``, else from a fixed cycle by its
    position in ``order``, else grey."""
    return MATERIAL_COLOURS.get(name, _CYCLE[order.index(name) % len(_CYCLE)] if name in order else (128, 128, 128))


def composite_image(masks: dict[str, np.ndarray], order: list[str]) -> np.ndarray:
    """``(H, W, 3) uint8``: each material's pixels in its colour on white (later on top).

    Parameters
    ----------
    masks : dict of str to (H, W) bool
        Each material's pixels; all of the same shape. Must not be empty.
    order : list of str
        Drawing order; materials not in it are not drawn.

    Returns
    -------
    (H, W, 3) uint8 ndarray
        RGB; colours from ``MATERIAL_COLOURS``, else from a fixed cycle by position in
        ``order``.
    """
    shape = next(iter(masks.values())).shape
    img = np.full(shape + (3,), 255, np.uint8)
    for m in order:
        if m in masks:
            img[masks[m]] = material_colour(m, order)
    return img
