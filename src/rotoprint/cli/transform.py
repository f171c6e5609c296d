"""`rotoprint transform IMAGE`: a design made print-ready for a rotary platform."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Annotated

import typer

from ..errors import ConfigError
from .options import is_quiet, DpiYOpt, QuietOpt
from .. import ranges as R
from ._common import DeviceOpt, ForceOpt, JsonOpt, console, device_input, direction_cb, in_range, print_json

METHODS = ("exact", "paper")


def transform_command(
    image: Annotated[Path, typer.Argument(help="8-bit greyscale or monochrome design (PNG, BMP, TIFF...); non-zero = ink.")],
    device: DeviceOpt,
    tilt: Annotated[float, typer.Option("--tilt", help="Head tilt, degrees (counter-clockwise positive).", callback=in_range(R.TILT_DEG))],
    radius: Annotated[float, typer.Option("--radius", help="Radius of the design's first column (inner edge), mm.", callback=in_range(R.RADIUS_MM))],
    out: Annotated[Path, typer.Option("--out", "-o", help="PRINT.png (several swathes: PRINT-s1.png, ...) and sidecar PRINT.json.")],
    method: Annotated[str, typer.Option("--method", help="exact (sample where every drop lands) or paper (polar + linear, eqs 1-6).")] = "exact",
    dpi_y: DpiYOpt = None,
    ref_radius: Annotated[float | None, typer.Option("--ref-radius", help="Reference radius of the clock, mm (default: each swathe's outermost track).", callback=in_range(R.RADIUS_MM))] = None,
    design_dpi: Annotated[float | None, typer.Option("--design-dpi", help="The design's resolution, dpi (default: the head's native dpi).", callback=in_range(R.DPI))] = None,
    max_swathes: Annotated[int | None, typer.Option("--max-swathes", help="Refuse designs that need more radial swathes.", callback=in_range(R.SWATHES))] = None,
    angle: Annotated[float, typer.Option("--angle", help="Angle of the design's centre line on the platform, degrees.", callback=in_range(R.ANGLE_DEG))] = 0.0,
    direction: Annotated[int, typer.Option("--direction", help="+1: platform turns counter-clockwise seen from above; -1 clockwise.", callback=direction_cb)] = 1,
    invert: Annotated[bool, typer.Option("--invert", help="Dark pixels are ink (e.g. black shapes on white).")] = False,
    passes: Annotated[str, typer.Option("--passes", help="Interlaced passes: N, or 'auto' (the planner's choice, at most 4); "
                                        "N > 1 writes PRINT-p1.png ... and PRINT-passes.json.")] = "1",
    equalise: Annotated[bool | None, typer.Option("--equalise/--no-equalise", help="With --passes: thin dense tracks so every radius gets the same volume per area "
                                                  "(the default); --no-equalise: the plain print, every track keeps every drop.")] = None,
    edge_restore: Annotated[bool | None, typer.Option("--edge-restore/--no-edge-restore",
                                                      help="With equalised --passes (binary heads): restore some thinned-out drops within 50 um "
                                                      "(at most a design pixel) of the design's edges met along the radius, where levelling would thin "
                                                      "the film (rotary/edgecomp.py). The default of equalised passes on binary heads (off with --no-equalise or "
                                                      "a grey-level head); --no-edge-restore: the thinning alone.")] = None,
    json_out: JsonOpt = False,
    quiet: QuietOpt = False,
    force: ForceOpt = False,
) -> None:
    """Make IMAGE print-ready: rows = firing index, columns = nozzles, plus a sidecar JSON."""
    quiet = is_quiet(quiet)
    from ..devices import InkjetDevice, load_device
    from ..io.images import read_grey_image
    from ..io.atomic import check_output_path
    from ..pipeline.prints import write_print
    from ..rotary.files import print_paths
    from ..io.inputs import MAX_IMAGE_BYTES, read_input_bytes
    from ..rotary.placement import Placement

    if method not in METHODS:
        raise ConfigError(f"--method must be one of {', '.join(METHODS)}; got {method!r}")
    if out.suffix.lower() != ".png":
        raise ConfigError(f"--out must end in .png, got {out.name!r}")
    inputs = [image, device_input(device)]
    check_output_path(out, is_dir=False, inputs=inputs, force=force, also=print_paths(out)[1:])  # before any work
    dev = load_device(device)
    if not isinstance(dev, InkjetDevice):
        raise ConfigError(f"device {dev.name!r} is a projector; 'transform' needs an inkjet device")
    head = dev.head
    design = read_grey_image(image)
    if invert:
        design = 255 - design
    dpi = float(head.dpi_x if design_dpi is None else design_dpi)
    if not dpi > 0:
        raise ConfigError(f"--design-dpi must be > 0, got {design_dpi}")
    h, w = design.shape
    pl = Placement(w, h, 25.4 / dpi, 25.4 / dpi, inner_radius_mm=radius, angle_deg=angle)
    kw = dict(tilt_deg=tilt, dpi_y=dpi_y, ref_radius_mm=ref_radius, mount_angle_deg=0.0, direction=direction, max_swathes=max_swathes)
    if passes != "1":
        from ..pipeline.prints import transform_passes

        if method != "exact":
            raise ConfigError("--passes needs --method exact")
        info = {"path": str(image.resolve()),
                "sha256": hashlib.sha256(read_input_bytes(image, what="image file", limit_bytes=MAX_IMAGE_BYTES)).hexdigest(),
                "invert": invert, "design_dpi": dpi}
        from ..rotary.interlace import PassOptions
        from ..rotary.options import RotarySetup

        if edge_restore and equalise is False:
            raise ConfigError("--edge-restore needs the equalised passes (not --no-equalise)")
        if edge_restore and dev.head.grey_levels > 1:
            raise ConfigError(f"--edge-restore needs a binary head; {dev.name}'s has {dev.head.grey_levels} grey levels "
                              "(its equalisation spreads ink by drop size, not by thinning)")
        # the default EdgeRestore(): a zone of 50 um, or one design pixel where the pixels are finer (the radial look-up's reach)
        popts = PassOptions(setup=RotarySetup(**kw), passes=passes, equalise=equalise is not False,
                            **({"edge_restore": None} if edge_restore is False else {}))
        manifest = transform_passes(design, dev, pl, out, popts, design_info=info, force=force, inputs=inputs)
        if json_out:
            print_json(manifest)
        elif not quiet:
            pp = manifest["pass_plan"]
            console.print(
                f"exact, {pp['passes']} interlaced pass(es), offsets {', '.join(f'{o * 1000:.1f}' for o in pp['offsets_mm'])} um: "
                f"largest track gap {pp['largest_gap_mm'] * 1000:.1f} um (one pass: {pp['single_pass_largest_gap_mm'] * 1000:.1f} um), "
                f"clock {pp['dpi_y']:.0f} dpi ({pp['along_track_mm'] * 1000:.1f} um along the track) for {pp['footprint_um']:.1f} um footprints; "
                + (f"equalised by {manifest['equalise']}, printed at {manifest['dpi_y']:.0f} dpi" if manifest["equalise"]
                   else "plain (every track keeps every drop)")
            )
            for f in manifest["files"]:
                console.print(f"  {f}")
        return
    if equalise is not None or edge_restore is not None:
        flag = ("" if edge_restore else "no-") + "edge-restore" if edge_restore is not None else ("" if equalise else "no-") + "equalise"
        raise ConfigError(f"--{flag} needs --passes (N or auto)")
    if method == "exact":
        from ..rotary.exact import transform_exact

        pr = transform_exact(design, head, pl, **kw)
    else:
        from ..rotary.paper import transform_paper

        pr = transform_paper(design, head, pl, **kw)
    info = {
        "path": str(image.resolve()),
        "sha256": hashlib.sha256(read_input_bytes(image, what="image file", limit_bytes=MAX_IMAGE_BYTES)).hexdigest(),
        "invert": invert,
        "design_dpi": dpi,
    }
    side = write_print(pr, out, device_name=dev.name, design=info, force=force, inputs=inputs)
    if json_out:
        print_json(side)
    elif not quiet:
        console.print(
            f"{method}: {w} x {h} px design at {dpi:g} dpi ({pl.width_mm:.2f} x {pl.height_mm:.2f} mm), radius {radius:g} mm, "
            f"tilt {tilt:g} deg -> {len(pr.swathes)} swathe(s):"
        )
        for s in side["swathes"]:
            console.print(
                f"  {s['file']}: {s['firings']} firings x {s['nozzles']} nozzles, first firing {s['first_firing_index']}, "
                f"pivot {s['pivot_radius_mm']:.4f} mm, band {s['band_mm'][0]:.3f}-{s['band_mm'][1]:.3f} mm, "
                f"{s['angle_per_firing_deg']:.5f} deg/firing, {s['drops']} drops"
            )
        console.print(f"  sidecar: {out.with_suffix('.json')}")
