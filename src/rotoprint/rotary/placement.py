"""Where a bitmap design sits on the platform (``rotary-geometry.md`` section 4).

The paper's placement: the design's first column starts at ``inner_radius_mm``, its central
horizontal axis lies on the radial line at ``angle_deg`` (0: head 0's centre line), rows run
in the direction of travel. Continuous design coordinates ``(col, row)`` put pixel ``(j, c)``
on ``[c, c+1) x [j, j+1)``, so its centre is ``(c + 0.5, j + 0.5)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError, GeometryError

__all__ = ["Placement"]


@dataclass(frozen=True)
class Placement:
    """A ``height_px x width_px`` design on the platform.

    Parameters
    ----------
    width_px, height_px : int
        Design size (columns, rows).
    pitch_x_mm, pitch_y_mm : float
        Pixel pitch across columns (radial) and rows (along the direction of travel).
    inner_radius_mm : float
        Radius of the design's first column's inner edge (the paper's ``cx_T + px_T``).
    angle_deg : float
        Angle of the design's central horizontal axis in the platform frame.

    Examples
    --------
    >>> pl = Placement(10, 4, 0.1, 0.1, inner_radius_mm=50.0)
    >>> [round(float(v), 6) for v in pl.to_platform(np.array([0.5]), np.array([0.5]))[0]]
    [50.05]
    >>> [round(float(v), 6) for v in pl.to_platform(np.array([0.5]), np.array([0.5]))[1]]
    [0.15]
    """

    width_px: int
    height_px: int
    pitch_x_mm: float
    pitch_y_mm: float
    inner_radius_mm: float
    angle_deg: float = 0.0

    def __post_init__(self) -> None:
        if self.width_px <= 0 or self.height_px <= 0:
            raise ConfigError(f"design size must be positive, got {self.width_px} x {self.height_px} px")
        if not (self.pitch_x_mm > 0 and self.pitch_y_mm > 0):
            raise ConfigError(f"design pixel pitch must be positive, got {self.pitch_x_mm} x {self.pitch_y_mm} mm")
        if not math.isfinite(self.angle_deg):
            raise ConfigError(f"placement angle must be a finite number of degrees, got {self.angle_deg}")
        if not (math.isfinite(self.inner_radius_mm) and self.inner_radius_mm > 0):
            raise GeometryError(
                f"design radius must be > 0 mm (the design would cover the axis of rotation), got {self.inner_radius_mm}"
            )

    @property
    def width_mm(self) -> float:
        return self.width_px * self.pitch_x_mm

    @property
    def height_mm(self) -> float:
        return self.height_px * self.pitch_y_mm

    def to_platform(self, col: np.ndarray, row: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Continuous design coordinates to platform ``(x, y)`` mm (arrays of any shape)."""
        xl = self.inner_radius_mm + np.asarray(col, dtype=np.float64) * self.pitch_x_mm
        yl = (self.height_px / 2.0 - np.asarray(row, dtype=np.float64)) * self.pitch_y_mm
        a = math.radians(self.angle_deg)
        c, s = math.cos(a), math.sin(a)
        return c * xl - s * yl, s * xl + c * yl

    def to_design(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Platform ``(x, y)`` mm to continuous design ``(col, row)``."""
        a = math.radians(self.angle_deg)
        c, s = math.cos(a), math.sin(a)
        x = np.asarray(x, dtype=np.float64)
        y = np.asarray(y, dtype=np.float64)
        xl = c * x + s * y
        yl = -s * x + c * y
        return (xl - self.inner_radius_mm) / self.pitch_x_mm, self.height_px / 2.0 - yl / self.pitch_y_mm

    def radial_range_mm(self) -> tuple[float, float]:
        """Smallest and largest radius of the design's footprint."""
        r0 = self.inner_radius_mm
        r1 = r0 + self.width_mm
        h = self.height_mm / 2.0
        return r0, math.hypot(r1, h)

    def angular_range_rad(self) -> tuple[float, float]:
        """Smallest and largest polar angle of the footprint (it never covers the axis)."""
        r0 = self.inner_radius_mm
        h = self.height_mm / 2.0
        a = math.radians(self.angle_deg)
        half = math.atan2(h, r0)
        return a - half, a + half

    def to_json(self) -> dict:
        return {
            "width_px": self.width_px,
            "height_px": self.height_px,
            "pitch_x_mm": self.pitch_x_mm,
            "pitch_y_mm": self.pitch_y_mm,
            "inner_radius_mm": self.inner_radius_mm,
            "angle_deg": self.angle_deg,
            "convention": "pixel (row j, col c) centre at x = inner_radius + (c + 0.5) * pitch_x, "
            "y = (height/2 - j - 0.5) * pitch_y, then rotated by angle_deg",
        }

    @classmethod
    def from_json(cls, d: dict) -> Placement:
        return cls(
            int(d["width_px"]), int(d["height_px"]), float(d["pitch_x_mm"]), float(d["pitch_y_mm"]),
            inner_radius_mm=float(d["inner_radius_mm"]), angle_deg=float(d.get("angle_deg", 0.0)),
        )
