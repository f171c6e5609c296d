"""The install warm-up: a kernel is compiled by one of its processes only (issue 16)."""

from __future__ import annotations

import fcntl
import subprocess
import sys
import time

KERNEL = "from numba import njit\n\n\n@njit(cache=True)\ndef bump(x):\n    return x + 1\n"

PROBE = """
import sys
sys.path.insert(0, {folder!r})
from rotoprint._warmup import share_compiles
share_compiles({locks!r})
from numba.core import event

compiled = []


class Count(event.Listener):
    def on_start(self, ev):
        compiled.append(1)

    def on_end(self, ev):
        pass


event.register("numba:compile", Count())
import warmup_probe_kernel

print("ready", flush=True)
assert warmup_probe_kernel.bump(1) == 2
print(len(compiled), flush=True)
"""


def test_second_process_waits_and_loads_the_kernel_the_first_compiled(tmp_path):
    """The probe process reaches the kernel's compile while this process holds its lock; this
    process compiles and caches the kernel, then lets go: the probe must load it from the
    cache (0 compiles). Without the lock it would compile the kernel itself (1)."""
    (tmp_path / "warmup_probe_kernel.py").write_text(KERNEL)
    locks = tmp_path / "locks"
    locks.mkdir()
    script = PROBE.format(folder=str(tmp_path), locks=str(locks))
    with open(locks / "warmup_probe_kernel.bump.lock", "w") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)
        probe = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                 text=True)
        assert probe.stdout.readline().strip() == "ready"
        time.sleep(0.5)  # the probe is now at the kernel's compile (waiting on the lock)
        sys.path.insert(0, str(tmp_path))
        try:
            import warmup_probe_kernel

            assert warmup_probe_kernel.bump(1) == 2  # compiled and cached here
        finally:
            sys.path.remove(str(tmp_path))
            sys.modules.pop("warmup_probe_kernel", None)
        fcntl.flock(fh, fcntl.LOCK_UN)
    out, err = probe.communicate(timeout=120)
    assert probe.returncode == 0, err[-2000:]
    assert out.split() == ["0"], (out, err[-2000:])


def _cached_kernels() -> set[str]:
    """``module.name`` of every ``@njit(cache=True, ...)`` function in the sources that is not
    inlined (an inlined kernel has no cache file of its own)."""
    import ast
    from pathlib import Path

    import rotoprint

    root = Path(rotoprint.__file__).parent
    found = set()
    for path in root.rglob("*.py"):
        mod = ".".join(path.relative_to(root.parent).with_suffix("").parts)
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.FunctionDef):
                continue
            for d in node.decorator_list:
                if isinstance(d, ast.Call) and getattr(d.func, "id", getattr(d.func, "attr", "")) == "njit":
                    kw = {k.arg: getattr(k.value, "value", None) for k in d.keywords}
                    if kw.get("cache") is True and kw.get("inline", "never") != "always":
                        found.add(f"{mod}.{node.name}")
    return found


def test_every_cached_kernel_is_warmed_or_says_why_not():
    """A new jit kernel must be reached by a warm-up command (then listed in WARMED, checked by
    bench/warmup_cover.py against a cold warm-up) or listed in NOT_WARMED with the reason no
    user's first command reaches it: otherwise that first command compiles it."""
    from rotoprint._warmup import NOT_WARMED, WARMED

    warmed = {f"{m}.{n}" for m, names in WARMED.items() for n in names}
    found = _cached_kernels()
    assert len(found) > 60  # the scan sees the kernels (71 when this was written)
    assert not warmed & set(NOT_WARMED), warmed & set(NOT_WARMED)
    assert found - warmed - set(NOT_WARMED) == set(), "kernels in neither rotoprint._warmup.WARMED nor NOT_WARMED"
    assert (warmed | set(NOT_WARMED)) - found == set(), "listed in rotoprint._warmup but not a cached kernel"
    assert all(len(why) > 20 for why in NOT_WARMED.values())
