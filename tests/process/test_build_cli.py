"""`rotoprint build` and `rotoprint demo` end to end; job-file errors name the field."""

from __future__ import annotations

import hashlib
import json
import re

import numpy as np
import pytest

from _build_helpers import box_part, job_dict
from rotoprint.errors import ConfigError
from rotoprint.io.images import read_grey_image
from rotoprint.process import parse_job
from rotoprint.pipeline.examples import write_example
from rotoprint.rotary.files import read_print


def test_build_cli_writes_plan_images_and_report(gas_build):
    # gas_build: the session's `rotoprint build` of the gas sensor (tests/conftest.py)
    code, out = gas_build.code, gas_build.out
    assert code == 0, gas_build.stderr
    plan = json.loads((out / "plan.json").read_text())
    assert plan["format"] == "rotoprint-build-plan" and plan["layers"] == len(plan["layers_detail"]) == 10
    assert plan["material_order"] == ["plaster", "silver", "polyamide"]
    assert (out / "report.html").stat().st_size > 10_000
    n_images = 0
    for L in plan["layers_detail"]:
        for im in L["images"]:
            for s in im["swathes"]:
                data = (out / s["file"]).read_bytes()
                assert hashlib.sha256(data).hexdigest() == s["sha256"]
                n_images += 1
            pr, side, _ = read_print(out / im["sidecar"])  # readable by rotoprint simulate
            assert pr.mount_angle_deg == im["mount_angle_deg"]
    assert n_images >= 10 * 2
    # the combs do not touch: open; comb A from its pad to its farthest finger conducts
    r_open, r_comb = plan["resistance"]
    assert r_open["design"]["resistance_ohm"] is None and not r_open["design"]["connected"]
    assert r_comb["design"]["connected"] and 0 < r_comb["design"]["resistance_ohm"] < 1e6
    assert plan["interdigitated"]["electrode"]["cell_constant_per_mm"] == pytest.approx(0.3 / (8.0 * 15))
    assert all(c["ok"] for c in plan["printability"])
    assert plan["overlays"] and all((out / o["file"]).exists() for o in plan["overlays"])
    # the deposit model's film is the headline of every overlay (issue 14)
    for o in plan["overlays"]:
        f = o["deposit"]
        assert 0 <= f["uncovered_fraction"] <= 1 and abs(f["volume_error_fraction"]) < 0.005 and f["footprint_um"] > 0


def test_build_cli_layer_images_are_binary_drops(gas_build):
    out = gas_build.out
    plan = json.loads((out / "plan.json").read_text())
    s = plan["layers_detail"][6]["images"][0]["swathes"][0]
    img = read_grey_image(out / s["file"])
    assert img.shape[1] == 764 and set(np.unique(img).tolist()) <= {0, 255}
    assert int((img > 0).sum()) == s["drops"]


def test_build_demo_builds_the_coil_and_says_where_the_report_is(coil_demo):
    # coil_demo: the session's `rotoprint demo --out DIR` (tests/conftest.py)
    code, out, err = coil_demo.code, coil_demo.stdout, coil_demo.stderr
    assert code == 0, err
    rep = coil_demo.out / "report.html"
    assert rep.is_file() and f"report: {rep.resolve()}" in out.replace("\n", "")
    plan = json.loads((coil_demo.out / "plan.json").read_text())
    (r,) = plan["resistance"]
    hand = r["hand_check"]["resistance_ohm"]
    assert r["design"]["resistance_ohm"] == pytest.approx(hand, rel=0.01)
    assert r["printed"]["resistance_ohm"] == pytest.approx(hand, rel=0.15)
    assert any("crystallises" in w for w in plan["warnings"])
    # not a terminal: a line as each stage ends, never a silent build (rich's bar is off here)
    for stage in ("plan", "check", "layers", "simulate", "resistance", "report"):
        assert re.search(rf"^  {stage}: \d+ steps? in \d+\.\d s$", err, re.M), (stage, err[:400])


@pytest.mark.parametrize(
    "change, where",
    [
        (lambda d: d["parts"][0].update(material="silvr"), "parts[0].material: unknown material 'silvr'"),
        (lambda d: d["job"].pop("layer_height_mm"), "job.layer_height_mm is missing (it is required)"),
        (lambda d: d["job"].update(layer_height_mm=-1), "job.layer_height_mm must be at least 0.0001, got -1"),
        (lambda d: d["printer"]["heads"].pop(1), "no head carries the ink 'calcium_chloride'"),
        (lambda d: d["parts"][1].update(priority=1), "parts[1].priority: 1 is also the priority of a 'plaster' part"),
        (lambda d: d["parts"][0].update(mesh="x.stl"), "parts[0]: give exactly one of"),
        (lambda d: d["parts"][0]["shape"].update(size_mm=[1, 0, 1]), "parts[0].shape.box: size_mm"),
        (lambda d: d.update(resistance=[{"part": "body", "between": ["a", "b"]}]), "resistance[0].part: 'body' is plaster"),
        (lambda d: d.update(resistance=[{"part": "pad", "between": ["a", "b"]}]), "resistance[0].between: part 'pad' has no terminal 'a'"),
        (lambda d: d["printer"].update(tilt_deg=89.0), "printer.tilt_deg: tilt 89 deg is at or beyond the maximum"),
        (lambda d: d.update(extra={"x": 1}), "extra is not a known field (a misspelt name?)"),
        (lambda d: d["printer"].update(clock={"dpi_y": 1e-6}), "printer.clock.dpi_y: must be 25 to 100000 drops per inch"),
        (lambda d: d["printer"].update(clock={"dpi_y": 2e5}), "printer.clock.dpi_y: must be 25 to 100000 drops per inch"),
        (lambda d: d["printer"].update(clock={"frequency_hz": 1e7}), "printer.clock.frequency_hz must be at most 1000000.0, got 10000000.0"),
        (lambda d: d["placement"].update(inner_radius_mm=float("inf")), "placement.inner_radius_mm must be a finite number, got inf"),
        (lambda d: d["placement"].update(inner_radius_mm=float("nan")), "placement.inner_radius_mm must be a finite number, got nan"),
        (lambda d: d["placement"].update(angle_deg=float("inf")), "placement.angle_deg must be a finite number, got inf"),
    ],
)
def test_build_job_errors_name_the_field(change, where):
    d = job_dict([box_part("body", "plaster", 1, (6, 4, 0.1)), box_part("pad", "silver", 2, (2, 2, 0.05))])
    change(d)
    with pytest.raises(ConfigError) as ei:
        from rotoprint.process import plan_job

        plan_job(parse_job(d, source="job.toml"))
    assert where in str(ei.value) and "job.toml" in str(ei.value)


@pytest.mark.parametrize(
    "change, line",
    [
        (lambda d: d["job"].update(layer_height_mm="thin"), "job.layer_height_mm must be a number, got 'thin'"),
        (lambda d: d["printer"].update(equalise="sometimes"), "printer.equalise must be true or false, got 'sometimes'"),
        (lambda d: d["printer"].update(direction=1.5), "printer.direction must be a whole number, got 1.5"),
        (lambda d: d["parts"][0].update(name=7), "parts[0].name must be a text string, got 7"),
        (lambda d: d["parts"][1].update(priority=[2]), "parts[1].priority must be a whole number, got a list of 1"),
        (lambda d: d.update(placement=60.0), "placement must be a table, got a number"),
        (lambda d: d.update(process={"order": "plaster"}), "process.order must be a list, got a text string"),
    ],
)
def test_build_job_wrong_types_are_one_line_in_words(change, line):
    # pydantic's own text ("Input should be a valid number, unable to parse ...") never reaches the user
    d = job_dict([box_part("body", "plaster", 1, (6, 4, 0.1)), box_part("pad", "silver", 2, (2, 2, 0.05))])
    change(d)
    with pytest.raises(ConfigError) as ei:
        parse_job(d, source="job.toml")
    msg = str(ei.value)
    assert msg.startswith("job.toml: ") and line in msg and "\n" not in msg, msg
    for raw in ("Input should", "Field required", "Extra inputs", "unable to parse", "valid "):
        assert raw not in msg, msg


def test_build_cli_wrong_typed_field_is_one_line_in_words(run_cli, tmp_path):
    job = tmp_path / "typed.toml"
    job.write_text('[job]\nlayer_height_mm = "thin"\n[printer]\nheads = [{name = "A", ink = "ammonium_sulphate"}, '
                   '{name = "B", ink = "calcium_chloride"}]\n[placement]\ninner_radius_mm = 60\n[[parts]]\nname = "p"\n'
                   'material = "plaster"\nshape = { kind = "box", size_mm = [2, 2, 0.1] }\n')
    out = tmp_path / "out"
    code, so, err = run_cli("build", job, "--out", out)
    lines = [x for x in err.strip().splitlines() if x.strip()]
    assert code == 2 and not out.exists() and len(lines) == 1, err
    assert str(job) in lines[0] and "job.layer_height_mm must be a number, got 'thin'" in lines[0], err
    assert "Input should" not in err and "Traceback" not in err


def test_build_cli_bad_job_exit_2_one_line_nothing_written(run_cli, tmp_path):
    job = tmp_path / "bad.toml"
    job.write_text('[job]\nlayer_height_mm = 0.05\n[printer]\nheads = [{name = "A", ink = "ammonium_sulphate"}, {name = "B", ink = "calcium_chloride"}]\n'
                   '[placement]\ninner_radius_mm = 60\n[[parts]]\nname = "p"\nmaterial = "plaster"\nmesh = "missing.stl"\n')
    out = tmp_path / "out"
    code, so, err = run_cli("build", job, "--out", out)
    assert code == 2 and not out.exists()
    lines = [x for x in err.strip().splitlines() if x.strip()]
    assert len(lines) == 1 and "missing.stl" in lines[0], err
    job.write_text("[job\n")
    code, so, err = run_cli("build", job, "--out", out)
    assert code == 2 and "not valid TOML" in err and str(job) in err and not out.exists()
    code, so, err = run_cli("build", tmp_path / "nope.toml", "--out", out)
    assert code == 2 and "no such job file" in err
    assert [p.name for p in tmp_path.iterdir()] == ["bad.toml"]
