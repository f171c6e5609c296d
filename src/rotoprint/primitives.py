"""Triangle soups of simple solids (closed, outward-wound), used by the bundled examples and
pieces and by the test meshes of :mod:`rotoprint.testing`."""

from __future__ import annotations

import numpy as np

__all__ = ["box_triangles", "extrude_polygon"]


def box_triangles(size=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0)) -> np.ndarray:
    """``(12, 3, 3) float64`` triangles of an axis-aligned box with its min corner at ``origin``."""
    sx, sy, sz = size
    o = np.asarray(origin, dtype=np.float64)
    c = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float)
    v = c * [sx, sy, sz] + o
    f = np.array(
        [[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
         [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]]
    )
    return v[f]


def extrude_polygon(xy: np.ndarray, height: float, z0: float = 0.0) -> np.ndarray:
    """Triangles of a prism over a star-shaped polygon (counter-clockwise ``(N, 2)``),
    capped by fans from the vertex centroid."""
    xy = np.asarray(xy, dtype=np.float64)
    n = len(xy)
    c = xy.mean(axis=0)
    tris = []
    for i in range(n):
        a, b = xy[i], xy[(i + 1) % n]
        a0, b0, a1, b1 = [*a, z0], [*b, z0], [*a, z0 + height], [*b, z0 + height]
        tris += [[a0, b0, b1], [a0, b1, a1]]
        tris += [[[*c, z0], b0, a0], [[*c, z0 + height], a1, b1]]
    return np.asarray(tris, dtype=np.float64)
