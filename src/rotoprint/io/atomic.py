"""Atomic output: write under a temporary name beside the target, rename when complete."""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

from ..errors import InputFileError

MANIFEST_NAME = "manifest.json"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _public(path: str | Path, *, is_dir: bool) -> None:
    """mkstemp / mkdtemp create private entries; give the finished output the usual mode."""
    os.chmod(path, (0o777 if is_dir else 0o666) & ~_umask())


@contextlib.contextmanager
def atomic_file(path: str | Path, mode: str = "wb") -> Iterator:
    """Open a temporary file beside ``path``; on success rename it onto ``path``.

    On any exception the temporary file is removed and ``path`` is left as it was.
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputFileError("output folder does not exist", path=parent)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=parent)
    try:
        with os.fdopen(fd, mode) as fh:
            yield fh
        _public(tmp, is_dir=False)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def check_output_target(path: Path, *, is_dir: bool, owned_marker: str = MANIFEST_NAME) -> None:
    """Refuse an output we must not write or replace: a missing parent folder, a file where a
    folder goes (or the reverse), or a non-empty folder without ``owned_marker`` (not ours)."""
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputFileError("parent folder of the output does not exist", path=parent)
    if not path.exists():
        return
    if is_dir:
        if not path.is_dir():
            raise InputFileError("output exists and is not a folder", path=path)
        if any(path.iterdir()) and not (path / owned_marker).exists():
            raise InputFileError(f"output folder is not empty and holds no {owned_marker}; refusing to replace it", path=path)
    elif path.is_dir():
        raise InputFileError("output is a folder, expected a file name", path=path)


def replace_with(src: Path, dst: Path) -> None:
    """Rename ``src`` onto ``dst``; an existing ``dst`` is first moved into a fresh hidden
    folder beside it (never onto a name that may exist) and removed after the rename."""
    if not dst.exists():
        os.replace(src, dst)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{dst.name}.", suffix=".old", dir=dst.parent))
    os.replace(dst, old / "x")
    os.replace(src, dst)
    shutil.rmtree(old, ignore_errors=True)


@contextlib.contextmanager
def atomic_dir(path: str | Path, *, owned_marker: str = MANIFEST_NAME) -> Iterator[Path]:
    """Yield a fresh temporary folder beside ``path``; on success it replaces ``path``.

    An existing ``path`` is replaced only when it is empty or holds ``owned_marker`` (an
    earlier rotoprint output); anything else is refused, so user data is never deleted.
    """
    path = Path(path)
    check_output_target(path, is_dir=True, owned_marker=owned_marker)
    parent = path.parent if str(path.parent) else Path(".")
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".part", dir=parent))
    try:
        yield tmp
        _public(tmp, is_dir=True)
        replace_with(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
