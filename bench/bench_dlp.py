"""DLP masks: layers of an 80k-triangle model at 1400 x 1050 into an SL1 archive.

Each case runs in a fresh Python process, so its peak resident memory (ru_maxrss) is its own;
``rss_over_base_MiB`` is that peak minus the process's RSS after imports and model set-up.
Cases: exact coverage masks and binary masks through ``rotoprint`` (slice, raster, PNG,
zip), and trimesh + PIL (``section_multiplane`` then ``Path2D.rasterize``, which fills
polygons with PIL after rounding vertices to pixels, then PNG encoding). trimesh is timed
on a subset of layers and extrapolated linearly (marked in the table).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

TITLE = "DLP masks: 80k-triangle torus, 1400 x 1050 (perfactory-sxga), into SL1"
N_FULL = 1000
N_QUICK = 50
TRIMESH_SUBSET = 100


def _model():
    from rotoprint.testing import torus_mesh

    return torus_mesh(6.0, 3.0, 400, 100)  # 80,000 triangles, 18 x 18 x 6 mm


def _rss_mib() -> float:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _peak_mib() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _case(case: str, n_layers: int) -> dict:
    import numpy as np

    from rotoprint import load_device, slice_mesh
    from rotoprint.io.archives import JobInfo
    from rotoprint.pipeline import write_dlp_job
    from rotoprint.masks import MaskOptions, coverage_mask

    mesh = _model()
    dev = load_device("perfactory-sxga")
    height = float(mesh.bounds[1][2] - mesh.bounds[0][2])
    lh = height / n_layers
    # warm up the jit kernels (numba caches them on disk; this loads them)
    tiny = slice_mesh(mesh, dev, layer_height_mm=height / 2)
    s, e, _ = tiny.pixel_segments(0)
    coverage_mask(s, e, tiny.grid.shape)
    tiny.layer(0)
    base = _rss_mib()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        if case in ("coverage", "binary"):
            job = slice_mesh(mesh, dev, layer_height_mm=lh)
            opts = MaskOptions(mode=case)
            p = dev.projector
            info = JobInfo(
                job_name="bench", layer_height_mm=lh, layer_count=len(job), copies=1, width_px=job.grid.width,
                height_px=job.grid.height, pixel_x_mm=job.grid.pitch_x_mm, pixel_y_mm=job.grid.pitch_y_mm,
                mirror_x=False, mirror_y=False, orientation=p.orientation, exposure_s=p.exposure_s,
                first_exposure_s=p.first_exposure_s, first_exposure_layers=p.first_exposure_layers,
                printer_model=p.printer_model,
            )
            # what `rotoprint dlp` runs: masks journalled in .partial, then the SL1 assembled
            write_dlp_job(job, os.path.join(tmp, "bench.sl1"), info, opts)
            done = len(job)
            size = os.path.getsize(os.path.join(tmp, "bench.sl1"))
        else:  # trimesh + PIL on a subset of the same layers
            import trimesh

            from rotoprint.io.images import png_bytes

            job = slice_mesh(mesh, dev, layer_height_mm=lh)
            tm = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
            sub = min(TRIMESH_SUBSET, len(job))
            idx = np.linspace(0, len(job) - 1, sub).round().astype(int)
            heights = job.plan.z_slice_mm[idx]
            g = job.grid
            # the same placement: platform origin at the image centre, model centred (no rotation)
            tx, ty = g.translation_mm
            origin = np.array([-(g.width / 2) * g.pitch_x_mm - tx, -(g.height / 2) * g.pitch_y_mm - ty])
            sections = tm.section_multiplane(plane_origin=[0, 0, 0], plane_normal=[0, 0, 1], heights=list(heights))
            size = 0
            for sec in sections:
                if sec is None:
                    img = np.zeros((g.height, g.width), np.uint8)
                else:
                    im = sec.rasterize(pitch=g.pitch_x_mm, origin=origin, resolution=(g.width, g.height), fill=True)
                    img = (np.asarray(im, dtype=np.uint8) * 255)[::-1]
                size += len(png_bytes(np.ascontiguousarray(img)))
            done = sub
        sec_ = time.perf_counter() - t0
    return {"layers_run": done, "seconds": sec_, "peak_MiB": _peak_mib(), "rss_over_base_MiB": _peak_mib() - base, "bytes": size}


def run(quick: bool) -> list[dict]:
    n = N_QUICK if quick else N_FULL
    rows = []
    env = dict(os.environ)
    src = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "src")
    env["PYTHONPATH"] = src + os.pathsep + env.get("PYTHONPATH", "")
    for case in ("coverage", "binary", "trimesh+PIL"):
        out = subprocess.run([sys.executable, os.path.abspath(__file__), case, str(n)], capture_output=True, text=True, env=env)
        if out.returncode:
            raise RuntimeError(f"bench case {case} failed:\n{out.stderr}")
        r = json.loads(out.stdout.strip().splitlines()[-1])
        per = r["seconds"] / r["layers_run"]
        extrap = r["layers_run"] < n
        rows.append(
            {
                "case": case,
                "layers": n,
                "seconds": per * n,
                "ms_per_layer": 1000 * per,
                "timed_layers": r["layers_run"] if not extrap else f"{r['layers_run']} (extrapolated)",
                "peak_RSS_MiB": r["peak_MiB"],
                "RSS_over_setup_MiB": r["rss_over_base_MiB"],
                "output_MB": r["bytes"] / 1e6 * (n / r["layers_run"]),
            }
        )
    ref = rows[0]["seconds"]
    for r in rows:
        r["x_coverage_time"] = r["seconds"] / ref
    return rows


if __name__ == "__main__":
    print(json.dumps(_case(sys.argv[1], int(sys.argv[2]))))
