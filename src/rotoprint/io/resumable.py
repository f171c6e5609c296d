"""Resumable outputs: work happens in ``<out>.partial`` beside the target, with a journal.

After every layer a JSON line is appended to ``<out>.partial/journal.jsonl`` naming its files
and their SHA-256. A later run of the *same* job (the journal's first line holds the job's
fingerprint) with ``resume=True`` keeps every journalled layer whose files still have their
checksums and makes only the rest; a run without ``resume`` starts afresh. The journal is
trusted only as far as it should be: it is read bounded, every file it names must be a regular
file inside the ``.partial`` folder (else the journal is refused as corrupt) and have its
checksum, and a record of the wrong shape counts as a layer not done. The finished
output is put in place under its final name only when complete, so a killed run never leaves
a half-written output there.
"""

from __future__ import annotations

import json
import logging
import os
import shutil
import weakref
from array import array
from collections.abc import Iterator, Mapping
from pathlib import Path

from .._hashing import sha256 as _sha256
from .._resources import available_memory_bytes, format_bytes
from ..errors import InputFileError, ResourceError
from .atomic import OutputClaim, disk_full, kill_point
from .inputs import MAX_IMAGE_BYTES, MAX_JOURNAL_BYTES, read_input_bytes
from .ownership import write_tracked

__all__ = ["PartialOutput", "JournalRecords", "check_resources", "partial_path"]

log = logging.getLogger(__name__)
JOURNAL = "journal.jsonl"


#: Largest layer file a resumed run re-reads to verify (a layer PNG, a mask, a swathe image).
MAX_JOURNAL_LAYER_BYTES = MAX_IMAGE_BYTES


def _well_formed(rec: object, n_layers: int) -> bool:
    """A journal record with an int ``index`` in range and equal-length lists of str
    ``files`` and hex ``sha256s``."""
    if not isinstance(rec, dict):
        return False
    i, files, sums = rec.get("index"), rec.get("files"), rec.get("sha256s")
    return (isinstance(i, int) and not isinstance(i, bool) and 0 <= i < n_layers
            and isinstance(files, list) and isinstance(sums, list) and len(files) == len(sums) and len(files) > 0
            and all(isinstance(f, str) and f for f in files)
            and all(isinstance(h, str) and len(h) == 64 for h in sums))


def partial_path(out: str | Path) -> Path:
    """The work folder of a run writing ``out``.

    Parameters
    ----------
    out : str or Path

    Returns
    -------
    Path
        ``<out>.partial`` in the folder of ``out``.
    """
    out = Path(out)
    return out.parent / f"{out.name}.partial"


def check_resources(*, n_layers: int, bytes_per_layer: float, copies_on_disk: int, per_process_bytes: int,
                    processes: int, in_flight_bytes: int, where: Path) -> dict:
    """Refuse a run, before it starts, that needs more disk or memory than the machine has.

    Parameters
    ----------
    n_layers : int
    bytes_per_layer : float
        Output bytes of one layer (e.g. the mean of sample layers).
    copies_on_disk : int
        Copies of the output the disk holds at once.
    per_process_bytes : int
        Memory of one working process.
    processes : int
    in_flight_bytes : int
        Memory of results made but not yet written.
    where : Path
        Folder whose file system must hold the output.

    Returns
    -------
    dict
        ``estimated_output_bytes`` and ``estimated_memory_bytes``, ints.

    Raises
    ------
    ResourceError
        The estimated output exceeds the free space at ``where``, or the estimated memory
        exceeds the available memory.
    """
    est_disk = int(bytes_per_layer * n_layers * 1.25 * copies_on_disk) + 64 * 1024 + 2048 * n_layers
    free = shutil.disk_usage(where).free
    if est_disk > free:
        raise ResourceError(
            f"the output would take about {format_bytes(est_disk)} ({n_layers} layers of "
            f"~{format_bytes(bytes_per_layer)}), but only {format_bytes(free)} is free",
            path=where,
        )
    est_mem = processes * per_process_bytes + in_flight_bytes
    avail = available_memory_bytes()
    if est_mem > avail:
        raise ResourceError(
            f"{processes} process(es) would need about {format_bytes(est_mem)} of memory, "
            f"{format_bytes(avail)} is available; use fewer --workers"
        )
    log.info("estimated output %s, memory %s", format_bytes(est_disk), format_bytes(est_mem))
    return {"estimated_output_bytes": est_disk, "estimated_memory_bytes": est_mem}


class JournalRecords(Mapping):
    """The journalled layers, ``index -> record``, read from the journal when asked.

    Only a table of the records' byte offsets in the journal is held (8 bytes a layer), so
    memory does not grow with the layer count; a record is read (one line) each time it is
    looked up. Iteration gives the indices in increasing order.
    """

    def __init__(self, path: Path, n_layers: int) -> None:
        self.path = path
        self._off = array("q", [-1]) * n_layers
        self._n = 0
        self._fh = None

    def put(self, index: int, offset: int) -> None:
        """The record of layer ``index`` is the line at byte ``offset`` of the journal."""
        if self._off[index] < 0:
            self._n += 1
        self._off[index] = offset

    def __getitem__(self, index: int) -> dict:
        if not (isinstance(index, int) and 0 <= index < len(self._off)) or self._off[index] < 0:
            raise KeyError(index)
        if self._fh is None:
            self._fh = open(self.path, "rb")  # noqa: SIM115 - closed by close() or with the object
            self._closer = weakref.finalize(self, self._fh.close)
        self._fh.seek(self._off[index])
        return json.loads(self._fh.readline())

    def __contains__(self, index: object) -> bool:
        return isinstance(index, int) and 0 <= index < len(self._off) and self._off[index] >= 0

    def __iter__(self) -> Iterator[int]:
        return (i for i, o in enumerate(self._off) if o >= 0)

    def __len__(self) -> int:
        return self._n

    def close(self) -> None:
        if self._fh is not None:
            self._closer()
            self._fh = None


class PartialOutput:
    """The ``<out>.partial`` folder of a run and its journal (see module doc).

    ``done`` (:class:`JournalRecords`) maps every journalled layer to its record.
    """

    def __init__(self, out: str | Path, fingerprint: str, n_layers: int, *, resume: bool) -> None:
        self.out = Path(out)
        self.dir = partial_path(self.out)
        self.fingerprint = fingerprint
        self.n_layers = n_layers
        self.done = JournalRecords(self.dir / JOURNAL, n_layers)
        self._jpos = 0
        if self.dir.exists():
            if not (self.dir / JOURNAL).is_file():
                raise InputFileError(f"{self.dir.name} exists but holds no {JOURNAL}: not a run of ours; refusing to delete it",
                                     path=self.dir)
            if resume:
                self.done = self._verified()
                log.info("resuming: %d of %d layers verified in %s", len(self.done), n_layers, self.dir)
            if not self.done:
                shutil.rmtree(self.dir)
        self._journal = None

    def _verified(self) -> JournalRecords:
        """The journalled layers whose files are intact (see the module doc for what is trusted).

        The journal is read bounded (:data:`~rotoprint.io.inputs.MAX_JOURNAL_BYTES`). A record
        whose ``index`` / ``files`` / ``sha256s`` are missing or of the wrong type is treated as
        not done (the layer is made again: nothing is lost, and nothing outside the folder is
        touched). A record naming a file outside this folder (``..``, an absolute path, a symlink
        leading out) or a file that is not a regular file is a corrupt journal: refused.
        """
        jpath = self.dir / JOURNAL
        done = JournalRecords(jpath, self.n_layers)
        if not jpath.exists():
            return done
        lines = read_input_bytes(jpath, what="resume journal", limit_bytes=MAX_JOURNAL_BYTES).split(b"\n")
        try:
            head = json.loads(lines[0].decode("utf-8", "replace"))
        except (json.JSONDecodeError, RecursionError):
            return done
        if not isinstance(head, dict) or head.get("fingerprint") != self.fingerprint:
            return done
        root = self.dir.resolve()
        pos = len(lines[0]) + 1
        for raw in lines[1:]:
            offset, pos = pos, pos + len(raw) + 1
            line = raw.decode("utf-8", "replace")
            if not line.strip():
                continue
            try:
                rec = json.loads(line)
            except (json.JSONDecodeError, RecursionError):
                break  # a line cut by the crash: everything after it is made again
            if not _well_formed(rec, self.n_layers):
                log.warning("resume journal %s: a record without a valid index, files and sha256s; its layer is made again",
                            jpath)
                continue
            ok = True
            for f, h in zip(rec["files"], rec["sha256s"], strict=True):
                fp = self.dir / f
                if Path(f).is_absolute() or not fp.resolve().is_relative_to(root) or fp.resolve() == root:
                    raise InputFileError(f"corrupt resume journal: layer {rec['index']} names {f!r}, outside its folder; "
                                         "run without --resume to start afresh", path=jpath)
                if not fp.exists():
                    ok = False
                    break
                if fp.is_symlink() or not fp.is_file():
                    raise InputFileError(f"corrupt resume journal: layer {rec['index']} file {f!r} is not a regular file; "
                                         "run without --resume to start afresh", path=jpath)
                data = read_input_bytes(fp, what="layer file", limit_bytes=MAX_JOURNAL_LAYER_BYTES)
                if _sha256(data).hexdigest() != h:
                    ok = False
                    break
            if ok:
                done.put(rec["index"], offset)
        return done

    def open(self) -> None:
        """Create the folder and the journal (appending when resuming)."""
        self.dir.mkdir(exist_ok=True)
        fresh = not self.done
        self._journal = open(self.dir / JOURNAL, "w" if fresh else "a", encoding="utf-8", newline="\n")  # noqa: SIM115
        if fresh:
            self._journal.write(json.dumps({"fingerprint": self.fingerprint, "layers": self.n_layers}) + "\n")
            self._journal.flush()
        self._jpos = os.fstat(self._journal.fileno()).st_size

    def record(self, index: int, files: dict[str, bytes], **payload) -> dict:
        """Write a layer's files, then journal them; returns the journal record."""
        rec = {"index": index, "files": list(files), "sha256s": [_sha256(d).hexdigest() for d in files.values()], **payload}
        where = self.dir / JOURNAL
        try:
            for (name, data), sha in zip(files.items(), rec["sha256s"], strict=True):
                where = self.dir / name
                write_tracked(where, data, sha256=sha)  # recorded for the output's ownership marker (not read again)
            where = self.dir / JOURNAL
            line = json.dumps(rec) + "\n"  # ASCII: its length is its size in bytes
            self._journal.write(line)
            self._journal.flush()
        except OSError as exc:
            full = disk_full(exc, where)
            if full is None:
                raise
            self.discard()
            self.done = JournalRecords(self.dir / JOURNAL, self.n_layers)
            raise full from None
        self.done.put(index, self._jpos)
        self._jpos += len(line)
        kill_point(f"layer-{index}")
        return rec

    def close(self) -> None:
        if self._journal is not None:
            self._journal.close()
            self._journal = None
        self.done.close()

    def finish_as_folder(self, claim: OutputClaim) -> None:
        """Drop the journal, mark the folder as ours and put it in place of the output
        (replacing an earlier output of ours; crash-safe, see :class:`OutputClaim`).

        Parameters
        ----------
        claim : OutputClaim
            The entered claim of ``self.out`` (its lock is held).
        """
        self.close()
        (self.dir / JOURNAL).unlink()
        claim.install(self.dir)

    def __enter__(self) -> PartialOutput:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        """Close the journal; after a failure (any exception, interrupts too) also remove the
        folder if no layer was finished (nothing to resume). The exception propagates."""
        self.close()
        if exc_type is not None:
            self.discard_if_empty()

    def discard_if_empty(self) -> None:
        """After a failure: remove the folder if no layer was finished (nothing to resume)."""
        if not self.done:
            self.discard()

    def discard(self) -> None:
        self.close()
        shutil.rmtree(self.dir, ignore_errors=True)
