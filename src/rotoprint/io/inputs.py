"""Reading a user's file, bounded: regular files only, a size limit checked before reading.

Every input rotoprint reads (meshes, device / job / materials TOML, sidecar JSON, journals,
designs, layer-folder manifests, archives) goes through :func:`read_input_bytes` or
:func:`read_input_text`. A FIFO, a character or block device, a socket or a directory (or a
symlink to one) is refused with one line naming the file and what it is, without opening it
for a blocking read; a file over its limit is refused before a byte of it is read, saying how
big it is and the limit. The read itself stops one byte past the limit, so a file that grows
while it is read cannot run away either.

Zip members (SL1 / SL1S / 3MF) are inflated by :func:`read_zip_members`, which refuses a member
whose declared size is over the limit and also stops inflating at the limit (a declared size
can lie).
"""

from __future__ import annotations

import io
import json
import os
import stat
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path

from .._resources import format_bytes
from ..errors import InputFileError

__all__ = [
    "MAX_MESH_BYTES",
    "MAX_TOML_BYTES",
    "MAX_JSON_BYTES",
    "MAX_JOURNAL_BYTES",
    "MAX_IMAGE_BYTES",
    "MAX_ARCHIVE_BYTES",
    "MAX_MEMBER_BYTES",
    "check_input_file",
    "read_input_bytes",
    "read_input_text",
    "read_zip_members",
    "read_json_file",
    "parse_json",
    "parse_toml",
]

#: A mesh file (binary STL: 40 million triangles).
MAX_MESH_BYTES = 2 << 30
#: A device, job or materials TOML file.
MAX_TOML_BYTES = 4 << 20
#: A sidecar JSON or a layer folder's manifest.json.
MAX_JSON_BYTES = 64 << 20
#: A resume journal (one short line per layer).
MAX_JOURNAL_BYTES = 256 << 20
#: A design or layer image file (its pixels are bounded separately, by Pillow's bomb limit).
MAX_IMAGE_BYTES = 1 << 30
#: An SL1 / SL1S / 3MF archive file, and everything its members inflate to together.
MAX_ARCHIVE_BYTES = 4 << 30
#: One member of an archive, inflated.
MAX_MEMBER_BYTES = 1 << 30


def _kind(mode: int) -> str | None:
    """What a non-regular file is, in words; None for a regular file."""
    if stat.S_ISREG(mode):
        return None
    for test, name in ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return name
    return "not a regular file"  # pragma: no cover - door, whiteout, ...


def check_input_file(path: str | Path, *, what: str, limit_bytes: int) -> int:
    """Refuse, without opening it, a path that is not a regular file within ``limit_bytes``.

    Parameters
    ----------
    path : str or Path
    what : str
        What the file should be, for the message (``"mesh file"``, ``"job .toml file"``).
    limit_bytes : int
        Largest size accepted.

    Returns
    -------
    int
        The file's size in bytes.

    Raises
    ------
    InputFileError
        Missing, unreadable, not a regular file (FIFO, device, directory, socket, also through
        a symlink), or larger than ``limit_bytes``.
    """
    p = Path(path)
    try:
        st = os.stat(p)
    except FileNotFoundError:
        raise InputFileError("no such file", path=p) from None
    except PermissionError:
        raise InputFileError("permission denied", path=p) from None
    except OSError as exc:
        raise InputFileError(f"cannot read: {exc.strerror or exc}", path=p) from None
    _refuse_special(p, st.st_mode, what)
    _refuse_size(p, st.st_size, what, limit_bytes)
    return st.st_size


def _refuse_special(p: Path, mode: int, what: str) -> None:
    kind = _kind(mode)
    if kind is not None:
        via = ""
        if p.is_symlink():
            try:
                via = f" (a symlink to {os.readlink(p)})"
            except OSError:  # pragma: no cover - raced
                via = " (a symlink)"
        raise InputFileError(f"is {kind}{via}, expected a regular {what}", path=p)


def _refuse_size(p: Path, size: int, what: str, limit_bytes: int) -> None:
    if size > limit_bytes:
        raise InputFileError(
            f"is {format_bytes(size)} ({size} bytes), more than the {format_bytes(limit_bytes)} limit for a {what}",
            path=p,
        )


def read_input_bytes(path: str | Path, *, what: str, limit_bytes: int) -> bytes:
    """The content of a regular file of at most ``limit_bytes`` (see module doc).

    Parameters
    ----------
    path : str or Path
    what : str
        What the file should be, for messages.
    limit_bytes : int

    Returns
    -------
    bytes

    Raises
    ------
    InputFileError
        See :func:`check_input_file`; also a file that grew past the limit while read.
    """
    p = Path(path)
    check_input_file(p, what=what, limit_bytes=limit_bytes)
    try:
        # O_NONBLOCK: if the path was swapped for a FIFO since the check, opening does not wait
        # for a writer; fstat below then refuses it.
        fd = os.open(p, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_CLOEXEC", 0))
    except PermissionError:
        raise InputFileError("permission denied", path=p) from None
    except OSError as exc:
        raise InputFileError(f"cannot read: {exc.strerror or exc}", path=p) from None
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fd)
        _refuse_special(p, st.st_mode, what)
        _refuse_size(p, st.st_size, what, limit_bytes)
        try:
            # read what fstat said (+1 to see growth), never a buffer of the limit's size
            parts = [fh.read(st.st_size + 1)]
            got = len(parts[0])
            while got > st.st_size and got <= limit_bytes:  # the file grew: read on, up to the limit
                more = fh.read(min(1 << 20, limit_bytes + 1 - got))
                if not more:
                    break
                parts.append(more)
                got += len(more)
        except OSError as exc:
            raise InputFileError(f"cannot read: {exc.strerror or exc}", path=p) from None
        data = parts[0] if len(parts) == 1 else b"".join(parts)
    if len(data) > limit_bytes:
        raise InputFileError(f"grew past the {format_bytes(limit_bytes)} limit for a {what} while it was read", path=p)
    return data


def read_input_text(path: str | Path, *, what: str, limit_bytes: int,
                    error: Callable[..., Exception] = InputFileError) -> str:
    """A regular file's content as UTF-8 text; ``error(message, path=...)`` if it is not UTF-8.

    Parameters
    ----------
    path : str or Path
    what : str
    limit_bytes : int
    error : exception class
        Raised (with ``path=``) when the bytes are not UTF-8; default :class:`InputFileError`.

    Returns
    -------
    str

    Raises
    ------
    InputFileError
        See :func:`read_input_bytes`.
    """
    data = read_input_bytes(path, what=what, limit_bytes=limit_bytes)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"{what} is not UTF-8 text (byte {exc.start})", path=Path(path)) from None


def parse_json(text: str | bytes, path: str | Path, *, what: str,
               error: Callable[..., Exception] = InputFileError) -> object:
    """``json.loads`` with its failures (syntax, nesting too deep for the parser) as one
    ``error(message, path=...)``."""
    if not text.strip():
        raise error(f"{what} is empty", path=Path(path))
    try:
        return json.loads(text)
    except RecursionError:
        raise error(f"{what} is nested too deeply to be read", path=Path(path)) from None
    except UnicodeDecodeError as exc:  # bytes given: the codec's text names no file
        raise error(f"{what} is not UTF-8 text (byte {exc.start})", path=Path(path)) from None
    except json.JSONDecodeError as exc:
        raise error(f"{what} is not valid JSON: {exc}", path=Path(path)) from None


def parse_toml(text: str, path: str | Path, *, what: str, error: Callable[..., Exception]) -> dict:
    """``tomllib.loads`` with its failures (syntax, nesting too deep) as one ``error(message, path=...)``."""
    import tomllib

    try:
        return tomllib.loads(text)
    except RecursionError:
        raise error(f"{what} is nested too deeply to be read", path=Path(path)) from None
    except tomllib.TOMLDecodeError as exc:
        raise error(f"not valid TOML: {exc}", path=Path(path)) from None


def read_json_file(path: str | Path, *, what: str, limit_bytes: int = MAX_JSON_BYTES,
                   error: Callable[..., Exception] = InputFileError) -> object:
    """A regular UTF-8 JSON file of at most ``limit_bytes``, parsed (see :func:`parse_json`).

    Parameters
    ----------
    path : str or Path
    what : str
        ``"sidecar"``, ``"manifest.json"``, ...
    limit_bytes : int
    error : exception class
        For content that is not UTF-8 JSON; size and file-type refusals are InputFileError.

    Returns
    -------
    object
        The parsed JSON value (the caller checks its shape).
    """
    text = read_input_text(path, what=what, limit_bytes=limit_bytes, error=error)
    return parse_json(text, path, what=what, error=error)


def read_zip_members(data: bytes, path: str | Path, *, what: str = "archive",
                     member_limit_bytes: int = MAX_MEMBER_BYTES,
                     total_limit_bytes: int = MAX_ARCHIVE_BYTES) -> dict[str, bytes]:
    """Inflate every member of a zip held in memory, each and all together within a bound.

    Parameters
    ----------
    data : bytes
        The zip file's content (read with :func:`read_input_bytes`).
    path : str or Path
        The file, for messages.
    what : str
        ``"SL1 archive"``, ``"3MF file"``, ...
    member_limit_bytes, total_limit_bytes : int
        Largest inflated size of one member and of all members.

    Returns
    -------
    dict
        Member name to its inflated bytes, in the archive's order.

    Raises
    ------
    InputFileError
        Not a zip, a corrupt member (CRC, bad compression), or a member (declared or actually
        inflated) larger than ``member_limit_bytes``, or all members together larger than
        ``total_limit_bytes``; the message names the member and its size.
    """
    p = Path(path)
    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
    except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, ValueError) as exc:
        raise InputFileError(f"not a valid {what} (not a zip archive: {exc})", path=p) from None
    out: dict[str, bytes] = {}
    total = 0
    with zf:
        infos = zf.infolist()
        declared = sum(i.file_size for i in infos)
        for info in infos:
            if info.file_size > member_limit_bytes:
                raise InputFileError(
                    f"{what} member {info.filename!r} inflates to {format_bytes(info.file_size)} "
                    f"({info.file_size} bytes), more than the {format_bytes(member_limit_bytes)} limit per member",
                    path=p,
                )
        if declared > total_limit_bytes:
            raise InputFileError(
                f"{what} members inflate to {format_bytes(declared)} together, more than the "
                f"{format_bytes(total_limit_bytes)} limit",
                path=p,
            )
        for info in infos:
            if info.is_dir():
                continue
            chunks = []
            got = 0
            try:
                with zf.open(info) as fh:
                    while True:
                        chunk = fh.read(1 << 20)
                        if not chunk:
                            break
                        got += len(chunk)
                        if got > member_limit_bytes or total + got > total_limit_bytes:
                            raise InputFileError(
                                f"{what} member {info.filename!r} inflates past {format_bytes(got)} although it "
                                f"declares {format_bytes(info.file_size)}: refused (limit "
                                f"{format_bytes(min(member_limit_bytes, total_limit_bytes))})",
                                path=p,
                            )
                        chunks.append(chunk)
            except InputFileError:
                raise
            except (zipfile.BadZipFile, zipfile.LargeZipFile, OSError, ValueError, EOFError,
                    NotImplementedError, RuntimeError, zlib.error) as exc:
                raise InputFileError(f"{what} member {info.filename!r} is corrupt: {exc}", path=p) from None
            total += got
            out[info.filename] = b"".join(chunks)
    return out
