"""Acceptance table of the direct rotary slicer (issue 4); prints a markdown table.

    PYTHONPATH=src python bench/direct_acceptance.py

For every mesh and tilt, on the middle layer (and, for the exactness column, three layers):

- *shapely*: random drop sites checked against "landing point inside the exact cross-section"
  (trimesh + shapely, independent of rotoprint): mismatches farther than 1e-6 mm from the
  boundary (must be 0);
- *two-step*: the same layer sliced to a Cartesian bitmap (native head pitch, and 4x finer;
  2x for the 100 mm sphere), then the exact transform, on the same drop lattice: sites that
  differ from the direct print, and the farthest of them from the boundary in units of
  max(firing step, track pitch) (must be <= 1);
- *IoU*: the simulator's cell-model IoU against the exact cross-section rasterised by shapely
  on a grid 2x finer than the head's (4x for the 3 mm donut).

Then the density spread with and without equalisation on a 40 mm box at 20..60 mm (3:1).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests" / "rotary"))

from _direct_checks import compare_sites, iou_pair, section_geom, shapely_mismatches, two_step  # noqa: E402

from rotoprint import load_device, load_mesh  # noqa: E402
from rotoprint.rotary.direct import slice_rotary  # noqa: E402
from rotoprint.testing import box_mesh, cylinder_mesh, torus_mesh  # noqa: E402

MESHES = HERE.parents[1] / "shared" / "data" / "meshes"


def main() -> None:
    dev = load_device("omnidot760")
    cases = [
        ("box 20x12x2", box_mesh((20.0, 12.0, 2.0)), 1.0, 40.0, 4, 2),
        ("cylinder r=8", cylinder_mesh(8.0, 2.0, 96), 1.0, 40.0, 4, 2),
        ("torus 10/3", torus_mesh(10.0, 3.0, 96, 32), 1.0, 40.0, 4, 2),
        ("half_donut_ascii.stl", load_mesh(MESHES / "half_donut_ascii.stl"), 0.5, 40.0, 4, 4),
        ("sphere_openscad.stl (100 mm)", load_mesh(MESHES / "sphere_openscad.stl"), 10.0, 30.0, 2, 2),
    ]
    print("| mesh | tilt | swathes | sites checked (shapely) | mismatches > 1e-6 mm | sites != two-step 1x | worst (steps) | "
          "sites != two-step fine | worst (steps) | IoU direct | IoU two-step 1x | IoU two-step fine |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, mesh, lh, radius, fine, ev in cases:
        for tilt in (0.0, 20.0):
            job = slice_rotary(mesh, dev, layer_height_mm=lh, tilt_deg=tilt, inner_radius_mm=radius, angle_deg=15.0)
            n_chk = n_bad = 0
            for L in sorted({0, len(job) // 2, len(job) - 1}):
                c, b, w = shapely_mismatches(job, job.layer(L), section_geom(job, L), n_random=50_000, seed=L)
                n_chk += c
                n_bad += int(b and w > 1e-6)
            L = len(job) // 2
            pr = job.layer(L)
            g = section_geom(job, L)
            p1, _, _ = two_step(job, L, oversample=1)
            pf, _, _ = two_step(job, L, oversample=fine)
            d1 = compare_sites(job, pr, p1, g)
            df = compare_sites(job, pr, pf, g)
            iou = iou_pair(job, [pr, p1, pf], g, oversample=ev)
            print(f"| {name} | {tilt:g} | {len(job.tracks)} | {n_chk} | {n_bad} | {d1[0]} | {d1[1]:.3f} | {df[0]} ({fine}x) | {df[1]:.3f} | "
                  f"{iou[0]:.5f} | {iou[1]:.5f} | {iou[2]:.5f} |", flush=True)
    # equalisation
    sys.path.insert(0, str(HERE.parent / "tests" / "rotary"))
    from shapely.geometry import box

    from test_direct import _density_per_bin

    print("\n| tilt | density spread without | with equalisation | expected (manifest) without | with |")
    print("|---|---|---|---|---|")
    for tilt in (0.0, 20.0):
        res = {}
        for eq in (False, True):
            job = slice_rotary(box_mesh((40.0, 10.0, 0.5)), dev, layer_height_mm=0.5, tilt_deg=tilt, inner_radius_mm=20.0, equalise=eq)
            x0, y0 = job.part.model_to_platform(np.array([0.0, 40.0]), np.array([0.0, 10.0]))
            dens = _density_per_bin(job, job.layer(0), box(x0[0], y0[0], x0[1], y0[1]), 8)
            res[eq] = dens.max() / dens.min() - 1.0
        print(f"| {tilt:g} | {100 * res[False]:.2f} % | {100 * res[True]:.2f} % | {100 * job.density_spread(equalised=False):.1f} % | "
              f"{100 * job.density_spread(equalised=True):.2f} % |")


if __name__ == "__main__":
    main()
