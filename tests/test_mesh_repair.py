"""Mesh repair: holes (closed loops of open edges) filled before slicing."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import Polygon

from rotoprint import load_device, load_mesh, slice_mesh
from rotoprint._holes import boundary_loops, ear_clip
from rotoprint.io.stl import write_binary_stl
from rotoprint.io.mesh import load_triangles
from rotoprint.mesh import Mesh
from rotoprint.testing import box_triangles, cylinder_mesh, uv_sphere_mesh

PERFACTORY = load_device("perfactory-sxga")


def _holed_box() -> tuple[np.ndarray, np.ndarray]:
    """A 3 x 2 x 1 mm box and the same box missing one triangle on each of two side faces."""
    tri = box_triangles((3.0, 2.0, 1.0), (-1.3, -0.7, 0.0))
    y_face = [i for i, t in enumerate(tri) if np.all(t[:, 1] == -0.7)]
    x_face = [i for i, t in enumerate(tri) if np.all(t[:, 0] == -1.3)]
    return tri, np.delete(tri, [y_face[0], x_face[0]], axis=0)


def _areas_mm2(mesh: Mesh, layer_height_mm: float) -> np.ndarray:
    job = slice_mesh(mesh, PERFACTORY, layer_height_mm=layer_height_mm)
    px = job.grid.pitch_x_mm * job.grid.pitch_y_mm
    return np.array([np.count_nonzero(layer.image) * px for layer in job])


# ------------------------------------------------------------------ acceptance cases
def test_box_missing_two_triangles_slices_to_the_full_box():
    full, holed = _holed_box()
    repaired = Mesh.from_triangles(holed)
    h = repaired.report.holes
    assert repaired.watertight and len(h.filled) == 2 and h.filled_edges == 6
    assert sorted(f.area_mm2 for f in h.filled) == pytest.approx([1.0, 1.5])  # half of a 2 x 1 and a 3 x 1 face
    assert all(f.planar and f.method == "ear-clipping" for f in h.filled)
    assert repaired.volume_mm3 == pytest.approx(6.0, abs=1e-12)
    pitch = slice_mesh(repaired, PERFACTORY, layer_height_mm=0.25).grid.pitch_x_mm
    got = _areas_mm2(repaired, 0.25)
    # within a one-pixel band around the exact 3 x 2 mm square, on every layer
    assert np.all(np.abs(got - 6.0) <= 10.0 * pitch), got
    plain = slice_mesh(Mesh.from_triangles(full), PERFACTORY, layer_height_mm=0.25)
    for a, b in zip(slice_mesh(repaired, PERFACTORY, layer_height_mm=0.25), plain):
        assert np.array_equal(a.image, b.image)
    # without the repair the holes are wider than the gap radius: the chords cut the square
    unrepaired = _areas_mm2(Mesh.from_triangles(holed, fill_holes=False), 0.25)
    # measured: 3.37, 4.12, 4.87 mm^2; the top layer (5.98) is within the gap radius of the hole's apex
    assert np.all(unrepaired[:3] < got[:3] - 1.0), unrepaired


def test_cylinder_with_a_cap_triangle_removed():
    full = cylinder_mesh(5.0, 3.0, 64)
    tri = full.triangles
    top = np.flatnonzero(np.all(tri[:, :, 2] == 3.0, axis=1))
    m = Mesh.from_triangles(np.delete(tri, top[5], axis=0))
    assert m.watertight and len(m.report.holes.filled) == 1 and m.report.holes.filled_edges == 3
    assert m.volume_mm3 == pytest.approx(full.volume_mm3, rel=1e-12)
    a, b = _areas_mm2(m, 1.0), _areas_mm2(full, 1.0)
    assert np.array_equal(a, b)


def _sphere_with_hole(radius=8.0):
    full = uv_sphere_mesh(radius, 24, 48)
    tri = full.triangles
    centre = radius * np.array([np.cos(0.4) * np.cos(0.3), np.cos(0.4) * np.sin(0.3), np.sin(0.4)])
    cut = np.linalg.norm(tri.mean(axis=1) - centre, axis=1) < 0.45 * radius  # a jagged, non-planar rim
    return full, tri[~cut], int(cut.sum())


def test_sphere_with_a_non_planar_hole_gets_its_volume_back():
    full, holed, n_cut = _sphere_with_hole()
    open_mesh = Mesh.from_triangles(holed, fill_holes=False)
    m = Mesh.from_triangles(holed)
    (hole,) = m.report.holes.filled
    assert n_cut > 20 and not hole.planar and hole.method == "ear-clipping"
    assert m.watertight and m.report.shells_flipped == 0
    # the fill spans the cap: the volume is the full sphere's less a thin cap
    assert abs(m.volume_mm3 - full.volume_mm3) < 0.02 * full.volume_mm3
    assert abs(open_mesh.volume_mm3 - full.volume_mm3) > abs(m.volume_mm3 - full.volume_mm3)


def test_inside_out_holed_box_is_filled_and_turned_outward():
    _, holed = _holed_box()
    m = Mesh.from_triangles(holed[:, ::-1])
    assert m.watertight and m.report.shells_flipped == 1 and m.volume_mm3 == pytest.approx(6.0, abs=1e-12)


# ------------------------------------------------------------------ what is not filled
def test_open_sheets_stay_open():
    quad = np.array([[[0, 0, 0], [1, 0, 0], [1, 1, 0]], [[0, 0, 0], [1, 1, 0], [0, 1, 0]]], float)
    ribbon = quad[:, :, [0, 2, 1]]  # the same sheet standing up
    for sheet in (quad, ribbon, quad[:1]):
        m = Mesh.from_triangles(sheet)
        assert m.faces.shape[0] == len(sheet) and not m.watertight
        assert m.report.holes.left_open_loops == 1 and not m.report.holes.filled


def test_pinched_boundary_splits_into_two_loops():
    # two boxes touching at one corner, each missing the two triangles at that corner's top face
    a = box_triangles((1.0, 1.0, 1.0), (0.0, 0.0, 0.0))
    b = box_triangles((1.0, 1.0, 1.0), (1.0, 1.0, 1.0))
    m = Mesh.from_triangles(np.concatenate([a, b]), fill_holes=False)
    assert m.watertight
    a_open = a[~np.all(a[:, :, 2] == 1.0, axis=1)]  # top face removed
    b_open = b[~np.all(b[:, :, 2] == 1.0, axis=1)]  # bottom face removed: rims touch at (1, 1, 1)
    m = Mesh.from_triangles(np.concatenate([a_open, b_open]), fill_holes=False)
    t = m.topology
    loops, stray = boundary_loops(m.faces, t.boundary_edge[t.face_edges])
    assert stray == 0 and sorted(len(x) for x in loops) == [4, 4]
    r = Mesh.from_triangles(np.concatenate([a_open, b_open]))
    assert r.watertight and r.volume_mm3 == pytest.approx(2.0, abs=1e-12)


# ------------------------------------------------------------------ ear clipping
def test_ear_clipping_of_a_concave_comb():
    xy = np.array([[0, 0], [5, 0], [5, 3], [4, 3], [4, 1], [3, 1], [3, 3], [2, 3], [2, 1], [1, 1], [1, 3], [0, 3]], float)
    tri = ear_clip(xy)
    assert tri.shape == (len(xy) - 2, 3)
    p = xy[tri]
    cross = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])
    assert np.all(cross > 0) and 0.5 * cross.sum() == pytest.approx(Polygon(xy).area)


@settings(max_examples=60, deadline=2000)
@given(seed=st.integers(0, 2**31), n=st.integers(3, 80))
def test_ear_clipping_tiles_random_simple_polygons(seed, n):
    rng = np.random.default_rng(seed)
    ang = np.sort(rng.uniform(0, 2 * np.pi, n))
    if len(np.unique(ang)) < n:
        return
    r = rng.uniform(0.2, 1.0, n)
    xy = np.stack([r * np.cos(ang), r * np.sin(ang)], axis=1)  # star-shaped, often very concave
    poly = Polygon(xy)
    if not poly.is_valid or poly.area < 1e-9 or not poly.exterior.is_ccw:
        return  # ear_clip takes simple counter-clockwise polygons (the origin may lie outside)
    tri = ear_clip(xy)
    assert tri is not None and tri.shape == (n - 2, 3)
    p = xy[tri]
    cross = (p[:, 1, 0] - p[:, 0, 0]) * (p[:, 2, 1] - p[:, 0, 1]) - (p[:, 1, 1] - p[:, 0, 1]) * (p[:, 2, 0] - p[:, 0, 0])
    assert np.all(cross >= 0)
    assert 0.5 * cross.sum() == pytest.approx(poly.area, rel=1e-9)


# ------------------------------------------------------------------ real meshes, reports
@pytest.mark.realmesh
@pytest.mark.parametrize("name", ["sphere_openscad.stl", "half_donut_ascii.stl"])
def test_closed_real_meshes_are_untouched(shared_meshes, name):
    a = load_mesh(shared_meshes / name)
    b = load_mesh(shared_meshes / name, fill_holes=False)
    assert not a.report.holes.filled and np.array_equal(a.faces, b.faces) and np.array_equal(a.vertices, b.vertices)


@pytest.mark.realmesh
@pytest.mark.parametrize(("name", "scale", "filled", "left"), [
    ("teapot_open.stl", 0.4, 5, 1),  # spout, handle ends, body rim filled; the lid (an open dome) is not
    ("featuretype_open.stl", 4.0, 16, 0),
    ("soup.stl", 15.0, 0, 100),  # 100 loose triangles: sheets, none filled
    ("octagonal_pocket_solid_header_binary.stl", 100.0, 0, 5),  # loose quads and a rim that folds over
])
def test_open_real_meshes_slice_as_before(shared_meshes, name, scale, filled, left):
    tri = load_triangles(shared_meshes / name) * scale
    a = Mesh.from_triangles(tri.copy())
    b = Mesh.from_triangles(tri.copy(), fill_holes=False)
    h = a.report.holes
    assert len(h.filled) == filled and h.left_open_loops == left
    lh = (a.bounds[1, 2] - a.bounds[0, 2]) / 5
    for la, lb in zip(slice_mesh(a, PERFACTORY, layer_height_mm=lh), slice_mesh(b, PERFACTORY, layer_height_mm=lh)):
        assert np.array_equal(la.image, lb.image), la.index


def test_info_and_manifest_report_the_holes(run_cli, tmp_path):
    _, holed = _holed_box()
    p = tmp_path / "holed.stl"
    write_binary_stl(p, holed)
    code, out, err = run_cli("info", p, "--json")
    assert code == 0, err
    h = json.loads(out)["holes"]
    assert h["filled"] == 2 and h["filled_edges"] == 6 and h["filled_area_mm2"] == pytest.approx(2.5, rel=1e-6)
    code, out, err = run_cli("slice", p, "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", tmp_path / "out")
    assert code == 0, err
    assert "2 hole(s) filled" in err
    man = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert man["mesh"]["holes"]["filled"] == 2 and man["options"]["fill_holes"] is True
    assert all(L["gaps"]["left_open"] == 0 and L["gaps"]["closed"] == 0 for L in man["layers"])
    code, out, err = run_cli("info", p, "--json", "--no-fill-holes")
    data = json.loads(out)
    assert code == 0 and not data["holes"]["enabled"] and data["open_edges"] == 6
