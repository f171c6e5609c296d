"""`rotoprint info LAYER`: what is in a Gerber, Excellon, DXF or SVG layer."""

from __future__ import annotations

from pathlib import Path

from ._common import print_json, print_quantities

#: Arc tolerance of `rotoprint info` (mm).
INFO_TOLERANCE_MM = 0.001


def cad_info(path: Path, *, units: str | None, json_out: bool) -> None:
    from ..io.cad import read_layer

    lay = read_layer(path, tolerance_mm=INFO_TOLERANCE_MM, units=units)
    data = lay.info()
    if json_out:
        print_json(data)
        return
    def mm(v):
        return "-" if v is None else f"{v:.4f}"

    rows = [
        ("format", data["format"]),
        ("area (mm^2)", f"{data['area_mm2']:.6g}"),
        ("regions", str(data["regions"])),
        ("holes", str(data["holes"])),
        ("narrowest track (mm)", mm(data["narrowest_track_mm"])),
        ("narrowest gap (mm)", mm(data["narrowest_gap_mm"])),
        ("terminals", ", ".join(sorted(data["terminals"])) or "-"),
        ("arc tolerance (mm)", f"{data['tolerance_mm']:g}"),
    ]
    print_quantities(str(path), data, rows)
