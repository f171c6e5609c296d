"""kill -9 at each stage of a run, then a plain rerun or ``--resume``: the output is
byte-identical to a clean run and no ``.partial`` / ``.old`` / ``.part`` / lock is left.

The killed run is a subprocess that SIGKILLs itself at a named point
(``ROTOPRINT_TEST_KILL_AT``, read by :func:`rotoprint.io.atomic.kill_point`); the reruns are
in-process. Parts are tiny (a 2 mm box in 4 layers) so each case takes a few seconds.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from _own_helpers import killed_run, strays, tree
from rotoprint.examples import write_binary_stl
from rotoprint.io.ownership import folder_not_ours
from rotoprint.testing import box_triangles

SLICE = ("-d", "perfactory-sxga", "--layer-height", "0.5")
OLD = ("-d", "perfactory-sxga", "--layer-height", "1")  # an earlier output of ours with other content
EPOCH = "1700000000"


def _killed_run(cwd: Path, stage: str, *args: str) -> None:
    killed_run(cwd, stage, *args, SOURCE_DATE_EPOCH=EPOCH)


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    """Clean runs: the slice folder and the SL1 archive the killed runs must end up as."""
    from rotoprint.cli.main import main

    root = tmp_path_factory.mktemp("clean")
    write_binary_stl(root / "box.stl", box_triangles((2, 2, 2)))
    old_env, old_cwd = os.environ.get("SOURCE_DATE_EPOCH"), os.getcwd()
    os.environ["SOURCE_DATE_EPOCH"] = EPOCH
    os.chdir(root)  # the same relative paths as the killed runs (the manifest names the mesh as given)
    try:
        assert main(["slice", "box.stl", *SLICE, "-o", "out", "-q"]) == 0
        assert main(["slice", "box.stl", *OLD, "-o", "old", "-q"]) == 0
        assert main(["dlp", "box.stl", *SLICE, "-o", "job.sl1", "-q"]) == 0
        os.mkdir("prev")  # the same archive name (its job folder inside is named after it)
        assert main(["dlp", "box.stl", *OLD, "-o", "prev/job.sl1", "-q"]) == 0
    finally:
        os.chdir(old_cwd)
        if old_env is None:
            del os.environ["SOURCE_DATE_EPOCH"]
        else:
            os.environ["SOURCE_DATE_EPOCH"] = old_env
    return {"out": tree(root / "out"), "old": tree(root / "old"), "job.sl1": (root / "job.sl1").read_bytes(),
            "old.sl1": (root / "prev" / "job.sl1").read_bytes()}


@pytest.fixture
def work(tmp_path, monkeypatch):
    write_binary_stl(tmp_path / "box.stl", box_triangles((2, 2, 2)))
    monkeypatch.setenv("SOURCE_DATE_EPOCH", EPOCH)
    monkeypatch.chdir(tmp_path)
    return tmp_path


# stage, whether an earlier output of ours is there, what the path holds right after the kill
SLICE_CASES = [
    ("layer-1", False, None),
    ("finish", True, "old"),
    ("install-old-moved", True, None),  # between the two renames: the old output is in .old
    ("install-new-moved", True, "out"),  # the new output in place, .old not yet removed
]


@pytest.mark.parametrize("rerun", ["plain", "resume"])
@pytest.mark.parametrize("stage, earlier, after_kill", SLICE_CASES)
def test_slice_killed_then_rerun(run_cli, work, clean, stage, earlier, after_kill, rerun):
    out = Path("out")
    (work / "mine.txt").write_text("the user's")
    if earlier:
        assert run_cli("slice", "box.stl", *OLD, "-o", out, "-q")[0] == 0
        assert tree(out) == clean["old"]
    _killed_run(work, stage, "slice", "box.stl", *SLICE, "-o", "out", "-q")
    if after_kill is None:
        assert not out.exists()
    else:
        assert tree(out) == clean[after_kill]  # complete, old or new
    code, _, err = run_cli("slice", "box.stl", *SLICE, "-o", out, "-q", *(["--resume"] if rerun == "resume" else []))
    assert code == 0, err
    assert tree(out) == clean["out"]
    assert folder_not_ours(out, complete=True) is None
    assert strays(work) == []
    assert (work / "mine.txt").read_text() == "the user's"


def test_killed_between_renames_a_plain_run_of_another_job_finds_the_old_output(run_cli, work, clean):
    """The next run puts the old complete output back before anything else (here: a run that
    only checks the output path and fails on a bad option, so it writes nothing itself)."""
    out = Path("out")
    assert run_cli("slice", "box.stl", *OLD, "-o", out, "-q")[0] == 0
    _killed_run(work, "install-old-moved", "slice", "box.stl", *SLICE, "-o", "out", "-q")
    assert not out.exists() and (work / "out.old").is_dir()
    from rotoprint.io.atomic import OutputClaim

    with OutputClaim(out, is_dir=True, kind="test"):
        assert tree(out) == clean["old"]
    assert strays(work) == []


DLP_CASES = [
    ("layer-1", False),
    ("archive-2", False),  # during the zip assembly: a .part archive is left
    ("archive-2", True),
    ("finish", True),
]


@pytest.mark.parametrize("rerun", ["plain", "resume"])
@pytest.mark.parametrize("stage, earlier", DLP_CASES)
def test_dlp_archive_killed_then_rerun(run_cli, work, clean, stage, earlier, rerun):
    job = Path("job.sl1")
    if earlier:
        assert run_cli("dlp", "box.stl", *OLD, "-o", job, "-q")[0] == 0
        assert job.read_bytes() == clean["old.sl1"]
    _killed_run(work, stage, "dlp", "box.stl", *SLICE, "-o", "job.sl1", "-q")
    if earlier:
        assert job.read_bytes() == clean["old.sl1"]  # a file is replaced in one rename: old until then
    else:
        assert not job.exists()
    code, _, err = run_cli("dlp", "box.stl", *SLICE, "-o", job, "-q", *(["--resume"] if rerun == "resume" else []))
    assert code == 0, err
    assert job.read_bytes() == clean["job.sl1"]
    assert strays(work) == []


def test_check_report_killed_between_renames(run_cli, work):
    """The same replace for the folders written in one go (check, build): old output back."""
    out = Path("rep")
    args = ("check", "box.stl", *SLICE, "-o", out, "-q")
    assert run_cli(*args)[0] == 0
    first = tree(out)
    _killed_run(work, "install-old-moved", *map(str, args))
    assert not out.exists()
    assert run_cli(*args)[0] == 0
    assert tree(out) == first
    assert strays(work) == []


ROTARY = ("-d", "omnidot760", "--layer-height", "0.5", "--rotary", "--tilt", "20", "--radius", "60")


@pytest.mark.parametrize("stage, rerun", [("layer-1", "resume"), ("install-old-moved", "plain")])
def test_rotary_slices_killed_then_rerun(run_cli, work, stage, rerun):
    (work / "c").mkdir()
    assert run_cli("slice", "box.stl", *ROTARY, "-o", "c/rot", "-q")[0] == 0  # the clean run
    old = ("-d", "omnidot760", "--layer-height", "1", *ROTARY[4:])
    assert run_cli("slice", "box.stl", *old, "-o", "rot", "-q")[0] == 0  # an earlier output of ours
    before = tree(work / "rot")
    _killed_run(work, stage, "slice", "box.stl", *ROTARY, "-o", "rot", "-q")
    if stage == "layer-1":
        assert tree(work / "rot") == before
    code, _, err = run_cli("slice", "box.stl", *ROTARY, "-o", "rot", "-q", *(["--resume"] if rerun == "resume" else []))
    assert code == 0, err
    assert tree(work / "rot") == tree(work / "c" / "rot")
    assert strays(work) == []
