"""`rotoprint slice MESH`: one image per layer on the device's own pixel grid."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..constants import DEFAULT_GAP_RADIUS_MM
from ._common import (
    DeviceOpt,
    LayerHeightOpt,
    RotateOpt,
    ScaleOpt,
    TranslateOpt,
    UnitsOpt,
    console,
    load_mesh_from_options,
    parse_pair,
    progress,
    setup_logging,
)


def slice_command(
    mesh: Annotated[Path, typer.Argument(help="Mesh file: STL, OBJ, PLY, 3MF, OFF, GLB.")],
    device: DeviceOpt,
    layer_height: LayerHeightOpt,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder (created; replaced only if it holds an earlier manifest).")],
    fibre_angle: Annotated[float | None, typer.Option("--fibre-angle", help="Fibre direction in the model's XY plane, degrees from +X. Default: the device's own direction.")] = None,
    fill: Annotated[str, typer.Option("--fill", help="Fill rule: nonzero (overlapping shells union) or evenodd.")] = "nonzero",
    offset: Annotated[str | None, typer.Option("--offset", help="'X,Y' mm: the part's centre relative to the field centre.")] = None,
    gap_radius: Annotated[float, typer.Option("--gap-radius", help="Open meshes: join open ends of a section closer than this, mm.")] = DEFAULT_GAP_RADIUS_MM,
    dpi_y: Annotated[float | None, typer.Option("--dpi-y", help="Inkjet: circumferential / print-direction density, dpi.")] = None,
    units: UnitsOpt = "mm",
    scale: ScaleOpt = 1.0,
    rotate: RotateOpt = None,
    translate: TranslateOpt = None,
    workers: Annotated[int, typer.Option("--workers", "-j", help="Layers in parallel in this many processes.")] = 1,
    scheduler: Annotated[str | None, typer.Option("--scheduler", help="Address of a Dask distributed scheduler to run the layers on (rotoprint[dask]).")] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Continue an interrupted run: keep its verified layers, make the rest.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar or summary.")] = False,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log what happens (resume, workers) on stderr.")] = False,
) -> None:
    """Slice MESH into DIR/layer_00000.png ... (255 = material) and DIR/manifest.json."""
    from ..devices import load_device
    from ..io.layers import write_layer_folder
    from ..slicing import slice_mesh

    setup_logging(verbose)
    overrides = {"dpi_y": dpi_y} if dpi_y is not None else {}
    dev = load_device(device, **overrides)
    m = load_mesh_from_options(mesh, units, scale, rotate, translate)
    job = slice_mesh(
        m,
        dev,
        layer_height_mm=layer_height,
        fibre_angle_deg=fibre_angle,
        fill=fill,
        offset_mm=parse_pair(offset, "--offset"),
        gap_radius_mm=gap_radius,
    )
    options = {
        "layer_height_mm": layer_height,
        "fibre_angle_deg": fibre_angle,
        "fill": fill,
        "offset_mm": list(parse_pair(offset, "--offset")),
        "gap_radius_mm": gap_radius,
        "units": units,
        "scale": scale,
        "rotate_deg": rotate,
        "translate_mm": translate,
    }
    with progress(quiet) as bar:
        task = bar.add_task("slicing", total=len(job))
        manifest = write_layer_folder(
            job,
            out,
            device_name=dev.name,
            device=dev.model_dump(mode="json"),
            options=options,
            workers=workers,
            scheduler=scheduler,
            resume=resume,
            on_layer=lambda i: bar.advance(task),
        )
    if not quiet:
        g = job.grid
        left_open = sum(1 for L in manifest["layers"] if L["gaps"]["left_open"])
        closed = sum(L["gaps"]["closed"] for L in manifest["layers"])
        console.print(
            f"{len(job)} layers of {g.width} x {g.height} px at {g.pitch_x_mm * 1000:.2f} x {g.pitch_y_mm * 1000:.2f} um "
            f"-> {out}/ (manifest.json)"
        )
        if closed or left_open:
            console.print(
                f"[yellow]open mesh:[/yellow] {closed} gap(s) closed within {gap_radius} mm; "
                f"{left_open} layer(s) had chains left open and closed by a chord (see manifest 'gaps')"
            )
