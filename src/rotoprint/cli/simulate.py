"""`rotoprint simulate PRINT.png`: place every drop and compare with the design."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Annotated

import typer

from ..errors import ConfigError, InputFileError
from ._common import ForceOpt, JsonOpt, console, out_console, print_json


def parse_dead(text: str | None) -> tuple[int, ...]:
    if not text:
        return ()
    try:
        return tuple(sorted({int(t) for t in text.split(",") if t.strip()}))
    except ValueError:
        raise ConfigError(f"--dead must be nozzle indices 'K,K,...', got {text!r}") from None


def simulate_command(
    print_file: Annotated[Path, typer.Argument(help="A print written by 'rotoprint transform' (PRINT.png, PRINT-s1.png or PRINT.json).")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Overlay PNG: design, drops and errors in colour.")],
    design: Annotated[Path | None, typer.Option("--design", help="Design image (default: the one named in the sidecar, if unchanged).")] = None,
    drop_diameter: Annotated[float | None, typer.Option("--drop-diameter", help="Drop diameter on the substrate, um (default: the head's).")] = None,
    jitter: Annotated[float, typer.Option("--jitter", help="Drop misdirection, standard deviation in um per axis.")] = 0.0,
    dead: Annotated[str | None, typer.Option("--dead", help="Extra dead nozzles 'K,K,...'.")] = None,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the jitter.")] = 0,
    scale: Annotated[int, typer.Option("--scale", help="Overlay pixels per design pixel.")] = 2,
    json_out: JsonOpt = False,
    force: ForceOpt = False,
) -> None:
    """IoU, area ratio, mean/max placement error, uncovered design area, drops outside the design."""
    from ..io.atomic import check_output_path, write_owned_file
    from ..io.images import read_grey_image
    from ..rotary.files import read_print
    from ..rotary.simulate import render_overlay, simulate

    if out.suffix.lower() != ".png":
        raise ConfigError(f"--out must end in .png, got {out.name!r}")
    check_output_path(out, is_dir=False, inputs=[print_file, design], force=force)  # before anything is read
    pr, side, sp = read_print(print_file)
    inputs = [print_file, sp, design, *(sp.parent / s.get("file", "") for s in side.get("swathes", []) if isinstance(s, dict))]
    check_output_path(out, is_dir=False, inputs=inputs, force=force)
    dinfo = side.get("design", {})
    if design is None:
        cand = Path(dinfo.get("path", ""))
        if dinfo.get("path") and not cand.is_absolute():
            cand = sp.parent / cand  # a path relative to the sidecar's folder
        if not dinfo.get("path") or not cand.exists():
            raise InputFileError("the design named in the sidecar is not available; give --design IMAGE", path=sp)
        if hashlib.sha256(cand.read_bytes()).hexdigest() != dinfo.get("sha256"):
            raise InputFileError(f"the design {cand} changed since the transform; give --design IMAGE", path=sp)
        design = cand
        inputs.append(design)
        check_output_path(out, is_dir=False, inputs=inputs, force=force)
    img = read_grey_image(design)
    if dinfo.get("invert"):
        img = 255 - img
    sim = simulate(pr, img, drop_diameter_um=drop_diameter, jitter_um=jitter, dead_nozzles=parse_dead(dead), seed=seed)
    overlay = render_overlay(sim, scale=scale)
    from PIL import Image
    import io

    buf = io.BytesIO()
    Image.fromarray(overlay, mode="RGB").save(buf, format="PNG", compress_level=3)
    write_owned_file(out, buf.getvalue(), kind="simulate-overlay", inputs=inputs, force=force)
    r = sim.report.to_json()
    r["method"] = pr.method
    r["tilt_deg"] = pr.tilt_deg
    r["swathes"] = len(pr.swathes)
    r["overlay"] = str(out)
    if json_out:
        print_json(r)
        return
    out_console.print(
        f"{pr.method} print, tilt {pr.tilt_deg:g} deg, {len(pr.swathes)} swathe(s), {r['drops']} drops\n"
        f"  IoU {r['iou']:.4f}   area ratio {r['area_ratio']:.4f}\n"
        f"  placement error: mean {r['mean_error_px']:.3f} px ({r['mean_error_um']:.1f} um), max {r['max_error_px']:.3f} px ({r['max_error_um']:.1f} um)\n"
        f"  design left uncovered: {r['uncovered_pixels']} px ({100 * r['uncovered_fraction']:.2f} %, {r['uncovered_area_mm2']:.3f} mm2)\n"
        f"  drops outside the design: {r['drops_outside']} ({100 * r['drops_outside_fraction']:.2f} %)\n"
        f"  {r['drop_diameter_um']:g} um discs: IoU {r['disc_iou']:.4f}, uncovered {100 * r['disc_uncovered_fraction']:.2f} %"
    )
    console.print(f"overlay -> {out} (light blue: printed design, orange: uncovered, pink: printed outside, dots: drops, red = stray)")
