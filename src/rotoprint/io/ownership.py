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

Folder markers are made and checked in bounded memory, whatever the file count: the folder's
listing, the files writers recorded and the marker's entries are spooled to anonymous
temporary files in sorted runs and merged (:class:`_Spool`), the marker is written and hashed
in one pass, and a marker of the layout we write is read line by line. A file written through
a :class:`FolderLedger` (:func:`write_tracked`, :func:`open_tracked`) is hashed while it is
written and not read again when the marker is made; any other file is hashed then.
"""

from __future__ import annotations

import contextlib
import heapq
import json
import os
import re
import struct
import threading
import zipfile
import zlib
from collections.abc import Iterable, Iterator
from itertools import islice
from pathlib import Path

from .._hashing import sha256 as _sha256

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
    "FolderLedger",
    "ledger_for",
    "write_tracked",
    "open_tracked",
]

MARKER_NAME = "rotoprint-output.json"
FORMAT = "rotoprint-output"
PNG_KEY = b"rotoprint-output"
JSON_KEY = "rotoprint_output"
_PNG_SIG = b"\x89PNG\r\n\x1a\n"
_MAX_MARKER_BYTES = 64 * 2**20  # a marker of 64 MB would list ~400,000 files
_HASH_CHUNK = 2**18
#: records a spool keeps in memory before it writes a sorted run (about 100 KB of them)
_SORT_CHUNK = 256
#: runs merged at once (one open file and its read buffer each)
_MERGE_FAN_IN = 64
#: read / write buffer of a run, bytes
_RUN_BUFFER = 2048
#: directory entries listed at once by remove_ours (about 450 bytes each)
_REMOVE_BATCH = 256


def _canonical(obj) -> bytes:
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), ensure_ascii=True).encode("ascii")


def _sha_file(path: Path) -> str:
    buf = bytearray(_HASH_CHUNK)  # one buffer, read into: memory does not follow the file's size
    view = memoryview(buf)
    with open(path, "rb", buffering=0) as fh:
        h = _sha256(expect_bytes=os.fstat(fh.fileno()).st_size)
        while n := fh.readinto(buf):
            h.update(view[:n])
    return h.hexdigest()


# ---------------------------------------------------------------- bounded sorting


def _key0(rec: list):
    return rec[0]


class _Spool:
    """Records ``[key, ...]`` (JSON lists, ``key`` a str) given back sorted by key in bounded memory.

    Up to :data:`_SORT_CHUNK` records are held; beyond that each full chunk is sorted and
    written as a run to an anonymous temporary file (gone with the process, even when it is
    killed), and iterating merges the runs (:data:`_MERGE_FAN_IN` at a time). Records with
    equal keys come back in the order they were added. Iterate once.
    """

    def __init__(self) -> None:
        self._buf: list[list] = []
        self._runs: list = []
        self.count = 0

    def add(self, rec: list) -> None:
        self._buf.append(rec)
        self.count += 1
        if len(self._buf) >= _SORT_CHUNK:
            self._spill()

    def _run_of(self, recs: Iterable[list]):
        import tempfile  # (with random: imported when a spool spills, not at a job's start)

        fh = tempfile.TemporaryFile("w+b", buffering=_RUN_BUFFER)
        try:
            for r in recs:
                fh.write(json.dumps(r).encode("ascii") + b"\n")
            fh.seek(0)
        except BaseException:
            fh.close()
            raise
        return fh

    def _spill(self) -> None:
        self._buf.sort(key=_key0)
        self._runs.append(self._run_of(self._buf))
        self._buf = []

    @staticmethod
    def _merged(runs: list) -> Iterator[list]:
        return heapq.merge(*(map(json.loads, fh) for fh in runs), key=_key0)

    def __iter__(self) -> Iterator[list]:
        if not self._runs:
            buf, self._buf = self._buf, []
            buf.sort(key=_key0)
            yield from buf
            return
        if self._buf:
            self._spill()
        while len(self._runs) > _MERGE_FAN_IN:
            runs, merged = self._runs, []
            for k in range(0, len(runs), _MERGE_FAN_IN):
                group = runs[k: k + _MERGE_FAN_IN]
                merged.append(self._run_of(self._merged(group)))
                for fh in group:
                    fh.close()
            self._runs = merged
        yield from self._merged(self._runs)

    def close(self) -> None:
        for fh in self._runs:
            fh.close()
        self._runs, self._buf = [], []

    def __enter__(self) -> _Spool:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _last_per_key(recs: Iterable[list]) -> Iterator[list]:
    """Of sorted records with equal keys, the last added."""
    prev = None
    for r in recs:
        if prev is not None and r[0] != prev[0]:
            yield prev
        prev = r
    if prev is not None:
        yield prev


def _scan(folder: Path, files: _Spool, dirs: _Spool) -> str | None:
    """Spool the relative POSIX paths of the regular files and the sub-folders under ``folder``;
    return the first (in sorted order) of the rest (symlinks, devices, unreadable folders), or None.

    Depth first with one open directory per level, so memory does not grow with the number
    of entries of a folder.
    """
    other: str | None = None

    def visit(path: str, rel: str) -> None:
        nonlocal other
        try:
            it = os.scandir(path)
        except OSError:
            if rel:
                other = rel if other is None or rel < other else other
            return
        with it:
            for e in it:
                r = f"{rel}/{e.name}" if rel else e.name
                if e.is_symlink():
                    other = r if other is None or r < other else other
                elif e.is_dir(follow_symlinks=False):
                    dirs.add([r])
                    visit(e.path, r)
                elif e.is_file(follow_symlinks=False):
                    files.add([r])
                else:
                    other = r if other is None or r < other else other

    visit(os.fspath(folder), "")
    return other


# ---------------------------------------------------------------- ledger of written files


_LEDGERS: dict[str, FolderLedger] = {}


class FolderLedger:
    """The files written into a folder being built, with sizes and SHA-256s, spooled to disk.

    :meth:`OutputClaim.install <rotoprint.io.atomic.OutputClaim.install>` takes a file's
    hash from the ledger when the file is still the one recorded (same size, modification
    time and inode), and hashes it again otherwise. Use :func:`ledger_for` to find the
    ledger of a folder (None when nothing records for it).

    Parameters
    ----------
    root : str or Path
        The folder (a ``.part`` / ``.partial`` of an output).
    """

    def __init__(self, root: str | Path) -> None:
        self.root = os.path.abspath(root)
        self._spool = _Spool()
        self._lock = threading.Lock()  # writers in several threads may record at once

    def rel(self, path: str | Path) -> str:
        return Path(os.path.relpath(os.path.abspath(path), self.root)).as_posix()

    def record(self, path: str | Path, sha256: str) -> None:
        """Record ``path`` (a file under the root, just written, with content hash ``sha256``)."""
        st = os.stat(path, follow_symlinks=False)
        with self._lock:
            self._spool.add([self.rel(path), st.st_size, st.st_mtime_ns, st.st_ino, sha256])

    def entries(self) -> Iterator[list]:
        """``[rel, size, mtime_ns, inode, sha256]`` sorted by path, the last record of a path."""
        return _last_per_key(self._spool)

    def close(self) -> None:
        self._spool.close()
        if _LEDGERS.get(self.root) is self:
            del _LEDGERS[self.root]

    @classmethod
    @contextlib.contextmanager
    def opened(cls, *roots: str | Path) -> Iterator[list[FolderLedger]]:
        """Register a ledger for each of ``roots`` while the block runs."""
        leds = [cls(r) for r in roots]
        for led in leds:
            _LEDGERS[led.root] = led
        try:
            yield leds
        finally:
            for led in leds:
                led.close()


def ledger_for(path: str | Path) -> FolderLedger | None:
    """The ledger recording the folder that holds ``path`` (or is it), or None."""
    if not _LEDGERS:
        return None
    p = os.path.abspath(path)
    while True:
        led = _LEDGERS.get(p)
        if led is not None:
            return led
        up = os.path.dirname(p)
        if up == p:
            return None
        p = up


def write_tracked(path: str | Path, data: bytes, *, sha256: str | None = None) -> str:
    """Write ``data`` to ``path``, record it in its folder's ledger (if any); returns its SHA-256
    (``sha256``: the caller's, already computed from ``data``)."""
    Path(path).write_bytes(data)
    sha = _sha256(data).hexdigest() if sha256 is None else sha256
    led = ledger_for(path)
    if led is not None:
        led.record(path, sha)
    return sha


class _TrackedFile:
    """A file open for writing that hashes what it is given; closing records it in the ledger."""

    def __init__(self, path: str | Path, text: bool) -> None:
        self.path = Path(path)
        self._text = text
        self._h = _sha256()
        self._fh = open(self.path, "wb")  # noqa: SIM115 - closed by close()

    def write(self, data) -> int:
        b = data.encode("utf-8") if self._text else data
        self._h.update(b)
        self._fh.write(b)
        return len(data)

    @property
    def closed(self) -> bool:
        return self._fh.closed

    def hexdigest(self) -> str:
        return self._h.hexdigest()

    def close(self) -> None:
        if self._fh.closed:
            return
        self._fh.close()
        led = ledger_for(self.path)
        if led is not None:
            led.record(self.path, self._h.hexdigest())

    def __enter__(self) -> _TrackedFile:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def open_tracked(path: str | Path, *, text: bool = True) -> _TrackedFile:
    """Open ``path`` for writing (``text``: str in, UTF-8 out, no newline translation), hashed
    as it is written and recorded in its folder's ledger when closed."""
    return _TrackedFile(path, text)


# ---------------------------------------------------------------- folder marker


def _entry_json(name: str, size: int, sha: str) -> tuple[str, str]:
    """One file's entry: (canonical text, the lines of the written layout without the last comma)."""
    n, s = json.dumps(name), json.dumps(sha)
    return (f'{n}:{{"sha256":{s},"size":{size}}}',
            f'  {n}: {{\n   "sha256": {s},\n   "size": {size}\n  }}')


def _folder_entries(folder: Path, files: _Spool, ledger: FolderLedger | None) -> Iterator[tuple[str, int, str]]:
    """(name, size, sha256) of every file (sorted), the hash from the ledger where it still holds."""
    known = ledger.entries() if ledger is not None else iter(())
    nxt = next(known, None)
    for (rel,) in files:
        if rel == MARKER_NAME:
            continue
        while nxt is not None and nxt[0] < rel:
            nxt = next(known, None)
        p = folder / rel
        st = os.stat(p, follow_symlinks=False)
        if nxt is not None and nxt[0] == rel and nxt[1:4] == [st.st_size, st.st_mtime_ns, st.st_ino]:
            sha = nxt[4]
        else:
            sha = _sha_file(p)
        yield rel, st.st_size, sha


def write_folder_marker(folder: str | Path, kind: str, *, ledger: FolderLedger | None = None) -> dict:
    """List every file and sub-folder of ``folder`` in its ``rotoprint-output.json``.

    The marker is the same, byte for byte, as ``json.dumps(marker, indent=1, sort_keys=True)``
    of the whole listing, but it is written and hashed in one pass over the sorted listing,
    in bounded memory.

    Parameters
    ----------
    folder : str or Path
        A complete output of ours (written last, when nothing else will be added).
    kind : str
        What the folder is (``cartesian-layers``, ``check-report``, ...).
    ledger : FolderLedger, optional
        The files recorded as they were written (default: the ledger of ``folder``, if any);
        their hashes are taken from it, the other files are read.

    Returns
    -------
    dict
        ``format, version, kind, sha256`` of the marker written and its ``files`` and
        ``folders`` counts.
    """
    folder = Path(folder)
    ledger = ledger if ledger is not None else _LEDGERS.get(os.path.abspath(folder))
    canon = _sha256()
    target = folder / MARKER_NAME
    with _Spool() as files, _Spool() as dirs:
        _scan(folder, files, dirs)  # before the marker is opened (it is not listed)
        with open(target, "w", encoding="ascii", newline="\n") as fh:
            sha, n_files, n_dirs = _write_marker(fh, canon, folder, files, dirs, kind, ledger)
    return {"format": FORMAT, "version": 1, "kind": kind, "sha256": sha, "files": n_files, "folders": n_dirs}


def _write_marker(fh, canon, folder: Path, files: _Spool, dirs: _Spool, kind: str, ledger: FolderLedger | None) -> tuple[str, int, int]:
    """Write the marker to ``fh`` and hash its canonical content with ``canon``, in one pass."""
    n_files = n_dirs = 0
    canon.update(b'{"files":{')
    fh.write('{\n "files": {')
    for name, size, sha in _folder_entries(folder, files, ledger):
        c, text = _entry_json(name, size, sha)
        canon.update((("," if n_files else "") + c).encode("ascii"))
        fh.write(("," if n_files else "") + "\n" + text)
        n_files += 1
    fh.write("\n }" if n_files else "}")
    canon.update(b'},"folders":[')
    fh.write(',\n "folders": [')
    for (d,) in dirs:
        j = json.dumps(d)
        canon.update((("," if n_dirs else "") + j).encode("ascii"))
        fh.write(("," if n_dirs else "") + "\n  " + j)
        n_dirs += 1
    fh.write("\n ]" if n_dirs else "]")
    k = json.dumps(kind)
    canon.update(f'],"format":"{FORMAT}","kind":{k},"version":1}}'.encode("ascii"))
    sha = canon.hexdigest()
    fh.write(f',\n "format": "{FORMAT}",\n "kind": {k},\n "sha256": "{sha}",\n "version": 1\n}}\n')
    return sha, n_files, n_dirs


class _NotLayout(Exception):
    """The marker is not in the layout :func:`write_folder_marker` writes (read it whole)."""


_DEC = json.JSONDecoder()
_INT = re.compile(r"-?(?:0|[1-9][0-9]*)\Z")


def _jstr(line: str, start: int) -> tuple[str, int]:
    if line[start: start + 1] != '"':
        raise _NotLayout
    try:
        s, end = _DEC.raw_decode(line, start)
    except ValueError:
        raise _NotLayout from None
    if not isinstance(s, str):
        raise _NotLayout
    return s, end


def _jint(text: str) -> int:
    if not _INT.match(text) or len(text) > 30:  # no size or version of ours has 30 digits (and int() stops at 4300)
        raise _NotLayout
    return int(text)


def _layout(path: Path) -> Iterator[tuple]:
    """The marker at ``path`` read line by line: ``("file", name, size, sha256)``, ``("dir",
    name)`` in file order, then ``("end", kind, version, sha256)``. Raises :class:`_NotLayout`
    for anything else than the layout we write (names strictly increasing)."""
    with open(path, "rb") as fb:
        def line() -> str:
            b = fb.readline()
            if not b.endswith(b"\n"):
                raise _NotLayout
            try:
                return b[:-1].decode("utf-8")
            except UnicodeDecodeError:
                raise _NotLayout from None

        def expect(text: str) -> None:
            if line() != text:
                raise _NotLayout

        expect("{")
        first = line()
        if first == ' "files": {':
            prev = None
            while True:
                ln = line()
                if ln == " },":
                    if prev is None:
                        raise _NotLayout
                    break
                name, end = _jstr(ln, 2)
                if not ln.startswith("  ") or ln[end:] != ": {" or (prev is not None and name <= prev):
                    raise _NotLayout
                ln = line()
                if not ln.startswith('   "sha256": ') or not ln.endswith(","):
                    raise _NotLayout
                sha, end = _jstr(ln, 13)
                if end != len(ln) - 1:
                    raise _NotLayout
                ln = line()
                if not ln.startswith('   "size": '):
                    raise _NotLayout
                size = _jint(ln[11:])
                ln = line()
                if ln not in ("  },", "  }"):
                    raise _NotLayout
                yield ("file", name, size, sha)
                prev = name
                if ln == "  }":
                    expect(" },")
                    break
        elif first != ' "files": {},':
            raise _NotLayout
        first = line()
        if first == ' "folders": [':
            prev = None
            while True:
                ln = line()
                name, end = _jstr(ln, 2)
                if not ln.startswith("  ") or ln[end:] not in (",", "") or (prev is not None and name <= prev):
                    raise _NotLayout
                yield ("dir", name)
                prev = name
                if ln[end:] == "":
                    expect(" ],")
                    break
        elif first != ' "folders": [],':
            raise _NotLayout
        expect(f' "format": "{FORMAT}",')
        ln = line()
        if not ln.startswith(' "kind": '):
            raise _NotLayout
        kind, end = _jstr(ln, 9)
        if ln[end:] != ",":
            raise _NotLayout
        ln = line()
        if not ln.startswith(' "sha256": '):
            raise _NotLayout
        sha, end = _jstr(ln, 11)
        if ln[end:] != ",":
            raise _NotLayout
        ln = line()
        if not ln.startswith(' "version": '):
            raise _NotLayout
        version = _jint(ln[12:])
        expect("}")
        if fb.read(1):
            raise _NotLayout
        yield ("end", kind, version, sha)


class _Marker:
    """A folder's marker, checked: its files and folders given back sorted, streamed from the
    file (our layout) or from the whole marker read (any other JSON form of it)."""

    def __init__(self, path: Path, whole: dict | None) -> None:
        self.path = path
        self.whole = whole

    @classmethod
    def read(cls, folder: Path) -> _Marker | str:
        mp = folder / MARKER_NAME
        if not mp.is_file() or mp.is_symlink():
            return f"it holds no {MARKER_NAME} of ours"
        if mp.stat().st_size > _MAX_MARKER_BYTES:
            return f"its {MARKER_NAME} is too large to be ours"
        invalid = f"its {MARKER_NAME} is not a valid rotoprint marker"
        try:
            canon = _sha256(b'{"files":{')
            n_files = n_dirs = 0
            for ev in _layout(mp):
                if ev[0] == "file":
                    c, _ = _entry_json(ev[1], ev[2], ev[3])
                    canon.update((("," if n_files else "") + c).encode("ascii"))
                    n_files += 1
                elif ev[0] == "dir":
                    if n_dirs == 0:
                        canon.update(b'},"folders":[')
                    canon.update((("," if n_dirs else "") + json.dumps(ev[1])).encode("ascii"))
                    n_dirs += 1
                else:
                    if n_dirs == 0:
                        canon.update(b'},"folders":[')
                    _, kind, version, sha = ev
                    canon.update(f'],"format":"{FORMAT}","kind":{json.dumps(kind)},"version":{version}}}'.encode("ascii"))
            return cls(mp, None) if canon.hexdigest() == sha else invalid
        except _NotLayout:
            pass
        except OSError:
            return invalid
        try:  # another JSON form of a marker (read whole, at most _MAX_MARKER_BYTES)
            marker = json.loads(mp.read_bytes())
            body = {k: v for k, v in marker.items() if k != "sha256"}
            ok = (marker.get("format") == FORMAT and isinstance(marker.get("files"), dict) and isinstance(marker.get("folders"), list)
                  and marker.get("sha256") == _sha256(_canonical(body)).hexdigest())
        except (ValueError, AttributeError, TypeError, RecursionError):
            ok = False
        return cls(mp, marker) if ok else invalid

    def files(self) -> Iterator[tuple[str, object]]:
        """(name, entry) sorted by name; an entry of our layout is ``{"size", "sha256"}``."""
        if self.whole is not None:
            yield from sorted(self.whole["files"].items())
            return
        for ev in _layout(self.path):
            if ev[0] == "file":
                yield ev[1], {"size": ev[2], "sha256": ev[3]}
            elif ev[0] == "dir":
                return

    def folders(self) -> Iterator[str]:
        """The listed sub-folders, sorted, each once."""
        if self.whole is not None:
            yield from sorted({d for d in self.whole["folders"] if isinstance(d, str)})
            return
        for ev in _layout(self.path):
            if ev[0] == "dir":
                yield ev[1]


def folder_not_ours(folder: str | Path, *, complete: bool = False) -> str | None:
    """Why ``folder`` is not provably ours, or None when it is (see the module doc).

    Memory does not grow with the file count for a marker of the layout we write (the
    folder's listing and the marker are merged in sorted order).

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
    with _Spool() as files, _Spool() as dirs:
        other = _scan(folder, files, dirs)
        if not files.count and other is None:
            return None  # empty, or empty sub-folders only: there is nothing to lose
        marker = _Marker.read(folder)
        if isinstance(marker, str):
            return marker
        if other is not None:
            return f"it holds {other}, which rotoprint did not write"
        listed_dirs = marker.folders()
        nxt = next(listed_dirs, None)
        for (d,) in dirs:
            while nxt is not None and nxt < d:
                nxt = next(listed_dirs, None)
            if nxt != d:
                return f"it holds the folder {d}, which rotoprint did not write"
        listed = marker.files()
        nxt = next(listed, None)
        missing = False
        for (f,) in files:
            if f == MARKER_NAME:
                continue
            while nxt is not None and nxt[0] < f:
                missing = missing or nxt[0] != MARKER_NAME
                nxt = next(listed, None)
            if nxt is None or nxt[0] != f or not isinstance(nxt[1], dict):
                return f"it holds {f}, which rotoprint did not write"
            ent = nxt[1]
            p = folder / f
            if p.stat().st_size != ent.get("size") or _sha_file(p) != ent.get("sha256"):
                return f"{f} was changed since rotoprint wrote it"
            nxt = next(listed, None)
        while nxt is not None and not missing:
            missing = nxt[0] != MARKER_NAME
            nxt = next(listed, None)
        if complete and missing:
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
    h = _sha256(expect_bytes=len(data))
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
    return _sha256(_canonical([[i.filename, i.CRC, i.file_size] for i in zf.infolist()])).hexdigest()


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
    return {**body, JSON_KEY: {"format": FORMAT, "sha256": _sha256(_canonical(body)).hexdigest()}}


def _json_not_ours(path: Path) -> str | None:
    if path.stat().st_size > _MAX_MARKER_BYTES:
        return "it is too large to be ours"
    try:
        obj = json.loads(path.read_bytes())
        body = {k: v for k, v in obj.items() if k != JSON_KEY}
        m = obj.get(JSON_KEY)
        if isinstance(m, dict) and m.get("format") == FORMAT and m.get("sha256") == _sha256(_canonical(body)).hexdigest():
            return None
    except (ValueError, AttributeError, TypeError, RecursionError):
        pass
    return "it carries no rotoprint marker (or was changed)"


_SVG_TAG = b"<!-- rotoprint-output "


def mark_svg(data: bytes, kind: str) -> bytes:
    """``data`` (an SVG document) followed by a comment marker of ours."""
    text = _canonical({"format": FORMAT, "kind": kind, "sha256": _sha256(data).hexdigest()})
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
    if isinstance(m, dict) and m.get("format") == FORMAT and m.get("sha256") == _sha256(data[:i]).hexdigest():
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


def _remove_tree_ours(path: str, top: bool) -> None:
    """Remove the files and sub-folders under ``path`` (not the top's marker) in batches, so
    memory does not grow with the entries of a folder; sub-folders once emptied."""
    while True:
        with os.scandir(path) as it:
            batch = list(islice(it, _REMOVE_BATCH))
        batch = [e for e in batch if not (top and e.name == MARKER_NAME)]
        if not batch:
            return
        for e in batch:
            if e.is_dir(follow_symlinks=False):
                _remove_tree_ours(e.path, False)
                os.rmdir(e.path)
            else:
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(e.path)


def remove_ours(path: str | Path) -> None:
    """Remove a file, or a folder of ours: its files and emptied sub-folders first, the marker
    last, then the folder, so a removal cut short still leaves a folder that is provably ours
    (what is left is listed, and the marker is there while any file is)."""
    path = Path(path)
    if path.is_symlink() or not path.is_dir():
        path.unlink(missing_ok=True)
        return
    _remove_tree_ours(os.fspath(path), True)
    (path / MARKER_NAME).unlink(missing_ok=True)
    os.rmdir(path)
