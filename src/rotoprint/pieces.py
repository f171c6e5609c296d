"""Generated test pieces with features of known width, like the paper's DLP test part.

The paper's part is 10 mm square and 1.6 mm high with concentric rings and fine walls and
channels; it lost walls of 10-50 microns to edge smoothing. :func:`feature_test_piece`
makes such a part, and says where every feature is and how wide it is, so that printability
checks and exposure checks can be tested against known answers.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .primitives import box_triangles

__all__ = ["Feature", "feature_test_piece", "DEFAULT_WIDTHS_MM", "annulus_prism"]

#: Wall and channel widths of the default piece, 10 to 200 microns.
DEFAULT_WIDTHS_MM: tuple[float, ...] = (0.010, 0.020, 0.030, 0.040, 0.050, 0.075, 0.100, 0.150, 0.200)


@dataclass(frozen=True)
class Feature:
    """One feature of known width.

    ``kind`` is ``'wall'`` (material between two empty sides), ``'channel'`` (empty between
    two material sides), ``'ring_wall'`` or ``'ring_gap'``. Straight features are the box
    ``[x0, x1] x [y0, y1]`` (mm, model frame; the width runs along x); ring features are the
    annulus of radii ``[r_in, r_out]`` about ``centre``. All span ``z0..z1``.
    """

    kind: str
    width_mm: float
    x0: float = 0.0
    x1: float = 0.0
    y0: float = 0.0
    y1: float = 0.0
    centre: tuple[float, float] = (0.0, 0.0)
    r_in: float = 0.0
    r_out: float = 0.0
    z0: float = 0.0
    z1: float = 0.0

    def to_json(self) -> dict:
        return asdict(self)


def annulus_prism(centre, r_in: float, r_out: float, z0: float, z1: float, n: int = 360) -> np.ndarray:
    """``(8 n, 3, 3)`` outward triangles of a ring prism (polygons of ``n`` sides)."""
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    cx, cy = centre
    co, so = np.cos(t), np.sin(t)
    tris = []
    for i in range(n):
        j = (i + 1) % n
        oi = (cx + r_out * co[i], cy + r_out * so[i])
        oj = (cx + r_out * co[j], cy + r_out * so[j])
        ii = (cx + r_in * co[i], cy + r_in * so[i])
        ij = (cx + r_in * co[j], cy + r_in * so[j])
        # outer wall (outward), inner wall (facing the axis), top and bottom
        tris += [[(*oi, z0), (*oj, z0), (*oj, z1)], [(*oi, z0), (*oj, z1), (*oi, z1)]]
        tris += [[(*ii, z0), (*ij, z1), (*ij, z0)], [(*ii, z0), (*ii, z1), (*ij, z1)]]
        tris += [[(*ii, z1), (*oj, z1), (*ij, z1)], [(*ii, z1), (*oi, z1), (*oj, z1)]]
        tris += [[(*ii, z0), (*ij, z0), (*oj, z0)], [(*ii, z0), (*oj, z0), (*oi, z0)]]
    return np.asarray(tris, dtype=np.float64)


def feature_test_piece(
    widths_mm: tuple[float, ...] = DEFAULT_WIDTHS_MM,
    *,
    size_mm: float = 10.0,
    height_mm: float = 1.6,
    base_mm: float = 0.4,
    ring_segments: int = 720,
) -> tuple[np.ndarray, list[Feature]]:
    """The test piece as ``(N, 3, 3) float64`` triangles, and its features.

    A ``size_mm`` square base plate ``base_mm`` thick carries, up to ``height_mm``:

    - a row of free-standing straight walls, one per width, 3 mm long, 0.4 mm apart;
    - a row of 0.3 mm blocks separated by straight channels, one per width;
    - concentric ring walls of each width about (7.5, 2.5), 0.12 mm apart;
    - concentric ring gaps of each width between 0.12 mm ring walls about (7.5, 7.5).

    The parts are separate closed shells that overlap or touch (the nonzero rule unions them).
    """
    w = tuple(float(x) for x in widths_mm)
    z0, z1 = base_mm, height_mm
    tris = [box_triangles((size_mm, size_mm, base_mm), (0.0, 0.0, 0.0))]
    feats: list[Feature] = []
    # free-standing walls, along y, widths along x
    x = 0.5
    for wi in w:
        tris.append(box_triangles((wi, 3.0, z1 - z0), (x, 0.5, z0)))
        feats.append(Feature("wall", wi, x0=x, x1=x + wi, y0=0.5, y1=3.5, z0=z0, z1=z1))
        x += wi + 0.4
    # channels between 0.3 mm blocks
    x = 0.5
    block = 0.3
    tris.append(box_triangles((block, 3.0, z1 - z0), (x, 4.5, z0)))
    x += block
    for wi in w:
        feats.append(Feature("channel", wi, x0=x, x1=x + wi, y0=4.5, y1=7.5, z0=z0, z1=z1))
        x += wi
        tris.append(box_triangles((block, 3.0, z1 - z0), (x, 4.5, z0)))
        x += block
    # concentric rings: ring walls about one centre, ring gaps about another
    sep = 0.12
    c = (7.5, 2.5)
    r = 0.2
    for wi in w:  # ring walls separated by `sep` gaps
        tris.append(annulus_prism(c, r, r + wi, z0, z1, ring_segments))
        feats.append(Feature("ring_wall", wi, centre=c, r_in=r, r_out=r + wi, z0=z0, z1=z1))
        r += wi + sep
    c2 = (7.5, 7.5)
    r = 0.2
    tris.append(annulus_prism(c2, r, r + sep, z0, z1, ring_segments))
    r += sep
    for wi in w:  # ring gaps between `sep` ring walls
        feats.append(Feature("ring_gap", wi, centre=c2, r_in=r, r_out=r + wi, z0=z0, z1=z1))
        r += wi
        tris.append(annulus_prism(c2, r, r + sep, z0, z1, ring_segments))
        r += sep
    if r > 2.45 or x > size_mm / 2:
        raise ValueError("the features do not fit the plate; use fewer or narrower widths")
    return np.concatenate(tris), feats
