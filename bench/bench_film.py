"""Issue 14's cost floor as a `make bench` row: a pass's firing images at the planned clock
(and its pivot offset) over today's print of a layer at the native clock, for the exact
transform of the bundled test design (360 dpi, first column at 60 mm) and for direct slicing
of one layer of a real mesh; and the default (equalised) pass at twice the planned clock,
thinned while sampled (``transform_exact(..., thin=ThinShares)``; its shares, once for all passes
and from the geometry only, timed apart as ``shares_s``; the edge restore that ``pass_prints`` adds
is timed by ``film_acceptance.py --passes-cost-only``); for the direct slicer also a real P-pass
layer's pass with the union's shares (``slice_default_pass_s``: what ``slice --rotary --passes``
prints; the shares, once per build and tilt, apart as ``slice_union_shares_s``). The
floor: ratio <= 2. The film figures themselves (uncovered, thinnest / mean, bins) are in
``bench/film_acceptance.py`` (minutes per tilt)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

TITLE = "Film: a pass's firing images against today's layer (issue 14 cost floor: ratio <= 2)"


def run(quick: bool = False) -> list[dict]:
    from film_acceptance import _best, default_shares, direct_pass_layer

    from rotoprint import load_device
    from rotoprint.io.mesh import load_mesh
    from rotoprint.rotary import Placement, plan_swathes, transform_exact
    from rotoprint.rotary.direct import slice_rotary
    from rotoprint.rotary.exact import ThinShares
    from rotoprint.rotary.interlace import EQUALISE_CLOCK_FACTOR, plan_passes
    from rotoprint.rotary.testimage import test_design

    head = load_device("omnidot760").head
    n = 600 if quick else 1200
    d = test_design(n)
    px = 25.4 / 360
    pl = Placement(n, n, px, px, inner_radius_mm=60.0)
    r_in, r_out = pl.radial_range_mm()
    # /work/shared beside the checkout (the main checkout or a worktree one level deeper)
    mesh_file = next((q / "shared" / "data" / "meshes" / "sphere_openscad.stl" for q in Path(__file__).resolve().parents[1:4]
                      if (q / "shared" / "data" / "meshes" / "sphere_openscad.stl").is_file()), Path("sphere_openscad.stl"))
    mesh = load_mesh(mesh_file) if mesh_file.is_file() else None
    rows = []
    for tilt in ((0.0, 20.0) if quick else (0.0, 20.0, 45.0, 70.0)):
        sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
        pp = plan_passes(head, sp, footprint_um=49.6)
        off = pp.offsets_mm[-1]
        t0 = _best(lambda: transform_exact(d, head, pl, tilt_deg=tilt), 7)
        t1 = _best(lambda: transform_exact(d, head, pl, tilt_deg=tilt, dpi_y=pp.dpi_y, pivot_offset_mm=off), 7)
        dpi_e = pp.dpi_y * EQUALISE_CLOCK_FACTOR

        def shares():
            return default_shares(head, sp, pp, tilt)

        fr = shares()
        thin = ThinShares(fr[-1], len(fr) - 1)
        te = _best(lambda: transform_exact(d, head, pl, tilt_deg=tilt, dpi_y=dpi_e, pivot_offset_mm=off, thin=thin), 7)
        tf = _best(shares, 3)
        row = {"tilt_deg": tilt, "passes": pp.passes, "clock_dpi": pp.dpi_y, "transform_native_s": t0,
               "transform_pass_s": t1, "transform_ratio": t1 / t0, "equalised_clock_dpi": dpi_e,
               "transform_equalised_pass_s": te, "equalised_ratio": te / t0, "shares_s": tf,
               "equalised_ratio_with_shares_per_pass": (te + tf / pp.passes) / t0}
        if mesh is not None:
            h = float(np.ptp(np.asarray(mesh.vertices)[:, 2]))
            kw = dict(layer_height_mm=h / 3, tilt_deg=tilt, inner_radius_mm=60.0)
            s0 = _best(lambda: slice_rotary(mesh, "omnidot760", **kw).layer(1), 7)
            s1 = _best(lambda: slice_rotary(mesh, "omnidot760", **kw, dpi_y=pp.dpi_y, pivot_offset_mm=off).layer(1), 7)
            s2 = _best(lambda: slice_rotary(mesh, "omnidot760", **kw, dpi_y=dpi_e, pivot_offset_mm=off).layer(1), 7)
            tu, tp, n_p = direct_pass_layer(mesh, head, kw, 5)
            row.update({"slice_layer_native_s": s0, "slice_layer_pass_s": s1, "slice_ratio": s1 / s0,
                        "slice_layer_equalised_clock_s": s2, "slice_equalised_ratio": s2 / s0,
                        "slice_passes": n_p, "slice_default_pass_s": tp / n_p, "slice_default_pass_ratio": tp / n_p / s0,
                        "slice_union_shares_s": tu})
        rows.append(row)
    return rows
