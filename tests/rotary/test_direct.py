"""Direct rotary slicing (issue 4): exactness against shapely, agreement with the two-step path,
kernels equal, swathes shared with the transforms, density equalisation, the CLI."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
import shapely
from shapely.geometry import Point, box

from _direct_checks import compare_sites, iou_pair, section_geom, shapely_mismatches, two_step
from rotoprint import ConfigError, GeometryError, load_device, load_mesh
from rotoprint.rotary import exact_maps, place_drops, plan_swathes
from rotoprint.rotary import _direct_kernels as K
from rotoprint.rotary.direct import PartPlacement, slice_rotary
from rotoprint.testing import box_mesh, cylinder_mesh, torus_mesh

DEV = load_device("omnidot760")
HEAD = DEV.head

MESHES = {
    "box": lambda: box_mesh((20.0, 12.0, 2.0), origin=(3.0, -4.0, 0.0)),
    "cylinder": lambda: cylinder_mesh(8.0, 2.0, 96),
    "torus": lambda: torus_mesh(10.0, 3.0, 96, 32),
}


def _job(mesh, tilt, **kw):
    kw.setdefault("inner_radius_mm", 40.0)
    kw.setdefault("angle_deg", 15.0)
    return slice_rotary(mesh, DEV, layer_height_mm=kw.pop("layer_height_mm", 1.0), tilt_deg=tilt, **kw)


def _real(shared_meshes, name, scale=1.0):
    from rotoprint.io.mesh import make_transform

    return load_mesh(shared_meshes / name, transform=make_transform(scale=scale))


# ---------------------------------------------------------------------------------- exactness


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("tilt", [0.0, 20.0])
def test_drop_fired_exactly_when_inside_the_exact_section(name, tilt):
    job = _job(MESHES[name](), tilt)
    for L in sorted({0, len(job) // 2, len(job) - 1}):
        pr = job.layer(L)
        checked, bad, worst = shapely_mismatches(job, pr, section_geom(job, L), n_random=20000, seed=L)
        assert checked >= 20000 // len(job.tracks) * len(job.tracks)
        assert bad == 0 or worst <= 1e-6, (bad, worst)


@pytest.mark.parametrize("tilt", [0.0, 20.0])
def test_real_closed_meshes_exact(shared_meshes, tilt):
    # half_donut at full size; the 100 mm sphere (3-4 swathes) on two layers
    job = _job(_real(shared_meshes, "half_donut_ascii.stl"), tilt, layer_height_mm=0.5, inner_radius_mm=30.0)
    for L in range(len(job)):
        checked, bad, worst = shapely_mismatches(job, job.layer(L), section_geom(job, L), n_random=10000, seed=L)
        assert bad == 0 or worst <= 1e-6
    job = _job(_real(shared_meshes, "sphere_openscad.stl"), tilt, layer_height_mm=20.0, inner_radius_mm=30.0)
    assert len(job.tracks) >= 2
    for L in (0, len(job) // 2):
        checked, bad, worst = shapely_mismatches(job, job.layer(L), section_geom(job, L), n_random=40000, seed=L)
        assert bad == 0 or worst <= 1e-6


@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.parametrize("angle", [0.0, 200.0, -75.0])
def test_direction_and_angle_every_site(direction, angle):
    mesh = torus_mesh(4.0, 1.5, 48, 24)
    job = _job(mesh, 33.0, direction=direction, angle_deg=angle, inner_radius_mm=25.0, layer_height_mm=1.5)
    pr = job.layer(1)
    checked, bad, worst = shapely_mismatches(job, pr, section_geom(job, 1))
    assert checked > 50_000 and (bad == 0 or worst <= 1e-6)
    # the simulator lands every drop where the direct slicer meant it (same forward formula)
    d = place_drops(pr)
    X, Y = job.part.platform_to_model(d.x_mm, d.y_mm)
    g = section_geom(job, 1)
    inside = shapely.contains_xy(g, X, Y)
    far = shapely.distance(g.boundary, shapely.points(X, Y)) > 1e-6
    assert inside[far].all() and len(d) > 1000  # fired => inside
    # inside => fired: every lattice site (geometry checked against nozzle_layout) inside the
    # section, away from its boundary, has a simulated drop on it
    from scipy.spatial import cKDTree

    from _direct_checks import lattice

    tree = cKDTree(np.c_[X, Y])
    n_inside = 0
    for ts in job.tracks:
        LX, LY = lattice(job, ts)
        LX, LY = LX.ravel(), LY.ravel()
        keep = shapely.contains_xy(g, LX, LY)
        keep[keep] = shapely.distance(g.boundary, shapely.points(LX[keep], LY[keep])) > 1e-6
        dist, _ = tree.query(np.c_[LX[keep], LY[keep]])
        assert dist.max(initial=0.0) < 1e-9
        n_inside += int(keep.sum())
    assert n_inside == int(far.sum())  # and no two sites share a drop


def test_vertices_on_tracks_and_firing_angles():
    """A polygon whose vertices lie on track radii at firing angles: kernels agree, fill is
    the exact set up to boundary ties, and every tie follows the documented rule."""
    job = _job(box_mesh((12.0, 6.0, 1.0)), 0.0, inner_radius_mm=50.0, angle_deg=0.0)
    ts = job.tracks[0]
    rng = np.random.default_rng(3)
    m = rng.choice(ts.r_mm.size - 20, 40, replace=False) + 10
    i = rng.integers(ts.first_firing + 5, ts.first_firing + ts.firings - 5, 40)
    ang = ts.psi0_rad[m] - i * ts.dphi_rad
    order = np.argsort(ang)
    # a star-shaped loop around its centroid, vertices exactly on tracks and drop angles
    x = ts.r_mm[m] * np.cos(ang)
    y = ts.r_mm[m] * np.sin(ang)
    c = np.array([x.mean(), y.mean()])
    order = np.argsort(np.arctan2(y - c[1], x - c[0]))
    x, y = x[order], y[order]
    args = (x, y, np.roll(x, -1), np.roll(y, -1), ts.r_mm * ts.r_mm, ts.psi0_rad, ts.nozzle, np.ones(ts.r_mm.size), np.zeros(ts.r_mm.size))
    kw = dict(dphi=ts.dphi_rad, direction=1, i0=ts.first_firing, n_f=ts.firings, n_cols=HEAD.nozzles, fill="nonzero", level=1)
    a = K.direct_fill_jit(*args, **kw)
    b = K.direct_fill_numpy(*args, **kw)
    np.testing.assert_array_equal(a, b)
    poly = shapely.Polygon(np.column_stack([x, y]))
    bb = np.arange(ts.firings)[:, None] + ts.first_firing
    A = ts.psi0_rad[None, :] - bb * ts.dphi_rad
    px, py = ts.r_mm[None, :] * np.cos(A), ts.r_mm[None, :] * np.sin(A)
    inside = shapely.contains_xy(poly, px, py)
    fired = a[:, ts.nozzle] > 0
    bad = inside != fired
    if bad.any():
        assert shapely.distance(poly.boundary, shapely.points(px[bad], py[bad])).max() <= 1e-9
    assert fired.sum() > 1000


# ------------------------------------------------------------------------------ kernels equal


@pytest.mark.parametrize("tilt,fill,direction,equalise", [(0.0, "nonzero", 1, False), (20.0, "evenodd", -1, True), (47.0, "nonzero", 1, True)])
def test_numba_and_numpy_kernels_identical(tilt, fill, direction, equalise):
    mesh = torus_mesh(9.0, 3.0, 80, 30)
    kw = dict(fill=fill, direction=direction, equalise=equalise, inner_radius_mm=35.0, angle_deg=-40.0)
    a = _job(mesh, tilt, **kw)
    b = _job(mesh, tilt, backend="numpy", **kw)
    for L in range(len(a)):
        for sa, sb in zip(a.layer(L).swathes, b.layer(L).swathes):
            np.testing.assert_array_equal(sa.levels, sb.levels)
            assert sa.first_firing == sb.first_firing


def test_kernels_identical_on_random_polygons():
    rng = np.random.default_rng(11)
    r = np.sort(rng.uniform(30, 40, 200))
    psi0 = rng.uniform(-0.05, 0.05, 200)
    cols = rng.permutation(764)[:200]
    for trial in range(20):
        n = rng.integers(3, 60)
        x = rng.uniform(29, 41, n)
        y = rng.uniform(-5, 5, n)
        if trial % 2:  # some vertices exactly on a track radius (as nearly as floats allow)
            k = rng.integers(0, 200, n // 2)
            t = np.arctan2(y[: n // 2], x[: n // 2])
            x[: n // 2], y[: n // 2] = r[k] * np.cos(t), r[k] * np.sin(t)
        args = (x, y, np.roll(x, -1), np.roll(y, -1), r * r, psi0, cols, rng.uniform(0.2, 1.0, 200), rng.uniform(0, 1, 200))
        kw = dict(dphi=0.002, direction=int(rng.choice([1, -1])), i0=-150, n_f=300, n_cols=764, fill=["nonzero", "evenodd"][trial % 2], level=1)
        np.testing.assert_array_equal(K.direct_fill_jit(*args, **kw), K.direct_fill_numpy(*args, **kw))


def test_kernels_identical_with_whole_thinned_and_shared_columns():
    """The jit fill's row sweep (tracks kept whole, thinned tracks by thin_print's rule, shares of
    0) against the numpy reference, also when two tracks write one image column (one whole and one
    thinned; two thinned, which sends the thinned tracks to the tiled column writes)."""
    rng = np.random.default_rng(23)
    n_tr = 160
    r = np.sort(rng.uniform(30, 40, n_tr))
    psi0 = rng.uniform(-0.05, 0.05, n_tr)
    frac = rng.choice([1.0, 0.0, 0.3, 0.55, 0.9, 1.0 / 3.0], n_tr)
    base = rng.permutation(300)[:n_tr]
    whole, thin = np.flatnonzero(frac >= 1.0), np.flatnonzero((frac > 0.0) & (frac < 1.0))
    shared_whole = base.copy()
    shared_whole[thin[0]] = base[whole[0]]  # a whole and a thinned track in one column
    shared_thin = shared_whole.copy()
    other = thin[2:][np.flatnonzero(frac[thin[2:]] != frac[thin[1]])[0]]
    shared_thin[thin[1]] = base[other]  # two thinned tracks (different shares) in one column
    n_kept = []
    for trial, cols in enumerate([base, shared_whole, shared_thin] * 4):
        if trial < 3:  # a box over every track first: both tracks of a shared column inside on the same firings
            x, y = np.array([29.0, 41.0, 41.0, 29.0]), np.array([-5.0, -5.0, 5.0, 5.0])
        else:
            n = rng.integers(3, 40)
            x = rng.uniform(29, 41, n)
            y = rng.uniform(-5, 5, n)
        args = (x, y, np.roll(x, -1), np.roll(y, -1), r * r, psi0, cols, frac, rng.uniform(0, 1, n_tr))
        direction = int(rng.choice([1, -1]))
        kw = dict(dphi=0.002, direction=direction, i0=-100 if trial < 3 else int(rng.integers(-200, 50)), n_f=400, n_cols=300,
                  fill=["nonzero", "evenodd"][trial % 2], level=3)
        a = K.direct_fill_jit(*args, **kw)
        np.testing.assert_array_equal(a, K.direct_fill_numpy(*args, **kw))
        n_kept.append(int((a > 0).sum()))
    assert min(n_kept[:3]) > 0 and sum(n_kept) > 5000


# ---------------------------------------------------------------------- two-step and swathes


@pytest.mark.parametrize("name", sorted(MESHES))
@pytest.mark.parametrize("tilt", [0.0, 20.0])
def test_agrees_with_two_step_except_at_the_boundary(name, tilt):
    job = _job(MESHES[name](), tilt)
    L = len(job) // 2
    pr = job.layer(L)
    g = section_geom(job, L)
    fine, _, _ = two_step(job, L, oversample=4)
    native, _, _ = two_step(job, L, oversample=1)
    n4, worst4 = compare_sites(job, pr, fine, g)
    n1, worst1 = compare_sites(job, pr, native, g)
    assert worst4 <= 1.0 and worst1 <= 1.0  # in units of max(firing step, track pitch)
    assert n4 < n1
    iou_d, iou_1, iou_4 = iou_pair(job, [pr, native, fine], g, oversample=2)
    assert iou_d >= iou_1  # at equal output resolution the direct path is better
    assert iou_d >= iou_4 - 2e-3  # and level with a 4x finer bitmap (noise of the cell model)


def test_swathes_are_the_shared_planner(shared_meshes):
    """A part wider than the projected swathe: the direct slicer's swathes, pivots, bands and
    clocks are those of plan_swathes / the exact transform for the same footprint."""
    job = _job(_real(shared_meshes, "sphere_openscad.stl"), 20.0, layer_height_mm=25.0, inner_radius_mm=30.0)
    r_in, r_out = job.design.radial_range_mm()
    plan = plan_swathes(HEAD, tilt_deg=20.0, inner_radius_mm=r_in, outer_radius_mm=r_out)
    maps = exact_maps(HEAD, job.design, tilt_deg=20.0)
    assert len(job.tracks) == len(plan) == len(maps.swathes) >= 3
    for ts, sw, sm in zip(job.tracks, plan.swathes, maps.swathes):
        assert ts.pivot_radius_mm == sw.pivot_radius_mm and ts.band_mm == sw.band_mm
        assert ts.dphi_rad == sm.dphi_rad and np.array_equal(ts.enabled, sm.enabled)
        assert ts.first_firing <= sm.first_firing and ts.first_firing + ts.firings >= sm.first_firing + sm.index.shape[0]


# ------------------------------------------------------------------------------ equalisation


def _density_per_bin(job, pr, geom_platform, n_bins):
    """Drops per mm2 in annuli whose edges lie midway between tracks (interior of the part)."""
    d = place_drops(pr)
    rho = np.hypot(d.x_mm, d.y_mm)
    radii = np.sort(np.concatenate([t.r_mm for t in job.tracks]))
    lo, hi = job.part.inner_radius_mm + 1.0, job.part.inner_radius_mm + job.part.width_mm - 1.0
    targets = np.linspace(lo, hi, n_bins + 1)
    q = np.searchsorted(radii, targets)
    edges = 0.5 * (radii[q - 1] + radii[q])
    out = []
    for a, b in zip(edges[:-1], edges[1:]):
        ring = Point(0, 0).buffer(b, quad_segs=2048).difference(Point(0, 0).buffer(a, quad_segs=2048))
        area = ring.intersection(geom_platform).area
        out.append(((rho >= a) & (rho < b)).sum() / area)
    return np.array(out)


@pytest.mark.parametrize("tilt", [0.0, 20.0])
def test_equalisation_uniform_over_3_to_1(tilt):
    mesh = box_mesh((40.0, 10.0, 0.5))  # radii 20 .. 60 mm
    res = {}
    for eq in (False, True):
        job = _job(mesh, tilt, inner_radius_mm=20.0, angle_deg=0.0, layer_height_mm=0.5, equalise=eq)
        pr = job.layer(0)
        x0, y0 = job.part.model_to_platform(np.array([0.0, 40.0]), np.array([0.0, 10.0]))
        geom = box(x0[0], y0[0], x0[1], y0[1])
        dens = _density_per_bin(job, pr, geom, 8)
        res[eq] = dens.max() / dens.min() - 1.0
        assert job.density_spread(equalised=eq) >= res[eq] - 0.01  # the manifest's figure is over every track
    print(f"tilt {tilt}: density spread without {res[False]:.4f}, with {res[True]:.4f}")
    assert res[False] > 1.0  # inner tracks much denser without
    assert res[True] <= 0.05, res


# ------------------------------------------------------------------------------------ the CLI


def test_cli_rotary_then_simulate(run_cli, tmp_path, shared_meshes):
    out = tmp_path / "layers"
    code, _, err = run_cli("slice", shared_meshes / "half_donut_ascii.stl", "--device", "omnidot760", "--rotary", "--tilt", "20",
                           "--radius", "40", "--angle", "30", "--layer-height", "0.5", "--out", out, "--reference-images", "-q")
    assert code == 0, err
    man = json.loads((out / "manifest.json").read_text())
    assert man["format"] == "rotoprint-rotary-slice" and man["tilt_deg"] == 20.0
    assert man["placement"]["inner_radius_mm"] == 40.0 and man["placement"]["angle_deg"] == 30.0
    L = man["layers"][2]
    img = L["images"][0]
    assert {"head", "swathe", "file", "first_firing_index", "angle_per_firing_deg", "pivot_radius_mm", "sha256"} <= set(img)
    assert (out / img["file"]).exists() and (out / L["sidecar"]).exists()
    side = json.loads((out / L["sidecar"]).read_text())
    assert side["format"] == "rotoprint-rotary-print" and side["method"] == "direct"
    code, stdout, err = run_cli("simulate", out / img["file"], "--out", tmp_path / "ov.png", "--json")
    assert code == 0, err
    rep = json.loads(stdout)
    assert rep["method"] == "direct" and rep["drops"] == img["drops"] > 50 and rep["mean_error_px"] < 0.75


def test_cli_several_swathes_and_equalise(run_cli, tmp_path):
    mesh_path = tmp_path / "wide.stl"
    from rotoprint.testing import box_triangles

    _write_stl(mesh_path, box_triangles((60.0, 8.0, 0.4)))
    out = tmp_path / "o"
    code, _, err = run_cli("slice", mesh_path, "--device", "omnidot760", "--rotary", "--tilt", "0", "--radius", "30",
                           "--layer-height", "0.2", "--out", out, "--equalise")
    assert code == 0, err
    man = json.loads((out / "manifest.json").read_text())
    assert len(man["swathes"]) == 2 and man["equalise"] is True
    assert [i["file"] for i in man["layers"][0]["images"]] == ["layer_00000-s1.png", "layer_00000-s2.png"]
    assert man["density_spread"]["with_equalisation"] < 0.05 < man["density_spread"]["without_equalisation"]
    assert "spread" in err


def _write_stl(path, tri):
    import struct

    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + struct.pack("<I", len(tri)))
        for t in tri:
            fh.write(struct.pack("<12fH", 0, 0, 0, *t.ravel().tolist(), 0))


@pytest.mark.parametrize(
    "extra,pattern",
    [
        (["--rotary", "--radius", "40"], "--tilt"),
        (["--tilt", "20"], "need --rotary"),
        (["--rotary", "--tilt", "86", "--radius", "40"], "maximum tilt"),
        (["--rotary", "--tilt", "0", "--radius", "-3"], "radius"),
        (["--rotary", "--tilt", "0", "--radius", "40", "--max-swathes", "0"], "max-swathes"),
        (["--rotary", "--tilt", "0", "--radius", "40", "--device", "perfactory-sxga"], "projector"),
    ],
)
def test_cli_bad_input_one_line_exit_2_nothing_written(run_cli, tmp_path, shared_meshes, extra, pattern):
    out = tmp_path / "o"
    dev = [] if "--device" in extra else ["--device", "omnidot760"]
    code, _, err = run_cli("slice", shared_meshes / "half_donut_ascii.stl", *dev, "--layer-height", "0.5", "--out", out, *extra)
    assert code == 2
    assert pattern in err and len(err.strip().splitlines()) == 1
    assert not out.exists() and not list(tmp_path.iterdir())


def test_part_placement_round_trip_and_validation():
    pl = PartPlacement(50.0, 33.0, (-3.0, 1.0, 7.0, 5.0))
    X, Y = np.array([-3.0, 7.0, 2.0]), np.array([3.0, 5.0, 1.0])
    x, y = pl.model_to_platform(X, Y)
    assert math.hypot(x[0], y[0]) == pytest.approx(50.0) and math.degrees(math.atan2(y[0], x[0])) == pytest.approx(33.0)
    np.testing.assert_allclose(np.column_stack(pl.platform_to_model(x, y)), np.column_stack([X, Y]), atol=1e-12)
    d = pl.design_placement(0.07, 0.07)
    np.testing.assert_allclose(d.to_platform(np.array([0.0]), np.array([d.height_px / 2.0])), pl.model_to_platform(np.array([-3.0]), np.array([3.0])))
    with pytest.raises(GeometryError):
        PartPlacement(0.0, 0.0, (0, 0, 1, 1))
    with pytest.raises(ConfigError):
        slice_rotary(box_mesh(), load_device("perfactory-sxga"), layer_height_mm=0.5, tilt_deg=0.0, inner_radius_mm=40.0)
    with pytest.raises(ConfigError):
        slice_rotary(box_mesh(), DEV, layer_height_mm=0.5, tilt_deg=0.0, inner_radius_mm=40.0, backend="cuda")


def test_one_floor_kept_test_is_kept_jit():
    """The row sweep's thinned test ``floor((i + 1) f + o) > i f + o`` (one floor) is kept_jit's
    ``floor((i + 1) f + o) > floor(i f + o)`` bit for bit: k > floor(a) exactly when k > a for an
    integer k; here on exact integer hits (f = 1/2, 1/4, o = 0) and on random shares, phases and
    firings (negative ones too)."""
    from rotoprint.rotary._thin_kernels import kept_numpy

    rng = np.random.default_rng(5)
    i = np.concatenate([np.arange(-300, 300), rng.integers(-10**6, 10**6, 20000)]).astype(np.float64)
    f = np.concatenate([np.full(600, 0.5), rng.uniform(0.0, 1.0, 20000)])
    o = np.concatenate([np.zeros(300), np.full(300, 0.25), rng.uniform(0.0, 1.0, 20000)])
    for ff in (f, np.full_like(f, 0.25), np.full_like(f, 1.0 / 3.0)):
        one = np.floor((i + 1.0) * ff + o) > i * ff + o
        np.testing.assert_array_equal(one, kept_numpy(i, ff, o))


def _fixed_columns(f, o):
    n = f.size
    F, P, H = np.zeros(n, np.uint32), np.full(n, 0x80000000, np.uint32), np.zeros(n, np.uint32)
    for c in range(n):
        if 0.0 < f[c] < 1.0:
            F[c], P[c], H[c] = K._fixed_track(f[c], o[c])
    return F, P, H


@pytest.mark.parametrize("first", [-5000, 0, 123457, K.FIXED_MAX_FIRING - 3000, -K.FIXED_MAX_FIRING + 1])
def test_fixed_point_rows_are_the_float_rule(first):
    """The thinned rows decided in 32-bit fixed point give the float64 rule's bytes, on exact hits
    (dyadic and thirds shares, phases 0 and 1/2: the rule's floors land on integers), shares next to
    0 and 1, phases next to 1, random ones, columns of no thinned track and a whole track's state,
    for firings up to the fixed rows' limit (either sign); the float fallback is used there."""
    rng = np.random.default_rng(first & 0xFFFF)
    special_f = [0.5, 0.25, 0.75, 1.0 / 3.0, 2.0 / 3.0, 0.1, 2.0 ** -40, 1.0 - 2.0 ** -40, 1.0 - 2.0 ** -20, 0.6180339887498949]
    special_o = [0.0, 0.5, 0.25, 1.0 / 3.0, 1.0 - 2.0 ** -53, 2.0 ** -40]
    n_c = 700
    f = np.concatenate([rng.choice(special_f, 300), rng.uniform(0.0, 1.0, 400)])
    o = np.concatenate([rng.choice(special_o, 300), rng.uniform(0.0, 1.0, 400)])
    off = rng.random(n_c) < 0.1  # columns without a thinned track
    f[off], o[off] = 0.0, 0.0
    state = np.where(rng.random(n_c) < 0.2, 3, 0).astype(np.uint8)
    F, P, H = _fixed_columns(f, o)
    n_r = 2000
    a = np.full((n_r, n_c), 77, np.uint8)
    b = np.full((n_r, n_c), 77, np.uint8)
    K._thin_rows(a, 0, n_r, first, 0, n_c, f, o, state, np.uint8(3))
    K._thin_rows_fixed(b, 0, n_r, first, 0, n_c, f, o, F, P, H, state, np.uint8(3))
    np.testing.assert_array_equal(b, a)
    # the pattern's counts: exactly f of the firings over the run, within one, on the columns without a whole track
    free = state == 0
    assert np.all(np.abs((a[:, free] > 0).sum(axis=0) - f[free] * n_r) <= 1.0 + 1e-9)
    # a sub-range of columns and rows writes only there
    c = np.full((n_r, n_c), 77, np.uint8)
    K._thin_rows_fixed(c, 10, 400, first, 50, 650, f, o, F, P, H, state, np.uint8(3))
    np.testing.assert_array_equal(c[10:400, 50:650], a[10:400, 50:650])
    assert (c[:10] == 77).all() and (c[400:] == 77).all() and (c[:, :50] == 77).all() and (c[:, 650:] == 77).all()


def test_fixed_point_rows_on_near_integer_floors():
    """Phases set so that a row's ``i f + o`` or ``(i + 1) f + o`` lies 1e-16 .. 1e-6 from an integer
    (either side), at firings anywhere below the limit: the fixed rows still give the float rule's
    bytes; the fixed decision alone, without the guard, differs on many of these lanes."""
    rng = np.random.default_rng(7)
    n_c, n_r, unguarded = 512, 64, 0
    for _ in range(60):
        first = int(rng.integers(-K.FIXED_MAX_FIRING + 1, K.FIXED_MAX_FIRING - n_r))
        f = rng.uniform(0.0, 1.0, n_c)
        i = (first + rng.integers(0, n_r, n_c)).astype(np.float64)
        x = np.where(rng.integers(0, 2, n_c) == 0, i * f, (i + 1.0) * f)
        o = np.mod(np.ceil(x) - x + 10.0 ** rng.uniform(-16, -6, n_c) * rng.choice([-1.0, 1.0], n_c), 1.0)
        o[o >= 1.0] = 0.0
        F, P, H = _fixed_columns(f, o)
        s = np.zeros(n_c, np.uint8)
        a, b = np.empty((n_r, n_c), np.uint8), np.empty((n_r, n_c), np.uint8)
        K._thin_rows(a, 0, n_r, first, 0, n_c, f, o, s, np.uint8(1))
        K._thin_rows_fixed(b, 0, n_r, first, 0, n_c, f, o, F, P, H, s, np.uint8(1))
        np.testing.assert_array_equal(b, a)
        iu = (first + np.arange(n_r, dtype=np.int64))[:, None] & 0xFFFFFFFF
        R = ((iu * F.astype(np.int64) + P) & 0xFFFFFFFF).astype(np.uint32).view(np.int32)
        unguarded += int(((np.abs(R.astype(np.int64)) < H) != (a > 0)).sum())
    assert unguarded > 1000  # the cases are near enough to need the guard


def test_fill_refuses_a_share_that_is_not_finite():
    x, y = np.array([31.0, 39.0, 39.0, 31.0]), np.array([-3.0, -3.0, 3.0, 3.0])
    r = np.array([33.0, 35.0, 37.0])
    args = (x, y, np.roll(x, -1), np.roll(y, -1), r * r, np.zeros(3), np.arange(3), np.array([0.5, np.nan, 1.0]), np.zeros(3))
    with pytest.raises(ValueError, match="frac must be finite"):
        K.direct_fill_jit(*args, dphi=0.002, direction=1, i0=-100, n_f=200, n_cols=3, fill="nonzero", level=1)


def test_fill_beyond_the_fixed_rows_limit_is_the_reference():
    """Firing indices past FIXED_MAX_FIRING (a part far round the platform at a fine clock): the fill
    falls back to the float64 rows and still gives the numpy reference's image."""
    rng = np.random.default_rng(41)
    n_tr = 120
    r = np.sort(rng.uniform(30, 40, n_tr))
    psi0 = rng.uniform(-0.05, 0.05, n_tr)
    frac = rng.choice([1.0, 0.3, 0.7, 1.0 / 3.0], n_tr)
    x, y = np.array([29.0, 41.0, 41.0, 29.0]), np.array([-5.0, -5.0, 5.0, 5.0])
    cols, offs = rng.permutation(200)[:n_tr], rng.uniform(0, 1, n_tr)
    for i0 in (K.FIXED_MAX_FIRING - 100, -K.FIXED_MAX_FIRING - 50):
        # psi0 unwrapped so that firings i0 .. i0 + 299 land on the box (local angles -0.1 .. 0.5 rad)
        args = (x, y, np.roll(x, -1), np.roll(y, -1), r * r, psi0 + 0.1 + i0 * 0.002, cols, frac, offs)
        kw = dict(dphi=0.002, direction=1, i0=i0, n_f=300, n_cols=200, fill="nonzero", level=1)
        got = K.direct_fill_jit(*args, **kw)
        np.testing.assert_array_equal(got, K.direct_fill_numpy(*args, **kw))
        assert got.any()


def test_fill_writes_every_byte_of_its_image():
    """The jit fill allocates its image uninitialised: on an image of garbage it gives the numpy
    reference's image (rows without ink, columns beside it, tracks of share 0, no span at all, and
    two thinned tracks in one column, which the tiled writes fill after the sweep)."""
    rng = np.random.default_rng(31)
    n_tr = 120
    r = np.sort(rng.uniform(30, 40, n_tr))
    psi0 = rng.uniform(-0.05, 0.05, n_tr)
    for trial in range(12):
        frac = rng.choice([1.0, 0.0, 0.3, 0.7, 1.0 / 3.0], n_tr)
        if trial == 0:
            frac[:] = 0.0  # no track writes: no span events
        cols = rng.permutation(200)[:n_tr]
        if trial % 3 == 2:  # two thinned tracks in one column
            thin = np.flatnonzero((frac > 0) & (frac < 1))
            cols[thin[1]] = cols[thin[0]]
        n = rng.integers(3, 30)
        x, y = rng.uniform(31, 39, n), rng.uniform(-3, 3, n)
        args = (x, y, np.roll(x, -1), np.roll(y, -1), r * r, psi0, cols, frac, rng.uniform(0, 1, n_tr))
        kw = dict(dphi=0.002, direction=int(rng.choice([1, -1])), i0=int(rng.integers(-200, 50)), n_f=350, n_cols=200,
                  fill=["nonzero", "evenodd"][trial % 2], level=2)
        out = np.full((kw["n_f"], kw["n_cols"]), 171, np.uint8)
        got = K._direct_fill(*K._prep(*args), kw["dphi"], kw["direction"], kw["i0"], kw["n_f"], kw["fill"] == "evenodd",
                             np.uint8(kw["level"]), out, *K._NO_EDGE)
        np.testing.assert_array_equal(got, K.direct_fill_numpy(*args, **kw))


# ---------------------------------------------------------------------------------- reused images


def test_layers_write_into_the_blocks_of_dropped_layers_and_never_into_held_ones(shared_meshes):
    # one job over every layer (the blocks of the layer before are reused once dropped) against a new
    # job per layer; a print the caller still holds keeps its bytes while later layers are made
    mesh = _real(shared_meshes, "sphere_openscad.stl")
    h = float(mesh.bounds[1][2] - mesh.bounds[0][2])
    kw = dict(layer_height_mm=h / 6, inner_radius_mm=60.0, equalise=True)
    job = _job(mesh, 20.0, **kw)
    assert len(job) >= 5
    held = job.layer(2)
    held_copy = [s.levels.copy() for s in held.swathes]
    reused = 0
    addrs = set()
    for L in range(len(job)):
        pr = job.layer(L)
        now = {s.levels.ctypes.data for s in pr.swathes}
        reused += len(now & addrs)
        addrs |= now
        fresh = _job(mesh, 20.0, **kw).layer(L)
        for a, b in zip(pr.swathes, fresh.swathes):
            assert np.array_equal(a.levels, b.levels), L
        del pr
    assert reused > 0  # the dropped layers' blocks were written again
    for s, c in zip(held.swathes, held_copy):
        assert np.array_equal(s.levels, c)  # untouched by the layers made after it


def test_threads_sharing_one_job_get_the_serial_layers(shared_meshes):
    # helper-56 found 7 wrong layers of 240 when four threads shared a job (the slice job's face sweep
    # keeps one position); its steps are now taken under a lock
    import pickle
    from concurrent.futures import ThreadPoolExecutor

    mesh = _real(shared_meshes, "sphere_openscad.stl")
    h = float(mesh.bounds[1][2] - mesh.bounds[0][2])
    kw = dict(layer_height_mm=h / 12, inner_radius_mm=60.0)
    serial = _job(mesh, 20.0, **kw)
    want = [[s.levels.copy() for s in serial.layer(L).swathes] for L in range(len(serial))]
    shared = _job(mesh, 20.0, **kw)
    order = [L for _ in range(4) for L in (list(range(len(shared))) + list(range(len(shared)))[::-1])]
    with ThreadPoolExecutor(4) as ex:
        got = list(ex.map(lambda L: (L, [s.levels.copy() for s in shared.layer(L).swathes]), order))
    bad = [L for L, imgs in got if not all(np.array_equal(a, b) for a, b in zip(imgs, want[L]))]
    assert not bad
    clone = pickle.loads(pickle.dumps(shared))  # (the lock is made anew)
    assert all(np.array_equal(a.levels, b) for a, b in zip(clone.layer(3).swathes, want[3]))
