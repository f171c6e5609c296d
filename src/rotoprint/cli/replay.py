"""`rotoprint replay DIR/machine/program.json --out OVERLAY.png`: decode a machine program and
place every drop as the machine would (at its clock's angles); the figures and JSON keys of
`rotoprint simulate`, and how far the clock moves the drops off their nominal sites."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .. import ranges as R
from ..errors import ConfigError
from ._common import ForceOpt, JsonOpt, console, in_range, out_console, print_json, progress


def replay_command(
    program: Annotated[Path, typer.Argument(help="machine/program.json written by 'rotoprint build'.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Overlay PNG of one layer's images (design, drops, errors).")],
    layer: Annotated[int | None, typer.Option("--layer", help="Replay only this layer (every step is still checked).", callback=in_range(R.COUNT))] = None,
    scale: Annotated[int, typer.Option("--scale", help="Overlay pixels per design pixel.", callback=in_range(R.OVERLAY_SCALE))] = 2,
    deposit: Annotated[bool, typer.Option("--deposit", help="Also run the deposit model (film thickness, coverage) on every image; about a second each.")] = False,
    angles: Annotated[str, typer.Option("--angles", help="Fire at the angles the machine's clock gives ('machine': index offset in whole encoder counts, integer multiplier/divider) or at the nominal ones ('nominal').")] = "machine",
    json_out: JsonOpt = False,
    force: ForceOpt = False,
) -> None:
    """Read only the program and its packed files, decode them, land every drop and compare
    with each layer's design region: IoU, coverage, placement errors per layer, ink and head."""
    import io

    import numpy as np
    from PIL import Image

    from ..io.atomic import check_output_path, write_owned_file
    from ..machine.replay import ANGLES, replay_program
    from ..rotary.simulate import render_overlay

    if angles not in ANGLES:
        raise ConfigError(f"--angles must be one of {', '.join(ANGLES)}, got {angles!r}")
    if out.suffix.lower() != ".png":
        raise ConfigError(f"--out must end in .png, got {out.name!r}")
    root = program.parent
    check_output_path(out, is_dir=False, inputs=[program, root], force=force)  # before anything is read
    with progress() as bar:
        task = bar.add_task("replay", total=None)

        def on_step(stage: str, done: int, total: int) -> None:
            bar.update(task, completed=done, total=total)

        keep = 0 if layer is None else layer
        res = replay_program(program, layer=layer, on_step=on_step, keep_layer=keep, overlay_scale=scale,
                             deposit=deposit, angles=angles)
    sims = res.pop("_sims")
    if sims:
        tiles = [render_overlay(sim, scale=scale) for _, sim in sims]
        w = max(t.shape[1] for t in tiles)
        gap = np.full((4, w, 3), 255, np.uint8)
        rows = []
        for t in tiles:
            rows.append(np.pad(t, ((0, 0), (0, w - t.shape[1]), (0, 0)), constant_values=255))
            rows.append(gap)
        img = np.concatenate(rows[:-1])
    else:
        img = np.full((8, 8, 3), 255, np.uint8)
    buf = io.BytesIO()
    Image.fromarray(img, mode="RGB").save(buf, format="PNG", compress_level=3)
    write_owned_file(out, buf.getvalue(), kind="replay-overlay", inputs=[program], force=force)
    res["overlay"] = str(out)
    res["overlay_layer"] = keep
    res["overlay_images"] = [f"{im.material}/{im.ink} on {im.head}" for im, _ in sims]
    if json_out:
        print_json(res)
        return
    out_console.print(f"{program}: {res['layers']} layers, {res['steps']} steps, {res['revolutions']} revolutions, "
                      f"{res['time_s']:.1f} s; clock error up to {res['clock']['max_angle_error_per_rev_deg']:.2g} deg/rev"
                      + (f", FLAGGED: {', '.join(res['clock']['flagged'])}" if res["clock"]["flagged"] else "")
                      + (f"; drops at the machine's angles, up to {res['clock']['max_drop_displacement_um']:.3g} um off their "
                         "nominal sites" if angles == "machine" else "; drops at the nominal angles"))
    for r in res["images"]:
        out_console.print(f"  layer {r['layer']:5d} {r['material']}/{r['ink']} on {r['head']}: {r['drops']} drops, "
                          f"IoU {r['iou']:.4f}, uncovered {100 * r['uncovered_fraction']:.2f} %, "
                          f"outside {r['drops_outside']}, mean error {r['mean_error_um']:.1f} um"
                          + (f"; film: uncovered {100 * r['deposit']['uncovered_fraction']:.2f} %, mean {r['deposit']['mean_um']:.3f} um"
                             if "deposit" in r else ""))
    out_console.print(f"  lowest IoU {res['iou']:.4f}, highest uncovered {100 * res['uncovered_fraction']:.2f} %")
    console.print(f"overlay of layer {keep} -> {out}")
