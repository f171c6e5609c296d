"""The slicer against an independent exact reference (trimesh section + shapely).

Acceptance: the slicer's images differ in no pixel whose centre is farther than 1e-6 mm from
the boundary of the exact cross-section.
"""

from __future__ import annotations

import numpy as np
import pytest
from _reference import exact_section, mismatches_beyond
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rotoprint import load_mesh, make_transform
from rotoprint.devices import load_device
from rotoprint.mesh import Mesh
from rotoprint.slicing import slice_mesh
from rotoprint.testing import box_triangles, cylinder_mesh, torus_mesh, uv_sphere_mesh

SXGA = load_device("perfactory-sxga")
INKJET = load_device("omnidot760")


def _shapes() -> dict[str, Mesh]:
    two_boxes = np.concatenate([box_triangles((6, 4, 3)), box_triangles((5, 6, 2), (3, 2, 0.5))])
    return {
        "box": Mesh.from_triangles(box_triangles((10, 7, 3), (-2, 1, 0))),
        "cylinder": cylinder_mesh(6.0, 2.0, 90),
        "sphere": uv_sphere_mesh(8.0, 24, 48),
        "torus-odd-rotation": torus_mesh(6.0, 2.0, 48, 24).transformed(make_transform(rotate_deg=(37, 21, 5))),
        "two-overlapping-boxes": Mesh.from_triangles(two_boxes),
        "inside-out-box": Mesh.from_triangles(box_triangles((8, 5, 2))[:, ::-1]),
    }


SHAPES = _shapes()


def assert_matches_reference(job, triangles, layers=None, per_shell=True):
    checked = 0
    for i in layers if layers is not None else range(len(job)):
        layer = job.layer(i)
        geom = exact_section(triangles, layer.z_mm, per_shell=per_shell)
        bad = mismatches_beyond(layer.image, job.grid, geom)
        assert len(bad) == 0, f"layer {i} z={layer.z_mm}: {len(bad)} pixels differ, first {bad[:5].tolist()}"
        checked += int((layer.image > 0).sum())
    assert checked > 0


@pytest.mark.parametrize("name", list(SHAPES))
@pytest.mark.parametrize("fibre_angle", [None, 33.0])
def test_shapes_match_exact_reference(name, fibre_angle):
    mesh = SHAPES[name]
    job = slice_mesh(mesh, SXGA, layer_height_mm=0.8, fibre_angle_deg=fibre_angle)
    tri = mesh.triangles
    assert_matches_reference(job, tri, layers=range(0, len(job), max(1, len(job) // 4)))


def test_inkjet_grid_matches_reference():
    mesh = SHAPES["torus-odd-rotation"]
    job = slice_mesh(mesh, INKJET, layer_height_mm=1.0, fibre_angle_deg=70.0)
    assert job.grid.fibre_axis == "y"
    assert_matches_reference(job, mesh.triangles)


@pytest.mark.realmesh
@pytest.mark.parametrize(
    "name,device,units,lh",
    [
        ("sphere_openscad.stl", INKJET, "mm", 7.0),
        ("half_donut_ascii.stl", SXGA, "mm", 0.2),
    ],
)
def test_real_closed_meshes_match_reference(shared_meshes, name, device, units, lh):
    mesh = load_mesh(shared_meshes / name, units=units)
    assert mesh.watertight
    job = slice_mesh(mesh, device, layer_height_mm=lh)
    assert_matches_reference(job, mesh.triangles)


# ---------------------------------------------------------------- property: random rigid moves
def _boundary_bound(geom, pitch_mm: float) -> float:
    """Largest area pixel-centre sampling can get wrong: a band of half a pixel diagonal."""
    d = pitch_mm * np.sqrt(0.5)
    n_rings = len(getattr(geom, "geoms", [geom])) * 2 + 2
    return 2 * d * geom.boundary.length + n_rings * np.pi * d * d


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    rot=st.tuples(*[st.floats(-180, 180)] * 3),
    shift=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-5, 5)),
    which=st.sampled_from(["box", "torus", "sphere"]),
    fibre=st.one_of(st.none(), st.floats(-180, 180)),
)
def test_area_within_boundary_bound_under_rigid_moves(rot, shift, which, fibre):
    base = {"box": SHAPES["box"], "torus": torus_mesh(4.0, 1.5, 32, 16), "sphere": uv_sphere_mesh(5.0, 16, 32)}[which]
    mesh = base.transformed(make_transform(rotate_deg=rot, translate_mm=shift))
    job = slice_mesh(mesh, SXGA, layer_height_mm=1.3, fibre_angle_deg=fibre)
    pa = job.grid.pitch_x_mm * job.grid.pitch_y_mm
    for i in range(0, len(job), 3):
        layer = job.layer(i)
        geom = exact_section(mesh.triangles, layer.z_mm)
        area = (layer.image > 0).sum() * pa
        assert abs(area - geom.area) <= _boundary_bound(geom, max(job.grid.pitch_x_mm, job.grid.pitch_y_mm))
