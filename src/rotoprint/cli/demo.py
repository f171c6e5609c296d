"""`rotoprint demo`: build the bundled coil sensor and say where the report is."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated

import typer

from ._common import console


def demo(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder for the demo.")] = Path("demo-output"),
    example: Annotated[str, typer.Option("--example", help="coil-sensor, gas-sensor or cad-coil.")] = "coil-sensor",
) -> None:
    """Build the bundled coil sensor (plaster body, silver coil, epoxy cover): the job file is
    written to OUT/job/, the build (print-ready images, plan.json, report.html) to OUT/build/."""
    from ..process import load_job
    from ..pipeline import run_build
    from ..pipeline.examples import write_example
    from .build import report_summary, stage_progress

    from ..errors import ConfigError, InputFileError
    from ..process.examples import EXAMPLES

    if example not in EXAMPLES:
        raise ConfigError(f"unknown example {example!r}; examples: {', '.join(EXAMPLES)}")
    if out.exists() and not out.is_dir():
        raise InputFileError("output exists and is not a folder", path=out)
    t0 = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    job_path = write_example(example, out / "job")
    console.print(f"job file: {job_path.resolve()}")
    with stage_progress() as on_step:
        res = run_build(load_job(job_path), out / "build", on_step=on_step)
    report_summary(res)
    console.print(f"demo done in {time.perf_counter() - t0:.1f} s; rebuild with: rotoprint build {job_path} --out {out / 'build'}")
