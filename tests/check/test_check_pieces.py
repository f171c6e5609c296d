"""Acceptance on generated pieces of known widths: no wall or gap below the threshold missed,
none wider than the threshold plus one pixel reported."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rotoprint.check import check_layers, check_printability
from rotoprint.check.options import RESOLUTION_PX as _RESOLUTION_PX
from rotoprint.devices import load_device
from rotoprint.mesh import Mesh
from rotoprint.pieces import Feature, feature_test_piece
from rotoprint.testing import box_triangles, extrude_polygon

WALL_KINDS = ("wall", "ring_wall")
GAP_KINDS = ("channel", "ring_gap")


@pytest.fixture(scope="module")
def piece():
    tris, feats = feature_test_piece()
    # the piece also has ring walls of 0.12 mm between its ring gaps and 0.12 mm gaps between
    # its ring walls: add them as features of known width
    extra = []
    rg = [f for f in feats if f.kind == "ring_gap"]
    rw = [f for f in feats if f.kind == "ring_wall"]
    c = rg[0].centre
    extra.append(Feature("ring_wall", 0.12, centre=c, r_in=rg[0].r_in - 0.12, r_out=rg[0].r_in, z0=rg[0].z0, z1=rg[0].z1))
    for f in rg:
        extra.append(Feature("ring_wall", 0.12, centre=c, r_in=f.r_out, r_out=f.r_out + 0.12, z0=f.z0, z1=f.z1))
    for a, b in zip(rw[:-1], rw[1:]):
        extra.append(Feature("ring_gap", round(b.r_in - a.r_out, 9), centre=a.centre, r_in=a.r_out, r_out=b.r_in, z0=a.z0, z1=a.z1))
    return Mesh.from_triangles(tris), feats + extra


def _inside(f: Feature, x: np.ndarray, y: np.ndarray, tol: float) -> np.ndarray:
    if f.kind in ("wall", "channel"):
        return (x >= f.x0 - tol) & (x <= f.x1 + tol) & (y >= f.y0 - tol) & (y <= f.y1 + tol)
    r = np.hypot(x - f.centre[0], y - f.centre[1])
    return (r >= f.r_in - tol) & (r <= f.r_out + tol)


def _midpoints(lc, kind, grid):
    ch = lc.chords.get(kind)
    if ch is None:
        return np.empty(0), np.empty(0), np.empty(0)
    m = grid.pixel_to_model
    cm = 0.5 * (ch[:, 0] + ch[:, 2])
    rm = 0.5 * (ch[:, 1] + ch[:, 3])
    x = m[0, 0] * cm + m[0, 1] * rm + m[0, 2]
    y = m[1, 0] * cm + m[1, 1] * rm + m[1, 2]
    # chord lengths in mm
    a = np.stack([ch[:, 2] - ch[:, 0], ch[:, 3] - ch[:, 1]])
    w = np.hypot(m[0, 0] * a[0] + m[0, 1] * a[1], m[1, 0] * a[0] + m[1, 1] * a[1])
    return x, y, w


@pytest.mark.parametrize(
    "device_name, threshold_mm, resolution_mm",
    [
        ("perfactory-sxga", None, None),
        ("perfactory-sxga", None, 0.0),
        ("perfactory-sxga", 0.045, None),
        ("omnidot760", None, None),
        ("omnidot760", None, 0.0),
        ("omnidot760", 0.13, None),
    ],
)
def test_check_piece_no_miss_no_false_report(piece, device_name, threshold_mm, resolution_mm):
    mesh, feats = piece
    dev = load_device(device_name)
    from rotoprint.slicing import slice_mesh

    job = slice_mesh(mesh, dev, layer_height_mm=0.2)
    p = max(dev.pitch_x_mm, dev.pitch_y_mm)
    T = threshold_mm if threshold_mm is not None else (p if dev.kind == "projector" else max(p, dev.head.drop_diameter_um / 1000))
    layers = list(check_layers(job, dev, min_wall_mm=threshold_mm, min_gap_mm=threshold_mm, islands=False, resolution_mm=resolution_mm))
    # widths on the simplified section are within twice the resolution of the section's
    res = _RESOLUTION_PX * min(dev.pitch_x_mm, dev.pitch_y_mm) if resolution_mm is None else resolution_mm
    feature_layers = [lc for lc in layers if lc.z_mm > feats[0].z0]
    assert feature_layers
    for lc in feature_layers:
        wx, wy, ww = _midpoints(lc, "thin_wall", job.grid)
        gx, gy, gw = _midpoints(lc, "narrow_gap", job.grid)
        assert np.all(ww < T + 1e-9) and np.all(gw < T + 1e-9)
        claimed_w = np.zeros(wx.shape, bool)
        claimed_g = np.zeros(gx.shape, bool)
        for f in feats:
            is_wall = f.kind in WALL_KINDS
            x, y = (wx, wy) if is_wall else (gx, gy)
            hit = _inside(f, x, y, 1e-6)
            if f.width_mm < T:  # must be reported, and on its own width
                assert hit.any(), f"{f.kind} of {f.width_mm * 1000:.0f} um missed at z {lc.z_mm} (T {T * 1000:.1f} um)"
                w = (ww if is_wall else gw)[hit]
                assert abs(np.median(w) - f.width_mm) < 1e-5 + 2 * res  # rings are 720-gons
            elif f.width_mm >= T + p:  # must not be reported
                assert not hit.any(), f"{f.kind} of {f.width_mm * 1000:.0f} um reported (T {T * 1000:.1f} um)"
            if is_wall:
                claimed_w |= hit
            else:
                claimed_g |= hit
        # nothing reported outside the features
        assert claimed_w.all() and claimed_g.all()


def test_check_piece_report_counts(piece):
    mesh, feats = piece
    dev = load_device("perfactory-sxga")
    rep = check_printability(mesh, dev, layer_height_mm=0.4, min_wall_mm=0.045, min_gap_mm=0.045)
    # every layer above the base: walls of 10..40 um (straight and ring) and gaps of 10..40 um,
    # measured within twice the resolution (and exactly on the section as sliced)
    res = rep.settings["resolution_mm"]
    assert res == pytest.approx(_RESOLUTION_PX * min(dev.pitch_x_mm, dev.pitch_y_mm))
    assert rep.thinnest_wall["width_mm"] == pytest.approx(0.010, abs=1e-6 + 2 * res)
    assert rep.narrowest_gap["width_mm"] == pytest.approx(0.010, abs=1e-6 + 2 * res)
    exact = check_printability(mesh, dev, layer_height_mm=0.4, min_wall_mm=0.045, min_gap_mm=0.045, resolution_mm=0)
    assert exact.thinnest_wall["width_mm"] == pytest.approx(0.010, abs=1e-6)
    assert exact.narrowest_gap["width_mm"] == pytest.approx(0.010, abs=1e-6)
    for kind in ("thin_wall", "narrow_gap"):  # regions may group differently, not by much
        assert abs(exact.counts()[kind] - rep.counts()[kind]) <= 0.1 * exact.counts()[kind]
    c = rep.counts()
    assert c["thin_wall"] >= 3 * 8 and c["narrow_gap"] >= 3 * 8
    assert not rep.ok
    for f in rep.findings:
        if f.kind in ("thin_wall", "narrow_gap"):
            assert f.width_mm < 0.045
            assert f.bbox_mm[0] <= f.x_mm <= f.bbox_mm[2] and f.bbox_mm[1] <= f.y_mm <= f.bbox_mm[3]


@pytest.mark.parametrize("angle_deg", [0.0, 7.0, 30.0, 45.0, 61.0, 90.0])
@pytest.mark.parametrize("device_name", ["perfactory-sxga", "omnidot760"])
def test_check_rotated_walls_exact(angle_deg, device_name):
    """Walls and slots of known width at any angle to the grid: reported exactly below T."""
    dev = load_device(device_name)
    p = max(dev.pitch_x_mm, dev.pitch_y_mm)
    T = 3.2 * p
    widths = [0.4 * p, 1.3 * p, 2.9 * p, 3.19 * p, T + p, 5 * p]
    tris, walls = [], []
    a = math.radians(angle_deg)
    R = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    x = 0.0
    L = 40 * p
    for w in widths:  # free-standing walls
        poly = np.array([[x, 0], [x + w, 0], [x + w, L], [x, L]]) @ R.T
        tris.append(extrude_polygon(poly, 0.2))
        walls.append((x, w))
        x += w + 8 * p
    mesh = Mesh.from_triangles(np.concatenate(tris))
    rep = check_printability(mesh, dev, layer_height_mm=0.2, min_wall_mm=T, min_gap_mm=T, islands=False)
    thin = [f for f in rep.findings if f.kind == "thin_wall"]
    got = sorted(round(f.width_mm / p, 6) for f in thin)
    want = sorted(round(w / p, 6) for w in widths if w < T)
    assert got == want
    assert not [f for f in rep.findings if f.kind == "narrow_gap"]


def test_check_corners_are_not_thin():
    """An opening by a disc shaves convex corners; the rays do not report them."""
    dev = load_device("perfactory-sxga")
    tris = np.concatenate([box_triangles((1.0, 1.0, 0.2)), box_triangles((0.3, 0.05, 0.2), (1.0, 0.5, 0.0))])
    rep = check_printability(Mesh.from_triangles(tris), dev, layer_height_mm=0.2, min_wall_mm=0.1, min_gap_mm=0.1)
    kinds = {f.kind for f in rep.findings}
    assert kinds == {"thin_wall"}  # only the 50 um tab, not the square's corners or the notch
    f = [f for f in rep.findings if f.kind == "thin_wall"]
    assert len(f) == 1 and f[0].width_mm == pytest.approx(0.05, abs=1e-9)
    assert 1.0 <= f[0].x_mm <= 1.3


def test_regions_join_findings_through_layers():
    """A fin through every layer is one region; two fins apart are two; a fin broken by a
    layer without it is two."""
    from rotoprint.check import join_regions
    from rotoprint.check.core import Finding

    dev = load_device("perfactory-sxga")
    p = max(dev.pitch_x_mm, dev.pitch_y_mm)
    tris = np.concatenate(
        [
            box_triangles((2.0, 2.0, 0.2)),
            box_triangles((0.01, 1.0, 0.6), (0.5, 0.5, 0.2)),  # 10 um fin, z 0.2..0.8
            box_triangles((0.015, 1.0, 0.3), (1.5, 0.5, 0.2)),  # 15 um fin, z 0.2..0.5
        ]
    )
    rep = check_printability(Mesh.from_triangles(tris), dev, layer_height_mm=0.1, islands=False)
    thin = [r for r in rep.regions() if r["kind"] == "thin_wall"]
    assert len(thin) == 2
    a, b = sorted(thin, key=lambda r: r["x_mm"])
    assert a["width_mm"] == pytest.approx(0.010, abs=1e-6 + 2 * rep.settings["resolution_mm"])
    assert b["width_mm"] == pytest.approx(0.015, abs=1e-6 + 2 * rep.settings["resolution_mm"])
    assert a["last_layer"] - a["first_layer"] == 5 and b["last_layer"] - b["first_layer"] == 2
    assert a["findings"] == sum(1 for f in rep.findings if f.kind == "thin_wall" and f.x_mm < 1.0)
    assert rep.to_json()["regions"] == rep.regions()
    # a gap in the layers splits a region; boxes one pixel apart join
    f = lambda layer, x: Finding("thin_wall", layer, 0.1 * layer, x, 0.0, 0, 0, width_mm=0.01, bbox_mm=(x, 0.0, x + 0.01, 1.0))  # noqa: E731
    assert len(join_regions([f(0, 0.0), f(1, 0.0), f(3, 0.0)])) == 2
    assert len(join_regions([f(0, 0.0), f(1, 0.01 + p)], p)) == 1
    assert len(join_regions([f(0, 0.0), f(1, 0.01 + 2.5 * p)], p)) == 2
