"""The deposit model: drops become a film on a fine grid (rotary/deposit.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import ConfigError, ImageError, RasterTooLargeError
from rotoprint.rotary import Placement, transform_exact
from rotoprint.rotary import _deposit_kernels as K
from rotoprint.rotary.deposit import (
    DepositOptions,
    InkDrops,
    cap_height_um,
    deposit_film,
    deposit_print,
    flight_diameter_um,
    footprint_diameter_um,
)
from rotoprint.rotary.testimage import test_design as make_design

PX = 25.4 / 360


@pytest.fixture(scope="module")
def head():
    return load_device("omnidot760").head


def lattice(w_px, h_px, step_px, vol=8.0, shift=(0.0, 0.0)):
    c = np.arange(0.5 * step_px, w_px, step_px) + shift[0]
    r = np.arange(0.5 * step_px, h_px, step_px) + shift[1]
    cc, rr = np.meshgrid(c, r)
    return InkDrops(cc.ravel(), rr.ravel(), np.full(cc.size, vol))


def test_drop_sizes():
    # d0 = (6 V / pi)^(1/3), 1 pl = 1000 um^3
    assert flight_diameter_um(8.0) == pytest.approx((6 * 8000 / math.pi) ** (1 / 3))
    assert footprint_diameter_um(40.0, 2.0) == pytest.approx(2 * 42.43, abs=0.01)
    v = np.array([100.0, 8000.0, 40000.0])
    a = np.array([5.0, 24.8, 60.0])
    h = cap_height_um(v, a)
    assert np.allclose(np.pi * h * (3 * a**2 + h**2) / 6, v)


def test_jit_matches_numpy(head):
    rng = np.random.default_rng(3)
    m = 40
    u, v = rng.uniform(5, 45, m), rng.uniform(5, 45, m)
    a = rng.uniform(3, 30, m)
    vol = rng.uniform(100, 9000, m)
    h = cap_height_um(vol, a)
    rs = (a * a + h * h) / (2 * h)
    oj, on = np.zeros((30, 50)), np.zeros((30, 50))
    K.deposit_strip_jit(u, v, vol, a, rs, h, 7.0, 9.0, 10, oj)
    K.deposit_strip_numpy(u, v, vol, a, rs, h, 7.0, 9.0, 10, on)
    assert np.allclose(oj, on) and oj.sum() > 0


@pytest.mark.parametrize("footprint_um", [5.0, 49.6, 140.0])
def test_volume_conserved(head, footprint_um):
    rng = np.random.default_rng(1)
    pl = Placement(40, 30, PX, PX, inner_radius_mm=60.0)
    m = 500
    drops = InkDrops(rng.uniform(0, 40, m), rng.uniform(0, 30, m), rng.uniform(1, 8, m))
    dep = deposit_film(np.ones((30, 40), bool), pl, head, [drops], options=DepositOptions(footprint_um=footprint_um, strip_cells=10_000), keep_map=True)
    f = dep.films[0]
    assert f.planned_volume_pl == pytest.approx(drops.volume_pl.sum())
    assert abs(f.volume_error_fraction) < 1e-9
    gx, gy = f.grid_um
    assert dep.thickness.sum() * gx * gy / 1000 == pytest.approx(f.planned_volume_pl, rel=1e-9)


def test_strips_do_not_change_figures(head):
    pl = Placement(60, 50, PX, PX, inner_radius_mm=30.0)
    mask = make_design(60)[:50] > 0
    drops = lattice(60, 50, 0.8)
    a = deposit_film(mask, pl, head, [drops], options=DepositOptions(strip_cells=10_000)).films[0]
    b = deposit_film(mask, pl, head, [drops], options=DepositOptions(strip_cells=10_000_000)).films[0]
    c = deposit_film(mask, pl, head, [drops], use_jit=False).films[0]
    for k in ("uncovered_fraction", "band_uncovered_fraction", "interior_area_mm2", "mean_um", "thinnest_um",
              "deposited_volume_pl", "radial_spread"):
        assert getattr(b, k) == pytest.approx(getattr(a, k), rel=1e-9, abs=1e-12)
        assert getattr(c, k) == pytest.approx(getattr(a, k), rel=1e-9, abs=1e-12)
    assert a.uncovered_fraction > 0


def test_disjoint_footprints_cover_their_disc_area(head):
    # footprint D = 0.8 x lattice step: discs do not touch, covered share = pi (0.4)^2
    pl = Placement(80, 80, PX, PX, inner_radius_mm=100.0)
    step_um = PX * 1000
    f = deposit_film(np.ones((80, 80), bool), pl, head, [lattice(80, 80, 1.0)],
                     options=DepositOptions(footprint_um=0.8 * step_um, cells_per_footprint=30)).films[0]
    assert f.uncovered_fraction == pytest.approx(1 - math.pi * 0.16, abs=0.01)
    assert f.thinnest_um == 0.0 and f.thinnest_to_mean == 0.0
    # D = 1.5 x step > step * sqrt(2): every point is within D / 2 of a site
    f = deposit_film(np.ones((80, 80), bool), pl, head, [lattice(80, 80, 1.0)],
                     options=DepositOptions(footprint_um=1.5 * step_um)).films[0]
    assert f.uncovered_fraction == 0.0 and f.thinnest_um > 0
    # mean thickness: the volume per lattice cell over its area (8 pl = 8000 um^3)
    assert f.mean_um == pytest.approx(8000 / step_um**2, rel=0.02)
    assert f.radial_spread < 0.02


def test_interior_is_design_less_half_a_footprint(head):
    pl = Placement(100, 100, PX, PX, inner_radius_mm=60.0)
    mask = np.zeros((100, 100), bool)
    mask[20:80, 10:90] = True
    f = deposit_film(mask, pl, head, [lattice(100, 100, 0.5)], options=DepositOptions(footprint_um=300.0)).films[0]
    w, h = 80 * PX, 60 * PX
    d = 0.3
    assert f.design_area_mm2 == pytest.approx(w * h, rel=1e-9)
    assert f.interior_area_mm2 == pytest.approx((w - d) * (h - d), rel=0.01)
    assert f.band_area_mm2 == pytest.approx(w * h - f.interior_area_mm2, rel=1e-9)
    # every lattice site outside the rectangle counts as a drop outside
    inside = (np.floor(lattice(100, 100, 0.5).col) >= 10) & (np.floor(lattice(100, 100, 0.5).col) < 90)
    inside &= (np.floor(lattice(100, 100, 0.5).row) >= 20) & (np.floor(lattice(100, 100, 0.5).row) < 80)
    assert f.drops_outside == int((~inside).sum())
    assert 0 < f.volume_outside_design_fraction < 1


def test_interior_kernel_is_the_distance_transforms_threshold():
    """interior_rows_jit gives what scipy's distance_transform_edt (with the cells' sampling)
    thresholded gives, on block masks like an upsampled design, any core rows, square and
    non-square cells, thresholds at and between whole cells."""
    from scipy import ndimage

    rng = np.random.default_rng(0)
    for trial in range(150):
        rows, cols = int(rng.integers(5, 90)), int(rng.integers(5, 90))
        by, bx = int(rng.integers(1, 6)), int(rng.integers(1, 6))
        m = np.kron(rng.random((rows // by + 1, cols // bx + 1)) < 0.8, np.ones((by, bx), bool))[:rows, :cols]
        m[:, :2] = False
        gx, gy = float(rng.uniform(5, 15)), float(rng.uniform(5, 15))
        if trial % 3 == 0:
            gy = gx
        thr = float(rng.uniform(3, 60)) if trial % 5 else 4 * gx
        c0 = int(rng.integers(0, rows))
        c1 = int(rng.integers(c0 + 1, rows + 1))
        want = (ndimage.distance_transform_edt(m, sampling=(gy, gx)) >= thr)[c0:c1] & m[c0:c1]
        got = np.empty((c1 - c0, cols), bool)
        K.interior_rows_jit(m, c0, c1, thr, gx, gy, got)
        assert np.array_equal(got, want), trial


def test_reagent_pair(head):
    pl = Placement(60, 60, PX, PX, inner_radius_mm=60.0)
    mask = np.ones((60, 60), bool)
    a = lattice(60, 60, 1.0)
    b = InkDrops(a.col[a.col < 30], a.row[a.col < 30], a.volume_pl[a.col < 30])
    dep = deposit_film(mask, pl, head, [a, b], options=DepositOptions(footprint_um=120.0), pairs=[(0, 1)])
    p = dep.pairs[0]
    assert p["a_not_b_fraction"] == pytest.approx(0.5, abs=0.03)
    assert p["b_not_a_fraction"] == 0.0
    assert "reagent_pairs" in dep.to_json() and len(dep.to_json()["films"]) == 2


def test_bad_input(head):
    pl = Placement(10, 10, PX, PX, inner_radius_mm=60.0)
    d = lattice(10, 10, 1.0)
    with pytest.raises(ImageError, match="10 x 10"):
        deposit_film(np.ones((9, 10), bool), pl, head, [d])
    with pytest.raises(ConfigError, match="pair"):
        deposit_film(np.ones((10, 10), bool), pl, head, [d], pairs=[(0, 1)])
    with pytest.raises(ConfigError, match="cells_per_footprint"):
        DepositOptions(cells_per_footprint=1)
    with pytest.raises(ConfigError, match="volumes"):
        InkDrops(np.zeros(1), np.zeros(1), np.array([-1.0]))
    big = Placement(300_000, 10, PX, PX, inner_radius_mm=60.0)
    with pytest.raises(RasterTooLargeError, match="cells"):
        deposit_film(np.ones((10, 300_000), bool), big, head, [d])


def test_print_deposit_tilt0_vs_interlaced_clock(head):
    """At the native lattice (70.4 x 70.6 um) 49.6 um footprints leave holes; at a clock
    with drops 1/3 as far apart along the track they still leave the gaps between tracks."""
    d = make_design(120)
    pl = Placement(120, 120, PX, PX, inner_radius_mm=60.0)
    pr = transform_exact(d, head, pl, tilt_deg=0.0)
    f = deposit_print(pr, d).films[0]
    assert f.uncovered_fraction > 0.3  # 49.6 um discs on a ~70 um square lattice: pi 24.8^2 / 70^2 ~ 0.4 covered
    assert abs(f.volume_error_fraction) < 0.005
    pr3 = transform_exact(d, head, pl, tilt_deg=0.0, dpi_y=3 * 360.0)
    f3 = deposit_print(pr3, d).films[0]
    # tracks 70.4 um apart, footprints 49.6 um: a stripe of ~21 um between every two tracks
    assert f3.uncovered_fraction == pytest.approx(1 - 49.6 / 70.4, abs=0.05)


def test_simulate_cli_has_deposit_headline(run_cli, tmp_path):
    import json
    import math

    from rotoprint.io.images import write_png

    p = tmp_path / "d.png"
    write_png(p, make_design(100))
    out = tmp_path / "p.png"
    code, _, err = run_cli("transform", p, "--device", "omnidot760", "--tilt", "20", "--radius", "60", "--out", out)
    assert code == 0, err
    code, o, err = run_cli("simulate", out, "--out", tmp_path / "ov.png", "--json", "--spread", "3")
    assert code == 0, err
    dep = json.loads(o)["deposit"]
    assert 0 <= dep["uncovered_fraction"] <= 1 and dep["spread_factor"] == 3.0
    assert dep["footprint_um"] == pytest.approx(3 * (6 * 8000 / math.pi) ** (1 / 3))
    code, o, err = run_cli("simulate", out, "--out", tmp_path / "ov.png")
    assert code == 0 and "interior uncovered" in o
    code, o, err = run_cli("simulate", out, "--out", tmp_path / "ov.png", "--spread", "2", "--footprint", "50")
    assert code == 2 and "either" in err
