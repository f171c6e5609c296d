"""The work of ``rotoprint dlp`` once its options are read: one function that both the typer
command (:func:`rotoprint.cli.dlp.dlp_command`) and the fast entry (:mod:`._fast`) call with
the same keyword arguments, so that the two cannot drift apart. Neither typer nor rich is
imported here: a progress bar and the summary reach the terminal through the ``ui`` object
the caller passes (:class:`PlainUI` without a terminal)."""

from __future__ import annotations

import sys
from pathlib import Path

from ..errors import ConfigError
from ._base import device_input, escape_controls, is_quiet, is_verbose, load_mesh_from_options, parse_pair, setup_logging


class _NoBar:
    """A progress bar that shows nothing (quiet, or no terminal), as rich's disabled one."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        return None

    def add_task(self, description: str, total: int | None = None) -> int:
        return 0

    def advance(self, task: int, advance: float = 1) -> None:
        return None


class PlainUI:
    """Messages without rich: the summary as one line on stderr (what the rich console prints
    with ``soft_wrap`` when stderr is not a terminal), and no progress bar."""

    def progress(self, quiet: bool):
        return _NoBar()

    def say(self, text: str) -> None:
        if not (text.isascii() and text.isprintable()):  # tabs, wide characters: as rich lays them out
            RichUI().say(text)
            return
        sys.stderr.write(escape_controls(text, keep_newlines=True) + "\n")


class RichUI:
    """Messages through the command's rich console (a progress bar on a terminal)."""

    def progress(self, quiet: bool):
        from ._common import progress

        return progress(quiet)

    def say(self, text: str) -> None:
        from ._console import console

        console.print(text, soft_wrap=True)


def run_dlp(
    *,
    mesh: Path,
    device: str,
    layer_height: float,
    out: Path,
    mode: str,
    erm: bool,
    invert: bool,
    mirror_x: bool,
    mirror_y: bool,
    first_layers: int,
    first_layer_offset: float,
    fmt: str,
    exposure: float | None,
    first_exposure: float | None,
    fibre_angle: float | None,
    offset: str | None,
    units: str,
    scale: float,
    rotate: str | None,
    translate: str | None,
    fill_holes: bool,
    workers: int,
    scheduler: str | None,
    resume: bool,
    quiet: bool,
    verbose: bool,
    force: bool,
    ui=None,
) -> None:
    """Slice ``mesh`` into DLP masks and write the job (the parameters are the options of
    ``rotoprint dlp``, already range-checked as the option callbacks do)."""
    from .._plain_device import load_projector
    from ..io.archives import JobInfo, creation_time, format_from_path, job_dir_name
    from ..pipeline import RunOptions, write_dlp_job
    from ..masks import MaskOptions, check_first_layer_offset
    from ..slicing import slice_mesh

    from ..io.atomic import check_output_path

    ui = RichUI() if ui is None else ui
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
    dev = load_projector(device, **overrides)  # a projector preset without pydantic, else load_device's
    if dev is None:
        from ..devices import ProjectorDevice, load_device

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
    with ui.progress(quiet) as bar:
        task = bar.add_task(f"{mode} masks", total=info.mask_count)
        summary = write_dlp_job(job, out, info, options, fmt=kind, on_mask=lambda i: bar.advance(task),
                                run=RunOptions(workers=workers, scheduler=scheduler, resume=resume, force=force, inputs=tuple(inputs)))
    if not quiet:
        vol = summary.get("volume_mm3", 0.0)
        # one line (soft wrap): a pipe or log gets it whole, as the error lines
        ui.say(
            f"{info.mask_count} {mode} masks ({len(job)} layers{' x 2, ERM' if erm else ''}) of "
            f"{info.width_px} x {info.height_px} px, {vol:.3f} mm^3 of resin -> {out} ({kind})"
        )
