"""A jit compile prints a progress line (issue 16): the numba compile event is relayed."""

from __future__ import annotations

import io
import subprocess
import sys


def test_a_compile_prints_a_line_and_a_cache_hit_prints_nothing(tmp_path):
    # a fresh process: the notice is installed before numba is imported (the import hook)
    code = (
        "import io\n"
        "from rich.console import Console\n"
        "from rotoprint import _jitnotice\n"
        "buf = io.StringIO(); con = Console(file=buf, force_terminal=False)\n"
        "_jitnotice.install(con)\n"
        "from numba import njit\n"
        "@njit\n"
        "def twice(x):\n"
        "    return 2 * x\n"
        "assert twice(21) == 42\n"
        "assert twice(4) == 8\n"  # same signature: no second compile
        "_jitnotice.finish(con)\n"
        "print(buf.getvalue())\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env={"ROTOPRINT_COMPILE_NOTICE": "1", "PATH": "/usr/bin:/bin"}, cwd=tmp_path, check=True).stdout
    lines = [ln for ln in out.splitlines() if ln.strip()]
    assert len(lines) == 2, out
    assert lines[0].startswith("compiling jit kernel 1: __main__.twice")
    assert lines[1].startswith("compiled 1 jit kernel(s) in ")


def test_silent_off_a_terminal_without_the_variable(monkeypatch):
    from rich.console import Console

    from rotoprint import _jitnotice

    monkeypatch.delenv("ROTOPRINT_COMPILE_NOTICE", raising=False)
    monkeypatch.setitem(_jitnotice._STATE, "installed", False)
    con = Console(file=io.StringIO(), force_terminal=False)
    _jitnotice.install(con)
    assert _jitnotice._STATE["installed"] is False  # nothing installed: scripts' output unchanged
