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
