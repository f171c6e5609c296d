"""Exact area coverage: against shapely per pixel, jit against numpy, area sums on meshes."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
import shapely.affinity
from hypothesis import given, settings
from hypothesis import strategies as st

from rotoprint import load_device, load_mesh, slice_mesh
from rotoprint.errors import ConfigError, GeometryError
from rotoprint.masks import coverage_fraction, coverage_mask, segments_area_px
from rotoprint.testing import box_mesh, cylinder_mesh, torus_mesh, uv_sphere_mesh

from _dlp_helpers import nonzero_region, pixel_boxes_area, polygon_segments, winding_regions

BACKENDS = ["jit", "numpy"]


def star(n, cx, cy, r0, r1, seed):
    """A simple polygon, star-shaped about (cx, cy): one vertex per angular stratum (n >= 5
    keeps every gap below pi, so edges never cross)."""
    rng = np.random.default_rng(seed)
    t = (np.arange(n) + rng.uniform(0, 1, n)) / n * 2 * np.pi
    r = rng.uniform(r0, r1, n)
    return np.c_[cx + r * np.cos(t), cy + r * np.sin(t)]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("seed", range(6))
def test_per_pixel_exact_against_shapely(backend, seed):
    xy = star(9, 12.3, 10.7, 3.0, 9.0, seed)
    s, e = polygon_segments(xy if seed % 2 else xy[::-1])  # both windings
    got = coverage_fraction(s, e, (22, 25), backend=backend)
    want = pixel_boxes_area(shapely.Polygon(xy), (22, 25))
    np.testing.assert_allclose(got, want, atol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_clipped_by_the_image_edges(backend):
    xy = np.array([[-5.2, -3.1], [14.7, 2.2], [9.9, 13.4], [-2.0, 16.0]])
    s, e = polygon_segments(xy)
    got = coverage_fraction(s, e, (10, 12), backend=backend)
    want = pixel_boxes_area(shapely.Polygon(xy), (10, 12))
    np.testing.assert_allclose(got, want, atol=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_axis_aligned_and_degenerate_segments(backend):
    # edges exactly on pixel borders and through pixel centres, a zero-length and a horizontal segment
    xy = np.array([[0.5, 0.5], [4.5, 0.5], [4.5, 3.0], [2.0, 3.0], [2.0, 3.0], [0.5, 3.0]])
    s, e = polygon_segments(xy)
    got = coverage_fraction(s, e, (5, 6), backend=backend)
    want = pixel_boxes_area(shapely.Polygon(xy), (5, 6))
    np.testing.assert_allclose(got, want, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(st.integers(5, 40), st.integers(0, 10_000), st.floats(0.1, 6.0))
def test_jit_matches_numpy_and_area(n, seed, rmax):
    xy = star(n, 7.1, 6.3, 0.05, rmax, seed)
    s, e = polygon_segments(xy)
    a = coverage_fraction(s, e, (14, 15), backend="jit")
    b = coverage_fraction(s, e, (14, 15), backend="numpy")
    np.testing.assert_allclose(a, b, atol=1e-12)
    assert a.sum() == pytest.approx(abs(segments_area_px(s, e)), rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_overlapping_shells_clamped_within_bound(backend):
    """Two overlapping discs (winding 2 in the lens): exact except in pixels crossed by both
    boundaries inside the overlap, where the error is at most that pixel's overlap area."""
    t = np.linspace(0, 2 * np.pi, 200, endpoint=False)
    a = np.c_[20 + 10 * np.cos(t), 20 + 10 * np.sin(t)]
    b = np.c_[31 + 9 * np.cos(t), 22 + 9 * np.sin(t)]
    sa, ea = polygon_segments(a)
    sb, eb = polygon_segments(b)
    s, e = np.vstack([sa, sb]), np.vstack([ea, eb])
    got = coverage_fraction(s, e, (40, 45), backend=backend)
    region = nonzero_region(s, e)
    want = pixel_boxes_area(region, (40, 45))
    lens = pixel_boxes_area(shapely.Polygon(a).intersection(shapely.Polygon(b)), (40, 45))
    err = got - want
    assert np.all(err >= -1e-12)
    assert np.all(err <= lens + 1e-12)
    assert (np.abs(err) > 1e-9).sum() <= 12  # only where both boundaries cross inside the lens
    assert region.area == pytest.approx(shapely.Polygon(a).union(shapely.Polygon(b)).area, rel=1e-12)


def test_mask_rounds_and_validates():
    sq = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])
    s, e = polygon_segments(sq)
    m = coverage_mask(s, e, (3, 3))
    # exact levels 63.75 (corners) and 127.5 (edges): nearest rounding would give 64 and 128,
    # a grey sum of 1024 for an area of 4 pixels (1020); the carried rounding gives 1020
    assert m.dtype == np.uint8 and m.tolist() == [[64, 127, 64], [128, 255, 127], [64, 127, 64]]
    assert int(m.sum()) == 4 * 255
    np.testing.assert_array_equal(m, coverage_mask(s, e, (3, 3), backend="numpy"))
    with pytest.raises(GeometryError, match=r"\(S, 2\)"):
        coverage_fraction(s[:, :1], e, (3, 3))
    with pytest.raises(GeometryError, match="finite"):
        coverage_fraction(s * np.nan, e, (3, 3))
    with pytest.raises(ConfigError, match="backend must be one of jit, numpy"):
        coverage_fraction(s, e, (3, 3), backend="gpu")
    with pytest.raises(ConfigError, match="shape"):
        coverage_fraction(s, e, (0, 3))
    assert coverage_fraction(np.empty((0, 2)), np.empty((0, 2)), (2, 2)).sum() == 0


SMOOTH_SHAPES = {
    "sphere": lambda: uv_sphere_mesh(8.0, 48, 96),
    "cylinder": lambda: cylinder_mesh(9.0, 4.0, 256),
    "torus": lambda: torus_mesh(7.0, 2.5, 96, 48),
}


@pytest.mark.parametrize("name", ["sphere", "cylinder", "torus"])
def test_area_within_1e5_at_full_resolution(name):
    """Acceptance: grey sum x pixel area == exact section area within 1e-5 at 1400 x 1050,
    against the segments' own polygon area and against trimesh's section (shapely)."""
    import trimesh

    mesh = SMOOTH_SHAPES[name]()
    dev = load_device("perfactory-sxga")
    job = slice_mesh(mesh, dev, layer_height_mm=mesh.bounds[1][2] / 3.0 - 1e-3)
    assert job.grid.shape == (1050, 1400)
    px_area = job.grid.pitch_x_mm * job.grid.pitch_y_mm
    tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    worst = 0.0
    for i in range(len(job)):
        s, e, _ = job.pixel_segments(i)
        grey = coverage_mask(s, e, job.grid.shape)
        area = grey.sum(dtype=np.int64) / 255.0 * px_area
        exact_px = abs(segments_area_px(s, e)) * px_area
        sec = tm.section(plane_origin=[0, 0, job.plan.z_slice_mm[i]], plane_normal=[0, 0, 1])
        planar, _ = sec.to_2D()
        exact_tm = sum(p.area for p in planar.polygons_full)
        assert exact_px == pytest.approx(exact_tm, rel=1e-9)
        frac = coverage_fraction(s, e, job.grid.shape)
        exact_levels = frac.sum() * 255.0
        # hard bound: the carried rounding keeps the layer's grey sum within half a level of
        # the exact one, whatever the number of boundary pixels (nearest rounding: up to half
        # a level per boundary pixel)
        assert abs(int(grey.sum(dtype=np.int64)) - exact_levels) <= 0.5 + 1e-6
        assert np.abs(grey - 255.0 * frac).max() < 1.0  # each pixel within one level
        if exact_px > 1.0:  # sections of at least 1 mm^2 (a 16-pixel cap is not a shape)
            worst = max(worst, abs(area - exact_px) / exact_px)
    assert worst < 1e-5


REAL = {
    "sphere_openscad.stl": dict(scale=0.2),
    "half_donut_ascii.stl": dict(),
    "teapot_open.stl": dict(scale=0.3),
    "featuretype_open.stl": dict(),
    "octagonal_pocket_solid_header_binary.stl": dict(units="inch"),
}


@pytest.mark.realmesh
@pytest.mark.parametrize("name", sorted(REAL))
def test_real_meshes_exact_except_where_shells_overlap(shared_meshes, name):
    from rotoprint import make_transform

    opts = REAL[name]
    mesh = load_mesh(shared_meshes / name, units=opts.get("units", "mm"), transform=make_transform(scale=opts.get("scale", 1.0)))
    dev = load_device("perfactory-sxga")
    height = float(mesh.bounds[1][2] - mesh.bounds[0][2])
    job = slice_mesh(mesh, dev, layer_height_mm=height / 4)
    for i in range(len(job)):
        s, e, _ = job.pixel_segments(i)
        frac = coverage_fraction(s, e, job.grid.shape)
        region, multiple = winding_regions(s, e)
        tol = 1e-6 * max(region.area, 1.0)
        if multiple.is_empty:  # one shell at every point: exact
            assert abs(frac.sum() - region.area) <= tol
            continue
        # Overlapping shells (winding 2 or more): exact except in pixels that the overlap reaches,
        # where the error lies between 0 and the overlap's area in that pixel (as in
        # test_overlapping_shells_clamped_within_bound). Compared pixel by pixel in the window
        # of the segments.
        pts = np.vstack([s, e])
        c0, r0 = np.maximum(np.floor(pts.min(axis=0)).astype(int) - 1, 0)
        c1, r1 = np.minimum(np.ceil(pts.max(axis=0)).astype(int) + 2, [frac.shape[1], frac.shape[0]])
        outside = frac.copy()
        outside[r0:r1, c0:c1] = 0
        assert not outside.any()  # nothing outside the window
        want = pixel_boxes_area(shapely.affinity.translate(region, -c0, -r0), (r1 - r0, c1 - c0))
        lens = pixel_boxes_area(shapely.affinity.translate(multiple, -c0, -r0), (r1 - r0, c1 - c0))
        err = frac[r0:r1, c0:c1] - want
        assert np.all(err >= -1e-9) and np.all(err <= lens + 1e-9)
        assert np.abs(err[lens <= 1e-12]).sum() <= tol


@pytest.mark.parametrize(
    "dx,dy",
    [(0, 0), (-9, 0), (9, 0), (0, -8), (0, 8), (-30, 0), (30, 0), (0, 30), (-9, -8)],
)
def test_windowed_mask_equals_full_reference(dx, dy):
    """coverage_mask works in the segments' bounding window; it must equal the full-raster
    reference wherever the shape sits, including partly or wholly outside the image."""
    from rotoprint.masks import fraction_to_grey_summed

    xy = star(11, 10.0 + dx, 8.0 + dy, 2.0, 7.5, 3)
    s, e = polygon_segments(xy)
    got = coverage_mask(s, e, (16, 20))
    want = fraction_to_grey_summed(coverage_fraction(s, e, (16, 20), backend="numpy"))
    assert np.abs(got.astype(int) - want.astype(int)).max(initial=0) <= 1
    assert abs(int(got.sum()) - int(want.sum())) <= 2
