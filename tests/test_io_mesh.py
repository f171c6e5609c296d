"""Mesh input: formats, units, transforms, and every kind of bad file."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from rotoprint import InputFileError, MeshError, load_mesh, make_transform
from rotoprint.io.stl import write_binary_stl
from rotoprint.testing import box_triangles, torus_mesh


def ascii_stl(tri: np.ndarray, name: str = "part") -> str:
    lines = [f"solid {name}"]
    for t in tri:
        lines += ["  facet normal 0 0 0", "    outer loop"]
        lines += [f"      vertex {float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in t]
        lines += ["    endloop", "  endfacet"]
    lines.append(f"endsolid {name}")
    return "\n".join(lines) + "\n"


@pytest.fixture
def box_stl(tmp_path):
    p = tmp_path / "box.stl"
    write_binary_stl(p, box_triangles((2, 3, 4)))
    return p


def test_binary_box_volume_and_bounds(box_stl):
    m = load_mesh(box_stl)
    assert m.report.triangles_in == 12
    assert m.watertight
    assert m.volume_mm3 == pytest.approx(24.0)
    np.testing.assert_allclose(m.bounds, [[0, 0, 0], [2, 3, 4]])


def test_ascii_with_several_solids(tmp_path):
    a = box_triangles((1, 1, 1))
    b = box_triangles((1, 1, 1), (5, 0, 0))
    p = tmp_path / "two.stl"
    p.write_text(ascii_stl(a, "a") + ascii_stl(b, "b"))
    m = load_mesh(p)
    assert m.report.triangles_in == 24
    assert m.report.shells == 2
    assert m.volume_mm3 == pytest.approx(2.0)


def test_ascii_matches_binary(tmp_path):
    tri = torus_mesh(3, 1, 16, 8).triangles
    pa, pb = tmp_path / "a.stl", tmp_path / "b.stl"
    pa.write_text(ascii_stl(tri))
    write_binary_stl(pb, tri)
    ma, mb = load_mesh(pa), load_mesh(pb)
    assert ma.volume_mm3 == pytest.approx(mb.volume_mm3, rel=1e-6)  # binary is float32


def test_binary_header_starting_with_solid(shared_meshes):
    p = shared_meshes / "octagonal_pocket_solid_header_binary.stl"
    data = p.read_bytes()
    assert data[:5].lower() == b"solid"
    n = int(np.frombuffer(data, dtype="<u4", count=1, offset=80)[0])  # the binary header's triangle count
    assert len(data) == 84 + 50 * n  # ... which the file's size confirms: it is binary, not ASCII
    m = load_mesh(p)
    assert m.report.triangles_in == n


@pytest.mark.parametrize("units,factor", [("mm", 1), ("inch", 25.4), ("m", 1000), ("um", 1e-3), ("cm", 10)])
def test_units(box_stl, units, factor):
    m = load_mesh(box_stl, units=units)
    np.testing.assert_allclose(m.bounds[1], np.array([2, 3, 4]) * factor)


def test_transform_and_mirror_keep_solid_outward(box_stl):
    T = make_transform(translate_mm=(10, 0, 0), rotate_deg=(0, 0, 90), scale=(-1, 1, 1))
    m = load_mesh(box_stl, transform=T)
    assert m.volume_mm3 == pytest.approx(24.0)
    # mirror x: [-2, 0]; rotate 90 about z: x <- -y, y <- x; then +10 in x
    np.testing.assert_allclose(m.bounds, [[7, -2, 0], [10, 0, 4]], atol=1e-12)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"rotate_deg": (float("nan"), 0, 0)}, "rotate_deg (--rotate) must be three finite numbers, got (nan, 0.0, 0.0)"),
        ({"translate_mm": (0, 0, float("inf"))}, "translate_mm (--translate) must be three finite numbers, got (0.0, 0.0, inf)"),
        ({"scale": 0.0}, "scale (--scale) must be finite and non-zero"),
    ],
)
def test_make_transform_names_the_option(kwargs, message):
    from rotoprint.errors import ConfigError

    with pytest.raises(ConfigError) as ei:
        make_transform(**kwargs)
    assert str(ei.value).startswith(message)


def test_load_mesh_refuses_a_non_finite_transform(box_stl):
    from rotoprint.errors import ConfigError

    T = np.eye(4)
    T[0, 3] = np.nan
    with pytest.raises(ConfigError, match=r"^transform has NaN or infinite entries \(check --rotate, --translate and --scale\)$"):
        load_mesh(box_stl, transform=T)
    with pytest.raises(ConfigError, match=r"^transform must be a \(4, 4\) matrix, got shape \(3, 3\)$"):
        load_mesh(box_stl, transform=np.eye(3))


@pytest.mark.parametrize("fmt", ["obj", "ply", "off", "3mf"])
def test_other_formats_through_trimesh(tmp_path, fmt):
    tm = trimesh.Trimesh(**trimesh.triangles.to_kwargs(box_triangles((2, 3, 4))))
    p = tmp_path / f"box.{fmt}"
    tm.export(p)
    m = load_mesh(p)
    assert m.volume_mm3 == pytest.approx(24.0)


def _check_error(path, *fragments, exc=MeshError):
    with pytest.raises(exc) as info:
        load_mesh(path)
    msg = str(info.value)
    assert str(path) in msg and "\n" not in msg
    for f in fragments:
        assert f in msg, msg


def test_missing_file(tmp_path):
    _check_error(tmp_path / "nope.stl", "no such file", exc=InputFileError)


def test_directory(tmp_path):
    d = tmp_path / "d.stl"
    d.mkdir()
    _check_error(d, "directory", exc=InputFileError)


def test_empty_file(tmp_path):
    p = tmp_path / "e.stl"
    p.write_bytes(b"")
    _check_error(p, "empty")


def test_zero_triangles_binary_and_ascii(tmp_path):
    p = tmp_path / "z.stl"
    p.write_bytes(b"\0" * 80 + np.uint32(0).tobytes())
    _check_error(p, "zero triangles")
    q = tmp_path / "za.stl"
    q.write_text("solid x\nendsolid x\n")
    _check_error(q, "zero facets")


def test_truncated_binary(tmp_path, box_stl):
    p = tmp_path / "t.stl"
    p.write_bytes(box_stl.read_bytes()[:-17])
    _check_error(p, "truncated")


def test_header_count_that_lies(tmp_path, box_stl):
    data = bytearray(box_stl.read_bytes())
    data[80:84] = np.uint32(20).tobytes()
    p = tmp_path / "lie.stl"
    p.write_bytes(bytes(data))
    _check_error(p, "declares 20 triangles", "room for 12")


def test_nan_and_inf(tmp_path):
    tri = box_triangles()
    tri[3, 1, 2] = np.nan
    tri[5, 0, 0] = np.inf
    p = tmp_path / "nan.stl"
    write_binary_stl(p, tri)
    _check_error(p, "2 triangle(s) have NaN or infinite", "first: triangle 3")


def test_garbage_bytes(tmp_path):
    p = tmp_path / "g.stl"
    p.write_bytes(np.random.default_rng(1).integers(0, 256, 1000, dtype=np.uint8).tobytes())
    _check_error(p, "not a valid STL")


def test_short_garbage(tmp_path):
    p = tmp_path / "g.stl"
    p.write_bytes(b"\x00\xff\x10")
    _check_error(p, "not an STL")


def test_ascii_broken_facet(tmp_path):
    text = ascii_stl(box_triangles())
    lines = text.splitlines()
    idx = [i for i, ln in enumerate(lines) if "vertex" in ln][7]
    lines[idx] = "      vertex 1.0 oops 2.0"
    p = tmp_path / "broken.stl"
    p.write_text("\n".join(lines))
    _check_error(p, "broken facet at line")


def test_ascii_cut_short(tmp_path):
    text = ascii_stl(box_triangles())
    p = tmp_path / "cut.stl"
    p.write_text(text.replace("endsolid part", ""))
    _check_error(p, "cut short")


def test_unsupported_suffix(tmp_path):
    p = tmp_path / "m.xyz"
    p.write_text("hello")
    _check_error(p, "unsupported mesh format")


def test_bad_obj(tmp_path):
    p = tmp_path / "m.obj"
    p.write_text("this is not an obj\n")
    _check_error(p)


def test_degenerate_triangles_counted_not_fatal(tmp_path):
    tri = box_triangles()
    sliver = np.array([[[0, 0, 0], [0.5, 0, 0], [1, 0, 0]]], float)  # collinear, zero area
    point = np.array([[[1, 1, 1], [1, 1, 1], [1, 1, 1]]], float)  # collapsed
    p = tmp_path / "d.stl"
    write_binary_stl(p, np.concatenate([tri, sliver, point]))
    m = load_mesh(p)
    assert m.report.degenerate == 2
    assert m.report.collapsed_dropped == 1
    assert m.volume_mm3 == pytest.approx(1.0)
