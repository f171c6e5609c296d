"""Running the CLI as a user would, in a subprocess bounded in time and address space."""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import rotoprint

#: Address space the CLI may map (numpy, numba and Pillow start in far less).
MEMORY_LIMIT_BYTES = 1536 << 20
#: A hang guard, not a speed target (those live in bench/): a blocking or endless read never
#: returns, so any generous bound catches it, while a loaded machine (the suite runs beside
#: other work) may take several times the idle start-up.
TIME_LIMIT_S = 120.0


#: The child imports the rotoprint this test process imported: a relative PYTHONPATH (``src``,
#: as the suite is run from a checkout) would name another folder from the child's cwd, and
#: the child would then run an installed copy instead of the code under test.
_SRC_PATH = os.pathsep.join([str(Path(rotoprint.__file__).resolve().parents[1]),
                             *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))])


@dataclass
class Run:
    code: int
    out: str
    err: str
    seconds: float
    maxrss_kib: int


def _limit_memory() -> None:  # runs in the child before exec
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT_BYTES, MEMORY_LIMIT_BYTES))


def run_cli_bounded(*args: str | Path, cwd: Path, timeout_s: float = TIME_LIMIT_S, env: dict | None = None) -> Run:
    """``python -m rotoprint.cli.main ARGS`` under RLIMIT_AS and a wall-clock timeout; a run
    that outlives the timeout fails the test (subprocess.TimeoutExpired)."""
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-m", "rotoprint.cli.main", *map(str, args)],
        cwd=cwd, capture_output=True, text=True, timeout=timeout_s, preexec_fn=_limit_memory,
        env={**os.environ, "NUMBA_DISABLE_JIT": os.environ.get("NUMBA_DISABLE_JIT", "0"), "PYTHONPATH": _SRC_PATH,
             **(env or {})},
        stdin=subprocess.DEVNULL,
    )
    dt = time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss  # max over children so far
    return Run(proc.returncode, proc.stdout, proc.stderr, dt, rss)


def assert_refused(run: Run, *fragments: str) -> str:
    """Exit 2, one line on stderr that starts 'rotoprint: error:', no traceback, fragments in it."""
    assert run.code == 2, (run.code, run.err[-2000:])
    lines = run.err.strip().splitlines()
    assert len(lines) == 1, run.err[-2000:]
    assert lines[0].startswith("rotoprint: error:"), lines[0]
    assert "Traceback" not in run.err
    for f in fragments:
        assert f in lines[0], (f, lines[0])
    return lines[0]


def tree(folder: Path) -> dict[str, bytes | None]:
    """Every path under ``folder`` with its content (None for folders and special files)."""
    out: dict[str, bytes | None] = {}
    for p in sorted(folder.rglob("*")):
        rel = str(p.relative_to(folder))
        out[rel] = p.read_bytes() if (p.is_file() and not p.is_symlink()) else None
    return out
