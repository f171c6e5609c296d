"""Rotary transforms: a 1200 x 1200 design at 360 dpi, 60 mm radius, head tilted 20 deg.

Peers in the same run: the per-pixel Python baseline of the same mapping (timed on a subset
of firings and extrapolated, said in the row) and OpenCV's warpPolar on the same image with
as many output samples. Ratios are "peer time / rotoprint exact (maps built + applied)".
"""

from __future__ import annotations

import time

import numpy as np

TITLE = "Rotary transforms (1200 x 1200 px, 360 dpi, radius 60 mm, tilt 20 deg, omnidot760)"


def _best(fn, reps):
    best = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


_CV2_SNIPPET = """
import sys, time, numpy as np, cv2
sys.path.insert(0, sys.argv[1])
from rotoprint.rotary.testimage import test_design
n, w, h, cx, cy, rmax, reps = int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), float(sys.argv[5]), float(sys.argv[6]), float(sys.argv[7]), int(sys.argv[8])
d = test_design(n)
for flag in (cv2.INTER_NEAREST, cv2.INTER_LINEAR):
    best = 1e9
    for _ in range(reps):
        t0 = time.perf_counter(); cv2.warpPolar(d, (w, h), (cx, cy), rmax, flag | cv2.WARP_POLAR_LINEAR); best = min(best, time.perf_counter() - t0)
    print(best)
"""


def run(quick: bool = False) -> list[dict]:
    import subprocess
    import sys
    from pathlib import Path

    from _baseline_rotary import transform_rows
    from rotoprint import load_device
    from rotoprint.rotary import Placement, exact_maps, transform_exact
    from rotoprint.rotary.paper import transform_paper
    from rotoprint.rotary.testimage import test_design

    n = 600 if quick else 1200
    px = 25.4 / 360
    head = load_device("omnidot760").head
    design = test_design(n)
    pl = Placement(n, n, px, px, inner_radius_mm=60.0)
    tilt = 20.0
    reps = 3 if quick else 7
    # warm the jit (compiled once per machine, cached on disk)
    transform_exact(design[:50, :50].copy(), head, Placement(50, 50, px, px, inner_radius_mm=60.0), tilt_deg=tilt)

    def full():
        exact_maps.cache_clear()
        return transform_exact(design, head, pl, tilt_deg=tilt)

    t_full = _best(full, reps)
    pr = full()
    samples = sum(s.levels.size for s in pr.swathes)
    maps = exact_maps(head, pl, tilt_deg=tilt)
    t_apply = _best(lambda: maps.apply(design), reps)

    def full_np():
        exact_maps.cache_clear()
        return transform_exact(design, head, pl, tilt_deg=tilt, kernel="numpy")

    t_np = _best(full_np, max(2, reps // 2))
    exact_maps.cache_clear()
    t_paper = _best(lambda: transform_paper(design, head, pl, tilt_deg=tilt), max(2, reps // 2))

    # per-pixel Python baseline on every 25th firing of every swathe, extrapolated; checked equal
    dl = design.tolist()
    step = 25
    t_base_sub = 0.0
    rows_done = 0
    rows_total = 0
    for sm, sw in zip(maps.swathes, pr.swathes):
        F = sw.levels.shape[0]
        rows = list(range(0, F, step))
        args = (dl, n, n, px, px, 60.0, sm.layout.r_mm.tolist(), sm.layout.phi_rad.tolist(), sm.enabled.tolist(),
                sm.first_firing, sm.dphi_rad, 1, rows)
        t0 = time.perf_counter()
        got = transform_rows(*args)
        t_base_sub += time.perf_counter() - t0
        for b in rows:
            if not np.array_equal(np.array(got[b], np.uint8), sw.levels[b]):
                raise AssertionError(f"baseline disagrees with the library at swathe {sw.index} firing row {b}")
        rows_done += len(rows)
        rows_total += F
    t_base = t_base_sub * rows_total / rows_done

    # OpenCV warpPolar: the same image, the axis as centre, as many output samples as our print
    r_max_px = float(np.hypot(60.0 / px + n, n / 2))
    w_rad = int(round(r_max_px))
    h_ang = max(1, int(round(samples / w_rad)))
    centre = (-60.0 / px, n / 2.0)
    # in its own process: importing cv2 beside numba's OpenMP layer slows numba's threads ~6x here
    import rotoprint

    src = str(Path(rotoprint.__file__).resolve().parents[1])
    res = subprocess.run(
        [sys.executable, "-c", _CV2_SNIPPET, src, str(n), str(w_rad), str(h_ang), str(centre[0]), str(centre[1]), str(r_max_px), str(reps)],
        check=True, capture_output=True, text=True,
    )
    t_cv, t_cv_lin = (float(v) for v in res.stdout.split())

    def row(name, t, note=""):
        return {"method": name, "time_ms": t * 1e3, "x faster than this": t_full and t / t_full, "note": note}

    import numba

    return [
        {"method": f"(numba {numba.__version__}, threading layer {numba.threading_layer()}, {numba.get_num_threads()} threads)", "time_ms": float("nan"), "x faster than this": float("nan"), "note": ""},
        row("rotoprint exact, maps built + applied (numba)", t_full, f"{len(pr.swathes)} swathes, {samples:,} nozzle-firings"),
        row("rotoprint exact, cached maps (next layer)", t_apply, "one gather per swathe"),
        row("rotoprint exact, numpy kernel", t_np, "same maps, no jit"),
        row("rotoprint paper method (polar + linear)", t_paper, "comparison mode"),
        row("per-pixel Python baseline", t_base, f"extrapolated from {rows_done} of {rows_total} firing rows ({100 * rows_done / rows_total:.0f} %), output checked equal"),
        row("OpenCV warpPolar, nearest", t_cv, f"{w_rad} x {h_ang} output (same sample count), polar step only, own process"),
        row("OpenCV warpPolar, linear", t_cv_lin, "same"),
    ]
