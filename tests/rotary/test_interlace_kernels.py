"""The pass planner's kernels against their numpy references, bit for bit."""

import numpy as np

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


def test_profile_add_matches_bincount_order():
    rng = np.random.default_rng(7)
    idx = rng.integers(-5, 60, (9, 200))  # many hits per bin, some outside
    k = rng.uniform(-0.2, 1.0, (9, 200))
    t0 = rng.uniform(0.0, 3.0, 55)
    a, b = t0.copy(), t0.copy()
    ik.profile_add_jit(a, idx, k)
    assert np.array_equal(a, ik.profile_add_numpy(b, idx, k))


def test_shortfall_terms_match_numpy():
    rng = np.random.default_rng(9)
    fixed, prof = rng.uniform(0.0, 2.0, 500), rng.uniform(0.0, 2.0, (4, 500))
    prof[:, 100:130] = 0.0
    out = np.empty(prof.shape)
    ik.shortfall_terms_jit(fixed, prof, 25, 0.8, out)
    t = fixed[None, :] + prof
    c = np.cumsum(np.pad(t, ((0, 0), (1, 0))), axis=1)
    i = np.arange(500)
    lo, hi = np.maximum(0, i - 25), np.minimum(500, i + 26)
    local = (c[:, hi] - c[:, lo]) / (hi - lo)
    assert np.array_equal(out, np.maximum(0.0, 1.0 - t / np.maximum(0.8 * local, 1e-300)) ** 2)
