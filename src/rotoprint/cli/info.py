"""`rotoprint info MESH`: what is in a mesh file."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ._common import FillHolesOpt, JsonOpt, RotateOpt, ScaleOpt, TranslateOpt, UnitsOpt, load_mesh_from_options, print_json, print_quantities


def info(
    mesh: Annotated[Path, typer.Argument(help="Mesh file: STL (binary or ASCII), OBJ, PLY, 3MF, OFF, GLB; or a layer: Gerber, Excellon, DXF, SVG.")],
    units: UnitsOpt = "mm",
    scale: ScaleOpt = 1.0,
    rotate: RotateOpt = None,
    translate: TranslateOpt = None,
    json_out: JsonOpt = False,
    fill_holes: FillHolesOpt = True,
) -> None:
    """Triangles, bounds, shells, open edges, watertightness, volume, degenerate triangles.

    Gerber, Excellon, DXF and SVG layers: area, bounds, regions, holes, narrowest track and gap."""
    from ..io.cad import is_cad_file

    if is_cad_file(mesh):
        from ._cad_info import cad_info

        return cad_info(mesh, units=None if units == "mm" else units, json_out=json_out)
    m = load_mesh_from_options(mesh, units, scale, rotate, translate, fill_holes)
    data = m.info()
    if json_out:
        print_json(data)
        return
    rows = [
        ("triangles", f"{data['triangles']:,}"),
        ("vertices", f"{data['vertices']:,}"),
        ("shells", str(data["shells"])),
        ("open edges", str(data["open_edges"])),
        ("non-manifold edges", str(data["nonmanifold_edges"])),
        ("watertight", ("yes" if data["watertight"] else "no") + ("" if data["watertight"] == data["watertight_as_read"] else "  (after filling holes)")),
        ("holes filled", _holes_line(data["holes"])),
        ("volume (mm^3)", f"{data['volume_mm3']:.6g}" + ("" if data["volume_exact"] else "  (approximate: not watertight)")),
        ("degenerate triangles", f"{data['degenerate_triangles']} ({data['collapsed_triangles_dropped']} collapsed, dropped)"),
        ("faces re-wound", str(data["faces_reoriented"])),
        ("shells turned outside-in", str(data["shells_flipped"])),
    ]
    print_quantities(str(mesh), data, rows)


def _holes_line(h: dict) -> str:
    if not h["enabled"]:
        return "off (--no-fill-holes)"
    line = f"{h['filled']} ({h['filled_edges']} edges, {h['filled_area_mm2']:.6g} mm^2)"
    if h["left_open_loops"] or h["left_open_edges"]:
        line += f"; {h['left_open_loops']} loop(s) left open, {h['left_open_edges']} open edge(s) left to the slicer's chords"
    return line
