"""Writing a bundled example (its job file and meshes, :mod:`rotoprint.process.examples`) into
a folder for ``rotoprint demo``: atomically, and never over what the user made."""

from __future__ import annotations

import contextlib
from pathlib import Path

from ..errors import InputFileError
from ..io.atomic import atomic_file
from ..process.examples import example_files

__all__ = ["write_example"]


# SHA-256 of the job files earlier releases wrote (every committed version of examples/*/*.toml and
# what process/examples.py wrote at each commit that changed it, since its example_files existed):
# a folder holding one of them holds our own earlier copy, replaced like the current one, so a
# changed comment in a bundled job never turns a user's earlier `rotoprint demo` folder "edited".
_EARLIER_SHA256 = frozenset({
    "5e06ad979524a15be1d3b09add05096961afb28d06068dfb1511c0b6fd1c465e",  # cad-coil.toml
    "93c878a95bf023756fd974aaaad6c6031e5ae4638e926594900445d028ea51bd",
    "beeb6b1a47fe66e44ef21c64bffd97fe56d5af2557718c00f4e9d874566ddd93",
    "35bfeb1c5eb65af2d6552941a28471818ba3c22b7d3b132f2a42ea1d32e7475e",  # coil-sensor.toml
    "90929a8eb1382a1180ec64f546ef63c4529fd921e5acc4605bdc399293d9089e",
    "0b39ded22ccf8bdbb01596d3d701277cab24def0f607d38e54f991d220fa769d",
    "86814f5d838f73d75d1c3cb0cb295a5af25e98ad93686f194fc67ab0a17dab0c",  # gas-sensor.toml
    "eef40ecbf0764936217a4af07aa6c4a437696d2431563c68d37164ae6a788db0",
})
_EARLIER_MAX_BYTES = 1 << 20  # an earlier job file is a few KiB; anything larger is not one


def _holds(p: Path, data: bytes) -> bool:
    """Whether ``p`` is a regular file holding exactly ``data``, or a job file an earlier release
    wrote (:data:`_EARLIER_SHA256`); read bounded: a FIFO or a device is never read, it just does
    not hold the example."""
    import hashlib

    from ..io.inputs import read_input_bytes

    try:
        if not p.is_file():
            return False
        size = p.stat().st_size
        if size == len(data) and read_input_bytes(p, what="example file", limit_bytes=len(data)) == data:
            return True
        if p.suffix != ".toml" or size > _EARLIER_MAX_BYTES:
            return False
        return hashlib.sha256(read_input_bytes(p, what="example file", limit_bytes=size)).hexdigest() in _EARLIER_SHA256
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
