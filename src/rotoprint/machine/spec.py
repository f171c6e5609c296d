"""The ``[machine]`` section of a job: what the rotary printer's motion and controller allow.

Every field has a nominal default (a machine with a 2^20-count platform encoder and a 100 mm
radial stage); measure your own machine and set them.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

__all__ = ["MachineSpec", "NozzleNumbering", "IdleSpec"]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class NozzleNumbering(_Strict):
    """How the head numbers its nozzles (the order of a packed row), see
    :func:`rotoprint.io.machine.nozzle_order`."""

    odd_row: int = Field(default=0, ge=0, le=15)
    direction: Literal["ascending", "descending"] = "ascending"


class IdleSpec(_Strict):
    """What a head does while it waits (waits, post-steps, z steps): ``spit`` fires
    ``spit_drops`` drops from every nozzle into the spittoon every ``spit_interval_s``;
    ``wet`` keeps the nozzle plate capped and wet; ``none`` does nothing."""

    mode: Literal["spit", "wet", "none"] = "spit"
    spit_interval_s: float = Field(default=2.0, gt=0, le=3600)
    spit_drops: int = Field(default=10, ge=1, le=10_000)
    after_s: float = Field(default=1.0, ge=0, le=3600)


class MachineSpec(_Strict):
    """The machine: platform encoder, radial stage, speeds, controller clock limits."""

    encoder_counts_per_rev: int = Field(default=2**20, ge=16, le=2**40)
    radial_stage_mm: tuple[float, float] = (0.0, 100.0)
    max_platform_rpm: float = Field(default=120.0, gt=0, le=100_000)
    head_frequency_hz: float | None = Field(default=None, gt=0, le=1_000_000)
    clock_max_multiplier: int = Field(default=65_535, ge=1, le=2**32)
    clock_max_divider: int = Field(default=65_535, ge=1, le=2**32)
    z_step_s: float = Field(default=0.0, ge=0, le=3600)
    radial_move_s: float = Field(default=0.0, ge=0, le=3600)
    nozzle_numbering: NozzleNumbering = NozzleNumbering()
    idle: IdleSpec = IdleSpec()

    @model_validator(mode="after")
    def _stage(self) -> MachineSpec:
        lo, hi = self.radial_stage_mm
        if not hi > lo:
            raise ValueError(f"radial_stage_mm must be [low, high] with high > low, got [{lo:g}, {hi:g}]")
        return self
