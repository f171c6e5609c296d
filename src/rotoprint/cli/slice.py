"""`rotoprint slice MESH`: one image per layer on the device's own pixel grid."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..constants import DEFAULT_GAP_RADIUS_MM
from ..errors import ConfigError
from .options import is_quiet, is_verbose, DpiYOpt, FibreAngleOpt, FillOpt, GapRadiusOpt, OffsetOpt, QuietOpt, ResumeOpt, SchedulerOpt, VerboseOpt, WorkersOpt
from .. import ranges as R
from ._common import direction_cb, in_range
from ._common import (
    styled,
    DeviceOpt,
    FillHolesOpt,
    LayerHeightOpt,
    RotateOpt,
    ScaleOpt,
    TranslateOpt,
    UnitsOpt,
    console,
    load_mesh_from_options,
    parse_pair,
    progress,
    setup_logging,
)
from ._common import ForceOpt, device_input


def slice_command(
    mesh: Annotated[Path, typer.Argument(help="Mesh file: STL, OBJ, PLY, 3MF, OFF, GLB.")],
    device: DeviceOpt,
    layer_height: LayerHeightOpt,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder (created; replaced only if provably an earlier rotoprint output, or with --force).")],
    fibre_angle: FibreAngleOpt = None,
    fill: FillOpt = "nonzero",
    offset: OffsetOpt = None,
    gap_radius: GapRadiusOpt = DEFAULT_GAP_RADIUS_MM,
    dpi_y: DpiYOpt = None,
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
    rotary: Annotated[bool, typer.Option("--rotary", help="Direct rotary slicing: per-nozzle firing images straight from the mesh (inkjet heads).")] = False,
    tilt: Annotated[float | None, typer.Option("--tilt", help="--rotary: head tilt, degrees (counter-clockwise positive).", callback=in_range(R.TILT_DEG))] = None,
    radius: Annotated[float | None, typer.Option("--radius", help="--rotary: radius of the part's inner edge (smallest model X), mm.", callback=in_range(R.RADIUS_MM))] = None,
    angle: Annotated[float, typer.Option("--angle", help="--rotary: angle of the part's centre line on the platform, degrees.", callback=in_range(R.ANGLE_DEG))] = 0.0,
    direction: Annotated[int, typer.Option("--direction", help="--rotary: +1 platform turns counter-clockwise seen from above, -1 clockwise.", callback=direction_cb)] = 1,
    ref_radius: Annotated[float | None, typer.Option("--ref-radius", help="--rotary: reference radius of the clock, mm (default: each swathe's outermost track).", callback=in_range(R.RADIUS_MM))] = None,
    max_swathes: Annotated[int | None, typer.Option("--max-swathes", help="--rotary: refuse parts that need more radial swathes.", callback=in_range(R.SWATHES))] = None,
    equalise: Annotated[bool | None, typer.Option("--equalise/--no-equalise", help="--rotary: thin dense tracks so drops per unit area are uniform; with --passes N > 1 (on by default) over the union of the passes, --no-equalise: every drop.")] = None,
    reference_images: Annotated[bool, typer.Option("--reference-images", help="--rotary: also write each layer's Cartesian cross-section (for 'rotoprint simulate').")] = False,
    force: ForceOpt = False,
    passes: Annotated[str, typer.Option("--passes", help="--rotary: interlaced passes N or 'auto' (at most 4); N > 1 writes DIR-p1/, DIR-p2/, ... and DIR-passes.json.")] = "1",
) -> None:
    """Slice MESH into DIR/layer_00000.png ... (255 = material) and DIR/manifest.json.

    With --rotary: DIR/layer_00000.png (or -s1.png, -s2.png ... per swathe), rows = firings,
    columns = nozzles, a sidecar layer_00000.json per layer and DIR/manifest.json.
    """
    from ..devices import load_device
    from ..pipeline import RunOptions, write_layer_folder
    from ..slicing import slice_mesh

    from ..io.atomic import check_output_path

    setup_logging(is_verbose(verbose))
    quiet = is_quiet(quiet)
    inputs = [mesh, device_input(device)]
    check_output_path(out, is_dir=True, inputs=inputs, force=force)  # before any work
    if scheduler is not None:  # a malformed address or port is refused before any work
        from ..pipeline.producer import check_scheduler_address

        check_scheduler_address(scheduler)
    overrides = {"dpi_y": dpi_y} if dpi_y is not None else {}
    if rotary:
        _check_rotary_options(tilt=tilt, radius=radius, workers=workers, scheduler=scheduler, resume=resume,
                              fibre_angle=fibre_angle, offset=offset)
    elif any(v is not None for v in (tilt, radius, ref_radius, max_swathes)) or equalise is not None or reference_images or angle != 0.0 or direction != 1 or passes != "1":
        raise ConfigError("--tilt, --radius, --angle, --direction, --ref-radius, --max-swathes, --equalise, --reference-images and --passes need --rotary")
    dev = load_device(device, **overrides)
    m = load_mesh_from_options(mesh, units, scale, rotate, translate, fill_holes)
    if rotary:
        _slice_rotary(m, mesh, dev, out, force=force, inputs=inputs, layer_height=layer_height, tilt=tilt, radius=radius, angle=angle, direction=direction,
                      ref_radius=ref_radius, max_swathes=max_swathes, equalise=equalise, reference_images=reference_images,
                      fill=fill, gap_radius=gap_radius, quiet=quiet, workers=workers, scheduler=scheduler, resume=resume,
                      options={"units": units, "scale": scale, "rotate_deg": rotate, "translate_mm": translate,
                               "fill_holes": fill_holes}, passes=passes)
        return
    job = slice_mesh(
        m,
        dev,
        layer_height_mm=layer_height,
        fibre_angle_deg=fibre_angle,
        fill=fill,
        offset_mm=parse_pair(offset, "--offset"),
        gap_radius_mm=gap_radius,
    )
    options = {
        "layer_height_mm": layer_height,
        "fibre_angle_deg": fibre_angle,
        "fill": fill,
        "offset_mm": list(parse_pair(offset, "--offset")),
        "gap_radius_mm": gap_radius,
        "units": units,
        "scale": scale,
        "rotate_deg": rotate,
        "translate_mm": translate,
        "fill_holes": fill_holes,
    }
    with progress(quiet) as bar:
        task = bar.add_task("slicing", total=len(job))
        manifest = write_layer_folder(
            job,
            out,
            device_name=dev.name,
            device=dev.model_dump(mode="json"),
            options=options,
            run=RunOptions(workers=workers, scheduler=scheduler, resume=resume, force=force, inputs=tuple(inputs)),
            on_layer=lambda i: bar.advance(task),
        )
    if not quiet:
        g = job.grid
        left_open = sum(1 for L in manifest["layers"] if L["gaps"]["left_open"])
        closed = sum(L["gaps"]["closed"] for L in manifest["layers"])
        console.print(
            f"{len(job)} layers of {g.width} x {g.height} px at {g.pitch_x_mm * 1000:.2f} x {g.pitch_y_mm * 1000:.2f} um "
            f"-> {out}/ (manifest.json)"
        )
        holes = m.report.holes
        if holes.filled:
            console.print(styled(("mesh repaired:", "yellow"), f" {len(holes.filled)} hole(s) filled ({holes.filled_edges} edges, "
                                 f"{holes.filled_area_mm2:.4g} mm^2; see manifest 'mesh.holes')"))
        if closed or left_open:
            console.print(
                styled(("open mesh:", "yellow"), f" {closed} gap(s) closed within {gap_radius} mm; "
                       f"{left_open} layer(s) had chains left open and closed by a chord (see manifest 'gaps')")
            )


def _check_rotary_options(*, tilt, radius, workers, scheduler, resume, fibre_angle, offset) -> None:
    if tilt is None or radius is None:
        raise ConfigError("--rotary needs --tilt DEG and --radius MM (the radius of the part's inner edge)")
    refused = [name for name, bad in (("--fibre-angle", fibre_angle is not None), ("--offset", offset is not None)) if bad]
    if refused:
        raise ConfigError(f"{', '.join(refused)} cannot be used with --rotary (place the part with --radius/--angle and --rotate)")


def _slice_rotary(m, mesh_path: Path, dev, out: Path, *, layer_height, tilt, radius, angle, direction, ref_radius, max_swathes,
                  equalise, reference_images, fill, gap_radius, quiet, options, workers=1, scheduler=None, resume=False,
                  force=False, inputs=(), passes="1") -> None:
    from ..devices import InkjetDevice
    from ..pipeline import RunOptions, write_rotary_slices
    from ..rotary.direct import slice_rotary

    if not isinstance(dev, InkjetDevice):
        raise ConfigError(f"device {dev.name!r} is a projector; --rotary needs an inkjet device")
    if passes != "1":
        equalise = True if equalise is None else equalise  # union-equalised passes by default
        from ..constants import DEFAULT_GAP_RADIUS_MM
        from ..pipeline.passes import slice_rotary_passes
        from ..rotary.options import RotarySliceOptions

        ro = RotarySliceOptions(layer_height_mm=layer_height, tilt_deg=tilt, inner_radius_mm=radius, angle_deg=angle,
                                direction=direction, ref_radius_mm=ref_radius, max_swathes=max_swathes, equalise=equalise,
                                fill=fill, gap_radius_mm=DEFAULT_GAP_RADIUS_MM if gap_radius is None else gap_radius)
        man = slice_rotary_passes(m, dev, out, ro, passes=passes, reference_images=reference_images,
                                  record={"equalise": equalise, **options}, run=RunOptions(force=force, inputs=tuple(inputs)))
        if not quiet:
            pp = man["pass_plan"]
            console.print(f"{pp['passes']} interlaced pass(es), offsets {', '.join(f'{o * 1000:.1f}' for o in pp['offsets_mm'])} um, "
                          f"largest track gap {pp['largest_gap_mm'] * 1000:.1f} um (one pass {pp['single_pass_largest_gap_mm'] * 1000:.1f} um), "
                          f"clock {man['dpi_y']:.0f} dpi -> {', '.join(man['folders'])} ({out.name}-passes.json)")
            us = man["union_shares"]
            console.print(f"  equalised over the union of the passes: mean share {us['mean_share']:.3f}, {us['tracks_left_out']} of "
                          f"{us['tracks']} tracks left out, clock {us['clock_factor']} x the plan's" if us is not None else
                          "  plain passes: every track keeps every drop (--equalise: the union's shares)")
        return
    equalise = bool(equalise)
    job = slice_rotary(m, dev, layer_height_mm=layer_height, tilt_deg=tilt, inner_radius_mm=radius, angle_deg=angle,
                       direction=direction, ref_radius_mm=ref_radius, max_swathes=max_swathes, equalise=equalise,
                       fill=fill, gap_radius_mm=gap_radius)
    opts = {"layer_height_mm": layer_height, "tilt_deg": tilt, "radius_mm": radius, "angle_deg": angle, "direction": direction,
            "ref_radius_mm": ref_radius, "max_swathes": max_swathes, "equalise": equalise, "fill": fill,
            "gap_radius_mm": gap_radius, "reference_images": reference_images, **options}
    mesh_info = {"path": str(mesh_path), "triangles": int(m.faces.shape[0]), "bounds_mm": [list(map(float, b)) for b in m.bounds]}
    with progress(quiet) as bar:
        task = bar.add_task("slicing (rotary)", total=len(job))
        manifest = write_rotary_slices(job, out, device_name=dev.name, options=opts, mesh_info=mesh_info,
                                       reference_images=reference_images, on_layer=lambda i: bar.advance(task),
                                       run=RunOptions(workers=workers, scheduler=scheduler, resume=resume, force=force,
                                                      inputs=tuple(inputs)))
    if not quiet:
        ds = manifest["density_spread"]
        console.print(
            f"{len(job)} layers, {len(job.tracks)} swathe(s) at tilt {tilt:g} deg, part inner edge at {radius:g} mm, "
            f"centre line at {angle:g} deg -> {out}/ (manifest.json)"
        )
        for s in manifest["swathes"]:
            console.print(
                f"  swathe {s['index'] + 1}: pivot {s['pivot_radius_mm']:.4f} mm, band {s['band_mm'][0]:.3f}-{s['band_mm'][1]:.3f} mm, "
                f"{s['tracks']} tracks, {s['firings']} firings from index {s['first_firing_index']}, {s['angle_per_firing_deg']:.5f} deg/firing"
            )
        console.print(
            f"  drops per unit area across the part: spread {100 * ds['without_equalisation']:.1f} % without equalisation, "
            f"{100 * ds['with_equalisation']:.1f} % with it ({'on' if equalise else 'off: --equalise'})"
        )
