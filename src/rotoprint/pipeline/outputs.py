"""The journalled outputs: a layer folder, a DLP job (SL1 / SL1S archive or folder), direct
rotary slices. Each is the producer + the journalled writer + the format's manifest or
archive writer from :mod:`rotoprint.io`; streamed, parallel, resumable, and never
half-written under its final name (see :mod:`rotoprint.io.resumable`).
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np

from ..io.atomic import MANIFEST_NAME, OutputClaim, disk_full
from .journal import LayerPlan, write_journalled
from .producer import RunOptions
from .tasks import MaskLayer, MeshJob, PlainLayer, RotaryLayer, forget_last_window, layer_source

__all__ = ["write_layer_folder", "write_dlp_job", "write_rotary_slices"]


def write_layer_folder(job, out_dir: str | Path, *, device_name: str, device: dict, options: dict,
                       run: RunOptions | None = None, on_layer: Callable[[int], None] | None = None) -> dict:
    """Slice every layer of ``job`` into ``out_dir``; returns the manifest.

    ``out_dir/layer_00000.png`` ... are 8-bit, 255 = material; ``manifest.json`` gives the
    device, the layer heights and, for every image, the affine maps from pixel indices
    ``(col, row)`` (centre of pixel (0, 0) at (0, 0)) to platform and model mm
    (:func:`rotoprint.io.layers.layer_folder_manifest`). The bytes are identical for any
    ``run.workers`` or ``run.scheduler``; ``run.resume`` continues a killed run.

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
    run : RunOptions, optional
        Workers, Dask scheduler, resume, force, inputs (default: this process, afresh).
    on_layer : callable, optional
        Called with the index of every layer once it is made (resumed ones included).

    Returns
    -------
    dict
        The manifest, as written to ``manifest.json``; its ``layers`` a sequence read back
        from a temporary file (:class:`rotoprint.io.layers.SpooledRecords`).

    Raises
    ------
    InputFileError
        ``out_dir`` must not be written or replaced (missing parent folder, a file, an input,
        or a folder not provably ours, see :mod:`rotoprint.io.ownership`), another run is
        writing it, or ``<out_dir>.partial`` exists without a journal.
    ResourceError
        The run would need more disk or memory than is available (checked before any layer is
        written).
    """
    from ..io.layers import write_layer_folder_manifest

    out = Path(out_dir)
    run = run or RunOptions()
    with OutputClaim(out, is_dir=True, kind="cartesian-layers", inputs=run.inputs, force=run.force) as claim:
        mj = MeshJob.of(job)
        plan = LayerPlan(layer_source(mj, PlainLayer()), len(job), job.grid.width * job.grid.height, mj.nbytes)

        def finish(partial) -> dict:
            manifest = write_layer_folder_manifest(partial.dir / MANIFEST_NAME, job, partial.done, device_name=device_name,
                                                   device=device, options=options)  # streamed, layer by layer
            partial.finish_as_folder(claim)
            return manifest

        return write_journalled(out, plan, run, finish=finish, on_layer=on_layer)


def write_dlp_job(job, out: str | Path, info, options, *, fmt: str | None = None, run: RunOptions | None = None,
                  on_mask: Callable[[int], None] | None = None) -> dict:
    """Make every mask of ``job`` with ``options`` (a :class:`rotoprint.masks.MaskOptions`)
    and write the job to ``out`` as ``fmt`` (default: from the suffix). The bytes are the same
    for any ``run.workers`` or ``run.scheduler`` (set ``SOURCE_DATE_EPOCH`` to fix the
    archive's creation time too); ``run.resume`` continues a killed run.

    Parameters
    ----------
    job : SliceJob
    out : str or Path
        ``.sl1`` / ``.sl1s`` file, or a folder (``png`` or ``perfactory``). Masks are made in
        ``<out>.partial`` and ``out`` is written only when all are there.
    info : JobInfo
        Printer and exposure settings written with the masks.
    options : MaskOptions
        How each layer's image becomes its mask(s); ``options.copies`` masks per layer.
    fmt : {'auto', 'sl1', 'sl1s', 'png', 'perfactory'}, optional
        Default: from the suffix of ``out`` (see :func:`~rotoprint.io.archives.format_from_path`).
    run : RunOptions, optional
        Workers, Dask scheduler, resume, force, inputs (default: this process, afresh).
    on_mask : callable, optional
        Called with the number of every mask once it is made (resumed ones included).

    Returns
    -------
    dict
        The summary of :func:`~rotoprint.io.archives.write_encoded` (the manifest for folders).

    Raises
    ------
    ConfigError
        Unknown ``fmt`` or a suffix it cannot be told from.
    InputFileError
        ``out`` must not be written or replaced (missing parent folder, a file where a folder
        goes or the reverse, an input, anything not provably ours), another run is writing
        it, or ``<out>.partial`` exists without a journal.
    ResourceError
        The run would need more disk or memory than is available (checked before any mask is
        written).
    """
    from ..io.archives import Encoded, format_from_path, write_encoded
    from ..masks.pipeline import plain_from_image

    fmt = format_from_path(out, fmt)
    out = Path(out)
    run = run or RunOptions()
    with OutputClaim(out, is_dir=fmt not in ("sl1", "sl1s"), kind=f"dlp-{fmt}", inputs=run.inputs, force=run.force) as claim:
        mj = MeshJob.of(job)
        px = job.grid.width * job.grid.height
        plan = LayerPlan(layer_source(mj, MaskLayer(options.to_json())), len(job), px, mj.nbytes, copies_on_disk=2)
        copies = options.copies
        footprint = np.zeros((job.grid.height, job.grid.width), np.uint8)
        box = [job.grid.height, job.grid.width, 0, 0]  # rows box[0]:box[2], columns box[1]:box[3] merged

        def merged(r0: int, c0: int, r1: int, c1: int) -> None:
            box[0], box[1], box[2], box[3] = min(box[0], r0), min(box[1], c0), max(box[2], r1), max(box[3], c1)

        def on_resumed(i: int, rec: dict, folder: Path) -> None:  # resumed layers: footprints from their files
            from PIL import Image

            for name in rec["files"]:
                with Image.open(folder / name) as im:
                    np.maximum(footprint, plain_from_image(np.asarray(im.convert("L")), options), out=footprint)
            merged(0, 0, *footprint.shape)

        def on_result(res) -> None:
            if res.extra is not None:
                r0, c0, a = res.extra
                view = footprint[r0 : r0 + a.shape[0], c0 : c0 + a.shape[1]]
                np.maximum(view, a, out=view)
                merged(r0, c0, r0 + view.shape[0], c0 + view.shape[1])

        def on_layer(i: int) -> None:
            if on_mask is not None:
                for c in range(copies):
                    on_mask(i * copies + c)

        def finish(partial) -> dict:
            def items() -> Iterator[Encoded]:
                for i in range(len(job)):
                    rec = partial.done[i]
                    z = float(job.plan.z_slice_mm[i])
                    for c, (name, s) in enumerate(zip(rec["files"], rec["plain_sums"], strict=True)):
                        # the merged part of the footprint only (not a pass over the whole field)
                        fp = (box[0], box[1], footprint[box[0] : box[2], box[1] : box[3]]) if (i == 0 and c == 0 and box[2] > box[0]) else None
                        yield Encoded(i * copies + c, i, c, z, (partial.dir / name).read_bytes(), int(s), fp,
                                      whole_footprint=fp is not None)

            try:
                summary = write_encoded(out, items(), info, fmt=fmt, claim=claim)
            except OSError as exc:
                if disk_full(exc, out) is not None:
                    partial.discard()  # a full disk: free what the run took (the claim names the file)
                raise
            partial.discard()
            return summary

        try:
            return write_journalled(out, plan, run, finish=finish, on_layer=on_layer, on_result=on_result,
                                    on_resumed=on_resumed)
        finally:
            forget_last_window()


def write_rotary_slices(job, out_dir: str | Path, *, device_name: str, options: dict, mesh_info: dict | None = None,
                        reference_images: bool = False, run: RunOptions | None = None,
                        on_layer: Callable[[int], None] | None = None) -> dict:
    """Write every layer of a direct rotary ``job`` into ``out_dir``; returns the manifest.

    Per layer ``layer_00000.png`` (one swathe) or ``layer_00000-s1.png``, ... (several), each
    with the sidecar ``layer_00000.json`` that ``rotoprint simulate`` reads; with
    ``reference_images`` also ``layer_00000-design.png``, the Cartesian cross-section on the
    sidecar's design grid (named in the sidecar, so ``rotoprint simulate`` finds it).
    ``manifest.json`` (:func:`rotoprint.rotary.direct.rotary_manifest`) lists every image with
    its head, tilt, placement, swathe, angle per firing and first firing index. Layers are
    made in threads, worker processes or on a Dask scheduler, journalled in ``<out>.partial``
    (``run.resume`` continues a killed run) and the folder is renamed into place only when
    complete; the bytes are the same whichever way they were made.

    Parameters
    ----------
    job : DirectSliceJob
        From :func:`rotoprint.rotary.slice_rotary`; each layer prints as ``(F_j, N) uint8``
        swathe images.
    out_dir : str or Path
        The output folder; replaced only if it is provably an earlier rotoprint output (or
        with ``run.force``).
    device_name : str
        Recorded in the sidecars and the manifest.
    options : dict
        The command's options, recorded in the manifest (JSON-ready values).
    mesh_info : dict, optional
        :meth:`~rotoprint.mesh.Mesh.info` of the source mesh, recorded in the manifest.
    reference_images : bool
        Also write each layer's Cartesian design image (``(H, W) uint8``, 255 = inside).
    run : RunOptions, optional
        Workers, Dask scheduler, resume, force, inputs (default: this process, afresh).
    on_layer : callable, optional
        Called with each finished layer's index (progress).

    Returns
    -------
    dict
        The manifest written as ``manifest.json``.

    Raises
    ------
    InputFileError
        The output folder holds something that is not provably an earlier rotoprint output
        (see :mod:`rotoprint.io.ownership`), is or holds an input, is in use by another run,
        or cannot be written.
    ResourceError
        Not enough disk space or memory for the run (checked before anything is written).
    """
    from ..rotary.direct import rotary_manifest

    out = Path(out_dir)
    run = run or RunOptions()
    with OutputClaim(out, is_dir=True, kind="rotary-slices", inputs=run.inputs, force=run.force) as claim:
        mj = MeshJob.of(job.slice_job, rotary_options=job.rotary_options)
        px = sum(job.head.nozzles * t.firings for t in job.tracks)
        plan = LayerPlan(layer_source(mj, RotaryLayer(device_name, bool(reference_images))), len(job), px, mj.nbytes)

        def finish(partial) -> dict:
            entries = [partial.done[i]["entry"] for i in range(len(job))]
            manifest = rotary_manifest(job, entries, device_name=device_name, options=options, mesh_info=mesh_info)
            (partial.dir / MANIFEST_NAME).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
            partial.finish_as_folder(claim)
            return manifest

        return write_journalled(out, plan, run, finish=finish, on_layer=on_layer)
