"""Scale: whole `rotoprint dlp` runs into SL1 archives, wall time and peak memory.

Each row runs the CLI in a fresh process (mesh loading, slicing, masks, PNG encoding, the zip);
peak memory is the largest sum of the resident sets of the process and all its workers,
sampled every 20 ms (shared libraries are counted once per process, so this overstates).
Models are UV spheres of 19 mm diameter; 1,000 layers of 19 um.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "bench" / "out"
TITLE = "Scale: rotoprint dlp -> SL1, whole runs (wall seconds, peak memory of all processes)"


def _tree_rss_kb(root: int) -> int:
    children: dict[int, list[int]] = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open(f"/proc/{d}/stat") as fh:
                    ppid = int(fh.read().rsplit(")", 1)[1].split()[1])
                children.setdefault(ppid, []).append(int(d))
            except (OSError, ValueError, IndexError):
                pass
    total, todo = 0, [root]
    while todo:
        pid = todo.pop()
        todo.extend(children.get(pid, []))
        try:
            with open(f"/proc/{pid}/status") as fh:
                for line in fh:
                    if line.startswith("VmRSS:"):
                        total += int(line.split()[1])
        except OSError:
            pass
    return total


def run_measured(cmd: list[str]) -> tuple[float, float]:
    """Wall seconds and peak MiB of the process tree of ``cmd``."""
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    peak = 0
    stop = threading.Event()

    def sample():
        nonlocal peak
        while not stop.is_set():
            peak = max(peak, _tree_rss_kb(proc.pid))
            time.sleep(0.02)

    th = threading.Thread(target=sample, daemon=True)
    th.start()
    _, err = proc.communicate()
    stop.set()
    th.join()
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed: {err.decode()[-500:]}")
    return wall, peak / 1024.0


def _sphere(n_tri_target: int) -> Path:
    from rotoprint.examples import write_binary_stl
    from rotoprint.testing import uv_sphere_mesh

    n_lat = max(8, int(round((n_tri_target / 4) ** 0.5)))
    path = OUT / f"sphere_{n_tri_target}.stl"
    if not path.exists():
        write_binary_stl(path, uv_sphere_mesh(9.5, n_lat, 2 * n_lat).triangles)
    return path


def _device(scale: float) -> Path:
    px, py = int(1400 * scale), int(1050 * scale)
    path = OUT / f"projector_{px}x{py}.toml"
    path.write_text(
        f'name = "sxga-x{scale:g}"\nkind = "projector"\n[projector]\npixels_x = {px}\npixels_y = {py}\n'
        f"width_mm = 27.77\nheight_mm = 20.83\n"
    )
    return path


def _dlp(mesh: Path, device: str, layers: int, workers: int, mode: str) -> tuple[float, float, int]:
    out = OUT / "scale.sl1"
    cmd = [sys.executable, "-m", "rotoprint.cli.main", "dlp", str(mesh), "-d", device, "--layer-height",
           f"{19.0 / layers:.9f}", "--mode", mode, "--workers", str(workers), "-q", "-o", str(out)]
    wall, peak = run_measured(cmd)
    return wall, peak, out.stat().st_size


def run(quick: bool = False) -> list[dict]:
    OUT.mkdir(parents=True, exist_ok=True)
    rows = []
    sxga = "perfactory-sxga"
    big = _sphere(1_000_000 if not quick else 100_000)
    layers = 1000 if not quick else 100
    for mode in ("coverage", "binary"):
        for workers in (2, 1):
            wall, peak, size = _dlp(big, sxga, layers, workers, mode)
            rows.append({"table": "headline", "triangles": big.stem.split("_")[1], "pixels": "1400x1050", "layers": layers,
                         "mode": mode, "workers": workers, "wall s": wall, "peak MiB": peak, "SL1 MB": size / 1e6})
    for n in ((10_000, 100_000, 1_000_000) if quick else (10_000, 30_000, 100_000, 300_000, 1_000_000)):
        wall, peak, size = _dlp(_sphere(n), sxga, 200, 2, "coverage")
        rows.append({"table": "triangles", "triangles": n, "pixels": "1400x1050", "layers": 200, "mode": "coverage",
                     "workers": 2, "wall s": wall, "peak MiB": peak, "SL1 MB": size / 1e6})
    for scale in (0.5, 1.0, 2.0) if not quick else (0.5, 1.0):
        dev = _device(scale)
        wall, peak, size = _dlp(_sphere(100_000), str(dev), 200, 2, "coverage")
        rows.append({"table": "resolution", "triangles": 100_000, "pixels": dev.stem.split("_")[1], "layers": 200,
                     "mode": "coverage", "workers": 2, "wall s": wall, "peak MiB": peak, "SL1 MB": size / 1e6})
    return rows


if __name__ == "__main__":
    for r in run(quick="--quick" in sys.argv):
        print(r)
