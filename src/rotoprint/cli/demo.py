"""`rotoprint demo`: run the main job on a bundled example and say where the output is."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ._common import console, out_console


def demo(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder for the demo.")] = Path("demo-output"),
) -> None:
    """Slice the bundled gear example for the omnidot760 head and the Perfactory projector."""
    from ..devices import load_device
    from ..examples import gear_triangles, write_binary_stl
    from ..io.layers import write_layer_folder
    from ..io.mesh import load_mesh
    from ..slicing import slice_mesh

    out.mkdir(parents=True, exist_ok=True)
    stl = out / "gear.stl"
    write_binary_stl(stl, gear_triangles())
    mesh = load_mesh(stl)
    for dev_name, lh in (("omnidot760", 0.5), ("perfactory-sxga", 0.5)):
        dev = load_device(dev_name)
        if dev_name == "perfactory-sxga":
            from ..io.mesh import make_transform

            mesh_d = mesh.transformed(make_transform(scale=0.8))
        else:
            mesh_d = mesh
        job = slice_mesh(mesh_d, dev, layer_height_mm=lh)
        target = out / f"layers-{dev_name}"
        write_layer_folder(job, target, device_name=dev.name, device=dev.model_dump(mode="json"), options={"layer_height_mm": lh})
        console.print(f"{dev_name}: {len(job)} layers of {job.grid.width} x {job.grid.height} px")
        out_console.print(f"layers written to {target.resolve()}/ (manifest.json lists them)")
