"""Issue 14's cost floor against the code of the day it was filed: "a pass's firing images cost at
most 2 x today's direct slicing of a layer". Today, for the issue, is main as it stood when it was
filed (``FILING`` = 00263d0, the last commit before the work of 2026-12-01, the day it was filed); later sessions
made the native layer itself faster (the direct fill by tiles and rows, the exact transform's
int32 landing index), which the other cost tables charge against the passes.

    PYTHONPATH=src python bench/film_cost_filing.py [TILTS] [--rounds=N] [--k=K] [--states=default,fresh,reused]

Both codes run in child processes, alternating, each round one child per code and memory state:
the filing-day code is exported from this checkout's git history (``git archive``) into a
temporary folder (its own numba cache there: the first call of each kernel is left out). Each
figure is the best of its rounds of ``K`` calls (default 5), the calling thread's CPU time
(``time.thread_time``, which counts the kernel's page faults), the exact maps' cache emptied and
``gc.collect()`` before each call.

**Memory states.** A layer's images are a few MB a swathe; whether their pages are new (a page
fault each 4 KiB, the kernel zeroing it) or reused depends on glibc malloc's state: a block freed
back to the system comes back as new pages. Measured on the native layer: 1784 faults a call and
~35 % of its time until some larger block has been freed, then none. So both codes are timed in
three states, set the same way for both (glibc's tunables, by environment):

- ``default``: glibc's own (its mmap threshold rises to the largest block freed so far, up to 32 MiB;
  what a user's process gets);
- ``fresh``: ``MALLOC_MMAP_THRESHOLD_=131072 MALLOC_TRIM_THRESHOLD_=0``: every large block is a
  new mapping, every call's images take new pages (a layer at a time in a long build, as the
  first call of any process);
- ``reused``: ``MALLOC_MMAP_THRESHOLD_=33554432 MALLOC_TRIM_THRESHOLD_=4294967296``: blocks up to
  32 MiB come from the heap and stay there, so a call reuses the pages the last one freed.

numpy asks for transparent huge pages on blocks of 4 MiB and more (``madvise``), so a pass's images
(8-11 MB a swathe at the equalised clock) take few faults in any state, a native layer's (2-3 MB
a swathe) a fault each 4 KiB when fresh. A direct slicing job writes a layer into the blocks of
the layers the caller dropped (:class:`rotoprint._buffers.ReusedBuffers`, since session 15), so
"the layer alone" reuses its pages in every state on this checkout; the filing-day code does not.

Rows, per state and tilt: the native layer of 1200 x 1200 px test design at 360 dpi (first column at
60 mm) by the exact transform and of ``sphere_openscad.stl``'s layer 1 (layer height a third of the
mesh) by the direct slicer, on the filing-day code and on this checkout; this checkout's default pass
of each (``pass_prints``' images per pass: maps, thinned sampling, edge restore; a real P-pass layer
of the direct slicer per pass, with the union's shares, as ``slice --rotary --passes`` prints it);
the ratios to both. The direct slicer twice: the whole call (``slice_rotary(...)`` and its
``layer(1)``: the job's set-up, device file, swathe plan, as a one-layer call pays) and the layer
alone (the job made once, as every layer of a build after the first).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
FILING = "00263d0"

STATES = {
    "default": {},
    "fresh": {"MALLOC_MMAP_THRESHOLD_": "131072", "MALLOC_TRIM_THRESHOLD_": "0"},
    "reused": {"MALLOC_MMAP_THRESHOLD_": "33554432", "MALLOC_TRIM_THRESHOLD_": "4294967296"},
}

# run by both codes: native transform, native layer (whole call, layer alone); this checkout also its passes
_CHILD = r"""
import gc, json, sys, time
from rotoprint import load_device
from rotoprint.io.mesh import load_mesh
from rotoprint.rotary import Placement, transform_exact
from rotoprint.rotary.direct import slice_rotary
from rotoprint.rotary.testimage import test_design
try:
    from rotoprint.rotary.exact import exact_maps
    clear = exact_maps.cache_clear
except (ImportError, AttributeError):
    clear = lambda: None
tilts, k, mesh_file, now = json.loads(sys.argv[1]), int(sys.argv[2]), sys.argv[3], sys.argv[4] == "now"
dev = load_device("omnidot760")  # (the filing day's slice_rotary takes a device, not its name)
head = dev.head
d = test_design(1200)
pl = Placement(1200, 1200, 25.4 / 360, 25.4 / 360, inner_radius_mm=60.0)
mesh = load_mesh(mesh_file)
h = float(mesh.bounds[1][2] - mesh.bounds[0][2])
clock = time.thread_time
def best(fn, first=True):
    if first:
        fn()  # compiles on the first call
    b = float("inf")
    for _ in range(k):
        clear(); gc.collect(); t = clock(); fn(); b = min(b, clock() - t)
    return b
if now:
    from film_acceptance import default_pass_cost
    from rotoprint.rotary.deposit import DepositOptions
    from rotoprint.rotary.direct import union_pass_shares
    from rotoprint.rotary.interlace import plan_passes
out = {}
for tilt in tilts:
    kw = dict(layer_height_mm=h / 3, tilt_deg=tilt, inner_radius_mm=60.0)
    job = slice_rotary(mesh, dev, **kw)
    row = {"transform": best(lambda: transform_exact(d, head, pl, tilt_deg=tilt)),
           "layer": best(lambda: slice_rotary(mesh, dev, **kw).layer(1)),
           "layer_alone": best(lambda: job.layer(1))}
    if now:
        row["pass_images"] = default_pass_cost(d, pl, head, tilt, k, clock)[0]
        pp = plan_passes(head, job.plan, footprint_um=DepositOptions().full_footprint_um(head))
        sh, clk = union_pass_shares(head, slice_rotary(mesh, dev, **kw, dpi_y=pp.dpi_y).plan, pp.offsets_mm, dpi_y=pp.dpi_y)[:2]
        args = [dict(kw, dpi_y=clk, pivot_offset_mm=o, shares=sh[q], pass_index=q) for q, o in enumerate(pp.offsets_mm)]
        jobs = [slice_rotary(mesh, dev, **a) for a in args]
        for j in jobs:
            j.layer(1)
        row["pass"] = best(lambda: [slice_rotary(mesh, dev, **a).layer(1) for a in args], first=False) / len(args)
        row["pass_alone"] = best(lambda: [j.layer(1) for j in jobs], first=False) / len(args)
    out[str(tilt)] = row
print(json.dumps(out))
"""


def _export(rev: str, dest: Path) -> Path:
    """``src/`` of ``rev`` from this checkout's git history into ``dest``; returns its ``src``."""
    repo = HERE.parent
    with tempfile.TemporaryFile() as tar:
        subprocess.run(["git", "-C", str(repo), "archive", "--format=tar", rev, "src"], stdout=tar, check=True)
        tar.seek(0)
        with tarfile.open(fileobj=tar) as t:
            t.extractall(dest, filter="data")
    return dest / "src"


def _run(label: str, code: str, env: dict, args: list, cwd: str) -> dict:
    res = subprocess.run([sys.executable, "-c", _CHILD, *args], env=env, capture_output=True, text=True, cwd=cwd)
    if res.returncode:
        sys.exit(f"film_cost_filing: {label} failed: {res.stderr.strip().splitlines()[-1:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tilts = [float(t) for t in args[0].split(",")] if args else [0.0, 20.0, 45.0, 70.0]
    opt = {a.split("=", 1)[0]: a.split("=", 1)[1] for a in sys.argv[1:] if a.startswith("--") and "=" in a}
    rounds, k = int(opt.get("--rounds", 2)), int(opt.get("--k", 5))
    states = opt.get("--states", "default,fresh,reused").split(",")
    if any(s not in STATES for s in states):
        sys.exit(f"film_cost_filing: --states takes {', '.join(STATES)}")
    mesh_file = next((q / "shared" / "data" / "meshes" / "sphere_openscad.stl" for q in HERE.parents
                      if (q / "shared" / "data" / "meshes" / "sphere_openscad.stl").is_file()), None)
    if mesh_file is None:
        sys.exit("film_cost_filing: shared/data/meshes/sphere_openscad.stl not found beside the checkout")
    here_src = HERE.parent / "src"
    best: dict = {}
    with tempfile.TemporaryDirectory(prefix="rotoprint-filing-") as tmp:
        old_src = _export(FILING, Path(tmp))
        child_args = [json.dumps(tilts), str(k), str(mesh_file)]
        for r in range(rounds):
            for st in states:
                base = dict(os.environ, OPENBLAS_NUM_THREADS="1", **STATES[st])
                for code, src, extra in (("filing", old_src, {"ROTOPRINT_NATIVE": "0"}), ("now", here_src, {})):
                    print(f"round {r + 1} of {rounds}, {st} pages: {'the filing-day code (' + FILING + ')' if code == 'filing' else 'this checkout'}",
                          file=sys.stderr, flush=True)
                    env = dict(base, PYTHONPATH=os.pathsep.join([str(src), str(HERE)]), **extra)
                    got = _run(f"the {code} code", code, env, [*child_args, code], tmp if code == "filing" else str(HERE.parent))
                    for t, row in got.items():
                        cell = best.setdefault((st, code, float(t)), {})
                        for key, v in row.items():
                            cell[key] = min(cell.get(key, float("inf")), v)
    print(f"\nfiling day: {FILING}; each figure the best of {rounds} rounds of {k} calls, thread CPU seconds\n")
    print("| pages | tilt deg | native transform, filing day | now | default pass's images | / filing day's | / now's | "
          "native layer, filing day: whole call | alone | now: whole call | alone | direct pass: whole call | alone | "
          "/ filing day's: whole | alone | / now's: whole | alone |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for st in states:
        for t in tilts:
            o, n = best[(st, "filing", t)], best[(st, "now", t)]
            print(f"| {st} | {t:g} | {o['transform']:.4f} | {n['transform']:.4f} | {n['pass_images']:.4f} | "
                  f"{n['pass_images'] / o['transform']:.2f} | {n['pass_images'] / n['transform']:.2f} | "
                  f"{o['layer']:.4f} | {o['layer_alone']:.4f} | {n['layer']:.4f} | {n['layer_alone']:.4f} | "
                  f"{n['pass']:.4f} | {n['pass_alone']:.4f} | {n['pass'] / o['layer']:.2f} | {n['pass_alone'] / o['layer_alone']:.2f} | "
                  f"{n['pass'] / n['layer']:.2f} | {n['pass_alone'] / n['layer_alone']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
