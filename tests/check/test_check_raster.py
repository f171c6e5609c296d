"""Raster, island and exposure checks, and the device limits."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotoprint.check import check_layers, check_printability, device_limits, rotary_tracks, smooth_mask
from rotoprint.devices import load_device
from rotoprint.errors import ConfigError, RotoprintError
from rotoprint.mesh import Mesh
from rotoprint.pieces import feature_test_piece
from rotoprint.slicing import slice_mesh
from rotoprint.testing import box_mesh, box_triangles


def _pixel_centres_in_box(job, img, x0, x1, y0, y1):
    H, W = img.shape
    rr, cc = np.mgrid[0:H, 0:W]
    m = job.grid.pixel_to_model
    X = m[0, 0] * cc + m[0, 1] * rr + m[0, 2]
    Y = m[1, 0] * cc + m[1, 1] * rr + m[1, 2]
    return (X >= x0) & (X <= x1) & (Y >= y0) & (Y <= y1)


def test_check_vanished_walls_match_the_image():
    """A straight wall with no material pixel centre in it is reported as vanished; one with a
    pixel column all along its length is not (checked on the image, independently)."""
    tris, feats = feature_test_piece()
    dev = load_device("omnidot760")
    job = slice_mesh(Mesh.from_triangles(tris), dev, layer_height_mm=0.6)
    lc = list(check_layers(job, dev, islands=False))[1]  # a layer through the features
    vanished = [f for f in lc.findings if f.kind == "vanished_wall"]
    n_checked = 0
    for f in feats:
        if f.kind != "wall":
            continue
        inside = _pixel_centres_in_box(job, lc.image, f.x0, f.x1, f.y0 + 0.1, f.y1 - 0.1)
        material = inside & (lc.image > 0)
        hit = [v for v in vanished if f.x0 - 1e-6 <= v.x_mm <= f.x1 + 1e-6 and f.y0 <= v.y_mm <= f.y1]
        if not material.any():
            assert hit, f"wall of {f.width_mm * 1000:.0f} um has no pixel but is not reported vanished"
            n_checked += 1
        elif np.all(material.any(axis=1)[inside.any(axis=1)]):  # a material pixel in every row
            assert not hit, f"wall of {f.width_mm * 1000:.0f} um is in the image but reported vanished"
            n_checked += 1
    assert n_checked >= 5


def test_check_islands():
    base = box_triangles((1.0, 1.0, 0.4))
    floating = box_triangles((0.3, 0.3, 0.2), (2.0, 0.0, 0.4))  # nothing below it
    cap = box_triangles((1.2, 1.2, 0.2), (-0.1, -0.1, 0.4))  # overhangs, but stands on the base
    rep = check_printability(Mesh.from_triangles(np.concatenate([base, floating, cap])), load_device("perfactory-sxga"), layer_height_mm=0.2)
    isl = [f for f in rep.findings if f.kind == "island"]
    assert len(isl) == 1
    f = isl[0]
    assert f.layer == 2 and f.area_mm2 == pytest.approx(0.09, rel=0.1)
    assert 2.0 <= f.x_mm <= 2.3 and 0.0 <= f.y_mm <= 0.3
    rep2 = check_printability(Mesh.from_triangles(np.concatenate([base, floating, cap])), load_device("perfactory-sxga"), layer_height_mm=0.2, islands=False)
    assert not [f for f in rep2.findings if f.kind == "island"]


def test_check_exposure_smooth_mask():
    dev = load_device("perfactory-sxga")
    p = dev.pitch_x_mm
    # a wall of 0.6 px holds at most one pixel column: SMOOTH gives it 7/13 < 0.6 of full;
    # a wall of 3.5 px holds three or four and cures
    tris = np.concatenate([box_triangles((0.6 * p, 1.0, 0.2), (0.0, 0.0, 0.0)), box_triangles((3.5 * p, 1.0, 0.2), (0.5, 0.0, 0.0))])
    rep = check_printability(
        Mesh.from_triangles(tris), dev, layer_height_mm=0.2, mask_fn=smooth_mask, mask_name="smooth", cure_threshold=0.6, min_wall_mm=0.01, min_gap_mm=0.01
    )
    under = [f for f in rep.findings if f.kind == "underexposed"]
    assert under and all(f.x_mm < 0.6 * p + 1e-6 for f in under)
    assert all(f.value < 0.6 for f in under)
    assert rep.settings["exposure_model"] == "smooth" and rep.settings["cure_threshold"] == 0.6
    # the paper's default threshold 0.5: a one-pixel line still cures (137/255)
    assert int(smooth_mask(np.pad(np.full((9, 1), 255, np.uint8), ((0, 0), (4, 4))))[4, 4]) == 137


def test_check_cured_gap_smooth_mask():
    dev = load_device("perfactory-sxga")
    p = dev.pitch_x_mm
    # a gap of 0.9 px holds at most one empty pixel column; with SMOOTH and a
    # low threshold a one-pixel gap (6/13 of full) cures shut too
    tris = np.concatenate([box_triangles((0.5, 1.0, 0.2)), box_triangles((0.5, 1.0, 0.2), (0.5 + 0.9 * p, 0.0, 0.0))])
    rep = check_printability(
        Mesh.from_triangles(tris), dev, layer_height_mm=0.2, mask_fn=smooth_mask, mask_name="smooth", cure_threshold=0.3, islands=False
    )
    cured = [f for f in rep.findings if f.kind == "cured_gap"]
    assert cured and all(0.5 <= f.x_mm <= 0.5 + 0.9 * p for f in cured)


def test_check_limits_headline():
    ink = device_limits(load_device("omnidot760"))
    assert ink["min_wall_mm"] == pytest.approx(0.07056, abs=1e-5)  # about 70 um across a 360 dpi head
    assert ink["min_wall_x_mm"] == pytest.approx(53.8 / 764)
    proj = device_limits(load_device("perfactory-sxga"))
    assert proj["min_wall_mm"] == pytest.approx(0.01984, abs=1e-5)  # about 20 um for 1400 x 1050
    sm = device_limits(load_device("perfactory-sxga"), mask_fn=smooth_mask, cure_threshold=0.6)
    assert sm["min_wall_x_mm"] == pytest.approx(2 * 27.77 / 1400)  # one pixel no longer cures
    assert sm["min_gap_x_mm"] == pytest.approx(27.77 / 1400)
    big_drop = device_limits(load_device("omnidot760", drop_diameter_um=150))
    assert big_drop["min_gap_x_mm"] == pytest.approx(2 * 53.8 / 764)  # (n + 1) p > d: two empty tracks


@pytest.mark.parametrize("tilt", [0.0, 20.0, 45.0, 60.0, 80.0])
def test_check_rotary_track_gap_far_from_axis(tilt):
    """Far from the axis the tracks follow rotary-geometry.md section 7: rows offset by
    p cos + d sin, so the two rows leave gaps a and 2 p cos - a."""
    dev = load_device("omnidot760")
    r = rotary_tracks(dev, tilt_deg=tilt, radius_mm=1e8)
    p, d = dev.head.pitch_mm, dev.head.row_separation_mm
    c = math.cos(math.radians(tilt))
    a = (p * c + d * math.sin(math.radians(tilt))) % (2 * p * c)
    assert r["largest_track_gap_mm"] == pytest.approx(max(a, 2 * p * c - a), rel=2e-3)
    assert r["track_pitch_nominal_mm"] == pytest.approx(p * c)
    assert r["projected_swathe_mm"] == pytest.approx(53.8 * c - d * math.sin(math.radians(tilt)))


def test_check_bad_arguments():
    dev = load_device("perfactory-sxga")
    m = box_mesh((1, 1, 0.2))
    for kw in ({"min_wall_mm": 0}, {"min_gap_mm": -1}, {"min_wall_mm": float("inf")}, {"cure_threshold": 0.5}):
        with pytest.raises(ConfigError):
            check_printability(m, dev, layer_height_mm=0.2, **kw)
    with pytest.raises(ConfigError):
        check_printability(m, dev)  # no layer height
    with pytest.raises(ConfigError):
        check_printability("part.stl", dev, layer_height_mm=0.2)
    with pytest.raises(RotoprintError):
        rotary_tracks(dev, tilt_deg=10, radius_mm=50)  # a projector has no tracks
    with pytest.raises(ConfigError):
        rotary_tracks(load_device("omnidot760"), tilt_deg=95, radius_mm=50)


@pytest.mark.parametrize("device_name", ["perfactory-sxga", "omnidot760"])
def test_raster_test_limit_covers_every_wall_that_can_vanish(device_name):
    """Why walls and gaps are tested against the raster only below 1.1 pixels: the chord's
    rectangle (width across, one pixel either side along) holds a pixel centre, at any angle
    and offset, as soon as it is one (larger) pitch wide; narrower, it can miss them all. On
    an all-material image every chord of 1.0 pitch finds material, and some of 0.95 do not."""
    import _reference_kernels as R
    from rotoprint.check.options import RASTER_TEST_PX as _RASTER_TEST_PX

    dev = load_device(device_name)
    job = slice_mesh(box_mesh((2.0, 2.0, 0.2)), dev, layer_height_mm=0.1)
    g = job.grid
    p = max(g.pitch_x_mm, g.pitch_y_mm)
    img = np.full((g.height, g.width), 255, np.uint8)
    rng = np.random.default_rng(7)
    n = 20000
    th = rng.uniform(0, 2 * np.pi, n)
    bx = rng.uniform(-3 * p, 3 * p, n) + float(g.pixel_to_model[0, 0] * g.width / 2 + g.pixel_to_model[0, 1] * g.height / 2 + g.pixel_to_model[0, 2])
    by = rng.uniform(-3 * p, 3 * p, n) + float(g.pixel_to_model[1, 0] * g.width / 2 + g.pixel_to_model[1, 1] * g.height / 2 + g.pixel_to_model[1, 2])
    ux, uy = np.cos(th), np.sin(th)
    m2p, p2m = np.ascontiguousarray(g.model_to_pixel), np.ascontiguousarray(g.pixel_to_model)
    for f, all_found in ((1.0, True), (0.95, False)):
        # the 0.05-pitch margin to 1.1 leaves room for a centre strictly inside the wall
        got = R.chord_presence(bx, by, ux, uy, np.full(n, f * p), img, 255, p2m, m2p, p)
        assert got.all() == all_found, (f, int((~got).sum()))
    assert _RASTER_TEST_PX >= 1.05
