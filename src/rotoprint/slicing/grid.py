"""The device pixel grid a part is sliced onto, and its affine maps.

Pixel indices are ``(col, row)``; the centre of pixel ``(0, 0)`` is at index ``(0, 0)``. The
platform frame has its origin at the centre of the image (of the projector field, where the
device has one), X to the right and Y up as the image is viewed (row 0 on top).

The part is placed by rotating the model about Z so that the requested fibre angle (in the
model's XY plane, degrees counter-clockwise from model +X) falls on the device's fibre axis,
then translating it: by default its footprint's centre goes to the platform origin plus
``offset_mm``.
"""

from __future__ import annotations

import math

import numpy as np

from .._dataclass import dataclass
from ..errors import GeometryError

__all__ = ["Grid", "make_grid"]


@dataclass(frozen=True)
class Grid:
    """A raster of ``height x width`` pixels at the device's pitch.

    Attributes
    ----------
    width, height : int
    pitch_x_mm, pitch_y_mm : float
        Column and row spacing.
    fibre_axis : {'x', 'y'}
        ``'x'``: every image row is a fibre; ``'y'``: every column is one.
    rotation_deg : float
        Rotation of the model about Z onto the platform.
    translation_mm : (2,) float64
        Platform position of the model's origin after the rotation.
    """

    width: int
    height: int
    pitch_x_mm: float
    pitch_y_mm: float
    fibre_axis: str
    rotation_deg: float
    translation_mm: tuple[float, float]

    @property
    def shape(self) -> tuple[int, int]:
        return (self.height, self.width)

    @property
    def pixel_to_platform(self) -> np.ndarray:
        """``(2, 3) float64``: ``[X, Y] = M @ [col, row, 1]`` in platform mm."""
        kx, ky = (self.width - 1) / 2.0, (self.height - 1) / 2.0
        return np.array(
            [[self.pitch_x_mm, 0.0, -kx * self.pitch_x_mm], [0.0, -self.pitch_y_mm, ky * self.pitch_y_mm]]
        )

    @property
    def model_to_platform(self) -> np.ndarray:
        """``(2, 3) float64``: model XY to platform XY (rotation then translation)."""
        c, s = math.cos(math.radians(self.rotation_deg)), math.sin(math.radians(self.rotation_deg))
        tx, ty = self.translation_mm
        return np.array([[c, -s, tx], [s, c, ty]])

    @property
    def model_to_pixel(self) -> np.ndarray:
        """``(2, 3) float64``: model XY to continuous pixel indices ``(col, row)``."""
        return _compose(_invert(self.pixel_to_platform), self.model_to_platform)

    @property
    def pixel_to_model(self) -> np.ndarray:
        """``(2, 3) float64``: pixel indices ``(col, row)`` to model XY mm."""
        return _invert(self.model_to_pixel)

    def to_json(self) -> dict:
        return {
            "width_px": self.width,
            "height_px": self.height,
            "pitch_x_mm": self.pitch_x_mm,
            "pitch_y_mm": self.pitch_y_mm,
            "fibre_axis": self.fibre_axis,
            "rotation_deg": self.rotation_deg,
            "translation_mm": list(self.translation_mm),
            "pixel_to_platform": self.pixel_to_platform.tolist(),
            "pixel_to_model": self.pixel_to_model.tolist(),
            "model_to_pixel": self.model_to_pixel.tolist(),
        }


def _invert(m: np.ndarray) -> np.ndarray:
    a = np.linalg.inv(m[:, :2])
    return np.hstack([a, -(a @ m[:, 2])[:, None]])


def _compose(outer: np.ndarray, inner: np.ndarray) -> np.ndarray:
    return np.hstack([outer[:, :2] @ inner[:, :2], (outer[:, :2] @ inner[:, 2] + outer[:, 2])[:, None]])


def make_grid(
    vertices_xy: np.ndarray,
    *,
    pitch_mm: tuple[float, float],
    fibre_axis: str,
    field_px: tuple[int, int] | None,
    fibre_angle_deg: float | None = None,
    offset_mm: tuple[float, float] = (0.0, 0.0),
    centre: bool = True,
    margin_px: int = 1,
) -> Grid:
    """Place a part given by its ``(V, 2)`` vertex XY on a device grid (see module doc).

    Parameters
    ----------
    vertices_xy : (V, 2) float array
        Model XY of the part's vertices, mm.
    pitch_mm : (2,) float
        ``(x, y)``: column and row spacing of the device's pixels, mm.
    fibre_axis : {'x', 'y'}
        Device direction the fibres run along (``'x'``: image rows).
    field_px : (2,) int, optional
        ``(width, height)`` of a fixed device field (a projector); ``None`` sizes the grid to
        the part (an inkjet head), symmetric about the origin, plus ``margin_px``.
    fibre_angle_deg : float, optional
        Model direction (degrees counter-clockwise from +X) to put along the fibre axis;
        ``None`` keeps the model unrotated.
    offset_mm : (2,) float
        Platform position of the footprint's centre (``centre=True``) or of the model origin.
    centre : bool
        Centre the footprint's bounding box on ``offset_mm``.
    margin_px : int
        Empty pixels around the part when the grid is sized to it.

    Returns
    -------
    Grid
        ``width x height`` pixels with the rotation and translation applied to the model.

    Raises
    ------
    GeometryError
        An unknown ``fibre_axis``, a non-finite offset, or a part that does not fit the field.
    """
    if fibre_axis not in ("x", "y"):
        raise GeometryError(f"fibre_axis must be 'x' or 'y', got {fibre_axis!r}")
    pitch_x_mm, pitch_y_mm = pitch_mm
    axis_deg = 0.0 if fibre_axis == "x" else 90.0
    rot = 0.0 if fibre_angle_deg is None else (axis_deg - float(fibre_angle_deg))
    rot = (rot + 180.0) % 360.0 - 180.0
    c, s = math.cos(math.radians(rot)), math.sin(math.radians(rot))
    xy = np.asarray(vertices_xy, dtype=np.float64)
    rx = c * xy[:, 0] - s * xy[:, 1]
    ry = s * xy[:, 0] + c * xy[:, 1]
    lo = np.array([rx.min(), ry.min()])
    hi = np.array([rx.max(), ry.max()])
    off = np.asarray(offset_mm, dtype=np.float64)
    if off.shape != (2,) or not np.isfinite(off).all():
        raise GeometryError(f"offset must be two finite numbers of mm, got {tuple(np.ravel(off).tolist())}")
    t = off - (lo + hi) / 2.0 if centre else off
    plo, phi = lo + t, hi + t  # platform footprint
    if field_px is not None:
        w, h = int(field_px[0]), int(field_px[1])
        half = np.array([w * pitch_x_mm, h * pitch_y_mm]) / 2.0
        if np.any(plo < -half) or np.any(phi > half):
            raise GeometryError(
                f"the part's footprint ({phi[0] - plo[0]:.3f} x {phi[1] - plo[1]:.3f} mm, from "
                f"({plo[0]:.3f}, {plo[1]:.3f}) to ({phi[0]:.3f}, {phi[1]:.3f}) mm) does not fit the device "
                f"field of {2 * half[0]:.3f} x {2 * half[1]:.3f} mm"
            )
    else:
        ext = np.maximum(np.abs(plo), np.abs(phi))
        w = 2 * math.ceil(ext[0] / pitch_x_mm) + 1 + 2 * margin_px
        h = 2 * math.ceil(ext[1] / pitch_y_mm) + 1 + 2 * margin_px
    return Grid(
        width=w,
        height=h,
        pitch_x_mm=float(pitch_x_mm),
        pitch_y_mm=float(pitch_y_mm),
        fibre_axis=fibre_axis,
        rotation_deg=rot,
        translation_mm=(float(t[0]), float(t[1])),
    )
