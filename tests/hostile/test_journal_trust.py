"""Resume journals are trusted only for regular files inside their own ``.partial`` folder.

A run is stopped after a few layers (a failing record: a 'disk full' after three layers), its
journal is then edited as a hostile user could, and ``--resume`` is run:

* a record naming a file outside the folder (``../``, an absolute path, a symlink leading
  out), even with the right checksum, is a corrupt journal: exit 2, one line, no output, the
  outside file untouched;
* a record of the wrong shape (no ``files``, wrong types, index out of range) counts as a layer
  not done: the run makes it again and the output is identical to a clean run's.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import pytest

from rotoprint.errors import ResourceError
from rotoprint.examples import write_binary_stl
from rotoprint.io import resumable
from rotoprint.testing import box_triangles


@pytest.fixture
def box(tmp_path):
    write_binary_stl(tmp_path / "box.stl", box_triangles((2, 2, 1.0)))
    return tmp_path / "box.stl"


def _args(cmd: str, box: Path, out: Path) -> list:
    return [cmd, box, "-d", "perfactory-sxga", "--layer-height", "0.1", "-o", out]


def _stopped_run(run_cli, monkeypatch, cmd, box, out) -> Path:
    """A run stopped after three layers; returns its journal."""
    real = resumable.PartialOutput.record
    calls = []

    def record(self, index, files, **payload):
        if len(calls) == 3:
            raise ResourceError("disk full (simulated)")
        calls.append(index)
        return real(self, index, files, **payload)

    with monkeypatch.context() as m:
        m.setattr(resumable.PartialOutput, "record", record)
        code, _, err = run_cli(*_args(cmd, box, out))
    assert code == 2 and "disk full" in err, err
    journal = resumable.partial_path(out) / resumable.JOURNAL
    assert journal.is_file()
    return journal


def _records(journal: Path) -> tuple[str, list[dict]]:
    head, *rest = journal.read_text().splitlines()
    return head, [json.loads(x) for x in rest]


def _write(journal: Path, head: str, recs: list) -> None:
    journal.write_text("\n".join([head, *(r if isinstance(r, str) else json.dumps(r) for r in recs)]) + "\n")


def _one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


@pytest.mark.parametrize("how", ["dotdot", "absolute", "symlink"])
@pytest.mark.parametrize("cmd", ["slice", "dlp"])
def test_record_pointing_outside_its_folder_is_a_corrupt_journal(run_cli, monkeypatch, tmp_path, box, cmd, how):
    out = tmp_path / ("out" if cmd == "slice" else "out.sl1")
    journal = _stopped_run(run_cli, monkeypatch, cmd, box, out)
    head, recs = _records(journal)
    secret = tmp_path / "secret.png"
    secret.write_bytes(b"the user's own file")
    digest = hashlib.sha256(secret.read_bytes()).hexdigest()
    first = recs[0]["files"][0]
    if how == "dotdot":
        recs[0]["files"][0] = "../secret.png"
    elif how == "absolute":
        recs[0]["files"][0] = str(secret)
    else:
        link = journal.parent / first
        link.unlink()
        os.symlink(secret, link)
    recs[0]["sha256s"][0] = digest
    _write(journal, head, recs)
    code, _, err = run_cli(*_args(cmd, box, out), "--resume")
    assert code == 2
    line = _one_line(err)
    assert "corrupt resume journal" in line and str(journal) in line, line
    assert not out.exists()
    assert secret.read_bytes() == b"the user's own file"


BAD_RECORDS = {
    "no files": lambda r: {k: v for k, v in r.items() if k != "files"},
    "files a string": lambda r: {**r, "files": r["files"][0]},
    "index a string": lambda r: {**r, "index": str(r["index"])},
    "index out of range": lambda r: {**r, "index": 10**6},
    "sha256s a number": lambda r: {**r, "sha256s": 5},
    "a list": lambda r: [r],
    "nested too deep": lambda r: "[" * 100_000 + "]" * 100_000,
}


@pytest.mark.parametrize("bad", list(BAD_RECORDS))
def test_record_of_the_wrong_shape_is_a_layer_not_done(run_cli, monkeypatch, tmp_path, box, bad):
    clean = tmp_path / "clean"
    code, _, err = run_cli(*_args("slice", box, clean))
    assert code == 0, err
    out = tmp_path / "out"
    journal = _stopped_run(run_cli, monkeypatch, "slice", box, out)
    head, recs = _records(journal)
    recs[1] = BAD_RECORDS[bad](recs[1])
    _write(journal, head, recs)
    code, _, err = run_cli(*_args("slice", box, out), "--resume")
    assert code == 0, err
    assert "Traceback" not in err
    assert not resumable.partial_path(out).exists()
    names = sorted(p.name for p in clean.iterdir())
    assert sorted(p.name for p in out.iterdir()) == names
    for n in names:
        if n != "manifest.json":
            assert (out / n).read_bytes() == (clean / n).read_bytes(), n
    m_clean, m_out = json.loads((clean / "manifest.json").read_text()), json.loads((out / "manifest.json").read_text())
    assert m_out["layers"] == m_clean["layers"]


def test_journal_that_is_a_fifo_is_refused(run_cli, monkeypatch, tmp_path, box):
    out = tmp_path / "out"
    journal = _stopped_run(run_cli, monkeypatch, "slice", box, out)
    journal.unlink()
    os.mkfifo(journal)
    code, _, err = run_cli(*_args("slice", box, out), "--resume")
    assert code == 2
    line = _one_line(err)
    assert str(resumable.partial_path(out).name) in line
    assert not out.exists()
