"""Pass plans: order, repeats, cycles from the thickness estimate, priority on overlap, and
every layer's images equal to the direct rotary slicer's output for that material."""

from __future__ import annotations

import numpy as np
import pytest

from _build_helpers import box_part, job_dict
from rotoprint import load_device
from rotoprint.mesh import Mesh
from rotoprint.process import parse_job, plan_job
from rotoprint.rotary import simulate
from rotoprint.rotary.direct import slice_rotary
from rotoprint.testing import box_triangles


def _levels(pr):
    return [s.levels for s in pr.swathes]


def test_build_pass_order_repeats_and_post_steps():
    parts = [box_part("body", "plaster", 1, (6, 4, 0.1)), box_part("track", "silver", 2, (4, 1, 0.05), (1, 1.5, 0.05))]
    plan = plan_job(parse_job(job_dict(parts, layer_height_mm=0.05, process={"cycles_per_layer": {"silver": 3}, "max_passes_per_layer": 400})))
    assert len(plan) == 2
    L0, L1 = plan.layer(0), plan.layer(1)
    assert [b.material for b in L0.blocks] == ["plaster"]
    assert [b.material for b in L1.blocks] == ["plaster", "silver"]
    pl, ag = L1.blocks
    assert [(p.ink, p.repeats, p.head) for p in pl.passes] == [("ammonium_sulphate", 3, "H1"), ("calcium_chloride", 1, "H2")]
    assert [(p.ink, p.repeats, p.head) for p in ag.passes] == [("silver_nitrate", 1, "H3"), ("ascorbate", 1, "H4")]
    assert ag.cycles == 3 and ag.pass_count == 6 and ag.post_steps == ("flash heat at 150 C for 60 s (after the silver passes of each layer)",)
    seq = L1.sequence()
    kinds = [(s["kind"], s.get("ink") or s.get("step")) for s in seq]
    n_pl = pl.cycles * 2
    assert kinds[:4] == [("pass", "ammonium_sulphate"), ("pass", "calcium_chloride")] * 2
    assert kinds[n_pl:n_pl + 2] == [("pass", "silver_nitrate"), ("pass", "ascorbate")]
    assert kinds[-1][0] == "post" and "flash heat" in kinds[-1][1]
    assert sum(1 for k in kinds if k[0] == "pass") == n_pl + 6
    # cycles: the fewest that reach the layer height at the thinnest point, a multiple of the interlaced passes
    est = plan.estimates["plaster"]
    n = est.interlace_passes
    assert n == plan.heads[0].passes > 1 and est.cycles % n == 0
    assert est.cycles * est.per_cycle_um[0] >= 50.0 > (est.cycles - n) * est.per_cycle_um[0]
    assert any("crystallises" in w for w in plan.warnings)
    assert any("silver: 3 cycle(s) per layer" in w for w in plan.warnings)


def test_build_too_many_passes_warns_and_caps():
    parts = [box_part("track", "silver", 2, (4, 1, 0.05))]
    plan = plan_job(parse_job(job_dict(parts, layer_height_mm=0.05, process={"max_passes_per_layer": 40})))
    est = plan.estimates["silver"]
    assert est.cycles_needed * 2 > 40 and est.cycles == 20 and est.passes_per_layer == 40
    assert any("more than process.max_passes_per_layer = 40" in w for w in plan.warnings)


@pytest.mark.parametrize("equalise", [False, True])
def test_build_density_follows_one_over_r(equalise):
    parts = [box_part("body", "plaster", 1, (40, 6, 0.05))]
    plan = plan_job(parse_job(job_dict(parts, tilt_deg=0.0, equalise=equalise)))
    h = plan.head("H1")
    d_in, d_out = h.density_at(61.0), h.density_at(99.0)
    if equalise:
        # interlaced passes (the default): the union's shares make the measured drops per mm^2
        # of every 1 mm bin even (one pass's tracks are not: its shares are the union's)
        d = plan.estimates["plaster"].drops_per_mm2["ammonium_sulphate"]
        assert h.passes > 1 and float(np.abs(d / d.mean() - 1).max()) < 0.05, d  # plain: 99 / 61
        assert not any("varies by" in w for w in plan.warnings)
        one = plan_job(parse_job(job_dict(parts, tilt_deg=0.0, equalise=True, passes=1))).head("H1")
        assert one.density_at(61.0) == pytest.approx(one.density_at(99.0), rel=1e-9)  # one pass: every track
    else:
        assert d_in / d_out == pytest.approx(99.0 / 61.0, rel=0.01)
        assert any("varies by" in w and "equalise" in w for w in plan.warnings)
        est = plan.estimates["plaster"]
        assert est.per_cycle_um[1] / est.per_cycle_um[0] == pytest.approx(est.band_mm[1] / est.band_mm[0], rel=0.02)


@pytest.mark.parametrize("equalise", [False, True])
def test_build_single_part_images_equal_the_direct_slicer(equalise):
    """One part: the union footprint is the part's, so each head's image must be exactly
    slice_rotary's for the part at angle (placement angle - mount angle)."""
    parts = [{"name": "ring", "material": "plaster", "priority": 1,
              "shape": {"kind": "cylinder", "radius_mm": 4.0, "height_mm": 0.15, "segments": 40}}]
    job = parse_job(job_dict(parts, equalise=equalise, passes=1))  # interlaced passes: tests/process/test_build_passes.py
    plan = plan_job(job)
    dev = load_device("omnidot760")
    mesh = Mesh.from_triangles(job.spec.parts[0].shape.triangles())
    for h in plan.heads:
        ref = slice_rotary(mesh, dev, layer_height_mm=0.05, tilt_deg=20.0, inner_radius_mm=60.0,
                           angle_deg=0.0 - h.mount_angle_deg, equalise=equalise)
        assert len(ref) == len(plan) == 3
        for i in range(len(plan)):
            L = plan.layer(i)
            if ("plaster", h.ink) not in L.images:
                continue
            pr = L.images[("plaster", h.ink)]
            assert pr.mount_angle_deg == h.mount_angle_deg
            for a, b in zip(_levels(pr), _levels(ref.layer(i)), strict=True):
                np.testing.assert_array_equal(a, b)


def test_build_priority_on_overlap():
    """Two overlapping boxes: the higher priority keeps every drop of its own slice, the lower
    loses exactly the sites inside the higher one, and no site prints both materials."""
    parts = [box_part("body", "plaster", 1, (8, 6, 0.05)), box_part("pad", "epoxy", 5, (3, 3, 0.05), (4, 2, 0.0))]
    heads = [{"name": "A", "ink": "ammonium_sulphate"}, {"name": "B", "ink": "calcium_chloride", "mount_angle_deg": 90.0},
             {"name": "C", "ink": "polyepoxide"}, {"name": "D", "ink": "diamine", "mount_angle_deg": 90.0}]
    job = parse_job(job_dict(parts, heads=heads, equalise=False))
    plan = plan_job(job)
    L = plan.layer(0)
    sec = plan.sections(0)
    for ink_pl, ink_ep in (("ammonium_sulphate", "polyepoxide"), ("calcium_chloride", "diamine")):
        h = plan.head(ink_pl)
        assert plan.head(ink_ep).mount_angle_deg == h.mount_angle_deg  # same lattice: compare sites
        body_alone = h.lattice.print_from_segments(sec["body"], layer_index=0)
        pad_alone = h.lattice.print_from_segments(sec["pad"], layer_index=0)
        pl = L.images[("plaster", ink_pl)]
        ep = L.images[("epoxy", ink_ep)]
        for a, b, ba, pa in zip(_levels(pl), _levels(ep), _levels(body_alone), _levels(pad_alone), strict=True):
            assert not ((a > 0) & (b > 0)).any()
            np.testing.assert_array_equal(b, pa)
            np.testing.assert_array_equal(a > 0, (ba > 0) & ~(pa > 0))
            assert ((ba > 0) & (pa > 0)).sum() > 1000
    # the reference (Cartesian) region of plaster excludes the pad
    ref_pl = plan.reference_image("plaster", sec)
    ref_ep = plan.reference_image("epoxy", sec)
    assert not (ref_pl & ref_ep).any() and ref_ep.sum() > 0


def test_build_two_parts_of_one_material_and_layers_shared():
    """Parts at different heights share the assembly's layers; each layer's image is the
    slicer's print of the part's own cross-section at that layer's height."""
    parts = [box_part("low", "plaster", 1, (4, 4, 0.1)), box_part("high", "plaster", 1, (4, 4, 0.1), (6, 0, 0.1))]
    plan = plan_job(parse_job(job_dict(parts)))
    assert len(plan) == 4
    for i in range(4):
        sec = plan.sections(i)
        assert bool(len(sec["low"])) == (i < 2) and bool(len(sec["high"])) == (i >= 2)
        L = plan.layer(i)
        for h in plan.heads:
            key = ("plaster", h.ink)
            want = h.lattice.print_from_segments(sec["low" if i < 2 else "high"], layer_index=i)
            for a, b in zip(_levels(L.images[key]), _levels(want), strict=True):
                np.testing.assert_array_equal(a, b)


def test_build_simulator_handles_a_head_half_a_turn_away():
    """A design 180 degrees from the head (e.g. the head mounted opposite the part)."""
    dev = load_device("omnidot760")
    mesh = Mesh.from_triangles(box_triangles((8, 6, 0.1)))
    for angle in (0.0, 150.0, 180.0, -170.0):
        job = slice_rotary(mesh, dev, layer_height_mm=0.1, tilt_deg=20.0, inner_radius_mm=60.0, angle_deg=angle)
        sim = simulate(job.layer(0), job.reference_image(0))
        assert sim.report.iou > 0.97, angle
