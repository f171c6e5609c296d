"""Built-in generated shapes for job files: boxes, cylinders, a planar square-spiral coil and
an interdigitated electrode (IDE), with named terminal pads.

Shapes are unions of closed, axis-aligned prisms (overlapping shells; the slicer's nonzero
rule unions them), so they need no mesh file and ship with the package. Every shape gives
``(N, 3, 3) float64`` triangles in millimetres and named terminal rectangles
``(x0, y0, x1, y1)`` in model XY for the resistance estimate.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from ..ranges import COORD_MM
from ..testing import box_triangles, extrude_polygon

__all__ = ["BoxShape", "CylinderShape", "SquareCoilShape", "InterdigitatedShape", "Shape", "coil_centreline"]


_MAX_MM = COORD_MM.hi  # every length and coordinate of a shape: within rotoprint.ranges.COORD_MM
_Mm = Annotated[float, Field(ge=COORD_MM.lo, le=COORD_MM.hi)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


def _box_xy(x0: float, y0: float, x1: float, y1: float, z0: float, h: float) -> np.ndarray:
    return box_triangles((x1 - x0, y1 - y0, h), (x0, y0, z0))


class BoxShape(_Strict):
    """An axis-aligned box with its min corner at ``origin_mm``."""

    kind: Literal["box"]
    size_mm: tuple[_Mm, _Mm, _Mm]
    origin_mm: tuple[_Mm, _Mm, _Mm] = (0.0, 0.0, 0.0)

    @model_validator(mode="after")
    def _pos(self) -> BoxShape:
        if not all(v > 0 and math.isfinite(v) for v in self.size_mm):
            raise ValueError(f"size_mm must be three positive numbers, got {list(self.size_mm)}")
        return self

    def triangles(self) -> np.ndarray:
        return box_triangles(self.size_mm, self.origin_mm)

    def terminals(self) -> dict[str, tuple[float, float, float, float]]:
        x, y, _ = self.origin_mm
        sx, sy, _ = self.size_mm
        e = 1e-6
        return {"xmin": (x - e, y, x + e, y + sy), "xmax": (x + sx - e, y, x + sx + e, y + sy)}


class CylinderShape(_Strict):
    """A vertical cylinder (polygon of ``segments`` sides)."""

    kind: Literal["cylinder"]
    radius_mm: float = Field(gt=0, le=_MAX_MM)
    height_mm: float = Field(gt=0, le=_MAX_MM)
    centre_mm: tuple[_Mm, _Mm] = (0.0, 0.0)
    z0_mm: _Mm = 0.0
    segments: int = Field(default=96, ge=8, le=4096)

    def triangles(self) -> np.ndarray:
        t = np.linspace(0, 2 * np.pi, self.segments, endpoint=False)
        xy = np.stack([self.radius_mm * np.cos(t), self.radius_mm * np.sin(t)], 1) + np.asarray(self.centre_mm)
        return extrude_polygon(xy, self.height_mm, self.z0_mm)

    def terminals(self) -> dict[str, tuple[float, float, float, float]]:
        return {}


def coil_centreline(outer_mm: float, pitch_mm: float, turns: int, lead_mm: float) -> np.ndarray:
    """``(4 turns + 1, 2)`` corner points of a square spiral's centreline, outside in.

    Starts at ``(-lead, 0)`` going +X; segment lengths ``D + lead, D, D, D - p, D - p, D - 2p,
    D - 2p, ...`` (``D = outer_mm``, ``p = pitch_mm``).

    Parameters
    ----------
    outer_mm : float
        ``D``, side of the outer turn.
    pitch_mm : float
        ``p``, distance between the centrelines of neighbouring turns.
    turns : int
    lead_mm : float
        Extra length of the first segment, before the outer corner.

    Returns
    -------
    (4 * turns + 1, 2) float64 ndarray
        Corner points, mm.

    Examples
    --------
    >>> coil_centreline(10.0, 1.0, 1, 0.0).tolist()
    [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0], [0.0, 1.0]]
    """
    pts = [np.array([0.0 - lead_mm, 0.0])]
    dirs = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
    for k in range(4 * turns):
        length = outer_mm + (lead_mm if k == 0 else 0.0) if k <= 2 else outer_mm - pitch_mm * ((k - 1) // 2)
        pts.append(pts[-1] + dirs[k % 4] * length)
    return np.array(pts)


class SquareCoilShape(_Strict):
    """A planar square-spiral induction coil: a track of ``track_width_mm`` with ``gap_mm``
    between turns, ``turns`` full turns starting at the outer corner ``origin_mm``, a square
    pad at each end (``outer`` and ``inner`` terminals) that may rise above the track
    (``pad_height_mm``, e.g. through a cover)."""

    kind: Literal["square_coil"]
    outer_mm: float = Field(gt=0, le=_MAX_MM)
    track_width_mm: float = Field(gt=0, le=_MAX_MM)
    gap_mm: float = Field(gt=0, le=_MAX_MM)
    turns: int = Field(ge=1, le=200)
    height_mm: float = Field(gt=0, le=_MAX_MM)
    z0_mm: _Mm = 0.0
    origin_mm: tuple[_Mm, _Mm] = (0.0, 0.0)
    pad_mm: float = Field(default=1.2, gt=0, le=_MAX_MM)
    lead_mm: float = Field(default=0.6, ge=0, le=_MAX_MM)
    pad_height_mm: float | None = Field(default=None, gt=0, le=_MAX_MM)

    @model_validator(mode="after")
    def _fits(self) -> SquareCoilShape:
        p = self.track_width_mm + self.gap_mm
        last = self.outer_mm - p * ((4 * self.turns - 2) // 2)
        if last <= self.pad_mm + self.gap_mm:
            raise ValueError(f"{self.turns} turns of pitch {p:g} mm do not fit in {self.outer_mm:g} mm with a "
                             f"{self.pad_mm:g} mm pad (innermost segment {last:g} mm)")
        return self

    @property
    def pitch_mm(self) -> float:
        return self.track_width_mm + self.gap_mm

    def centreline(self) -> np.ndarray:
        """``(M, 2)`` corner points of the track's centreline (pad edge to pad edge)."""
        return coil_centreline(self.outer_mm, self.pitch_mm, self.turns, self.lead_mm) + np.asarray(self.origin_mm)

    def track_length_mm(self) -> float:
        """Centreline length between the pads: from the outer pad's edge to where the inner
        pad begins (the inner pad sits inside the last turn, its far edge flush with the
        track's end)."""
        c = self.centreline()
        return float(np.abs(np.diff(c, axis=0)).sum()) - (self.pad_mm - self.track_width_mm / 2)

    def corners(self) -> int:
        """Right-angle corners of the track between the pads."""
        return len(self.centreline()) - 2

    def _pads(self) -> dict[str, tuple[float, float, float, float]]:
        c = self.centreline()
        h = self.pad_mm / 2
        hw = self.track_width_mm / 2
        ox, oy = c[0]
        outer = (ox - self.pad_mm, oy - h, ox, oy + h)
        d = c[-1] - c[-2]
        d = d / np.linalg.norm(d)
        n = np.array([-d[1], d[0]])  # the spiral turns left: its inside is on the left
        a = c[-1] + d * hw - n * hw
        b = a - d * self.pad_mm + n * self.pad_mm
        inner = (min(a[0], b[0]), min(a[1], b[1]), max(a[0], b[0]), max(a[1], b[1]))
        return {"outer": tuple(float(v) for v in outer), "inner": tuple(float(v) for v in inner)}

    def triangles(self) -> np.ndarray:
        c = self.centreline()
        hw = self.track_width_mm / 2
        tris = []
        for a, b in zip(c[:-1], c[1:]):
            lo = np.minimum(a, b) - hw
            hi = np.maximum(a, b) + hw
            tris.append(_box_xy(lo[0], lo[1], hi[0], hi[1], self.z0_mm, self.height_mm))
        ph = self.height_mm if self.pad_height_mm is None else self.pad_height_mm
        for x0, y0, x1, y1 in self._pads().values():
            tris.append(_box_xy(x0, y0, x1, y1, self.z0_mm, ph))
        return np.concatenate(tris)

    def terminals(self) -> dict[str, tuple[float, float, float, float]]:
        return self._pads()


class InterdigitatedShape(_Strict):
    """An interdigitated electrode (two combs) for a gas sensor: ``fingers`` per comb of
    ``finger_width_mm``, ``gap_mm`` between neighbouring fingers and between a finger tip and
    the other comb's bus bar, fingers overlapping over ``overlap_mm``. Terminals: ``A`` and
    ``B`` (pads at the bus bars' lower ends) and ``A_tip`` (the tip of comb A's farthest
    finger)."""

    kind: Literal["interdigitated"]
    fingers: int = Field(ge=1, le=500)
    finger_width_mm: float = Field(gt=0, le=_MAX_MM)
    gap_mm: float = Field(gt=0, le=_MAX_MM)
    overlap_mm: float = Field(gt=0, le=_MAX_MM)
    bus_width_mm: float = Field(default=1.0, gt=0, le=_MAX_MM)
    pad_mm: float = Field(default=1.5, gt=0, le=_MAX_MM)
    height_mm: float = Field(gt=0, le=_MAX_MM)
    z0_mm: _Mm = 0.0
    origin_mm: tuple[_Mm, _Mm] = (0.0, 0.0)

    def _layout(self):
        fw, g, ov, bw = self.finger_width_mm, self.gap_mm, self.overlap_mm, self.bus_width_mm
        x0, y0 = self.origin_mm
        flen = ov + g  # finger length from its bus
        xa1 = x0 + bw  # comb A bus: [x0, xa1]
        xb0 = xa1 + flen + g  # comb B bus: [xb0, xb0 + bw]
        step = 2 * (fw + g)
        y_start = y0 + self.pad_mm + g
        fa = [(xa1, y_start + i * step, xa1 + flen, y_start + i * step + fw) for i in range(self.fingers)]
        fb = [(xb0 - flen, y_start + i * step + fw + g, xb0, y_start + i * step + 2 * fw + g) for i in range(self.fingers)]
        top = y_start + (self.fingers - 1) * step + 2 * fw + g + g
        bus_a = (x0, y0 + self.pad_mm, xa1, top)
        bus_b = (xb0, y0 + self.pad_mm, xb0 + bw, top)
        pad_a = (x0, y0, x0 + self.pad_mm, y0 + self.pad_mm)
        pad_b = (xb0 + bw - self.pad_mm, y0, xb0 + bw, y0 + self.pad_mm)
        return fa, fb, bus_a, bus_b, pad_a, pad_b

    def triangles(self) -> np.ndarray:
        fa, fb, bus_a, bus_b, pad_a, pad_b = self._layout()
        return np.concatenate([_box_xy(*r, self.z0_mm, self.height_mm) for r in (*fa, *fb, bus_a, bus_b, pad_a, pad_b)])

    def terminals(self) -> dict[str, tuple[float, float, float, float]]:
        fa, _, _, _, pad_a, pad_b = self._layout()
        x0, y0, x1, y1 = fa[-1]
        tip = (x1 - self.finger_width_mm, y0, x1, y1)
        return {"A": pad_a, "B": pad_b, "A_tip": tip}

    def cell_constant_per_mm(self) -> float:
        """``gap / (overlap * number of finger gaps)``: the film's resistance between the combs
        is its sheet resistance times this (fringe and tip gaps neglected)."""
        return self.gap_mm / (self.overlap_mm * (2 * self.fingers - 1))


Shape = Annotated[BoxShape | CylinderShape | SquareCoilShape | InterdigitatedShape, Field(discriminator="kind")]
