"""The C extension (rotoprint._native) against the references: the numba kernels, the
pure-numpy paths, scipy and Pillow. Each fast path is held to its reference exactly."""

from __future__ import annotations

import io
import zlib

import numpy as np
import pytest
from PIL import Image

import rotoprint._accel as accel
from rotoprint.testing import box_triangles, torus_mesh, uv_sphere_mesh

native = accel.native
pytestmark = pytest.mark.skipif(native is None, reason="rotoprint._native is not built (no C compiler at install)")


def _decode(png: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(png)) as im:
        assert im.mode == "L"
        return np.asarray(im).copy()


def _masks():
    rng = np.random.default_rng(7)
    yield np.zeros((5, 7), np.uint8)
    yield np.full((4, 3), 255, np.uint8)  # inverted background: every row equal to the one above
    yield np.zeros((1, 1), np.uint8)
    yield rng.integers(0, 256, (9, 1), dtype=np.uint8)
    yield rng.integers(0, 256, (40, 33), dtype=np.uint8)
    img = np.zeros((300, 120), np.uint8)  # long runs of equal rows (cached chunks), then content
    img[40:200, 10:90] = 255
    img[40:200, 9] = 77
    img[120:130, 50:60] = 3
    yield img


@pytest.mark.parametrize("k", range(6))
def test_png_decodes_to_the_image(k):
    img = list(_masks())[k]
    png = native.png_grey(img, img.shape[1], img.shape[0], 0, 0, img.shape[0], img.shape[1], False, False, 6)
    assert np.array_equal(_decode(png), img)


@pytest.mark.parametrize("mx,my", [(False, False), (True, False), (False, True), (True, True)])
def test_png_window_mirrored(mx, my):
    from rotoprint.io.images import png_bytes_window

    rng = np.random.default_rng(3)
    win = rng.integers(0, 256, (37, 21), dtype=np.uint8)
    win[10:30] = win[10]  # equal rows inside the window
    shape, r0, c0 = (400, 90), 250, 5
    full = np.zeros(shape, np.uint8)
    full[r0 : r0 + 37, c0 : c0 + 21] = win
    want = full[:, ::-1] if mx else full
    want = want[::-1] if my else want
    png = png_bytes_window(win, shape, r0, c0, mirror_x=mx, mirror_y=my)
    assert np.array_equal(_decode(png), want)
    # the same pixels through the whole-image encoder: the same bytes
    from rotoprint.io.images import png_bytes

    assert png == png_bytes(np.ascontiguousarray(want))


def test_png_is_small_for_an_empty_sl1s_layer():
    png = native.png_grey(np.zeros((0, 0), np.uint8), 1620, 2560, 0, 0, 0, 0, False, False, 6)
    assert np.array_equal(_decode(png), np.zeros((2560, 1620), np.uint8))
    assert len(png) < 8000 and len(zlib.compress(png, 9)) < 400


def test_png_of_a_prism_layer_deflates_well_in_the_zip():
    """A 20 x 20 mm square on the SL1S (400 equal rows): the equal rows are filtered Up inside
    the one content stream, which the archive's deflate shrinks to under 200 bytes (copied
    cached chunks: 231; PrusaSlicer's layer of the same square: 200)."""
    win = np.full((400, 400), 255, np.uint8)
    png = native.png_grey(win, 1620, 2560, 1080, 610, 400, 400, True, False, 1)
    full = np.zeros((2560, 1620), np.uint8)
    full[1080:1480, 610:1010] = 255
    assert np.array_equal(_decode(png), full[:, ::-1])
    z = zlib.compressobj(9, zlib.DEFLATED, -15)
    assert len(z.compress(png) + z.flush()) < 200


@pytest.mark.parametrize("rows", [1025, 1026, 1500])  # runs of rows - 1 Up rows
def test_png_long_runs_of_equal_rows(rows):
    """Runs of up to 1024 rows equal to the row above are deflated in the content stream,
    longer ones copied from cached chunks (an inverted mask's full field): both decode."""
    img = np.full((rows + 3, 40), 255, np.uint8)
    img[0, 5] = 7
    img[rows + 1 :, 10:30] = 0
    png = native.png_grey(img, 40, rows + 3, 0, 0, rows + 3, 40, False, False, 3)
    assert np.array_equal(_decode(png), img)


def test_section_matches_the_numpy_reference():
    from rotoprint.slicing._sections import FaceSweep, section, section_numpy

    mesh = torus_mesh(6.0, 2.0, 90, 40)
    sweep = FaceSweep(mesh)
    for z in np.linspace(-1.9, 1.9, 7):
        faces = sweep.faces_at(float(z))
        a, b = section(mesh, faces, float(z)), section_numpy(mesh, faces, float(z))
        for f in ("start", "end", "start_edge", "end_edge"):
            assert np.array_equal(getattr(a, f), getattr(b, f)), f


def test_fill_matches_the_jit_kernel_and_numpy():
    """The binary fibre fill: random segments (on and off the fibres and samples, outside the
    image, degenerate), both rules, empty images; and a real part's layers."""
    from rotoprint import load_device, slice_mesh
    from rotoprint.slicing._fill import fill_fast, fill_numpy
    from rotoprint.slicing._kernels import fill_jit

    rng = np.random.default_rng(3)
    for t in range(200):
        n, n_fib, n_samp = int(rng.integers(0, 60)), int(rng.integers(0, 40)), int(rng.integers(0, 50))
        P = rng.uniform(-5, 45, (n, 4))
        if t % 3 == 0:
            P = np.round(P)  # vertices exactly on fibres and samples
        if t % 7 == 0 and n:
            P[:, 3] = P[:, 1]  # horizontal segments: no crossing
        args = (P[:, 0], P[:, 1], P[:, 2], P[:, 3], n_fib, n_samp)
        for rule in ("nonzero", "evenodd"):
            got = fill_fast(*args, rule)
            assert got.shape == (n_fib, n_samp) and got.dtype == np.uint8
            assert np.array_equal(got, fill_jit(*args, rule)), (t, rule)
            assert np.array_equal(got, fill_numpy(*args, rule)), (t, rule)
    job = slice_mesh(torus_mesh(6.0, 2.0, 90, 40), load_device("omnidot760"), layer_height_mm=0.5)
    numpy_job = slice_mesh(job.mesh, load_device("omnidot760"), layer_height_mm=0.5, backend="numpy")
    for i in range(0, len(job), 2):
        assert np.array_equal(job.layer(i).image, numpy_job.layer(i).image), i


def test_coverage_matches_the_jit_kernels_and_numpy(monkeypatch):
    from rotoprint import load_device, slice_mesh
    from rotoprint.masks.coverage import coverage_mask

    job = slice_mesh(uv_sphere_mesh(4.0, 24, 48), load_device("perfactory-sxga"), layer_height_mm=1.0)
    for i in range(len(job)):
        s, e, _ = job.pixel_segments(i)
        fast = coverage_mask(s, e, job.grid.shape)
        ref = coverage_mask(s, e, job.grid.shape, backend="numpy")
        assert np.abs(fast.astype(int) - ref.astype(int)).max() <= 1  # rounding at .5 only
        assert abs(int(fast.sum()) - int(ref.sum())) <= 1  # both within 1/2 level of the exact sum
        monkeypatch.setattr(accel, "native", None)
        jit = coverage_mask(s, e, job.grid.shape)
        monkeypatch.setattr(accel, "native", native)
        assert np.array_equal(fast, jit)


def test_shell_labels_match_scipy():
    from rotoprint.mesh import Mesh, shell_labels, shell_labels_scipy

    tri = np.concatenate([box_triangles((1, 1, 1), (5, 0, 0)), box_triangles((1, 1, 1)), box_triangles((2, 2, 2), (10, 0, 0))])
    mesh = Mesh.from_triangles(tri[np.random.default_rng(1).permutation(len(tri))])
    fe = mesh.topology.face_edges
    n_e = mesh.topology.edges.shape[0]
    a, na = shell_labels(fe, n_e)
    b, nb = shell_labels_scipy(fe, n_e)
    assert na == nb == 3 and np.array_equal(a, b)


def test_sl1_member_bytes_the_same_with_and_without_the_window_path(tmp_path):
    """The DLP fast path (window) and the general path make the same archive."""
    from rotoprint import load_device, slice_mesh
    from rotoprint.io.archives import JobInfo
    from rotoprint.pipeline import write_dlp_job
    from rotoprint.masks import MaskOptions

    dev = load_device("prusa-sl1s")
    job = slice_mesh(Mesh_box(), dev, layer_height_mm=0.5)
    p = dev.projector
    info = JobInfo(job_name="t", layer_height_mm=0.5, layer_count=len(job), copies=1, width_px=job.grid.width,
                   height_px=job.grid.height, pixel_x_mm=job.grid.pitch_x_mm, pixel_y_mm=job.grid.pitch_y_mm,
                   mirror_x=True, mirror_y=False, orientation=p.orientation, exposure_s=2, first_exposure_s=20,
                   first_exposure_layers=1, printer_model="SL1S")
    fast = MaskOptions(mirror_x=True)
    general = MaskOptions(mirror_x=True, first_layers=len(job), first_layer_offset_um=0.0)  # not the window path
    import os

    os.environ["SOURCE_DATE_EPOCH"] = "1700000000"
    try:
        for name, opts in (("a", fast), ("b", general)):
            (tmp_path / name).mkdir()
            write_dlp_job(job, tmp_path / name / "job.sl1s", info, opts)
    finally:
        del os.environ["SOURCE_DATE_EPOCH"]
    import zipfile

    with zipfile.ZipFile(tmp_path / "a" / "job.sl1s") as za, zipfile.ZipFile(tmp_path / "b" / "job.sl1s") as zb:
        names = [n for n in za.namelist() if n.endswith(".png") and "/" not in n]
        assert len(names) == len(job)
        for n in names:
            assert za.read(n) == zb.read(n)


def test_coverage_rows_match_the_jit_kernels_on_random_segments(monkeypatch):
    """The row-by-row kernel against the whole-window jit kernels, exactly: closed loops,
    open segments (tails right of the window), segments beyond the image on every side."""
    from rotoprint.masks.coverage import coverage_window

    rng = np.random.default_rng(11)
    for it in range(60):
        k = int(rng.integers(1, 40))
        s = rng.random((k, 2)) * rng.integers(2, 70) - 6.0
        e = np.roll(s, -1, axis=0) if it % 3 else rng.random((k, 2)) * 50 - 6.0
        shape = (int(rng.integers(1, 50)), int(rng.integers(1, 50)))
        fast = coverage_window(s, e, shape)
        monkeypatch.setattr(accel, "native", None)
        jit = coverage_window(s, e, shape)
        monkeypatch.setattr(accel, "native", native)
        assert fast[:2] == jit[:2] and np.array_equal(fast[2], jit[2]), it
        assert (fast[3] is None) == (jit[3] is None) and (fast[3] is None or np.array_equal(fast[3], jit[3])), it


def test_window_stats_match_numpy():
    rng = np.random.default_rng(5)
    for shape in [(0, 0), (0, 4), (3, 0), (1, 1), (7, 9), (40, 33), (5, 300)]:
        for density in (0.0, 0.05, 1.0):
            a = (rng.random(shape) < density).astype(np.uint8) * rng.integers(1, 256, shape, dtype=np.uint8)
            rows, cols = np.flatnonzero(a.any(axis=1)), np.flatnonzero(a.any(axis=0))
            box = (int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1) if rows.size else (0, 0, 0, 0)
            assert native.window_stats(a, *a.shape) == (int(a.sum(dtype=np.uint64)), *box)


def test_thumbnails_the_same_in_c_and_numpy(monkeypatch):
    """thumb_rgb against thumbnail_png's numpy path, byte for byte: shrinking and growing on
    either axis, binary and grey footprints, one-pixel ones."""
    from rotoprint.io.formats._common import THUMBNAIL_SIZES, thumbnail_png

    rng = np.random.default_rng(3)
    feet = [np.full((1, 1), 7, np.uint8), np.full((900, 1), 200, np.uint8), np.full((1, 900), 255, np.uint8),
            rng.integers(0, 256, (37, 53), dtype=np.uint8), (255 * (rng.random((300, 310)) < 0.5)).astype(np.uint8)]
    for _ in range(12):
        h, w = (int(v) for v in rng.integers(1, 1500, 2))
        a = rng.integers(0, 256, (h, w), dtype=np.uint8) if rng.random() < 0.5 else (255 * (rng.random((h, w)) < 0.6)).astype(np.uint8)
        feet.append(a)
    for a in feet:
        for size in THUMBNAIL_SIZES:
            fast = thumbnail_png(a, size)
            monkeypatch.setattr(accel, "native", None)
            ref = thumbnail_png(a, size)
            monkeypatch.setattr(accel, "native", native)
            assert fast == ref, (a.shape, size)


def test_equal_window_reused_only_for_equal_pixels(tmp_path):
    """Layers of a box with a cavity in its upper half have the same window (rows, columns,
    size) but not the same pixels: the PNG kept from the layer before is not reused for
    them, and every mask is the general path's."""
    from rotoprint import load_device, slice_mesh
    from rotoprint.io.archives import JobInfo, read_job
    from rotoprint.masks import MaskOptions, iter_masks
    from rotoprint.mesh import Mesh
    from rotoprint.pipeline import write_dlp_job

    outer = box_triangles((3.0, 3.0, 2.0), (-1.5, -1.5, 0.0))
    cavity = box_triangles((1.0, 1.0, 1.0), (-0.5, -0.5, 1.0))[:, ::-1]  # inward: a hole above z = 1
    dev = load_device("prusa-sl1s")
    job = slice_mesh(Mesh.from_triangles(np.concatenate([outer, cavity])), dev, layer_height_mm=0.25)
    p = dev.projector
    info = JobInfo(job_name="t", layer_height_mm=0.25, layer_count=len(job), copies=1, width_px=job.grid.width,
                   height_px=job.grid.height, pixel_x_mm=job.grid.pitch_x_mm, pixel_y_mm=job.grid.pitch_y_mm,
                   mirror_x=True, mirror_y=False, orientation=p.orientation, exposure_s=2, first_exposure_s=20,
                   first_exposure_layers=1, printer_model="SL1S")
    opts = MaskOptions(mirror_x=True)
    write_dlp_job(job, tmp_path / "job.sl1s", info, opts)
    a = read_job(tmp_path / "job.sl1s")
    want = [m.image for m in iter_masks(job, opts)]
    assert len(a) == len(want) == 8
    assert not np.array_equal(want[0], want[-1])  # (the cavity shows)
    for i, w in enumerate(want):
        np.testing.assert_array_equal(a.mask(i), w)


def test_archive_the_same_made_in_threads_or_in_the_calling_thread(tmp_path, monkeypatch):
    """The layers after the samples are made by two render threads, or in the calling thread
    when they are few or cheap (pipeline.journal.SMALL_REST_S): the same bytes either way."""
    import zipfile

    from rotoprint import load_device, slice_mesh
    from rotoprint.io.archives import JobInfo
    from rotoprint.masks import MaskOptions
    from rotoprint.pipeline import journal, write_dlp_job

    dev = load_device("prusa-sl1s")
    job = slice_mesh(uv_sphere_mesh(2.0, 16, 32), dev, layer_height_mm=0.25)
    p = dev.projector
    info = JobInfo(job_name="t", layer_height_mm=0.25, layer_count=len(job), copies=1, width_px=job.grid.width,
                   height_px=job.grid.height, pixel_x_mm=job.grid.pitch_x_mm, pixel_y_mm=job.grid.pitch_y_mm,
                   mirror_x=True, mirror_y=False, orientation=p.orientation, exposure_s=2, first_exposure_s=20,
                   first_exposure_layers=1, printer_model="SL1S")
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    made = {}
    for name, limit_s in (("threads", 0.0), ("here", 1e9)):
        monkeypatch.setattr(journal, "SMALL_REST_S", limit_s)
        (tmp_path / name).mkdir()
        write_dlp_job(job, tmp_path / name / "job.sl1s", info, MaskOptions(mirror_x=True))
        with zipfile.ZipFile(tmp_path / name / "job.sl1s") as z:
            made[name] = {n: z.read(n) for n in z.namelist()}
    assert len(job) == 16 and made["threads"] == made["here"]


def Mesh_box():
    from rotoprint.mesh import Mesh

    return Mesh.from_triangles(box_triangles((3.3, 2.1, 2.0), (-1.7, -1.0, 0.0)))


def test_vertex_merge_and_areas_match_numpy():
    from rotoprint.mesh import _double_areas, _double_areas_numpy, _unique_rows, _unique_rows_numpy

    rng = np.random.default_rng(5)
    pts = rng.integers(-3, 4, (500, 3)).astype(np.float64) * 0.25  # many repeats
    pts[::7] = pts[::7] + 0.0  # folded zeros
    rows = np.ascontiguousarray(pts[rng.integers(0, 500, 3000)])
    v1, i1 = _unique_rows(rows)
    v2, i2 = _unique_rows_numpy(rows)
    assert np.array_equal(v1, v2) and np.array_equal(i1, i2)
    faces = rng.integers(0, len(v1), (400, 3))
    assert np.array_equal(_double_areas(v1, faces), _double_areas_numpy(v1, faces))


def test_topology_matches_the_sorting_path(monkeypatch):
    """Edges, their numbering, counts, manifold pairs and suspect edges: hashing == sorting,
    on a mesh with open edges, a non-manifold edge and faces wound the wrong way."""
    from rotoprint.mesh import _Topology

    tri = np.concatenate([torus_mesh(3.0, 1.0, 24, 12).triangles, box_triangles((1, 1, 1), (10, 0, 0))[:-1]])
    tri[5] = tri[5][::-1]  # an orientation conflict
    tri = np.concatenate([tri, tri[7:8] + [0, 0, 0.5]])
    from rotoprint.mesh import Mesh

    mesh = Mesh.from_triangles(tri, orient="keep")
    fast = _Topology(mesh.faces, len(mesh.vertices))
    monkeypatch.setattr(accel, "native", None)
    ref = _Topology(mesh.faces, len(mesh.vertices))
    for f in ("edges", "face_edges", "edge_face_count", "forward", "pair_faces", "pair_same_direction",
              "suspect_edges", "shell"):
        assert np.array_equal(getattr(fast, f), getattr(ref, f)), f
    assert fast.orientation_conflicts == ref.orientation_conflicts > 0 and fast.n_shells == ref.n_shells


def test_fallbacks_without_the_extension(monkeypatch):
    """Without the C extension the numba section kernel and Pillow's PNG give the same data."""
    from rotoprint.io.images import png_bytes_window
    from rotoprint.slicing._sections import FaceSweep, section

    mesh = torus_mesh(6.0, 2.0, 60, 30)
    faces = FaceSweep(mesh).faces_at(0.3)
    fast = section(mesh, faces, 0.3)
    win = np.random.default_rng(2).integers(0, 256, (20, 30), dtype=np.uint8)
    png_fast = png_bytes_window(win, (50, 80), 10, 40, mirror_x=True, mirror_y=True)
    monkeypatch.setattr(accel, "native", None)
    slow = section(mesh, faces, 0.3)
    for f in ("start", "end", "start_edge", "end_edge"):
        assert np.array_equal(getattr(fast, f), getattr(slow, f)), f
    png_slow = png_bytes_window(win, (50, 80), 10, 40, mirror_x=True, mirror_y=True)
    assert png_slow != png_fast and np.array_equal(_decode(png_slow), _decode(png_fast))
