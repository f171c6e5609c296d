"""The Laplace resistance solver against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotoprint.errors import ConfigError
from rotoprint.process import solve_resistance

RS = 2.5  # ohm per square
G = 1.0 / RS


def _solve(mask, a, b, px=0.05, py=0.05, g=G):
    return solve_resistance(mask, sheet_conductance_s=g, terminal_a=a, terminal_b=b, pitch_x_mm=px, pitch_y_mm=py)


def _strip_raster(length, width, angle_deg, pitch, pad):
    """Pixel-centre raster of a strip of ``length x width`` at ``angle_deg``, with terminal pads
    (ideal) beyond both ends; returns mask, A, B."""
    n = int(math.ceil((length + 2 * pad + width) / pitch)) + 8
    c = (np.arange(n) - n / 2 + 0.5) * pitch
    X, Y = np.meshgrid(c, c)
    t = math.radians(angle_deg)
    u = X * math.cos(t) + Y * math.sin(t)  # along the strip
    v = -X * math.sin(t) + Y * math.cos(t)
    inside = (np.abs(v) <= width / 2) & (np.abs(u) <= length / 2 + pad)
    a = inside & (u < -length / 2)
    b = inside & (u > length / 2)
    return inside, a, b


def test_build_strip_aligned_is_exact():
    m = np.zeros((30, 220), bool)
    m[5:25, 10:210] = True  # 200 x 20 pixels of 0.05 mm: L = 10 mm, w = 1 mm
    a = np.zeros_like(m)
    b = np.zeros_like(m)
    a[:, :10] = True
    b[:, 210:] = True
    m |= False
    m[5:25, :10] = True
    m[5:25, 210:] = True
    r = _solve(m, a, b).resistance_ohm
    assert r == pytest.approx(RS * 10.0 / 1.0, rel=1e-12)


@pytest.mark.parametrize("angle", [0.0, 17.0, 30.0, 45.0])
def test_build_strip_at_an_angle_within_one_percent(angle):
    """Staircase edges of a slanted strip cost O(pitch / width): 2.6 % at 20 pixels across,
    1.4 % at 50, within 1 % at 100 (docs/build.md); aligned strips are exact."""
    L, w, p = 8.0, 1.0, 0.01
    m, a, b = _strip_raster(L, w, angle, p, pad=0.5)
    r = _solve(m, a, b, px=p, py=p).resistance_ohm
    assert r == pytest.approx(RS * L / w, rel=0.01)


def test_build_square_between_opposite_edges_is_sheet_resistance():
    n = 64
    m = np.ones((n, n + 2), bool)
    a = np.zeros_like(m)
    b = np.zeros_like(m)
    a[:, 0] = True
    b[:, -1] = True
    assert _solve(m, a, b, px=0.07, py=0.07).resistance_ohm == pytest.approx(RS, rel=1e-12)
    # non-square pixels: n columns of px by n rows of py with n px = n py only if px = py;
    # a square of side s sampled by 0.04 x 0.05 pixels
    s = 4.0
    m = np.ones((int(s / 0.05), int(s / 0.04) + 2), bool)
    a = np.zeros_like(m)
    b = np.zeros_like(m)
    a[:, 0] = True
    b[:, -1] = True
    assert _solve(m, a, b, px=0.04, py=0.05).resistance_ohm == pytest.approx(RS, rel=0.01)


def _annulus(r_in, r_out, pitch):
    n = int(2 * (r_out + 2 * pitch) / pitch)
    c = (np.arange(n) - n / 2 + 0.5) * pitch
    X, Y = np.meshgrid(c, c)
    r = np.hypot(X, Y)
    return r, r <= r_out + pitch, r <= r_in, r > r_out


def test_build_annulus_radial_resistance():
    """Corbino disc: R = R_s ln(b / a) / (2 pi); a curved, unaligned check."""
    a_, b_, p = 1.0, 3.0, 0.02
    r, m, A, B = _annulus(a_, b_, p)
    res = _solve(m, A, B, px=p, py=p)
    assert res.resistance_ohm == pytest.approx(RS * math.log(b_ / a_) / (2 * math.pi), rel=0.01)


def test_build_annulus_with_one_over_r_thickness():
    """Film thickness ~ r0 / r (one angular clock): R = (b - a) / (2 pi sigma t0 r0)."""
    a_, b_, p, r0 = 1.0, 3.0, 0.02, 1.0
    r, m, A, B = _annulus(a_, b_, p)
    g = G * r0 / np.maximum(r, 1e-9)
    res = _solve(m, A, B, px=p, py=p, g=g)
    assert res.resistance_ohm == pytest.approx((b_ - a_) / (2 * math.pi * G * r0), rel=0.01)


def test_build_open_circuit_floating_and_short():
    m = np.zeros((10, 30), bool)
    m[2:8, 0:10] = True
    m[2:8, 20:30] = True
    m[0, 12:15] = True  # floating island
    a = np.zeros_like(m)
    b = np.zeros_like(m)
    a[:, 0] = True
    b[:, 29] = True
    res = _solve(m, a, b)
    assert res.resistance_ohm == math.inf and not res.connected and res.floating_pixels == 3
    m[2:8, 10:20] = True  # now joined: 28 columns between the terminal columns, 6 rows
    res = _solve(m, a, b)
    assert res.connected and res.floating_pixels == 3
    assert res.resistance_ohm == pytest.approx(RS * 28 / 6, rel=1e-12)
    b2 = np.zeros_like(m)
    b2[:, 1] = True
    assert _solve(m, a, b2).resistance_ohm == 0.0
    with pytest.raises(ConfigError, match="terminal B touches no conductor"):
        _solve(m, a, np.zeros_like(m))
