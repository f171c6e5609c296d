"""rotoprint: print data for rotary 3D printers and DLP projectors.

Fibre slicing at the device's own resolution, rotary image transforms for tilted print heads,
DLP masks, printability checks and multi-material process plans.
"""

from __future__ import annotations

import logging

from ._version import __version__
from .errors import (  # noqa: E402
    ConfigError,
    DeviceError,
    GeometryError,
    ImageError,
    InputFileError,
    MeshError,
    RasterTooLargeError,
    ResourceError,
    RotoprintError,
)

logging.getLogger(__name__).addHandler(logging.NullHandler())

#: The top-level API, imported on first use (PEP 562): ``import rotoprint`` (and so every
#: ``rotoprint`` command, which imports this package first) does not pay for numpy,
#: pydantic and the slicer before it needs them.
_LAZY = {
    "load_mesh": ".io.mesh",
    "make_transform": ".io.mesh",
    "Mesh": ".mesh",
    "load_device": ".devices",
    "slice_mesh": ".slicing",
}


def __getattr__(name: str):
    mod = _LAZY.get(name)
    if mod is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(mod, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))

__all__ = [
    "__version__",
    "load_mesh",
    "make_transform",
    "Mesh",
    "load_device",
    "slice_mesh",
    "RotoprintError",
    "InputFileError",
    "MeshError",
    "DeviceError",
    "ConfigError",
    "ImageError",
    "GeometryError",
    "RasterTooLargeError",
    "ResourceError",
]
