"""Example models, made procedurally so that they ship with the package."""

from __future__ import annotations

import numpy as np

from .testing import box_triangles, extrude_polygon

__all__ = ["gear_triangles", "write_binary_stl"]


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


def binary_stl_bytes(triangles: np.ndarray) -> bytes:
    """``(N, 3, 3)`` triangles (any float dtype, mm) as the bytes of a binary STL (normals from the winding)."""
    from .io.stl import BINARY_RECORD

    tri = np.asarray(triangles, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        ln = np.linalg.norm(n, axis=1, keepdims=True)
    rec = np.zeros(len(tri), dtype=BINARY_RECORD)
    rec["normal"] = np.divide(n, ln, out=np.zeros_like(n), where=np.isfinite(ln) & (ln > 0))
    rec["vertices"] = tri
    header = b"rotoprint binary STL".ljust(80, b" ")
    return header + np.uint32(len(tri)).tobytes() + rec.tobytes()


def write_binary_stl(path, triangles: np.ndarray) -> None:
    """Write ``(N, 3, 3)`` triangles as a binary STL (normals from the winding)."""
    with open(path, "wb") as fh:
        fh.write(binary_stl_bytes(triangles))
