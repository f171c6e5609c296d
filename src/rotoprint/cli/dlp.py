"""`rotoprint dlp MESH`: DLP masks (binary, exact coverage, or the paper's smoothing) into an
SL1 / SL1S archive, a PNG folder with manifest.json, or a Perfactory-style job folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..errors import ConfigError
from .options import is_quiet, is_verbose, FibreAngleOpt, OffsetOpt, QuietOpt, ResumeOpt, SchedulerOpt, VerboseOpt, WorkersOpt
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
    console,
    device_input,
    load_mesh_from_options,
    parse_pair,
    progress,
    setup_logging,
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
    from ..devices import ProjectorDevice, load_device
    from ..io.archives import JobInfo, creation_time, format_from_path, job_dir_name
    from ..pipeline import RunOptions, write_dlp_job
    from ..masks import MaskOptions, check_first_layer_offset
    from ..slicing import slice_mesh

    from ..io.atomic import check_output_path

    setup_logging(is_verbose(verbose))
    quiet = is_quiet(quiet)
    if scheduler is not None:  # a malformed address or port is refused before any work
        from ..pipeline.producer import check_scheduler_address

        check_scheduler_address(scheduler)
    kind = format_from_path(out, fmt)
    inputs = [mesh, device_input(device)]
    check_output_path(out, is_dir=kind not in ("sl1", "sl1s"), inputs=inputs, force=force)  # before any work
    if kind in ("sl1", "sl1s"):
        creation_time()  # a bad SOURCE_DATE_EPOCH is refused before any work
    overrides = {"exposure_s": exposure, "first_exposure_s": first_exposure}
    dev = load_device(device, **overrides)
    if not isinstance(dev, ProjectorDevice):
        raise ConfigError(f"dlp needs a projector device, got the {dev.kind} device {dev.name!r}")
    options = MaskOptions(
        mode=mode,
        erm=erm,
        invert=invert,
        mirror_x=mirror_x or dev.projector.mirror_x,
        mirror_y=mirror_y or dev.projector.mirror_y,
        first_layers=first_layers,
        first_layer_offset_um=first_layer_offset,
    )
    m = load_mesh_from_options(mesh, units, scale, rotate, translate, fill_holes)
    lo, hi = m.bounds
    check_first_layer_offset(options, (float(hi[0] - lo[0]), float(hi[1] - lo[1])))
    job = slice_mesh(m, dev, layer_height_mm=layer_height, fibre_angle_deg=fibre_angle, offset_mm=parse_pair(offset, "--offset"))
    p = dev.projector
    info = JobInfo(
        job_name=job_dir_name(out),
        layer_height_mm=layer_height,
        layer_count=len(job),
        copies=options.copies,
        width_px=job.grid.width,
        height_px=job.grid.height,
        pixel_x_mm=job.grid.pitch_x_mm,
        pixel_y_mm=job.grid.pitch_y_mm,
        mirror_x=options.mirror_x,
        mirror_y=options.mirror_y,
        orientation=p.orientation,
        exposure_s=p.exposure_s,
        first_exposure_s=p.first_exposure_s,
        first_exposure_layers=p.first_exposure_layers,
        printer_model=p.printer_model,
        device_name=dev.name,
        device=dev.model_dump(mode="json"),
        mesh=m.info(),
        source=str(mesh),
        options={**options.to_json(), "layer_height_mm": layer_height, "fibre_angle_deg": fibre_angle, "offset_mm": list(parse_pair(offset, "--offset")), "units": units, "scale": scale},
        grid=job.grid.to_json(),
    )
    with progress(quiet) as bar:
        task = bar.add_task(f"{mode} masks", total=info.mask_count)
        summary = write_dlp_job(job, out, info, options, fmt=kind, on_mask=lambda i: bar.advance(task),
                                run=RunOptions(workers=workers, scheduler=scheduler, resume=resume, force=force, inputs=tuple(inputs)))
    if not quiet:
        vol = summary.get("volume_mm3", 0.0)
        console.print(
            f"{info.mask_count} {mode} masks ({len(job)} layers{' x 2, ERM' if erm else ''}) of "
            f"{info.width_px} x {info.height_px} px, {vol:.3f} mm^3 of resin -> {out} ({kind})"
        )
