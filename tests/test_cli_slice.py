"""The CLI called in-process: exit codes, outputs, one-line errors, nothing partial."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from rotoprint.io.stl import write_binary_stl
from rotoprint.testing import box_triangles, torus_mesh


@pytest.fixture
def torus_stl(tmp_path):
    p = tmp_path / "torus.stl"
    write_binary_stl(p, torus_mesh(6, 2, 48, 24).triangles)
    return p


def test_slice_writes_layers_and_manifest(run_cli, torus_stl, tmp_path):
    out = tmp_path / "layers"
    code, _, err = run_cli("slice", torus_stl, "--device", "perfactory-sxga", "--layer-height", "0.5", "--out", out)
    assert code == 0, err
    man = json.loads((out / "manifest.json").read_text())
    assert man["layer_count"] == 8 == len(list(out.glob("layer_*.png")))
    assert man["device"]["projector"]["pixels_x"] == 1400
    first = man["layers"][0]
    img = np.asarray(Image.open(out / first["file"]))
    assert img.shape == (1050, 1400) and img.dtype == np.uint8 and set(np.unique(img)) <= {0, 255}
    # the affine puts every material pixel inside the torus's annulus (model frame), give or take a pixel
    rows, cols = np.nonzero(img)
    m = np.array(first["pixel_to_model"])
    x = m[0, 0] * cols + m[0, 1] * rows + m[0, 2]
    y = m[1, 0] * cols + m[1, 1] * rows + m[1, 2]
    r = np.hypot(x, y)
    assert r.min() > 4 - 0.03 and r.max() < 8 + 0.03
    assert first["z_mm"] == pytest.approx(-2 + 0.25)
    assert first["sha256"] and first["gaps"]["left_open"] == 0


def test_slice_inkjet_with_fibre_angle(run_cli, torus_stl, tmp_path):
    out = tmp_path / "ink"
    code, _, err = run_cli(
        "slice", torus_stl, "-d", "omnidot760", "--layer-height", "1", "--fibre-angle", "30", "--dpi-y", "720", "-o", out
    )
    assert code == 0, err
    man = json.loads((out / "manifest.json").read_text())
    assert man["device"]["head"]["dpi_y"] == 720
    assert man["grid"]["pitch_y_mm"] == pytest.approx(25.4 / 720)
    assert man["grid"]["pitch_x_mm"] == pytest.approx(53.8 / 764)


def test_info_json(run_cli, torus_stl):
    code, out, _ = run_cli("info", torus_stl, "--json")
    assert code == 0
    data = json.loads(out)
    assert data["watertight"] and data["shells"] == 1 and data["triangles"] == 48 * 24 * 2
    assert data["volume_mm3"] == pytest.approx(2 * np.pi**2 * 6 * 4, rel=0.02)


def test_info_table(run_cli, torus_stl):
    code, out, _ = run_cli("info", torus_stl)
    assert code == 0 and "watertight" in out and "yes" in out


def _one_line_error(code, out, err, *fragments):
    assert code == 2
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for f in fragments:
        assert f in lines[0], lines[0]


@pytest.mark.parametrize(
    "args,fragments",
    [
        (["info", "{missing}"], ["no such file"]),
        (["info", "{garbage}"], ["not a valid STL"]),
        (["slice", "{box}", "-d", "nodevice", "--layer-height", "1", "-o", "{out}"], ["unknown device 'nodevice'"]),
        (["slice", "{box}", "-d", "perfactory-sxga", "--layer-height", "0", "-o", "{out}"], ["--layer-height must be in"]),
        (["slice", "{box}", "-d", "perfactory-sxga", "--layer-height", "1", "--fill", "odd", "-o", "{out}"], ["fill must be one of"]),
        (["slice", "{big}", "-d", "perfactory-sxga", "--layer-height", "1", "-o", "{out}"], ["does not fit the device field"]),
        (["slice", "{box}", "-d", "{baddev}", "--layer-height", "1", "-o", "{out}"], ["head.nozzles"]),
        (["slice", "{box}", "-d", "perfactory-sxga", "--layer-height", "1", "--offset", "1", "-o", "{out}"], ["--offset"]),
        (["info", "{box}", "--units", "furlong"], ["units must be one of"]),
        (["slice", "{box}", "-d", "perfactory-sxga", "--layer-height", "1", "--dpi-y", "720", "-o", "{out}"],
         ["--dpi-y applies to inkjet heads only; preset perfactory-sxga is a projector device"]),
        (["slice", "{box}", "-d", "omnidot760", "--layer-height", "1", "--dpi-y", "nan", "-o", "{out}"],
         ["--dpi-y must be in [1, 100000] dpi, got nan"]),
        (["slice", "{box}", "-d", "perfactory-sxga", "--layer-height", "1", "--rotate", "0,inf,0", "-o", "{out}"],
         ["--rotate must be three finite numbers"]),
    ],
)
def test_bad_input_one_line_exit_2_nothing_written(run_cli, tmp_path, args, fragments):
    box = tmp_path / "box.stl"
    write_binary_stl(box, box_triangles((2, 2, 2)))
    big = tmp_path / "big.stl"
    write_binary_stl(big, box_triangles((40, 2, 2)))
    garbage = tmp_path / "g.stl"
    garbage.write_bytes(bytes(range(256)) * 3)
    baddev = tmp_path / "dev.toml"
    baddev.write_text('name = "x"\nkind = "inkjet"\n[head]\nnozzles = -4\nswathe_mm = 10\nrow_separation_mm = 1\n')
    subst = {"{missing}": tmp_path / "nope.stl", "{garbage}": garbage, "{box}": box, "{big}": big,
             "{out}": tmp_path / "out", "{baddev}": baddev}
    code, out, err = run_cli(*[subst.get(a, a) for a in args])
    _one_line_error(code, out, err, *fragments)
    assert not (tmp_path / "out").exists()
    assert not list(tmp_path.glob(".out*"))  # no temporary left behind
    assert not (tmp_path / "out.partial").exists()  # nor a journal folder


def test_refuses_to_replace_a_foreign_folder(run_cli, tmp_path):
    box = tmp_path / "box.stl"
    write_binary_stl(box, box_triangles((2, 2, 2)))
    out = tmp_path / "mine"
    out.mkdir()
    (out / "precious.txt").write_text("keep me")
    code, _, err = run_cli("slice", box, "-d", "perfactory-sxga", "--layer-height", "1", "-o", out)
    _one_line_error(code, "", err, "refusing to replace")
    assert (out / "precious.txt").read_text() == "keep me"


def test_rerun_replaces_earlier_output(run_cli, tmp_path):
    box = tmp_path / "box.stl"
    write_binary_stl(box, box_triangles((2, 2, 2)))
    out = tmp_path / "o"
    for lh in ("1", "0.5"):
        code, _, err = run_cli("slice", box, "-d", "perfactory-sxga", "--layer-height", lh, "-o", out)
        assert code == 0, err
    assert len(list(out.glob("layer_*.png"))) == 4


def test_demo_runs(coil_demo):
    # coil_demo: the session's `rotoprint demo --out DIR` (tests/conftest.py)
    code, out, err = coil_demo.code, coil_demo.stdout, coil_demo.stderr
    assert code == 0, err
    # the demo builds the bundled coil sensor (issue 7; details in tests/process/test_build_cli.py)
    assert "report:" in out
    assert (coil_demo.root / "d" / "build" / "report.html").exists()
    assert (coil_demo.root / "d" / "job" / "coil-sensor.toml").exists()


def test_usage_error_exit_2(run_cli):
    code, _, _ = run_cli("slice")
    assert code == 2


def test_library_warnings_are_logged_not_printed(run_cli, tmp_path, monkeypatch, caplog):
    import logging
    import warnings

    import rotoprint.io.mesh as mesh_io

    box = tmp_path / "box.stl"
    write_binary_stl(box, box_triangles((2, 2, 2)))
    real = mesh_io.load_mesh

    def noisy(*a, **k):
        warnings.warn("Attempting to set identical low and high xlims", UserWarning)  # what matplotlib said
        return real(*a, **k)

    monkeypatch.setattr(mesh_io, "load_mesh", noisy)
    with caplog.at_level(logging.INFO, logger="rotoprint.warnings"), warnings.catch_warnings():
        warnings.simplefilter("default")  # a user's filters (pytest here turns warnings into errors)
        code, out, err = run_cli("info", box)
    assert code == 0, err
    assert "UserWarning" not in err and "xlims" not in err
    assert any("UserWarning: Attempting to set identical low and high xlims" in r.getMessage() for r in caplog.records)
