"""Output-sensitive maps of the exact transform: per-track firing windows against brute force.

The windows (where each nozzle's circle crosses the design's rectangle) are found analytically;
these tests check, over every firing and nozzle of the swathe, that no drop landing in the
design is left outside them, and that the gather gives the same print as a dense gather.
"""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.rotary import Placement, exact_maps, transform_exact
from rotoprint.rotary import _exact_kernels as K
from rotoprint.rotary.exact import firing_range
from rotoprint.rotary.testimage import test_design as make_design

HEAD = load_device("omnidot760").head

CASES = [
    # (width, height, pitch_x, pitch_y, inner radius, placement angle, tilt, direction, mount angle, ref radius)
    (120, 90, 25.4 / 360, 25.4 / 360, 60.0, 0.0, 20.0, 1, 0.0, None),
    (120, 90, 25.4 / 360, 25.4 / 360, 60.0, 0.0, 0.0, -1, 0.0, None),
    (300, 40, 0.1, 0.05, 20.0, 33.0, 45.0, 1, 0.0, None),  # wide and flat
    (40, 300, 0.05, 0.1, 8.0, -120.0, 70.0, -1, 0.0, 12.0),  # tall, near the axis: tracks beyond its outer edge cross two corners
    (200, 200, 0.2, 0.2, 3.0, 170.0, -25.0, 1, 15.0, None),  # several swathes, angle past 180 at the far edge
    (64, 64, 0.0705, 0.0705, 100.0, 90.0, 33.0, 1, -30.0, None),
    (1200, 1200, 25.4 / 360, 25.4 / 360, 60.0, 0.0, 20.0, 1, 0.0, None),  # the bench and acceptance setting
]


def _brute_force(m, j, pl):
    """Every firing of the swathe's firing range x every nozzle, trimmed like exact_maps."""
    sm = m.swathes[j]
    a_lo, a_hi = pl.angular_range_rad()
    i0, i1 = firing_range(sm.layout.phi_rad[sm.enabled], a_lo, a_hi, sm.dphi_rad, m.direction)
    ii = np.arange(i0, i1 + 1, dtype=np.float64) * sm.dphi_rad
    idx, hit = K.index_dense_numpy(*sm.coefficients, sm.enabled, np.cos(ii), np.sin(ii), pl.width_px, pl.height_px)
    if hit.any():
        b0, b1 = int(np.argmax(hit)), int(hit.size - np.argmax(hit[::-1]))
    else:
        b0, b1 = 0, 1
    return i0 + b0, idx[b0:b1]


@pytest.mark.parametrize("backend", ["jit", "numpy"])
@pytest.mark.parametrize("case", range(len(CASES)))
def test_windows_miss_no_drop(case, backend):
    w, h, px, py, r0, ang, tilt, direction, mount, ref = CASES[case]
    pl = Placement(w, h, px, py, inner_radius_mm=r0, angle_deg=ang)
    m = exact_maps(HEAD, pl, tilt_deg=tilt, direction=direction, mount_angle_deg=mount, ref_radius_mm=ref, backend=backend)
    two_arcs = 0
    for j, sm in enumerate(m.swathes):
        first, dense = _brute_force(m, j, pl)
        assert sm.first_firing == first
        np.testing.assert_array_equal(sm.index, dense)
        win = sm.windows
        assert np.all(win.count > 0) and np.all(np.diff(win.nozzle) >= 0)
        # the drops at both ends of every window land in the design (windows are trimmed)
        assert np.all(win.flat_index[win.start] != w * h)
        assert np.all(win.flat_index[win.start + win.count - 1] != w * h)
        two_arcs += int((np.bincount(win.nozzle) == 2).sum())
        # looked-up drops = drops in the design (+ the rare miss inside a window)
        assert win.n_drops >= int((dense != w * h).sum())
        assert win.n_drops <= int((dense != w * h).sum()) + win.nozzle.size
    if case == 3:
        assert two_arcs > 0  # the case meant to exercise the corner arcs does


def test_track_windows_cover_the_circle_rectangle_crossing():
    # sample every track densely in angle and check each point inside the rectangle is in a window
    rng = np.random.default_rng(3)
    r = rng.uniform(5.0, 80.0, 400)
    phi = rng.uniform(-0.3, 0.3, 400)
    en = rng.random(400) > 0.1
    x0, x1, yh, dphi, ang = 20.0, 60.0, 15.0, 0.002, 0.2
    for direction in (1, -1):
        i0, i1 = -2000, 2000
        wk, wlo, whi = K.track_windows(r, phi, en, direction, ang, x0, x1, yh, dphi, i0, i1)
        i = np.arange(i0, i1 + 1)
        for k in range(r.size):
            a = phi[k] - direction * i * dphi - ang
            x, y = r[k] * np.cos(a), r[k] * np.sin(a)
            inside = (x >= x0) & (x <= x1) & (np.abs(y) <= yh) & en[k]
            covered = np.zeros(i.size, bool)
            for lo, hi in zip(wlo[wk == k], whi[wk == k]):
                covered[lo:hi] = True
            assert not np.any(inside & ~covered), k
            assert np.sum(wk == k) <= 2


@pytest.mark.parametrize("case", [0, 3, 4])
def test_gather_equals_dense_gather(case):
    w, h, px, py, r0, ang, tilt, direction, mount, ref = CASES[case]
    pl = Placement(w, h, px, py, inner_radius_mm=r0, angle_deg=ang)
    d = make_design(max(w, h))[:h, :w].copy()
    for backend in ("jit", "numpy"):
        pr = transform_exact(d, HEAD, pl, tilt_deg=tilt, direction=direction, mount_angle_deg=mount, ref_radius_mm=ref, backend=backend)
        m = exact_maps(HEAD, pl, tilt_deg=tilt, direction=direction, mount_angle_deg=mount, ref_radius_mm=ref, backend=backend)
        flat = np.concatenate([(d.ravel() != 0).astype(np.uint8), np.zeros(1, np.uint8)])
        for s, sm in zip(pr.swathes, m.swathes):
            np.testing.assert_array_equal(s.levels, flat[sm.index])


@pytest.mark.parametrize(
    "values, binary",
    [([0, 0, 0], True), ([0, 255, 255], True), ([7, 0, 7], True), ([0, 5, 255], False), ([255, 5, 0], False), ([3, 3, 4], False)],
)
def test_binary_levels_agree_with_design_kind(values, binary):
    from rotoprint.rotary.printdata import design_kind

    d = np.array([values * 5] * 3, np.uint8)
    assert (design_kind(d) == "binary") == binary
    for backend in ("jit", "numpy"):
        flat, ok = K.BINARY_LEVELS[backend](d, 3)
        assert ok == binary
        np.testing.assert_array_equal(flat, np.concatenate([np.where(d.ravel() != 0, 3, 0), [0]]).astype(np.uint8))


def test_first_layer_fused_equals_later_layers():
    # the first gather fills the index in the same pass; later ones read it; a map whose index is
    # filled on its own (no gather) holds the same index
    pl = Placement(300, 260, 25.4 / 360, 25.4 / 360, inner_radius_mm=30.0, angle_deg=10.0)
    d = make_design(300)[:260].copy()
    for backend in ("jit", "numpy"):
        exact_maps.cache_clear()
        m = exact_maps(HEAD, pl, tilt_deg=45.0, backend=backend)
        first = m.apply(d)
        second = m.apply(d)
        exact_maps.cache_clear()
        fresh = exact_maps(HEAD, pl, tilt_deg=45.0, backend=backend)
        for a, b, sm, sf in zip(first.swathes, second.swathes, m.swathes, fresh.swathes):
            np.testing.assert_array_equal(a.levels, b.levels)
            np.testing.assert_array_equal(sm.windows.flat_index, sf.windows.flat_index)
            np.testing.assert_array_equal(sm.index, sf.index)


def test_index_kernel_int64_path():
    # designs of 2**31 pixels or more need int64 indices; run the backend on a one-drop window of such a size
    coef = (np.array([1.0]), np.array([0.0]), 0.0, np.array([1.0]), np.array([0.0]), 0.0)
    w = h = 50_000
    assert K.index_dtype(w, h) == np.int64
    one = np.array([0])
    idx = np.empty(1, np.int64)
    K.windows_fill_numba(coef, one, one, np.array([1]), one, np.array([40_000.5]), np.array([0.0]), w, h, idx)
    assert idx[0] == 40_000 * w + 40_000
    first, last = K.window_bounds_numba(*coef, one, one, np.array([1]), np.array([40_000.5]), np.array([0.0]), w, h)
    assert first[0] == 0 and last[0] == 1


def test_track_windows_never_overlap():
    # tracks just beyond the outer edge: two arcs close together, merged when their margins meet
    r = 60.0 + np.linspace(0.0, 0.05, 200)
    for direction in (1, -1):
        wk, wlo, whi = K.track_windows(r, np.zeros(r.size), np.ones(r.size, bool), direction, 0.0, 10.0, 60.0, 20.0, 0.001, -2000, 2000)
        for k in np.unique(wk):
            lo, hi = wlo[wk == k], whi[wk == k]
            assert np.all(lo[1:] >= hi[:-1])
        assert np.bincount(wk).max() == 2 and np.bincount(wk).min() == 1  # both cases occur


def test_maps_pickle_before_and_after_first_layer():
    import pickle

    pl = Placement(80, 60, 25.4 / 360, 25.4 / 360, inner_radius_mm=60.0)
    d = make_design(80)[:60].copy()
    exact_maps.cache_clear()
    m = exact_maps(HEAD, pl, tilt_deg=20.0)
    m2 = pickle.loads(pickle.dumps(m))  # index not filled yet
    ref = m.apply(d)
    m3 = pickle.loads(pickle.dumps(m))  # filled
    for a, b, c in zip(ref.swathes, m2.apply(d).swathes, m3.apply(d).swathes):
        np.testing.assert_array_equal(a.levels, b.levels)
        np.testing.assert_array_equal(a.levels, c.levels)


def test_maps_refuse_a_side_the_int32_landing_index_cannot_hold():
    """The kernels truncate a drop's column and row through int32 (packed float64 -> int32 exists on
    AVX2; -> int64 needs AVX-512): a design side of 2**31 px or more is refused before any map is built."""
    from rotoprint.errors import ImageError

    head = load_device("omnidot760").head
    with pytest.raises(ImageError, match=r"2147483648 x 2 px.*at most 2147483647 px a side"):
        exact_maps(head, Placement(2**31, 2, 1e-5, 0.07, inner_radius_mm=60.0), tilt_deg=20.0)
