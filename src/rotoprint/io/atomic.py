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


@contextlib.contextmanager
def atomic_dir(path: str | Path, *, owned_marker: str = MANIFEST_NAME) -> Iterator[Path]:
    """Yield a fresh temporary folder beside ``path``; on success it replaces ``path``.

    An existing ``path`` is replaced only when it is empty or holds ``owned_marker`` (an
    earlier rotoprint output); anything else is refused, so user data is never deleted.
    """
    path = Path(path)
    if path.exists():
        if not path.is_dir():
            raise InputFileError("output exists and is not a folder", path=path)
        if any(path.iterdir()) and not (path / owned_marker).exists():
            raise InputFileError(
                f"output folder is not empty and holds no {owned_marker}; refusing to replace it",
                path=path,
            )
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputFileError("parent folder of the output does not exist", path=parent)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".part", dir=parent))
    try:
        yield tmp
        _public(tmp, is_dir=True)
        if path.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".old", dir=parent))
            os.replace(path, old / "x")
            os.replace(tmp, path)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.replace(tmp, path)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
