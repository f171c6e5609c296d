"""machine/ of a build: the program's steps and times, clocks, limits, and its replay.

The coil demo is built once for the session (tests/conftest.py coil_build): replay of its program at
the nominal angles must give the drops, IoU and coverage that ``simulate`` gives for the
build's own images (at the machine clock's angles: tests/machine/test_replay_clock.py)."""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pytest

from rotoprint.machine import clock_ratio
from rotoprint.machine.program import MachineOptions, write_machine_folder
from rotoprint.machine.replay import load_program, replay_layers, replay_program
from rotoprint.process import load_job, parse_job
from rotoprint.pipeline import run_build
from rotoprint.process.plan import plan_job
from rotoprint.rotary.printdata import clock_dphi
from rotoprint.rotary.simulate import simulate


@pytest.fixture(scope="module")
def coil(coil_build):
    """(job, plan.json, program.json) of the session's coil build (no printability check)."""
    assert coil_build.code == 0, coil_build.stderr
    plan = json.loads((coil_build.out / "plan.json").read_text())
    return load_job(coil_build.job), plan, coil_build.out / "machine" / "program.json"


def _small_job(**machine):
    return parse_job(_small_job_dict(**machine), base_dir=".", source="small.toml")


def _small_job_dict(**machine) -> dict:
    d = {
        "job": {"name": "small", "layer_height_mm": 0.05},
        "printer": {"device": "omnidot760", "tilt_deg": 20.0,
                    "heads": [{"name": "H1", "ink": "ammonium_sulphate"},
                              {"name": "H2", "ink": "calcium_chloride", "mount_angle_deg": 90.0}]},
        "placement": {"inner_radius_mm": 60.0},
        "parts": [{"name": "b", "material": "plaster", "priority": 1,
                   "shape": {"kind": "box", "size_mm": [3, 2, 0.1], "origin_mm": [0, 0, 0]}}],
        "process": {"cycles_per_layer": {"plaster": 1}},
    }
    if machine:
        d["machine"] = machine
    return d


def _same(a: dict, b: dict) -> None:
    assert a.keys() >= b.keys()
    for k, v in b.items():
        if isinstance(v, float):
            assert (math.isnan(v) and math.isnan(a[k])) or a[k] == pytest.approx(v, rel=1e-9, abs=1e-12), k
        else:
            assert a[k] == v, k


def _same_print(a, b) -> None:
    """Two RotaryPrints equal bit for bit: geometry, head and every swathe's levels."""
    assert (a.method, a.tilt_deg, a.mount_angle_deg, a.direction, a.dpi_y, a.placement, a.head) == \
        (b.method, b.tilt_deg, b.mount_angle_deg, b.direction, b.dpi_y, b.placement, b.head)
    assert len(a.swathes) == len(b.swathes)
    for x, y in zip(a.swathes, b.swathes):
        assert (x.index, x.first_firing, x.dphi_rad, x.pivot_radius_mm, x.ref_radius_mm, x.band_mm, x.enabled_nozzles) == \
            (y.index, y.first_firing, y.dphi_rad, y.pivot_radius_mm, y.ref_radius_mm, y.band_mm, y.enabled_nozzles)
        assert np.array_equal(x.levels, y.levels) and x.levels.dtype == y.levels.dtype
        assert (x.enabled is None and y.enabled is None) or np.array_equal(x.enabled, y.enabled)


def test_replay_of_the_coil_program_gives_simulates_figures_for_every_layer_and_head(coil):
    job, _, prog_path = coil
    plan = plan_job(job)
    # every image of every layer decodes to the build's own print and design, bit for bit
    # (so the replay simulates exactly what the build planned; its drops are the print's)
    layers_of: dict[frozenset, int] = {}  # the first layer of each set of (material, ink)
    n_images, decoded = 0, []
    for lay, imgs in replay_layers(load_program(prog_path), prog_path):
        i = lay["index"]
        sched, secs = plan.layer(i), plan.sections(i)
        assert len(imgs) == sum(len(prs) for prs in sched.pass_images.values()) > 0
        for im in imgs:
            pr = sched.pass_images[(im.material, im.ink)][im.interlace]
            _same_print(im.print, pr)
            assert np.array_equal(im.design, plan.reference_image(im.material, secs).astype(np.uint8) * 255)
            assert im.head == plan.head(im.ink).name
        n_images += len(imgs)
        decoded.append(i)
        layers_of.setdefault(frozenset(sched.pass_images), i)
    assert decoded == list(range(len(plan))) and n_images > 100
    # and simulate's figures for every image (every interlaced pass of every ink of every
    # material) of the first layer of each material set: the replay of the other layers
    # simulates the same decoded prints and designs, checked bit for bit above, with the same
    # function (the whole-program replay's totals: tests/machine/test_replay_clock.py)
    assert len(layers_of) >= 2
    seen = set()
    for i in sorted(layers_of.values()):
        rep = replay_program(prog_path, layer=i, angles="nominal")
        sched, secs = plan.layer(i), plan.sections(i)
        assert rep["replayed_layers"] == [i] and {r["layer"] for r in rep["images"]} == {i}
        assert len(rep["images"]) == sum(len(prs) for prs in sched.pass_images.values())
        for r in rep["images"]:
            m, ink, q = r["material"], r["ink"], r["interlace"]
            pr = sched.pass_images[(m, ink)][q]
            ref = plan.reference_image(m, secs).astype(np.uint8) * 255
            _same(r, simulate(pr, ref).report.to_json())
            assert r["drops"] == sum(int(np.count_nonzero(sw.levels)) for sw in pr.swathes)
            assert r["head"] == plan.head(ink).name
            seen.add((m, ink, q))
        assert rep["iou"] == min(r["iou"] for r in rep["images"])
        assert {r["interlace"] for r in rep["images"]} == set(range(plan.heads[0].passes))
    every = {(m, ink, q) for i in range(len(plan)) for (m, ink), prs in plan.layer(i).pass_images.items()
             for q in range(len(prs))}
    assert seen == every and len(seen) > 15
    assert {plan.head(ink).name for (_, ink, _) in seen} == {h.name for h in plan.heads}


def test_replay_with_the_deposit_model_gives_the_builds_film_figures(tmp_path):
    # a small box in 4 interlaced passes per ink (the coil's plaster layers' shape of a layer:
    # 2 inks x 4 passes), every image compared: the deposit model on the replayed drops gives
    # the film figures of deposit_film on simulate's drops of the plan's own print
    from rotoprint.rotary.deposit import deposit_film, ink_drops

    d = _small_job_dict()
    d["printer"]["passes"] = 4
    d["process"]["cycles_per_layer"] = {"plaster": 4}
    plan = plan_job(parse_job(d, base_dir=".", source="small.toml"))
    write_machine_folder(plan, tmp_path / "m")
    rep = replay_program(tmp_path / "m" / "program.json", layer=1, deposit=True, angles="nominal")
    sched, secs = plan.layer(1), plan.sections(1)
    assert len(rep["images"]) == sum(len(p) for p in sched.pass_images.values()) == 8
    assert {r["interlace"] for r in rep["images"]} == {0, 1, 2, 3}
    for r in rep["images"]:
        pr = sched.pass_images[(r["material"], r["ink"])][r["interlace"]]
        sim = simulate(pr, plan.reference_image(r["material"], secs).astype(np.uint8) * 255)
        film = deposit_film(sim.inked, pr.placement, pr.head, [ink_drops(sim.drops, pr.head)]).films[0].to_json()
        _same(r["deposit"], {k: v for k, v in film.items() if k not in ("radial_bins", "grid_um")})
        assert r["deposit"]["grid_um"] == film["grid_um"] and 0 < r["deposit"]["uncovered_fraction"] < 1


def test_program_time_is_the_sum_of_its_steps_and_the_plans_estimate(coil):
    _, plan_json, prog_path = coil
    prog = json.loads(prog_path.read_text())
    steps = [s for L in prog["layers"] for s in L["steps"]]
    assert prog["totals"]["steps"] == len(steps) and [s["n"] for s in steps] == list(range(len(steps)))
    total = math.fsum(s["time_s"] for s in steps)
    assert prog["totals"]["time_s"] == pytest.approx(total, rel=1e-12)
    assert total == pytest.approx(plan_json["estimated_print_time_s"], rel=1e-12)
    for L in prog["layers"]:
        assert math.fsum(s["time_s"] for s in L["steps"]) == pytest.approx(L["plan_time_s"], rel=1e-12)
        assert L["steps"][-1]["kind"] == "z_step" and L["steps"][-1]["z_step_mm"] == pytest.approx(0.02)
    # silver's flash heat 150 C for 60 s after its passes, with the head spitting meanwhile
    posts = [s for s in steps if s["kind"] == "post" and s["material"] == "silver"]
    assert posts and all(s["post"] == "flash_heat" and s["temperature_c"] == 150 and s["time_s"] == 60 for s in posts)
    assert posts[0]["idle"] == {"mode": "spit", "spits": 30, "drops_per_nozzle": 300}
    rev = [s for s in steps if s["kind"] == "revolution"]
    assert prog["totals"]["revolutions"] == len(rev)
    for s in rev[:50]:
        assert {"layer", "pass", "interlace", "pass_offset_mm", "head", "ink", "swathe", "radial_stage_mm", "multiplier",
                "divider", "angle_error_per_rev_deg", "index_offset_counts", "firings", "image", "sha256", "time_s"} <= s.keys()
    # one revolution per interlaced pass: cycle c at pass c mod N, the stage at the swathe's pivot plus the pass's offset
    heads = {h["name"]: h for h in prog["heads"]}
    images = {im["file"]: im for L in prog["layers"] for im in L["images"]}
    assert {s["interlace"] for s in rev} == set(range(heads["H1"]["passes"])) and heads["H1"]["passes"] > 1
    for s in rev:
        h = heads[s["head"]]
        assert s["interlace"] == s["cycle"] % h["passes"]
        assert s["pass_offset_mm"] == h["pass_offsets_mm"][s["interlace"]]
        sw = h["swathes"][s["swathe"]]
        assert s["radial_stage_mm"] == pytest.approx(sw["radial_stage_mm"] + s["pass_offset_mm"], abs=1e-9)
        if s["image"]:
            im = images[s["image"]]
            assert im["interlace"] == s["interlace"] and im["pivot_radius_mm"] == pytest.approx(s["radial_stage_mm"], abs=1e-12)
    txt = (prog_path.parent / "program.txt").read_text()
    assert txt.count(" rev ") == len(rev) and "flash heat at 150 C for 60 s" in txt


def test_motion_times_add_to_the_total():
    job = _small_job(z_step_s=2.5, radial_move_s=1.5)
    plan = plan_job(job)
    est = sum(plan.layer(i).time_s for i in range(len(plan)))
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as d:
        tot = write_machine_folder(plan, Path(d) / "m")
        prog = json.loads((Path(d) / "m" / "program.json").read_text())
    moves = [s for L in prog["layers"] for s in L["steps"] if s["kind"] == "radial_move"]
    assert len(moves) == 2  # each head positioned once: one swathe
    assert tot["motion_s"] == pytest.approx(2.5 * len(plan) + 1.5 * 2)
    assert tot["time_s"] == pytest.approx(est + tot["motion_s"], rel=1e-12)


def test_clock_ratio_at_360_dpi_and_2_to_the_20_counts_is_reported_below_a_tenth_of_a_step(coil):
    _, _, prog_path = coil
    prog = json.loads(prog_path.read_text())
    assert prog["machine"]["encoder_counts_per_rev"] == 2**20
    for h in prog["heads"]:
        for s in h["swathes"]:
            c = s["clock"]
            want = 2 * math.pi / s["dphi_rad"]
            assert c["clocked_firings_per_rev"] == pytest.approx(2**20 * c["multiplier"] / c["divider"])
            err = want * abs(2 * math.pi * c["divider"] / (2**20 * c["multiplier"]) - s["dphi_rad"])
            assert math.degrees(err) == pytest.approx(c["angle_error_per_rev_deg"], rel=1e-9)
            assert c["angle_error_per_rev_steps"] < 0.1 and not c["flagged"]
    # the preset's clock at other reference radii; a controller that only divides: flagged
    for r in (60.0, 80.0, 113.8):
        dphi = clock_dphi(360.0, r)
        c = clock_ratio(dphi, 2**20)
        assert c.error_per_rev_steps < 0.1 and not c.flagged
        c1 = clock_ratio(dphi, 2**20, max_multiplier=1)
        assert c1.multiplier == 1 and c1.divider == round(2**20 * dphi / (2 * math.pi))
        assert c1.error_per_rev_steps > 1 and c1.flagged


def test_flagged_clock_is_said_in_the_program(tmp_path):
    job = _small_job(clock_max_multiplier=1)
    plan = plan_job(job)
    tot = write_machine_folder(plan, tmp_path / "m")
    assert tot["flagged_clocks"] == ["head H1 swathe 0", "head H2 swathe 0"]
    assert "FLAGGED" in (tmp_path / "m" / "program.txt").read_text()


@pytest.mark.parametrize("bits,row_delays", [(1, "program"), (2, "baked"), (4, "program")])
def test_replay_with_other_bit_depths_and_row_delays_in_the_program(tmp_path, bits, row_delays):
    job = _small_job(nozzle_numbering={"odd_row": 1, "direction": "descending"})
    plan = plan_job(job)
    write_machine_folder(plan, tmp_path / "m", options=MachineOptions(bits=bits, row_delays=row_delays))
    prog = json.loads((tmp_path / "m" / "program.json").read_text())
    sw = prog["heads"][0]["swathes"][0]
    if row_delays == "program":
        assert sw["row_offsets_firings"][0] == 0 and sw["row_offsets_firings"][1] != 0
    else:
        assert sw["row_offsets_firings"] is None
    rep = replay_program(tmp_path / "m" / "program.json", angles="nominal")
    for r in rep["images"]:
        sched = plan.layer(r["layer"])
        ref = plan.reference_image(r["material"], plan.sections(r["layer"])).astype(np.uint8) * 255
        _same(r, simulate(sched.pass_images[(r["material"], r["ink"])][r["interlace"]], ref).report.to_json())


def test_machine_limits_are_checked_when_the_job_is_built(tmp_path):
    from rotoprint.errors import ConfigError

    for machine, msg in [({"radial_stage_mm": [0.0, 40.0]}, "machine.radial_stage_mm: head H1 swathe 0 pass 0 needs the radial stage at"),
                         ({"max_platform_rpm": 10.0}, "machine.max_platform_rpm: head H1 swathe 0 turns the platform at"),
                         ({"head_frequency_hz": 4000.0}, "machine.head_frequency_hz: head H1 fires at 8000 Hz"),
                         ({"encoder_counts_per_rev": 1000, "clock_max_multiplier": 1, "clock_max_divider": 1},
                          "machine.encoder_counts_per_rev: head H1 swathe 0: no encoder multiplier")]:
        with pytest.raises(ConfigError, match="^small.toml: " + msg.replace(".", r"\.")):
            run_build(_small_job(**machine), tmp_path / "out", check=False, report=False)
        assert not (tmp_path / "out").exists()
    with pytest.raises(ConfigError, match=r"^small.toml: machine.*radial_stage_mm must be \[low, high\] with high > low"):
        _small_job(radial_stage_mm=[50.0, 10.0])
    with pytest.raises(ConfigError, match="machine.encoder_counts"):
        _small_job(encoder_counts=5)


@pytest.fixture
def small_program(tmp_path):
    plan = plan_job(_small_job())
    write_machine_folder(plan, tmp_path / "m")
    return tmp_path / "m" / "program.json"


def _edit(path, fn):
    prog = json.loads(path.read_text())
    fn(prog)
    path.write_text(json.dumps(prog))


def test_replay_refuses_altered_and_missing_files_impossible_stage_and_unreachable_clock(small_program, run_cli, tmp_path):
    p = small_program
    code, out, err = run_cli("replay", p, "--out", tmp_path / "ok.png", "--json")
    assert code == 0 and json.loads(out)["iou"] > 0.8 and (tmp_path / "ok.png").exists()
    backup = tmp_path / "backup"
    shutil.copytree(p.parent, backup)

    def restore():
        shutil.rmtree(p.parent)
        shutil.copytree(backup, p.parent)

    img = p.parent / "layers" / "layer_00000" / "plaster-ammonium_sulphate-p1-s0.bin"  # interlaced pass 1 of N
    data = bytearray(img.read_bytes())
    data[7] ^= 0x10
    img.write_bytes(bytes(data))
    code, out, err = run_cli("replay", p, "--out", tmp_path / "o.png")
    assert code == 2 and err.strip().count("\n") == 0 and "was altered" in err and "layer 0 image" in err
    restore()
    img.unlink()
    code, out, err = run_cli("replay", p, "--out", tmp_path / "o.png")
    assert code == 2 and "is missing" in err and "plaster-ammonium_sulphate-p1-s0.bin" in err
    restore()

    steps1 = json.loads(backup.joinpath("program.json").read_text())["layers"][1]["steps"]
    k = next(j for j, st in enumerate(steps1) if j >= 2 and st["kind"] == "revolution")

    def stage(prog):
        prog["layers"][1]["steps"][k]["radial_stage_mm"] = 250.0

    _edit(p, stage)
    code, out, err = run_cli("replay", p, "--out", tmp_path / "o.png")
    n = steps1[k]["n"]
    assert code == 2 and f"layer 1 step {n} (revolution of H" in err and "radial stage position 250.0 mm is outside" in err
    restore()

    def clock(prog):
        prog["layers"][0]["steps"][0]["frequency_hz"] = 50_000.0

    _edit(p, clock)
    code, out, err = run_cli("replay", p, "--out", tmp_path / "o.png")
    assert code == 2 and "layer 0 step 0 (revolution of H1 swathe 0): firing clock 50000.0 Hz is beyond" in err
    restore()

    def ratio(prog):
        prog["layers"][0]["steps"][1]["multiplier"] *= 2

    _edit(p, ratio)
    code, out, err = run_cli("replay", p, "--out", tmp_path / "o.png")
    assert code == 2 and "layer 0 step 1" in err and "the clock cannot be reached" in err
    assert not (tmp_path / "o.png").exists()
    code, out, err = run_cli("replay", p, "--layer", "9", "--out", tmp_path / "o.png")
    assert code == 2 and "--layer 9" in err
    code, out, err = run_cli("replay", tmp_path / "none.json", "--out", tmp_path / "o.png")
    assert code == 2 and "none.json: no such file" in err
    (tmp_path / "other.json").write_text('{"format": "rotoprint-build-plan"}')
    code, out, err = run_cli("replay", tmp_path / "other.json", "--out", tmp_path / "o.png")
    assert code == 2 and "not a rotoprint machine program" in err and err.strip().count("\n") == 0
    assert not (tmp_path / "o.png").exists()


@pytest.mark.parametrize("key, value, said", [
    ("multiplier", 10**3000 + 7, "encoder ratio x1.00e+3000/"),  # printed all 3001 digits
    ("divider", -(10**2000), "/-1.00e+2000 is beyond the controller's limits"),
    ("frequency_hz", 10**3000, "firing clock 1.00e+3000 Hz is beyond"),  # was a traceback (int past float)
    ("frequency_hz", True, "firing clock True Hz is beyond"),  # was taken as 1 Hz
    ("radial_stage_mm", 10**400, "radial stage position 1.00e+400 mm is outside"),  # was a traceback
    ("time_s", 10**500, "time_s 1.00e+500 is not a duration"),  # was a traceback
], ids=["multiplier", "divider", "frequency", "frequency-bool", "stage", "time"])
def test_replay_says_how_big_a_huge_number_is_in_one_short_line(small_program, run_cli, tmp_path, key, value, said):
    def edit(prog):
        prog["layers"][0]["steps"][0][key] = value

    _edit(small_program, edit)
    code, out, err = run_cli("replay", small_program, "--out", tmp_path / "o.png")
    assert code == 2 and said in err, err[:300]
    assert err.strip().count("\n") == 0 and len(err) < 400 and not (tmp_path / "o.png").exists()


def test_build_cli_options(tmp_path, run_cli):
    job = tmp_path / "small.toml"
    job.write_text("""
[job]
name = "small"
layer_height_mm = 0.05
[printer]
device = "omnidot760"
tilt_deg = 20.0
[[printer.heads]]
name = "H1"
ink = "ammonium_sulphate"
[[printer.heads]]
name = "H2"
ink = "calcium_chloride"
mount_angle_deg = 90.0
[placement]
inner_radius_mm = 60.0
[[parts]]
name = "b"
material = "plaster"
priority = 1
shape = { kind = "box", size_mm = [2, 2, 0.05] }
[process]
cycles_per_layer = { plaster = 1 }
check = false
[machine]
encoder_counts_per_rev = 1048576
radial_stage_mm = [20.0, 150.0]
""")
    code, out, err = run_cli("build", job, "--out", tmp_path / "b", "--no-report", "--row-delays", "program", "--bits", "2", "--json")
    assert code == 0, err
    s = json.loads(out)
    assert s["machine"]["revolutions"] > 0
    assert s["report"] is None and not (tmp_path / "b" / "report.html").exists()
    prog = json.loads((tmp_path / "b" / "machine" / "program.json").read_text())
    assert prog["packing"]["bits_per_nozzle"] == 2 and prog["row_delays"] == "program"
    assert prog["machine"]["radial_stage_mm"] == [20.0, 150.0]
    import tifffile

    from rotoprint.io.machine import nozzle_order, read_packed, unpack_levels

    rec = prog["layers"][0]["images"][0]
    folder = tmp_path / "b" / "machine"
    lv = unpack_levels(read_packed((folder / rec["file"]).read_bytes(), rec["firings"], rec["nozzles"], 2), 2,
                       nozzle_order(764, 2))
    assert lv.any() and np.array_equal(tifffile.imread(folder / rec["tiff"]), lv[:, nozzle_order(764, 2)])
    code, out, err = run_cli("build", job, "--out", tmp_path / "b2", "--no-report")
    # (the console wraps a long path at its width: a longer temporary folder, as under xdist, splits it)
    assert code == 0 and "machine: " in out and "program.json" in out.replace("\n", "")
    # --no-report writes no report and names none (it printed "report: .../report.html")
    assert "report:" not in out and f"plan:   {(tmp_path / 'b2' / 'plan.json').resolve()}" in out.replace("\n", "")
    assert not (tmp_path / "b2" / "report.html").exists()
    code, out, err = run_cli("build", job, "--out", tmp_path / "c", "--row-delays", "sideways")
    assert code == 2 and "--row-delays must be 'baked' or 'program'" in err and not (tmp_path / "c").exists()
    code, out, err = run_cli("build", job, "--out", tmp_path / "c", "--bits", "3")
    assert code == 2 and "--bits must be 1, 2 or 4" in err
    code, out, err = run_cli("build", job, "--out", tmp_path / "c", "--no-machine", "--no-report")
    assert code == 0 and not (tmp_path / "c" / "machine").exists()
    job.write_text(job.read_text().replace("radial_stage_mm = [20.0, 150.0]", "radial_stage_mm = [20.0, 150.0]\nspeed = 3"))
    code, out, err = run_cli("build", job, "--out", tmp_path / "d")
    assert code == 2 and "machine.speed" in err and err.strip().count("\n") == 0


@pytest.fixture(scope="module")
def program_text(tmp_path_factory):
    """A small program, written once for the record cases (each edits a copy)."""
    folder = tmp_path_factory.mktemp("records") / "m"
    write_machine_folder(plan_job(_small_job()), folder)
    return folder, (folder / "program.json").read_text()


RECORD_CASES = [
    ("direction", "x", "field direction must be 1 or -1, got 'x'"),
    ("direction", 10**400, "field direction must be 1 or -1, got 1.00e+400"),
    ("direction", 2, "field direction must be 1 or -1, got 2"),
    ("mount_angle_deg", "abc", "field mount_angle_deg must be a finite number, got 'abc'"),
    ("mount_angle_deg", 1e6, "field mount_angle_deg must be in [-3600, 3600] deg"),
    ("tilt_deg", None, "field tilt_deg must be a finite number, got None"),
    ("pivot_radius_mm", None, "field pivot_radius_mm must be a finite number, got None"),
    ("ref_radius_mm", -1, "field ref_radius_mm must be > 0, got -1"),
    ("dpi_y", 0, "field dpi_y must be > 0, got 0"),
    ("dphi_rad", "q", "field dphi_rad must be a finite number, got 'q'"),
    ("band_mm", [1], "field band_mm must be [low, high], got [1]"),
    ("band_mm", [70, 60], "field band_mm must be [low, high] with high >= low"),
    ("enabled_nozzles", -5, "field enabled_nozzles must be an integer in 0 ... 764, got -5"),
    ("enabled_nozzle_runs", [[5, 2]], "field enabled_nozzle_runs must be [start, end) nozzle runs"),
    ("firings", -3, "field firings must be an integer in 1 ..."),
    ("nozzles", "a", "field nozzles must be a finite number, got 'a'"),
    ("swathe", 99, "field swathe must be one of head H1's swathes 0..0, got 99"),
    ("swathe", True, "field swathe must be one of head H1's swathes"),
    ("interlace", "a", "field interlace must be a pass number 0..63, got 'a'"),
    ("row_offsets_firings", [1, 2], "field row_offsets_firings [1, 2] is not its swathe's None"),
    ("head", "H9", "no head 'H9' in the program's heads"),
    ("placement", None, "field placement must be a table, got None"),
    ("words_per_row", 0, "field words_per_row must be 24 (764 nozzles of 1 bit(s) in 32-bit words), got 0"),
]


@pytest.mark.parametrize("key, value, said", RECORD_CASES, ids=[f"{k}={str(v)[:12]}" for k, v, _ in RECORD_CASES])
def test_a_bad_image_record_is_one_line_naming_the_image_and_the_field(program_text, run_cli, tmp_path, key, value, said):
    """The program's JSON is not hashed (its packed files are): an edited record is one line naming
    the image and the field, exit 2, no output. These were tracebacks (a direction or angle that
    is not a number, a missing radius, a band of one value, a bad swathe or pass index) or were
    taken silently (a zero dpi, a negative nozzle count, row offsets that are not the swathe's)."""
    def edit(prog):
        prog["layers"][0]["images"][0][key] = value

    err = _replay_of_edited_program_refused(program_text, run_cli, tmp_path, edit, said)
    if key != "head":
        rec = json.loads(program_text[1])["layers"][0]["images"][0]
        assert f"layer 0 image {rec['file']}: field {key}" in err


def _replay_of_edited_program_refused(program_text, run_cli, tmp_path, edit, said) -> str:
    """``replay`` of a copy of the program with ``edit(prog)`` applied to its JSON: exit 2, one
    short line containing ``said`` and naming program.json, no output written. Returns stderr."""
    src, text = program_text
    folder = tmp_path / "m"
    shutil.copytree(src, folder)
    prog = json.loads(text)
    edit(prog)
    (folder / "program.json").write_text(json.dumps(prog))
    code, out, err = run_cli("replay", folder / "program.json", "--out", tmp_path / "o.png")
    assert code == 2, (code, err[-500:])
    assert said in err, err
    assert err.strip().count("\n") == 0 and "Traceback" not in err and len(err) < 400
    assert "program.json" in err and not (tmp_path / "o.png").exists()
    return err


def _set_placement(key, value):
    def edit(prog):
        prog["layers"][0]["images"][0]["placement"][key] = value
    return edit


def _set_grid(key, value):
    def edit(prog):
        prog["design_grid"][key] = value
    return edit


GRID_CASES = [
    (_set_placement("width_px", 0), "field placement: design size must be positive, got 0 x"),
    (_set_placement("pitch_x_mm", float("nan")), "field placement: design pixel pitch must be positive, got nan x"),
    (_set_placement("width_px", 10**9), "field placement is 1000000000 x"),
    (_set_grid("height_px", -3), "design_grid.height_px must be a whole number 1..1.09951e+12, got -3"),
    (_set_grid("width_px", "43"), "design_grid.width_px must be a whole number 1..1.09951e+12, got '43'"),
    (_set_grid("pitch_y_mm", 0), "design_grid.pitch_y_mm must be a finite length > 0 mm, got 0"),
]


@pytest.mark.parametrize("edit, said", GRID_CASES, ids=["w0", "pitch-nan", "w-huge", "grid-h", "grid-w-str", "grid-pitch"])
def test_a_bad_placement_or_design_grid_is_one_line_naming_the_program_and_field(program_text, run_cli, tmp_path, edit, said):
    """Were: a placement of no pixels or a NaN pitch refused without naming the program, one of
    another size refused only by the simulation ("the print was made for ..."), a design grid
    of -3 rows or a zero pitch taken silently."""
    _replay_of_edited_program_refused(program_text, run_cli, tmp_path, edit, said)
