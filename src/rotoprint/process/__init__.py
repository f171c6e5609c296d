"""Multi-material process planning: materials and inks, job files, pass plans, estimates.

See ``docs/build.md``. The stages of ``rotoprint build`` are run by :func:`rotoprint.pipeline.run_build`.
"""

from __future__ import annotations

from .estimates import (
    ResistanceResult,
    cycle_thickness_um,
    drops_per_mm2,
    sheet_resistance_ohm,
    solve_resistance,
    wet_film_um,
)
from .job import JobSpec, ResolvedJob, load_job, parse_job
from .materials import BUILTIN_MATERIALS, Ink, Material, MaterialLibrary, builtin_library, load_materials
from .plan import BuildPlan, LayerSchedule, plan_job

__all__ = [
    "ResistanceResult",
    "cycle_thickness_um",
    "drops_per_mm2",
    "sheet_resistance_ohm",
    "solve_resistance",
    "wet_film_um",
    "JobSpec",
    "ResolvedJob",
    "load_job",
    "parse_job",
    "BUILTIN_MATERIALS",
    "Ink",
    "Material",
    "MaterialLibrary",
    "builtin_library",
    "load_materials",
    "BuildPlan",
    "LayerSchedule",
    "plan_job",
]
