"""Dead-nozzle cover within one pass (rotary/deadcover.py)."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import ConfigError
from rotoprint.rotary import Placement, plan_swathes, transform_exact
from rotoprint.rotary.deadcover import cover_dead_nozzles
from rotoprint.rotary.deposit import deposit_print
from rotoprint.rotary.interlace import thin_print
from rotoprint.rotary.options import RotarySetup

PX = 25.4 / 360


@pytest.fixture(scope="module")
def setting():
    head = load_device("omnidot760").head
    d = np.full((50, 50), 255, np.uint8)
    pl = Placement(50, 50, PX, PX, inner_radius_mm=60.0)
    return head, d, pl


def volume(pr):
    return sum(int(s.levels.astype(np.int64).sum()) for s in pr.swathes)


def test_cover_conserves_volume_where_there_is_room(setting):
    head, d, pl = setting
    r0, r1 = pl.radial_range_mm()
    sp = plan_swathes(head, tilt_deg=0.0, inner_radius_mm=r0, outer_radius_mm=r1)
    # every track keeps half its firings at twice the clock: room on the neighbours
    pr = thin_print(transform_exact(d, head, pl, tilt_deg=0.0, dpi_y=2 * 360.0), [np.full(head.nozzles, 0.5)] * len(sp.swathes))
    en = np.flatnonzero(pr.swathes[0].levels.any(axis=0))
    dead = [int(en[len(en) // 3]), int(en[len(en) // 2])]
    before = volume(pr)
    cov, rep = cover_dead_nozzles(pr, dead)
    assert all(int(s.levels[:, dead].sum()) == 0 for s in cov.swathes)
    assert rep["levels_to_move"] == sum(int(pr.swathes[0].levels[:, k].sum()) for k in dead) > 0
    assert rep["levels_moved"] + rep["levels_lost"] == rep["levels_to_move"]
    assert volume(cov) == before - rep["levels_lost"]
    assert rep["volume_lost_fraction"] < 0.005
    assert 0 < rep["mean_shift_um"] < 100


def test_cover_closes_the_ring_in_the_film(setting):
    head, d, pl = setting
    pr = thin_print(transform_exact(d, head, pl, tilt_deg=0.0, dpi_y=4 * 360.0), [np.full(head.nozzles, 0.5)])
    en = np.flatnonzero(pr.swathes[0].levels.any(axis=0))
    dead = (int(en[len(en) // 2]),)
    from rotoprint.rotary.deposit import DepositOptions

    opts = DepositOptions(footprint_um=160.0)
    off = deposit_print(pr, d, dead_nozzles=dead, options=opts).films[0]
    cov, rep = cover_dead_nozzles(pr, dead)
    on = deposit_print(cov, d, options=opts).films[0]
    full = deposit_print(pr, d, options=opts).films[0]
    assert on.deposited_volume_pl == pytest.approx(full.deposited_volume_pl * (1 - rep["volume_lost_fraction"]))
    # 160 um footprints span the 141 um between the dead track's neighbours, thinly; the moved
    # drops double the neighbours' ink there (moving drops along tracks cannot bridge a gap
    # wider than the footprint: that needs another pass)
    assert full.uncovered_fraction == off.uncovered_fraction == on.uncovered_fraction == 0.0
    assert off.thinnest_um < 0.6 * full.thinnest_um
    assert on.thinnest_um > 1.3 * off.thinnest_um


def test_binary_head_without_room_reports_the_loss(setting):
    head, d, pl = setting
    pr = transform_exact(d, head, pl, tilt_deg=0.0)
    k = int(np.flatnonzero(pr.swathes[0].levels.any(axis=0))[10])
    cov, rep = cover_dead_nozzles(pr, [k], search=0)
    assert rep["levels_lost"] == rep["levels_to_move"] > 0 and rep["levels_moved"] == 0
    with pytest.raises(ConfigError, match="dead nozzle"):
        cover_dead_nozzles(pr, [10_000])


def _dead_setting(head, tilt=0.0):
    from rotoprint.rotary.interlace import pass_overlap_mm, plan_passes

    sp0 = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=60.0, outer_radius_mm=70.0)
    en = np.flatnonzero(sp0.swathes[0].enabled)
    dh = head.model_copy(update={"dead_nozzles": (int(en[30]), int(en[70]), int(en[110]))})
    sp = plan_swathes(dh, tilt_deg=tilt, inner_radius_mm=60.0, outer_radius_mm=70.0, overlap_mm=pass_overlap_mm(dh, dead_spread=True))
    pp = plan_passes(dh, sp, footprint_um=49.6, passes=4)
    return dh, sp, pp


def test_dead_tracks_drops_go_to_live_tracks_of_other_passes(setting):
    """Without shares every live track with room keeps one share s < 1 and the dead tracks'
    drops per mm fill the room nearest them: the volume per mm of the print is that of the
    share-s print with every nozzle live (nothing lost), each dead track's within the window."""
    from rotoprint.rotary.deadcover import cover_dead_tracks
    from rotoprint.rotary.exact import swathe_clock
    from rotoprint.rotary.head import nozzle_layout
    from rotoprint.rotary.swathes import pass_enabled

    head = setting[0]
    dh, sp, pp = _dead_setting(head)
    st = RotarySetup(tilt_deg=0.0, dpi_y=pp.dpi_y)
    # at the head's native clock (70 um along the track) a missed drop opens a hole: no room
    assert cover_dead_tracks(dh, sp, pp.offsets_mm, footprint_um=49.6)[1]["tracks_with_room"] == 0
    from rotoprint.rotary.deadcover import DeadCoverOptions

    wide = DeadCoverOptions(min_scale=0.75)
    f, rep = cover_dead_tracks(dh, sp, pp.offsets_mm, st, footprint_um=49.6, options=wide)
    assert rep["dead_tracks"] > 0 and rep["lost"] == 0 and rep["demand"] > 0 and rep["moved"] == pytest.approx(rep["demand"])
    s = rep["scale"]
    assert 0.75 <= s < 1 and 0 < rep["tracks_with_room"] <= rep["tracks"]
    raised = 0
    for per in f:
        for fj in per:
            on = fj > 0
            assert np.all(fj <= 1) and np.all(fj[list(dh.dead_nozzles)] == 0)
            # every live track keeps s, or every drop (no room beside a wide gap, or filled)
            # or, one per dead track at most, a share between
            mid = on & (fj > s + 1e-12) & (fj < 1 - 1e-12)
            raised += int(mid.sum())
            assert np.all((np.abs(fj[on] - s) < 1e-12) | (fj[on] > s))
    assert raised <= rep["dead_tracks"]
    # with shares (an equalised print, the dead nozzles live in it) there is room and no
    # scale: the live tracks' drops per mm grow by exactly the dead tracks'
    def tracks(shares):
        live = dead = 0.0
        for q, o in enumerate(pp.offsets_mm):
            for j in range(len(sp.swathes)):
                dphi, _ = swathe_clock(sp, j, dpi_y=pp.dpi_y, ref_radius_mm=None)
                r = np.hypot(*(nozzle_layout(dh, sp.mount(j)).xy_mm + o * np.array([1.0, 0.0])).T)
                en = pass_enabled(sp, j, r)
                w = np.where(en, shares[q][j], 0.0) / (r * dphi)
                isd = np.isin(np.arange(dh.nozzles), dh.dead_nozzles)
                live += float(w[~isd].sum())
                dead += float(w[isd].sum())
        return live, dead

    half = [[np.where(pass_enabled(sp, j, np.hypot(*(nozzle_layout(dh, sp.mount(j)).xy_mm + o * np.array([1.0, 0.0])).T)), 0.5, 0.0)
             for j in range(len(sp.swathes))] for o in pp.offsets_mm]
    f2, rep2 = cover_dead_tracks(dh, sp, pp.offsets_mm, st, shares=half)
    assert rep2["scale"] == 1.0 and rep2["lost"] == 0 and rep2["demand"] > 0
    live0, dead0 = tracks(half)
    live1, dead1 = tracks(f2)
    assert dead0 > 0 and dead1 == 0 and live1 == pytest.approx(live0 + dead0, rel=1e-12)
    up = sum(int(np.sum(fj > 0.5 + 1e-12)) for per in f2 for fj in per)
    assert 0 < up < 12 * rep2["dead_tracks"]
    # shares near 1 (the sparse end of an equalised swathe): no room for every dead drop at the
    # shares given; with scale_shares (the default) one common scale s < 1 makes room, every live
    # track keeps s of its share or more, and the drops per mm are s times the shares' (volume kept)
    full = [[0.95 * (fj > 0) for fj in per] for per in half]
    kept, rep_k = cover_dead_tracks(dh, sp, pp.offsets_mm, st, shares=full, options=DeadCoverOptions(scale_shares=False))
    assert rep_k["scale"] == 1.0 and rep_k["lost"] > 0
    f3, rep3 = cover_dead_tracks(dh, sp, pp.offsets_mm, st, shares=full)
    s3 = rep3["scale"]
    assert DeadCoverOptions().scale_shares and DeadCoverOptions().min_scale <= s3 < 1.0 and rep3["lost"] <= 1e-9 * rep3["demand"]
    live0, dead0 = tracks(full)
    live3, dead3 = tracks(f3)
    assert dead3 == 0 and live3 == pytest.approx(s3 * (live0 + dead0), rel=1e-9)
    assert all(np.all(fj[fj > 0] >= 0.95 * s3 - 1e-12) and np.all(fj <= 1) for per in f3 for fj in per)
    with pytest.raises(ConfigError, match="window"):
        DeadCoverOptions(window_mm=0.0)
    with pytest.raises(ConfigError, match="scale"):
        DeadCoverOptions(min_scale=0.2)
    # a narrow window: less room near the dead tracks (their two neighbours beside the gap
    # have none), so a smaller common share and drops lost even at the smallest
    narrow = cover_dead_tracks(dh, sp, pp.offsets_mm, st, footprint_um=49.6, options=DeadCoverOptions(window_mm=0.05, min_scale=0.5))[1]
    assert narrow["scale"] < s and narrow["lost"] > 0
    with pytest.raises(ConfigError, match="footprint"):
        cover_dead_tracks(dh, sp, pp.offsets_mm)
    with pytest.raises(ConfigError, match="one array per pass"):
        cover_dead_tracks(dh, sp, pp.offsets_mm, shares=half[:2])


def test_thin_by_landing_keeps_the_share_and_staggers_neighbours(setting):
    """Every track keeps its share of firings over the run (to one firing), and no two radially
    neighbouring tracks miss drops within one firing of each other along the track (the
    head's two rows fire half a step apart at tilt 0: measured, a pattern on the firing index
    alone left pinholes)."""
    from rotoprint.rotary.deadcover import thin_by_landing
    from rotoprint.rotary.head import Mount, nozzle_layout

    head, d, pl = setting
    r0, r1 = pl.radial_range_mm()
    offs = (0.0, 0.0176, 0.0352, 0.0528)
    prs = [transform_exact(d, head, pl, tilt_deg=0.0, dpi_y=720.0, pivot_offset_mm=o) for o in offs]
    f = 0.85
    sh = [[np.full(head.nozzles, f) for _ in p.swathes] for p in prs]
    out = thin_by_landing(prs, sh)
    miss = []  # (radius, landing angle in firings) of every missed drop of swathe 0
    for p, t in zip(prs, out):
        a, b = p.swathes[0].levels, t.swathes[0].levels
        assert np.all(b <= a)
        fired = a.astype(bool).sum(axis=0)
        kept = b.astype(bool).sum(axis=0)
        on = fired > 20
        assert np.all(np.abs(kept[on] - f * fired[on]) <= 2.0)
        sw = p.swathes[0]
        lay = nozzle_layout(p.head, Mount(sw.pivot_radius_mm, tilt_deg=0.0, mount_angle_deg=p.mount_angle_deg, direction=p.direction))
        i, k = np.nonzero(a.astype(bool) & ~b.astype(bool))
        t_land = (i + sw.first_firing) - p.direction * lay.phi_rad[k] / sw.dphi_rad
        miss.append(np.stack([lay.r_mm[k], t_land], axis=1))
    m = np.concatenate(miss)
    m = m[np.argsort(m[:, 0])]
    rr = np.unique(np.round(m[:, 0], 5))
    close = 0
    for r_a, r_b in zip(rr[:-1], rr[1:]):
        ta = m[np.isclose(m[:, 0], r_a, atol=1e-5), 1]
        tb = m[np.isclose(m[:, 0], r_b, atol=1e-5), 1]
        if ta.size and tb.size and r_b - r_a < 0.03:
            close += int((np.abs(ta[:, None] - tb[None, :]) < 1.01).sum())
    assert close == 0


@pytest.mark.parametrize("equalise", [True, False])
def test_pass_prints_cover_the_dead_tracks(setting, equalise):
    """pass_prints with 3 dead nozzles, tilt 0, a band of 12 x 284 px (60-80 mm): with the cover
    (a plain print: with the reserve)
    the film keeps its volume and stays closed, the rings at the dead tracks are shallower (the
    levelled film's thinnest 20 um ring over its mean, away from the band's edges) and the
    equalised 1 mm bins are evener; the manifest reports it."""
    from rotoprint.rotary.deposit import DepositOptions, LevelOptions
    from rotoprint.rotary.interlace import PassOptions, pass_prints

    head = setting[0]
    d = np.full((12, 284), 255, np.uint8)
    pl = Placement(284, 12, PX, PX, inner_radius_mm=60.0)
    r0, r1 = pl.radial_range_mm()
    en = np.flatnonzero(plan_swathes(head, tilt_deg=0.0, inner_radius_mm=r0, outer_radius_mm=r1).swathes[0].enabled)
    dead = (int(en[30]), int(en[110]), int(en[200]))
    dh = head.model_copy(update={"dead_nozzles": dead})
    out = {}
    for cover in (True, False):
        _, prs, man = pass_prints(d, dh, pl, PassOptions(RotarySetup(tilt_deg=0.0), passes=4, equalise=equalise, dead_cover=cover,
                                                           dead_reserve=True))
        lev = LevelOptions.from_head(head, set_time_s=1.0, coats=len(prs))
        dep = deposit_print(prs, d, dead_nozzles=dead, keep_map=True, options=DepositOptions(level=lev))
        f = dep.films[0]
        assert f.uncovered_fraction == 0 and abs(f.volume_error_fraction) < 1e-9
        th = dep.levelled_thickness
        nx, ny = dep.cells_per_pixel
        ox, oy = dep.origin_cells
        c = (np.arange(th.shape[1]) + 0.5 - ox) / nx
        rows = slice(oy + 2 * ny, oy + 10 * ny)
        cols = (c > 2) & (c < 282)
        ring = th[rows][:, cols].mean(axis=0)
        k = max(1, int(round(20 / f.grid_um[0])))
        ring = np.convolve(ring, np.ones(k) / k, mode="valid")
        out[cover] = (float(ring.min() / ring.mean()), f.radial_spread, man.get("dead_cover"))
    rep = out[True][2]
    assert rep and rep["lost_fraction"] < 0.15 and out[False][2] is None
    # equalised: every dead drop finds room, the shares scaled a little where the window had none (measured 0.993)
    assert (rep["lost"] == 0 and 0.95 < rep["scale"] <= 1.0) if equalise else rep["scale"] < 1.0
    assert out[True][0] > out[False][0] + 0.02
    # a plain print without the reserve is as before
    if not equalise:
        _, prs, man = pass_prints(d, dh, pl, PassOptions(RotarySetup(tilt_deg=0.0), passes=4, equalise=False))
        _, prs0, _ = pass_prints(d, dh, pl, PassOptions(RotarySetup(tilt_deg=0.0), passes=4, equalise=False, dead_cover=False))
        assert "dead_cover" not in man
        assert all(np.array_equal(a.levels, b.levels) for p, p0 in zip(prs, prs0) for a, b in zip(p.swathes, p0.swathes))
    if equalise:
        assert out[True][1] < out[False][1]


def test_thin_print_keeps_the_share_of_every_run_and_matches_its_formula(setting):
    """thin_print (its numba kernel) keeps firing i of track k exactly when floor((i + 1) f + o) >
    floor(i f + o): checked against that float64 expression in numpy on a real print with random
    shares, and over every run of firings of a track that prints throughout, the kept count is
    the share times the run within one."""
    from rotoprint.rotary._thin_kernels import GOLDEN as _GOLDEN

    head = setting[0]
    d = np.full((30, 40), 255, np.uint8)
    pl = Placement(40, 30, PX, PX, inner_radius_mm=60.0)
    pr = transform_exact(d, head, pl, tilt_deg=20.0, dpi_y=1440.0)
    rng = np.random.default_rng(3)
    fr = [rng.uniform(0.0, 1.0, head.nozzles) for _ in pr.swathes]
    out = thin_print(pr, fr, pass_index=2)
    for sw, sw2, f in zip(pr.swathes, out.swathes, fr):
        i = (np.arange(sw.levels.shape[0], dtype=np.float64) + sw.first_firing)[:, None]
        o = np.mod((np.arange(head.nozzles) + 7919 * 2) * _GOLDEN, 1.0)[None, :]
        keep = np.floor((i + 1) * f[None, :] + o) > np.floor(i * f[None, :] + o)
        assert np.array_equal(sw2.levels, np.where(keep, sw.levels, 0)) and sw2.levels.dtype == np.uint8
        on = sw.levels > 0
        full = [k for k in np.flatnonzero(on.sum(axis=0) > 40)
                if on[np.flatnonzero(on[:, k])[0]:np.flatnonzero(on[:, k])[-1] + 1, k].all()]  # printing without a break
        assert len(full) > 0
        for k in full[:20]:
            b = np.flatnonzero(on[:, k])
            c = np.concatenate([[0], np.cumsum(sw2.levels[b[0]:b[-1] + 1, k] > 0)])
            for run in (7, 31):
                got = c[run:] - c[:-run]
                assert np.all(np.abs(got - f[k] * run) <= 1.0 + 1e-9)
