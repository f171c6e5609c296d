"""Direct rotary slicing against the two-step path, per layer, at equal output resolution.

Both paths start from the same cross-section (``SliceJob.segments``) and produce the same
print images (same head, tilt, placement, swathes, clock: the same drop lattice):

- *direct*: the circular-fibre kernel (``DirectSliceJob.print_from_segments``);
- *two-step*: the cross-section filled on a Cartesian bitmap at the head's native pitch (the
  slicer's fibre fill), then the exact transform with its maps already built and cached (one
  gather per swathe). Building the maps is timed separately (once per job).

Each side is run over the same layers, alternating, several times; the best run is kept.
The ratio is "two-step time / direct time" (above 1: direct is faster).
"""

from __future__ import annotations

import time
from pathlib import Path


TITLE = "Direct rotary slicing vs slice-to-bitmap + exact transform (omnidot760, per layer)"

MESHES = Path(__file__).resolve().parents[2] / "shared" / "data" / "meshes"


def _cases(quick):
    from rotoprint import load_mesh
    from rotoprint.testing import torus_mesh, uv_sphere_mesh

    cases = [
        ("torus R=10 r=3 mm, 12k tri", torus_mesh(10.0, 3.0, 192, 32), 40.0, 0.25),
        ("uv sphere r=20 mm, 80k tri", uv_sphere_mesh(20.0, 200, 200), 40.0, 0.5),
    ]
    sphere = MESHES / "sphere_openscad.stl"
    if sphere.exists():
        cases.append(("sphere_openscad.stl (100 mm)", load_mesh(sphere), 30.0, 2.0))
    return cases[:2] if quick else cases


def _best_alternating(fns, reps):
    best = [float("inf")] * len(fns)
    for _ in range(reps):
        for q, fn in enumerate(fns):
            t0 = time.perf_counter()
            fn()
            best[q] = min(best[q], time.perf_counter() - t0)
    return best


def run(quick: bool = False) -> list[dict]:
    from rotoprint import load_device
    from rotoprint.rotary import exact_maps
    from rotoprint.rotary.direct import rasterize_section, slice_rotary

    dev = load_device("omnidot760")
    rows = []
    reps = 2 if quick else 5
    for tilt in (0.0, 20.0):
        for name, mesh, radius, lh in _cases(quick):
            job = slice_rotary(mesh, dev, layer_height_mm=lh, tilt_deg=tilt, inner_radius_mm=radius)
            idx = list(range(0, len(job), max(1, len(job) // (10 if quick else 40))))
            segs = [job.slice_job.segments(i)[0] for i in idx]
            t0 = time.perf_counter()
            exact_maps.cache_clear()
            maps = exact_maps(dev.head, job.design, tilt_deg=tilt, dpi_y=job.dpi_y)
            t_maps = time.perf_counter() - t0
            job.print_from_segments(segs[0])  # jit warm-up
            maps.apply(rasterize_section(segs[0], job.part, job.design))

            def direct():
                for i, s in zip(idx, segs):
                    job.print_from_segments(s, layer_index=i)

            def two_step():
                for s in segs:
                    maps.apply(rasterize_section(s, job.part, job.design), kind="binary")

            def section():
                for i in idx:
                    job.slice_job.segments(i)

            t_d, t_2, t_s = _best_alternating([direct, two_step, section], reps)
            # same lattice, so the outputs can be compared drop for drop
            pr_d = job.print_from_segments(segs[len(segs) // 2])
            pr_2 = maps.apply(rasterize_section(segs[len(segs) // 2], job.part, job.design), kind="binary")
            same = all(a.dphi_rad == b.dphi_rad and a.pivot_radius_mm == b.pivot_radius_mm for a, b in zip(pr_d.swathes, pr_2.swathes))
            sites = sum(s.levels.size for s in pr_d.swathes)
            n = len(idx)
            rows.append({
                "case": name,
                "tilt deg": tilt,
                "swathes": len(job.tracks),
                "nozzle-firings / layer": sites,
                "bitmap px": job.design.width_px * job.design.height_px,
                "layers timed": n,
                "section ms": t_s / n * 1e3,
                "direct ms (incl. section)": (t_d + t_s) / n * 1e3,
                "two-step ms (incl. section)": (t_2 + t_s) / n * 1e3,
                "two-step / direct": (t_2 + t_s) / (t_d + t_s),
                "kernels only: two-step / direct": t_2 / t_d,
                "maps built once, ms": t_maps * 1e3,
                "same lattice": same,
            })
    return rows
