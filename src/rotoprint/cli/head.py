"""`rotoprint head`: nozzle geometry of a (tilted) head, the paper's Figure 5 as table and plot."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.table import Table

from ..errors import ConfigError
from ._common import DeviceOpt, ForceOpt, JsonOpt, console, device_input, out_console, print_json


def parse_tilt_range(text: str) -> list[float]:
    """'A:B:STEP' (inclusive of B when it falls on a step) into a list of tilts."""
    parts = text.split(":")
    try:
        a, b, step = (float(p) for p in parts)
    except ValueError:
        raise ConfigError(f"--tilt-range must be 'A:B:STEP' in degrees, got {text!r}") from None
    if step <= 0 or b < a:
        raise ConfigError(f"--tilt-range needs A <= B and STEP > 0, got {text!r}")
    n = int((b - a) / step + 1e-9)
    if n > 10_000:
        raise ConfigError(f"--tilt-range gives {n + 1} tilts; at most 10001")
    return [a + i * step for i in range(n + 1)]


def head_command(
    device: DeviceOpt = "omnidot760",
    tilt: Annotated[float | None, typer.Option("--tilt", help="One tilt, degrees.")] = None,
    tilt_range: Annotated[str | None, typer.Option("--tilt-range", help="Tilts 'A:B:STEP', degrees (default 0:80:10).")] = None,
    radius: Annotated[float, typer.Option("--radius", help="Pivot radius cx for the exact figures, mm.")] = 60.0,
    plot: Annotated[Path | None, typer.Option("--plot", help="Write the paper's Figure 5 (a), (b) to this .png/.svg/.pdf.")] = None,
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
    if plot is not None:
        from ..rotary.plots import figure5, save_figure

        save_figure(figure5(dev.head, pivot_radius_mm=radius, title=dev.name), plot, force=force, inputs=[device_input(device)])
    if json_out:
        print_json({"device": dev.name, "source": dev.source, "nominal": list(dev.nominal), "head": dev.head.model_dump(mode="json"),
                    "max_tilt_deg": tmax, "tilts": [f.to_json() for f in figs]})
        return
    t = Table(title=f"{dev.name}: {dev.head.nozzles} nozzles, {dev.head.rows} rows, swathe {dev.head.swathe_mm} mm, "
                    f"pitch {dev.head.pitch_mm * 1000:.2f} um, cx = {radius:g} mm; max tilt {tmax:.2f} deg")
    for col in ("tilt deg", "cx_T mm", "ps_p mm", "dpi_xp", "p cos um", "band (exact) mm", "pitch exact um",
                "largest gap um", "single-row bands mm"):
        t.add_column(col, justify="right")
    for f in figs:
        p = f.paper
        lo, hi = f.overlap_band_mm
        t.add_row(
            f"{f.tilt_deg:g}", f"{p['cx_T_mm']:.3f}", f"{p['ps_p_mm']:.3f}", f"{p['dpi_xp']:.1f}",
            f"{p['pitch_radial_mm'] * 1000:.2f}", f"{lo:.3f}-{hi:.3f} ({hi - lo:.3f})",
            f"{f.pitch_radial_min_mm * 1000:.1f}-{f.pitch_radial_max_mm * 1000:.1f}",
            f"{f.largest_track_gap_mm * 1000:.1f}",
            f"{f.inner_single_row_band_mm[0]:.2f}-{f.inner_single_row_band_mm[1]:.2f}, "
            f"{f.outer_single_row_band_mm[0]:.2f}-{f.outer_single_row_band_mm[1]:.2f}",
        )
    out_console.print(t)
    if dev.nominal:
        console.print(f"nominal (not from the source) values of {dev.name}: {', '.join(dev.nominal)}")
    if plot is not None:
        console.print(f"Figure 5 -> {plot}")
