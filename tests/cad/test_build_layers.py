"""Layer parts in a build: a Gerber coil gives the built-in square coil's drops and
resistance; the bundled two-layer CAD example builds and reports each layer's material."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rotoprint.process import parse_job
from rotoprint.pipeline import run_build
from rotoprint.process.cad_examples import CAD_COIL, gerber_coil
from rotoprint.process.plan import plan_job

SILVER_JOB = """
[job]
name = "coil"
layer_height_mm = 0.02
[printer]
device = "omnidot760"
tilt_deg = 20.0
equalise = true
[printer.clock]
dpi_y = 360.0
[[printer.heads]]
name = "H3"
ink = "silver_nitrate"
mount_angle_deg = 0.0
[[printer.heads]]
name = "H4"
ink = "ascorbate"
mount_angle_deg = 90.0
[placement]
inner_radius_mm = 60.0
[[parts]]
name = "coil"
material = "silver"
priority = 3
{source}
[process]
cycles_per_layer = {{ silver = 30 }}
simulate_layers = 0
check = false
[[resistance]]
part = "coil"
between = [{terms}]
"""


def _job(tmp_path, source, terms):
    import tomllib

    return parse_job(tomllib.loads(SILVER_JOB.format(source=source, terms=terms)), base_dir=tmp_path, source="job.toml")


#: the built-in square coil of CAD_COIL's dimensions, as a job's shape
SQUARE_SHAPE = (f'shape = {{ kind = "square_coil", outer_mm = {CAD_COIL.outer_mm}, track_width_mm = {CAD_COIL.track_width_mm}, '
                f"gap_mm = {CAD_COIL.gap_mm}, turns = {CAD_COIL.turns}, height_mm = 0.04 }}")


@pytest.fixture(scope="module")
def square_coil_ohm(tmp_path_factory):
    """The built-in square coil's resistance from its build (shared by the two tests below)."""
    root = tmp_path_factory.mktemp("square")
    res = run_build(_job(root, SQUARE_SHAPE, '"outer", "inner"'), root / "a", report=False)
    return res.summary["resistance"][0]["design"]["resistance_ohm"]


def test_gerber_coil_same_drops_and_resistance_as_square_coil(tmp_path, square_coil_ohm):
    (tmp_path / "coil.gbr").write_text(gerber_coil(CAD_COIL, track="region"))
    a = _job(tmp_path, SQUARE_SHAPE, '"outer", "inner"')
    b = _job(tmp_path, 'layer = { file = "coil.gbr", z_mm = [0.0, 0.04] }', '"COIL_OUT", "COIL_IN"')
    pa, pb = plan_job(a), plan_job(b)
    assert len(pa) == len(pb) == 2
    assert pa.placement == pb.placement
    for i in range(len(pa)):
        la, lb = pa.layer(i), pb.layer(i)
        assert la.images.keys() == lb.images.keys()
        for k in la.images:
            for sa, sb in zip(la.images[k].swathes, lb.images[k].swathes):
                assert np.count_nonzero(sa.levels) > 1000
                np.testing.assert_array_equal(sa.levels, sb.levels)
    ra = square_coil_ohm
    rb = run_build(b, tmp_path / "b", report=False).summary["resistance"][0]["design"]["resistance_ohm"]
    assert rb == pytest.approx(ra, rel=0.005)
    print(f"square_coil {ra:.2f} ohm, Gerber region coil {rb:.2f} ohm")


def test_round_aperture_coil_differs_only_at_corners(tmp_path, square_coil_ohm):
    """KiCad-style draws (round aperture) round the outer corners: drops differ only within
    the corner radius of the centreline's corners, and the resistance within 0.5 %."""
    (tmp_path / "coil.gbr").write_text(gerber_coil(CAD_COIL, track="draw"))
    sh = CAD_COIL
    a = _job(tmp_path, SQUARE_SHAPE, '"outer", "inner"')
    b = _job(tmp_path, 'layer = { file = "coil.gbr", z_mm = [0.0, 0.04], tolerance_mm = 0.002 }', '"COIL_OUT", "COIL_IN"')
    pa, pb = plan_job(a), plan_job(b)
    ga, gb = pa.design_grid(oversample=2), pb.design_grid(oversample=2)
    ma = pa.reference_image("silver", pa.sections(0), oversample=2)
    mb = pb.reference_image("silver", pb.sections(0), oversample=2)
    assert ga == gb
    diff = ma ^ mb
    from rotoprint.process.conductance import pixel_centres_model

    x, y = pixel_centres_model(ga, pa.placement)
    rr, cc = np.nonzero(diff)
    corners = sh.centreline()[1:-1]
    d = np.min(np.hypot(x[cc][:, None] - corners[None, :, 0], y[rr][:, None] - corners[None, :, 1]), axis=1)
    assert d.max() <= sh.track_width_mm / 2 * np.sqrt(2) + ga.pitch_x_mm
    ra = square_coil_ohm
    rb = run_build(b, tmp_path / "b", report=False).summary["resistance"][0]["design"]["resistance_ohm"]
    assert rb == pytest.approx(ra, rel=0.005)
    print(f"square_coil {ra:.2f} ohm, round-aperture Gerber coil {rb:.2f} ohm, {diff.sum()} pixels differ")


def test_bundled_cad_example_two_layers_build_and_report(tmp_path, run_cli):
    """Silver coil (Gerber) on a plaster body (DXF outline) with silver vias through the drill
    holes: builds; plan.json and the report list each layer part with its material."""
    from rotoprint.pipeline.examples import write_example

    job = write_example("cad-coil", tmp_path / "ex")
    code, out, err = run_cli("build", job, "--out", tmp_path / "build", "--no-check")
    assert code == 0, err
    plan = json.loads((tmp_path / "build" / "plan.json").read_text())
    parts = {lp["part"]: lp for lp in plan["layer_parts"]}
    assert {k: v["material"] for k, v in parts.items()} == {"body": "plaster", "vias": "silver", "coil": "silver"}
    assert parts["body"]["holes"] == 2 and parts["body"]["holes_from"] == ["coil-vias.drl"]
    assert parts["coil"]["terminals"] == ["COIL_IN", "COIL_OUT", "L1.1", "L1.2"]
    # the via holes in the body are printed with silver, not plaster: layer 0 has both
    l0 = {b["material"] for b in plan["layers_detail"][0]["blocks"]}
    assert l0 == {"plaster", "silver"}
    html = (tmp_path / "build" / "report.html").read_text()
    table = html[html.index("id='cad-layers'"):]
    table = table[: table.index("</table>")]
    for part, mat in (("body", "plaster"), ("vias", "silver"), ("coil", "silver")):
        assert f"<td>{part}</td>" in table and mat in table
    r = plan["resistance"][0]
    # one 20 um layer of 24 cycles at the pass plan's clock: about 2.5 um of silver, 2.8 ohm/sq, about 470 squares
    assert r["between"] == ["COIL_OUT", "COIL_IN"] and 900 < r["design"]["resistance_ohm"] < 2000


def test_layer_part_bad_terminal_and_file_one_line(tmp_path, run_cli):
    from rotoprint.pipeline.examples import write_example

    job = write_example("cad-coil", tmp_path / "ex")
    text = job.read_text()
    job.write_text(text.replace('between = ["COIL_OUT", "COIL_IN"]', 'between = ["COIL_OUT", "GND"]'))
    code, out, err = run_cli("build", job, "--out", tmp_path / "b1", "--no-check")
    assert code == 2 and "no terminal 'GND'" in err and "COIL_IN" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "b1").exists()
    (tmp_path / "ex" / "coil-F_Cu.gbr").write_text("%FSLAX46Y46*%\n%MOMM*%\nD13*\nX0Y0D03*\nM02*\n")
    job.write_text(text)
    code, out, err = run_cli("build", job, "--out", tmp_path / "b2", "--no-check")
    assert code == 2 and "coil-F_Cu.gbr" in err and "undefined aperture 13" in err, err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "b2").exists()
    job.write_text(text.replace('z_mm = [0.12, 0.16], tolerance_mm', 'z_mm = [0.12, 0.16], units = "kg", tolerance_mm'))
    code, out, err = run_cli("build", job, "--out", tmp_path / "b3", "--no-check")
    assert code == 2 and "not a length unit" in err and len(err.strip().splitlines()) == 1, err


def test_cad_example_files_are_reproducible(tmp_path):
    """The example script writes the same bytes every time (the DXF has no time stamps), so a
    second run over an earlier copy is accepted as unchanged."""
    import time

    from rotoprint.pipeline.examples import write_example
    from rotoprint.process.examples import example_files

    a = example_files("cad-coil")
    time.sleep(1.1)
    assert example_files("cad-coil") == a
    write_example("cad-coil", tmp_path / "ex")
    write_example("cad-coil", tmp_path / "ex")  # no overwrite needed: nothing changed
    assert (tmp_path / "ex" / "coil-body.dxf").read_bytes() == a["coil-body.dxf"]


def test_point_terminals_in_the_job(tmp_path):
    """Terminals given as points: the conductor within terminal_radius_mm of each point."""
    (tmp_path / "coil.gbr").write_text(gerber_coil(CAD_COIL, track="region"))
    pads = CAD_COIL.terminals()
    (ox, oy), (ix, iy) = [((x0 + x1) / 2, (y0 + y1) / 2) for x0, y0, x1, y1 in (pads["outer"], pads["inner"])]
    src = (f'layer = {{ file = "coil.gbr", z_mm = [0.0, 0.04], terminal_radius_mm = 0.6, '
           f"terminals = {{ A = [{ox}, {oy}], B = [{ix}, {iy}] }} }}")
    b = _job(tmp_path, src, '"A", "B"')
    pads_job = _job(tmp_path, 'layer = { file = "coil.gbr", z_mm = [0.0, 0.04] }', '"COIL_OUT", "COIL_IN"')
    rb = run_build(b, tmp_path / "b", report=False).summary["resistance"][0]["design"]["resistance_ohm"]
    rp = run_build(pads_job, tmp_path / "p", report=False).summary["resistance"][0]["design"]["resistance_ohm"]
    # a disc of 0.6 mm inside the 1.2 mm pad: the pad's corners add a little spreading resistance
    assert rp < rb < rp * 1.02
    print(f"pads {rp:.2f} ohm, 0.6 mm point discs {rb:.2f} ohm")
    off = _job(tmp_path, 'layer = { file = "coil.gbr", z_mm = [0.0, 0.04], terminals = { A = [30, 30], B = [0, 0] } }',
               '"A", "B"')
    from rotoprint.errors import CadError

    with pytest.raises(CadError, match="terminal 'A' at \\(30, 30\\) mm is not on the layer"):
        plan_job(off)
