"""Compile and cache the jit kernels at install time: ``python -m rotoprint._warmup``.

numba keeps its cache in ``__pycache__`` next to the sources, so an editable install in a
fresh clone starts cold, and the first ``rotoprint demo`` / ``check`` / ``slice --rotary``
would spend a minute compiling. ``make`` runs this once after installing: the demo, a check
and a rotary slice of a small part and the DLP modes run in two processes at once (the
machine's cores), each compile shown as a line, and each kernel compiled by one of the two
only (:func:`share_compiles`). Later runs load the kernels from the cache.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path


def _commands(tmp: Path) -> list[list[list[str]]]:
    """Two groups of rotoprint commands (one per process), together touching every kernel."""
    from .examples import write_binary_stl
    from .testing import box_triangles, torus_mesh

    part = tmp / "part.stl"
    write_binary_stl(part, torus_mesh(4.0, 1.5, 48, 24).triangles)
    box = tmp / "box.stl"
    write_binary_stl(box, box_triangles((3.0, 2.0, 0.4)))
    a = [["demo", "--out", str(tmp / "demo")]]
    b = [
        ["check", str(part), "--device", "perfactory-sxga", "--layer-height", "0.5", "--json"],
        ["check", str(part), "--device", "omnidot760", "--layer-height", "0.5", "--json"],
        ["slice", str(part), "--device", "omnidot760", "--rotary", "--tilt", "20", "--radius", "60", "--angle", "0",
         "--layer-height", "0.5", "--out", str(tmp / "rot"), "--reference-images", "-q"],
        ["slice", str(part), "--device", "perfactory-sxga", "--layer-height", "0.5", "--out", str(tmp / "cart"), "-q"],
    ]
    for mode in ("binary", "smooth", "coverage"):
        b.append(["dlp", str(box), "--device", "perfactory-sxga", "--layer-height", "0.2", "--mode", mode,
                  "--first-layers", "1", "--first-layer-offset", "20", "--out", str(tmp / f"dlp-{mode}"), "-q"])
    return [a, b]


def share_compiles(lock_dir: str) -> None:
    """Let the warm-up processes compile each kernel once between them.

    Both processes run commands that touch some of the same kernels (the demo checks its
    parts, as ``rotoprint check`` does). Each kernel's compile is made to take an exclusive
    lock on ``lock_dir/<module>.<name>.lock`` first: the process that comes second waits, and
    numba's ``Dispatcher.compile`` then finds the kernel in the disk cache the first one
    wrote, and loads it instead of compiling it again. Kernels calling kernels take their
    locks in call order (callers before callees, and a call graph has no cycles), so two
    processes cannot wait on each other; a kernel already locked by this process (its own
    nested compiles) is not locked again.
    """
    import fcntl

    from numba.core.dispatcher import Dispatcher

    original = Dispatcher.compile
    held: set[str] = set()
    one_thread = threading.RLock()  # numba compiles one kernel at a time per process anyway

    def compile_once(self, sig):
        fn = self.py_func
        key = f"{fn.__module__}.{fn.__qualname__}"
        with one_thread:
            if key in held:
                return original(self, sig)
            with open(os.path.join(lock_dir, key + ".lock"), "w") as fh:
                fcntl.flock(fh, fcntl.LOCK_EX)
                held.add(key)
                try:
                    return original(self, sig)
                finally:
                    held.discard(key)
                    fcntl.flock(fh, fcntl.LOCK_UN)

    Dispatcher.compile = compile_once


def _run_group(cmds: list[list[str]], env: dict, lock_dir: str) -> tuple[subprocess.Popen, threading.Thread]:
    """Run ``cmds`` in one process; pass on only its compile lines (and, on failure, the rest)."""
    script = ";".join(f"rc = main({c!r}); rc and sys.exit(rc)" for c in cmds)
    code = (f"import sys; from rotoprint._warmup import share_compiles; share_compiles({lock_dir!r}); "
            f"from rotoprint.cli.main import main; {script}")
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, errors="replace")
    other: list[str] = []

    def relay() -> None:
        for line in proc.stderr:
            if line.startswith(("compiling jit kernel", "compiled ")):
                print("  " + line.rstrip(), flush=True)
            else:
                other.append(line)

    t = threading.Thread(target=relay, daemon=True)
    t.start()
    t.other = other  # type: ignore[attr-defined]
    return proc, t


def main() -> int:
    env = {**os.environ, "ROTOPRINT_COMPILE_NOTICE": "1"}
    t0 = time.perf_counter()
    print("rotoprint: compiling the jit kernels once (cached for every later run)...", flush=True)
    with tempfile.TemporaryDirectory(prefix="rotoprint-warmup-") as tmp:
        locks = Path(tmp) / "locks"
        locks.mkdir()
        runs = [_run_group(g, env, str(locks)) for g in _commands(Path(tmp))]
        codes = [p.wait() for p, _ in runs]
        for _, t in runs:
            t.join()
    if any(codes):
        for (_, t), c in zip(runs, codes):
            if c:
                sys.stderr.write("".join(t.other[-20:]))
        print(f"rotoprint: warm-up failed (exit codes {codes}); kernels will compile on first use", file=sys.stderr)
        return 1
    print(f"rotoprint: kernels ready in {time.perf_counter() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
