"""Fuzzing the mesh loaders: random bytes, truncations and mutations of small valid files.

Every input must either load into a mesh or raise one of rotoprint's own errors (the root
:class:`~rotoprint.errors.RotoprintError`; the CLI prints those as one line, exit 2) --
never another exception, never hang (an alarm bounds every call), and never allocate more
than a bounded amount (``tracemalloc`` peak, which numpy reports to).
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
import struct
import tracemalloc
import zipfile

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from rotoprint.errors import RotoprintError
from rotoprint.io.mesh import load_mesh
from rotoprint.testing import box_mesh

#: wall-clock hang guard of one load (the alarm; generous: the suite runs on loaded machines,
#: and speed targets live in bench/), and the allocation bound
TIME_LIMIT_S = 60
PEAK_LIMIT_BYTES = 256 * 2**20

#: ROTOPRINT_FUZZ_EXAMPLES=5000 runs a longer, randomised campaign (the suite's default is small
#: and derandomised so that it is fast and repeatable)
_N = int(os.environ.get("ROTOPRINT_FUZZ_EXAMPLES", "40"))
SETTINGS = settings(max_examples=_N, deadline=None, derandomize="ROTOPRINT_FUZZ_EXAMPLES" not in os.environ,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _seeds() -> dict[str, bytes]:
    import trimesh

    m = box_mesh((2.0, 3.0, 4.0))
    t = trimesh.Trimesh(m.vertices, m.faces, process=False)
    tri = m.triangles.astype("<f4")
    binary_stl = b"\0" * 80 + struct.pack("<I", len(tri)) + b"".join(b"\0" * 12 + x.tobytes() + b"\0\0" for x in tri)
    return {
        "binary.stl": binary_stl,
        "ascii.stl": trimesh.exchange.stl.export_stl_ascii(t).encode(),
        "box.obj": t.export(file_type="obj").encode(),
        "binary.ply": t.export(file_type="ply"),
        "ascii.ply": trimesh.exchange.ply.export_ply(t, encoding="ascii"),
        "box.off": t.export(file_type="off").encode(),
        "box.3mf": t.export(file_type="3mf"),
    }


SEEDS = _seeds()
NAMES = sorted(SEEDS)


class _Timeout(Exception):
    pass


@contextlib.contextmanager
def _alarm(seconds: int):
    def on_alarm(signum, frame):
        raise _Timeout(f"load took more than {seconds} s")

    old = signal.signal(signal.SIGALRM, on_alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _check_load(path) -> None:
    """Load ``path``: a mesh or a RotoprintError, within the time and allocation bounds."""
    tracemalloc.start()
    try:
        with _alarm(TIME_LIMIT_S):
            try:
                mesh = load_mesh(path)
            except RotoprintError as exc:
                msg = str(exc)
                assert msg and "\n" not in msg.strip(), f"message is not one line: {msg!r}"
                return
        assert mesh.faces.shape[0] > 0 and np.isfinite(mesh.vertices).all()
    finally:
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        assert peak < PEAK_LIMIT_BYTES, f"loading allocated {peak / 2**20:.0f} MiB"


def _write(tmp_path, name: str, data: bytes):
    p = tmp_path / name
    p.write_bytes(data)
    return p


def test_the_seeds_load(tmp_path):
    for name, data in SEEDS.items():
        m = load_mesh(_write(tmp_path, name, data))
        assert m.watertight and m.volume_mm3 == pytest.approx(24.0, rel=1e-6), name


@SETTINGS
@given(suffix=st.sampled_from([".stl", ".obj", ".ply", ".off", ".3mf"]), data=st.binary(max_size=600))
@example(suffix=".stl", data=b"")
@example(suffix=".ply", data=b"ply\n")
@example(suffix=".3mf", data=b"PK\x03\x04")
def test_random_bytes(tmp_path, suffix, data):
    _check_load(_write(tmp_path, "random" + suffix, data))


@SETTINGS
@given(name=st.sampled_from(NAMES), cut=st.floats(0.0, 1.0))
def test_truncated_files(tmp_path, name, cut):
    data = SEEDS[name]
    _check_load(_write(tmp_path, name, data[: int(cut * len(data))]))


_NUMBERS = [b"0", b"-1", b"1e308", b"-1e400", b"nan", b"inf", b"4294967295", b"18446744073709551616",
            b"99999999999999999999", b"2147483648", b"1.5", b"-0"]


@st.composite
def _mutations(draw, data: bytes) -> bytes:
    buf = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["flip", "set", "insert", "delete", "number", "duplicate"]))
        pos = draw(st.integers(0, max(0, len(buf) - 1)))
        if kind == "flip" and buf:
            buf[pos] ^= 1 << draw(st.integers(0, 7))
        elif kind == "set" and buf:
            buf[pos] = draw(st.integers(0, 255))
        elif kind == "insert":
            buf[pos:pos] = draw(st.binary(min_size=1, max_size=16))
        elif kind == "delete":
            del buf[pos : pos + draw(st.integers(1, 32))]
        elif kind == "number":
            # replace the run of digits around pos by an extreme number (text formats)
            s = e = pos
            while s > 0 and chr(buf[s - 1]).isdigit():
                s -= 1
            while e < len(buf) and chr(buf[e]).isdigit():
                e += 1
            buf[s:e] = draw(st.sampled_from(_NUMBERS))
        elif kind == "duplicate" and buf:
            n = draw(st.integers(1, 64))
            buf[pos:pos] = buf[pos : pos + n]
    return bytes(buf)


@SETTINGS
@given(name=st.sampled_from([n for n in NAMES if n != "box.3mf"]), data=st.data())
def test_mutated_files(tmp_path, name, data):
    mutated = data.draw(_mutations(SEEDS[name]))
    _check_load(_write(tmp_path, name, mutated))


def _rezip(members: dict[str, bytes]) -> bytes:
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for k, v in members.items():
            z.writestr(k, v)
    return out.getvalue()


_3MF_MEMBERS = {i.filename: zipfile.ZipFile(io.BytesIO(SEEDS["box.3mf"])).read(i) for i in
                zipfile.ZipFile(io.BytesIO(SEEDS["box.3mf"])).infolist()}


@SETTINGS
@given(data=st.data())
def test_mutated_3mf(tmp_path, data):
    """3MF is a zip: mutate the model XML inside it (a mutated zip is mostly a bad CRC)."""
    model = next(k for k in _3MF_MEMBERS if k.endswith(".model"))
    members = dict(_3MF_MEMBERS)
    members[model] = data.draw(_mutations(members[model]))
    _check_load(_write(tmp_path, "box.3mf", _rezip(members)))


def _crafted() -> dict[str, tuple[bytes, str]]:
    """What the fuzzer found (and a few hand-made neighbours): file name -> (bytes, the start
    of the error, or '' when the file must load)."""
    off = SEEDS["box.off"].decode()
    ply = SEEDS["ascii.ply"].decode()
    obj = SEEDS["box.obj"].decode()
    stl = SEEDS["ascii.stl"].decode()
    model = next(k for k in _3MF_MEMBERS if k.endswith(".model"))
    xml = _3MF_MEMBERS[model].decode()
    return {
        # face indices past the last vertex (an IndexError before) or negative (wrapped around)
        "ply_index.ply": (ply.replace("\n3 0 6 4\n", "\n3 0 6 13\n").encode(), "1 face(s) refer to vertices that do not exist"),
        "ply_negative.ply": (ply.replace("\n3 0 6 4\n", "\n3 0 6 -1\n").encode(), "1 face(s) refer to vertices that do not exist"),
        "off_index.off": (off.replace("\n3 0 6 4\n", "\n3 0 6 8\n").encode(), "face index outside the range"),  # trimesh checks OFF
        "off_negative.off": (off.replace("\n3 0 6 4\n", "\n3 0 -6 4\n").encode(), "face index outside the range"),
        "3mf_index.3mf": (_rezip({**_3MF_MEMBERS, model: xml.replace('v3="4"', 'v3="7000"', 1).encode()}), "face(s) refer to vertices"),
        "obj_index.obj": (obj.replace("f 1 7 5", "f 1 7 99999999999999999999").encode(), "could not read as OBJ"),
        # coordinates whose squares overflow (a RuntimeWarning, then garbage, before)
        "obj_huge.obj": (obj.replace("v 0.00000000 0.00000000 0.00000000", "v 1e308 -1e308 1e308").encode(), "a coordinate reaches 1e+308 mm"),
        "stl_huge.stl": (stl.replace("vertex 0.0 0.0 0.0", "vertex 1e200 0.0 0.0", 1).encode(), "a coordinate reaches 1e+200 mm"),
        "obj_nan.obj": (obj.replace("v 0.00000000 0.00000000 0.00000000", "v nan 0 0").encode(), "5 triangle(s) have NaN"),
        # declared counts larger than the content
        "off_count.off": (off.replace("8 12 0", "999999999 12 0").encode(), "OFF header declares 999999999 vertices"),
        "ply_count.ply": (ply.replace("element vertex 8", "element vertex 999999999").encode(), "PLY header declares 999999999 vertex"),
    }


CRAFTED = _crafted()


@pytest.mark.parametrize("name", sorted(CRAFTED))
def test_crafted_cases(tmp_path, name):
    data, expected = CRAFTED[name]
    p = _write(tmp_path, name, data)
    with pytest.raises(RotoprintError) as info:
        load_mesh(p)
    assert expected in str(info.value) and str(info.value).startswith(str(p)), str(info.value)
    _check_load(p)
