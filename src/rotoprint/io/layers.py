"""Writing a slicing run as a folder of PNG layers with a manifest: streamed, parallel,
resumable, and never half-written under its final name.

The folder is built in ``<out>.partial`` beside the target, journalled layer by layer (see
:mod:`rotoprint.io.resumable`); when all layers are there, ``manifest.json`` is written and
the folder is renamed onto ``<out>``.
"""

from __future__ import annotations

import dataclasses
import json
import logging
from collections.abc import Callable, Iterable, Iterator
from pathlib import Path

from .. import __version__
from ..errors import ConfigError
from ..runner import LayerTask, check_scheduler_address, produce_layers, render_layer, task_fingerprint
from ..slicing.fibres import SliceJob
from .atomic import MANIFEST_NAME, OutputClaim
from .resumable import PartialOutput, check_resources, partial_path

__all__ = ["write_layer_folder", "layer_filename", "task_from_job", "partial_path", "run_layers"]

log = logging.getLogger(__name__)


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


def task_from_job(job: SliceJob, *, mask_options: dict | None = None) -> LayerTask:
    """The picklable task for ``job``, keyed by its fingerprint.

    Parameters
    ----------
    job : SliceJob
        Its mesh, device and slicing options go into the task.
    mask_options : dict, optional
        JSON form of the mask options (:meth:`MaskOptions.to_json`) when the task makes DLP
        masks; None for plain layer images.

    Returns
    -------
    LayerTask
        With ``_key`` set to :func:`~rotoprint.runner.task_fingerprint` of the task.
    """
    task = LayerTask(
        vertices=job.mesh.vertices,
        faces=job.mesh.faces,
        source=job.mesh.source,
        device=job.device.model_dump(mode="json"),
        slice_options=dict(job.slice_options),
        mask_options=mask_options,
        face_edges=job.mesh.topology.face_edges,
        suspect_edges=job.mesh.topology.suspect_edges,
    )
    return dataclasses.replace(task, _key=task_fingerprint(task))


def _result_bytes(r) -> int:
    if hasattr(r, "pngs"):
        return sum(len(p) for p in r.pngs)
    if hasattr(r, "files"):
        return sum(len(b) for b in r.files.values())
    return len(r.png)


def run_layers(n_layers: int, px: int, task: LayerTask, partial: PartialOutput, *, workers: int, scheduler: str | None,
               copies_on_disk: int = 1) -> Iterator:
    """Size the run (three sample layers made first), then yield the results of every layer
    not already done, in order. ``px`` is the pixel count of one layer's raster(s). Nothing
    is written before the size check passes.

    Parameters
    ----------
    n_layers : int
    px : int
    task : LayerTask
    partial : PartialOutput
        Layers in ``partial.done`` are skipped; ``partial.open()`` is called after the size
        check.
    workers : int
        Local processes (at least 1).
    scheduler : str, optional
        Dask scheduler address ``[tcp://]HOST:PORT``.
    copies_on_disk : int
        How many copies of each layer's output the disk must hold at once (for the disk check).

    Yields
    ------
    LayerResult
        One per layer not yet done, in index order.

    Raises
    ------
    ConfigError
        ``workers < 1`` or a malformed ``scheduler`` address.
    ResourceError
        The estimated output exceeds the free disk space beside ``partial``, or the estimated
        memory exceeds what is available.
    """
    if workers < 1:
        raise ConfigError(f"workers must be at least 1, got {workers}")
    if scheduler is not None:
        check_scheduler_address(scheduler)
    todo = [i for i in range(n_layers) if i not in partial.done]
    sample_idx = sorted({todo[0], todo[len(todo) // 2], todo[-1]}) if todo else []
    samples = {i: render_layer(task, i) for i in sample_idx}
    sizes = [_result_bytes(r) for r in samples.values()]
    procs = 1 if (scheduler is not None or workers == 1) else workers + 1
    check_resources(
        n_layers=n_layers,
        bytes_per_layer=sum(sizes) / max(1, len(sizes)),
        copies_on_disk=copies_on_disk,
        per_process_bytes=task.vertices.nbytes + task.faces.nbytes * 6 + 8 * px + 150 * 2**20,
        processes=procs,
        in_flight_bytes=4 * max(workers, 2) * 2 * px,
        where=partial.dir.parent,
    )
    partial.open()
    rest = [i for i in todo if i not in samples]
    it = iter(produce_layers(task, rest, workers=workers, scheduler=scheduler))
    for i in todo:
        yield samples[i] if i in samples else next(it)


def write_layer_folder(
    job: SliceJob,
    out_dir: str | Path,
    *,
    device_name: str,
    device: dict,
    options: dict,
    workers: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    on_layer: Callable[[int], None] | None = None,
    force: bool = False,
    inputs: Iterable[str | Path | None] = (),
) -> dict:
    """Slice every layer of ``job`` into ``out_dir``; returns the manifest.

    ``out_dir/layer_00000.png`` ... are 8-bit, 255 = material; ``manifest.json`` gives the
    device, the layer heights and, for every image, the affine maps from pixel indices
    ``(col, row)`` (centre of pixel (0, 0) at (0, 0)) to platform and model mm. The bytes
    are identical for any ``workers`` or ``scheduler``; ``resume`` continues a killed run
    (see :mod:`rotoprint.io.resumable`).

    Parameters
    ----------
    job : SliceJob
    out_dir : str or Path
        The folder to write; built in ``<out_dir>.partial`` and renamed onto ``out_dir`` when
        complete (replacing an earlier output of ours).
    device_name : str
    device : dict
    options : dict
        Written as they are into the manifest.
    workers : int
        Local processes making layers (at least 1).
    scheduler : str, optional
        Address ``[tcp://]HOST:PORT`` of a Dask scheduler to make the layers on instead.
    resume : bool
        Keep the verified layers of an earlier run of the same job.
    on_layer : callable, optional
        Called with the index of every layer once it is made (resumed ones included).
    force : bool
        Replace an existing ``out_dir`` even if it is not provably ours.
    inputs : iterable of path
        Files the run read (the mesh, a device file): ``out_dir`` must not be or hold one.

    Returns
    -------
    dict
        The manifest, as written to ``manifest.json``.

    Raises
    ------
    ConfigError
        ``workers < 1`` or a malformed ``scheduler`` address.
    InputFileError
        ``out_dir`` must not be written or replaced (missing parent folder, a file, an input,
        or a folder not provably ours, see :mod:`rotoprint.io.ownership`), another run is
        writing it, or ``<out_dir>.partial`` exists without a journal.
    ResourceError
        The run would need more disk or memory than is available (checked before any layer is
        written).
    """
    out = Path(out_dir)
    with OutputClaim(out, is_dir=True, kind="cartesian-layers", inputs=inputs, force=force) as claim:
        task = task_from_job(job)
        partial = PartialOutput(out, task._key, len(job), resume=resume)
        with partial:  # a run that fails before finishing a layer leaves nothing
            for i in partial.done:
                if on_layer is not None:
                    on_layer(i)
            for res in run_layers(len(job), job.grid.width * job.grid.height, task, partial, workers=workers, scheduler=scheduler):
                partial.record(res.index, {layer_filename(res.index): res.png}, pixels_on=res.pixels_on, gaps=res.gaps)
                if on_layer is not None:
                    on_layer(res.index)
            manifest = _manifest(job, partial.done, device_name, device, options)
            (partial.dir / MANIFEST_NAME).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
        partial.finish_as_folder(claim)
    return manifest


def _manifest(job: SliceJob, done: dict[int, dict], device_name: str, device: dict, options: dict) -> dict:
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

