"""Overlay images: a layer's material in grey with each problem painted in its own colour."""

from __future__ import annotations

import numpy as np

from . import _kernels as K
from .core import KINDS, LayerCheck

__all__ = ["COLOURS", "overlay_image"]

#: RGB colour of each problem kind.
COLOURS: dict[str, tuple[int, int, int]] = {
    "thin_wall": (230, 30, 30),
    "narrow_gap": (40, 90, 255),
    "vanished_wall": (255, 0, 255),
    "closed_gap": (0, 220, 220),
    "island": (255, 210, 0),
    "underexposed": (255, 140, 0),
    "cured_gap": (0, 200, 60),
    "cavity": (170, 80, 255),
}


def overlay_image(lc: LayerCheck, *, material_grey: int = 110) -> np.ndarray:
    """``(H, W, 3) uint8``: material grey on black, islands then chords of each kind on top
    (later kinds in :data:`KINDS` over earlier ones)."""
    img = lc.image
    out = np.zeros(img.shape + (3,), np.uint8)
    out[img > 0] = material_grey
    if lc.islands is not None:
        out[lc.islands] = COLOURS["island"]
    for kind in KINDS:
        ch = lc.chords.get(kind)
        if ch is None or not len(ch):
            continue
        mask = np.zeros(img.shape, np.uint8)
        c = np.ascontiguousarray
        K.paint_chords(c(ch[:, 0]), c(ch[:, 1]), c(ch[:, 2]), c(ch[:, 3]), mask, 1)
        out[mask > 0] = COLOURS[kind]
    return out
