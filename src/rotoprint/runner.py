"""Producing layers: one process, a pool of worker processes, or a Dask cluster.

A :class:`LayerTask` is a picklable description of a slicing run (the mesh arrays, the device,
the options and what to make of each layer). Workers rebuild the slicing job once and then
turn layer indices into encoded PNG bytes. Results come back *in layer order* through a
bounded window of layers in flight, so memory does not grow with the layer count, and the
bytes are the same whichever way they were made (same pixels, same encoder settings).
"""

from __future__ import annotations

import hashlib
import json
import os
import threading
from collections import deque
from collections.abc import Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor
from dataclasses import dataclass, field
from multiprocessing import get_context

import numpy as np

from .errors import ConfigError

__all__ = ["LayerTask", "LayerResult", "MaskLayerResult", "RotaryLayerResult", "produce_layers", "task_fingerprint"]

#: Seconds to wait for a Dask scheduler (connection and handshake) before giving up.
DASK_CONNECT_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class LayerResult:
    index: int
    png: bytes
    sha256: str
    pixels_on: int
    gaps: dict


@dataclass(frozen=True)
class MaskLayerResult:
    """The DLP masks of one layer: one PNG per copy (ERM makes two), the sum of each copy's
    plain mask (for the resin volume), and the layer's footprint (max over its copies),
    cropped to its bounding box as ``(row0, col0, (h, w) uint8)`` or None when empty."""

    index: int
    pngs: tuple[bytes, ...]
    sha256s: tuple[str, ...]
    plain_sums: tuple[int, ...]
    footprint: tuple[int, int, np.ndarray] | None


@dataclass(frozen=True)
class RotaryLayerResult:
    """One layer of direct rotary slicing: its files as bytes and its manifest entry."""

    index: int
    files: dict
    record: dict


@dataclass(frozen=True)
class LayerTask:
    """Everything a worker needs to make layers, and nothing that is not picklable.

    ``vertices`` ``(V, 3) float64``, ``faces`` ``(F, 3) int64``: the repaired mesh (the
    worker does not repair it again); ``device`` the device model's JSON; ``slice_options``
    the keyword arguments of :func:`rotoprint.slice_mesh`.
    """

    vertices: np.ndarray
    faces: np.ndarray
    source: str | None
    device: dict
    slice_options: dict
    compress_level: int = 3
    mask_options: dict | None = None  # set: DLP masks (MaskOptions fields) instead of plain layers
    rotary: dict | None = None  # set: direct rotary slicing (options, device name, reference images)
    face_edges: np.ndarray | None = field(default=None, compare=False)
    suspect_edges: np.ndarray | None = field(default=None, compare=False)
    _key: str = field(default="", compare=False)

    def build_job(self):
        from .devices import _validate
        from .mesh import Mesh
        from .slicing import slice_mesh

        mesh = Mesh(vertices=self.vertices, faces=self.faces, source=self.source)  # already repaired
        if self.face_edges is not None and self.suspect_edges is not None:
            from .mesh import PrebuiltTopology

            object.__setattr__(mesh, "_topology", PrebuiltTopology(self.face_edges, self.suspect_edges))
        device = _validate(self.device, "task device")
        if self.rotary is not None:
            from .rotary.direct import slice_rotary

            job = slice_rotary(mesh, device, **self.rotary["options"])
        else:
            job = slice_mesh(mesh, device, **self.slice_options)
        from ._resources import release_free_memory

        release_free_memory()
        return job


def task_fingerprint(task: LayerTask, extra: dict | None = None) -> str:
    """SHA-256 over the mesh, the device, the options and the rotoprint version."""
    from . import __version__

    h = hashlib.sha256()
    h.update(np.ascontiguousarray(task.vertices, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(task.faces, dtype="<i8").tobytes())
    meta = {"device": task.device, "options": task.slice_options, "png": task.compress_level,
            "masks": task.mask_options, "rotary": task.rotary, "version": __version__, "extra": extra or {}}
    h.update(json.dumps(meta, sort_keys=True, default=str).encode())
    return h.hexdigest()


# ---------------------------------------------------------------------- worker side
_LOCAL = threading.local()  # one job per thread: a job's face sweep has state


def _job_for(task: LayerTask):
    """The thread's job for ``task``, built once. Keyed by the task's fingerprint when it has
    one, else by the task object itself (held, so that its id cannot be reused meanwhile)."""
    cached = getattr(_LOCAL, "job", None)
    if cached is not None:
        key, held, job = cached
        if (task._key and key == task._key) or held is task:
            return job
    job = task.build_job()
    _LOCAL.job = (task._key, task, job)
    return job


def render_layer(task: LayerTask, index: int) -> LayerResult | MaskLayerResult:
    """Make layer ``index`` of ``task`` as PNG bytes (runs in a worker or in-process)."""
    from .io.images import png_bytes

    if task.mask_options is not None:
        return _render_masks(task, index)
    if task.rotary is not None:
        from .rotary.direct import rotary_layer_files

        r = task.rotary
        files, record = rotary_layer_files(_job_for(task), index, device_name=r["device_name"],
                                           reference_images=r["reference_images"])
        return RotaryLayerResult(index, files, record)
    layer = _job_for(task).layer(index)
    data = png_bytes(layer.image, compress_level=task.compress_level)
    return LayerResult(index, data, hashlib.sha256(data).hexdigest(), int(np.count_nonzero(layer.image)),
                       layer.gaps.to_json())


def _render_masks(task: LayerTask, index: int) -> MaskLayerResult:
    from .io.images import png_bytes
    from .masks.pipeline import MaskOptions, layer_masks

    options = MaskOptions(**task.mask_options)
    job = _job_for(task)
    fast = _render_coverage_window(job, index, options)
    if fast is not None:
        return fast
    masks = layer_masks(job, index, options)
    pngs = tuple(png_bytes(m.image, compress_level=task.compress_level) for m in masks)
    fp = masks[0].plain
    for m in masks[1:]:
        fp = np.maximum(fp, m.plain)
    rows = np.flatnonzero(fp.any(axis=1))
    crop = None
    if rows.size:
        cols = np.flatnonzero(fp.any(axis=0))
        crop = (int(rows[0]), int(cols[0]), np.ascontiguousarray(fp[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]))
    return MaskLayerResult(
        index=index,
        pngs=pngs,
        sha256s=tuple(hashlib.sha256(p).hexdigest() for p in pngs),
        plain_sums=tuple(int(m.plain.sum(dtype=np.uint64)) for m in masks),
        footprint=crop,
    )


def _render_coverage_window(job, index: int, options) -> MaskLayerResult | None:
    """Coverage masks without inset, smoothing, ERM or inversion, made and encoded from the
    part's window only (the rest of the mask is black): the same pixels as
    :func:`~rotoprint.masks.pipeline.layer_masks`, without whole-image passes. None when
    the options or the layer need the general path."""
    if (options.mode != "coverage" or options.erm or options.invert or index < options.first_layers
            or job.fill != "nonzero"):
        return None
    from .io.images import png_bytes_window
    from .masks.coverage import coverage_window

    s, e, _ = job.pixel_segments(index)
    shape = job.grid.shape
    r0, c0, win, tail = coverage_window(s, e, shape)
    if tail is not None:  # the rows right of the window are not black: general path
        return None
    rows = np.flatnonzero(win.any(axis=1))
    crop = None
    if rows.size:
        cols = np.flatnonzero(win.any(axis=0))
        crop = (r0 + int(rows[0]), c0 + int(cols[0]),
                np.ascontiguousarray(win[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]))
    png = png_bytes_window(win, shape, r0, c0, mirror_x=options.mirror_x, mirror_y=options.mirror_y)
    return MaskLayerResult(index=index, pngs=(png,), sha256s=(hashlib.sha256(png).hexdigest(),),
                           plain_sums=(int(win.sum(dtype=np.uint64)),), footprint=crop)


_POOL_TASK: LayerTask | None = None


def _pool_init(task: LayerTask) -> None:
    global _POOL_TASK
    _POOL_TASK = task


def _pool_render(index: int) -> LayerResult:
    assert _POOL_TASK is not None  # noqa: S101 - set by the pool initializer
    return render_layer(_POOL_TASK, index)


# ---------------------------------------------------------------------- driver side
def produce_layers(
    task: LayerTask,
    indices: Iterable[int],
    *,
    workers: int = 1,
    scheduler: str | None = None,
    window: int | None = None,
) -> Iterator[LayerResult]:
    """Yield :class:`LayerResult` for ``indices``, in that order.

    Parameters
    ----------
    workers : int
        1: in this process (two threads overlap, since the kernels and zlib release the
        GIL). N > 1: N worker processes on this machine.
    scheduler : str, optional
        Address of a running Dask distributed scheduler (``tcp://host:port``); the task (the
        mesh) is sent to the workers once. Needs the ``rotoprint[dask]`` extra.
    window : int, optional
        Layers in flight at most (default ``4 * workers``, or 4 x the cluster's threads).
    """
    indices = list(indices)
    if workers < 1:
        raise ConfigError(f"workers must be at least 1, got {workers}")
    task = _keyed(task)
    if scheduler is not None:
        if indices:  # connect now, not at the first next(): a dead scheduler fails before any layer is kept
            check_scheduler_address(scheduler)
            _probe_scheduler(scheduler, DASK_CONNECT_TIMEOUT_S)
        return _produce_dask(task, indices, scheduler, window)
    return _produce_local(task, indices, workers, window)


def _produce_local(task: LayerTask, indices: list[int], workers: int, window: int | None) -> Iterator[LayerResult]:
    if workers == 1 or len(indices) <= 1:
        threads = min(2, cpu_count())
        if threads == 1 or len(indices) <= 1:
            for i in indices:
                yield render_layer(task, i)
            return
        with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="rotoprint-layer") as ex:
            yield from _ordered(lambda i: ex.submit(render_layer, task, i), indices, window or 2 * threads)
        return
    ctx = get_context("spawn")  # no fork: the parent may hold threads (progress bars, BLAS)
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_pool_init, initargs=(task,)) as ex:
        yield from _ordered(lambda i: ex.submit(_pool_render, i), indices, window or 4 * workers)


def _keyed(task: LayerTask) -> LayerTask:
    if task._key:
        return task
    import dataclasses

    return dataclasses.replace(task, _key=task_fingerprint(task))


def _ordered(submit, indices: list[int], window: int) -> Iterator[LayerResult]:
    pending: deque = deque()
    it = iter(indices)
    for i in it:
        pending.append(submit(i))
        if len(pending) >= window:
            break
    while pending:
        fut = pending.popleft()
        yield fut.result()
        nxt = next(it, None)
        if nxt is not None:
            pending.append(submit(nxt))


def check_scheduler_address(address: str) -> None:
    """Refuse, before any work, a scheduler address that is not ``[tcp://]host:port``."""
    import re

    m = re.fullmatch(r"(?:(?:tcp|tls|inproc|ws|wss)://)?[^\s:/]+:(\d{1,5})", address or "")
    if not m:
        raise ConfigError(f"scheduler address must look like tcp://HOST:PORT, got {address!r}")
    if not 1 <= int(m.group(1)) <= 65535:
        raise ConfigError(f"scheduler address {address!r}: port {m.group(1)} is not a TCP port (1 to 65535)")


def _probe_scheduler(address: str, timeout_s: float) -> None:
    """Connect to the scheduler and complete Dask's handshake within ``timeout_s``.

    ``distributed.Client`` bounds the TCP connect but not the handshake read after it, so a
    server that accepts and never answers would block it forever; this refuses such an
    address first, in bounded time.
    """
    import asyncio

    from distributed.comm import connect
    from distributed.security import Security

    async def handshake() -> None:
        comm = await connect(address, timeout=timeout_s, **Security().get_connection_args("client"))
        await comm.close()

    try:
        asyncio.run(asyncio.wait_for(handshake(), timeout_s))
    except (asyncio.TimeoutError, TimeoutError):
        raise ConfigError(f"the Dask scheduler at {address} did not answer within {timeout_s:g} s "
                          "(is it a Dask scheduler?)") from None
    except (OSError, ValueError, TypeError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler at {address}: {exc}") from None


def _produce_dask(task: LayerTask, indices: list[int], address: str, window: int | None) -> Iterator[LayerResult]:
    try:
        from distributed import Client
    except ImportError:
        raise ConfigError("--scheduler needs Dask distributed: pip install 'rotoprint[dask]'") from None
    try:
        client = Client(address, timeout=f"{DASK_CONNECT_TIMEOUT_S}s", set_as_default=False)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        raise ConfigError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        threads = sum(client.nthreads().values()) or 1
        remote = client.scatter(task, broadcast=True)  # the mesh goes to the workers once
        yield from _ordered(lambda i: client.submit(render_layer, remote, i, pure=False), indices, window or 4 * threads)
    finally:
        client.close()


def cpu_count() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - non-Linux
        return os.cpu_count() or 1
