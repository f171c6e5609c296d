"""Real meshes: the check completes, and its findings agree with an independent computation on
the exact section (shapely: faces of the noded outline kept by their winding number, opening
``buffer(-T/2).buffer(T/2)`` and closing ``buffer(T/2).buffer(-T/2)``)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import shapely
from shapely.geometry import MultiLineString, Point

from rotoprint import load_mesh
from rotoprint.check import check_layers
from rotoprint.devices import load_device
from rotoprint.slicing import slice_mesh

pytestmark = pytest.mark.realmesh

CASES = [
    # file, units, device, layer height (mm), threshold (mm)
    ("half_donut_ascii.stl", "mm", "perfactory-sxga", 0.5, 0.3),
    ("featuretype_open.stl", "mm", "perfactory-sxga", 0.25, 0.25),
    ("octagonal_pocket_solid_header_binary.stl", "inch", "perfactory-sxga", 0.1, 0.5),
    ("teapot_open.stl", "mm", "omnidot760", 3.0, 1.5),
    ("sphere_openscad.stl", "mm", "omnidot760", 10.0, None),
]


def _winding(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Winding numbers by summed angles (independent of the check's crossing rule)."""
    out = np.empty(len(points))
    for i, q in enumerate(points):
        u, v = a - q, b - q
        ang = np.arctan2(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0], (u * v).sum(axis=1))
        out[i] = ang.sum() / (2 * np.pi)
    return np.rint(out)


def exact_polygon(start: np.ndarray, end: np.ndarray):
    lines = shapely.union_all(shapely.linestrings(np.stack([start, end], axis=1)))
    faces = list(shapely.get_parts(shapely.polygonize(shapely.get_parts(lines))))
    if not faces:
        return shapely.Polygon()
    reps = np.array([[f.representative_point().x, f.representative_point().y] for f in faces])
    w = _winding(reps, start, end)
    return shapely.union_all([f for f, wi in zip(faces, w) if wi != 0])


def _chord_lines(lc, kind, grid):
    ch = lc.chords.get(kind)
    if ch is None or not len(ch):
        return None, np.empty((0, 2)), np.empty(0)
    m = grid.pixel_to_model
    A = ch[:, :2] @ m[:, :2].T + m[:, 2]
    B = ch[:, 2:] @ m[:, :2].T + m[:, 2]
    return MultiLineString([[tuple(a), tuple(b)] for a, b in zip(A, B)]), 0.5 * (A + B), np.hypot(*(B - A).T)


@pytest.mark.parametrize("name, units, device_name, layer_h, threshold", CASES)
def test_check_real_mesh_against_shapely(shared_meshes, name, units, device_name, layer_h, threshold):
    mesh = load_mesh(shared_meshes / name, units=units)
    dev = load_device(device_name)
    job = slice_mesh(mesh, dev, layer_height_mm=layer_h)
    p = max(dev.pitch_x_mm, dev.pitch_y_mm)
    checked = 0
    for lc in check_layers(job, dev, min_wall_mm=threshold, min_gap_mm=threshold):
        T = threshold if threshold is not None else max(p, dev.head.drop_diameter_um / 1000)
        seg, _ = job.segments(lc.index)
        if len(seg) == 0:
            assert not lc.findings
            continue
        P = exact_polygon(seg.start, seg.end)
        opened = P.buffer(-T / 2).buffer(T / 2)
        closed = P.buffer(T / 2).buffer(-T / 2)
        thin_region = P.difference(opened).buffer(-0.09 * T)  # shaved corners are thinner than this
        gap_region = closed.difference(P).buffer(-0.09 * T)
        for kind, region, inside in (("thin_wall", thin_region, True), ("narrow_gap", gap_region, False)):
            lines, mids, widths = _chord_lines(lc, kind, job.grid)
            # every report: a disc of diameter T about it does not fit (in the part / in the gap)
            for (x, y), w in zip(mids[:: max(1, len(mids) // 200)], widths[:: max(1, len(mids) // 200)]):
                disc = Point(x, y).buffer(T / 2 * 0.999, quad_segs=32)
                if inside:
                    assert P.buffer(1e-6).contains(Point(x, y)) and not P.contains(disc)
                else:
                    assert not P.buffer(-1e-6).contains(Point(x, y)) and disc.intersects(P)
                assert w < T + 1e-9
            # every region the opening removes (or the closing fills) is reported within a pixel
            for part in shapely.get_parts(region):
                if part.is_empty:
                    continue
                assert lines is not None, f"{kind} at {part.representative_point()} (layer {lc.index}) not reported"
                assert part.distance(lines) <= p, f"{kind} at {part.representative_point()} (layer {lc.index}) not reported"
        checked += 1
    assert checked > 0


def test_check_soup_completes(shared_meshes, run_cli, tmp_path):
    code, out, err = run_cli("check", shared_meshes / "soup.stl", "--device", "perfactory-sxga", "--layer-height", "0.2", "--out", tmp_path / "o")
    assert code in (0, 3), err
    rep = json.loads((tmp_path / "o" / "report.json").read_text())
    assert rep["n_layers"] == 5  # ceil(0.993 mm / 0.2 mm)
    assert (code == 0) == rep["ok"] and len(rep["findings"]) == sum(rep["counts"].values())
