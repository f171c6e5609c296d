"""The cases where slicers break, one test each (docs/slicing.md states each rule)."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rotoprint import ConfigError, GeometryError, RasterTooLargeError, load_mesh, make_transform
from rotoprint.devices import Projector, ProjectorDevice, load_device
from rotoprint.mesh import Mesh
from rotoprint.slicing import plan_layers, slice_mesh
from rotoprint.slicing._fill import fill_numpy
from rotoprint.slicing._kernels import fill_jit
from rotoprint.testing import box_triangles, torus_mesh, uv_sphere_mesh

# 41 x 41 pixels of exactly 0.25 mm: pixel centres at (c - 20) * 0.25, all exact in binary.
QUARTER = ProjectorDevice(
    kind="projector", name="quarter", projector=Projector(pixels_x=41, pixels_y=41, width_mm=10.25, height_mm=10.25)
)


def image(tri_or_mesh, z=None, *, device=QUARTER, fill="nonzero", centre=False, **kw):
    mesh = tri_or_mesh if isinstance(tri_or_mesh, Mesh) else Mesh.from_triangles(np.asarray(tri_or_mesh, float))
    job = slice_mesh(mesh, device, layer_height_mm=1e3, fill=fill, centre=centre, **kw)
    if z is None:
        return job.layer(0).image, job
    img, _ = job.image_at(z)
    return img, job


def octahedron(r=2.0):
    v = np.array([[r, 0, 0], [0, r, 0], [-r, 0, 0], [0, -r, 0], [0, 0, r], [0, 0, -r]], float)
    f = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [1, 0, 5], [2, 1, 5], [3, 2, 5], [0, 3, 5]]
    return v[np.array(f)]


# ------------------------------------------------------------------ vertex / edge on the plane
def test_vertices_on_the_slice_plane_give_the_limit_from_below():
    img, job = image(octahedron(2.0), z=0.0)  # the four equator vertices lie in the plane
    # limit from below of the section: the equator square |x| + |y| < 2 (diamond)
    c = (np.arange(41) - 20) * 0.25
    X, Y = np.meshgrid(c, -c)
    inside = np.abs(X) + np.abs(Y) < 2 - 1e-9
    on = np.isclose(np.abs(X) + np.abs(Y), 2)
    assert np.array_equal((img > 0)[~on], inside[~on])


def test_box_sliced_exactly_at_its_faces():
    tri = box_triangles((2, 2, 1), (-1, -1, 0))
    top, _ = image(tri, z=1.0)  # top face in the plane: limit from below is the full square
    bottom, _ = image(tri, z=0.0)  # bottom face in the plane: nothing below it
    mid, _ = image(tri, z=0.5)
    assert np.array_equal(top, mid) and mid.any()
    assert not bottom.any()


# ------------------------------------------------------------------ vertex / edge on a fibre
def test_diamond_with_vertices_on_pixel_centres():
    # a square pyramid of a diamond, apex-free: prism whose corners sit on fibres and centres
    d = 2.0
    xy = np.array([[d, 0], [0, d], [-d, 0], [0, -d]])
    from rotoprint.testing import extrude_polygon

    img, _ = image(extrude_polygon(xy, 1.0), z=0.5)
    c = (np.arange(41) - 20) * 0.25
    X, Y = np.meshgrid(c, -c)
    s = np.abs(X) + np.abs(Y)
    filled = img > 0
    assert filled[s < d].all()  # strictly inside: filled
    assert not filled[s > d].any()  # strictly outside: empty, so no streak along a fibre
    for ev in ("nonzero", "evenodd"):
        other, _ = image(extrude_polygon(xy, 1.0), z=0.5, fill=ev)
        assert np.array_equal(other, img)


def test_box_edges_on_fibres_and_pixel_centres():
    img, _ = image(box_triangles((2.0, 1.5, 1), (-1.0, -0.5, 0)), z=0.5)
    c = (np.arange(41) - 20) * 0.25
    X, Y = np.meshgrid(c, -c)
    strict = (np.abs(X) < 1.0) & (Y > -0.5) & (Y < 1.0)
    closed = (np.abs(X) <= 1.0) & (Y >= -0.5) & (Y <= 1.0)
    filled = img > 0
    assert filled[strict].all() and not filled[~closed].any()
    # half-open: exactly one of the two boundary fibres / columns is taken on each axis
    assert filled.sum() == 8 * 6


# ------------------------------------------------------------------ coplanar faces, duplicates
def test_touching_boxes_union_without_seam():
    a = box_triangles((1.0, 2.0, 1), (-1.0, -1.0, 0))
    b = box_triangles((1.0, 2.0, 1), (0.0, -1.0, 0))  # shares the face x = 0 (on a pixel column)
    both, _ = image(np.concatenate([a, b]), z=0.5)
    one, _ = image(box_triangles((2.0, 2.0, 1), (-1.0, -1.0, 0)), z=0.5)
    assert np.array_equal(both, one)


def test_duplicate_shell_nonzero_fills_evenodd_cancels():
    a = box_triangles((2.0, 2.0, 1), (-1.0, -1.0, 0))
    dup = np.concatenate([a, a + [0, 0, 0]])
    nz, _ = image(dup, z=0.5)
    eo, _ = image(dup, z=0.5, fill="evenodd")
    single, _ = image(a, z=0.5)
    assert np.array_equal(nz, single)
    assert not eo.any()


def test_overlapping_shells_union_and_evenodd_xor():
    a = box_triangles((3.0, 2.0, 1), (-2.0, -1.0, 0))
    b = box_triangles((3.0, 2.0, 1), (-0.6, -0.4, 0))
    nz, _ = image(np.concatenate([a, b]), z=0.5)
    eo, _ = image(np.concatenate([a, b]), z=0.5, fill="evenodd")
    ia, _ = image(a, z=0.5)
    ib, _ = image(b, z=0.5)
    assert np.array_equal(nz > 0, (ia > 0) | (ib > 0))
    assert np.array_equal(eo > 0, (ia > 0) ^ (ib > 0))


# ------------------------------------------------------------------ zero-area triangles
def test_zero_area_triangles_change_nothing():
    tri = box_triangles((2.0, 2.0, 1), (-1.1, -0.9, 0))
    sliver = np.array([[[-1.1, -0.9, 0], [0.2, -0.9, 0.5], [1.5, -0.9, 1.0]]])  # collinear
    point = np.array([[[0.3, 0.3, 0.3]] * 3])
    with_deg, _ = image(np.concatenate([tri, sliver, point]), z=0.4)
    plain, _ = image(tri, z=0.4)
    assert np.array_equal(with_deg, plain)


# ------------------------------------------------------------------ flipped normals
def test_inside_out_and_partly_flipped_fill_like_the_box():
    tri = box_triangles((3.0, 2.0, 1), (-1.3, -0.7, 0))
    plain, _ = image(tri, z=0.5)
    inv, _ = image(tri[:, ::-1], z=0.5)
    part = tri.copy()
    part[[0, 5, 7]] = part[[0, 5, 7]][:, ::-1]
    partly, _ = image(part, z=0.5)
    assert plain.any() and np.array_equal(inv, plain) and np.array_equal(partly, plain)


def test_cavity_stays_empty():
    outer = box_triangles((4.0, 4.0, 1), (-2.0, -2.0, 0))
    inner = box_triangles((2.0, 2.0, 0.5), (-1.0, -1.0, 0.25))[:, ::-1]  # an enclosed void
    img, _ = image(np.concatenate([outer, inner]), z=0.5)
    assert img[20, 20] == 0 and img[20, 13] == 255


# ------------------------------------------------------------------ open meshes
def test_small_hole_is_closed_within_the_gap_radius():
    tri = box_triangles((3.0, 2.0, 1), (-1.3, -0.7, 0))
    side = [i for i, t in enumerate(tri) if np.allclose(t[:, 1], -0.7)]  # the y = -0.7 face
    holed = np.delete(tri, side[:1], axis=0)  # one triangle missing: a triangular hole
    # hole filling off: the per-layer chords are the last resort this test checks
    img, job = image(Mesh.from_triangles(holed, fill_holes=False), z=0.5, gap_radius_mm=5.0)
    plain, _ = image(tri, z=0.5)
    assert np.array_equal(img, plain)
    _, rep = job.segments_at(0.5)
    assert rep.closed == 1 and rep.left_open == 0 and rep.closed_max_mm == pytest.approx(1.5)  # the missing triangle is 1.5 mm wide at z = 0.5


def test_gap_wider_than_radius_is_closed_by_a_chord_and_reported():
    tri = box_triangles((3.0, 2.0, 1), (-1.3, -0.7, 0))
    side = [i for i, t in enumerate(tri) if np.allclose(t[:, 1], -0.7)]
    open_box = np.delete(tri, side, axis=0)  # a whole side face missing
    img, job = image(Mesh.from_triangles(open_box, fill_holes=False), z=0.5, gap_radius_mm=0.1)
    plain, _ = image(tri, z=0.5)
    assert np.array_equal(img, plain)
    _, rep = job.segments_at(0.5)
    assert rep.closed == 0 and rep.left_open == 1 and rep.left_open_max_mm == pytest.approx(3.0)


@pytest.mark.realmesh
@pytest.mark.parametrize("name", ["teapot_open.stl", "featuretype_open.stl", "soup.stl"])
def test_open_real_meshes_never_streak(shared_meshes, name):
    mesh = load_mesh(shared_meshes / name)
    dev = load_device("omnidot760") if name == "teapot_open.stl" else load_device("perfactory-sxga")
    scale = {"teapot_open.stl": 1.0, "featuretype_open.stl": 4.0, "soup.stl": 15.0}[name]
    mesh = mesh.transformed(make_transform(scale=scale))
    job = slice_mesh(mesh, dev, layer_height_mm=mesh.bounds[1, 2] / 12)
    for layer in job:
        img = layer.image > 0
        # a streak would reach the image border; the part is centred with a margin
        assert not (img[:, 0].any() or img[:, -1].any() or img[0].any() or img[-1].any()), layer.index


# ------------------------------------------------------------------ backends
@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**31), n=st.integers(3, 60), snap=st.booleans(), rule=st.sampled_from(["nonzero", "evenodd"]))
def test_jit_and_numpy_fill_are_identical(seed, n, snap, rule):
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-5, 45, (n, 2))
    if snap:  # vertices exactly on fibres and samples
        pts = np.round(pts)
    nxt = np.roll(pts, -1, axis=0)
    a = fill_numpy(pts[:, 0], pts[:, 1], nxt[:, 0], nxt[:, 1], 37, 41, rule)
    b = fill_jit(pts[:, 0], pts[:, 1], nxt[:, 0], nxt[:, 1], 37, 41, rule)
    assert np.array_equal(a, b)


@pytest.mark.parametrize("fibre", [None, 17.0])
def test_backends_identical_on_meshes(fibre):
    mesh = torus_mesh(4.0, 1.5, 40, 20).transformed(make_transform(rotate_deg=(20, 10, 0)))
    dev = load_device("perfactory-sxga")
    a = slice_mesh(mesh, dev, layer_height_mm=0.5, backend="numpy", fibre_angle_deg=fibre)
    b = slice_mesh(mesh, dev, layer_height_mm=0.5, backend="jit", fibre_angle_deg=fibre)
    for la, lb in zip(a, b, strict=True):
        assert np.array_equal(la.image, lb.image)


# ------------------------------------------------------------------ plan, placement, limits
def test_layer_plan_mid_heights_and_last_layer():
    p = plan_layers(1.0, 2.0, 0.3)
    np.testing.assert_allclose(p.z_bottom_mm, [1.0, 1.3, 1.6, 1.9])
    np.testing.assert_allclose(p.z_top_mm, [1.3, 1.6, 1.9, 2.0])
    np.testing.assert_allclose(p.z_slice_mm, [1.15, 1.45, 1.75, 1.95])
    assert len(plan_layers(0.0, 1.0, 0.25)) == 4
    with pytest.raises(ConfigError):
        plan_layers(0.0, 1.0, 0.0)


def test_images_are_born_at_device_pitch_and_centred():
    dev = load_device("perfactory-sxga")
    job = slice_mesh(Mesh.from_triangles(box_triangles((5, 3, 1), (10, 20, 0))), dev, layer_height_mm=0.5)
    assert job.grid.shape == (1050, 1400)
    img = job.layer(0).image > 0
    rows, cols = np.nonzero(img)
    # centred on the field: the filled block's centre is the image centre within a pixel
    assert abs(cols.mean() - 699.5) <= 1 and abs(rows.mean() - 524.5) <= 1
    assert cols.max() - cols.min() + 1 == pytest.approx(5 / dev.pitch_x_mm, abs=1)


def test_offset_places_the_part():
    dev = load_device("perfactory-sxga")
    job = slice_mesh(Mesh.from_triangles(box_triangles((2, 2, 1))), dev, layer_height_mm=0.5, offset_mm=(5.0, -3.0))
    rows, cols = np.nonzero(job.layer(0).image)
    m = job.grid.pixel_to_platform
    x = m[0, 0] * cols.mean() + m[0, 2]
    y = m[1, 1] * rows.mean() + m[1, 2]
    assert x == pytest.approx(5.0, abs=dev.pitch_x_mm) and y == pytest.approx(-3.0, abs=dev.pitch_y_mm)


def test_part_larger_than_the_field_is_refused():
    with pytest.raises(GeometryError, match="does not fit the device field"):
        slice_mesh(Mesh.from_triangles(box_triangles((30, 5, 1))), load_device("perfactory-sxga"), layer_height_mm=0.5)


def test_raster_too_large_is_refused_before_allocating():
    with pytest.raises(RasterTooLargeError, match="would need"):
        slice_mesh(Mesh.from_triangles(box_triangles((200_000, 200_000, 1))), load_device("omnidot760"), layer_height_mm=0.5)


def test_lazy_layers_memory_does_not_grow_with_layer_count():
    mesh = uv_sphere_mesh(9.0, 24, 48)
    job = slice_mesh(mesh, load_device("perfactory-sxga"), layer_height_mm=0.1)
    assert len(job) == 180
    img_bytes = 1400 * 1050
    tracemalloc.start()
    n = 0
    for layer in job:
        n += int(layer.image[525, 700] > 0)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert n > 100
    assert peak < 12 * img_bytes  # a few working arrays, not 180 images


def test_fibre_angle_rotates_the_part_on_the_grid():
    mesh = Mesh.from_triangles(box_triangles((8, 2, 1), (-4, -1, 0)))
    dev = load_device("perfactory-sxga")
    a = slice_mesh(mesh, dev, layer_height_mm=0.5).layer(0).image > 0
    b = slice_mesh(mesh, dev, layer_height_mm=0.5, fibre_angle_deg=90.0).layer(0).image > 0
    ra, ca = np.nonzero(a)
    rb, cb = np.nonzero(b)
    assert (np.ptp(ca) > 3 * np.ptp(ra)) and (np.ptp(rb) > 3 * np.ptp(cb))  # long along x, then along y
    assert abs(a.sum() - b.sum()) < 0.02 * a.sum()


@pytest.mark.parametrize("name", ["torus", "sphere", "open-box"])
def test_section_kernel_matches_numpy_reference_bit_for_bit(name):
    from rotoprint.slicing._sections import FaceSweep, section, section_numpy

    mesh = {
        "torus": torus_mesh(4.0, 1.5, 40, 20).transformed(make_transform(rotate_deg=(20, 10, 0))),
        "sphere": uv_sphere_mesh(3.0, 20, 40),
        "open-box": Mesh.from_triangles(box_triangles((2, 3, 4))[2:], fill_holes=False),
    }[name]
    sweep = FaceSweep(mesh)
    lo, hi = mesh.bounds[:, 2]
    for z in np.linspace(lo, hi, 23):  # includes the planes through the lowest and highest vertices
        faces = sweep.faces_at(z)
        a, b = section(mesh, faces, z), section_numpy(mesh, faces, z)
        for f in ("start", "end", "start_edge", "end_edge"):
            assert np.array_equal(getattr(a, f), getattr(b, f)), (z, f)
