"""`rotoprint head`: nozzle geometry of a (tilted) head, the paper's Figure 5 as table and plot."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..errors import ConfigError
from .. import ranges as R
from ..ranges import check_count, check_range
from ._common import DeviceOpt, ForceOpt, JsonOpt, console, device_input, in_range, out_console, print_json


def parse_tilt_range(text: str) -> list[float]:
    """'A:B:STEP' (inclusive of B when it falls on a step) into a list of tilts."""
    parts = text.split(":")
    try:
        a, b, step = (float(p) for p in parts)
    except ValueError:
        raise ConfigError(f"--tilt-range must be 'A:B:STEP' in degrees, got {text!r}") from None
    if not all(math.isfinite(v) for v in (a, b, step)) or step <= 0 or b < a:
        raise ConfigError(f"--tilt-range needs finite A <= B and STEP > 0, got {text!r}")
    check_range(a, R.TILT_DEG, "--tilt-range A")
    check_range(b, R.TILT_DEG, "--tilt-range B")
    n = check_count(math.floor((b - a) / step + 1e-9), "--tilt-range: the number of tilts", 10_000)
    if n > 10_000:
        raise ConfigError(f"--tilt-range gives {n + 1} tilts; at most 10001")
    return [a + i * step for i in range(n + 1)]


def head_command(
    device: DeviceOpt = "omnidot760",
    tilt: Annotated[float | None, typer.Option("--tilt", help="One tilt, degrees.", callback=in_range(R.TILT_DEG))] = None,
    tilt_range: Annotated[str | None, typer.Option("--tilt-range", help="Tilts 'A:B:STEP', degrees (default 0:80:10).")] = None,
    radius: Annotated[float, typer.Option("--radius", help="Pivot radius cx for the exact figures, mm.", callback=in_range(R.RADIUS_MM))] = 60.0,
    plot: Annotated[Path | None, typer.Option("--plot", help="Write the paper's Figure 5 (a), (b) to this .png/.svg/.pdf.")] = None,
    best: Annotated[bool, typer.Option("--best", help="Name the evenly interleaved tilt with the finest radial pitch.")] = False,
    even_ratio: Annotated[float, typer.Option("--even-ratio", help="Even: largest track gap <= this x the mean gap.", callback=in_range(R.EVEN_RATIO))] = 1.25,
    json_out: JsonOpt = False,
    force: ForceOpt = False,
) -> None:
    """Per tilt: cx_T, projected swathe ps_p, dpi_xp, radial pitch, largest track gap, single-row bands, max tilt."""
    from ..devices import InkjetDevice, load_device
    from ..rotary.head import head_figures, max_tilt_deg

    if plot is not None:
        from ..io.atomic import check_output_path

        check_output_path(plot, is_dir=False, inputs=[device_input(device)], force=force)  # before any work
    dev = load_device(device)
    if not isinstance(dev, InkjetDevice):
        raise ConfigError(f"device {dev.name!r} is a projector; 'head' needs an inkjet device")
    if tilt is not None and tilt_range is not None:
        raise ConfigError("give either --tilt or --tilt-range, not both")
    tilts = [tilt] if tilt is not None else parse_tilt_range(tilt_range or "0:80:10")
    tmax = max_tilt_deg(dev.head)
    figs = [head_figures(dev.head, tilt_deg=t, pivot_radius_mm=radius) for t in tilts]
    from ..rotary.interlace import best_tilt, tilt_scan

    scan = tilt_scan(dev.head, tilts, pivot_radius_mm=radius, even_ratio=even_ratio)
    chosen = best_tilt(scan) if best else None
    if plot is not None:
        from ..rotary.plots import figure5, save_figure

        save_figure(figure5(dev.head, pivot_radius_mm=radius, title=dev.name), plot, force=force, inputs=[device_input(device)])
    if json_out:
        print_json({"device": dev.name, "source": dev.source, "nominal": list(dev.nominal), "head": dev.head.model_dump(mode="json"),
                    "max_tilt_deg": tmax, "tilts": [{**f.to_json(), "interleave": r.to_json()} for f, r in zip(figs, scan)],
                    **({"best": chosen.to_json() if chosen else None} if best else {})})
        return
    t = Table(title=f"{dev.name}: {dev.head.nozzles} nozzles, {dev.head.rows} rows, swathe {dev.head.swathe_mm} mm, "
                    f"pitch {dev.head.pitch_mm * 1000:.2f} um, cx = {radius:g} mm; max tilt {tmax:.2f} deg")
    for col in ("tilt deg", "cx_T mm", "ps_p mm", "dpi_xp", "p cos um", "band (exact) mm", "pitch exact um",
                "largest gap um", *(("mean gap um", "even") if best else ()), "single-row bands mm"):
        t.add_column(col, justify="right")
    for f, ev in zip(figs, scan):
        p = f.paper
        lo, hi = f.overlap_band_mm
        t.add_row(
            f"{f.tilt_deg:g}", f"{p['cx_T_mm']:.3f}", f"{p['ps_p_mm']:.3f}", f"{p['dpi_xp']:.1f}",
            f"{p['pitch_radial_mm'] * 1000:.2f}", f"{lo:.3f}-{hi:.3f} ({hi - lo:.3f})",
            f"{f.pitch_radial_min_mm * 1000:.1f}-{f.pitch_radial_max_mm * 1000:.1f}",
            f"{f.largest_track_gap_mm * 1000:.1f}",
            *((f"{ev.mean_pitch_mm * 1000:.1f}", ("yes" if ev.even else f"no ({ev.evenness:.2f})") + (" best" if chosen is ev else ""))
              if best else ()),
            f"{f.inner_single_row_band_mm[0]:.2f}-{f.inner_single_row_band_mm[1]:.2f}, "
            f"{f.outer_single_row_band_mm[0]:.2f}-{f.outer_single_row_band_mm[1]:.2f}",
        )
    out_console.print(t)
    if dev.nominal:
        console.print(f"nominal (not from the source) values of {dev.name}: {', '.join(dev.nominal)}")
    if best:
        if chosen is None:
            out_console.print(f"no tilt of {tilts[0]:g}..{tilts[-1]:g} deg interleaves evenly at {radius:g} mm "
                              f"(largest gap <= {even_ratio:g} x mean): print in interlaced passes (--passes)")
        else:
            out_console.print(f"best tilt {chosen.tilt_deg:g} deg: even radial pitch {chosen.mean_pitch_mm * 1000:.1f} um, "
                              f"largest gap {chosen.largest_gap_mm * 1000:.1f} um")
    if plot is not None:
        console.print(f"Figure 5 -> {plot}")
