"""Writing a slicing run as a folder of PNG layers with a manifest."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

from .. import __version__
from ..slicing.fibres import SliceJob
from .atomic import MANIFEST_NAME, atomic_dir
from .images import write_png

__all__ = ["write_layer_folder", "layer_filename"]


def layer_filename(index: int) -> str:
    return f"layer_{index:05d}.png"


def write_layer_folder(
    job: SliceJob,
    out_dir: str | Path,
    *,
    device_name: str,
    device: dict,
    options: dict,
    on_layer: Callable[[int], None] | None = None,
) -> dict:
    """Slice every layer of ``job`` into ``out_dir`` (atomically); returns the manifest.

    ``out_dir/layer_00000.png`` ... are 8-bit, 255 = material; ``manifest.json`` gives the
    device, the layer heights and, for every image, the affine maps from pixel indices
    ``(col, row)`` (centre of pixel (0, 0) at (0, 0)) to platform and model mm.
    """
    grid = job.grid
    g = grid.to_json()
    px_area = grid.pitch_x_mm * grid.pitch_y_mm
    layers = []
    with atomic_dir(out_dir) as tmp:
        for layer in job:
            name = layer_filename(layer.index)
            sha = write_png(tmp / name, layer.image)
            on = int((layer.image > 0).sum())
            layers.append(
                {
                    "index": layer.index,
                    "file": name,
                    "z_mm": layer.z_mm,
                    "z_bottom_mm": layer.z_bottom_mm,
                    "z_top_mm": layer.z_top_mm,
                    "pixels_on": on,
                    "area_mm2": on * px_area,
                    "pixel_to_platform": g["pixel_to_platform"],
                    "pixel_to_model": g["pixel_to_model"],
                    "gaps": layer.gaps.to_json(),
                    "sha256": sha,
                }
            )
            if on_layer is not None:
                on_layer(layer.index)
        manifest = {
            "rotoprint_version": __version__,
            "kind": "cartesian-layers",
            "source": job.mesh.source,
            "mesh": job.mesh.info(),
            "device_name": device_name,
            "device": device,
            "options": options,
            "layer_height_mm": job.plan.layer_height_mm,
            "fill": job.fill,
            "gap_radius_mm": job.gap_radius_mm,
            "grid": g,
            "image": {"format": "png", "mode": "L", "material": 255, "empty": 0},
            "layer_count": len(layers),
            "layers": layers,
        }
        (tmp / MANIFEST_NAME).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    return manifest
