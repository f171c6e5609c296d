"""Example models, made procedurally so that they ship with the package."""

from __future__ import annotations

import numpy as np

from .io.stl import binary_stl_bytes, write_binary_stl  # noqa: F401
from .primitives import box_triangles, extrude_polygon

__all__ = ["gear_triangles", "write_binary_stl"]  # write_binary_stl: from rotoprint.io.stl, kept here for old imports


def gear_outline(teeth: int = 12, r_root_mm: float = 8.0, r_tip_mm: float = 10.0, per_tooth: int = 8) -> np.ndarray:
    """``(teeth * per_tooth, 2)`` counter-clockwise outline of a simple spur gear."""
    n = teeth * per_tooth
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    phase = (np.arange(n) % per_tooth) / per_tooth
    r = np.where((phase >= 0.25) & (phase < 0.75), r_tip_mm, r_root_mm)
    return np.stack([r * np.cos(t), r * np.sin(t)], axis=1)


def gear_triangles() -> np.ndarray:
    """A 20 mm spur gear plate (2 mm thick) with a hub that overlaps it (two shells that the
    nonzero rule unions) and a lug bar across the hub: the paper's plaster gear test shape."""
    plate = extrude_polygon(gear_outline(), 2.0, 0.0)
    t = np.linspace(0, 2 * np.pi, 48, endpoint=False)
    hub = extrude_polygon(np.stack([4.0 * np.cos(t), 4.0 * np.sin(t)], 1), 3.0, 1.0)
    bar = box_triangles((12.0, 2.0, 1.5), (-6.0, -1.0, 2.5))
    return np.concatenate([plate, hub, bar])
