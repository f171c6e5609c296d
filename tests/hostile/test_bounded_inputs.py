"""Every input is read bounded: FIFOs, devices, directories and oversize files are one line.

Each case runs the real CLI in a subprocess under RLIMIT_AS (1.5 GiB) and a 120 s hang guard
(a blocking or endless read fails the test by timing out), and checks: exit 2, one line naming
the file, no traceback, nothing written in the folder. That a refusal comes before reading is
checked directly (the file is never opened, the zip member never inflated), not by the time
it takes: speed targets live in bench/.
"""

from __future__ import annotations

import io
import os
import struct
import zipfile
from pathlib import Path

import pytest
from PIL import Image

from _bounds_helpers import assert_refused, run_cli_bounded, tree
from rotoprint.errors import ImageError, InputFileError
from rotoprint.examples import write_binary_stl
from rotoprint.io.inputs import MAX_MESH_BYTES, MAX_TOML_BYTES, read_input_bytes, read_zip_members
from rotoprint.testing import box_triangles

JOB = """[job]
layer_height_mm = 0.05
{materials}
[printer]
device = "{device}"
heads = [{{name = "A", ink = "ammonium_sulphate"}}, {{name = "B", ink = "calcium_chloride"}}]
[placement]
inner_radius_mm = 60
[[parts]]
name = "p"
material = "plaster"
mesh = "{mesh}"
"""


def _special(tmp: Path, name: str, kind: str) -> Path:
    """A FIFO, a symlink to a character device, or a directory, under ``name``."""
    p = tmp / name
    if kind == "fifo":
        os.mkfifo(p)
    elif kind == "zero":
        os.symlink("/dev/zero", p)
    elif kind == "urandom":
        os.symlink("/dev/urandom", p)
    elif kind == "dir":
        p.mkdir()
    return p


KINDS = {"fifo": "FIFO", "zero": "character device", "urandom": "character device", "dir": "directory"}


@pytest.mark.parametrize(("kind", "suffix"), [("fifo", ".stl"), ("fifo", ".obj"), ("fifo", ".3mf"),
                                             ("zero", ".stl"), ("urandom", ".ply")])
def test_mesh_that_never_ends_is_refused(tmp_path, kind, suffix):
    _special(tmp_path, f"m{suffix}", kind)
    before = tree(tmp_path)
    run = run_cli_bounded("info", f"m{suffix}", cwd=tmp_path)
    assert_refused(run, f"m{suffix}", KINDS[kind], "expected a regular mesh file")
    assert tree(tmp_path) == before


def test_slice_from_a_fifo_writes_nothing(tmp_path):
    _special(tmp_path, "m.stl", "fifo")
    run = run_cli_bounded("slice", "m.stl", "-d", "perfactory-sxga", "--layer-height", "0.1", "-o", "out", cwd=tmp_path)
    assert_refused(run, "m.stl", "FIFO")
    assert sorted(os.listdir(tmp_path)) == ["m.stl"]


def test_oversize_mesh_is_refused_before_reading(tmp_path):
    big = tmp_path / "big.stl"
    with open(big, "wb") as fh:  # sparse: no disk used, and a read would take 3 GiB of memory
        fh.truncate(MAX_MESH_BYTES + (1 << 30))
    run = run_cli_bounded("info", "big.stl", cwd=tmp_path)
    line = assert_refused(run, "big.stl", "3.0 GiB", "2.0 GiB limit for a mesh file")
    assert str(MAX_MESH_BYTES + (1 << 30)) in line
    # the CLI's loader refuses it from its size, before it is opened (a read would need 3 GiB)
    import builtins

    from rotoprint.io.mesh import load_mesh

    def no_open(*a, **k):
        raise AssertionError(f"opened {a[0]}")

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(os, "open", no_open)
        mp.setattr(builtins, "open", no_open)
        with pytest.raises(InputFileError, match="2.0 GiB limit for a mesh file"):
            load_mesh(big)


@pytest.mark.parametrize("kind", ["fifo", "zero", "dir"])
def test_device_file_that_never_ends_is_refused(tmp_path, kind):
    _special(tmp_path, "dev.toml", kind)
    write_binary_stl(tmp_path / "box.stl", box_triangles((2, 2, 2)))
    run = run_cli_bounded("slice", "box.stl", "-d", "dev.toml", "--layer-height", "0.1", "-o", "out", cwd=tmp_path)
    assert_refused(run, "dev.toml", KINDS[kind])
    assert not (tmp_path / "out").exists()


def test_oversize_device_file_is_refused(tmp_path):
    with open(tmp_path / "dev.toml", "wb") as fh:
        fh.truncate(MAX_TOML_BYTES + 1)
    run = run_cli_bounded("head", "-d", "dev.toml", cwd=tmp_path)
    assert_refused(run, "dev.toml", "4.0 MiB limit for a device file")


@pytest.mark.parametrize("kind", ["fifo", "zero"])
def test_job_file_that_never_ends_is_refused(tmp_path, kind):
    _special(tmp_path, "job.toml", kind)
    run = run_cli_bounded("build", "job.toml", "-o", "out", cwd=tmp_path)
    assert_refused(run, "job.toml", KINDS[kind])
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("what", ["device", "materials", "mesh"])
def test_files_a_job_names_are_read_bounded_from_the_jobs_folder(tmp_path, what):
    """device, materials_file and mesh in a job are relative to the job's folder; a FIFO
    there is refused by name. The run starts elsewhere, so a path taken from the working
    directory would say 'no such file' instead."""
    jobdir = tmp_path / "jobs"
    jobdir.mkdir()
    write_binary_stl(jobdir / "box.stl", box_triangles((2, 2, 0.2)))
    names = {"device": "omnidot760", "materials": "", "mesh": "box.stl"}
    if what == "device":
        names["device"] = "dev.toml"
    elif what == "materials":
        names["materials"] = 'materials_file = "inks.toml"'
    else:
        names["mesh"] = "part.stl"
    fifo = {"device": "dev.toml", "materials": "inks.toml", "mesh": "part.stl"}[what]
    os.mkfifo(jobdir / fifo)
    (jobdir / "job.toml").write_text(JOB.format(**names))
    run = run_cli_bounded("build", jobdir / "job.toml", "-o", "out", cwd=tmp_path)
    assert_refused(run, str(jobdir / fifo), "FIFO")
    assert sorted(os.listdir(tmp_path)) == ["jobs"]


def test_relative_device_in_a_job_is_read_from_the_jobs_folder(tmp_path):
    """The device file beside the job is the one read: its (invalid) content is what the error names."""
    jobdir = tmp_path / "jobs"
    jobdir.mkdir()
    write_binary_stl(jobdir / "box.stl", box_triangles((2, 2, 0.2)))
    (jobdir / "dev.toml").write_text("name = 3\n")
    (jobdir / "job.toml").write_text(JOB.format(device="dev.toml", materials="", mesh="box.stl"))
    run = run_cli_bounded("build", jobdir / "job.toml", "-o", "out", cwd=tmp_path)
    assert_refused(run, str(jobdir / "dev.toml"), "no device kind")


def _bomb(path: Path, inflated: int, member: str = "3D/3dmodel.model") -> None:
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        with z.open(member, "w", force_zip64=True) as f:
            chunk = b" " * (1 << 24)
            for _ in range(inflated // len(chunk)):
                f.write(chunk)


@pytest.fixture(scope="module")
def bomb_3mf(tmp_path_factory) -> Path:
    p = tmp_path_factory.mktemp("bomb") / "bomb.3mf"
    _bomb(p, (1 << 30) + (1 << 26))  # 1.06 GiB of spaces in ~5 MB
    return p


def test_zip_bomb_3mf_is_refused_naming_member_and_size(bomb_3mf, tmp_path):
    run = run_cli_bounded("info", bomb_3mf, cwd=tmp_path)
    assert_refused(run, "bomb.3mf", "'3D/3dmodel.model'", "1.1 GiB", "1.0 GiB limit per member")
    assert os.listdir(tmp_path) == []
    # the CLI's loader refuses it from the declared size, before any member is inflated
    from rotoprint.io.mesh import load_mesh

    def no_inflate(self, *a, **k):
        raise AssertionError(f"member {a[0]!r} opened")

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(zipfile.ZipFile, "open", no_inflate)
        with pytest.raises(InputFileError, match="'3D/3dmodel.model'.*1.0 GiB limit per member"):
            load_mesh(bomb_3mf)


def _lying_zip(member_bytes: int, declared: int) -> bytes:
    """A zip of one deflated member whose local and central headers declare ``declared``
    bytes inflated while the member inflates to ``member_bytes``."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("a.png", b"\0" * member_bytes)
    data = bytearray(buf.getvalue())
    assert data[:4] == b"PK\x03\x04"
    data[22:26] = struct.pack("<I", declared)  # local header: uncompressed size
    c = data.index(b"PK\x01\x02")
    data[c + 24 : c + 28] = struct.pack("<I", declared)  # central directory: uncompressed size
    return bytes(data)


def test_zip_member_declared_too_big_is_refused():
    with pytest.raises(InputFileError, match=r"member 'a.png' inflates to .*more than the 1000 B limit"):
        read_zip_members(_lying_zip(100, 5000), "x.sl1", member_limit_bytes=1000)


def test_zip_member_whose_declared_size_lies_stops_at_the_bound():
    """Declares 10 bytes, inflates to 1 MB: never more than the bound is inflated."""
    with pytest.raises(InputFileError, match=r"member 'a.png' (inflates past|is corrupt)"):
        read_zip_members(_lying_zip(1 << 20, 10), "x.sl1", member_limit_bytes=1000)
    # within the bound the lie is still caught (CRC / size), as a one-line corrupt member
    with pytest.raises(InputFileError, match=r"member 'a.png' is corrupt"):
        read_zip_members(_lying_zip(100, 10), "x.sl1", member_limit_bytes=1000)


def test_sl1_bomb_is_refused_by_read_job(tmp_path):
    from rotoprint.io.archives import read_job

    p = tmp_path / "bomb.sl1"
    p.write_bytes(_lying_zip(100, (1 << 30) + 5))
    with pytest.raises(InputFileError, match=r"bomb.sl1: SL1 archive member 'a.png' inflates to 1.0 GiB"):
        read_job(p)


def test_layer_folder_manifest_fifo_is_refused(tmp_path):
    from rotoprint.io.archives import read_job

    (tmp_path / "job").mkdir()
    os.mkfifo(tmp_path / "job" / "manifest.json")
    with pytest.raises(InputFileError, match="FIFO"):
        read_job(tmp_path / "job")


def test_read_input_bytes_refuses_a_file_that_grows_past_the_bound(tmp_path, monkeypatch):
    """The read stops one byte past the limit even when the size seen before reading was fine
    (a file that grows while it is read): the size checks are disabled to simulate it."""
    import rotoprint.io.inputs as inputs

    p = tmp_path / "x.toml"
    p.write_bytes(b"a" * 10)
    assert read_input_bytes(p, what="x", limit_bytes=10) == b"a" * 10
    p.write_bytes(b"a" * 100_000)
    with pytest.raises(InputFileError, match="97.7 KiB.*more than the 10 B limit"):
        read_input_bytes(p, what="x", limit_bytes=10)
    monkeypatch.setattr(inputs, "_refuse_size", lambda *a: None)
    with pytest.raises(InputFileError, match="grew past the 10 B limit for a x while it was read"):
        read_input_bytes(p, what="x", limit_bytes=10)


def _png(path: Path, w: int, h: int) -> None:
    """A valid 1 x 1 PNG whose header then says w x h (a few bytes that decode to w * h pixels)."""
    import zlib

    buf = io.BytesIO()
    Image.new("L", (1, 1)).save(buf, "PNG")
    d = bytearray(buf.getvalue())
    d[16:24] = struct.pack(">II", w, h)
    d[29:33] = struct.pack(">I", zlib.crc32(bytes(d[12:29])))
    path.write_bytes(bytes(d))


@pytest.mark.parametrize("side", [10_000, 20_000])  # over Pillow's warning limit, over its error limit
def test_design_over_the_bomb_limit_is_one_line(tmp_path, side):
    _png(tmp_path / "d.png", side, side)
    run = run_cli_bounded("transform", "d.png", "-d", "omnidot760", "--radius", "60", "--tilt", "0", "-o", "p.png",
                          cwd=tmp_path)
    assert_refused(run, "d.png", f"{side * side} pixels", "decompression bombs")
    assert sorted(os.listdir(tmp_path)) == ["d.png"]


def test_design_bomb_in_process_is_an_image_error(tmp_path):
    """Under pytest warnings are errors: the DecompressionBombWarning path is converted too."""
    from rotoprint.io.images import read_grey_image

    _png(tmp_path / "d.png", 10_000, 10_000)
    with pytest.raises(ImageError, match="100000000 pixels"):
        read_grey_image(tmp_path / "d.png")


@pytest.mark.parametrize("kind", ["fifo", "zero"])
def test_design_that_never_ends_is_refused(tmp_path, kind):
    _special(tmp_path, "d.png", kind)
    run = run_cli_bounded("transform", "d.png", "-d", "omnidot760", "--radius", "60", "--tilt", "0", "-o", "p.png",
                          cwd=tmp_path)
    assert_refused(run, "d.png", KINDS[kind])
    assert not (tmp_path / "p.png").exists()


@pytest.fixture(scope="module")
def rotary_print(tmp_path_factory) -> Path:
    """A small print written by 'rotoprint transform': PRINT.png + PRINT.json, design d.png."""
    d = tmp_path_factory.mktemp("print")
    img = Image.new("L", (40, 30), 0)
    img.paste(255, (5, 5, 35, 25))
    img.save(d / "d.png")
    run = run_cli_bounded("transform", "d.png", "-d", "omnidot760", "--radius", "60", "--tilt", "0", "-o", "p.png",
                          cwd=d, timeout_s=120)
    assert run.code == 0, run.err
    return d


def test_sidecar_design_path_to_a_device_is_refused(rotary_print, tmp_path):
    import json
    import shutil

    for f in rotary_print.iterdir():
        shutil.copy(f, tmp_path / f.name)
    side = json.loads((tmp_path / "p.json").read_text())
    side["design"]["path"] = "zero.png"
    (tmp_path / "p.json").write_text(json.dumps(side))
    os.symlink("/dev/zero", tmp_path / "zero.png")
    before = tree(tmp_path)
    run = run_cli_bounded("simulate", "p.json", "-o", "o.png", cwd=tmp_path)
    assert_refused(run, "zero.png", "character device")
    assert tree(tmp_path) == before


@pytest.mark.parametrize("kind", ["fifo", "zero"])
def test_sidecar_that_never_ends_is_refused(rotary_print, tmp_path, kind):
    import shutil

    shutil.copy(rotary_print / "p.png", tmp_path / "p.png")
    _special(tmp_path, "p.json", kind)
    run = run_cli_bounded("simulate", "p.png", "-o", "o.png", cwd=tmp_path)
    assert_refused(run, "p.json", KINDS[kind])
    assert not (tmp_path / "o.png").exists()


def test_garbage_obj_is_not_a_valid_obj(tmp_path):
    (tmp_path / "g.obj").write_bytes(bytes(range(256)) * 40)
    run = run_cli_bounded("info", "g.obj", cwd=tmp_path)
    line = assert_refused(run, "g.obj", "could not read as OBJ: binary data, not text")
    assert "charset_normalizer" not in line and "No module" not in line


def test_latin1_comment_in_an_obj_still_loads(tmp_path):
    """Without charset_normalizer: an OBJ that is text in another 8-bit encoding is read."""
    body = "# mod\xe8le export\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n"
    (tmp_path / "t.obj").write_bytes(body.encode("latin-1"))
    run = run_cli_bounded("info", "t.obj", "--json", cwd=tmp_path, timeout_s=60)
    assert run.code == 0, run.err
    assert '"triangles": 4' in run.out or '"faces": 4' in run.out, run.out


@pytest.fixture
def gltf(tmp_path):
    """A glTF box whose two buffers are separate .bin files beside it."""
    import trimesh

    from trimesh.exchange.gltf import export_gltf

    for name, data in export_gltf(trimesh.creation.box().scene()).items():  # {"model.gltf": ..., "gltf_buffer_0.bin": ...}
        (tmp_path / ("b.gltf" if name.endswith(".gltf") else name)).write_bytes(data)
    bins = sorted(p.name for p in tmp_path.glob("*.bin"))
    assert bins, "trimesh wrote no external buffer: the test would test nothing"
    return tmp_path / "b.gltf", bins


@pytest.mark.parametrize("kind", ["fifo", "zero"])
def test_gltf_buffer_that_never_ends_is_refused(gltf, kind):
    path, bins = gltf
    (path.parent / bins[0]).unlink()
    _special(path.parent, bins[0], kind)
    run = run_cli_bounded("info", path.name, cwd=path.parent)
    # a FIFO in the folder is refused as such; a symlink to /dev/zero leads out of the folder
    assert_refused(run, bins[0], "FIFO" if kind == "fifo" else "leads outside the mesh's folder")


def test_gltf_buffer_outside_the_folder_is_refused(gltf, tmp_path):
    path, bins = gltf
    (tmp_path / "sub").mkdir()
    moved = tmp_path / "sub" / "b.gltf"
    moved.write_text(path.read_text().replace(bins[0], f"../{bins[0]}"))
    run = run_cli_bounded("info", moved, cwd=tmp_path)
    assert_refused(run, "b.gltf", f"'../{bins[0]}'", "leads outside the mesh's folder")


def test_obj_material_library_on_a_device_is_not_read(tmp_path):
    """An .mtl that never ends is skipped (trimesh loads the geometry without materials), in bounded time."""
    os.symlink("/dev/zero", tmp_path / "z.mtl")
    (tmp_path / "t.obj").write_text("mtllib z.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n")
    run = run_cli_bounded("info", "t.obj", "--json", cwd=tmp_path, timeout_s=60)
    assert run.code == 0, run.err


@pytest.mark.parametrize("target", ["../p.png", "/etc/hostname", "link.png"])
def test_sidecar_swathe_image_outside_its_folder_is_refused(rotary_print, tmp_path, target):
    import json
    import shutil

    d = tmp_path / "print"
    d.mkdir()
    for f in rotary_print.iterdir():
        shutil.copy(f, d / f.name)
    shutil.copy(rotary_print / "p.png", tmp_path / "p.png")
    if target == "link.png":
        os.symlink(tmp_path / "p.png", d / "link.png")
    side = json.loads((d / "p.json").read_text())
    side["swathes"][0]["file"] = target
    (d / "p.json").write_text(json.dumps(side))
    run = run_cli_bounded("simulate", "p.json", "-o", "o.png", cwd=d)
    assert_refused(run, "p.json", "outside its folder")
    assert not (d / "o.png").exists()


@pytest.mark.parametrize(("kind", "suffix"), [("fifo", ".gbr"), ("fifo", ".drl"), ("zero", ".dxf"), ("fifo", ".svg")])
def test_cad_layer_that_never_ends_is_refused(tmp_path, kind, suffix):
    """Gerber, Excellon, DXF and SVG readers open the file themselves: it is checked first."""
    _special(tmp_path, f"layer{suffix}", kind)
    before = tree(tmp_path)
    run = run_cli_bounded("info", f"layer{suffix}", cwd=tmp_path)
    assert_refused(run, f"layer{suffix}", KINDS[kind])
    assert tree(tmp_path) == before
