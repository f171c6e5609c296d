"""Device models: inkjet print heads and DLP projectors, validated by pydantic.

Every device gives the slicer the same four things: the pixel pitch across columns and rows
(``pitch_x_mm``, ``pitch_y_mm``), an optional fixed field (``field_px``), and the direction
its fibres run (``fibre_axis``: ``"x"`` fibres are image rows, ``"y"`` image columns). For an
inkjet head a fibre is a nozzle's track: image columns are nozzles, one nozzle pitch apart,
and rows are firings, ``25.4 / dpi_y`` apart.

Numeric fields are bounded by the ranges of :mod:`rotoprint.ranges` (``dpi_y`` 1 to 100000,
lengths up to 10 m, exposures up to an hour), so no device a file describes overflows a pixel
count later.
"""

from __future__ import annotations

from typing import Annotated, Literal

from .. import ranges as R
from .._projector import ProjectorGeometry
from pydantic import BaseModel, ConfigDict, Field, field_validator

__all__ = ["InkjetHead", "InkjetDevice", "Projector", "ProjectorDevice", "Device"]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class InkjetHead(_Strict):
    """A print head: ``nozzles`` spread evenly over ``swathe_mm`` in ``rows`` staggered rows."""

    nozzles: int = Field(gt=0, le=100_000)
    rows: int = Field(default=2, ge=1, le=16)
    swathe_mm: float = Field(gt=0, le=R.COORD_MM.hi)
    row_separation_mm: float = Field(ge=0, le=R.COORD_MM.hi)
    dpi_y: float = Field(default=360.0, ge=R.DPI.lo, le=R.DPI.hi)
    drop_volume_pl: float = Field(default=10.0, gt=0, le=1e6)
    drop_diameter_um: float = Field(default=60.0, ge=R.DROP_UM.lo, le=R.DROP_UM.hi)
    #: footprint diameter on the substrate over the in-flight diameter (6 V / pi)^(1/3): an
    #: ink/substrate figure used by the deposit model (rotary/deposit.py)
    spread_factor: float = Field(default=2.0, gt=0, le=20)
    #: the wet film's levelling under surface tension (rotary/deposit.py, LevelOptions): ink
    #: viscosity and surface tension at the substrate, and the time the film flows before it
    #: sets (0: no levelling, the film as landed); nominal, measure per ink
    viscosity_mpa_s: float = Field(default=10.0, ge=R.VISCOSITY_MPA_S.lo, le=R.VISCOSITY_MPA_S.hi)
    surface_tension_mn_m: float = Field(default=30.0, ge=R.SURFACE_TENSION_MN_M.lo, le=R.SURFACE_TENSION_MN_M.hi)
    set_time_s: float = Field(default=0.0, ge=R.SET_TIME_S.lo, le=R.SET_TIME_S.hi)
    max_frequency_hz: float = Field(default=8000.0, gt=0, le=1e7)
    grey_levels: int = Field(default=1, ge=1, le=255)
    dead_nozzles: tuple[int, ...] = Field(default=(), max_length=100_000)

    @field_validator("dead_nozzles")
    @classmethod
    def _dead_in_range(cls, v: tuple[int, ...], info) -> tuple[int, ...]:
        n = info.data.get("nozzles")
        bad = [k for k in v if n is not None and not 0 <= k < n]
        if bad:
            raise ValueError(f"dead nozzle indices must be in 0..{n - 1}, got {bad}")
        return tuple(sorted(set(v)))

    @property
    def pitch_mm(self) -> float:
        """Nozzle pitch across the swathe, ``swathe_mm / nozzles``."""
        return self.swathe_mm / self.nozzles

    @property
    def dpi_x(self) -> float:
        return 25.4 / self.pitch_mm


class InkjetDevice(_Strict):
    kind: Literal["inkjet"]
    name: str
    description: str = ""
    source: str = ""
    nominal: tuple[str, ...] = ()
    head: InkjetHead

    @property
    def pitch_x_mm(self) -> float:
        return self.head.pitch_mm

    @property
    def pitch_y_mm(self) -> float:
        return 25.4 / self.head.dpi_y

    @property
    def field_px(self) -> tuple[int, int] | None:
        return None

    @property
    def fibre_axis(self) -> str:
        return "y"


class Projector(_Strict):
    pixels_x: int = Field(gt=0, le=100_000)
    pixels_y: int = Field(gt=0, le=100_000)
    width_mm: float = Field(gt=0, le=R.COORD_MM.hi)
    height_mm: float = Field(gt=0, le=R.COORD_MM.hi)
    mirror_x: bool = False
    mirror_y: bool = False
    orientation: Literal["landscape", "portrait"] = "landscape"
    cure_threshold: float = Field(default=0.5, ge=0, le=1)
    exposure_s: float = Field(default=8.0, ge=R.EXPOSURE_S.lo, le=R.EXPOSURE_S.hi)
    first_exposure_s: float = Field(default=35.0, ge=R.EXPOSURE_S.lo, le=R.EXPOSURE_S.hi)
    first_exposure_layers: int = Field(default=10, ge=0, le=10_000)
    printer_model: str = "rotoprint"


class ProjectorDevice(_Strict, ProjectorGeometry):
    kind: Literal["projector"]
    name: str
    description: str = ""
    source: str = ""
    nominal: tuple[str, ...] = ()
    projector: Projector


Device = Annotated[InkjetDevice | ProjectorDevice, Field(discriminator="kind")]
