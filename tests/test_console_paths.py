"""Paths in the CLI's messages are printed whole where the output is not a terminal (a pipe, a
CI log): rich wraps at 80 columns there, and a path a user copies must not come with a newline
in it (rotoprint.cli._console)."""

from __future__ import annotations

import io
import os
import subprocess
import sys

import numpy as np

CLI = "import sys; from rotoprint.cli.main import main; sys.exit(main(sys.argv[1:]))"


def test_a_long_output_path_is_printed_whole_through_a_pipe(tmp_path):
    from PIL import Image

    design = np.zeros((20, 30), np.uint8)
    design[4:16, 5:25] = 255
    Image.fromarray(design).save(tmp_path / "d.png")
    folder = tmp_path / ("a-long-folder-name-" * 4) / ("nested-" * 8)
    folder.mkdir(parents=True)
    out = folder / "PRINT.png"
    env = {k: v for k, v in os.environ.items() if k not in ("COLUMNS", "LINES", "FORCE_COLOR", "TTY_COMPATIBLE")}
    r = subprocess.run([sys.executable, "-c", CLI, "transform", str(tmp_path / "d.png"), "-d", "omnidot760",
                        "--tilt", "20", "--radius", "60", "-o", str(out)],
                       stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    sidecar = str(folder / "PRINT.json")
    assert len(sidecar) > 120 and (folder / "PRINT.json").is_file()
    lines = (r.stdout + r.stderr).splitlines()
    assert any(sidecar in line for line in lines), lines  # the "sidecar: ..." line, unbroken


def test_a_terminal_still_wraps_at_its_width():
    """Soft wrap only off a terminal: on one, rich wraps at the terminal's width as before."""
    from rotoprint.cli._console import _SafeConsole

    text = "word " * 30
    pipe = _SafeConsole(file=io.StringIO(), width=40, force_terminal=False)
    tty = _SafeConsole(file=io.StringIO(), width=40, force_terminal=True, color_system=None)
    assert pipe.soft_wrap and not tty.soft_wrap
    pipe.print(text)
    tty.print(text)
    assert len(pipe.file.getvalue().splitlines()) == 1
    assert len(tty.file.getvalue().splitlines()) > 1
    assert max(len(ln) for ln in tty.file.getvalue().splitlines()) <= 40
