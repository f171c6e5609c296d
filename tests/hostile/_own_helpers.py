"""Helpers of the hostile-input tests: a snapshot of a folder tree, the one-line-error check."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path


def tree(root: Path) -> dict[str, bytes | None]:
    """Every path under ``root`` (relative, POSIX), hidden ones too: file bytes, None for folders."""
    root = Path(root)
    out: dict[str, bytes | None] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        for d in dirnames:
            out[(Path(dirpath) / d).relative_to(root).as_posix()] = None
        for f in filenames:
            p = Path(dirpath) / f
            out[p.relative_to(root).as_posix()] = p.read_bytes()
    return out


def one_line_error(code: int, err: str, *fragments: str) -> str:
    """Assert exit 2, exactly one line on stderr, no traceback, each fragment in it; returns the line."""
    assert code == 2, err
    lines = [ln for ln in err.strip().splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for f in fragments:
        assert f in lines[0], lines[0]
    return lines[0]


def strays(root: Path) -> list[str]:
    """Paths a run may leave behind by mistake: ``*.partial``, ``*.old``, ``*.part``, ``*.lock``."""
    return sorted(p for p in tree(root) if p.endswith((".partial", ".old", ".part", ".lock")))


def killed_run(cwd: Path, stage: str, *args: str, **env: str) -> None:
    """``rotoprint ARGS`` in a subprocess (in ``cwd``, ``env`` added) that SIGKILLs itself at the
    kill point ``stage`` (:func:`rotoprint.io.atomic.kill_point`); asserts it was killed there."""
    full_env = {**os.environ, "ROTOPRINT_TEST_KILL_AT": stage, **env}
    code = "import sys; from rotoprint.cli.main import main; sys.exit(main(sys.argv[1:]))"
    p = subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=cwd, env=full_env, capture_output=True, text=True,
                       timeout=120)
    assert p.returncode == -signal.SIGKILL, (p.returncode, p.stderr)
