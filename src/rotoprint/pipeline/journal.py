"""The one journalled, resumable writer of layer outputs (layer folders, DLP jobs, rotary
slices).

Layers are made by the producer (:mod:`rotoprint.pipeline.producer`) and journalled one by
one in ``<out>.partial`` (:class:`rotoprint.io.resumable.PartialOutput`); before anything is
written, three sample layers size the run against the free disk and memory. When every layer
is there, the caller's ``finish`` turns the work folder into the output (a folder renamed
into place, or an archive assembled from it).
"""

from __future__ import annotations

import time
from array import array
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TypeVar

from .._dataclass import dataclass
from ..io.resumable import PartialOutput, check_resources
from .producer import LayerSource, Rendered, RunOptions, produce_layers, render_one

__all__ = ["LayerPlan", "write_journalled"]

#: In-process runs: when the median sample layer's CPU time times the layers left is less than
#: this (seconds), they are made in this thread: two render threads would each build the job
#: first (a few ms) for little to share (a 10-layer plate whose layers are all alike).
SMALL_REST_S = 0.02

T = TypeVar("T")


@dataclass(frozen=True)
class LayerPlan:
    """What a journalled run makes.

    Parameters
    ----------
    source : LayerSource
        Its key is the run's fingerprint in the journal.
    n_layers : int
    px : int
        Pixels of one layer's raster(s), for the memory estimate.
    job_bytes : int
        Memory one worker's job takes beyond its rasters (e.g. the mesh and its sweep).
    copies_on_disk : int
        Copies of each layer's output the disk must hold at once (2 when an archive is
        assembled from the work folder).
    """

    source: LayerSource
    n_layers: int
    px: int
    job_bytes: int = 0
    copies_on_disk: int = 1


def write_journalled(
    out: str | Path,
    plan: LayerPlan,
    run: RunOptions,
    *,
    finish: Callable[[PartialOutput], T],
    on_layer: Callable[[int], None] | None = None,
    on_result: Callable[[Rendered], None] | None = None,
    on_resumed: Callable[[int, dict, Path], None] | None = None,
) -> T:
    """Make every layer of ``plan`` into ``<out>.partial``, journalled; then ``finish``.

    Parameters
    ----------
    out : str or Path
        The final output (checked by the caller before).
    plan : LayerPlan
    run : RunOptions
    finish : callable
        ``finish(partial)`` once every layer is journalled (``partial.done`` holds every
        layer's record); its result is returned.
    on_layer : callable, optional
        Called with the index of every layer once it is there (resumed ones first).
    on_result : callable, optional
        Called with every :class:`Rendered` layer once it is journalled (not the resumed ones).
    on_resumed : callable, optional
        ``on_resumed(index, record, folder)`` for every layer kept from an earlier run.

    Returns
    -------
    object
        What ``finish`` returns.

    Raises
    ------
    ResourceError
        The run would need more disk or memory than is available (before anything is written).
    """
    partial = PartialOutput(out, plan.source.key, plan.n_layers, resume=run.resume)
    with partial:  # a run that fails before finishing a layer leaves nothing
        for i, rec in partial.done.items():
            if on_resumed is not None:
                on_resumed(i, rec, partial.dir)
            if on_layer is not None:
                on_layer(i)
        for res in _run_layers(plan, partial, run):
            partial.record(res.index, res.files, **res.payload)
            if on_result is not None:
                on_result(res)
            if on_layer is not None:
                on_layer(res.index)
    return finish(partial)


def _run_layers(plan: LayerPlan, partial: PartialOutput, run: RunOptions) -> Iterator[Rendered]:
    """Size the run (three sample layers made first), then yield every layer not already
    done, in order. Nothing is written before the size check passes."""
    todo = array("q", (i for i in range(plan.n_layers) if i not in partial.done))  # 8 bytes a layer
    sample_idx = sorted({todo[0], todo[len(todo) // 2], todo[-1]}) if todo else []
    samples = {}
    took_s = []
    for i in sample_idx:
        t0 = time.thread_time()  # (this thread's CPU: not the waits of a loaded machine)
        samples[i] = render_one(plan.source, i)
        took_s.append(time.thread_time() - t0)
    # the median sample: the first layer made in a process also pays one-time costs
    typical_s = sorted(took_s)[len(took_s) // 2] if took_s else 0.0
    sizes = [r.nbytes for r in samples.values()]
    procs = 1 if (run.scheduler is not None or run.workers == 1) else run.workers + 1
    check_resources(
        n_layers=plan.n_layers,
        bytes_per_layer=sum(sizes) / max(1, len(sizes)),
        copies_on_disk=plan.copies_on_disk,
        per_process_bytes=plan.job_bytes + 8 * plan.px + 150 * 2**20,
        processes=procs,
        in_flight_bytes=4 * max(run.workers, 2) * 2 * plan.px,
        where=partial.dir.parent,
    )
    partial.open()
    rest = array("q", (i for i in todo if i not in samples))
    if run.workers == 1 and run.scheduler is None and typical_s * len(rest) < SMALL_REST_S:
        # what is left takes less than starting the render threads (and building their jobs)
        # saves: made here, one by one (the same bytes)
        it = (render_one(plan.source, i) for i in rest)
    else:
        it = iter(produce_layers(plan.source, rest, run))
    for i in todo:
        yield samples[i] if i in samples else next(it)
