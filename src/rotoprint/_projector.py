"""What every projector device derives from its projector: pixel pitch, field and fibre axis.

A module of its own, importing nothing, so that both the pydantic models
(:mod:`rotoprint.devices.models`) and the pydantic-free presets of the fast ``dlp`` entry
(:mod:`rotoprint._plain_device`) share it without importing each other.
"""

from __future__ import annotations

__all__ = ["ProjectorGeometry"]


class ProjectorGeometry:
    """The pixel pitch, field and fibre axis of a projector device, from its ``projector``
    (shared by :class:`rotoprint.devices.ProjectorDevice` and :class:`PlainProjectorDevice`;
    pydantic-free, so that the fast ``dlp`` entry does not import pydantic)."""

    @property
    def pitch_x_mm(self) -> float:
        """Pixel pitch along x, mm."""
        return self.projector.width_mm / self.projector.pixels_x

    @property
    def pitch_y_mm(self) -> float:
        """Pixel pitch along y, mm."""
        return self.projector.height_mm / self.projector.pixels_y

    @property
    def field_px(self) -> tuple[int, int] | None:
        """The projector's pixels, (x, y)."""
        return (self.projector.pixels_x, self.projector.pixels_y)

    @property
    def fibre_axis(self) -> str:
        """The axis fibres run along (rows of the mask): ``"x"``."""
        return "x"
