"""Levelling of the wet film under surface tension (rotary/deposit.py LevelOptions, rotary/_levelling.py)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from pydantic import ValidationError

from rotoprint import load_device
from rotoprint.devices.models import InkjetHead
from rotoprint.errors import ConfigError
from rotoprint.rotary import Placement
from rotoprint.rotary import _levelling as LV
from rotoprint.rotary.deposit import DepositOptions, InkDrops, LevelOptions, deposit_film, levelling_rate_um4_per_s

PX = 25.4 / 360


@pytest.fixture(scope="module")
def head():
    return load_device("omnidot760").head  # the preset levels (set time 1 s)


def lattice(w_px, h_px, step_px, vol=8.0):
    c = np.arange(0.5 * step_px, w_px, step_px)
    r = np.arange(0.5 * step_px, h_px, step_px)
    cc, rr = np.meshgrid(c, r)
    return InkDrops(cc.ravel(), rr.ravel(), np.full(cc.size, vol))


def test_rate_and_the_briefs_numbers():
    # 30 mN/m, 10 mPa s, 10 um: D = 1e-15 m^4/s; a ripple's e-folding time 1 / (D k^4)
    d = levelling_rate_um4_per_s(30.0, 10.0, 10.0)
    assert d == pytest.approx(1e9)
    tau = {lam: 1.0 / (d * (2 * math.pi / lam) ** 4) for lam in (35.0, 1000.0, 10_000.0)}
    assert tau[35.0] < 2e-6  # microseconds
    assert 0.5 < tau[1000.0] < 0.7  # ~0.6 s
    assert tau[10_000.0] > 5000.0  # not at all within a second
    assert levelling_rate_um4_per_s(30.0, 10.0, 5.0) == pytest.approx(d / 8)  # h0^3


def test_kernel_is_symmetric_normalised():
    g = LV.levelling_kernel(1e9, 8.8, 8.8, 10.0)
    assert g.shape[0] % 2 == 1 and g.shape[0] == g.shape[1]
    assert g.sum() == pytest.approx(1.0, abs=1e-14)
    assert np.array_equal(g, g[::-1, :]) and np.array_equal(g, g[:, ::-1])
    assert g.min() < 0  # the k^4 kernel has negative side lobes
    assert g.min() > -0.1 * g.max()


def test_ripple_decays_as_orchard():
    """A sinusoidal ripple on a wide wet film decays by exp(-D k^4 t) (the kernel's truncation
    at 10 levelling lengths moves the amplitude by < 0.1 % of the initial one, 2 % of the
    remaining one here)."""
    g_um, lam_um = 10.0, 400.0
    rows, cols = 700, 1000
    x = (np.arange(cols) + 0.5) * g_um
    film = 10.0 + 2.0 * np.cos(2 * math.pi * x / lam_um)[None, :] * np.ones((rows, 1))
    for t in (0.05, 0.3):
        dt = levelling_rate_um4_per_s(30.0, 10.0, 10.0) * t
        kern = LV.levelling_kernel(dt, g_um, g_um, 10.0)
        hx = (kern.shape[1] - 1) // 2
        lev = LV.level_window(film, kern, slice(0, rows))
        mid = lev[rows // 2, 2 * hx + 80: cols - 2 * hx - 80]
        amp = 0.5 * (mid.max() - mid.min())
        want = 2.0 * math.exp(-dt * (2 * math.pi / lam_um) ** 4)
        assert amp == pytest.approx(want, rel=0.02, abs=2e-3), (t, amp, want)
    # a flat film stays flat up to its pinned edge, and keeps its volume
    flat = np.zeros((300, 300))
    flat[50:250, 40:260] = 7.0
    kern = LV.levelling_kernel(levelling_rate_um4_per_s(30.0, 10.0, 10.0) * 0.01, g_um, g_um, 10.0)
    lev = LV.level_window(flat, kern, slice(0, 300))
    assert np.abs(lev[flat > 0] - 7.0).max() < 1e-9 and (lev[flat == 0] == 0).all()


def test_set_time_zero_is_the_film_as_landed(head):
    pl = Placement(24, 24, PX, PX, inner_radius_mm=60.0)
    mask = np.ones((24, 24), bool)
    drops = lattice(24, 24, 0.55)
    plain = deposit_film(mask, pl, head, [drops]).films[0]
    zero = deposit_film(mask, pl, head, [drops], options=DepositOptions(level=LevelOptions(set_time_s=0.0))).films[0]
    lev = deposit_film(mask, pl, head, [drops], options=DepositOptions(level=LevelOptions(set_time_s=0.2))).films[0]
    assert zero.levelled is None and "levelled" not in zero.to_json()
    assert zero.to_json() == plain.to_json()
    d = lev.to_json()
    assert d.pop("levelled")["set_time_s"] == 0.2
    assert d == plain.to_json()  # the as-landed figures are unchanged beside the levelled ones


def test_levelling_evens_the_drop_scale_ripple_and_conserves_volume(head):
    # drops 0.48 px (34 um) apart with 49.6 um footprints: covered, with a drop-scale ripple
    n = 30
    pl = Placement(n, n, PX, PX, inner_radius_mm=60.0)
    mask = np.ones((n, n), bool)
    drops = lattice(n, n, 0.48)
    d = deposit_film(mask, pl, head, [drops], keep_map=True, options=DepositOptions(level=LevelOptions(set_time_s=1e-3)))
    f = d.films[0]
    lv = f.levelled
    assert f.uncovered_fraction == 0.0 and f.thinnest_to_mean < 0.4
    assert lv.thinnest_to_mean > 0.8  # the interior's thinnest: by its corners, where the film ends
    mid = (slice(100, -100), slice(100, -100))
    landed, lev = d.thickness[mid], d.levelled_thickness[mid]
    assert landed.min() / landed.mean() < 0.4 and lev.min() / lev.mean() > 0.97
    assert abs(lv.volume_error_fraction) < 1e-9
    assert lv.h0_rule.startswith("p10") and 0 < lv.h0_um < f.mean_um


def test_tiling_does_not_change_the_levelled_film_and_dry_stays_dry(head):
    n = 40
    pl = Placement(n, n, PX, PX, inner_radius_mm=60.0)
    mask = np.ones((n, n), bool)
    mask[12:20, 15:30] = False  # a hole in the design: not printed, dry
    rng = np.random.default_rng(3)
    c, r = rng.uniform(0, n, 6000), rng.uniform(0, n, 6000)
    keep = mask[r.astype(int), c.astype(int)]
    drops = InkDrops(c[keep], r[keep], np.full(int(keep.sum()), 8.0))
    maps = []
    for cells in (10_000, 200_000, 50_000_000):
        d = deposit_film(mask, pl, head, [drops], keep_map=True,
                         options=DepositOptions(level=LevelOptions(set_time_s=0.1, window_cells=cells)))
        lv = d.films[0].levelled
        assert abs(lv.volume_error_fraction) < 1e-9
        landed, lev = d.thickness, d.levelled_thickness
        assert (lev[landed <= 0] == 0).all()  # dry cells stay dry (pinned contact line)
        assert lev.sum() == pytest.approx(landed.sum(), rel=1e-9)
        maps.append(lev)
    scale = float(maps[0].max())
    for m in maps[1:]:
        assert np.abs(m - maps[0]).max() < 1e-9 * scale
    # the small windows really were several strips
    hy = d.films[0].levelled.halo_cells[1]
    assert landed.shape[0] > 2 * hy


@pytest.mark.parametrize("set_time_s, factor", [(0.05, 10), (1e-4, 2)])
def test_coarse_grid_levels_as_the_exact_path(head, set_time_s, factor):
    """The default (convolutions on a grid f cells coarse, its cell within L / 3.5: f = 10 at
    L = 320 um, f = 2 at L = 68 um, the coil demo's levelling length) against the deposit-grid
    path on a small thick film with a hole: the same volume (1e-9), dry cells dry, the levelled
    thinnest within 1e-3 and mean within 2e-5 (relative), the map within 1e-3 of the mean
    everywhere; kept or re-deposited films (window_cells) give the same."""
    n = 60
    pl = Placement(n, n, PX, PX, inner_radius_mm=60.0)
    mask = np.ones((n, n), bool)
    mask[20:40, 20:28] = False
    rng = np.random.default_rng(5)
    cc, rr = np.meshgrid(np.arange(0.24, n, 0.48), np.arange(0.24, n, 0.48))
    c = (cc.ravel() + rng.normal(0, 0.08, cc.size)).clip(0, n - 1e-6)
    r = (rr.ravel() + rng.normal(0, 0.08, cc.size)).clip(0, n - 1e-6)
    keep = mask[r.astype(int), c.astype(int)]
    drops = InkDrops(c[keep], r[keep], rng.uniform(60.0, 100.0, int(keep.sum())))
    runs = {}
    for name, kw in (("exact", dict(exact=True)), ("coarse", {}), ("coarse, re-deposited", dict(window_cells=20_000))):
        lo = LevelOptions(set_time_s=set_time_s, **kw)
        runs[name] = deposit_film(mask, pl, head, [drops], keep_map=True, options=DepositOptions(level=lo))
    ex = runs["exact"].films[0].levelled
    assert ex.coarse_factor == 1 and runs["exact"].films[0].thinnest_to_mean < 0.6 < ex.thinnest_to_mean
    for name in ("coarse", "coarse, re-deposited"):
        d = runs[name]
        lv = d.films[0].levelled
        assert lv.coarse_factor == factor and lv.levelling_length_um == ex.levelling_length_um, name
        assert lv.thinnest_um == pytest.approx(ex.thinnest_um, rel=1e-3), name
        assert lv.mean_um == pytest.approx(ex.mean_um, rel=2e-5), name
        assert lv.radial_spread == pytest.approx(ex.radial_spread, abs=1e-3), name
        assert abs(lv.volume_error_fraction) < 1e-9 and d.levelled_thickness.sum() == pytest.approx(d.thickness.sum(), rel=1e-9)
        assert (d.levelled_thickness[d.thickness <= 0] == 0).all()
        assert np.abs(d.levelled_thickness - runs["exact"].levelled_thickness).max() < 1e-3 * ex.mean_um, name
    a, b = runs["coarse"].levelled_thickness, runs["coarse, re-deposited"].levelled_thickness
    assert np.abs(a - b).max() < 1e-9 * float(a.max())


def test_coarse_response_is_the_sampled_tents():
    """The round trip's response per axis: T^2 (T the box of f cells) at an odd f; at an even f
    the tent sampled at the cells' offsets is not a product of two boxes (f = 2: cos^3)."""
    k = np.linspace(1e-6, 0.3, 50)
    c = 8.8
    for f in (3, 5, 7):
        t = np.sin(0.5 * k * c * f) / (f * np.sin(0.5 * k * c))
        assert np.abs(LV._interp_response(k, c, f) - t * t).max() < 1e-12
    assert np.abs(LV._interp_response(k, c, 2) - np.cos(0.5 * k * c) ** 3).max() < 1e-12
    assert np.abs(LV._interp_response(k, c, 2) - np.cos(0.5 * k * c) ** 2).max() > 0.1
    assert LV._interp_response(np.zeros(1), c, 6)[0] == pytest.approx(1.0, abs=1e-15)


def test_coarse_grid_round_trip_is_symmetric_and_keeps_a_flat_film():
    from rotoprint.rotary import _levelling_kernels as LK

    rng = np.random.default_rng(1)
    rows, cols, f = 37, 53, 4
    rc, cc = -(-rows // f) + 2, -(-cols // f) + 2
    cx0, ctx = LK.axis_weights(cols, f)
    x = rng.uniform(0.5, 2.0, (rows, cols))
    y = rng.normal(size=(rc, cc))
    qtx, qtw = np.zeros((rc, cc)), np.zeros((rc, cc))
    LK.restrict_wet_jit(x, 0, f, cx0, ctx, qtx, qtw)
    qy = np.empty_like(x)
    LK.prolong_combine_jit(np.ones_like(x), 0, f, cx0, ctx, -y + 1.0, np.zeros_like(y), qy)  # h (1 - N) with N = 1 - y: Q y
    assert np.dot(qtx.ravel(), y.ravel()) == pytest.approx(np.dot(x.ravel(), qy.ravel()), rel=1e-12)  # <Q^T x, y> = <x, Q y>
    assert qtw.sum() == pytest.approx(rows * cols, rel=1e-12)
    # a wide flat film, restricted, convolved and interpolated back: flat well inside its edge
    rows = cols = 400
    flat = np.zeros((rows, cols))
    flat[20:380, 20:380] = 5.0
    f = 8
    rc, cc = -(-rows // f) + 2, -(-cols // f) + 2
    cx0, ctx = LK.axis_weights(cols, f)
    hc, wc = np.zeros((rc, cc)), np.zeros((rc, cc))
    LK.restrict_wet_jit(flat, 0, f, cx0, ctx, hc, wc)
    kern = LV.levelling_kernel(levelling_rate_um4_per_s(30.0, 10.0, 5.0) * 0.05, 10.0, 10.0, 6.0, factor=f)
    g, nn = LV.convolve_rows([hc, wc], kern, 10_000)
    out = np.empty_like(flat)
    LK.prolong_combine_jit(flat, 0, f, cx0, ctx, nn / f**2, g / f**2, out)
    assert np.abs(out[150:250, 150:250] - 5.0).max() < 1e-9 and (out[flat == 0] == 0).all()
    assert out.sum() == pytest.approx(flat.sum(), rel=1e-12)


def test_h0_choice(head):
    n = 24
    pl = Placement(n, n, PX, PX, inner_radius_mm=60.0)
    mask = np.ones((n, n), bool)
    drops = lattice(n, n, 0.48)
    lo = deposit_film(mask, pl, head, [drops], options=DepositOptions(level=LevelOptions(set_time_s=0.01, h0_percentile=5))).films[0].levelled
    hi = deposit_film(mask, pl, head, [drops], options=DepositOptions(level=LevelOptions(set_time_s=0.01, h0_percentile=90))).films[0].levelled
    fixed = deposit_film(mask, pl, head, [drops], options=DepositOptions(level=LevelOptions(set_time_s=0.01, h0_um=3.0))).films[0].levelled
    assert lo.h0_um < hi.h0_um and lo.levelling_length_um < hi.levelling_length_um
    assert fixed.h0_um == 3.0 and fixed.h0_rule == "fixed"
    # L = (sigma h0^3 t / (3 eta))^(1/4): a thinner h0 levels over a shorter length
    assert hi.levelling_length_um / lo.levelling_length_um == pytest.approx((hi.h0_um / lo.h0_um) ** 0.75)


@pytest.mark.parametrize("kw", [dict(set_time_s=-1.0), dict(set_time_s=4000.0), dict(viscosity_mpa_s=0.0),
                                dict(surface_tension_mn_m=500.0), dict(h0_percentile=101.0), dict(h0_um=0.0),
                                dict(halo_lengths=2.0), dict(window_cells=10), dict(set_time_s=float("nan"))])
def test_level_options_refuse_bad_values(kw):
    with pytest.raises(ConfigError):
        LevelOptions(**kw)


def test_head_fields_and_preset(head):
    dev = load_device("omnidot760")
    assert dev.head.set_time_s == 1.0  # the preset levels by default
    assert head.set_time_s == 1.0 and head.viscosity_mpa_s == 10.0 and head.surface_tension_mn_m == 30.0
    assert {"viscosity_mpa_s", "surface_tension_mn_m", "set_time_s"} <= set(dev.nominal)
    base = head.model_dump()
    for k, v in (("viscosity_mpa_s", 0.0), ("surface_tension_mn_m", 0.5), ("set_time_s", -0.1), ("set_time_s", 1e5)):
        with pytest.raises(ValidationError):
            InkjetHead(**{**base, k: v})
    lo = LevelOptions.from_head(head, set_time_s=None, viscosity_mpa_s=20.0)
    assert lo.set_time_s == 1.0 and lo.viscosity_mpa_s == 20.0


def test_simulate_reports_both_films(run_cli, tmp_path):
    from rotoprint.io.images import write_png
    from rotoprint.rotary.testimage import test_design as make_design

    design_png = tmp_path / "d.png"
    write_png(design_png, make_design(150))
    out = tmp_path / "p.png"
    code, _, err = run_cli("transform", design_png, "--device", "omnidot760", "--tilt", "0", "--radius", "60",
                           "--out", out)
    assert code == 0, err
    code, o1, err = run_cli("simulate", out, "--out", tmp_path / "ov.png", "--json")  # the preset: 1 s
    assert code == 0, err
    dep = json.loads(o1)["deposit"]
    assert dep["levelled"]["set_time_s"] == 1.0 and abs(dep["levelled"]["volume_error_fraction"]) < 1e-9
    code, o0, err = run_cli("simulate", out, "--out", tmp_path / "ov.png", "--json", "--set-time", "0", "--force")
    assert code == 0, err
    dep0 = json.loads(o0)["deposit"]
    assert "levelled" not in dep0
    dep.pop("levelled")
    assert dep == dep0
    code, text, err = run_cli("simulate", out, "--out", tmp_path / "ov.png", "--force", "--viscosity", "20")
    assert code == 0, err
    assert "levelled film (headline; set time 1 s, viscosity 20 mPa s" in text
    code, _, err = run_cli("simulate", out, "--out", tmp_path / "ov.png", "--force", "--set-time", "-1")
    assert code == 2 and "--set-time" in err


def test_coats_level_as_one_coat_each(head):
    """A film of c identical coats, each set before the next lands (``coats = c``), levels as
    c times one coat levelled by itself: the same map to rounding, h0 one coat's; with
    ``coats = 1`` the same ink levels farther (h0 c times larger, the length c^(3/4))."""
    n, c = 30, 4
    pl = Placement(n, n, PX, PX, inner_radius_mm=60.0)
    mask = np.ones((n, n), bool)
    mask[10:14, 8:22] = False
    one = lattice(n, n, 0.48)
    many = InkDrops.concat([one] * c)
    lo = LevelOptions(set_time_s=2e-4)
    d1 = deposit_film(mask, pl, head, [one], keep_map=True, options=DepositOptions(level=lo))
    dc = deposit_film(mask, pl, head, [many], keep_map=True,
                      options=DepositOptions(level=LevelOptions(set_time_s=2e-4, coats=c)))
    dw = deposit_film(mask, pl, head, [many], keep_map=True, options=DepositOptions(level=lo))
    f1, fc, fw = d1.films[0].levelled, dc.films[0].levelled, dw.films[0].levelled
    assert fc.h0_um == pytest.approx(f1.h0_um, rel=1e-12) and fw.h0_um == pytest.approx(c * f1.h0_um, rel=1e-12)
    assert fc.h0_rule.endswith(f"/ {c} coats")
    scale = float(d1.levelled_thickness.max())
    assert np.abs(dc.levelled_thickness - c * d1.levelled_thickness).max() < 1e-9 * c * scale
    assert fc.thinnest_to_mean == pytest.approx(f1.thinnest_to_mean, rel=1e-9)
    assert fw.levelling_length_um == pytest.approx(fc.levelling_length_um * c ** 0.75, rel=1e-9)
    assert np.abs(dw.levelled_thickness - dc.levelled_thickness).max() > 0.01 * c * scale  # not the same film
    with pytest.raises(ConfigError, match="coats must be a number in 1..1e6"):
        LevelOptions(coats=0.5)


def test_film_stats_kernel_matches_numpy():
    """film_stats_jit (the levelled figures, strip by strip) against numpy on the same cells: the
    sums, the thinnest, the count below half the mean, the 1 mm bins as Placement.to_platform
    puts the cells; any split into strips gives the same."""
    from rotoprint.rotary import _levelling_kernels as LK

    rng = np.random.default_rng(2)
    rows, cols, nx, ny, ox, oy = 90, 70, 3, 2, 5, 4
    pl = Placement(21, 41, 0.4, 0.3, inner_radius_mm=12.0, angle_deg=17.0)
    lv = rng.uniform(0.0, 9.0, (rows, cols))
    inter = rng.random((rows, cols)) < 0.6
    bits = np.packbits(inter, axis=1)
    a = math.radians(pl.angle_deg)
    geo = np.array([ox, oy, nx, ny, pl.inner_radius_mm, pl.pitch_x_mm, pl.pitch_y_mm, pl.height_px, math.cos(a), math.sin(a)])
    nb = int(pl.radial_range_mm()[1]) + 2
    ii, jj = np.nonzero(inter)
    x, y = pl.to_platform((jj + 0.5 - ox) / nx, (ii + 0.5 - oy) / ny)
    b = np.floor(np.hypot(x, y)).astype(np.int64)
    t = lv[ii, jj]
    for splits in ([0, rows], [0, 1, 37, 38, rows]):
        acc = np.array([0.0, 0.0, 0.0, 0.0, math.inf, 0.0, 0.0])
        bs, bn = np.zeros(nb), np.zeros(nb, np.int64)
        for r0, r1 in zip(splits[:-1], splits[1:]):
            LK.film_stats_jit(lv[r0:r1], bits[r0:r1], r0, geo, 2.5, acc, bs, bn)
        assert acc[0] + acc[1] == pytest.approx(lv.sum(), rel=1e-14)
        assert acc[2] + acc[3] == pytest.approx(t.sum(), rel=1e-14)
        assert acc[4] == t.min() and acc[5] == t.size and acc[6] == (t < 2.5).sum()
        assert np.array_equal(bn, np.bincount(b, minlength=nb))
        assert np.allclose(bs, np.bincount(b, weights=t, minlength=nb), rtol=1e-13, atol=0)
