"""The parallel layer producer: one process, a pool of worker processes, or a Dask cluster.

It is handed a :class:`LayerSource`, two picklable callables and a key: ``make_job()`` builds
the job once per worker thread, ``render(job, i)`` turns layer ``i`` into a
:class:`Rendered` (the layer's files as bytes). It knows nothing of what the layers are
(slicing, masks, rotary: see :mod:`rotoprint.pipeline.tasks`). Results come back *in layer
order* through a bounded window of layers in flight (:func:`rotoprint._window.ordered`),
so memory does not grow with the layer count, and the bytes are the same whichever way they
were made.
"""

from __future__ import annotations

import os
import re
import threading
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

from .._dataclass import dataclass, field
from ..errors import ConfigError
from .._window import ordered

__all__ = ["LayerSource", "Rendered", "RunOptions", "produce_layers", "render_one", "check_scheduler_address",
           "cpu_count", "DASK_CONNECT_TIMEOUT_S"]

#: Seconds to wait for a Dask scheduler (connection and handshake) before giving up.
DASK_CONNECT_TIMEOUT_S = 10.0


@dataclass(frozen=True)
class RunOptions:
    """Where and how layers are made.

    Parameters
    ----------
    workers : int
        1: in this process (two threads overlap, since the kernels and zlib release the GIL).
        N > 1: N worker processes on this machine.
    scheduler : str, optional
        Address ``[tcp://]HOST:PORT`` of a running Dask distributed scheduler to make the
        layers on instead (the ``rotoprint[dask]`` extra).
    resume : bool
        Keep the verified layers of an earlier run of the same job (journalled outputs).
    force : bool
        Replace an existing output even if it is not provably ours (see
        :mod:`rotoprint.io.ownership`).
    inputs : tuple of path
        Files the run read (the mesh, a device file): the output must not be or hold one.
    """

    workers: int = 1
    scheduler: str | None = None
    resume: bool = False
    force: bool = False
    inputs: tuple = ()

    def __post_init__(self) -> None:
        if self.workers < 1:
            raise ConfigError(f"workers must be at least 1, got {self.workers}")
        if self.scheduler is not None:
            check_scheduler_address(self.scheduler)


@dataclass(frozen=True)
class Rendered:
    """One layer as made by a worker.

    ``files`` ``{name: bytes}`` are written and journalled as they are; ``payload`` (JSON
    values) goes into the layer's journal record; ``extra`` travels to the writer and is not
    journalled (e.g. a DLP layer's footprint).
    """

    index: int
    files: dict[str, bytes]
    payload: dict = field(default_factory=dict)
    extra: Any = None

    @property
    def nbytes(self) -> int:
        return sum(len(b) for b in self.files.values())


@dataclass(frozen=True)
class LayerSource:
    """What the producer is given: picklable ``make_job() -> job`` and
    ``render(job, index) -> Rendered``, and ``key`` (a fingerprint of both, e.g. a SHA-256) by
    which a worker knows it already holds the job. An empty key: the source object itself is
    the key."""

    make_job: Callable[[], Any]
    render: Callable[[Any, int], Rendered]
    key: str = ""


# ---------------------------------------------------------------------- worker side
_LOCAL = threading.local()  # one job per thread: a job may keep state between layers


def _job_for(source: LayerSource):
    """The thread's job for ``source``, built once. Keyed by the source's key when it has one,
    else by the source object itself (held, so that its id cannot be reused meanwhile)."""
    cached = getattr(_LOCAL, "job", None)
    if cached is not None:
        key, held, job = cached
        if (source.key and key == source.key) or held is source:
            return job
    job = source.make_job()
    _LOCAL.job = (source.key, source, job)
    return job


def render_one(source: LayerSource, index: int) -> Rendered:
    """Make layer ``index`` of ``source`` (runs in a worker or in-process).

    Parameters
    ----------
    source : LayerSource
    index : int

    Returns
    -------
    Rendered
    """
    return source.render(_job_for(source), index)


_POOL_SOURCE: LayerSource | None = None


def _pool_init(source: LayerSource) -> None:
    global _POOL_SOURCE
    _POOL_SOURCE = source


def _pool_render(index: int) -> Rendered:
    assert _POOL_SOURCE is not None  # noqa: S101 - set by the pool initializer
    return render_one(_POOL_SOURCE, index)


# ---------------------------------------------------------------------- driver side
def produce_layers(source: LayerSource, indices: Iterable[int], run: RunOptions | None = None, *,
                   window: int | None = None) -> Iterator[Rendered]:
    """Yield the :class:`Rendered` layers ``indices`` of ``source``, in that order.

    Parameters
    ----------
    source : LayerSource
    indices : iterable of int
    run : RunOptions, optional
        Workers or Dask scheduler (default: this process).
    window : int, optional
        Layers in flight at most (default ``4 * workers``, or 4 x the cluster's threads).

    Returns
    -------
    iterator of Rendered
        In the order of ``indices``. A Dask scheduler is reached (and refused with a
        ConfigError) when this is called, before the first layer.
    """
    run = run or RunOptions()
    indices = indices if isinstance(indices, Sequence) else list(indices)  # an array of indices stays one
    if run.scheduler is not None:
        if indices:  # connect now, not at the first next(): a dead scheduler fails before any layer is kept
            check_scheduler_address(run.scheduler)
            _probe_scheduler(run.scheduler, DASK_CONNECT_TIMEOUT_S)
        return _produce_dask(source, indices, run.scheduler, window)
    return _produce_local(source, indices, run.workers, window)


def _produce_local(source: LayerSource, indices: list[int], workers: int, window: int | None) -> Iterator[Rendered]:
    if workers == 1 or len(indices) <= 1:
        threads = min(2, cpu_count())
        if threads == 1 or len(indices) <= 1:
            for i in indices:
                yield render_one(source, i)
            return
        from concurrent.futures import ThreadPoolExecutor  # (imported when threads start: a short job makes none)

        with ThreadPoolExecutor(max_workers=threads, thread_name_prefix="rotoprint-layer") as ex:
            yield from ordered(lambda i: ex.submit(render_one, source, i), indices, window or 2 * threads)
        return
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing import get_context

    ctx = get_context("spawn")  # no fork: the parent may hold threads (progress bars, BLAS)
    with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=_pool_init, initargs=(source,)) as ex:
        yield from ordered(lambda i: ex.submit(_pool_render, i), indices, window or 4 * workers)


def check_scheduler_address(address: str) -> None:
    """Refuse, before any work, a scheduler address that is not ``[tcp://]host:port``.

    Raises
    ------
    ConfigError
    """
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

    try:
        from distributed.comm import connect
        from distributed.security import Security
    except ImportError:
        raise ConfigError("--scheduler needs Dask distributed: pip install 'rotoprint[dask]'") from None

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


def _produce_dask(source: LayerSource, indices: list[int], address: str, window: int | None) -> Iterator[Rendered]:
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
        remote = client.scatter(source, broadcast=True)  # the mesh goes to the workers once
        yield from ordered(lambda i: client.submit(render_one, remote, i, pure=False), indices, window or 4 * threads)
    finally:
        client.close()


def cpu_count() -> int:
    """CPUs this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - non-Linux
        return os.cpu_count() or 1
