"""Orchestration: the stages of a build, the parallel layer producer and the journalled
outputs. The packages below (slicing, rotary, masks, check, process, report, io) compute or
read and write formats; this package runs them in order (see docs/architecture.md).

- :mod:`.producer`: layers in threads, worker processes or on a Dask cluster (through the
  one bounded ordered window of futures, :mod:`rotoprint._window`), handed
  picklable "make the job" and "render layer i" callables (:class:`LayerSource`).
- :mod:`.tasks`: the three kinds of layer work (plain layers, DLP masks, rotary slices).
- :mod:`.journal`: the one journalled, resumable writer.
- :mod:`.outputs`: layer folders, DLP jobs, rotary slices.
- :mod:`.build`: ``rotoprint build`` as named stages.
"""

from __future__ import annotations

from .outputs import write_dlp_job, write_layer_folder, write_rotary_slices
from .producer import LayerSource, Rendered, RunOptions, produce_layers

_LAZY = {"BuildResult": ".build", "run_build": ".build"}  # `rotoprint build` only: not imported by the others


def __getattr__(name: str):
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


__all__ = [
    "BuildResult",
    "LayerSource",
    "Rendered",
    "RunOptions",
    "produce_layers",
    "run_build",
    "write_dlp_job",
    "write_layer_folder",
    "write_rotary_slices",
]
