"""Rotary printing: head geometry, the exact and the paper's transforms, swathes, simulation.

Conventions: ``shared/design/rotary-geometry.md`` (platform frame, nozzle positions, firing).
"""

from __future__ import annotations

from .exact import ExactMaps, exact_maps, transform_exact
from .head import HeadFigures, Mount, NozzleLayout, head_figures, max_tilt_deg, nozzle_layout, nozzle_offsets, paper_figures
from .options import RotarySetup, RotarySliceOptions
from .placement import Placement
from .printdata import RotaryPrint, SwatheImage, clock_dphi
from .simulate import Simulation, SimulationReport, place_drops, render_overlay, simulate
from .swathes import Swathe, SwathePlan, plan_swathes

__all__ = [
    "ExactMaps",
    "exact_maps",
    "transform_exact",
    "HeadFigures",
    "Mount",
    "NozzleLayout",
    "head_figures",
    "max_tilt_deg",
    "nozzle_layout",
    "nozzle_offsets",
    "paper_figures",
    "Placement",
    "RotarySetup",
    "RotarySliceOptions",
    "RotaryPrint",
    "SwatheImage",
    "clock_dphi",
    "Simulation",
    "SimulationReport",
    "place_drops",
    "render_overlay",
    "simulate",
    "Swathe",
    "SwathePlan",
    "plan_swathes",
]
