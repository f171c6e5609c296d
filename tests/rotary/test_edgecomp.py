"""Design-aware edge compensation of equalised prints (rotary/edgecomp.py)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import ConfigError
from rotoprint.rotary import Placement, transform_exact
from rotoprint.rotary.deposit import DepositOptions, LevelOptions, deposit_print
from rotoprint.rotary.edgecomp import EdgeRestore, edge_distance_um, radial_edge_near, restore_near_edges
from rotoprint.rotary.equalise import thin_print
from rotoprint.rotary.interlace import PassOptions, pass_prints
from rotoprint.rotary.options import RotarySetup
from rotoprint.rotary.simulate import place_drops

PX = 25.4 / 360


@pytest.fixture(scope="module")
def head():
    return load_device("omnidot760").head


def _sliver_band(rows: int = 40, cols: int = 500, sliver_mm: float = 0.25):
    """A band at tilt 0 from 60 mm with a gap every 5 mm from ``b + sliver`` to ``b + 1`` mm of
    radius: bins 64, 69, ... hold only a sliver of interior beside a radial edge."""
    d = np.full((rows, cols), 255, np.uint8)
    r = 60.0 + (np.arange(cols) + 0.5) * PX
    slivers = list(range(64, int(r[-1]) - 2, 5))
    for b in slivers:
        d[:, (r > b + sliver_mm) & (r < b + 1.0)] = 0
    return d, Placement(cols, rows, PX, PX, inner_radius_mm=60.0), slivers


def test_edge_distance_matches_brute_force():
    rng = np.random.default_rng(3)
    mask = rng.random((9, 11)) > 0.3
    col, row = rng.uniform(-0.5, 11.5, 400), rng.uniform(-0.5, 9.5, 400)
    px, py, reach = 0.07, 0.05, 160.0
    got = edge_distance_um(mask, col, row, px, py, reach)
    pad = np.zeros((9 + 20, 11 + 20), bool)
    pad[10:19, 10:21] = mask
    ii, jj = np.nonzero(~pad)
    ii, jj = ii - 10, jj - 10  # empty pixels (design coordinates), the image's surround included
    for c, r, g in zip(col, row, got):
        i, j = int(np.floor(r)), int(np.floor(c))
        if not (0 <= i < 9 and 0 <= j < 11 and mask[i, j]):
            assert g == 0.0
            continue
        dx = np.maximum(0.0, np.maximum(jj - c, c - (jj + 1))) * px
        dy = np.maximum(0.0, np.maximum(ii - r, r - (ii + 1))) * py
        want = 1e3 * float(np.hypot(dx, dy).min())
        assert (g == pytest.approx(want, abs=1e-9)) if want <= reach else g == np.inf


def test_radial_edge_near_sees_edges_along_the_radius_only():
    d, pl, _ = _sliver_band(rows=20, cols=200)
    mask = d > 0
    # the first gap's columns 60..70 (centres 64.27-64.97 mm); its edges at 64.233 and 65.009 mm
    c = np.array([59.8, 59.2, 100.0, 100.0, 100.0, 60.5, 71.3])
    r = np.array([10.0, 10.0, 0.2, 10.0, 19.8, 10.0, 10.0])
    near = radial_edge_near(mask, pl, c, r, 50.0)
    # 14 um and 56 um from the gap; mid-band at a long edge (along the track), mid-band, in the gap, 31 um past it
    assert near.tolist() == [True, False, False, False, False, False, True]
    with pytest.raises(ConfigError, match="at most a pixel"):
        radial_edge_near(mask, pl, c, r, 100.0)


def test_restore_near_edges_gives_thinned_tracks_the_gain_in_the_zone_only(head):
    """One pass of the sliver band thinned to share 1/2 on every track, then restored with gain
    0.4: every drop of the thinned print is kept, every restored one is a drop of the full print
    inside the zone, in the zone the print keeps about 0.7 of the full print's drops (1/2 x 1.4),
    elsewhere exactly the thinned one; a track left out (share 0) and one at share 1 get none."""
    d, pl, _ = _sliver_band()
    pr = transform_exact(d, head, pl, tilt_deg=0.0)
    shares = [np.full(head.nozzles, 0.5) for _ in pr.swathes]
    for f in shares:
        f[:40] = 0.0
        f[40:80] = 1.0
    thinned = thin_print(pr, shares)
    out = restore_near_edges(pr, thinned, d, shares, options=EdgeRestore(50.0, 0.4))
    mask = d > 0
    full_dr = place_drops(pr)
    key = lambda dr: dr.swathe.astype(np.int64) * 10**12 + dr.firing * 10**4 + dr.nozzle  # noqa: E731
    k_full, k_thin, k_out = key(full_dr), key(place_drops(thinned)), key(place_drops(out))
    assert np.isin(k_thin, k_out).all() and np.isin(k_out, k_full).all()
    zone = radial_edge_near(mask, pl, full_dr.col, full_dr.row, 50.0)
    added = np.isin(k_full, k_out) & ~np.isin(k_full, k_thin)
    assert added.any() and (zone[added]).all()
    mid = (full_dr.nozzle >= 80)
    kept_zone = np.isin(k_full[zone & mid], k_out).mean()
    assert kept_zone == pytest.approx(0.7, abs=0.03), kept_zone
    assert not added[full_dr.nozzle < 80].any()
    with pytest.raises(ConfigError, match="one share per nozzle"):
        restore_near_edges(pr, thinned, d, shares[:1] * (len(shares) + 1))
    sw0 = thinned.swathes[0]
    bad = dataclasses.replace(thinned, swathes=(dataclasses.replace(sw0, first_firing=sw0.first_firing + 1),) + thinned.swathes[1:])
    with pytest.raises(ConfigError, match="before and after thinning"):
        restore_near_edges(pr, bad, d, shares)
    for z, c in ((0.0, 0.4), (50.0, 0.0), (50.0, 1.5)):
        with pytest.raises(ConfigError, match="edge"):
            EdgeRestore(z, c)


def test_edge_restore_flattens_the_levelled_sliver_bins_of_a_band(head):
    """The sliver band at tilt 0, equalised passes, levelled at 1 s: levelling pinned at the wet
    edge takes ink from the sliver bins (measured -1.4 to -1.8 % of the bins' mean); with the
    edge restore (PassOptions(edge_restore=EdgeRestore(50, 0.2))) those up to 84 mm come within
    1 % (measured +0.5 to +0.7 %; at 89 mm the tracks keep 0.93 of their drops, room for a 7 %
    gain only: -1.2 %), every whole bin stays within 1 %, under 1 % more drops, no hole opens,
    and the deposited volume is the planned one."""
    d, pl, slivers = _sliver_band()
    got = {}
    for er in (None, EdgeRestore(50.0, 0.2)):
        _, prs, _ = pass_prints(d, head, pl, PassOptions(RotarySetup(tilt_deg=0.0), edge_restore=er))
        f = deposit_print(prs, d, options=DepositOptions(level=LevelOptions.from_head(head, set_time_s=1.0, coats=len(prs)))).films[0]
        assert f.uncovered_fraction == 0.0
        assert abs(f.volume_error_fraction) <= 0.005 and abs(f.levelled.volume_error_fraction) <= 0.005
        bins = {round(b[0]): b for b in f.levelled.radial_bins}
        area = np.median([b[2] for b in bins.values()])
        whole = [b for b in bins if bins[b][2] >= 0.9 * area and b < slivers[-1]]
        m = np.mean([bins[b][1] for b in bins if bins[b][2] >= 0.1 * area])
        dev = {b: bins[b][1] / m - 1 for b in bins}
        got[er is None] = ([dev[b] for b in slivers], max(abs(dev[b]) for b in whole), f.drops)
    (s0, w0, n0), (s1, w1, n1) = got[True], got[False]
    assert max(s0) < -0.012 and all(abs(x) < 0.01 for x, b in zip(s1, slivers) if b < 85), (s0, s1)
    assert max(map(abs, s1)) < 0.7 * max(map(abs, s0)), (s0, s1)
    assert w1 <= 0.01 and w0 <= 0.01, (w0, w1)
    assert n0 < n1 < 1.01 * n0


@pytest.mark.parametrize("tilt, dead, q", [(0.0, (), 0), (20.0, (3, 100, 401), 2), (45.0, (), 1), (70.0, (7, 300), 3)])
def test_transform_restored_is_the_restore_of_the_unthinned_print(head, tilt, dead, q):
    """transform_restored (fused thinning + a transform of the edge zone only) makes the very print
    restore_near_edges(full, thin_print(full)) makes: several tilts, dead nozzles, passes, the
    radial zone and the all-edges one; shares with tracks left out and kept whole."""
    from rotoprint.rotary.edgecomp import transform_restored
    from rotoprint.rotary.testimage import test_design

    d = test_design(300)
    pl = Placement(300, 300, PX, PX, inner_radius_mm=60.0)
    hd = head.model_copy(update={"dead_nozzles": dead})
    st = RotarySetup(tilt_deg=tilt, dpi_y=1440.0, pivot_offset_mm=0.01 * q)
    full = transform_exact(d, hd, pl, st)
    rng = np.random.default_rng(q)
    shares = [np.clip(rng.uniform(0.2, 1.3, hd.nozzles), 0.0, 1.0) for _ in full.swathes]
    for f in shares:
        f[rng.integers(0, hd.nozzles, 30)] = 0.0
    for er in (EdgeRestore(), EdgeRestore(zone_um=120.0, radial_only=False)):
        want = restore_near_edges(full, thin_print(full, shares, pass_index=q), d, shares, options=er, pass_index=q)
        got = transform_restored(d, hd, pl, st, shares, options=er, pass_index=q)
        assert all(np.array_equal(a.levels, b.levels) for a, b in zip(want.swathes, got.swathes))
        assert sum(int(np.count_nonzero(a.levels)) for a in want.swathes) > \
            sum(int(np.count_nonzero(a.levels)) for a in thin_print(full, shares, pass_index=q).swathes)


@pytest.mark.parametrize("tilt, angle", [(0.0, 0.0), (20.0, 15.0), (70.0, -30.0)])
def test_restore_candidates_kernel_matches_its_numpy_reference(head, tilt, angle):
    """The jit sweep of the track windows finds the numpy reference's candidates, in the same
    order: shares 0, 1 and between, dead nozzles (rate 0), a rotated placement, several swathes."""
    from rotoprint.rotary import _edgecomp_kernels as ek
    from rotoprint.rotary._exact_kernels import claim_rows
    from rotoprint.rotary._thin_kernels import thin_phases
    from rotoprint.rotary.edgecomp import edge_zone, restore_pattern
    from rotoprint.rotary.exact import exact_maps
    from rotoprint.rotary.testimage import test_design

    d = test_design(240)
    pl = Placement(240, 240, PX, PX, inner_radius_mm=60.0, angle_deg=angle)
    z = edge_zone(d, head, pl, EdgeRestore())
    maps = exact_maps(head, pl, RotarySetup(tilt_deg=tilt, dpi_y=1440.0, pivot_offset_mm=0.013))
    rng = np.random.default_rng(int(tilt))
    found = 0
    for q, sm in enumerate(maps.swathes):
        f = np.clip(rng.uniform(-0.2, 1.2, head.nozzles), 0.0, 1.0)
        gain, o = restore_pattern(np.arange(head.nozzles), f, 0.5, q)
        gain[rng.integers(0, head.nozzles, 20)] = 0.0
        w = sm.windows
        args = (*w.coefficients, w.nozzle, w.row, w.count, w.cos_row, w.sin_row, w.width, w.height, z.zone_flat, z.zone_blocks,
                f, thin_phases(head.nozzles, q), gain, o, int(sm.first_firing), claim_rows(w.cos_row, w.sin_row))
        cap = int(w.count.sum())
        got = [np.empty(cap, np.int32), np.empty(cap, np.int32)]
        want = [np.empty(cap, np.int32), np.empty(cap, np.int32)]
        m = ek.restore_candidates_jit(*args, *got)
        assert m == ek.restore_candidates_numpy(*args, *want)
        assert np.array_equal(got[0][:m], want[0][:m]) and np.array_equal(got[1][:m], want[1][:m])
        found += m
    assert found > 100


def test_transform_restored_takes_the_layers_edge_zone(head):
    """One edge zone serves every pass of a layer (the same print as without it); a zone made for
    another design size or other options is refused; a grey design has none."""
    from rotoprint.rotary.edgecomp import edge_zone, transform_restored
    from rotoprint.rotary.testimage import test_design

    d = test_design(200)
    pl = Placement(200, 200, PX, PX, inner_radius_mm=60.0)
    st = RotarySetup(tilt_deg=20.0, dpi_y=1440.0)
    shares = [np.full(head.nozzles, 0.45) for _ in transform_exact(d, head, pl, st).swathes]
    z = edge_zone(d, head, pl, EdgeRestore())
    a = transform_restored(d, head, pl, st, shares, pass_index=1)
    b = transform_restored(d, head, pl, st, shares, pass_index=1, zone=z)
    assert all(np.array_equal(x.levels, y.levels) for x, y in zip(a.swathes, b.swathes))
    c = transform_restored(d, head, pl, dataclasses.replace(st, backend="numpy"), shares, pass_index=1, zone=z)  # the reference kernels
    assert all(np.array_equal(x.levels, y.levels) for x, y in zip(a.swathes, c.swathes))
    with pytest.raises(ConfigError, match="other options"):
        transform_restored(d, head, pl, st, shares, options=EdgeRestore(zone_um=30.0), zone=z)
    small = test_design(100)
    with pytest.raises(ConfigError, match="another design"):
        transform_restored(small, head, Placement(100, 100, PX, PX, inner_radius_mm=60.0), st, shares, zone=z)
    other = d.copy()
    other[50:60, 50:60] = 0  # the same size, another design
    with pytest.raises(ConfigError, match="another design"):
        transform_restored(other, head, pl, st, shares, zone=z)
    grey = np.where(d > 0, np.where(np.arange(200) % 2 == 0, 255, 128), 0).astype(np.uint8)  # two ink values
    assert edge_zone(grey, head, pl) is None


def test_radial_near_kernel_matches_radial_edge_near():
    """The jit loop of the radial edge test gives radial_edge_near's answer site for site: sites
    inside, beside and outside the image, several zones and placement angles."""
    import math

    from rotoprint.rotary import _edgecomp_kernels as ek
    from rotoprint.rotary.edgecomp import design_rim
    from rotoprint.rotary.testimage import test_design

    m = test_design(200) > 0
    rng = np.random.default_rng(3)
    col, row = rng.uniform(-3.0, 203.0, 100_000), rng.uniform(-3.0, 203.0, 100_000)
    for angle, zone in ((0.0, 50.0), (23.0, 20.0), (-61.0, 70.0)):
        pl = Placement(200, 200, PX, PX, inner_radius_mm=60.0, angle_deg=angle)
        want = radial_edge_near(m, pl, col, row, zone)
        got = np.empty(col.size, bool)
        a = math.radians(angle)
        ek.radial_near_jit(m, design_rim(m), col, row, 60.0, PX, PX, 100.0, math.cos(a), math.sin(a), zone, got)
        assert np.array_equal(want, got) and 1000 < int(want.sum()) < 50_000


def test_edge_zone_refuses_a_wider_radial_zone_and_another_head_or_placement(head):
    """The radial zone is at most a pixel on every route (the jit one checks it as radial_edge_near
    does); a zone made for another placement or another head's drop levels is refused."""
    from rotoprint.rotary.edgecomp import edge_zone, transform_restored
    from rotoprint.rotary.testimage import test_design

    d = test_design(120)
    pl = Placement(120, 120, PX, PX, inner_radius_mm=60.0)
    st = RotarySetup(tilt_deg=20.0, dpi_y=1440.0)
    shares = [np.full(head.nozzles, 0.45) for _ in transform_exact(d, head, pl, st).swathes]
    with pytest.raises(ConfigError, match="at most a pixel"):
        edge_zone(d, head, pl, EdgeRestore(zone_um=120.0))
    with pytest.raises(ConfigError, match="at most a pixel"):
        transform_restored(d, head, pl, st, shares, options=EdgeRestore(zone_um=120.0))
    z = edge_zone(d, head, pl, EdgeRestore(zone_um=50.0, radial_only=False))
    fine = Placement(120, 120, 0.02, 0.02, inner_radius_mm=60.0)
    with pytest.raises(ConfigError, match="another design, placement, head"):
        transform_restored(d, head, fine, st, shares, options=EdgeRestore(zone_um=50.0, radial_only=False), zone=z)
    grey = head.model_copy(update={"grey_levels": 3})
    with pytest.raises(ConfigError, match="another design, placement, head"):
        transform_restored(d, grey, pl, st, shares, options=EdgeRestore(zone_um=50.0, radial_only=False), zone=z)
