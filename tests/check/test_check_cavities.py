"""Enclosed cavities (resin traps): a sealed hollow is found once, with its volume; a cup open
at the top, a hollow with a drain hole and the feature piece have none."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint.check import check_printability
from rotoprint.check._cavities import CavityTracker, empty_runs
from rotoprint.devices import load_device
from rotoprint.mesh import Mesh
from rotoprint.testing import box_triangles


def _hollow(outer, wall, drain=None, lid=True):
    """A box ``outer`` (x, y, z) mm with walls ``wall`` thick; ``drain``: a hole (x0, x1) mm
    through the +x wall near the bottom; ``lid``: closed at the top."""
    X, Y, Z = outer
    t = wall
    parts = [
        box_triangles((X, Y, t)),  # floor
        box_triangles((X, t, Z - t), (0, 0, t)),
        box_triangles((X, t, Z - t), (0, Y - t, t)),
        box_triangles((t, Y - 2 * t, Z - t), (0, t, t)),
    ]
    if drain is None:
        parts.append(box_triangles((t, Y - 2 * t, Z - t), (X - t, t, t)))
    else:  # the +x wall with a slot from y0 to y1 through its whole height above the floor
        y0, y1 = drain
        parts.append(box_triangles((t, y0 - t, Z - t), (X - t, t, t)))
        parts.append(box_triangles((t, Y - t - y1, Z - t), (X - t, y1, t)))
    if lid:
        parts.append(box_triangles((X, Y, t), (0, 0, Z)))
    return Mesh.from_triangles(np.concatenate(parts))


def test_empty_runs_complement():
    rs = np.array([0, 2, 2, 3])
    r0 = np.array([0, 5, 3])
    r1 = np.array([2, 7, 10])
    es, e0, e1 = empty_runs(rs, r0, r1, 10)
    assert es.tolist() == [0, 2, 3, 4]
    assert list(zip(e0.tolist(), e1.tolist())) == [(2, 5), (7, 10), (0, 10), (0, 3)]


@pytest.mark.parametrize("device_name", ["perfactory-sxga", "omnidot760"])
def test_sealed_hollow_is_one_cavity(device_name):
    dev = load_device(device_name)
    mesh = _hollow((4.0, 3.0, 2.0), 0.5)
    rep = check_printability(mesh, dev, layer_height_mm=0.1, islands=False)
    cav = [f for f in rep.findings if f.kind == "cavity"]
    assert len(cav) == 1
    c = cav[0]
    # inside: 3 x 2 mm from z 0.5 to 2.0 (layers at 0.05 .. 1.95: 15 layers hollow)
    inner = 3.0 * 2.0 * 1.5
    assert c.volume_mm3 == pytest.approx(inner, rel=0.08)
    assert c.x_mm == pytest.approx(2.0, abs=0.05) and c.y_mm == pytest.approx(1.5, abs=0.05)
    assert rep.settings["layer_height_mm"] * (c.layer - c.first_layer) == pytest.approx(1.5, abs=1e-9)
    assert c.bbox_mm[0] == pytest.approx(0.5, abs=0.1) and c.bbox_mm[2] == pytest.approx(3.5, abs=0.1)
    assert rep.to_json()["cavity_volume_mm3"] == pytest.approx(c.volume_mm3)
    assert [r for r in rep.regions() if r["kind"] == "cavity"][0]["volume_mm3"] == pytest.approx(c.volume_mm3)
    # switched off: none
    off = check_printability(mesh, dev, layer_height_mm=0.1, islands=False, cavities=False)
    assert not [f for f in off.findings if f.kind == "cavity"]


@pytest.mark.parametrize("kind", ["cup", "drain"])
def test_open_hollows_are_not_cavities(kind):
    dev = load_device("perfactory-sxga")
    mesh = _hollow((4.0, 3.0, 2.0), 0.5, lid=kind != "cup", drain=(1.2, 1.8) if kind == "drain" else None)
    rep = check_printability(mesh, dev, layer_height_mm=0.1, islands=False)
    assert not [f for f in rep.findings if f.kind == "cavity"]


def test_two_cavities_and_a_merge():
    """Two sealed hollows side by side are two cavities; the tracker joins a U-shaped void
    (two pockets that meet higher up) into one."""
    dev = load_device("perfactory-sxga")
    a = _hollow((2.0, 2.0, 1.5), 0.4)
    b = _hollow((2.0, 2.0, 1.5), 0.4)
    tris = np.concatenate([a.vertices[a.faces], b.vertices[b.faces] + np.array([3.0, 0.0, 0.0])])
    rep = check_printability(Mesh.from_triangles(tris), dev, layer_height_mm=0.1, islands=False)
    cav = sorted((f for f in rep.findings if f.kind == "cavity"), key=lambda f: f.x_mm)
    assert len(cav) == 2 and cav[0].x_mm < 2.0 < 3.0 < cav[1].x_mm
    # the tracker on hand-made layers: two pockets (layers 1-2) joined by a bridge (layer 3),
    # roofed at layer 4
    W = H = 12

    def layer(holes):
        img = np.ones((H, W), bool)
        for r0_, r1_, c0_, c1_ in holes:
            img[r0_:r1_, c0_:c1_] = False
        rs, s0, s1 = [0], [], []
        for row in img:
            d = np.diff(np.concatenate([[0], row.astype(int), [0]]))
            st, en = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
            s0 += st.tolist()
            s1 += en.tolist()
            rs.append(len(s0))
        return np.array(rs), np.array(s0, np.int64), np.array(s1, np.int64)

    tr = CavityTracker(W, H)
    out = []
    for i, holes in enumerate([[], [(2, 5, 2, 5), (2, 5, 7, 10)], [(2, 5, 2, 5), (2, 5, 7, 10)], [(2, 5, 2, 10)], []]):
        out += [(i, r) for r in tr.step(*layer(holes), i)]
    assert len(out) == 1
    i, r = out[0]
    assert i == 4 and r["first_layer"] == 1 and r["last_layer"] == 3
    assert r["pixels"] == 9 + 9 + 9 + 9 + 24


def test_cavity_box_on_the_overlay():
    from rotoprint.check import check_layers, overlay_image
    from rotoprint.check.overlay import COLOURS

    dev = load_device("perfactory-sxga")
    for lc in check_layers(_hollow((4.0, 3.0, 2.0), 0.5), dev, layer_height_mm=0.1, islands=False):
        if any(f.kind == "cavity" for f in lc.findings):
            ov = overlay_image(lc)
            box = lc.chords["cavity"]
            assert box.shape == (4, 4)
            hit = np.all(ov == np.array(COLOURS["cavity"], np.uint8), axis=2)
            rows, cols = np.nonzero(hit)
            f = next(f for f in lc.findings if f.kind == "cavity")
            # the box's outline, around the cavity's centroid
            assert rows.min() < f.row < rows.max() and cols.min() < f.col < cols.max()
            break
    else:
        raise AssertionError("no cavity found")


def _runs(img):
    rs, s0, s1 = [0], [], []
    for row in img:
        d = np.diff(np.concatenate([[0], row.astype(int), [0]]))
        s0 += np.flatnonzero(d == 1).tolist()
        s1 += np.flatnonzero(d == -1).tolist()
        rs.append(len(s0))
    return np.array(rs), np.array(s0, np.int64), np.array(s1, np.int64)


@pytest.mark.parametrize("floor, cavity", [(False, False), (True, True)])
def test_hole_over_open_space_is_open(floor, cavity):
    """A ring closed by a roof: a cavity when a floor is under it; open when nothing is (its
    void reaches the outside through the layer below, which has no hole of its own)."""
    W = H = 10
    square = np.zeros((H, W), bool)
    square[2:8, 2:8] = True
    ring = square.copy()
    ring[4:6, 4:6] = False
    tr = CavityTracker(W, H)
    out = []
    for i, img in enumerate([square if floor else np.zeros((H, W), bool), ring, ring, square, np.zeros((H, W), bool)]):
        out += tr.step(*_runs(img), i)
    assert (len(out) == 1) == cavity
    if cavity:
        assert out[0]["first_layer"] == 1 and out[0]["last_layer"] == 2 and out[0]["pixels"] == 8


def test_nested_cavities_stay_two_regions():
    """A sealed hollow inside another (roofs one layer apart, boxes overlapping) is two
    regions, each with its own volume and layers."""
    inv = lambda t: t[:, ::-1, :]  # noqa: E731 - an inward-facing box (a void)
    tris = np.concatenate(
        [
            box_triangles((4, 4, 2)),
            inv(box_triangles((3, 3, 1.4), (0.5, 0.5, 0.3))),
            box_triangles((2, 2, 1.18), (1, 1, 0.5)),
            inv(box_triangles((1, 1, 0.8), (1.5, 1.5, 0.8))),
        ]
    )
    rep = check_printability(Mesh.from_triangles(tris), load_device("perfactory-sxga"), layer_height_mm=0.1, islands=False)
    cav = [f for f in rep.findings if f.kind == "cavity"]
    regs = [r for r in rep.regions() if r["kind"] == "cavity"]
    assert len(cav) == 2 and len(regs) == 2
    assert sorted(r["volume_mm3"] for r in regs) == sorted(f.volume_mm3 for f in cav)
    for r in regs:
        assert r["z_mm"][0] < r["z_mm"][1] and r["first_layer"] < r["last_layer"]
    inner = min(regs, key=lambda r: r["volume_mm3"])
    assert inner["volume_mm3"] == pytest.approx(1.0 * 1.0 * 0.8, rel=0.1)
