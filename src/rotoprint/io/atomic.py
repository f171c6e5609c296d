"""Outputs that never lose a user's file and survive a kill at any point.

Every output (a folder or a file) is written through an :class:`OutputClaim`:

1. *Before any work* (:func:`check_output_path`): the path must not be the current folder or
   one holding it, must not be or hold an input, its parent folder must exist, and anything
   already there must be provably ours (:mod:`rotoprint.io.ownership`), else the run is
   refused with one line saying to use ``--force`` or another path.
2. *Lock*: ``.<name>.lock`` beside the output is created and locked (``flock``) for the whole
   run; a second run into the same output is refused ("in use"). The lock file names the
   temporaries of the run (``<name>.part``, ``<name>.old``), so after a crash the next run
   knows they were ours.
3. *Recovery*: a lock left by a killed run means its temporaries are ours: a ``<name>.old``
   (the previous output, moved aside for the final rename) is put back if the output is
   missing, else removed; a ``<name>.part`` is removed; a finished ``<name>.partial`` without
   a journal is removed. So the next run finds the old complete output or the new one.
4. *Write* into ``<name>.part`` (or ``<name>.partial``, see :mod:`rotoprint.io.resumable`),
   mark it as ours, then :meth:`OutputClaim.install`: a file is renamed onto the output; an
   existing folder is first renamed to ``<name>.old``, the new one renamed into place, and
   the old one removed (its marker last).

A failure (an exception, Ctrl-C, a full disk) removes the temporaries; a full disk becomes
one line naming the file.
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
from collections.abc import Iterable, Iterator
from pathlib import Path

from ..errors import InputFileError, ResourceError
from .ownership import MARKER_NAME, FolderLedger, folder_not_ours, mark_json, mark_png, mark_svg, path_not_ours, remove_ours, write_folder_marker

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows: O_EXCL lock files only
    fcntl = None  # type: ignore[assignment]

__all__ = ["atomic_file", "atomic_dir", "check_output_path", "OutputClaim", "write_owned_file", "kill_point", "disk_full",
           "MANIFEST_NAME", "MARKER_NAME"]

MANIFEST_NAME = "manifest.json"
LOCK_FORMAT = "rotoprint-lock"
KILL_ENV = "ROTOPRINT_TEST_KILL_AT"
FORCE_HINT = "refusing to replace it: use --force to replace it anyway, or choose another output path"


def kill_point(name: str) -> None:
    """Test hook: SIGKILL this process when ``$ROTOPRINT_TEST_KILL_AT`` equals ``name``.

    The named points are ``layer-N`` (layer N journalled), ``finish`` (a folder complete in
    ``.partial``, before it is put in place), ``install-old-moved`` (the old output renamed
    to ``.old``), ``install-new-moved`` (the new output in place, ``.old`` not yet removed),
    ``archive-N`` (N members written into an archive's ``.part``).
    """
    if os.environ.get(KILL_ENV) == name:
        import signal

        os.kill(os.getpid(), signal.SIGKILL)


def disk_full(exc: OSError, path: Path) -> ResourceError | None:
    """A one-line error naming ``path`` when ``exc`` is a full disk or quota, else None."""
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return ResourceError("no space left on the device while writing it; the partial output was removed", path=path)
    return None


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

    For files *inside* a folder being built (its ``.part`` / ``.partial``); outputs of their
    own go through :func:`write_owned_file` / :class:`OutputClaim`. On any exception the
    temporary file is removed and ``path`` is left as it was.
    """
    path = Path(path)
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise InputFileError("output folder does not exist", path=parent)
    import tempfile  # (with random: imported when used, not at a job's start)

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


def _resolved(p: Path) -> Path:
    return Path(os.path.realpath(p))


def check_output_path(out: str | Path, *, is_dir: bool, inputs: Iterable[str | Path | None] = (), force: bool = False,
                      also: Iterable[str | Path] = ()) -> None:
    """Refuse, before any work, an output that cannot work or would replace what is not ours.

    Parameters
    ----------
    out : str or Path
        The output folder or file.
    is_dir : bool
        Whether the output is a folder.
    inputs : iterable of path
        Files the run reads (None and non-existing paths are skipped): ``out`` must not be one
        of them, and a folder ``out`` must not hold one.
    force : bool
        Replace an existing output even if it is not provably ours (``--force``).
    also : iterable of path
        Further files the run writes beside ``out`` (a sidecar, swathe images): the same rules.

    Raises
    ------
    InputFileError
        The output is the current folder or holds it, is or holds an input, its parent folder
        is missing, a file is where a folder goes (or the reverse), or something there is not
        provably ours (without ``force``). The message says how to proceed.
    """
    out = Path(out)
    ro = _resolved(out)
    cwd = _resolved(Path.cwd())
    if out.name in ("", ".", "..") or ro == cwd or ro in cwd.parents:
        raise InputFileError("the output cannot be the current folder or a folder holding it; give a new name such as out/",
                             path=out)
    parent = out.parent if str(out.parent) else Path(".")
    if not parent.is_dir():
        raise InputFileError("parent folder of the output does not exist", path=parent)
    targets = [out, *(Path(a) for a in also)]
    for inp in inputs:
        if inp is None or not Path(inp).exists():
            continue
        ri = _resolved(Path(inp))
        for t in targets:
            rt = _resolved(t)
            if ri == rt:
                raise InputFileError(f"the output is the input {inp}; choose another output path", path=t)
            if rt in ri.parents:
                raise InputFileError(f"the output folder holds the input {inp}; choose another output path", path=t)
    for t, t_is_dir in [(out, is_dir), *((Path(a), False) for a in also)]:
        if not (t.exists() or t.is_symlink()):
            continue
        if t_is_dir and not t.is_dir():
            raise InputFileError("output exists and is not a folder; choose another output path", path=t)
        if not t_is_dir and t.is_dir() and not t.is_symlink():
            raise InputFileError("output is a folder, expected a file name", path=t)
        if force:
            continue
        if not t_is_dir and t.is_file() and not t.is_symlink() and t.stat().st_size == 0:
            continue  # an empty file holds nothing to lose
        reason = path_not_ours(t)
        if reason is not None:
            raise InputFileError(f"exists and is not provably a rotoprint output ({reason}); {FORCE_HINT}", path=t)


class OutputClaim:
    """The lock, the recovery and the crash-safe replace of one output (see the module doc).

    Parameters
    ----------
    out : str or Path
    is_dir : bool
    kind : str
        Recorded in the ownership marker (``cartesian-layers``, ``dlp-sl1``, ...).
    inputs, force, also
        As for :func:`check_output_path`.
    """

    def __init__(self, out: str | Path, *, is_dir: bool, kind: str, inputs: Iterable[str | Path | None] = (),
                 force: bool = False, also: Iterable[str | Path] = ()) -> None:
        self.out = Path(out)
        self.is_dir = is_dir
        self.kind = kind
        self.inputs = list(inputs)
        self.force = force
        self.also = list(also)
        parent = self.out.parent if str(self.out.parent) else Path(".")
        self.part = parent / f"{self.out.name}.part"
        self.old = parent / f"{self.out.name}.old"
        self.partial = parent / f"{self.out.name}.partial"
        self.lock_path = parent / f".{self.out.name}.lock"
        self._fd: int | None = None
        self._ledgers: contextlib.ExitStack | None = None

    # ------------------------------------------------------------ lock
    def _acquire(self) -> bool:
        """Lock; returns True when a lock file of a killed run of ours was there."""
        for _ in range(5):
            try:
                fd = os.open(self.lock_path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError as exc:
                raise InputFileError(f"cannot write in the output's folder ({exc.strerror})", path=self.lock_path.parent) from None
            try:
                if fcntl is not None:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError:
                other = self._read_lock(fd)
                os.close(fd)
                pid = f" (pid {other['pid']})" if isinstance(other, dict) and "pid" in other else ""
                raise InputFileError(f"the output is in use by another rotoprint run{pid}; wait for it to finish or choose "
                                     "another output path", path=self.out) from None
            try:
                same = os.fstat(fd).st_ino == os.stat(self.lock_path).st_ino
            except FileNotFoundError:
                same = False
            if not same:  # the lock file was removed by the run that held it: take the new one
                os.close(fd)
                continue
            prev = self._read_lock(fd)
            if prev is False:
                os.close(fd)
                raise InputFileError(f"{self.lock_path.name} exists and is not a rotoprint lock; remove it or choose another "
                                     "output path", path=self.lock_path)
            if os.fstat(fd).st_size:  # a killed run's lock: emptied first (not a new, empty one: on ext4 a
                os.ftruncate(fd, 0)  # truncated file is flushed when it is closed, ~4 ms of wall time)
            os.lseek(fd, 0, os.SEEK_SET)
            # Not fsync-ed: the lock speaks for the temporaries after a killed run, which the page
            # cache outlives; after a power cut nothing of a run is on disk for sure (neither the
            # part file nor the rename), and a lock that did not reach the disk leaves them to
            # the user ("not provably ours"), never removed. The fsync, and the journal commit
            # that freeing its block then waited for at the end, were 4-8 ms of a 10-layer job's
            # wall time on the project's VM.
            os.write(fd, json.dumps({"format": LOCK_FORMAT, "pid": os.getpid(), "out": self.out.name, "force": self.force,
                                     "temporaries": [self.part.name, self.old.name, self.partial.name]}).encode())
            self._fd = fd
            return isinstance(prev, dict)
        raise InputFileError("could not lock the output (its lock file keeps changing)", path=self.out)

    @staticmethod
    def _read_lock(fd: int) -> dict | None | bool:
        """The lock's content: a dict (ours), None (empty) or False (not ours)."""
        os.lseek(fd, 0, os.SEEK_SET)
        data = os.read(fd, 65536)
        if not data.strip():
            return None
        try:
            d = json.loads(data)
        except ValueError:
            return False
        return d if isinstance(d, dict) and d.get("format") == LOCK_FORMAT else False

    def _release(self) -> None:
        if self._fd is not None:
            with contextlib.suppress(OSError):
                self.lock_path.unlink()
            os.close(self._fd)
            self._fd = None

    # ------------------------------------------------------------ recovery
    def _remove_temp(self, p: Path, *, stale: bool) -> None:
        """Remove a temporary of ours: proven by the stale lock of a killed run, or by its marker."""
        if not (p.exists() or p.is_symlink()):
            return
        if p.is_dir() and not p.is_symlink():
            if folder_not_ours(p) is None:
                remove_ours(p)
            elif stale:
                shutil.rmtree(p)
            else:
                raise InputFileError(f"is in the way of the output and is not provably ours; remove it or choose another output path",
                                     path=p)
        elif stale:
            p.unlink()
        else:
            raise InputFileError("is in the way of the output and is not provably ours; remove it or choose another output path",
                                 path=p)

    def _recover(self, stale: bool) -> None:
        if self.old.exists() and not self.out.exists() and (stale or folder_not_ours(self.old) is None):
            os.replace(self.old, self.out)  # killed between the two renames: the old output goes back
        self._remove_temp(self.old, stale=stale)
        self._remove_temp(self.part, stale=stale)
        if self.partial.is_dir() and not (self.partial / "journal.jsonl").exists() and (
                stale or ((self.partial / MARKER_NAME).exists() and folder_not_ours(self.partial) is None)):
            shutil.rmtree(self.partial)  # a finished folder killed before its rename: remade (its journal is gone)

    # ------------------------------------------------------------ context
    def __enter__(self) -> OutputClaim:
        check_output_path(self.out, is_dir=self.is_dir, inputs=self.inputs, force=True, also=self.also)
        stale = self._acquire()
        try:
            self._recover(stale)
            check_output_path(self.out, is_dir=self.is_dir, inputs=self.inputs, force=self.force, also=self.also)
        except BaseException:
            self._release()
            raise
        if self.is_dir:  # files written into the temporaries are recorded as they are written (ownership.FolderLedger)
            self._ledgers = contextlib.ExitStack()
            self._ledgers.enter_context(FolderLedger.opened(self.part, self.partial))
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if self._ledgers is not None:
            self._ledgers.close()
            self._ledgers = None
        try:
            if exc_type is not None:
                with contextlib.suppress(OSError):
                    if self.part.is_dir() and not self.part.is_symlink():
                        shutil.rmtree(self.part)
                    elif self.part.exists():
                        self.part.unlink()
        finally:
            self._release()
        if isinstance(exc, OSError) and not isinstance(exc, ResourceError):
            full = disk_full(exc, Path(exc.filename) if exc.filename else self.out)
            if full is not None:
                raise full from None

    def install(self, src: Path | None = None) -> None:
        """Put the complete output ``src`` (default: ``self.part``) in place under ``self.out``.

        A folder gets its ownership marker first (the hashes of the files recorded while
        they were written are not computed again, see :class:`~rotoprint.io.ownership.FolderLedger`). An existing folder output is renamed to
        ``.old``, the new one renamed into place, then the old one removed (marker last); a
        kill at any point leaves either output complete at ``self.out`` (or in ``.old``, put
        back by the next run).
        """
        src = self.part if src is None else Path(src)
        if self.is_dir:
            if not (src / MARKER_NAME).exists():
                write_folder_marker(src, self.kind)
            _public(src, is_dir=True)
        else:
            _public(src, is_dir=False)
        kill_point("finish")
        if self.is_dir and self.out.exists():
            forced_not_ours = folder_not_ours(self.out) is not None
            os.replace(self.out, self.old)
            kill_point("install-old-moved")
            os.replace(src, self.out)
            kill_point("install-new-moved")
            if forced_not_ours:  # --force: the user asked for it to go
                shutil.rmtree(self.old)
            else:
                remove_ours(self.old)
        else:
            if self.out.is_symlink():  # --force onto a link: the link goes, not what it points to
                self.out.unlink()
            os.replace(src, self.out)


@contextlib.contextmanager
def atomic_dir(path: str | Path, *, kind: str = "output", inputs: Iterable[str | Path | None] = (), force: bool = False) -> Iterator[Path]:
    """Yield the fresh folder ``<path>.part``; on success it is marked ours and replaces ``path``.

    An existing ``path`` is replaced only when it is empty or provably ours (or ``force``);
    see :class:`OutputClaim`. On failure ``<path>.part`` is removed and ``path`` is untouched.
    """
    with OutputClaim(path, is_dir=True, kind=kind, inputs=inputs, force=force) as claim:
        claim.part.mkdir()
        yield claim.part
        claim.install()


def write_owned_file(path: str | Path, data: bytes, *, kind: str, inputs: Iterable[str | Path | None] = (),
                     force: bool = False, marked: bool = False) -> bytes:
    """Write ``data`` to ``path`` marked as ours (PNG: a ``tEXt`` chunk; JSON: a marker field;
    SVG: a trailing comment; other kinds unmarked, so they are replaced only with ``force``),
    through ``<path>.part`` and a rename; returns the bytes written.

    An existing ``path`` is replaced only when it is empty or provably ours (or ``force``).
    ``marked``: ``data`` carries our marker already.
    """
    path = Path(path)
    if marked:
        pass
    elif path.suffix.lower() == ".png":
        data = mark_png(data, kind)
    elif path.suffix.lower() == ".json":
        data = (json.dumps(mark_json(json.loads(data)), indent=2) + "\n").encode("utf-8")
    elif path.suffix.lower() == ".svg":
        data = mark_svg(data, kind)
    with OutputClaim(path, is_dir=False, kind=kind, inputs=inputs, force=force) as c:
        try:
            c.part.write_bytes(data)
        except OSError as exc:
            c.part.unlink(missing_ok=True)
            raise (disk_full(exc, path) or exc) from None
        c.install()
    return data
