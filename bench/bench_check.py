"""Printability check time against slicing time, for the same part and layers.

The check slices every layer itself (the image and the exact section come from one pass), then
measures walls and gaps on the section, compares them with the image and looks for islands. The
floor set by issue 6: a check takes at most twice the time of slicing alone. The two sides
alternate over several rounds and each keeps its best time.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

TITLE = "Printability: check time vs slicing time (same part, same layers)"

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes"


def _best_alternating(fns, rounds: int) -> list[float]:
    """Best time of each function over ``rounds`` rounds, the functions alternating within a
    round (so that a load that comes and goes hits both sides alike)."""
    best = [float("inf")] * len(fns)
    for _ in range(rounds):
        for k, fn in enumerate(fns):
            t = time.perf_counter()
            fn()
            best[k] = min(best[k], time.perf_counter() - t)
    return best


def _cases(quick: bool):
    from rotoprint import load_mesh
    from rotoprint.mesh import Mesh
    from rotoprint.pieces import feature_test_piece

    piece = Mesh.from_triangles(feature_test_piece()[0])
    yield "feature piece (10 mm, 55k segments/layer)", piece, "perfactory-sxga", 0.1 if not quick else 0.4, {}
    yield "feature piece (10 mm, 55k segments/layer)", piece, "omnidot760", 0.1 if not quick else 0.4, {}
    # tilted 5 degrees about x: no side wall is vertical, every layer's section differs
    a = np.radians(5.0)
    rot = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(a), -np.sin(a)], [0.0, np.sin(a), np.cos(a)]])
    tilted = Mesh.from_triangles(feature_test_piece()[0] @ rot.T)
    yield "feature piece tilted 5 deg", tilted, "perfactory-sxga", 0.1 if not quick else 0.4, {}
    # the same on the section as sliced (no simplification): the exact path
    yield "feature piece, resolution 0", piece, "perfactory-sxga", 0.1 if not quick else 0.4, {"resolution_mm": 0.0}
    if (SHARED / "sphere_openscad.stl").exists():
        yield "sphere_openscad (100 mm)", load_mesh(SHARED / "sphere_openscad.stl"), "omnidot760", 1.0 if not quick else 5.0, {}
        yield "teapot_open (63 mm)", load_mesh(SHARED / "teapot_open.stl"), "omnidot760", 0.5 if not quick else 3.0, {}
        yield "half_donut (3 mm)", load_mesh(SHARED / "half_donut_ascii.stl"), "perfactory-sxga", 0.05 if not quick else 0.25, {}


def run(quick: bool) -> list[dict]:
    from rotoprint.check import check_printability
    from rotoprint.check.limits import default_minimum_mm
    from rotoprint.devices import load_device
    from rotoprint.slicing import slice_mesh

    rows = []
    rounds = 1 if quick else 7
    for name, mesh, dev_name, lh, opts in _cases(quick):
        dev = load_device(dev_name)
        job = slice_mesh(mesh, dev, layer_height_mm=lh)
        # warm the jit caches on one layer
        job.layer(0)
        check_printability(slice_mesh(mesh, dev, layer_height_mm=lh * max(1, len(job))), dev, **opts)

        def slice_all():
            j = slice_mesh(mesh, dev, layer_height_mm=lh)
            for i in range(len(j)):
                j.layer(i)

        def check_all():
            check_printability(slice_mesh(mesh, dev, layer_height_mm=lh), dev, **opts)

        # slicing: every layer's image (what a print needs); check: the whole check of the same
        # layers on the same device (it slices each layer itself, once)
        t_slice, t_check = _best_alternating([slice_all, check_all], rounds)
        rep = check_printability(slice_mesh(mesh, dev, layer_height_mm=lh), dev, **opts)
        rows.append(
            {
                "part": name,
                "device": dev_name,
                "layers": len(job),
                "grid_px": f"{job.grid.width}x{job.grid.height}",
                "min_um": round(default_minimum_mm(dev)[0] * 1000, 1),
                "res_um": round(rep.settings["resolution_mm"] * 1000, 3),
                "slice_s": t_slice,
                "check_s": t_check,
                "check/slice": t_check / t_slice,
                "findings": len(rep.findings),
            }
        )
    return rows
