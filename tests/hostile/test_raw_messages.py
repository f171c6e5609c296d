"""Bad input files whose one-line error used to carry a library's raw exception text instead
of the problem in words of the file: Pillow's ``cannot identify image file <_io.BytesIO object
at 0x...>`` for a garbage or truncated image, the codec's ``'utf-8' codec can't decode bytes in
position 5-6`` for a machine program that is not text, ``Expecting value: line 1 column 1``
for an empty sidecar or program, and ezdxf's class name (``DXFStructureError: missing ENDSEC
tag``) for a truncated DXF. Each: exit 2, one line naming the file, no traceback, no output."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
GARBAGE = bytes((i * 197 + 13) % 256 for i in range(4000))


def _png_bytes() -> bytes:
    from rotoprint.io.images import png_bytes

    d = np.zeros((20, 30), np.uint8)
    d[4:16, 5:25] = 255
    return png_bytes(d)


def _one_line_naming(code: int, err: str, path: Path, said: str) -> None:
    assert code == 2, (code, err[-500:])
    assert err.strip().count("\n") == 0 and "Traceback" not in err, err
    assert path.name in err and said in err, err


@pytest.mark.parametrize("data, said", [
    (b"", "image file is empty"),
    (GARBAGE, "not in an image format Pillow reads"),
    (None, "not a readable image"),  # a PNG cut in its first chunk
], ids=["empty", "garbage", "truncated"])
def test_an_unreadable_design_image_is_one_line_without_pillows_object_text(run_cli, tmp_path, data, said):
    design = tmp_path / "design.png"
    design.write_bytes(_png_bytes()[:20] if data is None else data)  # the signature and IHDR are 33 bytes
    out = tmp_path / "print.png"
    code, _, err = run_cli("transform", design, "-d", "omnidot760", "--tilt", "20", "--radius", "60", "-o", out)
    _one_line_naming(code, err, design, said)
    assert "BytesIO" not in err and " at 0x" not in err
    assert not out.exists() and not (tmp_path / "print.json").exists()


@pytest.mark.parametrize("data, said", [
    (b"", "program is empty"),
    (b"  \n", "program is empty"),
    (GARBAGE, "program is not UTF-8 text (byte 5)"),
    (b'{"format": "\xff\xfe"}', "program is not UTF-8 text (byte 12)"),
], ids=["empty", "blank", "garbage", "latin1"])
def test_a_machine_program_that_is_empty_or_not_text_is_said_so(run_cli, tmp_path, data, said):
    prog = tmp_path / "m" / "program.json"
    prog.parent.mkdir()
    prog.write_bytes(data)
    out = tmp_path / "o.png"
    code, _, err = run_cli("replay", prog, "--out", out)
    _one_line_naming(code, err, prog, said)
    assert "codec" not in err and "Expecting value" not in err
    assert not out.exists()


def test_an_empty_print_sidecar_is_said_to_be_empty(run_cli, tmp_path):
    png = tmp_path / "p.png"
    png.write_bytes(_png_bytes())
    side = tmp_path / "p.json"
    side.write_bytes(b"")
    out = tmp_path / "o.png"
    code, _, err = run_cli("simulate", png, "-o", out)
    _one_line_naming(code, err, side, "sidecar is empty")
    assert "Expecting value" not in err and not out.exists()


@pytest.mark.parametrize("cut, said", [
    (3, "missing ENDSEC tag"),
    (None, "no DXF header (empty, or another kind of file)"),
], ids=["truncated", "garbage"])
def test_an_unreadable_dxf_is_one_line_without_ezdxfs_class_name(run_cli, tmp_path, cut, said):
    src = (EXAMPLES / "cad-coil" / "coil-body.dxf").read_bytes()
    dxf = tmp_path / "body.dxf"
    dxf.write_bytes(GARBAGE if cut is None else src[: len(src) // cut])
    code, _, err = run_cli("info", dxf)
    _one_line_naming(code, err, dxf, f"not a readable DXF file: {said}")
    assert "DXFStructureError" not in err and "Error:" not in err.split("error:", 1)[1]
