"""DLP jobs made in parallel and resumably: masks journalled in ``<out>.partial``, then
assembled into the SL1 / SL1S archive or the folder named by ``out`` only when complete."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
from PIL import Image

from ..runner import MaskLayerResult
from ..slicing.fibres import SliceJob
from .archives import JobInfo, _Encoded, format_from_path, write_encoded
from .layers import run_layers, task_from_job
from .atomic import OutputClaim, disk_full
from .resumable import PartialOutput

__all__ = ["write_dlp_job"]


def _mask_name(number: int) -> str:
    return f"mask_{number:05d}.png"


def write_dlp_job(
    job: SliceJob,
    out: str | Path,
    info: JobInfo,
    options,
    *,
    fmt: str | None = None,
    workers: int = 1,
    scheduler: str | None = None,
    resume: bool = False,
    on_mask: Callable[[int], None] | None = None,
    force: bool = False,
    inputs=(),
) -> dict:
    """Make every mask of ``job`` with ``options`` (a :class:`rotoprint.masks.MaskOptions`)
    and write the job to ``out`` as ``fmt`` (default: from the suffix). The bytes are the same
    for any ``workers`` or ``scheduler`` (set ``SOURCE_DATE_EPOCH`` to fix the archive's
    creation time too); ``resume`` continues a killed run.

    Parameters
    ----------
    job : SliceJob
    out : str or Path
        ``.sl1`` / ``.sl1s`` file, or a folder (``png`` or ``perfactory``). Masks are made in
        ``<out>.partial`` (see :mod:`rotoprint.io.resumable`) and ``out`` is written only
        when all are there.
    info : JobInfo
        Printer and exposure settings written with the masks.
    options : MaskOptions
        How each layer's image becomes its mask(s); ``options.copies`` masks per layer.
    fmt : {'auto', 'sl1', 'sl1s', 'png', 'perfactory'}, optional
        Default: from the suffix of ``out`` (see :func:`~rotoprint.io.archives.format_from_path`).
    workers : int
        Local processes making layers (at least 1).
    scheduler : str, optional
        Address ``[tcp://]HOST:PORT`` of a Dask scheduler to make the layers on instead.
    resume : bool
        Keep the verified layers of an earlier run of the same job in ``<out>.partial``.
    on_mask : callable, optional
        Called with the number of every mask once it is made (resumed ones included).
    force : bool
        Replace an existing ``out`` even if it is not provably ours (see
        :mod:`rotoprint.io.ownership`).
    inputs : iterable of path
        Files the run read (the mesh, a device file): ``out`` must not be or hold one.

    Returns
    -------
    dict
        The summary of :func:`~rotoprint.io.archives.write_job` (the manifest for folders).

    Raises
    ------
    ConfigError
        Unknown ``fmt`` or a suffix it cannot be told from, ``workers < 1``, or a malformed
        ``scheduler`` address.
    InputFileError
        ``out`` must not be written or replaced (missing parent folder, a file where a folder
        goes or the reverse, an input, anything not provably ours), another run is writing
        it, or ``<out>.partial`` exists without a journal.
    ResourceError
        The run would need more disk or memory than is available (checked before any mask is
        written).
    """
    from ..masks.pipeline import plain_from_image

    fmt = format_from_path(out, fmt)
    out = Path(out)
    with OutputClaim(out, is_dir=fmt not in ("sl1", "sl1s"), kind=f"dlp-{fmt}", inputs=inputs, force=force) as claim:
        task = task_from_job(job, mask_options=options.to_json())
        partial = PartialOutput(out, task._key, len(job), resume=resume)
        copies = options.copies
        footprint = np.zeros((job.grid.height, job.grid.width), np.uint8)
        with partial:  # a run that fails before finishing a layer leaves nothing
            for i, rec in partial.done.items():  # resumed layers: footprints from their files
                for name in rec["files"]:
                    with Image.open(partial.dir / name) as im:
                        np.maximum(footprint, plain_from_image(np.asarray(im.convert("L")), options), out=footprint)
                if on_mask is not None:
                    for c in range(copies):
                        on_mask(i * copies + c)
            px = job.grid.width * job.grid.height
            for res in run_layers(len(job), px, task, partial, workers=workers, scheduler=scheduler, copies_on_disk=2):
                assert isinstance(res, MaskLayerResult)  # noqa: S101 - the task asks for masks
                names = [_mask_name(res.index * copies + c) for c in range(copies)]
                partial.record(res.index, dict(zip(names, res.pngs, strict=True)), plain_sums=list(res.plain_sums))
                if res.footprint is not None:
                    r0, c0, a = res.footprint
                    view = footprint[r0 : r0 + a.shape[0], c0 : c0 + a.shape[1]]
                    np.maximum(view, a, out=view)
                if on_mask is not None:
                    for c in range(copies):
                        on_mask(res.index * copies + c)

        def items() -> Iterator[_Encoded]:
            for i in range(len(job)):
                rec = partial.done[i]
                z = float(job.plan.z_slice_mm[i])
                for c, (name, s) in enumerate(zip(rec["files"], rec["plain_sums"], strict=True)):
                    fp = (0, 0, footprint) if (i == 0 and c == 0) else None
                    yield _Encoded(i * copies + c, i, c, z, (partial.dir / name).read_bytes(), int(s), fp)

        try:
            summary = write_encoded(out, items(), info, fmt=fmt, claim=claim)
        except OSError as exc:
            if disk_full(exc, out) is not None:
                partial.discard()  # a full disk: free what the run took (the claim names the file)
            raise
        partial.discard()
    return summary
