"""Mesh repair: winding made consistent, shells oriented by the nesting rule."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint.mesh import Mesh, winding_number
from rotoprint.testing import box_triangles, torus_mesh, uv_sphere_mesh


def test_inside_out_box_is_turned_outward():
    m = Mesh.from_triangles(box_triangles()[:, ::-1])
    assert m.report.shells_flipped == 1
    assert m.volume_mm3 == pytest.approx(1.0)


def test_some_faces_flipped_are_rewound():
    tri = box_triangles((2, 1, 1)).copy()
    tri[[1, 4, 9]] = tri[[1, 4, 9]][:, ::-1]
    m = Mesh.from_triangles(tri)
    assert m.report.faces_reoriented == 3
    assert m.report.orientation_conflicts == 0
    assert m.volume_mm3 == pytest.approx(2.0)


def test_cavity_inward_shell_is_kept():
    outer = box_triangles((4, 4, 4))
    inner = box_triangles((2, 2, 2), (1, 1, 1))[:, ::-1]  # inward: a cavity
    m = Mesh.from_triangles(np.concatenate([outer, inner]))
    assert m.report.shells_flipped == 0
    assert m.volume_mm3 == pytest.approx(64 - 8)


def test_whole_hollow_part_inside_out_is_turned_as_a_whole():
    outer = box_triangles((4, 4, 4))
    inner = box_triangles((2, 2, 2), (1, 1, 1))[:, ::-1]
    m = Mesh.from_triangles(np.concatenate([outer, inner])[:, ::-1])
    assert m.report.shells_flipped == 2
    assert m.volume_mm3 == pytest.approx(64 - 8)


def test_keep_orientation_option():
    m = Mesh.from_triangles(box_triangles()[:, ::-1], orient="keep")
    assert m.volume_mm3 == pytest.approx(-1.0)


def test_winding_number_inside_outside():
    tri = uv_sphere_mesh(1.0, 24, 48).triangles
    w = winding_number(np.array([[0, 0, 0], [0.5, 0.2, -0.1], [2, 0, 0], [0, 0, 1.5]]), tri)
    np.testing.assert_allclose(w, [1, 1, 0, 0], atol=1e-9)


def test_torus_topology():
    m = torus_mesh(3, 1, 32, 16)
    assert m.watertight
    assert m.report.shells == 1
    # Euler characteristic of a torus is zero
    assert m.vertices.shape[0] - m.topology.edges.shape[0] + m.faces.shape[0] == 0


def test_open_edges_counted():
    m = Mesh.from_triangles(box_triangles()[2:], fill_holes=False)  # bottom face removed
    assert m.report.open_edges == 4
    assert not m.watertight
    assert not m.report.holes.enabled and m.info()["holes"]["filled"] == 0


def test_missing_face_is_filled_by_default():
    m = Mesh.from_triangles(box_triangles()[2:])  # bottom face removed: one 4-edge loop
    assert m.report.open_edges == 0 and m.watertight and m.faces.shape[0] == 12
    assert m.volume_mm3 == pytest.approx(1.0, abs=1e-12)
    h = m.info()["holes"]
    assert h["filled"] == 1 and h["filled_edges"] == 4 and h["filled_area_mm2"] == pytest.approx(1.0)
    assert not m.info()["watertight_as_read"]


def test_negative_zero_merges():
    tri = box_triangles()
    tri2 = tri.copy()
    tri2[tri2 == 0] = -0.0
    a, b = Mesh.from_triangles(tri), Mesh.from_triangles(np.concatenate([tri[:6], tri2[6:]]))
    assert b.vertices.shape[0] == a.vertices.shape[0] == 8
    assert b.watertight
