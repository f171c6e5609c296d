"""`rotoprint check [MESH]`: what a part loses on a device, before the print.

Exit codes: 0 nothing falls short, 3 something does (the report and overlays are written
first), 2 bad input (one line on stderr, nothing written). Without MESH: the smallest wall and
gap the device prints for sure, and exit 0.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Annotated

import typer
from rich.text import Text

from ..constants import DEFAULT_GAP_RADIUS_MM
from ..errors import ConfigError
from .. import ranges as R
from ..ranges import check_count, check_range
from ._common import in_range
from ._common import (
    styled,
    DeviceOpt,
    ForceOpt,
    JsonOpt,
    RotateOpt,
    ScaleOpt,
    FillHolesOpt,
    TranslateOpt,
    UnitsOpt,
    device_input,
    load_mesh_from_options,
    out_console,
    parse_pair,
    print_json,
    progress,
)

EXIT_SHORT = 3
REPORT_NAME = "report.json"
_MAX_ANGLES = 360


def parse_orientations(text: str) -> list[float]:
    """'A:B:STEP' (degrees) into the angles A, A+STEP, ... up to B inclusive."""
    parts = text.split(":")
    try:
        a, b, step = (float(t) for t in parts)
    except ValueError:
        raise ConfigError(f"--orientations must be 'A:B:STEP' in degrees, got {text!r}") from None
    if not all(math.isfinite(v) for v in (a, b, step)) or step <= 0 or b < a:
        raise ConfigError(f"--orientations needs finite A <= B and STEP > 0, got {text!r}")
    check_range(a, R.ANGLE_DEG, "--orientations A")
    check_range(b, R.ANGLE_DEG, "--orientations B")
    n = check_count(math.floor((b - a) / step + 1e-9), "--orientations: the number of angles", _MAX_ANGLES) + 1
    if n > _MAX_ANGLES:
        raise ConfigError(f"--orientations gives {n} angles, more than {_MAX_ANGLES}")
    return [a + i * step for i in range(n)]


def _um(v) -> str:
    return "-" if v is None else f"{v * 1000:.1f}"


def _limits_table(lim: dict):
    from rich.table import Table

    t = Table(title=f"What {lim['device']} prints for sure", title_justify="left")
    t.add_column("")
    t.add_column("wall (um)", justify="right")
    t.add_column("gap (um)", justify="right")
    t.add_row("across columns (x)", _um(lim.get("min_wall_x_mm")), _um(lim.get("min_gap_x_mm")))
    t.add_row("across rows (y)", _um(lim.get("min_wall_y_mm")), _um(lim.get("min_gap_y_mm")))
    t.add_row(Text("any direction", style="bold"), Text(_um(lim.get("min_wall_mm")), style="bold"),
              Text(_um(lim.get("min_gap_mm")), style="bold"))
    return t


def _rotary_lines(rot: dict) -> list[str]:
    return [
        f"rotary, tilt {rot['tilt_deg']:g} deg at pivot radius {rot['radius_mm']:g} mm: track pitch p cos(tilt) "
        f"{rot['track_pitch_nominal_mm'] * 1000:.1f} um, rows offset {rot['row_offset_mm'] * 1000:.1f} um, "
        f"largest gap between neighbouring tracks {rot['largest_track_gap_mm'] * 1000:.1f} um, "
        f"projected swathe {rot['projected_swathe_mm']:.2f} mm, drop spacing along tracks "
        f"{rot['along_track_spacing_mm'][0] * 1000:.1f}-{rot['along_track_spacing_mm'][1] * 1000:.1f} um"
    ]


def _summary(rep, orient: dict | None, out: Path | None, n_overlays: int) -> None:
    from rich.table import Table

    from ..check import KINDS

    j = rep.to_json()
    st = rep.settings
    out_console.print(_limits_table(rep.limits))
    out_console.print(f"basis: {rep.limits['basis']}")
    if "rotary" in rep.limits:
        for line in _rotary_lines(rep.limits["rotary"]):
            out_console.print(line)
    t = Table(
        title=f"Check: {rep.n_layers} layers, walls under {st['min_wall_mm'] * 1000:.1f} um, gaps under {st['min_gap_mm'] * 1000:.1f} um",
        title_justify="left",
    )
    for col, just in (("problem", "left"), ("found", "right"), ("regions", "right"), ("layers", "right"), ("worst", "right"), ("at layer, x, y (mm)", "left")):
        t.add_column(col, justify=just)
    by_kind: dict[str, list] = {k: [] for k in KINDS}
    for f in rep.findings:
        by_kind[f.kind].append(f)
    n_regions = {k: 0 for k in KINDS}
    for r in j["regions"]:
        n_regions[r["kind"]] += 1
    for k in KINDS:
        fs = by_kind[k]
        if k in ("underexposed", "cured_gap") and st["exposure_model"] is None:
            continue
        if k == "island" and not st["islands"]:
            continue
        if k == "cavity" and not st.get("cavities", True):
            continue
        if not fs:
            t.add_row(k.replace("_", " "), Text("0", style="green"), "0", "0", "", "")
            continue
        if k == "island":
            w = max(fs, key=lambda f: f.area_mm2)
            worst = f"{w.area_mm2:.4g} mm2"
        elif k == "cavity":
            w = max(fs, key=lambda f: f.volume_mm3)
            worst = f"{w.volume_mm3:.4g} mm3"
        else:
            w = min(fs, key=lambda f: f.width_mm)
            worst = f"{w.width_mm * 1000:.1f} um"
        t.add_row(k.replace("_", " "), Text(str(len(fs)), style="red"), str(n_regions[k]), str(len({f.layer for f in fs})), worst,
                  f"{w.layer}, {w.x_mm:.3f}, {w.y_mm:.3f}")
    out_console.print(t)
    for name, key in (("thinnest wall", "thinnest_wall"), ("narrowest gap", "narrowest_gap")):
        v = j[key]
        if v is None:
            out_console.print(f"{name}: none under {st['measured_up_to_mm'] * 1000:.0f} um")
        else:
            out_console.print(f"{name}: {v['width_mm'] * 1000:.1f} um at layer {v['layer']} (z {v['z_mm']:.3f} mm), x {v['x_mm']:.3f}, y {v['y_mm']:.3f} mm")
    if orient is not None:
        ot = Table(title="Orientations (fibre angle): length lost to the raster and exposure", title_justify="left")
        for col in ("angle (deg)", "lost (mm)", "islands (mm2)", "problems"):
            ot.add_column(col, justify="right")
        for r in orient["rows"]:
            best = " *" if r["angle_deg"] == orient["best_angle_deg"] else ""
            ot.add_row(f"{r['angle_deg']:g}{best}", f"{r['loss_mm']:.3f}", f"{r['island_area_mm2']:.4g}", str(sum(r["counts"].values())))
        out_console.print(ot)
        out_console.print(f"least loss at fibre angle {orient['best_angle_deg']:g} deg")
    verdict = ("nothing falls short", "green") if rep.ok else (f"{len(rep.findings)} problem(s)", "red")
    where = f" -> {out}/ ({REPORT_NAME}, {n_overlays} overlay(s))" if out is not None else ""
    out_console.print(styled(verdict, where))


def check_command(
    mesh: Annotated[Path | None, typer.Argument(help="Mesh file (STL, OBJ, PLY, 3MF, OFF, GLB). Without it: the device's limits only.")] = None,
    device: DeviceOpt = ...,  # type: ignore[assignment]
    layer_height: Annotated[float | None, typer.Option("--layer-height", help="Layer height, mm (needed with MESH).", callback=in_range(R.LAYER_HEIGHT_MM))] = None,
    min_wall: Annotated[float | None, typer.Option("--min-wall", help="Thinnest wall that prints, mm. Default: the device pitch, or an inkjet's drop diameter if larger.", callback=in_range(R.WIDTH_MM))] = None,
    min_gap: Annotated[float | None, typer.Option("--min-gap", help="Narrowest gap that stays open, mm. Default as --min-wall.", callback=in_range(R.WIDTH_MM))] = None,
    out: Annotated[Path | None, typer.Option("--out", "-o", help="Output folder: report.json and overlays/layer_NNNNN.png (created; replaced only if provably an earlier rotoprint output, or with --force).")] = None,
    json_out: JsonOpt = False,
    fibre_angle: Annotated[float | None, typer.Option("--fibre-angle", help="Fibre direction in the model's XY plane, degrees from +X.", callback=in_range(R.ANGLE_DEG))] = None,
    orientations: Annotated[str | None, typer.Option("--orientations", help="'A:B:STEP' degrees: check every fibre angle and say which loses least.")] = None,
    rotary: Annotated[bool, typer.Option("--rotary", help="Inkjet on the rotary platform: add the track figures (needs --tilt and --radius).")] = False,
    tilt: Annotated[float | None, typer.Option("--tilt", help="Head tilt, degrees (with --rotary).", callback=in_range(R.TILT_DEG))] = None,
    radius: Annotated[float | None, typer.Option("--radius", help="Pivot radius of the head, mm (with --rotary).", callback=in_range(R.RADIUS_MM))] = None,
    mask: Annotated[str, typer.Option("--mask", help="Exposure model for DLP masks: none, binary or smooth (the paper's SMOOTH filter).")] = "none",
    cure_threshold: Annotated[float | None, typer.Option("--cure-threshold", help="Fraction of full exposure that cures (with --mask). Default: the projector's.", callback=in_range(R.FRACTION))] = None,
    islands: Annotated[bool, typer.Option("--islands/--no-islands", help="Look for regions with nothing below them.")] = True,
    cavities: Annotated[bool, typer.Option("--cavities/--no-cavities", help="Look for empty space the part shuts in (resin traps).")] = True,
    resolution: Annotated[float | None, typer.Option("--resolution", help="Measure widths on the section simplified to this deviation, mm (widths within twice it). Default: 1/100 pixel; 0: the section as sliced.", callback=in_range(R.RESOLUTION_MM))] = None,
    max_overlays: Annotated[int, typer.Option("--max-overlays", help="Write at most this many overlay images (layers with problems, first first).", callback=in_range(R.COUNT))] = 200,
    fill: Annotated[str, typer.Option("--fill", help="Fill rule: nonzero or evenodd.")] = "nonzero",
    offset: Annotated[str | None, typer.Option("--offset", help="'X,Y' mm: the part's centre relative to the field centre.")] = None,
    gap_radius: Annotated[float, typer.Option("--gap-radius", help="Open meshes: join open ends closer than this, mm.", callback=in_range(R.GAP_RADIUS_MM))] = DEFAULT_GAP_RADIUS_MM,
    dpi_y: Annotated[float | None, typer.Option("--dpi-y", help="Inkjet: print-direction density, dpi.", callback=in_range(R.DPI))] = None,
    units: UnitsOpt = "mm",
    scale: ScaleOpt = 1.0,
    rotate: RotateOpt = None,
    translate: TranslateOpt = None,
    fill_holes: FillHolesOpt = True,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar or summary.")] = False,
    force: ForceOpt = False,
) -> None:
    """Check MESH for walls and gaps below the device's minimum, features lost to the raster,
    islands and (--mask) features that do not cure. Exit 0: nothing falls short; 3: something
    does (after writing the report); 2: bad input."""
    from ..check import CheckOptions, check_printability, compare_orientations, device_limits, mask_model, overlay_image
    from ..check.options import resolution_for
    from ..devices import load_device
    from ..io.atomic import atomic_dir, atomic_file, check_output_path

    inputs = [mesh, device_input(device)]
    if out is not None:
        check_output_path(out, is_dir=True, inputs=inputs, force=force)  # before anything is read

    # -------- every option is validated before anything is read or written
    dev = load_device(device, **({"dpi_y": dpi_y} if dpi_y is not None else {}))
    if rotary:
        if tilt is None or radius is None:
            raise ConfigError("--rotary needs --tilt DEG and --radius MM")
        if dev.kind != "inkjet":
            raise ConfigError(f"--rotary needs an inkjet head, {dev.name} is a {dev.kind}")
    elif tilt is not None or radius is not None:
        raise ConfigError("--tilt and --radius go with --rotary")
    mask_fn = None
    if mask != "none":
        mask_fn = mask_model(mask)
        if dev.kind != "projector":
            raise ConfigError(f"--mask applies to projectors, {dev.name} is a {dev.kind}")
    elif cure_threshold is not None:
        raise ConfigError("--cure-threshold needs --mask binary or smooth")
    if max_overlays < 0:
        raise ConfigError(f"--max-overlays must be >= 0, got {max_overlays}")
    angles = parse_orientations(orientations) if orientations is not None else None
    resolution_for(dev, resolution)  # refused now, before anything is read
    rot_kw = {"tilt_deg": tilt, "radius_mm": radius} if rotary else {}

    if mesh is None:
        if out is not None or orientations is not None or layer_height is not None:
            raise ConfigError("--out, --orientations and --layer-height need a MESH to check")
        lim = device_limits(dev, mask_fn=mask_fn, cure_threshold=cure_threshold, **rot_kw)
        if json_out:
            print_json({"limits": lim})
        elif not quiet:
            out_console.print(_limits_table(lim))
            out_console.print(f"basis: {lim['basis']}")
            if "rotary" in lim:
                for line in _rotary_lines(lim["rotary"]):
                    out_console.print(line)
        return
    if layer_height is None:
        raise ConfigError("--layer-height is needed to check a mesh")
    m = load_mesh_from_options(mesh, units, scale, rotate, translate, fill_holes)
    slice_options = {"fill": fill, "offset_mm": parse_pair(offset, "--offset"), "gap_radius_mm": gap_radius}
    options = CheckOptions(
        min_wall_mm=min_wall,
        min_gap_mm=min_gap,
        mask_fn=mask_fn,
        mask_name=mask,
        cure_threshold=cure_threshold,
        islands=islands,
        resolution_mm=resolution,
        cavities=cavities,
        **rot_kw,
    )

    def run(folder: Path | None):
        written: list[str] = []

        def on_layer(lc) -> None:
            if folder is not None and lc.findings and len(written) < max_overlays:
                from PIL import Image

                name = f"overlays/layer_{lc.index:05d}.png"
                Image.fromarray(overlay_image(lc)).save(folder / name, format="PNG", compress_level=3)
                written.append(name)
            bar.advance(task)

        with progress(quiet or json_out) as bar:
            from ..slicing import slice_mesh

            job = slice_mesh(m, dev, layer_height_mm=layer_height, fibre_angle_deg=fibre_angle, **slice_options)
            task = bar.add_task("checking", total=len(job))
            if folder is not None:
                (folder / "overlays").mkdir()
            rep = check_printability(job, dev, options, on_layer=on_layer)
            rep.settings["fibre_angle_deg"] = fibre_angle
            orient = None
            if angles is not None:
                task2 = bar.add_task("orientations", total=len(angles))
                orient = compare_orientations(m, dev, options, angles_deg=angles, layer_height_mm=layer_height, slice_options=slice_options)
                bar.advance(task2, len(angles))
        data = rep.to_json()
        data["mesh"] = str(mesh)
        data["overlays"] = written
        data["overlays_skipped"] = max(0, len(rep.layers_with_findings) - len(written)) if folder is not None else None
        if orient is not None:
            data["orientations"] = orient
        if folder is not None:
            with atomic_file(folder / REPORT_NAME, "w") as fh:
                fh.write(json.dumps(data, indent=2) + "\n")
        return rep, data, orient, written

    if out is not None:
        with atomic_dir(out, kind="check-report", inputs=inputs, force=force) as tmp:
            rep, data, orient, written = run(tmp)
    else:
        rep, data, orient, written = run(None)
    if json_out:
        print_json(data)
    elif not quiet:
        _summary(rep, orient, out, len(written))
    if not rep.ok:
        raise typer.Exit(EXIT_SHORT)
