"""The install warm-up from a cold numba cache: its time, and whether it compiles what
``rotoprint._warmup.WARMED`` says (issue 16).

    .venv/bin/python bench/warmup_cover.py

Runs ``python -m rotoprint._warmup`` with ``NUMBA_CACHE_DIR`` set to an empty temporary folder
(the worktree's own caches stay as they are, so this is a fresh clone's warm-up without a
clone), then lists the cache index files it wrote (one per compiled kernel) and compares them
with ``WARMED``. Prints wall time, the warm-up processes' CPU time and the load average; exits
1 when a listed kernel was not compiled or an unlisted one was. Slow (a cold compile of every
kernel: minutes on 2 cores), so not part of ``make bench``.
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def compiled_kernels(cache_dir: Path) -> set[tuple[str, str]]:
    """``(module file stem, kernel name)`` of every index file in ``cache_dir``
    (``chains.chain_components-36.py311.nbi``: one per compiled kernel)."""
    out = set()
    for f in cache_dir.rglob("*.nbi"):
        stem, rest = f.name.split(".", 1)
        out.add((stem, rest.split("-", 1)[0]))
    return out


def _key(module: str, name: str) -> tuple[str, str]:
    return module.rsplit(".", 1)[-1], name  # the kernels' module file stems are unique


def main() -> int:
    from rotoprint._warmup import NOT_WARMED, WARMED

    want = {_key(m, n) for m, names in WARMED.items() for n in names}
    with tempfile.TemporaryDirectory(prefix="rotoprint-cold-cache-") as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        load0 = os.getloadavg()
        t0 = time.perf_counter()
        r = subprocess.run([sys.executable, "-m", "rotoprint._warmup"], env=env)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        load1 = os.getloadavg()
        got = compiled_kernels(Path(cache))
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    print(f"warm-up from a cold cache: {wall:.0f} s wall, {cpu:.0f} s CPU (user + sys, both processes), "
          f"load average {load0[0]:.1f} -> {load1[0]:.1f}; exit {r.returncode}")
    not_warmed = {_key(*k.rsplit(".", 1)) for k in NOT_WARMED}
    missing = sorted(want - got)
    extra = sorted(got - want)
    print(f"kernels compiled: {len(got)}; listed in WARMED: {len(want)}")
    if missing:
        print("listed in WARMED but not compiled:", ", ".join(f"{s}.{n}" for s, n in missing))
    if extra:
        print("compiled but not in WARMED:", ", ".join(f"{s}.{n}" + (" (in NOT_WARMED)" if (s, n) in not_warmed else "")
                                                          for s, n in extra))
    return 1 if (missing or extra or r.returncode) else 0


if __name__ == "__main__":
    sys.exit(main())
