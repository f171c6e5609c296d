"""The machine program: what a rotary printer runs, revolution by revolution, and its replay."""

from .clock import ClockRatio, clock_ratio
from .spec import IdleSpec, MachineSpec, NozzleNumbering

__all__ = ["ClockRatio", "clock_ratio", "MachineSpec", "NozzleNumbering", "IdleSpec"]
