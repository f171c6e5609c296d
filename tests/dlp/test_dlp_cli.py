"""`rotoprint dlp` in-process: outputs reopened, bad input is one line and exit 2."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint.examples import write_binary_stl
from rotoprint.io.archives import read_job
from rotoprint.testing import box_triangles


@pytest.fixture
def stl(tmp_path):
    p = tmp_path / "block.stl"
    write_binary_stl(p, box_triangles((3.0, 2.0, 1.0)))
    return p


@pytest.mark.parametrize(
    "out,extra,n,fmt",
    [
        ("job.sl1", [], 2, "sl1"),
        ("job.sl1s", ["--device", "prusa-sl1s"], 2, "sl1s"),
        ("masks", ["--mode", "smooth", "--erm"], 4, "png"),
        ("pjob", ["--format", "perfactory", "--mode", "binary", "--invert", "--mirror-x"], 2, "perfactory"),
    ],
)
def test_dlp_writes_and_reopens(run_cli, stl, tmp_path, out, extra, n, fmt):
    args = ["dlp", stl, "--layer-height", "0.5", "--out", tmp_path / out, *extra]
    if "--device" not in extra:
        args += ["--device", "perfactory-sxga"]
    code, _, err = run_cli(*args)
    assert code == 0, err
    a = read_job(tmp_path / out)
    assert a.format == fmt and len(a) == n
    img = a.mask(0)
    if fmt == "sl1s":
        assert img.shape == (2560, 1620)
        assert a.prusaslicer["display_mirror_x"] == "1"
    else:
        assert img.shape == (1050, 1400)
    exposed = (255 - img) if "--invert" in extra else img
    area = exposed.sum(dtype=np.int64) / 255 * (0.05 * 0.05 if fmt == "sl1s" else (27.77 / 1400) * (20.83 / 1050))
    assert area == pytest.approx(6.0, rel=0.02)
    mode = extra[extra.index("--mode") + 1] if "--mode" in extra else "coverage"
    summary = " ".join(err.split())  # the console wraps long lines
    assert summary.startswith(f"{n} {mode} masks (2 layers{' x 2, ERM' if '--erm' in extra else ''}) of "), err
    assert f"-> {tmp_path / out} ({fmt})" in summary


def test_dlp_first_layer_offset(run_cli, stl, tmp_path):
    code, _, err = run_cli("dlp", stl, "-d", "perfactory-sxga", "--layer-height", "0.25", "--first-layers", "2",
                           "--first-layer-offset", "100", "--out", tmp_path / "f.sl1", "-q")
    assert code == 0, err
    a = read_job(tmp_path / "f.sl1")
    px = (27.77 / 1400) * (20.83 / 1050)
    areas = [a.mask(i).sum(dtype=np.int64) / 255 * px for i in range(len(a))]
    assert areas[0] == pytest.approx(2.8 * 1.8, rel=5e-3)
    assert areas[1] == pytest.approx(2.9 * 1.9, rel=5e-3)
    assert areas[2] == pytest.approx(6.0, rel=5e-3)


@pytest.mark.parametrize(
    "args,needle",
    [
        (["--mode", "blur"], "mode must be one of binary, coverage, smooth"),
        (["--device", "omnidot760"], "dlp needs a projector device"),
        (["--first-layer-offset", "50"], "--first-layers"),
        (["--layer-height", "-1"], "--layer-height must be in [0.0001, 100] mm, got -1"),
        (["--format", "ctb"], "format must be one of"),
        # the block is 3 x 2 mm: an inset above 1000 um would blank layer 0; 1e9 um is above the fixed maximum
        (["--first-layers", "2", "--first-layer-offset", "1001"], "--first-layer-offset of 1001 um is more than half the part's smallest footprint dimension (2 mm)"),
        (["--first-layers", "2", "--first-layer-offset", "1e9"], "--first-layer-offset must be in [0, 2000] um, got 1e+09"),
        (["--offset", "nan,0"], "--offset must be two finite numbers 'X,Y', got 'nan,0'"),
        (["--rotate", "nan,0,0"], "--rotate must be three finite numbers 'X,Y,Z', got 'nan,0,0'"),
        (["--exposure", "nan"], "--exposure must be in [0.001, 3600] s, got nan"),
        (["--first-exposure", "inf"], "--first-exposure must be in [0.001, 3600] s, got inf"),
        (["--exposure", "4000"], "--exposure must be in [0.001, 3600] s, got 4000"),
    ],
)
def test_dlp_bad_options_exit_2(run_cli, stl, tmp_path, args, needle):
    base = {"--device": "perfactory-sxga", "--layer-height": "0.5"}
    for k in ("--device", "--layer-height"):
        if k in args:
            base.pop(k)
    flat = [x for kv in base.items() for x in kv]
    code, out, err = run_cli("dlp", stl, *flat, *args, "--out", tmp_path / "o.sl1")
    assert code == 2
    assert needle in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o.sl1").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["block.stl"]


def test_dlp_bad_files_exit_2(run_cli, tmp_path):
    bad = tmp_path / "bad.stl"
    bad.write_bytes(b"\x00" * 10)
    code, _, err = run_cli("dlp", bad, "-d", "perfactory-sxga", "--layer-height", "0.1", "--out", tmp_path / "o.sl1")
    assert code == 2 and err.startswith(f"rotoprint: error: {bad}: ")
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    code, _, err = run_cli("dlp", tmp_path / "none.stl", "-d", "perfactory-sxga", "--layer-height", "0.1", "--out", tmp_path / "o.sl1")
    assert code == 2 and err.strip() == f"rotoprint: error: {tmp_path / 'none.stl'}: no such file"
    good = tmp_path / "good.stl"
    write_binary_stl(good, box_triangles((1.0, 1.0, 1.0)))
    code, _, err = run_cli("dlp", good, "-d", "perfactory-sxga", "--layer-height", "0.5", "--out", tmp_path / "nodir" / "o.sl1")
    assert code == 2 and "nodir" in err and "does not exist" in err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.stl", "good.stl"]


def test_dlp_part_outside_field(run_cli, tmp_path):
    p = tmp_path / "big.stl"
    write_binary_stl(p, box_triangles((40.0, 2.0, 1.0)))
    code, _, err = run_cli("dlp", p, "-d", "perfactory-sxga", "--layer-height", "0.5", "--out", tmp_path / "o.sl1")
    assert code == 2 and "does not fit the device field" in err
