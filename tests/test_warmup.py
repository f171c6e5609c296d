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
