"""The `rotoprint check` command: exit codes, outputs, nothing partial on bad input."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from rotoprint.testing import box_triangles


def _write_stl(path, tris):
    with open(path, "wb") as f:
        f.write(b"test".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<12fH", 0, 0, 0, *np.asarray(t, np.float32).ravel(), 0))
    return path


@pytest.fixture
def thin_part(tmp_path):
    # a 2 x 2 mm block with a 40 um fin and, beside it, a 30 um slot between two blocks
    tris = np.concatenate(
        [
            box_triangles((2.0, 2.0, 0.4)),
            box_triangles((1.0, 0.04, 0.4), (2.0, 0.98, 0.0)),  # a fin out of the block's side
            box_triangles((0.5, 2.0, 0.4), (3.5, 0.0, 0.0)),
            box_triangles((0.5, 2.0, 0.4), (4.03, 0.0, 0.0)),
        ]
    )
    return _write_stl(tmp_path / "thin.stl", tris)


@pytest.fixture
def good_part(tmp_path):
    return _write_stl(tmp_path / "good.stl", box_triangles((2.0, 1.0, 0.4)))


def test_check_cli_finds_and_exits_3(run_cli, thin_part, tmp_path):
    out = tmp_path / "out"
    code, stdout, err = run_cli("check", thin_part, "--device", "perfactory-sxga", "--layer-height", "0.2", "--min-wall", "0.05", "--min-gap", "0.05", "--out", out)
    assert code == 3, err
    rep = json.loads((out / "report.json").read_text())
    assert not rep["ok"]
    assert rep["counts"]["thin_wall"] == 2 and rep["counts"]["narrow_gap"] == 2  # one each per layer
    assert rep["thinnest_wall"]["width_mm"] == pytest.approx(0.04, abs=1e-6)
    assert rep["narrowest_gap"]["width_mm"] == pytest.approx(0.03, abs=1e-6)
    assert 2.0 <= rep["thinnest_wall"]["x_mm"] <= 3.0 and 0.98 <= rep["thinnest_wall"]["y_mm"] <= 1.02
    assert 4.0 <= rep["narrowest_gap"]["x_mm"] <= 4.03
    assert rep["overlays"] == ["overlays/layer_00000.png", "overlays/layer_00001.png"]
    assert all((out / p).is_file() for p in rep["overlays"])
    assert "thin wall" in stdout and "40.0 um" in stdout


def test_check_cli_json_and_ok(run_cli, good_part):
    code, stdout, err = run_cli("check", good_part, "--device", "omnidot760", "--layer-height", "0.2", "--json")
    assert code == 0, err
    rep = json.loads(stdout)
    assert rep["ok"] and rep["findings"] == [] and rep["n_layers"] == 2
    assert rep["limits"]["min_wall_mm"] == pytest.approx(25.4 / 360, rel=1e-9)


def test_check_cli_limits_only(run_cli):
    code, stdout, err = run_cli("check", "--device", "omnidot760", "--json", "--rotary", "--tilt", "0", "--radius", "200")
    assert code == 0, err
    lim = json.loads(stdout)["limits"]
    assert lim["rotary"]["largest_track_gap_mm"] == pytest.approx(53.8 / 764, rel=1e-3)
    code, stdout, err = run_cli("check", "--device", "perfactory-sxga", "--json")
    assert code == 0
    assert json.loads(stdout)["limits"]["min_wall_mm"] == pytest.approx(20.83 / 1050, rel=1e-9)


@pytest.mark.parametrize(
    "args",
    [
        ("--layer-height", "0.2", "--min-wall", "-1"),
        ("--layer-height", "0.2", "--min-gap", "nan"),
        ("--layer-height", "0.2", "--orientations", "0:90"),
        ("--layer-height", "0.2", "--orientations", "90:0:10"),
        ("--layer-height", "0.2", "--rotary", "--tilt", "10"),
        ("--layer-height", "0.2", "--tilt", "10"),
        ("--layer-height", "0.2", "--mask", "blur"),
        ("--layer-height", "0.2", "--cure-threshold", "0.4"),
        ("--layer-height", "0.2", "--resolution", "-0.001"),
        ("--layer-height", "0.2", "--resolution", "nan"),
        ("--layer-height", "0.2", "--resolution", "0.01"),  # over a quarter pixel
        ("--layer-height", "0.2", "--resolution", "abc"),  # not a number: one line too
        ("--layer-height", "0.2", "--bogus"),
        ("--layer-height", "0.2", "--no-cavities=no"),
        (),  # no layer height
    ],
)
def test_check_cli_bad_input_exit_2_nothing_written(run_cli, thin_part, tmp_path, args):
    out = tmp_path / "out"
    code, stdout, err = run_cli("check", thin_part, "--device", "perfactory-sxga", "--out", out, *args)
    assert code == 2, (stdout, err)
    assert "error" in err and len(err.strip().splitlines()) == 1
    assert not out.exists()
    assert not list(tmp_path.glob(".out*"))


def test_check_cli_resolution(run_cli, thin_part):
    """--resolution is recorded; 0 measures on the section as sliced."""
    widths = {}
    for res in ("0", "0.0002"):
        code, stdout, err = run_cli("check", thin_part, "--device", "perfactory-sxga", "--layer-height", "0.2", "--resolution", res, "--json")
        assert code in (0, 3), err
        rep = json.loads(stdout)
        assert rep["settings"]["resolution_mm"] == float(res)
        widths[res] = rep["thinnest_wall"]["width_mm"] if rep["thinnest_wall"] else None
    assert widths["0"] == pytest.approx(0.04, abs=1e-6)  # the fin (float32 STL coordinates)
    assert abs(widths["0"] - widths["0.0002"]) <= 2 * 0.0002 + 1e-12


def test_check_cli_bad_mesh_and_device(run_cli, tmp_path):
    bad = tmp_path / "bad.stl"
    bad.write_bytes(b"garbage")
    code, _, err = run_cli("check", bad, "--device", "perfactory-sxga", "--layer-height", "0.2", "--out", tmp_path / "o")
    assert code == 2 and not (tmp_path / "o").exists()
    assert err.startswith(f"rotoprint: error: {bad}: ") and "Traceback" not in err and len(err.strip().splitlines()) == 1
    code, _, err = run_cli("check", bad, "--device", "nosuchdevice", "--layer-height", "0.2")
    assert code == 2
    assert err.startswith("rotoprint: error: unknown device 'nosuchdevice'") and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.stl"]


def test_check_cli_orientations(run_cli, thin_part, tmp_path):
    out = tmp_path / "o"
    code, stdout, err = run_cli(
        "check", thin_part, "--device", "perfactory-sxga", "--layer-height", "0.4", "--orientations", "0:90:45", "--out", out, "--no-islands", "--min-wall", "0.05"
    )
    assert code == 3, err
    rep = json.loads((out / "report.json").read_text())
    rows = rep["orientations"]["rows"]
    assert [r["angle_deg"] for r in rows] == [0.0, 45.0, 90.0]
    best = min(rows, key=lambda r: r["loss_mm"])
    assert rep["orientations"]["best_angle_deg"] == best["angle_deg"]
    assert "least loss" in stdout


def test_check_cli_refuses_foreign_folder(run_cli, good_part, tmp_path):
    out = tmp_path / "mine"
    out.mkdir()
    (out / "precious.txt").write_text("keep")
    code, _, err = run_cli("check", good_part, "--device", "omnidot760", "--layer-height", "0.2", "--out", out)
    assert code == 2 and (out / "precious.txt").read_text() == "keep"
