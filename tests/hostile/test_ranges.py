"""Hostile numbers: every numeric input is range-checked where it enters (CLI option, device,
job, materials file, sidecar, environment), and a value that parses but is out of range is one
line on stderr naming the option or field, exit 2, no traceback, nothing written.

The CLI sweep is generated from the commands themselves: every int or float option of every
subcommand is given values no documented range admits (:mod:`rotoprint.ranges`), so an option
added later without a range check fails here.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotoprint import ranges as R
from rotoprint.errors import ConfigError

OUT_OF_EVERY_RANGE = ["nan", "inf", "-inf", "1e300", str(2**63)]

# a valid command line per subcommand, the swept option appended last (click lets it override)
BASE = {
    "info": ["info", "box.stl"],
    "slice": ["slice", "box.stl", "-d", "omnidot760", "--layer-height", "0.5", "-o", "out", "-q", "--rotary", "--tilt", "30", "--radius", "50"],
    "dlp": ["dlp", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", "out", "-q"],
    "check": ["check", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.5", "-q"],
    "head": ["head", "-d", "omnidot760"],
    "transform": ["transform", "d.png", "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", "p.png", "-q"],
    "simulate": ["simulate", "pr/p.png", "-o", "ov.png"],
    # build and replay: the swept value is refused while the options are parsed, before the
    # job or the program is looked at
    "build": ["build", "job.toml", "--out", "bout", "--no-report"],
    "replay": ["replay", "bout/machine/program.json", "-o", "ov.png"],
}


def _write_box(path: Path, size=(4.0, 4.0, 2.0)) -> None:
    from rotoprint.testing import box_triangles

    tri = box_triangles(size).astype(np.float32)
    rec = np.zeros(len(tri), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["v"] = tri
    path.write_bytes(b"\0" * 80 + np.uint32(len(tri)).tobytes() + rec.tobytes())


def _write_design(path: Path) -> None:
    from PIL import Image

    d = np.zeros((40, 60), np.uint8)
    d[5:35, 10:50] = 255
    Image.fromarray(d).save(path)


@pytest.fixture(scope="module")
def inputs(tmp_path_factory) -> Path:
    """box.stl, d.png and pr/p.png + pr/p.json (a small print made by transform)."""
    from rotoprint.cli.main import main

    base = tmp_path_factory.mktemp("hostile_inputs")
    _write_box(base / "box.stl")
    _write_design(base / "d.png")
    (base / "pr").mkdir()
    code = main(["transform", str(base / "d.png"), "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", str(base / "pr" / "p.png"), "-q"])
    assert code == 0
    return base


@pytest.fixture
def work(inputs, tmp_path, monkeypatch) -> Path:
    """A fresh folder holding links to the inputs, made the working directory."""
    for name in ("box.stl", "d.png"):
        (tmp_path / name).symlink_to(inputs / name)
    (tmp_path / "pr").mkdir()
    for f in (inputs / "pr").iterdir():
        (tmp_path / "pr" / f.name).write_bytes(f.read_bytes())
    monkeypatch.chdir(tmp_path)
    return tmp_path


def _tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() else b"") for p in sorted(folder.rglob("*"))}


def _refused(run_cli, folder: Path, argv: list[str], *names: str) -> str:
    """Run argv in-process; assert exit 2, one line naming ``names``, no traceback, nothing written."""
    before = _tree(folder)
    code, out, err = run_cli(*argv)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert code == 2, (argv, code, err)
    assert len(lines) == 1 and "Traceback" not in err, err
    for n in names:
        assert n in err, (n, err)
    assert _tree(folder) == before, "something was written"
    return lines[0]


def _numeric_options() -> list[tuple[str, str, str]]:
    """(subcommand, option, click type name) for every int/float option of every subcommand."""
    import typer

    from rotoprint.cli.main import app

    group = typer.main.get_command(app)
    found = []
    for name, cmd in sorted(group.commands.items()):
        for p in cmd.params:
            ann = getattr(getattr(p, "type_descriptor", None), "annotation", None)
            if p.param_type_name == "option" and ann in (int, float):
                found.append((name, [o for o in p.opts if o.startswith("--")][0], ann.__name__))
    return found


NUMERIC = _numeric_options()


def test_the_sweep_finds_the_options():
    opts = {(c, o) for c, o, _ in NUMERIC}
    assert ("check", "--min-wall") in opts and ("simulate", "--seed") in opts and ("transform", "--design-dpi") in opts
    assert len(opts) >= 40


@pytest.mark.parametrize("value", OUT_OF_EVERY_RANGE)
@pytest.mark.parametrize("command,option,kind", NUMERIC, ids=[f"{c}{o}" for c, o, _ in NUMERIC])
def test_every_numeric_option_refuses_values_out_of_every_range(run_cli, work, command, option, kind, value):
    if command not in BASE:
        pytest.skip(f"no base command line for {command!r} (it has no numeric option to sweep)")
    _refused(run_cli, work, [*BASE[command], option, value], option)


# the examples of issue 12, and the values just past each documented range
@pytest.mark.parametrize(
    "argv,names",
    [
        (["check", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.1", "--min-wall", "1e19"], ["--min-wall", "[0.0001, 100] mm", "1e+19"]),
        (["check", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.1", "--min-gap", "101"], ["--min-gap"]),
        (["check", "box.stl", "-d", "perfactory-sxga", "--layer-height", "1e300"], ["--layer-height"]),
        (BASE["slice"] + ["--angle", "1e300"], ["--angle"]),
        (BASE["slice"] + ["--dpi-y", "1e-6"], ["--dpi-y"]),
        (BASE["slice"] + ["--direction", "0"], ["--direction"]),
        (BASE["slice"] + ["--translate", "1e300,0,0"], ["--translate X"]),
        (BASE["dlp"] + ["--translate", "0,0,10001"], ["--translate Z"]),
        (BASE["dlp"] + ["--rotate", "0,1e300,0"], ["--rotate Y"]),
        (BASE["dlp"] + ["--offset", "nan,0"], ["--offset"]),
        (BASE["dlp"] + ["--scale", "0"], ["--scale"]),
        (BASE["dlp"] + ["--scale", "1e-300"], ["--scale"]),
        (BASE["head"] + ["--tilt-range", "nan:80:10"], ["--tilt-range"]),
        (BASE["head"] + ["--tilt-range", "0:inf:10"], ["--tilt-range"]),
        (BASE["head"] + ["--tilt-range", "0:80:1e-300"], ["--tilt-range"]),
        (BASE["check"] + ["--orientations", "0:1e300:1e290"], ["--orientations"]),
        (BASE["transform"] + ["--design-dpi", "1e9"], ["--design-dpi"]),
        (BASE["transform"] + ["--angle", "1e300"], ["--angle"]),
        (BASE["transform"] + ["--method", "paper", "--dpi-y", "1e300"], ["--dpi-y"]),
        (BASE["simulate"] + ["--seed", "-1"], ["--seed"]),
        (BASE["simulate"] + ["--scale", "17"], ["--scale"]),
        (BASE["simulate"] + ["--drop-diameter", "1e5"], ["--drop-diameter"]),
        (BASE["simulate"] + ["--dead", str(2**63)], ["--dead"]),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) and len(v) > 2 else None,
)
def test_issue_examples_are_one_line_exit_2(run_cli, work, argv, names):
    _refused(run_cli, work, argv, *names)


def test_values_inside_the_ranges_still_work(run_cli, work):
    assert run_cli(*BASE["check"], "--min-wall", "0.5", "--min-gap", "0.5", "--gap-radius", "0")[0] in (0, 3)
    assert run_cli(*BASE["head"], "--tilt-range", "-10:10:5", "--radius", "1e4")[0] == 0
    assert run_cli(*BASE["info"], "--scale", "-1", "--translate", "-9000,0,0")[0] == 0  # a mirror, far out


def test_mesh_coordinates_beyond_the_range_are_refused(run_cli, work):
    _write_box(work / "far.stl", size=(1.0, 1.0, 1.0))
    line = _refused(run_cli, work, ["info", "far.stl", "--translate", "9999.5,0,0"], "far.stl", "10000")
    assert "--translate" in line
    _refused(run_cli, work, ["info", "box.stl", "--units", "m", "--scale", "1000"], "box.stl")


# ------------------------------------------------------------------ the range table itself


def test_check_range_names_the_field_and_refuses_non_numbers():
    assert R.check_range(3, R.COUNT, "n") == 3 and isinstance(R.check_range(3.0, R.COUNT, "n"), int)
    for bad in (True, "1", None, float("nan"), 2**1100, 1.5):
        with pytest.raises(ConfigError, match="^n must be an integer"):
            R.check_range(bad, R.COUNT, "n")
    with pytest.raises(ConfigError, match=r"tilt must be in \(-90, 90\) deg, got 90"):
        R.check_range(90.0, R.TILT_DEG, "tilt")
    with pytest.raises(ConfigError, match="would be 1e\\+30, more than"):
        R.check_count(1e30, "the firings")
    with pytest.raises(ConfigError):
        R.check_count(float("inf"), "the firings")


def test_every_range_is_finite_and_ordered():
    rngs = [v for v in vars(R).values() if isinstance(v, R.Range)]
    assert len(rngs) >= 20
    for r in rngs:
        assert np.isfinite([r.lo, r.hi]).all() and r.lo < r.hi and abs(r.hi) < 2**40
    names = {k for k, v in vars(R).items() if isinstance(v, R.Range)}
    for k in names - {"DIRECTION", "NOZZLE_INDEX"}:
        assert f"``{k}``" in R.__doc__, f"{k} is not in the documented table"


# ------------------------------------------------------------------ files: device, sidecar, job, materials


def _sidecar_refused(run_cli, work, edit, *names):
    sp = work / "pr" / "p.json"
    side = json.loads(sp.read_text())
    edit(side)
    sp.write_text(json.dumps(side))
    return _refused(run_cli, work, ["simulate", "pr/p.png", "-o", "ov.png"], "p.json", *names)


@pytest.mark.parametrize(
    "edit,names",
    [
        (lambda s: s["swathes"][0].__setitem__("first_firing_index", 1e30), ["first_firing_index"]),
        (lambda s: s["swathes"][0].__setitem__("first_firing_index", 2**63), ["first_firing_index"]),
        (lambda s: s["swathes"][0].__setitem__("first_firing_index", 0.5), ["first_firing_index"]),
        (lambda s: s["swathes"][0].__setitem__("enabled_nozzle_runs", [[0, 100000]]), ["enabled_nozzle_runs"]),
        (lambda s: s["swathes"][0].__setitem__("enabled_nozzle_runs", [[-5, 3]]), ["enabled_nozzle_runs"]),
        (lambda s: s["swathes"][0].__setitem__("firings", 2**62), ["firings"]),
        (lambda s: s["swathes"][0].__setitem__("nozzles", 10**9), ["nozzles"]),
        (lambda s: s["swathes"][0].__setitem__("pivot_radius_mm", 1e300), ["pivot_radius_mm"]),
        (lambda s: s.__setitem__("dpi_y", 1e-6), ["dpi_y"]),
        (lambda s: s.__setitem__("mount_angle_deg", 1e300), ["mount_angle_deg"]),
        (lambda s: s["head"].__setitem__("dpi_y", 1e6), ["head.dpi_y"]),
        (lambda s: s["head"].__setitem__("drop_diameter_um", 1e9), ["head.drop_diameter_um"]),
    ],
)
def test_sidecar_numbers_out_of_range(run_cli, work, edit, names):
    _sidecar_refused(run_cli, work, edit, *names)


def test_deeply_nested_json_and_toml_are_one_line(run_cli, work):
    depth = 200_000
    (work / "pr" / "p.json").write_text("[" * depth + "]" * depth)
    _refused(run_cli, work, ["simulate", "pr/p.png", "-o", "ov.png"], "p.json")
    (work / "dev.toml").write_text("a = " + "[" * depth + "]" * depth + "\n")
    _refused(run_cli, work, ["head", "-d", "dev.toml"], "dev.toml")
    (work / "job.toml").write_text("x = " + "{a = " * 50_000 + "1" + "}" * 50_000 + "\n")
    _refused(run_cli, work, ["build", "job.toml", "-o", "b"], "job.toml")


def _device_toml(**head) -> str:
    fields = {"nozzles": 764, "rows": 2, "swathe_mm": 54.1, "row_separation_mm": 4.0, **head}
    body = "\n".join(f"{k} = {v}" for k, v in fields.items())
    return f'kind = "inkjet"\nname = "x"\n[head]\n{body}\n'


@pytest.mark.parametrize("field,value", [("dpi_y", "1e-300"), ("dpi_y", "inf"), ("swathe_mm", "1e300"), ("drop_diameter_um", "1e30"),
                                         ("max_frequency_hz", "nan"), ("nozzles", str(2**63))])
def test_device_fields_out_of_range(run_cli, work, field, value):
    (work / "dev.toml").write_text(_device_toml(**{field: value}))
    _refused(run_cli, work, ["check", "-d", "dev.toml"], "dev.toml", field)


@pytest.fixture
def job_text(work) -> str:
    from rotoprint.pipeline.examples import write_example

    return write_example("gas-sensor", work / "ex").read_text()


@pytest.mark.parametrize(
    "old,new,names",
    [
        ("cycles_per_layer = { silver = 24 }", f"cycles_per_layer = {{ silver = {2**63 - 1} }}", ["cycles_per_layer"]),
        ("inner_radius_mm = 70.0", "inner_radius_mm = 1e300", ["inner_radius_mm"]),
        ("\nangle_deg = 0.0", "\nangle_deg = inf", ["placement.angle_deg"]),
        ("mount_angle_deg = 60.0", "mount_angle_deg = 1e300", ["mount_angle_deg"]),
        ("size_mm = [14.0, 14.0, 0.1]", "size_mm = [1e300, 14.0, 0.1]", ["size_mm[0]", "10000"]),
        ("origin_mm = [-2.0, -2.0, 0.0]", "origin_mm = [-2.0, -2.0, inf]", ["origin_mm[2]"]),
        ("tilt_deg = 20.0", "tilt_deg = nan", ["tilt_deg"]),
    ],
)
def test_job_values_out_of_range(run_cli, work, job_text, old, new, names):
    assert old in job_text
    (work / "ex" / "job.toml").write_text(job_text.replace(old, new, 1))
    _refused(run_cli, work, ["build", "ex/job.toml", "-o", "b"], "job.toml", *names)


@pytest.mark.parametrize("value", ["inf", "nan", "1e300"])
def test_materials_file_with_inf(work, value):
    from rotoprint.process.materials import builtin_library, load_materials

    text = (f'[materials.foo]\ninks = [{{ name = "silver_nitrate", reactant = "AgNO3", concentration_mol_per_l = 1.0, '
            f'wait_after_s = {value} }}]\n')
    (work / "m.toml").write_text(text)
    with pytest.raises(ConfigError, match="m.toml.*wait_after_s"):
        load_materials(work / "m.toml", base=builtin_library())


@pytest.mark.parametrize("epoch", ["abc", "1e30", str(10**20), "-5", "253402300800"])
def test_source_date_epoch_is_checked_before_any_work(run_cli, work, monkeypatch, epoch):
    monkeypatch.setenv("SOURCE_DATE_EPOCH", epoch)
    _refused(run_cli, work, ["dlp", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", "job.sl1", "-q"], "SOURCE_DATE_EPOCH")


# ------------------------------------------------------------------ a PLY header that lies


def test_ply_header_declaring_more_faces_than_it_holds(run_cli, work):
    body = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 2 3\n3 1 2 3\n"
    head = ("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "element face {n}\nproperty list uchar int vertex_indices\nend_header\n")
    (work / "lie.ply").write_text(head.format(n=100_000) + body)
    _refused(run_cli, work, ["info", "lie.ply"], "lie.ply", "100000 face")
    (work / "ok.ply").write_text(head.format(n=4) + body)
    assert run_cli("info", "ok.ply")[0] == 0


def test_binary_ply_header_declaring_more_faces_than_it_holds(run_cli, work):
    import trimesh

    trimesh.creation.box().export(work / "b.ply", encoding="binary")
    data = (work / "b.ply").read_bytes()
    assert b"element face 12\n" in data
    (work / "lie.ply").write_bytes(data.replace(b"element face 12\n", b"element face 1000000\n"))
    _refused(run_cli, work, ["info", "lie.ply"], "lie.ply", "1000000 face")
    assert run_cli("info", "b.ply")[0] == 0


def test_off_header_declaring_more_faces_than_it_holds(run_cli, work):
    body = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 2 3\n3 1 2 3\n"
    (work / "lie.off").write_text("OFF\n# a comment\n4 100000 0\n" + body)
    _refused(run_cli, work, ["info", "lie.off"], "lie.off", "100000 faces")
    (work / "lie1.off").write_text("OFF 40 4 0\n" + body)  # counts on the keyword's line
    _refused(run_cli, work, ["info", "lie1.off"], "lie1.off", "40 vertices")
    (work / "ok.off").write_text("OFF\n4 4 0\n" + body)
    assert run_cli("info", "ok.off")[0] == 0


# ------------------------------------------------------------------ the segfault, in a child process


def _limit_child():  # pragma: no cover - runs in the child
    with open("/proc/self/statm") as fh:
        mapped = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    lim = mapped + (1 << 30)
    resource.setrlimit(resource.RLIMIT_AS, (lim, lim))


def test_min_wall_1e19_is_refused_not_a_segfault(work):
    """Issue 12: SIGSEGV, exit 139. In a child with 1 GiB of address space and 60 s."""
    argv = [sys.executable, "-m", "rotoprint.cli.main", "check", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.1", "--min-wall", "1e19"]
    r = subprocess.run(argv, capture_output=True, text=True, timeout=60, preexec_fn=_limit_child, cwd=work)
    assert r.returncode == 2, r
    assert r.stderr.count("\n") == 1 and "--min-wall" in r.stderr and "Traceback" not in r.stderr
    assert sorted(p.name for p in work.iterdir()) == ["box.stl", "d.png", "pr"]


def test_check_kernel_widths_bounded_in_the_library():
    from rotoprint.check import check_printability
    from rotoprint.devices import load_device
    from rotoprint.slicing import slice_mesh
    from rotoprint.testing import box_mesh

    dev = load_device("perfactory-sxga")
    job = slice_mesh(box_mesh((2.0, 2.0, 0.2)), dev, layer_height_mm=0.1)
    with pytest.raises(ConfigError, match="min_wall_mm must be in"):
        check_printability(job, dev, min_wall_mm=1e19)
    with pytest.raises(ConfigError, match="measure_up_to_mm"):
        check_printability(job, dev, measure_up_to_mm=1e300)


def test_check_kernel_cell_indices_clamp_before_the_int_conversion():
    """The kernels' cell lookups stay in the grid for any pad, even past int64 (was: a wrapped
    index and SIGSEGV)."""
    from rotoprint.check._kernels.grid import _cell_index, _span

    assert _span(0.0, 0.0, 1.0, 1.0, 0, 0.0, 0.0, 0.1, 10, 1e19) == (0, 9)
    assert _span(0.25, 0.0, 0.55, 0.0, 0, 0.0, 0.0, 0.1, 10, 0.0) == (2, 5)
    assert _cell_index(float("nan"), 7) == 0
    assert _cell_index(-1e300, 7) == 0 and _cell_index(1e300, 7) == 6 and _cell_index(3.7, 7) == 3
