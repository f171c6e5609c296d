"""Writing a slicing run as a folder of PNG layers with a manifest: streamed, parallel,
resumable, and never half-written under its final name.

The folder is built in ``<out>.partial`` beside the target. After every layer a line is
appended to ``<out>.partial/journal.jsonl`` (index, file, SHA-256); with ``resume=True`` a
later run of the *same* job (same mesh, device, options and version: the journal's first line
holds their fingerprint) keeps every journalled layer whose file still has its checksum and
makes only the rest. When all layers are there, ``manifest.json`` is written and the folder
is renamed onto ``<out>``.
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import shutil
from collections.abc import Callable
from pathlib import Path

from .. import __version__
from .._resources import available_memory_bytes, format_bytes
from ..errors import InputFileError, ResourceError
from ..runner import LayerResult, LayerTask, produce_layers, render_layer, task_fingerprint
from ..slicing.fibres import SliceJob
from .atomic import MANIFEST_NAME

__all__ = ["write_layer_folder", "layer_filename", "task_from_job", "partial_path"]

log = logging.getLogger(__name__)
JOURNAL = "journal.jsonl"


def layer_filename(index: int) -> str:
    return f"layer_{index:05d}.png"


def partial_path(out_dir: str | Path) -> Path:
    out = Path(out_dir)
    return out.parent / f"{out.name}.partial"


def task_from_job(job: SliceJob) -> LayerTask:
    return LayerTask(
        vertices=job.mesh.vertices,
        faces=job.mesh.faces,
        source=job.mesh.source,
        device=job.device.model_dump(mode="json"),
        slice_options=dict(job.slice_options),
    )


def _check_target(out: Path) -> None:
    if out.exists():
        if not out.is_dir():
            raise InputFileError("output exists and is not a folder", path=out)
        if any(out.iterdir()) and not (out / MANIFEST_NAME).exists():
            raise InputFileError(
                f"output folder is not empty and holds no {MANIFEST_NAME}; refusing to replace it", path=out
            )
    if not out.parent.exists():
        raise InputFileError("parent folder of the output does not exist", path=out.parent)


def _read_journal(partial: Path, fingerprint: str) -> dict[int, dict]:
    """Journalled layers whose files are intact; {} if the journal is of another job."""
    jpath = partial / JOURNAL
    if not jpath.exists():
        return {}
    done: dict[int, dict] = {}
    with open(jpath, encoding="utf-8") as fh:
        head = fh.readline()
        try:
            if json.loads(head).get("fingerprint") != fingerprint:
                return {}
        except json.JSONDecodeError:
            return {}
        for line in fh:
            try:
                rec = json.loads(line)
            except json.JSONDecodeError:
                break  # a line cut by the crash: everything after it is redone
            f = partial / rec["file"]
            if f.exists() and hashlib.sha256(f.read_bytes()).hexdigest() == rec["sha256"]:
                done[int(rec["index"])] = rec
    return done


def _estimate_and_check(job: SliceJob, task: LayerTask, samples: dict[int, LayerResult], workers: int,
                        out_parent: Path) -> dict:
    n = len(job)
    mean_png = sum(len(r.png) for r in samples.values()) / max(1, len(samples))
    est_disk = int(mean_png * n * 1.25) + 64 * 1024 + 2048 * n
    free = shutil.disk_usage(out_parent).free
    if est_disk > free:
        raise ResourceError(
            f"the output would take about {format_bytes(est_disk)} ({n} layers of ~{format_bytes(mean_png)}), "
            f"but only {format_bytes(free)} is free",
            path=out_parent,
        )
    px = job.grid.width * job.grid.height
    mesh_bytes = task.vertices.nbytes + task.faces.nbytes * 6
    per_process = mesh_bytes + 6 * px + 150 * 2**20  # arrays, rasters, interpreter and libraries
    est_mem = (workers + (1 if workers > 1 else 0)) * per_process + 4 * workers * (px + int(mean_png))
    avail = available_memory_bytes()
    if est_mem > avail:
        raise ResourceError(
            f"{workers} worker(s) would need about {format_bytes(est_mem)} of memory, "
            f"{format_bytes(avail)} is available; use fewer --workers"
        )
    log.info("estimated output %s, memory %s", format_bytes(est_disk), format_bytes(est_mem))
    return {"estimated_output_bytes": est_disk, "estimated_memory_bytes": est_mem}


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
) -> dict:
    """Slice every layer of ``job`` into ``out_dir``; returns the manifest.

    ``out_dir/layer_00000.png`` ... are 8-bit, 255 = material; ``manifest.json`` gives the
    device, the layer heights and, for every image, the affine maps from pixel indices
    ``(col, row)`` (centre of pixel (0, 0) at (0, 0)) to platform and model mm. The bytes
    are identical for any ``workers`` or ``scheduler``.
    """
    out = Path(out_dir)
    _check_target(out)
    task = task_from_job(job)
    fingerprint = task_fingerprint(task)
    partial = partial_path(out)
    done: dict[int, dict] = {}
    if partial.exists():
        if resume:
            done = _read_journal(partial, fingerprint)
            log.info("resuming: %d of %d layers verified in %s", len(done), len(job), partial)
        if not done:
            shutil.rmtree(partial)
    todo = [i for i in range(len(job)) if i not in done]
    # a few layers made here first: they size the run before anything is written
    sample_idx = sorted({todo[0], todo[len(todo) // 2], todo[-1]}) if todo else []
    samples = {i: render_layer(task, i) for i in sample_idx}
    _estimate_and_check(job, task, samples, workers if scheduler is None else 1, out.parent)
    partial.mkdir(exist_ok=True)
    jmode = "a" if done else "w"
    with open(partial / JOURNAL, jmode, encoding="utf-8") as journal:
        if not done:
            journal.write(json.dumps({"fingerprint": fingerprint, "layers": len(job)}) + "\n")
        for i in done:
            if on_layer is not None:
                on_layer(i)
        rest = [i for i in todo if i not in samples]
        stream = _merge(samples, produce_layers(task, rest, workers=workers, scheduler=scheduler), todo)
        for res in stream:
            name = layer_filename(res.index)
            (partial / name).write_bytes(res.png)
            rec = {"index": res.index, "file": name, "sha256": res.sha256, "pixels_on": res.pixels_on, "gaps": res.gaps}
            journal.write(json.dumps(rec) + "\n")
            journal.flush()
            done[res.index] = rec
            if on_layer is not None:
                on_layer(res.index)
    manifest = _manifest(job, done, device_name, device, options)
    (partial / MANIFEST_NAME).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    (partial / JOURNAL).unlink()
    _replace(partial, out)
    return manifest


def _merge(samples: dict[int, LayerResult], rest, order: list[int]):
    """Results in ``order``: the samples made up front, the rest from the stream."""
    it = iter(rest)
    for i in order:
        yield samples[i] if i in samples else next(it)


def _replace(partial: Path, out: Path) -> None:
    if out.exists():
        old = out.parent / f".{out.name}.old"
        if old.exists():
            shutil.rmtree(old)
        os.replace(out, old)
        os.replace(partial, out)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.replace(partial, out)


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
                "file": rec["file"],
                "z_mm": float(job.plan.z_slice_mm[i]),
                "z_bottom_mm": float(job.plan.z_bottom_mm[i]),
                "z_top_mm": float(job.plan.z_top_mm[i]),
                "pixels_on": rec["pixels_on"],
                "area_mm2": rec["pixels_on"] * px_area,
                "pixel_to_platform": g["pixel_to_platform"],
                "pixel_to_model": g["pixel_to_model"],
                "gaps": rec["gaps"],
                "sha256": rec["sha256"],
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
