"""A killed run leaves its temporary and its lock behind (the lock is neither fsync-ed nor, when
new, truncated: ``rotoprint.io.atomic.OutputClaim._acquire``). The next run must then work, and
must never replace or delete a file the user made: only temporaries the killed run's lock names,
or outputs that carry our marker, go."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from _own_helpers import killed_run, one_line_error, strays, tree
from rotoprint.examples import write_binary_stl
from rotoprint.io.images import png_bytes
from rotoprint.testing import box_triangles

TRANSFORM = ("-d", "omnidot760", "--tilt", "20", "--radius", "60")
SLICE = ("-d", "perfactory-sxga", "--layer-height", "0.5")


@pytest.fixture
def work(tmp_path, monkeypatch):
    d = np.zeros((20, 30), np.uint8)
    d[4:16, 5:25] = 255
    (tmp_path / "design.png").write_bytes(png_bytes(d))
    write_binary_stl(tmp_path / "box.stl", box_triangles((2, 2, 2)))
    (tmp_path / "mine.txt").write_text("the user's")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _killed_transform(work: Path) -> None:
    killed_run(work, "finish", "transform", "design.png", *TRANSFORM, "-o", "print.png", "-q")
    assert (work / "print.png.part").is_file()
    lock = json.loads((work / ".print.png.lock").read_text())
    assert lock["format"] == "rotoprint-lock" and "print.png.part" in lock["temporaries"]


def test_a_run_after_a_killed_one_works_and_keeps_the_users_files(run_cli, work):
    _killed_transform(work)
    code, _, err = run_cli("transform", "design.png", *TRANSFORM, "-o", "print.png", "-q")
    assert code == 0, err
    assert (work / "print.png").is_file() and strays(work) == []
    assert (work / "mine.txt").read_text() == "the user's"
    again = (work / "print.png").read_bytes()
    assert run_cli("transform", "design.png", *TRANSFORM, "-o", "print.png", "-q")[0] == 0  # ours: replaced
    assert (work / "print.png").read_bytes() == again and strays(work) == []


@pytest.mark.parametrize("lock", ["emptied", "removed"])
def test_a_temporary_no_lock_speaks_for_is_kept(run_cli, work, lock):
    """The killed run's lock did not reach the disk (a power cut; it is not fsync-ed): its
    temporary is not provably ours, so the next run refuses and leaves it."""
    _killed_transform(work)
    part = (work / "print.png.part").read_bytes()
    if lock == "emptied":
        (work / ".print.png.lock").write_bytes(b"")
    else:
        (work / ".print.png.lock").unlink()
    code, _, err = run_cli("transform", "design.png", *TRANSFORM, "-o", "print.png", "-q")
    one_line_error(code, err, "print.png.part", "not provably ours")
    assert (work / "print.png.part").read_bytes() == part and not (work / "print.png").exists()
    assert (work / "mine.txt").read_text() == "the user's"


def test_the_users_file_at_the_output_path_survives_a_killed_run_and_the_next(run_cli, work):
    """A file the user made at the output path is refused before any work, killed or not."""
    (work / "print.png").write_bytes(b"the user's picture")
    code, _, err = run_cli("transform", "design.png", *TRANSFORM, "-o", "print.png", "-q")
    one_line_error(code, err, "print.png")
    assert (work / "print.png").read_bytes() == b"the user's picture" and strays(work) == []


def test_a_forced_run_killed_between_renames_puts_the_users_folder_back(run_cli, work):
    """``--force`` into a folder holding the user's file, killed after the folder was moved to
    ``.old``: the next plain run puts it back whole, removes the killed run's temporaries, and
    refuses (the folder is not ours)."""
    out = work / "out"
    out.mkdir()
    (out / "notes.txt").write_text("the user's notes")
    before = tree(out)
    killed_run(work, "install-old-moved", "slice", "box.stl", *SLICE, "-o", "out", "-q", "--force")
    assert not out.exists() and tree(work / "out.old") == before
    code, _, err = run_cli("slice", "box.stl", *SLICE, "-o", "out", "-q")
    one_line_error(code, err, "not provably a rotoprint output")
    assert tree(out) == before and strays(work) == []
    assert (work / "mine.txt").read_text() == "the user's"
