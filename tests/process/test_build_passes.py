"""Interlaced passes on the build (issue 14): ``[printer] passes``, every pass's own exact
images (the direct slicer with the pass's pivot offset), cycles from the measured drops per
area, the deposit model's coverage as the headline, dead nozzles covered by the plan."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rotoprint.errors import ConfigError
from rotoprint.pipeline import run_build
from rotoprint.process import parse_job
from rotoprint.process.plan import plan_job
from rotoprint.rotary.direct import slice_rotary
from rotoprint.rotary.interlace import plan_passes
from rotoprint.rotary.deposit import DepositOptions


def _job(tmp_path=None, *, passes="auto", dead=None, cycles=None, cap=None, set_time_s=None, equalise=True):
    printer = {"device": "omnidot760", "tilt_deg": 20.0, "passes": passes, "equalise": equalise,
               "heads": [{"name": "H1", "ink": "ammonium_sulphate"},
                         {"name": "H2", "ink": "calcium_chloride", "mount_angle_deg": 90.0}]}
    if dead is not None or set_time_s is not None:  # the preset edited, as a device file beside the job
        from importlib.resources import files

        text = (files("rotoprint.devices") / "presets" / "omnidot760.toml").read_text(encoding="utf-8")
        assert "dead_nozzles = []" in text and "set_time_s = 1.0" in text
        if dead is not None:
            text = text.replace("dead_nozzles = []", f"dead_nozzles = {list(dead)}")
        if set_time_s is not None:
            text = text.replace("set_time_s = 1.0", f"set_time_s = {set_time_s!r}")
        (tmp_path / "dev.toml").write_text(text, encoding="utf-8")
        printer["device"] = "dev.toml"
    d = {"job": {"name": "small", "layer_height_mm": 0.05}, "printer": printer, "placement": {"inner_radius_mm": 60.0},
         "parts": [{"name": "b", "material": "plaster", "priority": 1,
                    "shape": {"kind": "box", "size_mm": [3, 2, 0.05], "origin_mm": [0, 0, 0]}}]}
    if cycles:
        d["process"] = {"cycles_per_layer": {"plaster": cycles}}
    if cap:
        d.setdefault("process", {})["max_passes_per_layer"] = cap
    return parse_job(d, base_dir=tmp_path or ".", source="small.toml")


@pytest.mark.parametrize("equalise", [True, False])
def test_each_pass_is_the_direct_slicers_print_at_its_offset_and_the_plans_clock(equalise):
    from rotoprint.rotary.direct import union_pass_shares
    from rotoprint.rotary.equalise import EQUALISE_CLOCK_FACTOR

    plan = plan_job(_job(equalise=equalise))
    h = plan.heads[0]
    pp = plan_passes(plan.device.head, h.lattice.plan, footprint_um=DepositOptions().full_footprint_um(plan.device.head))
    assert h.passes == pp.passes > 1 and h.pass_offsets_mm == pp.offsets_mm
    # equalised: the union's shares at EQUALISE_CLOCK_FACTOR x the plan's clock; plain: the plan's clock, every drop
    factor = EQUALISE_CLOCK_FACTOR if equalise else 1
    assert h.interlace["clock"] == "pass plan" and h.lattice.dpi_y == pytest.approx(factor * pp.dpi_y)
    assert h.interlace["equalise"] == ("union shares" if equalise else False)
    shares = union_pass_shares(plan.device.head, h.lattice.plan, pp.offsets_mm, dpi_y=pp.dpi_y)[0] if equalise else None
    sched = plan.layer(0)
    prs = sched.pass_images[("plaster", h.ink)]
    assert len(prs) == h.passes and prs[0] is sched.images[("plaster", h.ink)]
    mesh = plan.meshes["b"]
    for q, pr in enumerate(prs):
        want = slice_rotary(mesh, plan.device, layer_height_mm=0.05, tilt_deg=20.0, inner_radius_mm=60.0, dpi_y=factor * pp.dpi_y,
                            equalise=False, pivot_offset_mm=pp.offsets_mm[q], shares=None if shares is None else shares[q],
                            pass_index=q).layer(0)
        assert len(pr.swathes) == len(want.swathes)
        for a, b in zip(pr.swathes, want.swathes):
            assert a.pivot_radius_mm == pytest.approx(b.pivot_radius_mm) and np.array_equal(a.levels, b.levels)
            assert a.extra["pass"] == q and a.extra["pass_offset_mm"] == pp.offsets_mm[q]
    assert not np.array_equal(prs[0].swathes[0].levels, prs[1].swathes[0].levels)


def test_cycles_follow_from_the_measured_drops_per_area_rounded_to_the_passes():
    plan = plan_job(_job())
    est = plan.estimates["plaster"]
    src = est.density_source
    assert src["layer"] == 0 and "first layer" in src["rule"]
    # the same density by hand: every drop of every pass over the design area, per pass; the
    # plan counts the drops landing in the interior (the box less half a footprint) over its area
    secs = plan.sections(0)
    g = plan.design_grid()
    area = plan.reference_image("plaster", secs).sum() * g.pitch_x_mm * g.pitch_y_mm
    assert "interior" in src["rule"] and 0.9 * area < src["area_mm2"] < area
    for ink in ("ammonium_sulphate", "calcium_chloride"):
        h = plan.head(ink)
        drops = sum(int(np.count_nonzero(s.levels)) for q in range(h.passes)
                    for s in plan.material_print("plaster", h, secs, 0, pass_index=q).swathes)
        assert 0.9 * drops < src["drops"][ink] < drops
        d = est.drops_per_mm2[ink]
        assert d.min() <= drops / h.passes / area * 1.02 and d.max() >= drops / h.passes / area * 0.98
    n = plan.heads[0].passes
    assert est.cycles % n == 0 and est.cycles == est.cycles_needed
    assert (est.cycles - n) * est.per_cycle_um[0] < 50.0 <= est.cycles * est.per_cycle_um[0]


def test_one_pass_keeps_the_job_clock_and_no_interlace():
    plan = plan_job(_job(passes=1))
    h = plan.heads[0]
    assert h.passes == 1 and h.pass_plan is None and h.lattice.dpi_y == plan.device.head.dpi_y
    sched = plan.layer(0)
    assert all(len(p) == 1 for p in sched.pass_images.values())


def test_bad_passes_are_refused_naming_the_field():
    for bad in (0, 65, "many", True, 2.5, "2"):
        with pytest.raises(ConfigError, match=r"^small.toml: printer\.passes: must be a whole number 1\.\.64 or 'auto'"):
            _job(passes=bad)


def test_the_passes_range_is_one_constant_for_the_job_the_cli_and_the_planner():
    from rotoprint.ranges import PASSES
    from rotoprint.rotary.interlace import parse_passes
    from rotoprint.rotary.swathes import plan_swathes
    from rotoprint.devices import load_device

    assert (PASSES.lo, PASSES.hi) == (1, 64)
    head = load_device("omnidot760").head
    sp = plan_swathes(head, tilt_deg=20.0, inner_radius_mm=60.0, outer_radius_mm=61.0)
    assert parse_passes(str(PASSES.hi)) == PASSES.hi and parse_passes("auto") is None
    assert _job(passes=PASSES.hi).spec.printer.passes == PASSES.hi
    for bad in (PASSES.lo - 1, PASSES.hi + 1):
        with pytest.raises(ConfigError, match=r"passes must be 1\.\.64 or 'auto', got"):
            parse_passes(str(bad))
        with pytest.raises(ConfigError, match=r"printer\.passes: must be a whole number 1\.\.64 or 'auto'"):
            _job(passes=bad)
        with pytest.raises(ConfigError, match=r"^passes must be 1\.\.64, got"):
            plan_passes(head, sp, footprint_um=49.6, passes=bad)
    with pytest.raises(ConfigError, match=r"max passes must be 1\.\.64"):
        plan_passes(head, sp, footprint_um=49.6, max_passes=PASSES.hi + 1)
    # a number of a thousand digits: said by its size, in a short line (it printed every digit)
    with pytest.raises(ConfigError, match=r"got 9\.99e\+999$") as ei:
        parse_passes("9" * 1000)
    assert len(str(ei.value)) < 80
    with pytest.raises(ConfigError, match=r"printer\.passes: must be a whole number 1\.\.64"):
        _job(passes=10**1000)


def test_a_limit_below_the_rounded_cycles_keeps_the_cycles_that_reach_the_layer():
    from rotoprint.process.estimates import cycles_for_height

    est = plan_job(_job()).estimates["plaster"]
    n = est.interlace_passes
    bare = cycles_for_height(50.0, est.per_cycle_um[0])
    assert n > 1 and est.cycles_needed == n * -(-bare // n)
    if est.cycles_needed == bare:
        pytest.skip(f"the layer needs {bare} cycles, already a multiple of the {n} passes: nothing to round")
    ppc = est.passes_per_layer // est.cycles
    low = plan_job(_job(cap=bare * ppc)).estimates["plaster"]  # room for the layer, not for a whole round of passes
    assert low.cycles == bare and low.per_layer_um[0] >= 50.0 * (1 - 1e-9)
    assert any("would exceed" in w for w in low.warnings) and not any("short" in w for w in low.warnings)


def test_dead_nozzles_are_covered_by_the_plan(tmp_path):
    ks = plan_job(_job()).heads[0].lattice.tracks[0].nozzle  # nozzles whose tracks cross the part, by radius
    dead = tuple(sorted(int(k) for k in ks[np.linspace(5, ks.size - 6, 5).astype(int)]))
    plan = plan_job(_job(tmp_path, dead=dead))
    h = plan.heads[0]
    assert h.pass_plan.dead_nozzles == dead and h.interlace["dead_nozzles"] == list(dead)
    assert h.interlace["dead_track_cover_um"] and max(h.interlace["dead_track_cover_um"]) < h.interlace["footprint_um"] / 2
    for pr in plan.layer(0).pass_images[("plaster", h.ink)]:
        for s in pr.swathes:
            assert not s.levels[:, list(dead)].any()


def test_build_without_levelling_reports_the_film_as_landed(tmp_path):
    # a device whose set_time_s is 0 (no levelling): the headline is the film as landed
    run_build(_job(tmp_path, cycles=4, set_time_s=0.0), tmp_path / "out", check=False)
    cov = json.loads((tmp_path / "out" / "plan.json").read_text())["coverage"]["plaster"]
    assert cov["thinnest_to_mean_basis"] == "as landed" and cov["thinnest_to_mean"] == cov["thinnest_to_mean_as_landed"]
    assert cov["thinnest_to_mean_levelled"] is None and cov["levelling"] == []


def test_build_in_passes_headline_coverage_machine_and_sidecars(tmp_path):
    job = _job(cycles=4)
    res = run_build(job, tmp_path / "out", check=False)
    plan = json.loads((tmp_path / "out" / "plan.json").read_text())
    cov = plan["coverage"]["plaster"]
    assert cov["model"] == "deposit" and cov["uncovered_fraction"] <= 0.01 and res.summary["coverage"] == plan["coverage"]
    assert all(o["deposit"]["uncovered_fraction"] <= 0.01 and o["reagent_pairs"] for o in plan["overlays"])
    # the preset's inks level (set time 1 s): the headline thinnest / mean is the levelled film's
    assert cov["thinnest_to_mean_basis"] == "levelled" and cov["thinnest_to_mean"] == cov["thinnest_to_mean_levelled"]
    assert cov["thinnest_to_mean_as_landed"] is not None and cov["levelling"][0]["set_time_s"] == 1.0
    assert all(abs(f["levelled"]["volume_error_fraction"]) < 1e-9 for o in plan["overlays"] for f in o["inks"].values())
    n = plan["heads"][0]["passes"]
    im = plan["layers_detail"][0]["images"][0]
    assert [p["pass"] for p in im["passes"]] == list(range(n))
    for p in im["passes"]:
        side = json.loads((tmp_path / "out" / p["sidecar"]).read_text())
        assert all(s["pass_offset_mm"] == p["pass_offset_mm"] for s in side["swathes"])
    html = (tmp_path / "out" / "report.html").read_text()
    table = html[html.index("<table id='coverage'>"):]
    table = table[: table.index("</table>")]
    assert "<td>plaster</td>" in table and f"<b>{100 * cov['uncovered_fraction']:.2f} %</b>" in table
    assert "true volume per area of the planned drops" in html
    assert "Thinnest / mean is that of the <b>levelled</b> film for plaster" in html and "set time 1 s" in html
    prog = json.loads((tmp_path / "out" / "machine" / "program.json").read_text())
    rev = [s for L in prog["layers"] for s in L["steps"] if s["kind"] == "revolution"]
    assert [s["interlace"] for s in rev if s["head"] == "H1" and s["repeat"] == 0] == [c % n for c in range(4)]
    assert len({s["radial_stage_mm"] for s in rev if s["head"] == "H1"}) == min(n, 4)


def test_bad_equalise_is_refused_naming_the_field():
    with pytest.raises(ConfigError, match=r"^small.toml: printer\.equalise must be true or false, got .maybe.$") as ei:
        _job(equalise="maybe")
    assert "\n" not in str(ei.value)


def test_equalised_build_passes_even_the_union_and_plan_the_true_volume(tmp_path):
    """The union's shares: fewer drops per pass than every drop at the finer clock, the shares
    recorded in plan.json, the cycles from the measured (thinned) drops, the film within floors."""
    run_build(_job(tmp_path, cycles=4), tmp_path / "eq", check=False)
    run_build(_job(tmp_path, cycles=4, equalise=False), tmp_path / "plain", check=False)
    eq, plain = (json.loads((tmp_path / d / "plan.json").read_text()) for d in ("eq", "plain"))
    us = eq["heads"][0]["interlace"]["union_shares"]
    assert 0.5 <= us["mean_share"] < 1.0 and us["clock_factor"] == 2 and eq["heads"][0]["interlace"]["dpi_y"] == us["dpi_y"]
    assert "union_shares" not in plain["heads"][0]["interlace"]
    for d in (eq, plain):
        for o in d["overlays"]:
            assert o["deposit"]["uncovered_fraction"] <= 0.01 and abs(o["deposit"]["volume_error_fraction"]) < 1e-9
    # the union-equalised film is even across the radius (the plain film has 1/r of one clock per swathe)
    (o_eq,), (o_pl,) = eq["overlays"][:1], plain["overlays"][:1]
    assert o_eq["deposit"]["radial_spread"] <= 0.05
    assert o_eq["deposit"]["levelled"]["thinnest_to_mean"] >= 0.4
