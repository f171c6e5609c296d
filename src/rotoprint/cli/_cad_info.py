"""`rotoprint info LAYER`: what is in a Gerber, Excellon, DXF or SVG layer."""

from __future__ import annotations

from pathlib import Path

from rich.table import Table

from ._common import out_console, print_json

#: Arc tolerance of `rotoprint info` (mm).
INFO_TOLERANCE_MM = 0.001


def cad_info(path: Path, *, units: str | None, json_out: bool) -> None:
    from ..io.cad import read_layer

    lay = read_layer(path, tolerance_mm=INFO_TOLERANCE_MM, units=units)
    data = lay.info()
    if json_out:
        print_json(data)
        return
    t = Table(title=str(path), show_header=False)
    t.add_column("quantity", style="bold")
    t.add_column("value")
    b = data["bounds_mm"]

    def mm(v):
        return "-" if v is None else f"{v:.4f}"

    rows = [
        ("format", data["format"]),
        ("area (mm^2)", f"{data['area_mm2']:.6g}"),
        ("bounds min (mm)", ", ".join(f"{v:.4f}" for v in b["min"])),
        ("bounds max (mm)", ", ".join(f"{v:.4f}" for v in b["max"])),
        ("size (mm)", " x ".join(f"{v:.4f}" for v in data["size_mm"])),
        ("regions", str(data["regions"])),
        ("holes", str(data["holes"])),
        ("narrowest track (mm)", mm(data["narrowest_track_mm"])),
        ("narrowest gap (mm)", mm(data["narrowest_gap_mm"])),
        ("terminals", ", ".join(sorted(data["terminals"])) or "-"),
        ("arc tolerance (mm)", f"{data['tolerance_mm']:g}"),
    ]
    for k, v in rows:
        t.add_row(k, v)
    out_console.print(t)
