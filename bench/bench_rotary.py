"""Rotary transforms: a 1200 x 1200 design at 360 dpi, 60 mm radius, head tilted 20 deg.

Everything is measured in this one process, in this order: rotoprint (exact, cold and cached;
numpy kernel; paper method), the per-pixel Python baseline of the same mapping (timed on a
subset of firings, best of 3, and extrapolated, said in the row; its output checked equal to
the library's), then OpenCV's ``warpPolar`` on the same image with as many output samples, and
finally rotoprint's cold and cached figures again with ``cv2`` loaded (its kernels are
single-threaded numba, no OpenMP, so loading cv2 must not slow them).

Two ratio columns: "peer / cold" = that row's time / rotoprint exact with the maps built
(from scratch: swathe plan, maps, gather); "peer / cached" = that row's time / rotoprint exact
with the maps cached (the next layer of a job: same head, placement and design size).
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


def run(quick: bool = False) -> list[dict]:
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
    reps = 5 if quick else 25
    # warm the jit (compiled once per machine, cached on disk)
    transform_exact(design[:50, :50].copy(), head, Placement(50, 50, px, px, inner_radius_mm=60.0), tilt_deg=tilt)

    def cold():
        exact_maps.cache_clear()
        return transform_exact(design, head, pl, tilt_deg=tilt)

    def cached():
        return transform_exact(design, head, pl, tilt_deg=tilt)

    pr = cold()
    samples = sum(s.levels.size for s in pr.swathes)
    maps = exact_maps(head, pl, tilt_deg=tilt)
    looked_up = sum(sm.windows.n_drops for sm in maps.swathes)
    t_cold = _best(cold, reps)
    cached()
    t_cached = _best(cached, reps)

    def maps_only():
        exact_maps.cache_clear()
        return exact_maps(head, pl, tilt_deg=tilt)

    t_maps = _best(maps_only, reps)

    def cold_np():
        exact_maps.cache_clear()
        return transform_exact(design, head, pl, tilt_deg=tilt, backend="numpy")

    t_np = _best(cold_np, max(2, reps // 5))
    exact_maps.cache_clear()
    t_paper = _best(lambda: transform_paper(design, head, pl, tilt_deg=tilt), max(2, reps // 5))
    maps = exact_maps(head, pl, tilt_deg=tilt)

    # per-pixel Python baseline on every 25th firing of every swathe (best of 3), extrapolated; checked equal
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
        best = float("inf")
        for _ in range(1 if quick else 3):  # best of 3, like every other row (best of N)
            t0 = time.perf_counter()
            got = transform_rows(*args)
            best = min(best, time.perf_counter() - t0)
        t_base_sub += best
        for b in rows:
            if not np.array_equal(np.array(got[b], np.uint8), sw.levels[b]):
                raise AssertionError(f"baseline disagrees with the library at swathe {sw.index} firing row {b}")
        rows_done += len(rows)
        rows_total += F
    t_base = t_base_sub * rows_total / rows_done

    # OpenCV warpPolar: the same image, the axis as centre, as many output samples as our print.
    # It builds its maps inside every call, so each call is "cold".
    import cv2

    r_max_px = float(np.hypot(60.0 / px + n, n / 2))
    w_rad = int(round(r_max_px))
    h_ang = max(1, int(round(samples / w_rad)))
    centre = (-60.0 / px, n / 2.0)
    cv_threads = cv2.getNumThreads()

    def polar(flag):
        return cv2.warpPolar(design, (w_rad, h_ang), centre, r_max_px, flag | cv2.WARP_POLAR_LINEAR)

    t_cv = _best(lambda: polar(cv2.INTER_NEAREST), reps)
    t_cv_lin = _best(lambda: polar(cv2.INTER_LINEAR), reps)
    cv2.setNumThreads(1)
    t_cv1 = _best(lambda: polar(cv2.INTER_NEAREST), reps)
    cv2.setNumThreads(cv_threads)

    # rotoprint again, cv2 now loaded in this process
    t_cold2 = _best(cold, reps)
    cached()
    t_cached2 = _best(cached, reps)

    def row(name, t, note=""):
        return {"method": name, "time_ms": t * 1e3, "peer / cold": t / t_cold, "peer / cached": t / t_cached, "note": note}

    return [
        row("rotoprint exact, cold: plan + maps built + applied", t_cold,
            f"{len(pr.swathes)} swathes, {samples:,} nozzle-firings, {looked_up:,} looked up; single-threaded numba"),
        row("rotoprint exact, cached maps (next layer)", t_cached, "transform_exact, maps in its cache: one gather per swathe"),
        row("rotoprint exact, maps only (exact_maps)", t_maps,
            "swathe plan + per-track windows with exact ends; the index is filled by the first gather (cold row)"),
        row("rotoprint exact, cold, cv2 loaded", t_cold2, "same, measured after the OpenCV rows"),
        row("rotoprint exact, cached, cv2 loaded", t_cached2, "same"),
        row("rotoprint exact, numpy kernel, cold", t_np, "same maps and output, no jit"),
        row("rotoprint paper method (polar + linear)", t_paper, "comparison mode"),
        row("per-pixel Python baseline", t_base,
            f"extrapolated from {rows_done} of {rows_total} firing rows ({100 * rows_done / rows_total:.0f} %), output checked equal"),
        row("OpenCV warpPolar, nearest", t_cv, f"{w_rad} x {h_ang} output (same sample count), polar step only, {cv_threads} threads"),
        row("OpenCV warpPolar, linear", t_cv_lin, f"same, {cv_threads} threads"),
        row("OpenCV warpPolar, nearest, 1 thread", t_cv1, "cv2.setNumThreads(1)"),
    ]
