"""Nothing the user made is replaced or deleted unless provably our own output.

Each case runs the CLI in-process and asserts exit 2, one line on stderr, no traceback, and
that every file of the user's (and everything else in the folder) is exactly as it was.
"""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import pytest

from _own_helpers import one_line_error, strays, tree
from rotoprint.examples import write_binary_stl
from rotoprint.io.atomic import OutputClaim
from rotoprint.io.images import write_png
from rotoprint.io.ownership import MARKER_NAME, file_not_ours, folder_not_ours
from rotoprint.rotary.testimage import test_design as make_design
from rotoprint.testing import box_triangles

SLICE = ("-d", "perfactory-sxga", "--layer-height", "0.5")


@pytest.fixture
def box(tmp_path) -> Path:
    p = tmp_path / "box.stl"
    write_binary_stl(p, box_triangles((2, 2, 1)))
    return p


def _web_project(w: Path) -> None:
    (w / "src").mkdir(parents=True)
    (w / "index.html").write_text("<html>mine</html>")
    (w / "src" / "app.js").write_text("console.log('mine')")
    (w / "manifest.json").write_text(json.dumps({"name": "my web app", "layers": []}))


def test_slice_into_a_web_project_with_a_manifest_is_refused(run_cli, tmp_path, box):
    _web_project(tmp_path / "w")
    before = tree(tmp_path)
    code, _, err = run_cli("slice", box, *SLICE, "-o", tmp_path / "w")
    one_line_error(code, err, "w:", "not provably a rotoprint output", "--force")
    assert tree(tmp_path) == before


def test_check_into_any_folder_with_a_report_json_is_refused(run_cli, tmp_path, box):
    r = tmp_path / "r"
    r.mkdir()
    (r / "report.json").write_text("{}")
    (r / "notes.txt").write_text("mine")
    before = tree(tmp_path)
    code, _, err = run_cli("check", box, *SLICE, "-o", r)
    one_line_error(code, err, "not provably a rotoprint output", "--force")
    assert tree(tmp_path) == before


def test_build_into_any_folder_with_a_plan_json_is_refused(run_cli, tmp_path):
    from rotoprint.pipeline.examples import write_example

    job = write_example("gas-sensor", tmp_path / "job")
    b = tmp_path / "b"
    b.mkdir()
    (b / "plan.json").write_text('{"format": "rotoprint-build-plan"}')
    (b / "thesis.tex").write_text("mine")
    before = tree(tmp_path)
    code, _, err = run_cli("build", job, "--out", b)
    one_line_error(code, err, "not provably a rotoprint output", "--force")
    assert tree(tmp_path) == before


def test_build_output_must_not_hold_the_job(run_cli, tmp_path):
    from rotoprint.pipeline.examples import write_example

    job = write_example("gas-sensor", tmp_path / "job")
    before = tree(tmp_path)
    code, _, err = run_cli("build", job, "--out", job.parent)
    one_line_error(code, err, "holds the input")
    assert tree(tmp_path) == before


def _transform(run_cli, design: Path, out: Path, *extra):
    return run_cli("transform", design, "--device", "omnidot760", "--tilt", "20", "--radius", "60", "--out", out, *extra)


def test_transform_onto_its_own_design_is_refused(run_cli, tmp_path):
    d = tmp_path / "d.png"
    write_png(d, make_design(60))
    (tmp_path / "d.json").write_text('{"my": "notes"}')
    before = tree(tmp_path)
    code, _, err = _transform(run_cli, d, d)
    one_line_error(code, err, "is the input")
    assert tree(tmp_path) == before
    code, _, err = _transform(run_cli, d, d, "--force")  # not even with --force
    one_line_error(code, err, "is the input")
    assert tree(tmp_path) == before


def test_transform_next_to_an_unrelated_json_is_refused(run_cli, tmp_path):
    d = tmp_path / "d.png"
    write_png(d, make_design(60))
    (tmp_path / "e.json").write_text('{"my": "notes"}')
    before = tree(tmp_path)
    code, _, err = _transform(run_cli, d, tmp_path / "e.png")
    one_line_error(code, err, "e.json", "--force")
    assert tree(tmp_path) == before


def test_transform_replaces_its_own_print_but_not_an_edited_one(run_cli, tmp_path):
    d = tmp_path / "d.png"
    write_png(d, make_design(60))
    out = tmp_path / "p.png"
    code, _, err = _transform(run_cli, d, out)
    assert code == 0, err
    assert file_not_ours(out) is None and file_not_ours(out.with_suffix(".json")) is None
    code, _, err = _transform(run_cli, d, out)  # our own: replaced
    assert code == 0, err
    side = json.loads(out.with_suffix(".json").read_text())
    side["tilt_deg"] = 21.0  # the user edits the sidecar: no longer ours
    out.with_suffix(".json").write_text(json.dumps(side))
    before = tree(tmp_path)
    code, _, err = _transform(run_cli, d, out)
    one_line_error(code, err, "p.json", "changed")
    assert tree(tmp_path) == before
    code, _, err = _transform(run_cli, d, out, "--force")
    assert code == 0, err
    assert file_not_ours(out.with_suffix(".json")) is None


def test_simulate_onto_its_own_input_print_is_refused(run_cli, tmp_path):
    d = tmp_path / "d.png"
    write_png(d, make_design(60))
    ok = tmp_path / "ok.png"
    code, _, err = _transform(run_cli, d, ok)
    assert code == 0, err
    before = tree(tmp_path)
    code, _, err = run_cli("simulate", tmp_path / "ok.json", "-o", ok)
    one_line_error(code, err, "is the input")
    assert tree(tmp_path) == before
    code, _, err = run_cli("simulate", tmp_path / "ok.json", "-o", d)  # nor onto the design it compares with
    one_line_error(code, err, "d.png", "--force")
    code, _, err = run_cli("simulate", tmp_path / "ok.json", "-o", d, "--force")  # not even with --force
    one_line_error(code, err, "is the input")
    assert tree(tmp_path) == before
    code, _, err = run_cli("simulate", tmp_path / "ok.json", "-o", tmp_path / "ov.png")
    assert code == 0, err
    code, _, err = run_cli("simulate", tmp_path / "ok.json", "-o", tmp_path / "ov.png")  # our own overlay: replaced
    assert code == 0, err
    write_png(tmp_path / "photo.png", make_design(20))
    before = tree(tmp_path)
    code, _, err = run_cli("simulate", tmp_path / "ok.json", "-o", tmp_path / "photo.png")  # a PNG that is not ours
    one_line_error(code, err, "photo.png", "no rotoprint marker", "--force")
    assert tree(tmp_path) == before


def test_dlp_does_not_replace_an_unrelated_file_but_replaces_its_own_archive(run_cli, tmp_path, box):
    keep = tmp_path / "keep.sl1"
    keep.write_bytes(b"my own archive, not a zip")
    before = tree(tmp_path)
    code, _, err = run_cli("dlp", box, *SLICE, "-o", keep)
    one_line_error(code, err, "keep.sl1", "--force")
    assert tree(tmp_path) == before
    ours = tmp_path / "ours.sl1"
    assert run_cli("dlp", box, *SLICE, "-o", ours)[0] == 0
    assert file_not_ours(ours) is None
    assert run_cli("dlp", box, *SLICE, "--mode", "binary", "-o", ours)[0] == 0  # ours: replaced without --force
    code, _, err = run_cli("dlp", box, *SLICE, "-o", keep, "--force")
    assert code == 0, err
    assert file_not_ours(keep) is None
    assert strays(tmp_path) == []


def test_rerun_into_an_earlier_output_keeps_files_the_user_added(run_cli, tmp_path, box):
    out = tmp_path / "out"
    assert run_cli("slice", box, *SLICE, "-o", out)[0] == 0
    assert folder_not_ours(out, complete=True) is None
    assert run_cli("slice", box, *SLICE, "-o", out)[0] == 0  # an unchanged output of ours is replaced
    (out / "my-notes.txt").write_text("mine")
    before = tree(tmp_path)
    code, _, err = run_cli("slice", box, *SLICE, "-o", out)
    one_line_error(code, err, "my-notes.txt", "--force")
    assert tree(tmp_path) == before
    (out / "my-notes.txt").unlink()
    (out / "layer_00000.png").write_bytes(b"edited by hand")  # a file of ours, changed: not ours any more
    code, _, err = run_cli("slice", box, *SLICE, "-o", out)
    one_line_error(code, err, "layer_00000.png", "changed")


def test_a_copied_or_edited_marker_does_not_make_a_folder_ours(run_cli, tmp_path, box):
    a = tmp_path / "a"
    assert run_cli("slice", box, *SLICE, "-o", a)[0] == 0
    w = tmp_path / "w"
    _web_project(w)
    (w / MARKER_NAME).write_bytes((a / MARKER_NAME).read_bytes())  # our marker copied in: lists none of these
    before = tree(tmp_path)
    code, _, err = run_cli("slice", box, *SLICE, "-o", w)
    one_line_error(code, err, "rotoprint did not write")
    marker = json.loads((a / MARKER_NAME).read_text())
    marker["files"]["index.html"] = {"size": 1, "sha256": "0" * 64}  # edited without its own hash
    (w / MARKER_NAME).write_text(json.dumps(marker))
    code, _, err = run_cli("slice", box, *SLICE, "-o", w)
    one_line_error(code, err, "not a valid rotoprint marker")
    (w / MARKER_NAME).unlink()
    assert tree(tmp_path) == {k: v for k, v in before.items() if k != f"w/{MARKER_NAME}"}


def test_force_replaces_a_foreign_folder(run_cli, tmp_path, box):
    _web_project(tmp_path / "w")
    code, _, err = run_cli("slice", box, *SLICE, "-o", tmp_path / "w", "--force")
    assert code == 0, err
    assert not (tmp_path / "w" / "index.html").exists() and folder_not_ours(tmp_path / "w", complete=True) is None
    assert strays(tmp_path) == []


@pytest.mark.parametrize("cmd", ["slice", "check", "dlp"])
def test_output_that_cannot_work_fails_before_the_work(run_cli, tmp_path, box, monkeypatch, cmd):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "mine.txt").write_text("mine")
    before = tree(tmp_path)
    for o in (".", "..", str(tmp_path.parent)):
        code, _, err = run_cli(cmd, box, *SLICE, "-o", o)
        one_line_error(code, err, "current folder")
        assert tree(tmp_path) == before
    code, _, err = run_cli(cmd, box, *SLICE, "-o", tmp_path / "no" / "such" / ("x.sl1" if cmd == "dlp" else "x"))
    one_line_error(code, err, "does not exist")
    code, _, err = run_cli(cmd, box, *SLICE, "-o", box)  # the output is the mesh itself
    one_line_error(code, err, "input")
    assert tree(tmp_path) == before


def test_output_folder_must_not_hold_the_mesh(run_cli, tmp_path):
    d = tmp_path / "d"
    d.mkdir()
    write_binary_stl(d / "box.stl", box_triangles((2, 2, 1)))
    before = tree(tmp_path)
    for force in ((), ("--force",)):
        code, _, err = run_cli("slice", d / "box.stl", *SLICE, "-o", d, *force)
        one_line_error(code, err, "holds the input")
        assert tree(tmp_path) == before


def test_two_runs_into_the_same_output_one_gets_in_use(run_cli, tmp_path, box):
    out = tmp_path / "out"
    with OutputClaim(out, is_dir=True, kind="test") as claim:  # another run holds the output
        code, _, err = run_cli("slice", box, *SLICE, "-o", out)
        one_line_error(code, err, "in use by another rotoprint run", f"pid {os.getpid()}")
        assert claim.lock_path.exists()
    assert not claim.lock_path.exists() and not out.exists()
    assert run_cli("slice", box, *SLICE, "-o", out)[0] == 0  # and once it is done, the next one runs
    assert strays(tmp_path) == []


def test_a_foreign_lock_file_is_not_overwritten(run_cli, tmp_path, box):
    (tmp_path / ".out.lock").write_text("my file that happens to have this name")
    before = tree(tmp_path)
    code, _, err = run_cli("slice", box, *SLICE, "-o", tmp_path / "out")
    one_line_error(code, err, "not a rotoprint lock")
    assert tree(tmp_path) == before


@pytest.mark.parametrize("cmd, out, where", [("slice", "out", ".partial"), ("dlp", "job.sl1", ".partial"), ("dlp", "job", ".partial"),
                                             ("dlp", "job.sl1", ".part"), ("dlp", "job", ".part")])
def test_full_disk_is_one_line_naming_the_file_and_nothing_is_left(run_cli, tmp_path, box, monkeypatch, cmd, out, where):
    """The disk fills while the layers are made (in .partial) or while the archive or folder
    is assembled (in .part)."""
    (tmp_path / "mine.txt").write_text("mine")
    before = tree(tmp_path)
    import builtins
    import io

    real_open = builtins.open

    class Full:  # a file object whose writes fail as on a full disk, after the first few bytes
        def __init__(self, fh):
            self._fh = fh

        def write(self, data):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

        def __getattr__(self, k):
            return getattr(self._fh, k)

        def __enter__(self):
            return self

        def __exit__(self, *a):
            self._fh.close()

    def full_open(file, mode="r", *a, **k):
        fh = real_open(file, mode, *a, **k)
        if "w" in mode and "b" in mode and str(tmp_path) in str(file) and f"{where}/" in f"{file}/":
            return Full(fh)
        return fh

    monkeypatch.setattr(builtins, "open", full_open)
    monkeypatch.setattr(io, "open", full_open)
    code, _, err = run_cli(cmd, box, *SLICE, "-o", tmp_path / out)
    monkeypatch.undo()
    line = one_line_error(code, err, "no space left")
    assert f"{tmp_path / out}" in line  # names the file it was writing
    assert tree(tmp_path) == before


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_head_plot_replaces_its_own_figure_only(run_cli, tmp_path, suffix):
    fig = tmp_path / f"f5{suffix}"
    args = ("head", "--device", "omnidot760", "--tilt", "20", "--plot", fig)
    assert run_cli(*args)[0] == 0
    assert file_not_ours(fig) is None
    assert run_cli(*args)[0] == 0  # ours: replaced
    mine = tmp_path / f"mine{suffix}"
    mine.write_bytes(b"<svg>my drawing</svg>" if suffix == ".svg" else fig.read_bytes()[:-40] + b"x" * 40)
    before = tree(tmp_path)
    code, _, err = run_cli("head", "--device", "omnidot760", "--tilt", "20", "--plot", mine)
    one_line_error(code, err, mine.name, "--force")
    assert tree(tmp_path) == before
