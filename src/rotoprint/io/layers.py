"""The layer folder format: a folder of PNG layers with ``manifest.json``.

The folder is made by :func:`rotoprint.pipeline.write_layer_folder` (streamed, parallel,
resumable); this module names its files and builds its manifest.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._version import __version__
from .resumable import partial_path

if TYPE_CHECKING:
    from ..slicing.fibres import SliceJob

__all__ = ["layer_filename", "layer_folder_manifest", "partial_path"]


def layer_filename(index: int) -> str:
    """File name of layer ``index`` in a layer folder.

    Parameters
    ----------
    index : int
        0-based layer index.

    Returns
    -------
    str
        ``layer_NNNNN.png``, the index zero-padded to five digits.
    """
    return f"layer_{index:05d}.png"


def layer_folder_manifest(job: SliceJob, done: dict[int, dict], *, device_name: str, device: dict, options: dict) -> dict:
    """The ``manifest.json`` of a layer folder.

    Parameters
    ----------
    job : SliceJob
    done : dict of int to dict
        Every layer's journal record (``files``, ``sha256s``, ``pixels_on``, ``gaps``).
    device_name : str
    device : dict
    options : dict
        The command's options, recorded as they are.

    Returns
    -------
    dict
        Device, layer heights, the grid and, per layer, its file, heights, pixels on, area,
        pixel-to-platform and pixel-to-model maps, gaps and SHA-256.
    """
    grid = job.grid
    g = grid.to_json()
    px_area = grid.pitch_x_mm * grid.pitch_y_mm
    layers = []
    for i in range(len(job)):
        rec = done[i]
        layers.append(
            {
                "index": i,
                "file": rec["files"][0],
                "z_mm": float(job.plan.z_slice_mm[i]),
                "z_bottom_mm": float(job.plan.z_bottom_mm[i]),
                "z_top_mm": float(job.plan.z_top_mm[i]),
                "pixels_on": rec["pixels_on"],
                "area_mm2": rec["pixels_on"] * px_area,
                "pixel_to_platform": g["pixel_to_platform"],
                "pixel_to_model": g["pixel_to_model"],
                "gaps": rec["gaps"],
                "sha256": rec["sha256s"][0],
            }
        )
    return {
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

