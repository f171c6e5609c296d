"""Independent exact references for slicing tests: trimesh's plane section, shapely polygons.

Nothing here uses rotoprint's slicing code. Each connected shell is sectioned separately and
the shells' polygons are unioned (what the nonzero rule means for overlapping solids).
"""

from __future__ import annotations

import numpy as np
import shapely
import trimesh
from shapely.geometry import MultiPolygon, Polygon
from shapely.ops import unary_union


def shell_triangles(triangles: np.ndarray) -> list[np.ndarray]:
    tm = trimesh.Trimesh(**trimesh.triangles.to_kwargs(triangles), process=True)
    return [b.triangles for b in tm.split(only_watertight=False)]


def exact_section(triangles: np.ndarray, z: float, *, per_shell: bool = True):
    """The cross-section at height ``z`` as a shapely geometry (model XY, mm)."""
    groups = shell_triangles(triangles) if per_shell else [triangles]
    polys = []
    for tri in groups:
        tm = trimesh.Trimesh(**trimesh.triangles.to_kwargs(tri), process=True)
        if tm.volume < 0:
            tm.invert()
        sec = tm.section(plane_origin=[0, 0, z], plane_normal=[0, 0, 1])
        if sec is None:
            continue
        planar, _ = sec.to_2D(to_2D=np.eye(4))
        polys.extend(planar.polygons_full)
    if not polys:
        return Polygon()
    return unary_union(polys)


def pixel_centres_model(grid) -> tuple[np.ndarray, np.ndarray]:
    """Model XY of every pixel centre, each ``(H, W) float64``."""
    rows, cols = np.mgrid[0 : grid.height, 0 : grid.width]
    m = grid.pixel_to_model
    x = m[0, 0] * cols + m[0, 1] * rows + m[0, 2]
    y = m[1, 0] * cols + m[1, 1] * rows + m[1, 2]
    return x, y


def mismatches_beyond(image: np.ndarray, grid, geom, tol_mm: float = 1e-6) -> np.ndarray:
    """``(K, 2)`` (row, col) of pixels where ``image`` disagrees with point-in-``geom`` at the
    pixel centre and the centre is farther than ``tol_mm`` from the boundary."""
    x, y = pixel_centres_model(grid)
    inside = shapely.contains_xy(geom, x, y) if not geom.is_empty else np.zeros_like(x, bool)
    diff = np.argwhere(inside != (image > 0))
    if len(diff) == 0:
        return diff
    pts = shapely.points(x[diff[:, 0], diff[:, 1]], y[diff[:, 0], diff[:, 1]])
    d = shapely.distance(geom.boundary, pts) if not geom.is_empty else np.full(len(diff), np.inf)
    return diff[d > tol_mm]


__all__ = ["exact_section", "mismatches_beyond", "pixel_centres_model", "shell_triangles", "MultiPolygon"]
