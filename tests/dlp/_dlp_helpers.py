"""Shared helpers for the DLP tests: exact reference areas with shapely."""

from __future__ import annotations

import numpy as np
import shapely
from shapely.ops import polygonize, unary_union


def winding_at(points: np.ndarray, start: np.ndarray, end: np.ndarray) -> np.ndarray:
    """``(P,) int`` winding numbers of points w.r.t. closed oriented segments (crossing rule)."""
    px, py = points[:, 0][:, None], points[:, 1][:, None]
    x0, y0, x1, y1 = start[:, 0][None], start[:, 1][None], end[:, 0][None], end[:, 1][None]
    up = (y0 <= py) & (y1 > py)
    down = (y1 <= py) & (y0 > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        xc = x0 + (py - y0) * (x1 - x0) / (y1 - y0)
    right = xc > px
    return ((up & right).astype(int) - (down & right).astype(int)).sum(axis=1)


def nonzero_region(start: np.ndarray, end: np.ndarray):
    """The exact nonzero-rule region of closed segments, as a shapely geometry.

    The segments are noded (split at every crossing), the faces of the arrangement are
    built, and each face is kept when the winding number at an inner point is not zero.
    """
    lines = shapely.linestrings(np.stack([start, end], axis=1))
    noded = unary_union(lines)
    faces = list(polygonize(noded))
    if not faces:
        return shapely.Polygon()
    reps = np.array([[p.x, p.y] for p in (f.representative_point() for f in faces)])
    w = winding_at(reps, start, end)
    return unary_union([f for f, k in zip(faces, w) if k != 0])


def winding_regions(start: np.ndarray, end: np.ndarray):
    """``(nonzero, multiple)``: the nonzero-rule region of closed segments and the part of it
    covered more than once (``|winding| >= 2``: overlapping shells), as shapely geometries."""
    lines = shapely.linestrings(np.stack([start, end], axis=1))
    faces = list(polygonize(unary_union(lines)))
    if not faces:
        return shapely.Polygon(), shapely.Polygon()
    reps = np.array([[p.x, p.y] for p in (f.representative_point() for f in faces)])
    w = np.abs(winding_at(reps, start, end))
    return unary_union([f for f, k in zip(faces, w) if k != 0]), unary_union([f for f, k in zip(faces, w) if k >= 2])


def pixel_boxes_area(region, shape) -> np.ndarray:
    """``(H, W)`` exact area of ``region`` inside every pixel ``[c-.5, c+.5] x [r-.5, r+.5]``."""
    h, w = shape
    r, c = np.mgrid[0:h, 0:w]
    boxes = shapely.box(c.ravel() - 0.5, r.ravel() - 0.5, c.ravel() + 0.5, r.ravel() + 0.5)
    return shapely.area(shapely.intersection(boxes, region)).reshape(h, w)


def polygon_segments(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    xy = np.asarray(xy, dtype=np.float64)
    return xy, np.roll(xy, -1, axis=0)
