"""User strings reach the terminal with their control characters escaped.

The CLI runs in a subprocess with pipes (rich adds no colour codes then), so any ESC byte in
its output came from a user string: there must be none.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from _bounds_helpers import assert_refused, run_cli_bounded
from rotoprint.cli._common import escape_controls
from rotoprint.examples import write_binary_stl
from rotoprint.testing import box_triangles

CLEAR = "\x1b[2J"


def test_escape_controls():
    assert escape_controls("plain name.stl") == "plain name.stl"
    assert escape_controls(f"a{CLEAR}b\x07c\x9bd\u202ee\x7f") == "a\\x1b[2Jb\\x07c\\x9bd\\u202ee\\x7f"
    assert escape_controls("two\nlines\tx") == "two\\x0alines\\x09x"
    assert escape_controls("two\nlines\tx", keep_newlines=True) == "two\nlines\tx"
    assert escape_controls("bad\udcffbyte") == "bad\\udcffbyte"
    assert escape_controls("caf\u00e9 \u00a0 \u4e2d") == "caf\u00e9 \u00a0 \u4e2d"


@pytest.mark.parametrize("name", [f"{CLEAR}box.stl", "new\nline.stl", "bell\x07.stl", "rtl\u202elts.stl"])
def test_error_naming_a_hostile_file_is_one_escaped_line(tmp_path, name):
    run = run_cli_bounded("info", name, cwd=tmp_path)
    line = assert_refused(run, escape_controls(name), "no such file")
    assert "\x1b" not in run.err and "\x07" not in run.err and "\u202e" not in run.err
    assert line.count("\n") == 0


def test_non_utf8_file_name_is_printed_escaped(tmp_path):
    raw = os.fsencode(tmp_path) + b"/caf\xe9.stl"
    with open(raw, "wb") as fh:  # noqa: PTH123 - a bytes path on purpose
        fh.write(b"garbage")
    proc = subprocess.run([sys.executable, "-m", "rotoprint.cli.main", "info", raw], capture_output=True, timeout=120)  # a hang guard
    err = proc.stderr.decode("utf-8")  # valid UTF-8: the odd byte is shown as \udce9
    assert proc.returncode == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "caf\\udce9.stl" in err


def test_output_naming_a_hostile_file_has_no_raw_escape(tmp_path):
    name = f"{CLEAR}box.stl"
    write_binary_stl(tmp_path / name, box_triangles((2, 2, 2)))
    run = run_cli_bounded("info", name, cwd=tmp_path, timeout_s=60)
    assert run.code == 0, run.err
    assert "\x1b" not in run.out + run.err
    out = f"{CLEAR}out"
    run = run_cli_bounded("slice", name, "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", out, "-v",
                          cwd=tmp_path, timeout_s=60)
    assert run.code == 0, run.err
    assert "\x1b" not in run.out + run.err
    assert "\\x1b[2Jout" in run.out + run.err


def test_logged_file_names_are_escaped(tmp_path):
    import logging

    from rotoprint.cli._common import _SafeFormatter

    rec = logging.LogRecord("x", logging.INFO, __file__, 1, "reading %s", (f"{CLEAR}m.stl",), None)
    assert _SafeFormatter("%(message)s").format(rec) == "reading \\x1b[2Jm.stl"
