"""The fast kernels of the check against plain references: runs against the slicer's image,
islands on runs against labelling the image, the limited width measurement against measuring
every width, chord grouping against painting and labelling a canvas."""

from __future__ import annotations

import os

from pathlib import Path

import numpy as np
import pytest
from scipy import ndimage

from rotoprint import load_mesh
from rotoprint.check import _kernels as K
from rotoprint.devices import load_device
from rotoprint.mesh import Mesh
from rotoprint.pieces import feature_test_piece
from rotoprint.slicing import slice_mesh
from rotoprint.slicing._fill import fill_numpy
from rotoprint.slicing.fibres import _affine
from rotoprint.testing import box_triangles

import _reference_kernels as R  # noqa: E402 - beside this file (tests/check)

SHARED = Path(__file__).resolve().parents[2].parent / "shared" / "data" / "meshes"


@pytest.fixture(scope="module")
def piece_mesh():
    return Mesh.from_triangles(feature_test_piece()[0])


def _runs_of(img: np.ndarray):
    """Runs of an image by plain numpy (row starts, first and past-the-end columns)."""
    b = np.pad(img > 0, ((0, 0), (1, 1))).astype(np.int8)
    d = np.diff(b, axis=1)
    r_on, c_on = np.nonzero(d == 1)
    r_off, c_off = np.nonzero(d == -1)
    rs = np.searchsorted(r_on, np.arange(img.shape[0] + 1))
    return rs.astype(np.int64), c_on.astype(np.int64), c_off.astype(np.int64)


def _jobs(piece_mesh, shared_meshes=SHARED):
    yield slice_mesh(piece_mesh, load_device("omnidot760"), layer_height_mm=0.3)
    yield slice_mesh(piece_mesh, load_device("perfactory-sxga"), layer_height_mm=0.5, fibre_angle_deg=33.0, fill="evenodd")
    yield slice_mesh(piece_mesh, load_device("omnidot760"), layer_height_mm=0.5, fibre_angle_deg=-71.0, backend="numpy")
    if shared_meshes.exists() or os.environ.get("CI"):  # CI has the shared meshes
        yield slice_mesh(load_mesh(shared_meshes / "teapot_open.stl"), load_device("omnidot760"), layer_height_mm=4.0)
        yield slice_mesh(load_mesh(shared_meshes / "half_donut_ascii.stl"), load_device("perfactory-sxga"), layer_height_mm=0.3, fill="evenodd")


def test_section_runs_equal_the_slicers_image(piece_mesh):
    n = 0
    for job in _jobs(piece_mesh):
        for i in range(len(job)):
            layer, seg = job.layer_and_segments(i)
            rs, r0, r1 = K.section_runs(seg.start, seg.end, job.fill_affine, job.grid.height, job.grid.width, job.fill == "evenodd")
            assert np.array_equal(R.runs_to_image(rs, r0, r1, job.grid.height, job.grid.width), layer.image)
            # and against the independent numpy fill (the slicer's image shares the jit bucketing)
            a, b = _affine(job.fill_affine, seg.start), _affine(job.fill_affine, seg.end)
            ref = fill_numpy(a[:, 0], a[:, 1], b[:, 0], b[:, 1], job.grid.height, job.grid.width, job.fill)
            assert np.array_equal(R.runs_to_image(rs, r0, r1, job.grid.height, job.grid.width), ref)
            want = _runs_of(layer.image)
            assert all(np.array_equal(a, b) for a, b in zip((rs, r0, r1), want))  # maximal runs
            n += 1
    assert n > 10


def _islands_reference(img: np.ndarray, below: np.ndarray):
    """The 8-connected regions of ``img`` with no pixel of ``below`` under them, in the order
    ``ndimage.label`` numbers them."""
    lab, n = ndimage.label(img > 0, structure=np.ones((3, 3), bool))
    held = np.unique(lab[(img > 0) & (below > 0)])
    out = []
    for k in range(1, n + 1):
        if k in held:
            continue
        rr, cc = np.nonzero(lab == k)
        out.append((rr.size, rr.mean(), cc.mean(), rr.min(), rr.max(), cc.min(), cc.max()))
    return out


@pytest.mark.parametrize("seed", range(12))
def test_island_runs_match_labelling(seed):
    rng = np.random.default_rng(seed)
    H, W = rng.integers(1, 40, 2)
    density = rng.uniform(0.1, 0.7)
    img = (rng.random((H, W)) < density).astype(np.uint8) * 255
    below = (rng.random((H, W)) < rng.uniform(0.0, 0.5)).astype(np.uint8) * 255
    cnt, srow, scol, rlo, rhi, clo, chi, isl = K.island_runs(*_runs_of(img), *_runs_of(below))
    ref = _islands_reference(img, below)
    assert cnt.size == len(ref)
    for i, (n, mr, mc, a, b, c, d) in enumerate(ref):
        assert cnt[i] == n and (rlo[i], rhi[i], clo[i], chi[i]) == (a, b, c, d)
        assert srow[i] / cnt[i] == pytest.approx(mr, abs=1e-12) and scol[i] / cnt[i] == pytest.approx(mc, abs=1e-12)
    # the run labels paint exactly the island pixels
    rs, r0, r1 = _runs_of(img)
    mask = np.zeros((H, W), bool)
    rows = np.repeat(np.arange(H), np.diff(rs))
    for k in np.flatnonzero(isl >= 0):
        mask[rows[k], r0[k] : r1[k]] = True
    lab, _ = ndimage.label(img > 0, structure=np.ones((3, 3), bool))
    held = np.unique(lab[(img > 0) & (below > 0)])
    assert np.array_equal(mask, (img > 0) & ~np.isin(lab, held))


def _sections(piece_mesh, shared_meshes=SHARED):
    dev = load_device("perfactory-sxga")
    job = slice_mesh(piece_mesh, dev, layer_height_mm=0.3)
    for i in (0, 2, 4):
        yield job.segments(i)[0], dev
    dev = load_device("omnidot760")
    yield slice_mesh(piece_mesh, dev, layer_height_mm=0.3).segments(3)[0], dev
    tabs = np.concatenate([box_triangles((1.0, 1.0, 0.2)), box_triangles((0.3, 0.05, 0.2), (1.0, 0.5, 0.0)), box_triangles((2.0, 0.03, 0.2), (-0.5, 1.06, 0.0))])
    yield slice_mesh(Mesh.from_triangles(tabs), dev, layer_height_mm=0.2).segments(0)[0], dev
    if shared_meshes.exists() or os.environ.get("CI"):  # CI has the shared meshes
        for name, dname, lh, k in (("teapot_open.stl", "omnidot760", 3.0, 7), ("sphere_openscad.stl", "omnidot760", 10.0, 4), ("half_donut_ascii.stl", "perfactory-sxga", 0.5, 3)):
            dev = load_device(dname)
            yield slice_mesh(load_mesh(shared_meshes / name), dev, layer_height_mm=lh).segments(k)[0], dev


@pytest.mark.parametrize("simplified", [False, True])
@pytest.mark.parametrize("chained", [False, True])
def test_sample_widths_measure_what_the_check_uses(piece_mesh, chained, simplified):
    """Against measuring every width of every sample: the same samples below the thresholds
    with the same widths, the same smallest width, no sample dropped that could matter.
    ``chained``: with the chain order, runs of segments are cleared as a whole.
    ``simplified``: on the section simplified as the check does by default (long segments,
    whose rays are tested against the segments their strip meets)."""
    n = dropped = 0
    for seg, dev in _sections(piece_mesh):
        p = max(dev.pitch_x_mm, dev.pitch_y_mm)
        cell = spacing = 0.5 * min(dev.pitch_x_mm, dev.pitch_y_mm)
        cap, need_w, need_g = 8 * p, 2 * p, 2.5 * p
        start, end = seg.start, seg.end
        if simplified:
            pos = np.full(int(max(seg.start_edge.max(), seg.end_edge.max())) + 1, -1, np.int32)
            start, end, _ = K.simplify_section(seg.start, seg.end, seg.start_edge, seg.end_edge, 0.01 * min(dev.pitch_x_mm, dev.pitch_y_mm), pos)
        sx, sy, ex, ey = (np.ascontiguousarray(a) for a in (start[:, 0], start[:, 1], end[:, 0], end[:, 1]))
        sx, sy, ex, ey, _, js, je = K.split_at_crossings(sx, sy, ex, ey, cell, 1e-5)
        comp, nc = K.chain_components(sx, sy, ex, ey, js, je, K._keys(sx, sy), K._keys(ex, ey))
        keep, nx, ny = K.classify_segments(sx, sy, ex, ey, comp, nc, False, 1e-7)
        rx, ry, rux, ruy, rsid, rln = R.boundary_samples(sx, sy, ex, ey, nx, ny, keep, spacing)
        rw, rg = R.cast_rays(rx, ry, rux, ruy, rsid, sx, sy, ex, ey, keep, cap, 1e-9, cell)
        if chained:
            succ = K.chain_successors(sx, sy, ex, ey, js, je, K._keys(sx, sy), K._keys(ex, ey))
            bx, by, ux, uy, ln, w, g = K.sample_widths_chained(sx, sy, ex, ey, nx, ny, keep, spacing, cap, 1e-9, cell, need_w, need_g, succ)
        else:
            bx, by, ux, uy, ln, w, g = K.sample_widths(sx, sy, ex, ey, nx, ny, keep, spacing, cap, 1e-9, cell, need_w, need_g)
        # the kept samples are reference samples (the same points, bit for bit), in order
        pos = np.flatnonzero(np.isin(rx + 1j * ry, bx + 1j * by))
        assert pos.size == bx.size and np.array_equal(rx[pos], bx) and np.array_equal(ry[pos], by)
        assert np.array_equal(rux[pos], ux) and np.array_equal(rln[pos], ln)
        for ref, got, need in ((rw, w, need_w), (rg, g, need_g)):
            below = ref < need
            assert set(np.flatnonzero(below)) <= set(pos)  # nothing that matters dropped
            assert np.array_equal(got[ref[pos] < need], ref[pos][ref[pos] < need])  # bit for bit
            assert not np.any(got[ref[pos] >= need] < need)
            if np.isfinite(ref).any():
                assert got.min() == ref.min()
            else:
                assert not np.isfinite(got).any()
        n += 1
        dropped += rx.size - bx.size
    assert n >= 5 and dropped > 0


@pytest.mark.parametrize("seed", range(8))
def test_group_chords_match_canvas_labelling(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 60))
    ac, ar = rng.uniform(0, 50, n), rng.uniform(0, 40, n)
    bc, br = ac + rng.normal(0, 3, n), ar + rng.normal(0, 3, n)
    grow, pad = 1, 2
    c0 = int(np.floor(min(ac.min(), bc.min()) + 0.5)) - pad
    r0 = int(np.floor(min(ar.min(), br.min()) + 0.5)) - pad
    c1 = int(np.floor(max(ac.max(), bc.max()) + 0.5)) + pad + 1
    r1 = int(np.floor(max(ar.max(), br.max()) + 0.5)) + pad + 1
    g, ng = R.group_chords(ac, ar, bc, br, c0, r0, r1 - r0, c1 - c0, grow)
    canvas = np.zeros((r1 - r0, c1 - c0), np.uint8)
    K.paint_chords(ac - c0, ar - r0, bc - c0, br - r0, canvas, 1)
    canvas = ndimage.binary_dilation(canvas, structure=np.ones((3, 3), bool), iterations=grow)
    lab, m = ndimage.label(canvas, structure=np.ones((3, 3), bool))
    want = lab[np.floor(ar + 0.5).astype(int) - r0, np.floor(ac + 0.5).astype(int) - c0] - 1
    assert ng == m and np.array_equal(g, want)
    # on a shared buffer (larger than the canvas), twice: the same, and the buffer left zero
    buf = np.zeros((r1 - r0 + 7) * (c1 - c0 + 3), np.int32)
    for _ in range(2):
        g2, ng2 = K.group_chords_in(ac, ar, bc, br, c0, r0, r1 - r0, c1 - c0, grow, buf)
        assert ng2 == ng and np.array_equal(g2, g) and not buf.any()


def test_check_layer_equals_widths_on_the_image_and_islands(piece_mesh):
    """The one-call layer check (raster tests on the runs, no image) gives exactly what the
    widths measured against the slicer's image and the islands on the runs give."""
    n = tested = 0
    for job in _jobs(piece_mesh):
        g = job.grid
        p = max(g.pitch_x_mm, g.pitch_y_mm)
        cell = spacing = 0.5 * min(g.pitch_x_mm, g.pitch_y_mm)
        m2p, p2m = np.ascontiguousarray(g.model_to_pixel), np.ascontiguousarray(g.pixel_to_model)
        evenodd = job.fill == "evenodd"
        prev = (np.zeros(g.height + 1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64))
        for i in range(len(job)):
            layer, seg = job.layer_and_segments(i)
            below = i > 0
            # widths well above a pixel so that the raster tests have candidates
            rest = (spacing, 8 * p, 1e-9, 3 * p, 3 * p, 1.5 * p, 1.5 * p, 3 * p, p2m, m2p, p)
            got = K.check_layer((seg.start, seg.end), (seg.start, seg.end), prev, below, K.LayerParams(job.fill_affine, g.height, g.width, evenodd, cell, 1e-5, 1e-7, *rest))
            rs, r0, r1, st, isl = R.layer_islands(seg.start, seg.end, job.fill_affine, g.height, g.width, evenodd, *prev, below)
            for a, b in zip(got[7:], (rs, r0, r1, st, isl)):
                assert np.array_equal(a, b)
            if len(seg):
                want = R.layer_widths(seg.start, seg.end, layer.image, cell, 1e-5, evenodd, 1e-7, *rest)
                assert np.array_equal(got[0], want[0])
                assert got[1] == want[1] and got[2] == want[2]
                for a, b in zip(got[3:7], want[3:7]):
                    assert np.array_equal(a, b)
                tested += got[5].size + got[6].size
                # presence on runs against presence on the image, every candidate
                S = got[0]
                for sgn, width, want_px in ((1.0, S[5], 255), (-1.0, S[6], 0)):
                    c = np.flatnonzero(np.isfinite(width))
                    if c.size:
                        args_c = (S[0][c], S[1][c], sgn * S[2][c], sgn * S[3][c], width[c])
                        ref = R.chord_presence(*args_c, layer.image, want_px, p2m, m2p, p)
                        new = K.chord_presence_runs(*args_c, rs, r0, r1, g.height, g.width, want_px, p2m, m2p, p)
                        assert np.array_equal(ref, new)
            prev = (rs, r0, r1)
            n += 1
    assert n > 10 and tested > 0


def _successors_plain(sx, sy, ex, ey, js, je):
    """The next piece of each by a dictionary of start points: the one joinable piece starting
    where this one ends (joinable end), and only if no other piece claims it; else -1."""
    starts = {}
    for o in range(sx.size):
        starts.setdefault((sx[o], sy[o]), []).append(o)
    succ = np.full(sx.size, -1)
    for i in range(sx.size):
        if je[i]:
            cand = [o for o in starts.get((ex[i], ey[i]), []) if js[o]]
            if len(cand) == 1 and cand[0] != i:
                succ[i] = cand[0]
    targets, counts = np.unique(succ[succ >= 0], return_counts=True)
    shared = set(targets[counts > 1].tolist())
    return np.array([-1 if s in shared else s for s in succ])


def test_chain_successors_and_runs_against_plain(piece_mesh):
    """Successors against a dictionary of start points; every run is a path along them of
    kept segments, none shorter than the minimum (but a lone one), directions within 35
    degrees of its first (any two within 70)."""
    for seg, dev in _sections(piece_mesh):
        cell = 0.5 * min(dev.pitch_x_mm, dev.pitch_y_mm)
        sx, sy, ex, ey = (np.ascontiguousarray(a) for a in (seg.start[:, 0], seg.start[:, 1], seg.end[:, 0], seg.end[:, 1]))
        sx, sy, ex, ey, _, js, je = K.split_at_crossings(sx, sy, ex, ey, cell, 1e-5)
        succ = K.chain_successors(sx, sy, ex, ey, js, je, K._keys(sx, sy), K._keys(ex, ey))
        assert np.array_equal(succ, _successors_plain(sx, sy, ex, ey, js, je))
        comp, nc = K.chain_components(sx, sy, ex, ey, js, je, K._keys(sx, sy), K._keys(ex, ey))
        keep, _, _ = K.classify_segments(sx, sy, ex, ey, comp, nc, False, 1e-7)
        run, ptr, mem = K._chain_runs(sx, sy, ex, ey, keep, succ, K.chains._RUN_MIN_LEN_MM)
        assert np.array_equal(np.sort(mem), np.flatnonzero(keep)) and np.all(run[~keep] == -1)
        L = np.hypot(ex - sx, ey - sy)
        for r in range(ptr.size - 1):
            m = mem[ptr[r] : ptr[r + 1]]
            assert np.all(run[m] == r) and 1 <= m.size <= K.chains._RUN_MAX
            assert np.all(succ[m[:-1]] == m[1:])
            if m.size > 1:
                assert np.all(L[m] >= K.chains._RUN_MIN_LEN_MM)
                t = np.stack([(ex - sx)[m], (ey - sy)[m]], 1) / L[m, None]
                assert np.all(t @ t[0] >= K.chains._RUN_COS - 1e-12)


def _circle(cx, cy, r, n=720, phase=0.0):
    a = phase + 2 * np.pi * np.arange(n) / n
    p = np.stack([cx + r * np.cos(a), cy + r * np.sin(a)], 1)
    return p, np.roll(p, -1, axis=0)


def _split_inputs(parts):
    s = np.concatenate([p[0] for p in parts])
    e = np.concatenate([p[1] for p in parts])
    return tuple(np.ascontiguousarray(a) for a in (s[:, 0], s[:, 1], e[:, 0], e[:, 1]))


def test_split_by_runs_equals_the_grid(piece_mesh):
    """The crossing search by runs of chained segments gives exactly what the grid search
    gives (every pair sharing a cell): on the sections and on circles that cross, touch,
    coincide in part and come within a few nanometres."""
    cases = []
    for seg, dev in _sections(piece_mesh):
        cases.append((tuple(np.ascontiguousarray(a) for a in (seg.start[:, 0], seg.start[:, 1], seg.end[:, 0], seg.end[:, 1])), 0.5 * min(dev.pitch_x_mm, dev.pitch_y_mm)))
    crossing = _split_inputs([_circle(0, 0, 0.1), _circle(0.05, 0.0, 0.1, phase=0.3), _circle(0.0, 0.0, 0.1 + 5e-9, phase=0.0), _circle(0.3, 0.0, 0.05, 90)])
    half = _circle(0.2, 0.2, 0.1)
    coincide = _split_inputs([half, (half[0][:360], half[1][:360]), _circle(0.2, 0.2, 0.05)])
    cases += [(crossing, 0.01), (crossing, 0.035), (coincide, 0.01)]
    for (sx, sy, ex, ey), cell in cases:
        a = K.split_at_crossings(sx, sy, ex, ey, cell, 1e-5)
        b = R.split_at_crossings_grid(sx, sy, ex, ey, cell, 1e-5)
        assert all(np.array_equal(x, y) for x, y in zip(a, b))
    # the crossing circles were cut, the near one flagged
    ox0, _, _, _, par, js, je = K.split_at_crossings(*crossing, 0.01, 1e-5)
    assert ox0.size > crossing[0].size
    near = (par >= 1440) & (par < 2160)
    assert not js[near].any() and not je[near].any()


def test_near_segments_in_different_cells_are_compared():
    """Two 1 um segments 5 nm apart (closer than the near distance) on either side of a cell
    boundary of the search grid are compared (the pieces are listed in the cells their boxes
    grown by the near distance touch): neither end of either is an ordinary joint, by either
    search. (Listed with a 1e-9-cell pad only, they were never compared.)"""
    for cell in (0.003, 0.01):
        xs = np.linspace(0.0, 1.0, 301)  # a straight chain of 300 segments, y = 0
        h = K._split_cell_size(1.0, 0.5, 302, cell)
        xb = -h + h * np.ceil((0.5 + h) / h)  # a cell boundary of the grid (x0 = min x - h)
        s = np.concatenate([np.stack([xs[:-1], np.zeros(300)], 1), [[xb - 2.5e-6, 0.5], [xb + 2.5e-6, 0.499]]])
        e = np.concatenate([np.stack([xs[1:], np.zeros(300)], 1), [[xb - 2.5e-6, 0.499], [xb + 2.5e-6, 0.5]]])
        args = tuple(np.ascontiguousarray(a) for a in (s[:, 0], s[:, 1], e[:, 0], e[:, 1]))
        for fn in (K.split_at_crossings, R.split_at_crossings_grid):
            _, _, _, _, par, js, je = fn(*args, cell, 1e-5)
            pair = par >= 300
            assert pair.sum() == 2 and not js[pair].any() and not je[pair].any()
            assert js[~pair][1:].all() and je[~pair][:-1].all()  # the chain's inner joints stay ordinary
