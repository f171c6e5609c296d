"""The layer folder format: a folder of PNG layers with ``manifest.json``.

The folder is made by :func:`rotoprint.pipeline.write_layer_folder` (streamed, parallel,
resumable); this module names its files and builds its manifest.
"""

from __future__ import annotations

import json
import tempfile
import weakref
from array import array
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from .._version import __version__
from .ownership import open_tracked
from .resumable import partial_path

if TYPE_CHECKING:
    from ..slicing.fibres import SliceJob

__all__ = ["layer_filename", "layer_folder_manifest", "write_layer_folder_manifest", "SpooledRecords", "partial_path"]


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
    return {**_manifest_head(job, device_name=device_name, device=device, options=options),
            "layers": list(_layer_entries(job, done))}


def _manifest_head(job: SliceJob, *, device_name: str, device: dict, options: dict) -> dict:
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
        "grid": job.grid.to_json(),
        "image": {"format": "png", "mode": "L", "material": 255, "empty": 0},
        "layer_count": len(job),
    }


def _layer_entries(job: SliceJob, done: Mapping[int, dict]) -> Iterator[dict]:
    grid = job.grid
    g = grid.to_json()
    px_area = grid.pitch_x_mm * grid.pitch_y_mm
    for i in range(len(job)):
        rec = done[i]
        yield (
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


class SpooledRecords(Sequence):
    """A read-only list of JSON records kept in an anonymous temporary file: only their byte
    offsets (8 bytes each) are in memory; each access reads one line."""

    def __init__(self) -> None:
        self._fh = tempfile.TemporaryFile("w+b")  # noqa: SIM115 - closed by close() or with the object
        self._off = array("q")
        self._closer = weakref.finalize(self, self._fh.close)

    def append(self, rec: dict) -> None:
        self._fh.seek(0, 2)
        self._off.append(self._fh.tell())
        self._fh.write(json.dumps(rec).encode("ascii") + b"\n")

    def __len__(self) -> int:
        return len(self._off)

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[j] for j in range(*k.indices(len(self)))]
        n = len(self._off)
        if not -n <= k < n:
            raise IndexError(k)
        self._fh.seek(self._off[k % n])
        return json.loads(self._fh.readline())

    def __iter__(self) -> Iterator[dict]:
        for k in range(len(self._off)):  # by index: other lookups may come in between
            yield self[k]

    def close(self) -> None:
        self._closer()


def write_layer_folder_manifest(path: str | Path, job: SliceJob, done: Mapping[int, dict], *, device_name: str, device: dict,
                                options: dict) -> dict:
    """Write :func:`layer_folder_manifest` to ``path`` layer by layer, in bounded memory.

    The bytes are those of ``json.dumps(manifest, indent=1)``. The file is hashed as it is
    written (:func:`rotoprint.io.ownership.open_tracked`).

    Returns
    -------
    dict
        The manifest; its ``layers`` a :class:`SpooledRecords` (a sequence of the layer
        entries read back from a temporary file).
    """
    head = _manifest_head(job, device_name=device_name, device=device, options=options)
    text = json.dumps({**head, "layers": []}, indent=1)
    tail = '"layers": []\n}'
    if not text.endswith(tail):  # pragma: no cover - json's layout of a trailing empty list
        raise AssertionError("unexpected manifest layout")
    layers = SpooledRecords()
    with open_tracked(path) as fh:
        fh.write(text[: -len(tail)] + '"layers": [')
        for k, entry in enumerate(_layer_entries(job, done)):
            fh.write(("," if k else "") + "\n" + "\n".join("  " + ln for ln in json.dumps(entry, indent=1).split("\n")))
            layers.append(entry)
        fh.write("\n ]\n}" if len(layers) else "]\n}")
    return {**head, "layers": layers}

