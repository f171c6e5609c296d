"""Folder markers made and checked in bounded memory: the same bytes as the whole marker
dumped at once, our layout read line by line, other JSON forms of a marker still read whole,
files recorded while written not read again, and a spool that holds a bounded number of
records whatever it is given."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from rotoprint.io import ownership as own
from rotoprint.io.atomic import OutputClaim
from rotoprint.io.ownership import MARKER_NAME, FolderLedger, folder_not_ours, remove_ours, write_folder_marker, write_tracked

ODD = ["a.png", "a-c", "a.b", "a!", "é ü", 'q"x', "line\nbreak", "z", "sub/b.txt", "sub/rotoprint-output.json",
       "sub/deeper/c", "sub-x/d", "sub.e"]


@pytest.fixture
def small_chunks(monkeypatch):
    """Spill a run every 3 records and merge 2 at a time: every path of the spool is taken."""
    monkeypatch.setattr(own, "_SORT_CHUNK", 3)
    monkeypatch.setattr(own, "_MERGE_FAN_IN", 2)


def _folder(root, names, extra_dirs=("empty", "empty/deeper")):
    d = root / "o"
    d.mkdir()
    for n in names:
        (d / n).parent.mkdir(parents=True, exist_ok=True)
        (d / n).write_bytes(n.encode("utf-8") * 3)
    for e in extra_dirs:
        (d / e).mkdir(parents=True, exist_ok=True)
    return d


def _whole_marker(d, kind):
    """The marker as json.dumps of the whole listing (what rotoprint wrote before streaming)."""
    import hashlib

    files, dirs = {}, []
    for root, dn, fn in os.walk(d):
        for x in dn:
            dirs.append(os.path.relpath(os.path.join(root, x), d).replace(os.sep, "/"))
        for x in fn:
            rel = os.path.relpath(os.path.join(root, x), d).replace(os.sep, "/")
            if rel != MARKER_NAME:
                data = Path(root, x).read_bytes()
                files[rel] = {"size": len(data), "sha256": hashlib.sha256(data).hexdigest()}
    body = {"format": own.FORMAT, "version": 1, "kind": kind, "files": files, "folders": sorted(dirs)}
    marker = {**body, "sha256": hashlib.sha256(own._canonical(body)).hexdigest()}
    return (json.dumps(marker, indent=1, sort_keys=True) + "\n").encode("utf-8")


@pytest.mark.parametrize("names", [[], ["only"], ODD, [f"many/f{(k * 37) % 41:02d}" for k in range(41)]])
def test_the_streamed_marker_has_the_bytes_of_the_whole_one(tmp_path, small_chunks, names):
    d = _folder(tmp_path, names)
    summary = write_folder_marker(d, "test")
    assert (d / MARKER_NAME).read_bytes() == _whole_marker(d, "test")
    assert summary["files"] == len(names) and summary["sha256"] == json.loads((d / MARKER_NAME).read_text())["sha256"]
    # read back line by line (our layout), not as a whole
    events = list(own._layout(d / MARKER_NAME))
    assert [e[1] for e in events if e[0] == "file"] == sorted(names)
    assert folder_not_ours(d, complete=True) is None


def test_other_json_forms_of_a_marker_are_read_whole_and_judged_as_before(tmp_path, small_chunks):
    d = _folder(tmp_path, ODD)
    write_folder_marker(d, "test")
    marker = json.loads((d / MARKER_NAME).read_text())
    (d / MARKER_NAME).write_text(json.dumps(marker))  # the same marker, compact: still ours
    with pytest.raises(own._NotLayout):
        list(own._layout(d / MARKER_NAME))
    assert folder_not_ours(d, complete=True) is None
    marker["files"]["z"]["size"] = 99  # edited without its own hash: not ours
    (d / MARKER_NAME).write_text(json.dumps(marker))
    assert "not a valid rotoprint marker" in folder_not_ours(d)
    # our layout edited in place (a listed size), hash left: not ours either
    write_folder_marker(d, "test")
    text = (d / MARKER_NAME).read_text()
    (d / MARKER_NAME).write_text(text.replace('"size": 3', '"size": 4', 1))
    assert "not a valid rotoprint marker" in folder_not_ours(d)


def test_a_marker_with_a_number_of_thousands_of_digits_is_not_ours_and_raises_nothing(tmp_path, small_chunks):
    d = _folder(tmp_path, ODD)
    write_folder_marker(d, "test")
    text = (d / MARKER_NAME).read_text()
    assert '"size": 3' in text
    (d / MARKER_NAME).write_text(text.replace('"size": 3', '"size": ' + "9" * 5000, 1))  # past int()'s 4300 digits
    assert "not a valid rotoprint marker" in folder_not_ours(d)


def test_the_streamed_check_names_the_first_file_in_order(tmp_path, small_chunks):
    d = _folder(tmp_path, ODD)
    write_folder_marker(d, "test")
    (d / "sub" / "aaa-extra").write_text("mine")
    (d / "zz-extra").write_text("mine")
    assert folder_not_ours(d) == "it holds sub/aaa-extra, which rotoprint did not write"
    (d / "sub" / "aaa-extra").unlink()
    (d / "zz-extra").unlink()
    (d / "a.b").write_bytes(b"x" * len((d / "a.b").read_bytes()))
    assert folder_not_ours(d) == "a.b was changed since rotoprint wrote it"
    write_folder_marker(d, "test")
    (d / "sub" / "deeper" / "c").unlink()
    assert folder_not_ours(d) is None
    assert folder_not_ours(d, complete=True) == "some files rotoprint wrote there are missing"
    (d / "new-dir").mkdir()
    (d / "new-dir" / "f").write_text("mine")
    assert folder_not_ours(d) == "it holds the folder new-dir, which rotoprint did not write"


def test_recorded_files_are_not_read_again_at_install(tmp_path, monkeypatch):
    hashed = []
    real = own._sha_file
    monkeypatch.setattr(own, "_sha_file", lambda p: hashed.append(p.name) or real(p))
    out = tmp_path / "out"
    with OutputClaim(out, is_dir=True, kind="test") as claim:
        claim.part.mkdir()
        (claim.part / "sub").mkdir()
        for k in range(7):
            write_tracked(claim.part / "sub" / f"t{k}.bin", bytes([k]) * (k + 1))
        with own.open_tracked(claim.part / "prog.txt") as fh:
            fh.write("line 1\n")
            fh.write("line 2\n")
        (claim.part / "untracked.txt").write_text("written without the ledger")
        write_tracked(claim.part / "rewritten.bin", b"first")
        os.replace(_write(tmp_path / "y", b"other bytes"), claim.part / "rewritten.bin")  # not through the ledger
        claim.install()
    assert sorted(hashed) == ["rewritten.bin", "untracked.txt"]  # the rest came from the ledger
    assert folder_not_ours(out, complete=True) is None  # and the marker is right about every file
    assert (out / MARKER_NAME).read_bytes() == _whole_marker(out, "test")
    assert own._LEDGERS == {}  # the claim's ledgers are gone with it


def _write(p, data):
    p.write_bytes(data)
    return p


def test_a_ledger_outside_a_claim_and_write_tracked_without_one(tmp_path):
    assert own.ledger_for(tmp_path / "a" / "b") is None
    assert write_tracked(tmp_path / "plain.bin", b"abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
    with FolderLedger.opened(tmp_path) as (led,):
        assert own.ledger_for(tmp_path / "deep" / "x") is led
        write_tracked(tmp_path / "t.bin", b"abc")
        assert [e[0] for e in led.entries()] == ["t.bin"]
    assert own.ledger_for(tmp_path / "t.bin") is None


def test_the_spool_holds_a_bounded_number_of_records_and_sorts_stably(monkeypatch):
    monkeypatch.setattr(own, "_SORT_CHUNK", 8)
    monkeypatch.setattr(own, "_MERGE_FAN_IN", 3)
    with own._Spool() as sp:
        for k in range(500):
            sp.add([f"k{(k * 7919) % 97:03d}", k])
            assert len(sp._buf) < 8
        assert sp.count == 500 and len(sp._runs) == 62
        out = list(sp)
    assert [r[0] for r in out] == sorted(r[0] for r in out)
    for key in {r[0] for r in out}:  # equal keys in the order they were added
        seq = [r[1] for r in out if r[0] == key]
        assert seq == sorted(seq)
    assert [r[1] for r in own._last_per_key(iter([["a", 1], ["a", 2], ["b", 3]]))] == [2, 3]


def test_remove_ours_empties_folders_of_more_entries_than_a_batch(tmp_path):
    d = tmp_path / "o"
    (d / "s").mkdir(parents=True)
    for k in range(1100):
        (d / "s" / f"f{k}").write_bytes(b"")
    (d / "top").write_text("t")
    write_folder_marker(d, "test")
    assert folder_not_ours(d, complete=True) is None
    remove_ours(d)
    assert not d.exists()
