"""The pass planner's kernels against their numpy references, bit for bit."""

import numpy as np
import pytest

from rotoprint.rotary import _interlace_kernels as ik


def test_max_gaps_match_numpy_with_nan_and_outside():
    rng = np.random.default_rng(3)
    rows = rng.uniform(59.0, 81.0, (17, 300))
    rows[rng.random(rows.shape) < 0.2] = np.nan
    rest = np.sort(rng.uniform(60.0, 80.0, 500))
    out = np.empty(17)
    ik.max_gaps_jit(rest, rows, 60.0, 80.0, out)
    assert np.array_equal(out, ik.max_gaps_numpy(rest, rows, 60.0, 80.0))
    one = np.full((1, 3), np.nan)
    one[0, 0] = 70.0
    ik.max_gaps_jit(np.zeros(0), one, 60.0, 80.0, out[:1])
    assert out[0] == 0.0  # fewer than two values inside


def test_candidate_gaps_match_radii_then_max_gaps():
    rng = np.random.default_rng(5)
    x, y = rng.uniform(40.0, 70.0, 400), rng.uniform(-20.0, 20.0, 400)
    band_lo = np.where(np.arange(400) < 200, -np.inf, 65.0 - 1e-9)
    band_hi = np.where(np.arange(400) < 200, 66.0, np.inf)
    cand = np.linspace(0.0, 0.14, 64, endpoint=False)
    rest = np.sort(rng.uniform(55.0, 75.0, 300))
    out = np.empty(cand.size)
    ik.candidate_gaps_jit(rest, x, y, band_lo, band_hi, 0.8, 0.6, cand, 55.0, 75.0, out)
    r = np.hypot(x[None, :] + cand[:, None] * 0.8, y[None, :] + cand[:, None] * 0.6)
    r = np.where((r >= band_lo) & (r < band_hi), r, np.nan)
    assert np.array_equal(out, ik.max_gaps_numpy(rest, r, 55.0, 75.0))


def test_kept_candidate_radii_give_the_same_gaps():
    """A kept candidate set (its sorted radii made once, then merged with each fixed set) gives
    candidate_gaps_jit's gaps bit for bit, against several fixed sets; beyond the kept sets' limit
    or without a key the gaps are computed afresh; another set under a kept key is refused."""
    import pytest

    rng = np.random.default_rng(11)
    x, y = rng.uniform(40.0, 70.0, 500), rng.uniform(-20.0, 20.0, 500)
    band_lo = np.where(np.arange(500) < 250, -np.inf, 65.0 - 1e-9)
    band_hi = np.where(np.arange(500) < 250, 66.0, np.inf)
    tracks = (x, y, band_lo, band_hi, 0.8, 0.6)
    cand = np.linspace(0.0, 0.14, 64, endpoint=False)
    kept: dict = {}
    for trial in range(4):
        rest = np.sort(rng.uniform(55.0, 75.0, 200 + 100 * trial))
        want = np.empty(cand.size)
        ik.candidate_gaps_jit(rest, x, y, band_lo, band_hi, 0.8, 0.6, cand, 55.0, 75.0, want)
        assert np.array_equal(ik.candidate_gaps(rest, tracks, cand, 55.0, 75.0, kept=kept, key=0.0), want)
        assert np.array_equal(ik.candidate_gaps(rest, tracks, cand, 55.0, 75.0), want)
    assert list(kept) == [0.0]
    for key in range(1, ik.KEPT_CANDIDATE_SETS + 2):
        ik.candidate_gaps(rest, tracks, cand + 0.01 * key, 55.0, 75.0, kept=kept, key=key)
    assert len(kept) == ik.KEPT_CANDIDATE_SETS
    with pytest.raises(ValueError, match="another candidate set"):
        ik.candidate_gaps(rest, tracks, cand + 0.5, 55.0, 75.0, kept=kept, key=0.0)


def test_profile_add_matches_bincount_order():
    rng = np.random.default_rng(7)
    idx = rng.integers(-5, 60, (9, 200))  # many hits per bin, some outside
    k = rng.uniform(-0.2, 1.0, (9, 200))
    t0 = rng.uniform(0.0, 3.0, 55)
    a, b = t0.copy(), t0.copy()
    ik.profile_add_jit(a, idx, k)
    assert np.array_equal(a, ik.profile_add_numpy(b, idx, k))


def test_shortfall_terms_match_numpy():
    """Random profiles with a hole, and rows at the edge of the kernel's shortcut (terms known to be
    0 without the divisions): constant rows at target 1 (t equal to its local mean), rows a hair
    above and below the target, zeros, denormals."""
    rng = np.random.default_rng(9)
    fixed, prof = rng.uniform(0.0, 2.0, 500), rng.uniform(0.0, 2.0, (10, 500))
    prof[:4, 100:130] = 0.0
    prof[4] = 0.3
    prof[5] = 0.3 * (1.0 + 1e-13 * rng.standard_normal(500))
    prof[6] = 0.3 * (1.0 + 1e-16 * rng.standard_normal(500))
    prof[7] = 0.0
    prof[8] = 1e-310 * rng.uniform(0.0, 1.0, 500)
    prof[9] = np.where(np.arange(500) % 7 == 0, 0.0, 0.3)
    for fx, target in ((fixed, 0.8), (np.zeros(500), 1.0), (np.zeros(500), 0.8), (np.full(500, 1e-305), 1.0)):
        out = np.empty(prof.shape)
        ik.shortfall_terms_jit(fx, prof, 25, target, out)
        t = fx[None, :] + prof
        c = np.cumsum(np.pad(t, ((0, 0), (1, 0))), axis=1)
        i = np.arange(500)
        lo, hi = np.maximum(0, i - 25), np.minimum(500, i + 26)
        local = (c[:, hi] - c[:, lo]) / (hi - lo)
        assert np.array_equal(out, np.maximum(0.0, 1.0 - t / np.maximum(target * local, 1e-300)) ** 2)


@pytest.mark.parametrize("n_g", [1, 10, 25, 26, 50, 51, 52, 53, 54, 200])
def test_shortfall_terms_at_every_window_edge(n_g):
    """The kernel's three row ranges (window cut at the start, whole inside, cut at the end) against
    numpy's cumsum form for grids shorter than, as long as and longer than the window (win 25)."""
    rng = np.random.default_rng(n_g)
    fixed, prof = rng.uniform(0.0, 2.0, n_g), rng.uniform(0.0, 2.0, (6, n_g))
    out = np.empty(prof.shape)
    ik.shortfall_terms_jit(fixed, prof, 25, 0.8, out)
    t = fixed[None, :] + prof
    c = np.cumsum(np.pad(t, ((0, 0), (1, 0))), axis=1)
    i = np.arange(n_g)
    lo, hi = np.maximum(0, i - 25), np.minimum(n_g, i + 26)
    local = (c[:, hi] - c[:, lo]) / (hi - lo)
    assert np.array_equal(out, np.maximum(0.0, 1.0 - t / np.maximum(0.8 * local, 1e-300)) ** 2)


def test_profile_base_matches_numpy():
    """The grid points near each track and their cap base, against numpy's form (radii on grid
    points, between them, a hair either side; the cap's edge at x = +-1)."""
    rng = np.random.default_rng(4)
    step, grid0, a_mm = 0.002, 59.9, 0.0248
    r = np.concatenate([grid0 + step * rng.integers(0, 5000, 40), rng.uniform(60.0, 70.0, 400),
                        np.nextafter(grid0 + step * 17, np.inf) + np.zeros(3), grid0 + step * 9 + a_mm * np.array([1.0, -1.0])])
    n_s = 2 * (int(np.ceil(a_mm / step)) + 1) + 1
    got = np.empty((n_s, r.size), np.int64), np.empty((n_s, r.size))
    want = np.empty((n_s, r.size), np.int64), np.empty((n_s, r.size))
    ik.profile_base_jit(r, grid0, step, a_mm, *got)
    ik.profile_base_numpy(r, grid0, step, a_mm, *want)
    assert np.array_equal(got[0], want[0]) and np.array_equal(got[1], want[1])
    assert (got[1] == 0.0).any() and (got[1] > 0.99).any()
