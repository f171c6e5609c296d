"""The DLP output formats, one module each, in one registry: ``FORMATS[name]`` is the
:class:`~rotoprint.io.formats._common.ArchiveFormat` (writer, reader, suffixes, mask names).
A new format is a module with its entry, added here."""

from __future__ import annotations

from ._common import ArchiveFormat
from .perfactory import PERFACTORY
from .png import PNG
from .sl1 import SL1, SL1S

__all__ = ["ArchiveFormat", "FORMATS", "by_kind", "by_suffix"]

FORMATS: dict[str, ArchiveFormat] = {f.name: f for f in (SL1, SL1S, PNG, PERFACTORY)}


def by_suffix(suffix: str) -> ArchiveFormat | None:
    """The file format written for an output ending in ``suffix`` (lower case), if any."""
    return next((f for f in FORMATS.values() if suffix in f.suffixes), None)


def by_kind(kind: str | None) -> ArchiveFormat:
    """The folder format whose manifest says ``kind``; a plain PNG folder otherwise."""
    return next((f for f in FORMATS.values() if f.is_dir and f.kind == kind), PNG)
