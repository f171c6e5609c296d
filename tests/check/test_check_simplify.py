"""The section simplification the check measures widths on (``resolution_mm``): every dropped
joint within the resolution of its chord, nothing moved or joined, and widths within twice the
resolution of those measured on the section as sliced."""

from __future__ import annotations

import numpy as np
import pytest
import shapely

from rotoprint.check import _kernels as K
from rotoprint.check import check_printability
from rotoprint.check.options import resolution_for
from rotoprint.devices import load_device
from rotoprint.errors import ConfigError
from rotoprint.mesh import Mesh
from rotoprint.pieces import annulus_prism, feature_test_piece
from rotoprint.slicing import slice_mesh
from rotoprint.testing import box_triangles


def _simplify(seg, tol):
    top = int(max(seg.start_edge.max(), seg.end_edge.max())) + 1
    pos = np.full(top, -1, np.int32)
    s0, e0, need = K.simplify_section(seg.start, seg.end, seg.start_edge, seg.end_edge, tol, pos[: top - 1])
    assert need == top and len(s0) == 0  # a buffer too short is refused with the length it needs
    s, e, need = K.simplify_section(seg.start, seg.end, seg.start_edge, seg.end_edge, tol, pos)
    assert need == 0 and (pos == -1).all()  # the buffer is left as it was given
    return s, e


def _section(tris, z, device="perfactory-sxga"):
    job = slice_mesh(Mesh.from_triangles(tris), load_device(device), layer_height_mm=0.05)
    i = int(np.argmin(np.abs(job.plan.z_slice_mm - z)))
    return job.segments(i)[0]


@pytest.mark.parametrize("tol", [0.0, 1e-4, 5e-4, 2e-3])
def test_simplified_section_within_tolerance(tol):
    tris = np.concatenate([annulus_prism((1.0, 1.0), 0.3, 0.5, 0.0, 1.0, 720), annulus_prism((2.2, 1.0), 0.1, 0.35, 0.0, 1.0, 97), box_triangles((0.5, 0.2, 1.0), (0.2, 2.0, 0.0))])
    seg = _section(tris, 0.5)
    s, e = _simplify(seg, tol)
    assert 0 < len(s) <= len(seg)
    # vertices are joints of the section, bit for bit
    pts = {tuple(p) for p in np.concatenate([seg.start, seg.end])}
    assert all(tuple(p) in pts for p in np.concatenate([s, e]))
    # every joint of the section within tol of the simplified outline, and back
    simp = shapely.MultiLineString([[tuple(a), tuple(b)] for a, b in zip(s, e)])
    orig = shapely.MultiLineString([[tuple(a), tuple(b)] for a, b in zip(seg.start, seg.end)])
    d = shapely.distance(shapely.points(seg.start), simp)
    assert d.max() <= tol * (1 + 1e-9) + 1e-12
    assert shapely.hausdorff_distance(simp, orig, densify=0.05) <= tol * (1 + 1e-6) + 1e-12
    # closed: every end is some start (chains are kept whole)
    assert {tuple(p) for p in s} == {tuple(p) for p in e}
    # the enclosed area is the section's to within tol times the perimeter
    area = lambda a, b: 0.5 * np.sum(a[:, 0] * b[:, 1] - b[:, 0] * a[:, 1])  # noqa: E731
    per = np.hypot(*(seg.end - seg.start).T).sum()
    assert abs(area(s, e) - area(seg.start, seg.end)) <= tol * per + 1e-12
    if tol == 0.0:  # only the collinear halves of split quads merge
        assert len(s) < len(seg)
    else:
        assert len(s) < 0.5 * len(seg)


def test_simplify_keeps_unchained_segments():
    """Segments that do not chain (no edge, a shared start edge, a joint not bit-identical)
    are kept as they are."""
    start = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [5.0, 5.0], [6.0, 5.0]])
    end = np.array([[1.0, 0.0], [2.0, 0.0], [3.0, 0.0], [6.0, 5.0], [7.0, 5.0 + 1e-9]])
    se = np.array([0, 1, 2, 10, 11])
    ee = np.array([1, 2, 3, 11, -1])
    pos = np.full(20, -1, np.int32)
    s, e, _ = K.simplify_section(start, end, se, ee, 1e-3, pos)
    got = sorted(map(tuple, np.concatenate([s, e], axis=1)))
    assert got == [(0.0, 0.0, 3.0, 0.0), (5.0, 5.0, 7.0, 5.0 + 1e-9)]
    # two segments starting on edge 1: neither is chained to
    se2 = np.array([0, 1, 1, 10, 11])
    s, e, _ = K.simplify_section(start, end, se2, ee, 1e-3, pos)
    assert len(s) == 5 - 1  # only 3 -> 4 joins
    # a joint that is not bit-identical does not chain
    end2 = end.copy()
    end2[0, 0] = np.nextafter(1.0, 2.0)
    s, e, _ = K.simplify_section(start, end2, se, ee, 1e-3, pos)
    assert len(s) == 3
    assert (pos == -1).all()


@pytest.mark.parametrize("device_name", ["perfactory-sxga", "omnidot760"])
def test_widths_within_twice_the_resolution(device_name):
    dev = load_device(device_name)
    mesh = Mesh.from_triangles(feature_test_piece()[0])
    res = resolution_for(dev, None)
    kw = dict(layer_height_mm=0.6, min_wall_mm=0.13, min_gap_mm=0.13, islands=False)
    a = check_printability(mesh, dev, resolution_mm=0, **kw)
    b = check_printability(mesh, dev, **kw)
    assert b.settings["resolution_mm"] == res
    for key in ("thinnest_wall", "narrowest_gap"):
        assert abs(a.__dict__[key]["width_mm"] - b.__dict__[key]["width_mm"]) <= 2 * res + 1e-12
    # the same regions, each with its narrowest width within twice the resolution (the
    # regions may group differently: samples sit elsewhere along the simplified outline)
    def overlap(f, g):
        return f.bbox_mm[0] <= g.bbox_mm[2] and g.bbox_mm[0] <= f.bbox_mm[2] and f.bbox_mm[1] <= g.bbox_mm[3] and g.bbox_mm[1] <= f.bbox_mm[3]

    for x_rep, y_rep in ((a, b), (b, a)):
        for f in x_rep.findings:
            if f.kind not in ("thin_wall", "narrow_gap"):
                continue
            near = [g.width_mm for g in y_rep.findings if g.kind == f.kind and g.layer == f.layer and overlap(f, g)]
            assert near, f
            assert min(near) <= f.width_mm + 2 * res + 1e-12


def test_resolution_validated():
    dev = load_device("perfactory-sxga")
    assert resolution_for(dev, 0) == 0.0
    for bad in (-1e-6, float("nan"), float("inf"), 0.01, "x"):
        with pytest.raises(ConfigError, match="resolution"):
            resolution_for(dev, bad)


def test_small_loops_are_not_flattened():
    """A pin smaller than the resolution keeps an inside: its thin-wall findings are those of
    the section as sliced (a loop simplified to out-and-back would have none)."""
    from rotoprint.testing import extrude_polygon

    dev = load_device("perfactory-sxga")
    p = min(dev.pitch_x_mm, dev.pitch_y_mm)
    a = np.linspace(0, 2 * np.pi, 8, endpoint=False) + 0.1
    r = 0.45 * p / 2  # a 9 um octagonal pin
    tris = np.concatenate([box_triangles((0.5, 0.5, 1.0)), extrude_polygon(np.c_[1 + r * np.cos(a), 1 + r * np.sin(a)], 1.0)])
    mesh = Mesh.from_triangles(tris)
    want = check_printability(mesh, dev, layer_height_mm=0.1, resolution_mm=0.0, islands=False).counts()
    for res in (0.01 * p, 0.25 * p):
        got = check_printability(mesh, dev, layer_height_mm=0.1, resolution_mm=res, islands=False).counts()
        assert got["thin_wall"] == want["thin_wall"] > 0 and got["vanished_wall"] == want["vanished_wall"]
    # the kernel: the pin's loop keeps at least three chords and an inside
    seg = _section(tris, 0.5)
    s, e = _simplify(seg, 0.25 * p)
    pin = np.hypot(s[:, 0] - 1, s[:, 1] - 1) < 2 * r
    assert pin.sum() >= 3
    area = 0.5 * np.sum(s[pin, 0] * e[pin, 1] - e[pin, 0] * s[pin, 1])
    assert area > 0.05 * np.pi * r * r  # squashed within the tolerance, but not to nothing
