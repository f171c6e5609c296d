"""Machine folder: peak memory of writing a 1,000-layer job's machine/ against a 10-layer job's.

Each job is a 2 x 2 mm plaster box (two heads, one cycle per layer, omnidot760 at 360 dpi)
of 10 or 1,000 layers of 10 um, each in a fresh process. The job is planned and its first
layer made (numba compiled, tifffile imported) before ``tracemalloc`` starts, so the figures
are peaks of Python and numpy allocations above what the plan holds:

- *streamed*: :class:`MachineWriter` (packed files, TIFFs, program.json and program.txt,
  layer by layer: the layer's images, its design regions and steps) into a plain folder;
  the acceptance is this peak within 20 % of the 10-layer job's;
- *installed*: :func:`write_machine_folder`, the same plus the atomic install with its
  ownership marker (``rotoprint-output.json``, SHA-256 of every file: 5 files per layer
  here), which is made in bounded memory (``io/ownership.py``);
- *slice*: a ``rotoprint slice`` layer folder (:func:`rotoprint.pipeline.write_layer_folder`,
  journalled, one PNG per layer, installed with its marker) of a 3 x 3 x 3 mm box on the
  perfactory-sxga, 10 or 1,000 layers, the first layer sliced before measuring; with one
  slicing thread (the process on one CPU) and with two (10, 100 and 1,000 layers: whether both
  threads hold a layer at the same moment varies from run to run), the highest peak of three
  runs each.
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

TITLE = "Machine folder: peak memory against the layer count"

_CHILD = textwrap.dedent("""
    import json, sys, tempfile, time, tracemalloc
    from pathlib import Path
    from rotoprint.process import parse_job
    from rotoprint.process.plan import plan_job
    from rotoprint.machine.program import write_machine_folder
    n = int(sys.argv[1])
    d = {"job": {"name": "bench", "layer_height_mm": 0.01},
         "printer": {"device": "omnidot760", "tilt_deg": 20.0,
                     "heads": [{"name": "H1", "ink": "ammonium_sulphate"},
                               {"name": "H2", "ink": "calcium_chloride", "mount_angle_deg": 90.0}]},
         "placement": {"inner_radius_mm": 60.0},
         "parts": [{"name": "b", "material": "plaster", "priority": 1,
                    "shape": {"kind": "box", "size_mm": [2.0, 2.0, n * 0.01]}}],
         "process": {"cycles_per_layer": {"plaster": 1}}}
    plan = plan_job(parse_job(d, base_dir="."))
    assert len(plan) == n, len(plan)
    import tifffile  # noqa: F401 - imported before measuring
    from rotoprint.machine.program import MachineWriter
    plan.layer(0)  # compile and warm the slicer before measuring
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "s"
        tracemalloc.start()
        t0 = time.perf_counter()
        w = MachineWriter(plan, out)
        for i in range(n):
            sched = plan.layer(i)
            secs = plan.sections(i)
            w.add_layer(sched, {b.material: plan.reference_image(b.material, secs) for b in sched.blocks})
        tot = w.close()
        dt = time.perf_counter() - t0
        _, peak_s = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        size = sum(f.stat().st_size for f in out.rglob("*") if f.is_file())
        tracemalloc.start()
        write_machine_folder(plan, Path(tmp) / "m")
        _, peak_i = tracemalloc.get_traced_memory()
        tracemalloc.stop()
    print(json.dumps({"layers": n, "peak_mib": peak_s / 2**20, "installed_mib": peak_i / 2**20, "seconds": dt,
                      "steps": tot["steps"], "output_mb": size / 1e6}))
""")


_SLICE_CHILD = textwrap.dedent("""
    import json, os, sys, tempfile, time, tracemalloc
    from pathlib import Path
    from rotoprint.devices import load_device
    from rotoprint.pipeline import RunOptions, write_layer_folder
    from rotoprint.slicing import slice_mesh
    from rotoprint.testing import box_mesh
    n = int(sys.argv[1])
    if sys.argv[2] == "1":  # one CPU: the producer slices in one thread
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})
    dev = load_device("perfactory-sxga")
    job = slice_mesh(box_mesh((3.0, 3.0, 3.0)), dev, layer_height_mm=3.0 / n)
    assert len(job) == n, len(job)
    job.layer(0)  # compile and warm the slicer before measuring
    with tempfile.TemporaryDirectory() as tmp:
        tracemalloc.start()
        t0 = time.perf_counter()
        write_layer_folder(job, Path(tmp) / "s", device_name=dev.name, device=dev.model_dump(mode="json"), options={},
                           run=RunOptions())
        dt = time.perf_counter() - t0
        _, peak = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        files = sum(1 for f in (Path(tmp) / "s").iterdir())
    print(json.dumps({"layers": n, "peak_mib": peak / 2**20, "seconds": dt, "files": files}))
""")


SLICE_RUNS = 3


def _measure(n: int, child: str = _CHILD, *args: str) -> dict:
    r = subprocess.run([sys.executable, "-c", child, str(n), *args], capture_output=True, text=True, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


def run(quick: bool = False) -> list[dict]:
    big = 100 if quick else 1000
    small = _measure(10)
    large = _measure(big)
    rows = []
    for m in (small, large):
        rows.append({"layers": m["layers"], "steps": m["steps"], "seconds": round(m["seconds"], 2),
                     "ms / layer": round(1000 * m["seconds"] / m["layers"], 1), "output (MB)": round(m["output_mb"], 2),
                     "streamed peak (MiB)": round(m["peak_mib"], 2),
                     "streamed / 10 layers": round(m["peak_mib"] / small["peak_mib"], 3),
                     "installed peak (MiB)": round(m["installed_mib"], 2),
                     "installed / 10 layers": round(m["installed_mib"] / small["installed_mib"], 3)})
    # one slicing thread (one CPU), then two: with two, a run's peak depends on whether both
    # threads hold a layer's raster at the same moment, which a short run may never see; each
    # size runs SLICE_RUNS times, alternating, and its highest peak is kept
    for threads in ("1", "2"):
        sizes = (10, big) if threads == "1" else (10, 100, big)
        runs: dict[int, list] = {n: [] for n in sizes}
        for _ in range(SLICE_RUNS):
            for n in sizes:
                runs[n].append(_measure(n, _SLICE_CHILD, threads))
        s_small = max(runs[10], key=lambda m: m["peak_mib"])
        for n, ms in runs.items():
            m = max(ms, key=lambda m: m["peak_mib"])
            rows.append({"layers": n, "slice threads": int(threads), "slice layer folder: files": m["files"],
                         "seconds": round(min(x["seconds"] for x in ms), 2), "slice peak (MiB)": round(m["peak_mib"], 2),
                         "slice peaks of the runs": [round(x["peak_mib"], 2) for x in ms],
                         "slice / 10 layers": round(m["peak_mib"] / s_small["peak_mib"], 3)})
    return rows


if __name__ == "__main__":
    for r in run(quick="--quick" in sys.argv):
        print(r)
