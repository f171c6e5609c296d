"""Writing a bundled example (its job file and meshes, :mod:`rotoprint.process.examples`) into
a folder for ``rotoprint demo``: atomically, and never over what the user made."""

from __future__ import annotations

import contextlib
from pathlib import Path

from ..errors import InputFileError
from ..io.atomic import atomic_file
from ..process.examples import example_files

__all__ = ["write_example"]


def _holds(p: Path, data: bytes) -> bool:
    """Whether ``p`` is a regular file holding exactly ``data`` (read bounded: a FIFO or a
    device is never read, it just does not hold the example)."""
    from ..io.inputs import read_input_bytes

    try:
        if not p.is_file() or p.stat().st_size != len(data):
            return False
        return read_input_bytes(p, what="example file", limit_bytes=len(data)) == data
    except (OSError, InputFileError):
        return False


def write_example(name: str, folder: str | Path, *, overwrite: bool = False) -> Path:
    """Write example ``name`` (job file and its meshes) into ``folder``; returns the job path.

    Every file is written atomically (a temporary file renamed into place). The folder may be
    new, empty, or hold an earlier copy of this example; a folder holding anything else, or
    one of the example's files changed since, is refused unless ``overwrite`` (which still
    leaves files that are not the example's alone).

    Parameters
    ----------
    name : str
        A key of :data:`EXAMPLES` (``"coil-sensor"``, ``"gas-sensor"``).
    folder : str or Path
        Where to write; created (with its parents) if missing.
    overwrite : bool
        Replace the example's files even if they were changed.

    Returns
    -------
    Path
        The job file, ``folder / "<name>.toml"``.

    Raises
    ------
    ConfigError
        Unknown example.
    InputFileError
        ``folder`` is a file, holds other files, or holds an edited copy of the example.
    """
    files = example_files(name)
    folder = Path(folder)
    if folder.exists():
        if not folder.is_dir():
            raise InputFileError("exists and is not a folder; refusing to write the example there", path=folder)
        others = sorted(p.name for p in folder.iterdir() if p.name not in files)
        if others and not overwrite:
            raise InputFileError(f"holds files that are not the {name} example ({', '.join(others[:3])}"
                                 f"{', ...' if len(others) > 3 else ''}); refusing to write the example there", path=folder)
        for fname, data in files.items():
            p = folder / fname
            if p.is_dir() or (p.exists() and not overwrite and not _holds(p, data)):
                raise InputFileError(f"differs from the {name} example (edited?); refusing to overwrite it", path=p)
    folder.mkdir(parents=True, exist_ok=True)
    # Every file is renamed into place only when all are written; the stack renames in reverse
    # order of entry, so the job file (entered first) is renamed last: no job without its meshes.
    with contextlib.ExitStack() as stack:
        for fname, data in reversed(files.items()):
            stack.enter_context(atomic_file(folder / fname)).write(data)
    return folder / next(reversed(files))
