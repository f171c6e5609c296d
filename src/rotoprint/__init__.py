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
from .io.mesh import load_mesh, make_transform  # noqa: E402
from .mesh import Mesh  # noqa: E402
from .devices import load_device  # noqa: E402
from .slicing import slice_mesh  # noqa: E402

logging.getLogger(__name__).addHandler(logging.NullHandler())

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
