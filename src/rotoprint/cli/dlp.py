"""`rotoprint dlp MESH`: DLP masks (binary, exact coverage, or the paper's smoothing) into an
SL1 / SL1S archive, a PNG folder with manifest.json, or a Perfactory-style job folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .options import FibreAngleOpt, OffsetOpt, QuietOpt, ResumeOpt, SchedulerOpt, VerboseOpt, WorkersOpt
from .. import ranges as R
from ._common import in_range
from ._common import (
    DeviceOpt,
    ForceOpt,
    LayerHeightOpt,
    RotateOpt,
    ScaleOpt,
    FillHolesOpt,
    TranslateOpt,
    UnitsOpt,
)


def dlp_command(
    mesh: Annotated[Path, typer.Argument(help="Mesh file: STL, OBJ, PLY, 3MF, OFF, GLB.")],
    device: DeviceOpt,
    layer_height: LayerHeightOpt,
    out: Annotated[Path, typer.Option("--out", "-o", help="JOB.sl1, JOB.sl1s, or a folder (PNG masks + manifest.json).")],
    mode: Annotated[str, typer.Option("--mode", help="binary (pixel centres), coverage (exact area fraction), smooth (the paper's PIL SMOOTH on binary).")] = "coverage",
    erm: Annotated[bool, typer.Option("--erm", help="Enhanced resolution mode: every layer twice, the second copy shifted one pixel in x and y.")] = False,
    invert: Annotated[bool, typer.Option("--invert", help="Black = expose.")] = False,
    mirror_x: Annotated[bool, typer.Option("--mirror-x", help="Flip masks left-right (besides the device's own setting).")] = False,
    mirror_y: Annotated[bool, typer.Option("--mirror-y", help="Flip masks top-bottom (besides the device's own setting).")] = False,
    first_layers: Annotated[int, typer.Option("--first-layers", help="Layers over which the first-layer offset fades to zero.", callback=in_range(R.COUNT))] = 0,
    first_layer_offset: Annotated[float, typer.Option("--first-layer-offset", help="Elephant-foot inset of layer 0, micrometres.", callback=in_range(R.OFFSET_UM))] = 0.0,
    fmt: Annotated[str, typer.Option("--format", help="auto (from --out), sl1, sl1s, png, perfactory.")] = "auto",
    exposure: Annotated[float | None, typer.Option("--exposure", help="Exposure per layer, s (default: the device's).", callback=in_range(R.EXPOSURE_S))] = None,
    first_exposure: Annotated[float | None, typer.Option("--first-exposure", help="Exposure of the first layers, s (default: the device's).", callback=in_range(R.EXPOSURE_S))] = None,
    fibre_angle: FibreAngleOpt = None,
    offset: OffsetOpt = None,
    units: UnitsOpt = "mm",
    scale: ScaleOpt = 1.0,
    rotate: RotateOpt = None,
    translate: TranslateOpt = None,
    fill_holes: FillHolesOpt = True,
    workers: WorkersOpt = 1,
    scheduler: SchedulerOpt = None,
    resume: ResumeOpt = False,
    quiet: QuietOpt = False,
    verbose: VerboseOpt = False,
    force: ForceOpt = False,
) -> None:
    """Slice MESH into DLP masks (white = expose) at the projector's own resolution."""
    params = dict(locals())  # the options as parsed, before any other name is bound
    from ._dlp_run import RichUI, run_dlp

    run_dlp(**params, ui=RichUI())
