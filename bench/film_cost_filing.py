"""Issue 14's cost floor against the code of the day it was filed: "a pass's firing images cost at
most 2 x today's direct slicing of a layer". Today, for the issue, is main as it stood when it was
filed (``FILING`` = 00263d0, 2026-12-01, the last commit before the deposit model); later sessions
made the native layer itself faster (the direct fill by tiles and rows, the exact transform's
int32 landing index), which the other cost tables charge against the passes.

    PYTHONPATH=src python bench/film_cost_filing.py [TILTS] [--rounds=N] [--k=K]

The filing-day code is exported from this checkout's git history (``git archive``) into a temporary
folder and timed in a child process (its own numba cache there: the first call of each kernel is
left out), alternating with this checkout's passes in this process, ``N`` rounds (default 2), each
figure the best of its rounds of ``K`` calls (default 5), the calling thread's CPU time
(``time.thread_time``), the exact maps' cache emptied and ``gc.collect()`` before each call.

Rows, per tilt: the native layer of 1200 x 1200 px test design at 360 dpi (first column at 60 mm)
by the exact transform and of ``sphere_openscad.stl``'s layer 1 (layer height a third of the mesh)
by the direct slicer, on the filing-day code and on this checkout; this checkout's default pass of
each (``pass_prints``' images per pass: maps, thinned sampling, edge restore; a real P-pass layer
of the direct slicer per pass, with the union's shares, as ``slice --rotary --passes`` prints it);
the ratios to both.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tarfile
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
FILING = "00263d0"

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
tilts, k, mesh_file = json.loads(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
dev = load_device("omnidot760")  # (the filing day's slice_rotary takes a device, not its name)
head = dev.head
d = test_design(1200)
pl = Placement(1200, 1200, 25.4 / 360, 25.4 / 360, inner_radius_mm=60.0)
mesh = load_mesh(mesh_file)
h = float(mesh.bounds[1][2] - mesh.bounds[0][2])
def best(fn):
    fn()  # compiles on the first call
    b = float("inf")
    for _ in range(k):
        clear(); gc.collect(); t = time.thread_time(); fn(); b = min(b, time.thread_time() - t)
    return b
out = {}
for tilt in tilts:
    kw = dict(layer_height_mm=h / 3, tilt_deg=tilt, inner_radius_mm=60.0)
    out[str(tilt)] = (best(lambda: transform_exact(d, head, pl, tilt_deg=tilt)),
                      best(lambda: slice_rotary(mesh, dev, **kw).layer(1)))
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


def main() -> None:
    sys.path.insert(0, str(HERE))
    from film_acceptance import _best, default_pass_cost, direct_pass_layer

    from rotoprint import load_device
    from rotoprint.io.mesh import load_mesh
    from rotoprint.rotary import Placement, transform_exact
    from rotoprint.rotary.direct import slice_rotary
    from rotoprint.rotary.testimage import test_design

    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tilts = [float(t) for t in args[0].split(",")] if args else [0.0, 20.0, 45.0, 70.0]
    rounds = next((int(a.split("=", 1)[1]) for a in sys.argv[1:] if a.startswith("--rounds=")), 2)
    k = next((int(a.split("=", 1)[1]) for a in sys.argv[1:] if a.startswith("--k=")), 5)
    mesh_file = next((q / "shared" / "data" / "meshes" / "sphere_openscad.stl" for q in HERE.parents
                      if (q / "shared" / "data" / "meshes" / "sphere_openscad.stl").is_file()), None)
    if mesh_file is None:
        sys.exit("film_cost_filing: shared/data/meshes/sphere_openscad.stl not found beside the checkout")
    head = load_device("omnidot760").head
    d = test_design(1200)
    pl = Placement(1200, 1200, 25.4 / 360, 25.4 / 360, inner_radius_mm=60.0)
    mesh = load_mesh(mesh_file)
    h = float(mesh.bounds[1][2] - mesh.bounds[0][2])
    clock = time.thread_time
    inf = float("inf")
    old = {t: [inf, inf] for t in tilts}
    new = {t: [inf, inf, inf, inf] for t in tilts}  # native transform, native layer, default pass, direct pass
    with tempfile.TemporaryDirectory(prefix="rotoprint-filing-") as tmp:
        src = _export(FILING, Path(tmp))
        env = dict(os.environ, PYTHONPATH=str(src), ROTOPRINT_NATIVE="0", OPENBLAS_NUM_THREADS="1")
        for r in range(rounds):
            print(f"round {r + 1} of {rounds}: the filing-day code ({FILING})", file=sys.stderr, flush=True)
            res = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(tilts), str(k), str(mesh_file)], env=env,
                                 capture_output=True, text=True, cwd=tmp)
            if res.returncode:
                sys.exit(f"film_cost_filing: the filing-day code failed: {res.stderr.strip().splitlines()[-1:]}")
            for t, (a, b) in json.loads(res.stdout.strip().splitlines()[-1]).items():
                old[float(t)] = [min(old[float(t)][0], a), min(old[float(t)][1], b)]
            print(f"round {r + 1} of {rounds}: this checkout", file=sys.stderr, flush=True)
            for t in tilts:
                kw = dict(layer_height_mm=h / 3, tilt_deg=t, inner_radius_mm=60.0)
                img, layer, n_p, _ = default_pass_cost(d, pl, head, t, k, clock)
                _, tp, n_d = direct_pass_layer(mesh, head, kw, k, clock)
                got = (_best(lambda: transform_exact(d, head, pl, tilt_deg=t), k, clock),
                       _best(lambda: slice_rotary(mesh, "omnidot760", **kw).layer(1), k, clock), img, tp / n_d)
                new[t] = [min(x, y) for x, y in zip(new[t], got)]
    print(f"\n| tilt deg | native transform s, filing day ({FILING}) | now | default pass's images s | / filing day's | / now's | "
          "native layer (direct slicer) s, filing day | now | direct pass s | / filing day's | / now's |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for t in tilts:
        (ot, ol), (nt, nl, tp, dp) = old[t], new[t]
        print(f"| {t:g} | {ot:.4f} | {nt:.4f} | {tp:.4f} | {tp / ot:.2f} | {tp / nt:.2f} | {ol:.4f} | {nl:.4f} | {dp:.4f} | "
              f"{dp / ol:.2f} | {dp / nl:.2f} |", flush=True)


if __name__ == "__main__":
    main()
