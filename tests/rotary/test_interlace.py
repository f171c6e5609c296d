"""Tilt choice and interlaced passes (rotary/interlace.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import ConfigError, GeometryError
from rotoprint.rotary import Placement, plan_swathes, transform_exact
from rotoprint.rotary.deposit import deposit_print
from rotoprint.rotary.head import head_figures
from rotoprint.rotary.interlace import MAX_CLOCK_FACTOR, best_tilt, plan_passes, tilt_scan, union_radii
from rotoprint.rotary.options import RotarySetup
from rotoprint.rotary.testimage import test_design as make_design

PX = 25.4 / 360


@pytest.fixture(scope="module")
def head():
    return load_device("omnidot760").head


def test_tilt_scan_matches_head_figures(head):
    rows = tilt_scan(head, [0.0, 20.0, 45.0], pivot_radius_mm=60.0)
    for r in rows:
        f = head_figures(head, tilt_deg=r.tilt_deg, pivot_radius_mm=60.0)
        assert r.largest_gap_mm == f.largest_track_gap_mm and r.tracks == f.tracks_in_band
        lo, hi = f.overlap_band_mm
        assert r.mean_pitch_mm == pytest.approx((hi - lo) / (r.tracks - 1))
        assert r.even == (r.largest_gap_mm <= 1.25 * r.mean_pitch_mm)
    assert rows[0].even and not rows[1].even  # the tilted rows pass through coincidence
    assert best_tilt(rows) is rows[0]
    assert best_tilt(rows[1:]) is None
    # a loose ratio admits every tilt: the finest mean pitch wins
    loose = tilt_scan(head, [0.0, 20.0, 45.0], pivot_radius_mm=60.0, even_ratio=3.0)
    assert best_tilt(loose).tilt_deg == 45.0
    with pytest.raises(ConfigError, match="even ratio"):
        tilt_scan(head, [0.0], pivot_radius_mm=60.0, even_ratio=1.0)


def test_head_cli_best(run_cli):
    code, out, err = run_cli("head", "--tilt-range", "0:30:10", "--radius", "60", "--best")
    assert code == 0, err
    assert "best tilt 0 deg" in out and "70.4 um" in out
    code, out, err = run_cli("head", "--tilt-range", "10:30:10", "--radius", "60", "--best", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert data["best"] is None and data["tilts"][0]["interleave"]["even"] is False
    code, out, err = run_cli("head", "--tilt-range", "10:30:10", "--best")
    assert code == 0 and "passes" in out


@pytest.mark.parametrize("tilt", [0.0, 20.0, 70.0])
def test_passes_shrink_the_largest_gap(head, tilt):
    sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=60.0, outer_radius_mm=75.0)
    pp = plan_passes(head, sp, footprint_um=49.6, passes=4)
    assert pp.passes == 4 and pp.offsets_mm[0] == 0.0
    # the gap figure is that of the union of the passes' tracks over the design's range
    r = union_radii(head, sp, pp.offsets_mm)
    r = r[(r >= 60.0) & (r <= 75.0)]
    assert np.diff(r).max() == pytest.approx(pp.largest_gap_mm)
    single = np.diff(union_radii(head, sp, [0.0])[(union_radii(head, sp, [0.0]) >= 60) & (union_radii(head, sp, [0.0]) <= 75)]).max()
    assert pp.single_pass_largest_gap_mm == pytest.approx(single)
    # about as good as the even split q p / 4 (the offsets are chosen by the radial film
    # profile on a grid of 128 per row period), and at most about a third of the single-pass gap
    # (measured at 70 deg: 30.6 of 91.1 um)
    even = union_radii(head, sp, [q * pp.mean_gap_mm * 4 / 4 for q in range(4)])
    assert pp.largest_gap_mm <= 1.1 * np.diff(even[(even >= 60) & (even <= 75)]).max()
    assert pp.largest_gap_mm < 0.35 * single
    # the clock closes the lattice within the cover share of the footprint, within the cost
    # floor: never finer than MAX_CLOCK_FACTOR x native, never coarser than native
    native = 25.4 / head.dpi_y
    fit = np.sqrt(max(0.0, (0.85 * 0.0496) ** 2 - pp.largest_gap_mm**2))
    assert pp.along_track_mm == pytest.approx(min(native, max(fit, native / MAX_CLOCK_FACTOR)))
    assert head.dpi_y <= pp.dpi_y <= MAX_CLOCK_FACTOR * head.dpi_y + 1e-9
    assert 0 < pp.profile_min_to_mean <= 1


def test_dead_nozzles_covered_by_other_passes(head):
    sp = plan_swathes(head, tilt_deg=20.0, inner_radius_mm=60.0, outer_radius_mm=75.0)
    dead = tuple(int(k) for k in np.random.default_rng(5).choice(np.flatnonzero(sp.swathes[0].enabled), 5, replace=False))
    pp = plan_passes(head, sp, footprint_um=49.6, passes=4, dead_nozzles=dead)
    assert pp.dead_nozzles == tuple(sorted(dead)) and pp.dead_track_cover_mm
    # every dead track has a live track of the union within the largest gap
    assert max(pp.dead_track_cover_mm) <= pp.largest_gap_mm
    r = union_radii(head, sp, pp.offsets_mm, dead_nozzles=dead)
    assert np.diff(r[(r >= 60) & (r <= 75)]).max() == pytest.approx(pp.largest_gap_mm)


def test_planner_chooses_passes_and_refuses_what_cannot_close(head):
    sp = plan_swathes(head, tilt_deg=0.0, inner_radius_mm=60.0, outer_radius_mm=70.0)
    pp = plan_passes(head, sp, footprint_um=49.6)
    assert pp.passes == 3  # 70.4 / 3 = 23.5 um <= 0.85 x 49.6 / sqrt(2); 2 passes leave 35.2 um
    with pytest.raises(GeometryError, match="footprint"):
        plan_passes(head, sp, footprint_um=49.6, passes=1)
    with pytest.raises(ConfigError, match="passes"):
        plan_passes(head, sp, footprint_um=49.6, passes=0)


def test_interlaced_film_is_closed(head):
    """A 60 px crop of the test design at tilt 20: one pass leaves most of the interior bare,
    four planned passes at the planned clock leave none of it, with the volume conserved."""
    d = make_design(1200)[300:360, 300:360]
    pl = Placement(60, 60, PX, PX, inner_radius_mm=60.0)
    sp = plan_swathes(head, tilt_deg=20.0, inner_radius_mm=pl.radial_range_mm()[0], outer_radius_mm=pl.radial_range_mm()[1])
    pp = plan_passes(head, sp, footprint_um=49.6)
    prs = [transform_exact(d, head, pl, tilt_deg=20.0, dpi_y=pp.dpi_y, pivot_offset_mm=o) for o in pp.offsets_mm]
    assert [p.swathes[0].pivot_radius_mm - prs[0].swathes[0].pivot_radius_mm for p in prs] == pytest.approx(list(pp.offsets_mm))
    f = deposit_print(prs, d).films[0]
    one = deposit_print(transform_exact(d, head, pl, tilt_deg=20.0), d).films[0]
    assert one.uncovered_fraction > 0.3
    assert f.uncovered_fraction < 0.005
    assert abs(f.volume_error_fraction) < 0.005


def test_transform_passes_cli_and_simulate_union(run_cli, tmp_path):
    from rotoprint.io.images import write_png

    p = tmp_path / "d.png"
    write_png(p, make_design(1200)[300:360, 300:360])
    out = tmp_path / "pr.png"
    code, _, err = run_cli("transform", p, "--device", "omnidot760", "--tilt", "20", "--radius", "60", "--design-dpi", "360",
                           "--passes", "auto", "--out", out)
    assert code == 0, err
    man = json.loads((tmp_path / "pr-passes.json").read_text())
    pp = man["pass_plan"]
    assert man["format"] == "rotoprint-rotary-passes" and pp["passes"] == len(man["files"]) == 4
    sides = [json.loads((tmp_path / f).read_text()) for f in man["files"]]
    for q, s in enumerate(sides):
        sw = s["swathes"][0]
        assert sw["pass"] == q and sw["pass_offset_mm"] == pp["offsets_mm"][q] and s["dpi_y"] == man["dpi_y"]
    piv = [s["swathes"][0]["pivot_radius_mm"] for s in sides]
    assert [v - piv[0] for v in piv] == pytest.approx(pp["offsets_mm"])
    code, o, err = run_cli("simulate", tmp_path / "pr-passes.json", "--out", tmp_path / "ov.png", "--json")
    assert code == 0, err
    r = json.loads(o)
    assert r["passes"] == 4 and r["deposit"]["uncovered_fraction"] < 0.005
    code, o1, err = run_cli("simulate", tmp_path / "pr-p1.png", "--out", tmp_path / "ov.png", "--json")
    assert code == 0, err
    assert json.loads(o1)["deposit"]["uncovered_fraction"] > 0.2  # one pass of the four at the fine clock
    # equalised: the same plan, thinned tracks, a finer clock
    code, _, err = run_cli("transform", p, "--device", "omnidot760", "--tilt", "20", "--radius", "60", "--design-dpi", "360",
                           "--passes", "4", "--equalise", "--out", tmp_path / "eq.png", "-q")
    assert code == 0, err
    assert json.loads((tmp_path / "eq-passes.json").read_text())["equalise"] == "thinning"
    for bad, msg in ((("--passes", "0"), "passes"), (("--passes", "x"), "passes"), (("--equalise",), "needs --passes"),
                     (("--passes", "2", "--method", "paper"), "exact")):
        code, _, err = run_cli("transform", p, "--device", "omnidot760", "--tilt", "20", "--radius", "60", "--out", tmp_path / "b.png", *bad)
        assert code == 2 and msg in err, err
    (tmp_path / "bad-passes.json").write_text('{"format": "rotoprint-rotary-passes", "files": ["../x.json"]}')
    code, _, err = run_cli("simulate", tmp_path / "bad-passes.json", "--out", tmp_path / "ov.png")
    assert code == 2 and "file names" in err


def test_equalised_fractions(head):
    """Shares are in [floor, 1]; at tilt 0 (even tracks) they follow 1 / r: outer tracks keep
    every drop, the radial thickness at the tracks is flat to a few per cent."""
    from rotoprint.rotary.interlace import EQUALISE_FLOOR, track_fractions

    sp = plan_swathes(head, tilt_deg=0.0, inner_radius_mm=60.0, outer_radius_mm=75.0)
    pp = plan_passes(head, sp, footprint_um=49.6)
    fr = track_fractions(head, sp, pp.offsets_mm, RotarySetup(tilt_deg=0.0, dpi_y=pp.dpi_y), footprint_um=49.6)
    en = sp.swathes[0].enabled
    f = fr[0][0][en]
    assert f.min() >= EQUALISE_FLOOR and f.max() <= 1.0
    from rotoprint.rotary.head import Mount, nozzle_layout

    r = nozzle_layout(head, Mount(sp.swathes[0].pivot_radius_mm)).r_mm[en]
    inner = (r > 61) & (r < 62)
    outer = (r > 73) & (r < 74)
    # drops per area ~ f / r: equal at both ends
    assert (f[inner] / r[inner]).mean() == pytest.approx((f[outer] / r[outer]).mean(), rel=0.03)


@pytest.mark.parametrize("tilt", [0.0, 20.0])
def test_direct_slicer_pass_is_exact_at_its_pivot(tilt):
    """A pass of the direct slicer: every swathe's pivot moved by the offset, and still a drop
    fires exactly when it lands inside the exact cross-section."""
    from _direct_checks import section_geom, shapely_mismatches

    from rotoprint.rotary.direct import slice_rotary
    from rotoprint.testing import box_mesh

    dev = load_device("omnidot760")
    mesh = box_mesh((20.0, 12.0, 2.0), origin=(3.0, -4.0, 0.0))
    kw = dict(layer_height_mm=1.0, tilt_deg=tilt, inner_radius_mm=40.0, angle_deg=15.0)
    base = slice_rotary(mesh, dev, **kw)
    job = slice_rotary(mesh, dev, pivot_offset_mm=0.0375, **kw)
    assert [t.pivot_radius_mm for t in job.tracks] == pytest.approx([t.pivot_radius_mm + 0.0375 for t in base.tracks])
    assert job.rotary_options["pivot_offset_mm"] == 0.0375
    pr = job.layer(1)
    checked, bad, worst = shapely_mismatches(job, pr, section_geom(job, 1), n_random=20000, seed=1)
    assert checked > 0 and (bad == 0 or worst <= 1e-6), (bad, worst)
    assert not np.array_equal(pr.swathes[0].levels, base.layer(1).swathes[0].levels)


def test_slice_rotary_passes_cli_then_simulate_union(run_cli, tmp_path):
    import struct

    from rotoprint.testing import box_triangles

    mesh_path = tmp_path / "box.stl"
    tri = box_triangles((4.0, 3.0, 0.4))
    with open(mesh_path, "wb") as fh:
        fh.write(b"\0" * 80 + struct.pack("<I", len(tri)))
        for t in tri:
            fh.write(struct.pack("<12fH", 0, 0, 0, *t.ravel().tolist(), 0))
    out = tmp_path / "o"
    code, _, err = run_cli("slice", mesh_path, "--device", "omnidot760", "--rotary", "--tilt", "20", "--radius", "40",
                           "--layer-height", "0.2", "--out", out, "--passes", "auto", "--reference-images")
    assert code == 0, err
    man = json.loads((tmp_path / "o-passes.json").read_text())
    n = man["pass_plan"]["passes"]
    assert n == 4 and man["folders"] == [f"o-p{q + 1}" for q in range(n)]
    sides = [json.loads((tmp_path / f / "layer_00000.json").read_text()) for f in man["folders"]]
    piv = [s["swathes"][0]["pivot_radius_mm"] for s in sides]
    assert [p - piv[0] for p in piv] == pytest.approx(man["pass_plan"]["offsets_mm"])
    code, o, err = run_cli("simulate", *[tmp_path / f / "layer_00001.json" for f in man["folders"]], "--out", tmp_path / "ov.png", "--json")
    assert code == 0, err
    r = json.loads(o)
    assert r["passes"] == n and r["deposit"]["uncovered_fraction"] < 0.005
    code, _, err = run_cli("slice", mesh_path, "--device", "omnidot760", "--layer-height", "0.2", "--out", tmp_path / "x", "--passes", "2")
    assert code == 2 and "need --rotary" in err


def test_pass_options_and_density_shares(head, tmp_path):
    from rotoprint.rotary.interlace import PassOptions, density_shares, read_passes, transform_passes
    from rotoprint.rotary.exact import swathe_clock

    with pytest.raises(ConfigError, match="pivot_offset_mm must be 0"):
        PassOptions(RotarySetup(tilt_deg=0.0, pivot_offset_mm=0.01))
    with pytest.raises(ConfigError, match="passes"):
        PassOptions(RotarySetup(tilt_deg=0.0), passes="many")
    with pytest.raises(ConfigError, match="footprint"):
        PassOptions(RotarySetup(tilt_deg=0.0), footprint_um=-1.0)
    # every track lays the same drops per mm: share = its drop spacing over the widest spacing
    sp = plan_swathes(head, tilt_deg=20.0, inner_radius_mm=60.0, outer_radius_mm=100.0)
    dead_head = head.model_copy(update={"dead_nozzles": (10, 11)})
    fr = density_shares(dead_head, sp, (0.0, 0.02), RotarySetup(tilt_deg=20.0, dpi_y=720.0))
    from rotoprint.rotary.head import nozzle_layout

    dphi, _ = swathe_clock(sp, 0, dpi_y=720.0, ref_radius_mm=None)
    xy = nozzle_layout(head, sp.mount(0)).xy_mm + np.array([0.02, 0.0])
    spacing = np.hypot(xy[:, 0], xy[:, 1]) * dphi
    f = fr[1][0]
    en = sp.swathes[0].enabled.copy()
    en[[10, 11]] = False
    assert (f[~en] == 0).all() and f[en].max() == pytest.approx(1.0) and f[en].min() > 0.5
    k = np.flatnonzero(en)
    assert np.allclose(f[k] / f[k].max(), spacing[k] / spacing[k].max())
    # a preset name, a device or a bare head; the manifest records the device's name only
    d = np.full((20, 20), 255, np.uint8)
    pl = Placement(20, 20, PX, PX, inner_radius_mm=60.0)
    m1 = transform_passes(d, "omnidot760", pl, tmp_path / "a.png", PassOptions(RotarySetup(tilt_deg=0.0), passes=2))
    m2 = transform_passes(d, head, pl, tmp_path / "b.png", PassOptions(RotarySetup(tilt_deg=0.0), passes=2, balance=True))
    assert m1["device"] == "omnidot760" and m2["device"] == "" and m2["balance"] is True and m1["balance"] is False
    assert len(read_passes(tmp_path / "a-passes.json")) == 2 and m1["pass_plan"] == m2["pass_plan"]


def test_clock_within_the_cost_floor(head):
    """However narrow the footprint, a pass's clock is at most MAX_CLOCK_FACTOR x native; a plan
    is refused only when its largest gap is not narrower than the footprint."""
    sp = plan_swathes(head, tilt_deg=70.0, inner_radius_mm=60.0, outer_radius_mm=75.0)
    pp = plan_passes(head, sp, footprint_um=40.0, passes=4)
    fit = np.sqrt((0.85 * 0.040) ** 2 - pp.largest_gap_mm**2)
    assert fit < 25.4 / head.dpi_y / MAX_CLOCK_FACTOR  # the fit alone would ask for > 2 x native
    assert pp.dpi_y == pytest.approx(MAX_CLOCK_FACTOR * head.dpi_y)
    wide = plan_passes(head, sp, footprint_um=200.0, passes=4)
    assert wide.dpi_y == pytest.approx(head.dpi_y)  # never coarser than native
    with pytest.raises(GeometryError, match="not less than the 20.0 um footprint"):
        plan_passes(head, sp, footprint_um=20.0, passes=2)
