"""The exception hierarchy: one root, subclasses that also inherit the matching builtin.

Every error rotoprint raises on bad input is a :class:`RotoprintError`. Messages say what was
expected and what came, and name the file where there is one, so the CLI can print them as
one line and exit with code 2.
"""

from __future__ import annotations

from pathlib import Path

__all__ = [
    "RotoprintError",
    "InputFileError",
    "MeshError",
    "DeviceError",
    "ConfigError",
    "ImageError",
    "RasterTooLargeError",
    "GeometryError",
    "ResourceError",
    "CadError",
]


class RotoprintError(Exception):
    """Root of every error rotoprint raises on purpose."""

    def __init__(self, message: str, *, path: str | Path | None = None) -> None:
        self.path = None if path is None else str(path)
        self.problem = message
        super().__init__(f"{self.path}: {message}" if self.path else message)


class InputFileError(RotoprintError, OSError):
    """A file is missing, is a directory, or cannot be read or written."""


class MeshError(RotoprintError, ValueError):
    """A mesh file was read but its content is not a usable triangle mesh."""


class DeviceError(RotoprintError, ValueError):
    """A device preset or device file is unknown or has an invalid field."""


class ConfigError(RotoprintError, ValueError):
    """An option or a job setting is out of range or inconsistent."""


class ImageError(RotoprintError, ValueError):
    """An input image cannot be used (format, depth, size)."""


class GeometryError(RotoprintError, ValueError):
    """A placement or geometry request cannot be satisfied (part outside the field, ...)."""


class RasterTooLargeError(RotoprintError, MemoryError):
    """A raster would not fit in the memory this machine has."""


class ResourceError(RotoprintError, OSError):
    """A run would need more disk or memory than this machine has; refused before it starts."""


class CadError(RotoprintError, ValueError):
    """A 2-D CAD file (Gerber, Excellon, DXF, SVG) was read but its content cannot be used
    (undefined aperture, self-intersecting region, unclosed contour, unit that is not a length)."""
