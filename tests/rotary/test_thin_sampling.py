"""Thinning while sampling (issue 14's cost floor): the exact transform given ``thin=ThinShares``
makes exactly the images ``thin_print`` makes of the unthinned print, for binary and grey
designs, both kernels, with dead nozzles; ``pass_prints`` prints its equalised passes that way."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import ConfigError
from rotoprint.rotary import Placement, plan_swathes, transform_exact
from rotoprint.rotary._thin_kernels import kept_numpy, thin_phases
from rotoprint.rotary.equalise import thin_print
from rotoprint.rotary.exact import ThinShares


def _band(n_rows=40, n_cols=240):
    """A band 17 mm wide radially with holes (design rows that print nothing), 360 dpi."""
    d = np.full((n_rows, n_cols), 255, np.uint8)
    d[10:14, 30:200] = 0
    d[:, 100:104] = 0
    px = 25.4 / 360
    return d, Placement(n_cols, n_rows, px, px, inner_radius_mm=60.0)


def _shapes(n=240):
    """The bundled test design (squares, discs, rings, fine bars and dots on empty ground), 360 dpi."""
    from rotoprint.rotary.testimage import test_design

    px = 25.4 / 360
    return test_design(n), Placement(n, n, px, px, inner_radius_mm=60.0)


@pytest.mark.parametrize("tilt", [0.0, 20.0, 45.0, 70.0])
@pytest.mark.parametrize("backend", ["jit", "numpy"])
@pytest.mark.parametrize("design", [_band, _shapes])
def test_thinning_while_sampling_is_thin_print_of_the_pointwise_print(tilt, backend, design):
    """Also where pieces of track are skipped because they can land on no ink (the shapes' empty ground)."""
    head = load_device("omnidot760").head.model_copy(update={"dead_nozzles": (3, 200, 411)})
    d, pl = design()
    sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=pl.radial_range_mm()[0], outer_radius_mm=pl.radial_range_mm()[1])
    rng = np.random.default_rng(int(tilt))
    fr = [np.where(rng.random(head.nozzles) < 0.1, 0.0, rng.uniform(0.25, 1.0, head.nozzles)) for _ in sp.swathes]
    fr[0][:50] = 1.0
    kw = dict(tilt_deg=tilt, dpi_y=1440.0, pivot_offset_mm=0.0123, backend=backend)
    for pass_index in (0, 3):
        plain = transform_exact(d, head, pl, **kw)
        want = thin_print(plain, fr, pass_index=pass_index)
        got = transform_exact(d, head, pl, **kw, thin=ThinShares(fr, pass_index))
        assert len(got.swathes) == len(want.swathes) == len(sp.swathes)
        for a, b, p in zip(got.swathes, want.swathes, plain.swathes):
            assert a.first_firing == b.first_firing and np.array_equal(a.levels, b.levels)
            assert 0 < np.count_nonzero(a.levels) < np.count_nonzero(p.levels)  # it thinned, and kept drops
            assert not a.levels[:, list(head.dead_nozzles)].any()
    # grey design: sampled bilinear, then thinned by the same rule
    grey = (np.linspace(1, 255, d.size).reshape(d.shape) * (d > 0)).astype(np.uint8)
    want = thin_print(transform_exact(grey, head, pl, **kw), fr, pass_index=1)
    got = transform_exact(grey, head, pl, **kw, thin=ThinShares(fr, 1))
    assert got.design_kind == "grey" and all(np.array_equal(a.levels, b.levels) for a, b in zip(got.swathes, want.swathes))


def test_the_rule_keeps_exactly_the_share_over_any_run():
    i = np.arange(-500, 1500, dtype=np.float64)
    for f in (0.25, 0.5, 0.61, 1.0):
        k = kept_numpy(i, f, thin_phases(np.array([7]), 2)[0])
        for lo in (0, 333, 1200):
            assert abs(int(k[lo:lo + 400].sum()) - 400 * f) <= 1
    assert not kept_numpy(i, 0.0, 0.3).any()


@pytest.mark.parametrize("dpi", [4.0, 40.0, 2880.0])
def test_coarse_and_fine_clocks_thin_the_same(dpi):
    """Coarse clocks (at 4 dpi the platform turns ~0.13 rad a row) and a design near the axis (its
    arcs turn 2.3 rad): the end points' box still bounds every drop (or the piece makes no claim)."""
    from rotoprint.rotary.testimage import test_design

    head = load_device("omnidot760").head
    px = 25.4 / 72  # 42 mm at 4 mm from the axis: the design spans 2.8 rad of every track
    d, pl = test_design(120), Placement(120, 120, px, px, inner_radius_mm=4.0)
    fr = [np.full(head.nozzles, 0.7)] * 4
    kw = dict(tilt_deg=20.0, dpi_y=dpi)
    want = thin_print(transform_exact(d, head, pl, **kw), fr, pass_index=2)
    got = transform_exact(d, head, pl, **kw, thin=ThinShares(fr[:len(want.swathes)], 2))
    assert all(np.array_equal(a.levels, b.levels) for a, b in zip(got.swathes, want.swathes))
    assert sum(int(np.count_nonzero(a.levels)) for a in got.swathes) > 0


def test_shares_of_the_wrong_shape_are_one_line_errors():
    head = load_device("omnidot760").head
    d, pl = _band()
    with pytest.raises(ConfigError, match=r"one \(764,\) array per swathe"):
        transform_exact(d, head, pl, tilt_deg=20.0, thin=ThinShares([np.ones(5)]))
    with pytest.raises(ConfigError, match="finite"):
        ThinShares([np.full(764, np.nan)])


def test_pass_prints_thins_while_sampling(monkeypatch):
    """The equalised passes (with dead nozzles and their cover) are what sampling unthinned, then
    thin_print, made before: the same images, and every pass was thinned while sampled, in one
    transform (the edge restore, the default, makes no second one)."""
    import rotoprint.rotary.exact as ex
    from rotoprint.rotary.interlace import PassOptions, pass_prints
    from rotoprint.rotary.options import RotarySetup

    head = load_device("omnidot760").head.model_copy(update={"dead_nozzles": (5, 300)})
    d, pl = _band()
    opts = PassOptions(RotarySetup(tilt_deg=20.0), passes="auto")
    orig, thinned = ex.transform_exact, []

    def sample_then_thin(design, head_, placement, setup=None, *, thin=None, **kw):
        thinned.append(thin is not None)
        pr = orig(design, head_, placement, setup, **kw)
        return pr if thin is None else thin_print(pr, thin.fractions, pass_index=thin.pass_index)

    monkeypatch.setattr(ex, "transform_exact", sample_then_thin)
    _, want, _ = pass_prints(d, head, pl, opts)
    monkeypatch.setattr(ex, "transform_exact", orig)
    _, got, man = pass_prints(d, head, pl, opts)
    # one thinned transform a pass: the edge restore (the default) sweeps that pass's windows for its drops
    assert man["equalise"] == "thinning" and "dead_cover" in man and "edge_restore" in man and len(got) > 1
    assert thinned == [True] * len(got)
    assert all(np.array_equal(a.levels, b.levels) for p, q in zip(got, want) for a, b in zip(p.swathes, q.swathes))


def test_the_ink_blocks_count_the_blocks_with_ink_and_all_ink():
    from rotoprint.rotary import _exact_kernels as _k

    d = np.zeros((20, 30), np.uint8)
    d[3, 5] = d[19, 29] = d[9, 8] = 255
    d[16:20, 8:16] = 255  # the bottom row of blocks is 4 px high: this one is all ink
    d[0:8, 16:24] = 255  # a whole block
    flat, _ = _k.binary_levels_numba(d, 1)
    sat = _k.ink_blocks(flat, 30, 20)
    some, full = np.zeros((3, 4), np.int32), np.zeros((3, 4), np.int32)
    for y, x in ((3, 5), (19, 29), (9, 8), (16, 8), (0, 16)):
        some[y // 8, x // 8] = 1
    full[2, 1] = full[0, 2] = 1
    assert sat.shape == (2, 4, 5) and not sat[:, 0].any() and not sat[:, :, 0].any()
    assert np.array_equal(sat[0, 1:, 1:], some.cumsum(0).cumsum(1)) and np.array_equal(sat[1, 1:, 1:], full.cumsum(0).cumsum(1))
