"""Head model and the paper's closed forms against hand-computed values."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rotoprint import GeometryError, load_device
from rotoprint.rotary import Mount, head_figures, max_tilt_deg, nozzle_layout, paper_figures

HEAD = load_device("omnidot760").head
P = 53.8 / 764
D = HEAD.row_separation_mm


def test_preset_reproduces_max_tilt():
    assert round(max_tilt_deg(HEAD), 1) == 85.5
    # eq (2) vanishes there
    assert abs(paper_figures(HEAD, max_tilt_deg(HEAD), check=False)["ps_p_mm"]) < 1e-9


@pytest.mark.parametrize("tilt", [0.0, 20.0, 45.0, 70.0])
def test_paper_formulas_hand_computed(tilt):
    f = paper_figures(HEAD, tilt, pivot_radius_mm=60.0)
    c, s = math.cos(math.radians(tilt)), math.sin(math.radians(tilt))
    assert f["cx_T_mm"] == pytest.approx(60.0 + D * s / 2)  # (1)
    assert f["ps_p_mm"] == pytest.approx(53.8 * c - D * s)  # (2)
    assert f["dpi_xp"] == pytest.approx(25.4 * 764 / 53.8 / c)  # (3)
    assert f["pitch_radial_mm"] == pytest.approx(P * c)


def test_paper_numbers_at_60_deg():
    # by hand: 25.4*764/53.8 = 360.699; /cos 60 = 721.398; 26.9 - 4.2334*0.866025 = 23.2338
    f = paper_figures(HEAD, 60.0)
    assert f["dpi_xp"] == pytest.approx(721.398, abs=1e-3)
    assert f["ps_p_mm"] == pytest.approx(23.2338, abs=1e-4)


@pytest.mark.parametrize("tilt", [0.0, 20.0, 45.0, 70.0])
def test_first_and_last_nozzle_of_each_row(tilt):
    R = 60.0
    th = math.radians(tilt)
    lay = nozzle_layout(HEAD, Mount(R, tilt_deg=tilt))
    for k, t in ((0, -D / 2), (762, -D / 2), (1, D / 2), (763, D / 2)):  # row A first/last, row B first/last
        s = k * P
        x = R + s * math.cos(th) - t * math.sin(th)
        y = s * math.sin(th) + t * math.cos(th)
        assert lay.r_mm[k] == pytest.approx(math.hypot(x, y), abs=1e-12)
        assert lay.phi_rad[k] == pytest.approx(math.atan2(y, x), abs=1e-12)
        assert lay.row[k] == k % 2


def test_untilted_head_hand_values():
    lay = nozzle_layout(HEAD, Mount(60.0))
    # nozzle 0: (60, -d/2), nozzle 763: (60 + 763 p, +d/2)
    assert lay.r_mm[0] == pytest.approx(math.sqrt(60**2 + (D / 2) ** 2))
    assert lay.r_mm[763] == pytest.approx(math.sqrt((60 + 763 * P) ** 2 + (D / 2) ** 2))
    assert lay.phi_rad[0] < 0 < lay.phi_rad[1]  # row A behind the centre line for direction +1


@settings(max_examples=40, deadline=None)
@given(R=st.floats(20, 400), tilt=st.floats(-80, 80), psi=st.floats(-180, 180))
def test_invariants_under_mount_angle(R, tilt, psi):
    """Radii do not depend on the mount angle; angles shift by it; neighbours in a row are 2p apart."""
    a = nozzle_layout(HEAD, Mount(R, tilt_deg=tilt))
    b = nozzle_layout(HEAD, Mount(R, tilt_deg=tilt, mount_angle_deg=psi))
    np.testing.assert_allclose(a.r_mm, b.r_mm, rtol=0, atol=1e-9)
    d = np.angle(np.exp(1j * (b.phi_rad - a.phi_rad - math.radians(psi))))
    np.testing.assert_allclose(d, 0, atol=1e-9)
    step = np.hypot(*np.diff(a.xy_mm[0::2], axis=0).T)
    np.testing.assert_allclose(step, 2 * P, rtol=1e-9)


def test_exact_band_tends_to_paper_at_large_radius():
    f = head_figures(HEAD, tilt_deg=30.0, pivot_radius_mm=1e8)
    lo, hi = f.overlap_band_mm
    # eq (2) counts ps = N p; nozzle centres span (N - 1) p, one radial pitch less
    assert hi - lo == pytest.approx(f.paper["ps_p_mm"] - f.paper["pitch_radial_mm"], abs=1e-5)


def test_largest_gap_untilted_is_pitch_and_tilted_is_larger():
    assert head_figures(HEAD, tilt_deg=0.0, pivot_radius_mm=60).largest_track_gap_mm == pytest.approx(P, rel=1e-3)
    f = head_figures(HEAD, tilt_deg=20.0, pivot_radius_mm=60)
    assert f.largest_track_gap_mm > 1.5 * f.paper["pitch_radial_mm"]  # rows nearly coincide somewhere


def test_dead_nozzle_widens_gap():
    h = HEAD.model_copy(update={"dead_nozzles": (400,)})
    assert head_figures(h, tilt_deg=0.0, pivot_radius_mm=60).largest_track_gap_mm == pytest.approx(2 * P, rel=1e-3)


@pytest.mark.parametrize("tilt", [85.5, 86.0, -90.0])
def test_tilt_at_or_beyond_max_refused(tilt):
    with pytest.raises(GeometryError, match="maximum tilt"):
        paper_figures(HEAD, tilt)


def test_nozzles_over_axis_refused():
    with pytest.raises(GeometryError, match="over or behind the axis"):
        nozzle_layout(HEAD, Mount(1.0, tilt_deg=70.0))
