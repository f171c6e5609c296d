"""`rotoprint simulate PRINT.png`: place every drop and compare with the design."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Annotated

import typer

from ..errors import ConfigError, InputFileError
from .. import ranges as R
from ..ranges import NOZZLE_INDEX, check_range
from ._common import ForceOpt, JsonOpt, console, in_range, out_console, print_json


def parse_dead(text: str | None) -> tuple[int, ...]:
    if not text:
        return ()
    try:
        ks = {int(t) for t in text.split(",") if t.strip()}
    except ValueError:
        raise ConfigError(f"--dead must be nozzle indices 'K,K,...', got {text!r}") from None
    for k in ks:  # the head's own count is checked by simulate(); this keeps them machine ints
        check_range(k, NOZZLE_INDEX, "--dead")
    return tuple(sorted(ks))


def simulate_command(
    print_file: Annotated[list[Path], typer.Argument(help="A print written by 'rotoprint transform' (PRINT.png, PRINT-s1.png or PRINT.json); "
                                                 "several, or a PRINT-passes.json: the passes of one layer, deposited together.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Overlay PNG: design, drops and errors in colour.")],
    design: Annotated[Path | None, typer.Option("--design", help="Design image (default: the one named in the sidecar, if unchanged).")] = None,
    drop_diameter: Annotated[float | None, typer.Option("--drop-diameter", help="Drop diameter on the substrate, um (default: the head's).", callback=in_range(R.DROP_UM))] = None,
    jitter: Annotated[float, typer.Option("--jitter", help="Drop misdirection, standard deviation in um per axis.", callback=in_range(R.JITTER_UM))] = 0.0,
    dead: Annotated[str | None, typer.Option("--dead", help="Extra dead nozzles 'K,K,...'.")] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the jitter.", callback=in_range(R.SEED))] = 0,
    spread: Annotated[float | None, typer.Option("--spread", help="Deposit model: footprint / in-flight diameter (default: the head's spread_factor).", callback=in_range(R.SPREAD))] = None,
    footprint: Annotated[float | None, typer.Option("--footprint", help="Deposit model: footprint diameter of a full drop, um (instead of --spread).", callback=in_range(R.DROP_UM))] = None,
    set_time: Annotated[float | None, typer.Option("--set-time", help="Film levelling: seconds the wet film flows before it sets (default: the head's set_time_s; 0: the film as landed).", callback=in_range(R.SET_TIME_S))] = None,
    viscosity: Annotated[float | None, typer.Option("--viscosity", help="Film levelling: ink viscosity, mPa s (default: the head's).", callback=in_range(R.VISCOSITY_MPA_S))] = None,
    surface_tension: Annotated[float | None, typer.Option("--surface-tension", help="Film levelling: ink surface tension, mN/m (default: the head's).", callback=in_range(R.SURFACE_TENSION_MN_M))] = None,
    h0_percentile: Annotated[float, typer.Option("--h0-percentile", help="Film levelling: the linear model's film thickness h0 is this percentile of the as-landed wet interior film.", callback=in_range(R.PERCENT))] = 10.0,
    scale: Annotated[int, typer.Option("--scale", help="Overlay pixels per design pixel.", callback=in_range(R.OVERLAY_SCALE))] = 2,
    json_out: JsonOpt = False,
    force: ForceOpt = False,
) -> None:
    """Deposited film (uncovered interior, thinnest/mean thickness, radial spread), IoU, placement error, drops outside."""
    from ..io.atomic import check_output_path, write_owned_file
    from ..io.images import read_grey_image
    from ..io.inputs import MAX_IMAGE_BYTES, read_input_bytes
    from ..rotary.files import read_print
    from ..rotary.simulate import check_overlay_fits, render_overlay, simulate

    if out.suffix.lower() != ".png":
        raise ConfigError(f"--out must end in .png, got {out.name!r}")
    from ..io.inputs import MAX_JSON_BYTES
    from ..rotary.interlace import PASSES_FORMAT, read_passes

    check_output_path(out, is_dir=False, inputs=[*print_file, design], force=force)  # before anything is read
    paths: list[Path] = []
    for f in print_file:
        is_passes = f.suffix.lower() == ".json" and PASSES_FORMAT.encode() in read_input_bytes(
            f, what="print sidecar", limit_bytes=MAX_JSON_BYTES)[:400]
        paths.extend(read_passes(f) if is_passes else [f])
    prints = [read_print(f) for f in paths]
    pr, side, sp = prints[0]
    for other, _, osp in prints[1:]:
        if other.placement != pr.placement or other.head != pr.head:
            raise InputFileError(f"this pass is not of the same design and head as {sp.name}", path=osp)
    inputs: list = [*print_file, design]
    for _, side_q, sp_q in prints:
        inputs += [sp_q, *(sp_q.parent / s.get("file", "") for s in side_q.get("swathes", []) if isinstance(s, dict))]
    check_output_path(out, is_dir=False, inputs=inputs, force=force)
    dinfo = side.get("design", {})
    if design is None:
        cand = Path(dinfo.get("path", ""))
        if dinfo.get("path") and not cand.is_absolute():
            cand = sp.parent / cand  # a path relative to the sidecar's folder
        if not dinfo.get("path") or not cand.exists():
            raise InputFileError("the design named in the sidecar is not available; give --design IMAGE", path=sp)
        data = read_input_bytes(cand, what="design image", limit_bytes=MAX_IMAGE_BYTES)
        if hashlib.sha256(data).hexdigest() != dinfo.get("sha256"):
            raise InputFileError(f"the design {cand} changed since the transform; give --design IMAGE", path=sp)
        design = cand
        inputs.append(design)
        check_output_path(out, is_dir=False, inputs=inputs, force=force)
    img = read_grey_image(design)
    if dinfo.get("invert"):
        img = 255 - img
    check_overlay_fits(img.shape, scale)  # before the simulation, not after it
    sim = simulate(pr, img, drop_diameter_um=drop_diameter, jitter_um=jitter, dead_nozzles=parse_dead(dead), seed=seed)
    from ..rotary.deposit import DepositOptions, LevelOptions, deposit_film, ink_drops

    if spread is not None and footprint is not None:
        raise ConfigError("give either --spread or --footprint, not both")
    from ..rotary.deposit import InkDrops
    from ..rotary.simulate import place_drops

    parts = [ink_drops(sim.drops, pr.head)] + [
        ink_drops(place_drops(o, jitter_um=jitter, dead_nozzles=parse_dead(dead), seed=seed + q + 1), pr.head)
        for q, (o, _, _) in enumerate(prints[1:])
    ]
    film = deposit_film(sim.inked, pr.placement, pr.head, [InkDrops.concat(parts)],
                        options=DepositOptions(spread_factor=spread, footprint_um=footprint,
                                               level=LevelOptions.from_head(pr.head, set_time_s=set_time, viscosity_mpa_s=viscosity,
                                                                            surface_tension_mn_m=surface_tension, h0_percentile=h0_percentile))).films[0]
    overlay = render_overlay(sim, scale=scale)
    from PIL import Image
    import io

    buf = io.BytesIO()
    Image.fromarray(overlay, mode="RGB").save(buf, format="PNG", compress_level=3)
    write_owned_file(out, buf.getvalue(), kind="simulate-overlay", inputs=inputs, force=force)
    r = {"deposit": film.to_json(), **sim.report.to_json()}
    r["method"] = pr.method
    r["tilt_deg"] = pr.tilt_deg
    r["swathes"] = len(pr.swathes)
    r["passes"] = len(prints)
    r["overlay"] = str(out)
    if json_out:
        print_json(r)
        return
    f = r["deposit"]
    lv = f.get("levelled")
    if lv is not None:
        out_console.print(
            f"levelled film (headline; set time {lv['set_time_s']:g} s, viscosity {lv['viscosity_mpa_s']:g} mPa s, surface tension "
            f"{lv['surface_tension_mn_m']:g} mN/m, h0 {lv['h0_um']:.2f} um = {lv['h0_rule']}, levelling length {lv['levelling_length_um']:.0f} um): "
            f"thinnest / mean {lv['thinnest_to_mean']:.3f} (mean {lv['mean_um']:.3f} um, thinnest {lv['thinnest_um']:.3f} um), 1 mm radial bins within "
            f"+-{100 * lv['radial_spread']:.1f} %; uncovered as landed (a dry pinhole is not filled by the linear model)"
        )
    else:
        out_console.print("film as landed (no levelling: set time 0 s)")
    out_console.print(
        f"{'as landed: ' if lv is not None else ''}film of {len(prints)} pass(es) ({f['footprint_um']:.1f} um footprints): interior uncovered {100 * f['uncovered_fraction']:.2f} % "
        f"({f['uncovered_area_mm2']:.3f} mm2), boundary band {100 * f['band_uncovered_fraction']:.2f} %; "
        f"thickness mean {f['mean_um']:.3f} um, thinnest {f['thinnest_um']:.3f} um (thinnest / mean {f['thinnest_to_mean']:.3f}), 1 mm radial bins within "
        f"+-{100 * f['radial_spread']:.1f} %; ink volume {f['deposited_volume_pl']:.0f} pl "
        f"(planned {f['planned_volume_pl']:.0f}), {100 * f['volume_outside_design_fraction']:.2f} % outside the design"
    )
    out_console.print(
        f"{'pass 1: ' if len(prints) > 1 else ''}{pr.method} print, tilt {pr.tilt_deg:g} deg, {len(pr.swathes)} swathe(s), {r['drops']} drops\n"
        f"  cell model: IoU {r['iou']:.4f}   area ratio {r['area_ratio']:.4f}\n"
        f"  placement error: mean {r['mean_error_px']:.3f} px ({r['mean_error_um']:.1f} um), max {r['max_error_px']:.3f} px ({r['max_error_um']:.1f} um)\n"
        f"  design left uncovered: {r['uncovered_pixels']} px ({100 * r['uncovered_fraction']:.2f} %, {r['uncovered_area_mm2']:.3f} mm2)\n"
        f"  drops outside the design: {r['drops_outside']} ({100 * r['drops_outside_fraction']:.2f} %)\n"
        f"  {r['drop_diameter_um']:g} um discs: IoU {r['disc_iou']:.4f}, uncovered {100 * r['disc_uncovered_fraction']:.2f} %"
    )
    console.print(f"overlay -> {out} (light blue: printed design, orange: uncovered, pink: printed outside, dots: drops, red = stray)")
