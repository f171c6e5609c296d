"""Exact and paper transforms, swathes, simulator: invariants and the acceptance round trip."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint import ConfigError, GeometryError, ImageError, load_device
from rotoprint.rotary import Placement, exact_maps, plan_swathes, simulate, transform_exact
from rotoprint.rotary.exact import firing_range
from rotoprint.rotary.head import nozzle_layout
from rotoprint.rotary.paper import paper_shifts, transform_paper
from rotoprint.rotary.testimage import test_design as make_design

HEAD = load_device("omnidot760").head
PX = 25.4 / 360


def _pl(n, r=60.0, dpi=360.0):
    return Placement(n, n, 25.4 / dpi, 25.4 / dpi, inner_radius_mm=r)


@pytest.mark.parametrize("backend", ["jit", "numpy"])
@pytest.mark.parametrize("tilt", [0.0, 33.0, -25.0])
def test_kernels_agree_and_hit_their_pixel(backend, tilt):
    pl = _pl(80)
    m = exact_maps(HEAD, pl, tilt_deg=tilt, backend=backend)
    if backend == "jit":  # the jit maps against the numpy reference
        ref = exact_maps(HEAD, pl, tilt_deg=tilt, backend="numpy")
        for a, b in zip(m.swathes, ref.swathes):
            np.testing.assert_array_equal(a.index, b.index)
            assert a.first_firing == b.first_firing
    # forward check: the landing point of every mapped drop lies in the pixel it samples
    sm = m.swathes[0]
    i, k = np.nonzero(sm.index != pl.width_px * pl.height_px)
    ang = sm.layout.phi_rad[k] - (i + sm.first_firing) * sm.dphi_rad
    col, row = pl.to_design(sm.layout.r_mm[k] * np.cos(ang), sm.layout.r_mm[k] * np.sin(ang))
    np.testing.assert_array_equal(np.floor(row).astype(int) * pl.width_px + np.floor(col).astype(int), sm.index[i, k])


def test_maps_cached():
    pl = _pl(40)
    assert exact_maps(HEAD, pl, tilt_deg=10.0) is exact_maps(HEAD, pl, tilt_deg=10.0)


def test_firing_range_covers_the_design():
    pl = _pl(100)
    m = exact_maps(HEAD, pl, tilt_deg=20.0)
    sm = m.swathes[0]
    hit = (sm.index != 100 * 100).any(axis=1)
    assert hit[0] and hit[-1]  # trimmed to the firings that see the design
    assert firing_range(np.array([0.1]), -0.01, 0.01, 0.001, -1) == (-110, -90)


def test_placement_round_trip():
    pl = Placement(50, 30, 0.05, 0.08, inner_radius_mm=40.0, angle_deg=33.0)
    c, r = np.meshgrid(np.linspace(-3, 60, 7), np.linspace(-2, 40, 5))
    x, y = pl.to_platform(c, r)
    c2, r2 = pl.to_design(x, y)
    np.testing.assert_allclose(c2, c, atol=1e-9)
    np.testing.assert_allclose(r2, r, atol=1e-9)
    lo, hi = pl.radial_range_mm()
    assert lo == 40.0 and hi == pytest.approx(np.hypot(40 + 2.5, 1.2))


@pytest.mark.parametrize("tilt", [0.0, 20.0, 45.0, 70.0])
def test_swathes_meet_without_gap_or_double_track(tilt):
    plan = plan_swathes(HEAD, tilt_deg=tilt, inner_radius_mm=30.0, outer_radius_mm=150.0)
    assert len(plan) >= 2
    tracks = []
    for j, sw in enumerate(plan.swathes):
        lay = nozzle_layout(HEAD, plan.mount(j))
        r = lay.r_mm[sw.enabled]
        assert r.min() >= sw.band_mm[0] and r.max() < sw.band_mm[1]
        tracks.append(np.sort(r))
        if j:
            assert sw.band_mm[0] == plan.swathes[j - 1].band_mm[1]  # bands partition the range
            gap = r.min() - tracks[j - 1].max()
            inner_gaps = np.diff(tracks[j - 1])
            assert 0 < gap <= inner_gaps.max() + 1e-9  # no double track, no gap wider than inside a swathe
            assert gap == pytest.approx(plan.swathes[j - 1].pitch_mm, rel=1e-6)
    allr = np.concatenate(tracks)
    assert np.unique(np.round(allr, 9)).size == allr.size
    assert tracks[0].min() > 30.0 and tracks[-1].max() < 150.0


def test_max_swathes_error_says_how_many():
    with pytest.raises(GeometryError, match=r"needs 3 swathes.*at most 1"):
        plan_swathes(HEAD, tilt_deg=0.0, inner_radius_mm=30.0, outer_radius_mm=150.0, max_swathes=1)


def test_dead_nozzles_never_fire():
    h = HEAD.model_copy(update={"dead_nozzles": (10, 11, 300)})
    pr = transform_exact(np.full((60, 60), 255, np.uint8), h, _pl(60), tilt_deg=20.0)
    for s in pr.swathes:
        assert not s.levels[:, [10, 11, 300]].any()


def test_bad_design_refused():
    with pytest.raises(ImageError, match="uint8"):
        transform_exact(np.zeros((10, 10), np.uint16), HEAD, _pl(10), tilt_deg=0.0)
    with pytest.raises(ImageError, match="2-D"):
        transform_exact(np.zeros((10, 10, 3), np.uint8), HEAD, _pl(10), tilt_deg=0.0)
    with pytest.raises(ConfigError, match="tilts >= 0"):
        transform_paper(np.zeros((10, 10), np.uint8), HEAD, _pl(10), tilt_deg=-5.0)


def test_grey_design_levels():
    h = HEAD.model_copy(update={"grey_levels": 3})
    d = np.tile(np.linspace(0, 255, 40).astype(np.uint8), (40, 1))
    pr = transform_exact(d, h, _pl(40), tilt_deg=10.0)
    lev = pr.swathes[0].levels
    assert set(np.unique(lev).tolist()) == {0, 1, 2, 3}


def test_paper_shifts_hand_values():
    # tilt 0, 2 rows: from -/+ d/(2 p_y) with parallax towards 0 at the outer end
    c = paper_shifts(HEAD, tilt_deg=0.0, cx_T_mm=60.0, pitch_y_mm=PX)
    half = HEAD.row_separation_mm / 2 / PX
    assert c[0] == pytest.approx(-half) and c[1] == pytest.approx(half)
    L = 762 * HEAD.pitch_mm
    assert c[762] == pytest.approx(-half + half * L / (60 + L))


def test_simulator_detects_a_misplaced_print():
    d = np.zeros((80, 80), np.uint8)
    d[20:60, 20:60] = 255
    pr = transform_exact(d, HEAD, _pl(80), tilt_deg=20.0)
    good = simulate(pr, d).report
    shifted = type(pr)(**{**pr.__dict__, "swathes": tuple(type(s)(**{**s.__dict__, "first_firing": s.first_firing + 10}) for s in pr.swathes)})
    bad = simulate(shifted, d).report
    assert good.iou > 0.97 and good.drops_outside == 0
    assert bad.iou < 0.8 and bad.drops_outside > 0 and bad.mean_error_px > good.mean_error_px
    dead = simulate(pr, d, dead_nozzles=tuple(range(0, 764, 2))).report
    assert dead.uncovered_fraction > good.uncovered_fraction
    jit = simulate(pr, d, jitter_um=40.0, seed=1).report
    assert jit.mean_error_px > good.mean_error_px


@pytest.fixture(scope="module")
def acceptance_design():
    return make_design(1200)


@pytest.mark.parametrize("tilt", [0.0, 20.0, 45.0, 70.0])
def test_acceptance_round_trip_1200(acceptance_design, tilt):
    d = acceptance_design
    pl = Placement(1200, 1200, PX, PX, inner_radius_mm=60.0)
    pr = transform_exact(d, HEAD, pl, tilt_deg=tilt)
    assert len(pr.swathes) >= 2  # 84.7 mm square: several swathes
    r = simulate(pr, d).report
    assert r.mean_error_px <= 0.5
    assert r.iou >= 0.98
    assert r.drops_outside == 0
