"""Proof that an output on disk is ours: a signed marker listing what rotoprint wrote.

rotoprint replaces or deletes a path only when it can prove it wrote everything there:

* a **folder** holds ``rotoprint-output.json`` (format ``rotoprint-output``) listing every
  file it wrote with its size and SHA-256, every sub-folder, and the SHA-256 of the marker's
  own canonical content (so an edited or copied-in marker does not count). The folder is ours
  when the marker checks and every file in it is listed with its size and hash (files may be
  missing: a half-removed output of ours is still ours; an extra or changed file is not);
* a **PNG** carries a ``tEXt`` chunk ``rotoprint-output`` with the SHA-256 of its image data;
* an **SL1 / SL1S archive** (a zip) carries the marker in its archive comment, with the
  SHA-256 of its member list (names, CRC-32s and sizes from the central directory);
* an **SVG** ends in a comment ``<!-- rotoprint-output {...} -->`` with the SHA-256 of the
  bytes before it;
* a **JSON** file we wrote holds a ``rotoprint_output`` object with the SHA-256 of the rest
  of its content.

The check functions return ``None`` when the path is ours, else a short reason naming the
first file that is not (for the one-line error the caller raises).
"""

from __future__ import annotations

import hashlib
import json
import os
import struct
import zipfile
import zlib
from pathlib import Path

__all__ = [
    "MARKER_NAME",
    "FORMAT",
    "write_folder_marker",
    "folder_not_ours",
    "file_not_ours",
    "path_not_ours",
    "mark_png",
    "zip_marker",
    "mark_json",
    "mark_svg",
    "remove_ours",
]

MARKER_NAME = "rotoprint-output.json"
FORMAT = "rotoprint-output"
PNG_KEY = b"rotoprint-output"
JSON_KEY = "rotoprint_output"
_PNG_SIG = b"\x89PNG\r\n\x1a\n"
_MAX_MARKER_BYTES = 64 * 2**20  # a marker of 64 MB would list ~400,000 files
_HASH_CHUNK = 2**20


def _canonical(obj) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode("ascii")


def _sha_file(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        while chunk := fh.read(_HASH_CHUNK):
            h.update(chunk)
    return h.hexdigest()


def _walk(folder: Path) -> tuple[list[str], list[str], list[str]]:
    """Relative POSIX paths under ``folder``: (files, folders, others such as symlinks)."""
    files, dirs, other = [], [], []
    for root, dnames, fnames in os.walk(folder, followlinks=False):
        rel_root = Path(root).relative_to(folder)
        for d in list(dnames):
            p = Path(root) / d
            rel = (rel_root / d).as_posix()
            if p.is_symlink():
                other.append(rel)
                dnames.remove(d)
            else:
                dirs.append(rel)
        for f in fnames:
            p = Path(root) / f
            rel = (rel_root / f).as_posix()
            (files if (p.is_file() and not p.is_symlink()) else other).append(rel)
    return sorted(files), sorted(dirs), sorted(other)


def write_folder_marker(folder: str | Path, kind: str) -> dict:
    """List every file and sub-folder of ``folder`` in its ``rotoprint-output.json``.

    Parameters
    ----------
    folder : str or Path
        A complete output of ours (written last, when nothing else will be added).
    kind : str
        What the folder is (``cartesian-layers``, ``check-report``, ...).

    Returns
    -------
    dict
        The marker as written.
    """
    folder = Path(folder)
    files, dirs, _ = _walk(folder)
    entries = {f: {"size": (folder / f).stat().st_size, "sha256": _sha_file(folder / f)} for f in files if f != MARKER_NAME}
    body = {"format": FORMAT, "version": 1, "kind": kind, "files": entries, "folders": dirs}
    marker = {**body, "sha256": hashlib.sha256(_canonical(body)).hexdigest()}
    (folder / MARKER_NAME).write_text(json.dumps(marker, indent=1, sort_keys=True) + "\n", encoding="utf-8")
    return marker


def _read_marker(folder: Path) -> dict | str:
    mp = folder / MARKER_NAME
    if not mp.is_file() or mp.is_symlink():
        return f"it holds no {MARKER_NAME} of ours"
    if mp.stat().st_size > _MAX_MARKER_BYTES:
        return f"its {MARKER_NAME} is too large to be ours"
    try:
        marker = json.loads(mp.read_bytes())
        body = {k: v for k, v in marker.items() if k != "sha256"}
        ok = (marker.get("format") == FORMAT and isinstance(marker.get("files"), dict) and isinstance(marker.get("folders"), list)
              and marker.get("sha256") == hashlib.sha256(_canonical(body)).hexdigest())
    except (ValueError, AttributeError, TypeError, RecursionError):
        ok = False
    return marker if ok else f"its {MARKER_NAME} is not a valid rotoprint marker"


def folder_not_ours(folder: str | Path, *, complete: bool = False) -> str | None:
    """Why ``folder`` is not provably ours, or None when it is (see the module doc).

    Parameters
    ----------
    folder : str or Path
    complete : bool
        Also require every listed file to be present (a finished output, not a half-removed one).

    Returns
    -------
    str or None
    """
    folder = Path(folder)
    files, dirs, other = _walk(folder)
    if not files and not other:
        return None  # empty, or empty sub-folders only: there is nothing to lose
    marker = _read_marker(folder)
    if isinstance(marker, str):
        return marker
    listed, listed_dirs = marker["files"], set(marker["folders"])
    if other:
        return f"it holds {other[0]}, which rotoprint did not write"
    for d in dirs:
        if d not in listed_dirs:
            return f"it holds the folder {d}, which rotoprint did not write"
    for f in files:
        if f == MARKER_NAME:
            continue
        ent = listed.get(f)
        if not isinstance(ent, dict):
            return f"it holds {f}, which rotoprint did not write"
        p = folder / f
        if p.stat().st_size != ent.get("size") or _sha_file(p) != ent.get("sha256"):
            return f"{f} was changed since rotoprint wrote it"
    if complete and any(not (folder / f).is_file() for f in listed):
        return "some files rotoprint wrote there are missing"
    return None


# ---------------------------------------------------------------- PNG


def _png_chunks(data: bytes):
    pos = len(_PNG_SIG)
    while pos + 12 <= len(data):
        (n,) = struct.unpack(">I", data[pos : pos + 4])
        ctype = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + n]
        if len(body) != n:
            return
        yield pos, ctype, body
        pos += 12 + n
        if ctype == b"IEND":
            return


def _idat_sha(data: bytes) -> str:
    h = hashlib.sha256()
    for _, ctype, body in _png_chunks(data):
        if ctype == b"IDAT":
            h.update(body)
    return h.hexdigest()


def mark_png(data: bytes, kind: str) -> bytes:
    """``data`` (a PNG) with a ``tEXt`` marker of ours before its ``IEND`` chunk."""
    if not data.startswith(_PNG_SIG):
        raise ValueError("not a PNG")
    text = _canonical({"format": FORMAT, "kind": kind, "idat_sha256": _idat_sha(data)})
    body = PNG_KEY + b"\x00" + text
    chunk = struct.pack(">I", len(body)) + b"tEXt" + body + struct.pack(">I", zlib.crc32(b"tEXt" + body) & 0xFFFFFFFF)
    iend = data.rfind(b"IEND") - 4
    return data[:iend] + chunk + data[iend:]


def _png_not_ours(path: Path) -> str | None:
    if path.stat().st_size > 2**31:
        return "it is too large to check"
    data = path.read_bytes()
    if not data.startswith(_PNG_SIG):
        return "it is not a PNG rotoprint wrote"
    for _, ctype, body in _png_chunks(data):
        if ctype == b"tEXt" and body.startswith(PNG_KEY + b"\x00"):
            try:
                m = json.loads(body[len(PNG_KEY) + 1 :])
            except ValueError:
                break
            if isinstance(m, dict) and m.get("format") == FORMAT and m.get("idat_sha256") == _idat_sha(data):
                return None
            return "its rotoprint marker does not match its image (the file was changed)"
    return "it carries no rotoprint marker"


# ---------------------------------------------------------------- zip (SL1 / SL1S)


def _members_sha(zf: zipfile.ZipFile) -> str:
    return hashlib.sha256(_canonical([[i.filename, i.CRC, i.file_size] for i in zf.infolist()])).hexdigest()


def zip_marker(zf: zipfile.ZipFile, kind: str) -> None:
    """Set the archive comment of ``zf`` (open for writing, every member written) to our marker."""
    zf.comment = _canonical({"format": FORMAT, "kind": kind, "members_sha256": _members_sha(zf)})


def _zip_not_ours(path: Path) -> str | None:
    try:
        with zipfile.ZipFile(path) as zf:
            m = json.loads(zf.comment or b"null")
            if isinstance(m, dict) and m.get("format") == FORMAT and m.get("members_sha256") == _members_sha(zf):
                return None
    except (zipfile.BadZipFile, ValueError, OSError):
        return "it is not an archive rotoprint wrote"
    return "it carries no rotoprint marker (or was changed)"


# ---------------------------------------------------------------- JSON


def mark_json(obj: dict) -> dict:
    """``obj`` with a ``rotoprint_output`` marker: the SHA-256 of the rest of its content."""
    body = {k: v for k, v in obj.items() if k != JSON_KEY}
    return {**body, JSON_KEY: {"format": FORMAT, "sha256": hashlib.sha256(_canonical(body)).hexdigest()}}


def _json_not_ours(path: Path) -> str | None:
    if path.stat().st_size > _MAX_MARKER_BYTES:
        return "it is too large to be ours"
    try:
        obj = json.loads(path.read_bytes())
        body = {k: v for k, v in obj.items() if k != JSON_KEY}
        m = obj.get(JSON_KEY)
        if isinstance(m, dict) and m.get("format") == FORMAT and m.get("sha256") == hashlib.sha256(_canonical(body)).hexdigest():
            return None
    except (ValueError, AttributeError, TypeError, RecursionError):
        pass
    return "it carries no rotoprint marker (or was changed)"


_SVG_TAG = b"<!-- rotoprint-output "


def mark_svg(data: bytes, kind: str) -> bytes:
    """``data`` (an SVG document) followed by a comment marker of ours."""
    text = _canonical({"format": FORMAT, "kind": kind, "sha256": hashlib.sha256(data).hexdigest()})
    return data + _SVG_TAG + text + b" -->\n"


def _svg_not_ours(path: Path) -> str | None:
    if path.stat().st_size > 2**31:
        return "it is too large to check"
    data = path.read_bytes()
    i = data.rfind(_SVG_TAG)
    if i < 0 or not data.endswith(b" -->\n"):
        return "it carries no rotoprint marker"
    try:
        m = json.loads(data[i + len(_SVG_TAG) : -len(b" -->\n")])
    except ValueError:
        return "it carries no rotoprint marker"
    if isinstance(m, dict) and m.get("format") == FORMAT and m.get("sha256") == hashlib.sha256(data[:i]).hexdigest():
        return None
    return "its rotoprint marker does not match its content (the file was changed)"


def file_not_ours(path: str | Path) -> str | None:
    """Why the file ``path`` is not provably ours (PNG, SL1/SL1S, JSON), or None when it is."""
    path = Path(path)
    if path.is_symlink() or not path.is_file():
        return "it is not a regular file"
    suffix = path.suffix.lower()
    if suffix == ".png":
        return _png_not_ours(path)
    if suffix in (".sl1", ".sl1s", ".zip"):
        return _zip_not_ours(path)
    if suffix == ".json":
        return _json_not_ours(path)
    if suffix == ".svg":
        return _svg_not_ours(path)
    return "rotoprint marks no file of this kind"


def path_not_ours(path: str | Path) -> str | None:
    """:func:`folder_not_ours` or :func:`file_not_ours`, by what ``path`` is."""
    path = Path(path)
    if path.is_dir() and not path.is_symlink():
        return folder_not_ours(path)
    return file_not_ours(path)


def remove_ours(path: str | Path) -> None:
    """Remove a file, or a folder of ours: its listed files first, the marker last, then the
    emptied folders, so a removal cut short still leaves a folder that is provably ours."""
    path = Path(path)
    if path.is_symlink() or not path.is_dir():
        path.unlink(missing_ok=True)
        return
    files, dirs, other = _walk(path)
    for f in [*other, *(f for f in files if f != MARKER_NAME)]:
        (path / f).unlink(missing_ok=True)
    (path / MARKER_NAME).unlink(missing_ok=True)
    for d in sorted(dirs, key=lambda s: -s.count("/")):
        os.rmdir(path / d)
    os.rmdir(path)
