"""Film acceptance of issue 14 as markdown tables (docs/rotary.md, docs/benchmarks.md): the
1200 x 1200 test design at 360 dpi, first column at 60 mm, tilts 0/20/45/70, preset 8 pl drops,
spread factor 2 (49.6 um footprints), deposit model on the interior.

    PYTHONPATH=src python bench/film_acceptance.py [SIZE_PX]

Rows: one pass at the head's native clock (the print without interlace); the planned interlaced
passes as printed by default (equalised: ``PassOptions()``, the shares of ``track_fractions`` at 2 x the
plan's clock, the dead-track cover on), with 5 seeded dead nozzles; beside them the plain print
(``equalise=False``: every track keeps every drop at the plan's clock), with and without the dead nozzles;
then angular phases and swathe overlap (equalised, and plain with and without the dead nozzles). The issue's
baseline (60 um discs judged at design-pixel centres, `disc_uncovered_fraction`) is printed
beside the one-pass row. A second table gives the cost floor: the time of one pass's firing
images (the exact transform at the planned clock and the pass's pivot offset; the default pass
at the equalised clock, thinned while sampled, its shares timed apart) over the same transform
at the native clock (today's print of a layer), best of 5, and the same for direct slicing of
one layer of a real mesh (``slice_rotary``, the planned and the equalised clock vs native).

    PYTHONPATH=src python bench/film_acceptance.py [SIZE_PX] [TILTS] [--cost-only | --passes-cost-only] [--cpu] [--strip=ROWS] [--equalised-only] [--quick] [--no-level]
                                                  [--default-only] [--dead-only | --live-only] [--no-phases] [--raise-sparse]
                                                  [--raise=off|on|auto] [--edge-restore[=ZONE_UM,COEFFICIENT] | --no-edge-restore]
                                                  [--no-sensitivity | --sensitivity-only]

``--cpu``: the cost tables' times are the calling thread's CPU times (``time.thread_time``; steadier on a
shared machine; not ``process_time``, which also counts an OpenBLAS worker spinning after a matrix product).
``--passes-cost-only``: only the last table: the default print's passes as ``pass_prints`` makes them (maps,
thinned sampling and edge restore of every pass; the per-layer shares, dead cover and edge zone; the planner).
``--equalised-only``: only the equalised rows (the default; with the 5 dead nozzles; with phases and
overlap), then the cost table. ``--default-only``: only the default print's two rows (without and
with the dead nozzles). ``--dead-only`` / ``--live-only``: only the rows with / without the 5 dead
nozzles (of those the other options keep). ``--no-phases``: without the rows with angular phases and
edge overlap. ``--raise-sparse``: the equalisation with ``equalise.EQUALISE_RAISE = True``; ``--raise=``
off / on / auto sets it to False / True / "auto" (the default). ``--edge-restore=ZONE_UM,COEFFICIENT``: the equalised prints
with ``PassOptions(edge_restore=EdgeRestore(ZONE_UM, COEFFICIENT))`` (the default ``EdgeRestore()``: 50 um, 0.3,
thinned-out drops near the design's edges restored, ``rotary/edgecomp.py``); ``--no-edge-restore``: without.

The last column is a secondary figure, never the acceptance one: the levelled 1 mm bins' largest
deviation counting only bins with at least 1/4 of the median bin's interior area (the deposit
model's floor is 1/10: a bin whose interior is a sliver beside the design's edges counts there).

Every film row also gives the **levelled** film (the wet film levelling under surface tension
before it sets, ``LevelOptions.from_head``: set time 1 s (the preset's nominal; the convolutions on the coarse grid, ``levelled.coarse_factor``), the preset's nominal 10 mPa s, 30 mN/m, h0 the
10th percentile of the as-landed wet interior film) beside the as-landed figures; a third table
is the sensitivity at the first tilt given after 0 (default 20), default plan: set time 0.1 / 1 /
10 s with h0 at the 10th percentile, and at 1 s h0 at the 1st and 50th. ``--quick``: only the
default and the plain print, each with and without the 5 dead nozzles (no one-pass or phases rows);
``--no-sensitivity`` / ``--sensitivity-only``: without / only the third table.
"""

from __future__ import annotations

import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from rotoprint import load_device
from rotoprint.errors import GeometryError
from rotoprint.rotary import Placement, plan_swathes, simulate, transform_exact
from rotoprint.rotary.deposit import DepositOptions, LevelOptions, deposit_print
from rotoprint.rotary.files import read_print
from rotoprint.rotary.interlace import (COVER_SHARE, EQUALISE_CLOCK_FACTOR, PassOptions, ReachFloor, pass_overlap_mm, phase_angles,
                                       plan_passes, read_passes, track_fractions)
from rotoprint.pipeline.prints import transform_passes
from rotoprint.rotary.options import RotarySetup
from rotoprint.rotary.testimage import test_design


#: The secondary bin rule of the last column: bins with at least this share of the median bin's interior area.
SLIVER_FLOOR = 0.25


def bins_spread(bins, floor: float = SLIVER_FLOOR) -> float:
    """Largest ``|bin / mean - 1|`` of ``radial_bins`` ``((r_mm, mean_um, area_mm2), ...)`` counting the
    bins with at least ``floor`` of the median area (the deposit model's own rule: 1/10)."""
    if not bins:
        return float("nan")
    a = np.array([b[2] for b in bins])
    m = np.array([b[1] for b in bins])
    keep = a >= floor * np.median(a)
    return float(np.max(np.abs(m[keep] / m[keep].mean() - 1.0)))


def film_row(label, tilt, passes, gap_um, dpi, f, secs, extra=""):
    lv = f.levelled
    lev = (f" {lv.thinnest_to_mean:.3f} | {100 * lv.radial_spread:.1f} | {lv.h0_um:.1f} | {lv.levelling_length_um:.0f} | "
           f"{lv.volume_error_fraction:+.1e} |") if lv is not None else " - | - | - | - | - |"
    sliver = f" {100 * bins_spread(lv.radial_bins):.1f} |" if lv is not None else " - |"
    return (f"| {tilt:g} | {label} | {passes} | {gap_um:.1f} | {dpi:.0f} | {100 * f.uncovered_fraction:.3f} | "
            f"{100 * f.band_uncovered_fraction:.2f} | {f.thinnest_to_mean:.3f} | {f.mean_um:.2f} | {100 * f.radial_spread:.1f} | "
            f"{100 * f.volume_error_fraction:+.1e} | {f.drops} |{lev} {secs:.0f} |{sliver}{extra}")


def sensitivity_table(prs, d, head, tilt) -> None:
    """Levelled thinnest / mean of one film against the set time and the h0 rule."""
    print()
    print(f"Sensitivity of the levelled film, tilt {tilt:g}, planned passes as printed by default (equalised; 10 mPa s, 30 mN/m):")
    print()
    print("| set time s | h0 rule | h0 um | levelling length um | levelled thinnest / mean | levelled 1 mm bins max dev % | "
          "below half the as-landed mean % | volume error | s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for st, pct in ((0.1, 10.0), (1.0, 1.0), (1.0, 10.0), (1.0, 50.0), (10.0, 10.0)):
        if True:
            t = time.perf_counter()
            f = deposit_print(prs, d, options=DepositOptions(level=LevelOptions.from_head(head, set_time_s=st, h0_percentile=pct, coats=len(prs)))).films[0]
            lv = f.levelled
            print(f"| {st:g} | p{pct:g} | {lv.h0_um:.2f} | {lv.levelling_length_um:.0f} | {lv.thinnest_to_mean:.3f} | "
                  f"{100 * lv.radial_spread:.1f} | {100 * lv.below_half_landed_mean_fraction:.3f} | "
                  f"{lv.volume_error_fraction:+.1e} | {time.perf_counter() - t:.0f} |", flush=True)


def _best(fn, k: int = 3, clock=time.perf_counter) -> float:
    """Best of ``k`` wall times (or of ``clock``: ``time.thread_time`` for the CPU time, steadier
    on a shared machine; the kernels are single-threaded), the exact transform's map cache
    emptied before each (a pass at a new pivot or clock builds its maps: that is its cost).

    Steady state: ``gc.collect()`` before each timed call. Measured (20 deg, one equalised pass):
    without it the first 3-4 calls after ``track_fractions`` take 21-31 ms, then 10-12; with it
    9-12 from the first. No collection runs during the slow calls (``gc.callbacks``), none is owed
    (``track_fractions`` leaves no tracked objects) and they take no page faults: the cause is not
    cyclic GC work; the collect before each call removes it all the same."""
    import gc

    from rotoprint.rotary.exact import exact_maps

    best = float("inf")
    for _ in range(k):
        exact_maps.cache_clear()
        gc.collect()
        t = clock()
        fn()
        best = min(best, clock() - t)
    return best


def default_shares(head, sp, pp, tilt: float) -> list:
    """The default (equalised) print's shares of every pass of plan ``pp`` over swathes ``sp``, as
    ``pass_prints`` computes them (once for all passes; the geometry only): what the cost tables time."""
    return track_fractions(head, sp, pp.offsets_mm, RotarySetup(tilt_deg=tilt, dpi_y=pp.dpi_y), footprint_um=49.6,
                           reach=ReachFloor(COVER_SHARE * 49.6, EQUALISE_CLOCK_FACTOR))


def direct_pass_layer(mesh, head, kw: dict, k: int = 5, clock=time.perf_counter) -> tuple[float, float, int]:
    """A real P-pass layer of the direct slicer, as ``slice_rotary_passes`` prints it (``layer(1)`` of
    ``mesh`` with ``slice_rotary`` keywords ``kw``): the union's shares (``union_pass_shares``, once
    per build and tilt), then every pass at its offset with its shares. Returns the best of ``k``
    times of the shares and of all the passes, and the pass count ``P``."""
    from rotoprint.rotary.direct import slice_rotary, union_pass_shares

    pp_d = plan_passes(head, slice_rotary(mesh, "omnidot760", **kw).plan, footprint_um=DepositOptions().full_footprint_um(head))

    def union():
        j0 = slice_rotary(mesh, "omnidot760", **kw, dpi_y=pp_d.dpi_y)
        return union_pass_shares(head, j0.plan, pp_d.offsets_mm, dpi_y=pp_d.dpi_y)[:2]

    sh_d, clk_d = union()

    def passes_alone():
        for q, o in enumerate(pp_d.offsets_mm):
            slice_rotary(mesh, "omnidot760", **kw, dpi_y=clk_d, pivot_offset_mm=o, shares=sh_d[q], pass_index=q).layer(1)

    tp = _best(passes_alone, k, clock)
    tu = _best(union, k, clock)
    return tu, tp, pp_d.passes


def cost_table(d, pl, head, tilts, k: int = 5, clock=time.perf_counter) -> None:
    """The cost floor: a pass's firing images at the planned clock over today's at native (best of ``k``
    times of ``clock``: wall, or ``time.thread_time`` with ``--cpu``).

    The default (equalised) pass is charged its maps and its thinned images (``transform_exact(...,
    thin=ThinShares)``, as ``pass_prints`` prints it); the shares (``track_fractions``, computed once
    for all the passes of a layer, from the geometry only) are given beside it, and the ratio with
    their 1 / P share per pass and with all of them. Beside the direct slicer's single layers, a real
    P-pass layer of it (``union_pass_shares`` once, then every pass's ``slice_rotary(..., shares=)``
    layer) per pass, with and without the shares (which a build computes once for all its layers).
    """
    from rotoprint.rotary.direct import slice_rotary
    from rotoprint.rotary.exact import ThinShares
    from rotoprint.io.mesh import load_mesh

    # /work/shared beside the checkout (the main checkout or a worktree one level deeper)
    mesh_path = next((q / "shared" / "data" / "meshes" for q in Path(__file__).resolve().parents[1:4]
                      if (q / "shared" / "data" / "meshes").is_dir()), Path("shared/data/meshes"))
    meshes = [m for m in (mesh_path / "sphere_openscad.stl",) if m.is_file()]
    mesh = load_mesh(meshes[0]) if meshes else None
    r_in, r_out = pl.radial_range_mm()
    print()
    print("| tilt deg | passes | planned clock dpi | transform (maps + images), native s | one pass, planned s | ratio | "
          "equalised clock dpi | one pass equalised (maps + thinned images) s | ratio | shares of all P passes s | "
          "ratio with shares / P | ratio with all shares | "
          f"slice_rotary 1 layer{f' ({meshes[0].name})' if meshes else ''}, native s | planned s | ratio | equalised clock s | ratio | "
          "P-pass layer (union shares + every pass's slice_rotary with its shares) / P s | ratio | its passes alone / P s | ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for tilt in tilts:
        # the default print: equalised, no phases or overlap; one pass's images at EQUALISE_CLOCK_FACTOR x the plan's
        # clock, thinned while sampled; the shares of every pass (once per layer) timed apart
        sp_e = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
        pp_e = plan_passes(head, sp_e, footprint_um=49.6)
        dpi_e = pp_e.dpi_y * EQUALISE_CLOCK_FACTOR

        def shares():
            return default_shares(head, sp_e, pp_e, tilt)

        fr = shares()
        thin = ThinShares(fr[-1], len(fr) - 1)
        tf = _best(shares, k, clock)
        te = _best(lambda: transform_exact(d, head, pl, tilt_deg=tilt, dpi_y=dpi_e, pivot_offset_mm=pp_e.offsets_mm[-1], thin=thin), k, clock)
        ov = pass_overlap_mm(head)
        sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out, overlap_mm=ov)
        pp = plan_passes(head, sp, footprint_um=49.6, phases=True)
        off = pp.offsets_mm[-1]
        ang = phase_angles(sp, pp.phases, dpi_y=pp.dpi_y)[0][-1]  # the last pass as printed: offset, phase, overlap
        t0 = _best(lambda: transform_exact(d, head, pl, tilt_deg=tilt), k, clock)
        t1 = _best(lambda: transform_exact(d, head, pl, tilt_deg=tilt, dpi_y=pp.dpi_y, pivot_offset_mm=off,
                                           mount_angle_deg=ang, swathe_overlap_mm=ov), k, clock)
        row = (f"| {tilt:g} | {pp.passes} | {pp.dpi_y:.0f} | {t0:.4f} | {t1:.4f} | {t1 / t0:.2f} | {dpi_e:.0f} | {te:.4f} | {te / t0:.2f} | "
               f"{tf:.4f} | {(te + tf / pp_e.passes) / t0:.2f} | {(te + tf) / t0:.2f} |")
        if mesh is not None:
            h = float(mesh.bounds[1][2] - mesh.bounds[0][2])
            kw = dict(layer_height_mm=h / 3, tilt_deg=tilt, inner_radius_mm=60.0)
            s0 = _best(lambda: slice_rotary(mesh, "omnidot760", **kw).layer(1), k, clock)
            s1 = _best(lambda: slice_rotary(mesh, "omnidot760", **kw, dpi_y=pp.dpi_y, pivot_offset_mm=off).layer(1), k, clock)
            s2 = _best(lambda: slice_rotary(mesh, "omnidot760", **kw, dpi_y=dpi_e, pivot_offset_mm=pp_e.offsets_mm[-1]).layer(1), k, clock)
            row += f" {s0:.4f} | {s1:.4f} | {s1 / s0:.2f} | {s2:.4f} | {s2 / s0:.2f} |"
            tu, tp, n_p = direct_pass_layer(mesh, head, kw, k, clock)
            row += f" {(tu + tp) / n_p:.4f} | {(tu + tp) / n_p / s0:.2f} | {tp / n_p:.4f} | {tp / n_p / s0:.2f} |"
        print(row, flush=True)


def default_pass_cost(d, pl, hd, tilt: float, k: int = 5, clock=time.perf_counter) -> tuple[float, float, int, float]:
    """One default pass of :func:`~rotoprint.rotary.interlace.pass_prints` (``PassOptions()`` at
    ``tilt``, head ``hd``) on design ``d``: ``(images, per-layer work, P, whole call)`` in seconds,
    the images the mean of ``transform_restored`` over the passes of one call, the per-layer work
    (shares, dead cover, edge zone) the sum over the call, both from the one of ``k`` calls whose
    pass with them costs least; the whole call its own best (the exact maps' cache emptied before each)."""
    import gc

    import rotoprint.rotary.deadcover as dc
    import rotoprint.rotary.interlace as il
    from rotoprint.rotary.exact import exact_maps
    from rotoprint.rotary.interlace import pass_prints

    rec: dict = {}

    def timed(mod, name, key):
        f = getattr(mod, name)

        def w(*a, **kw):
            t = clock()
            r = f(*a, **kw)
            rec.setdefault(key, []).append(clock() - t)
            return r
        setattr(mod, name, w)
        return f

    saved = [(mod, name, timed(mod, name, key)) for mod, name, key in
             ((il, "transform_restored", "images"), (il, "track_fractions", "layer"), (il, "edge_zone", "layer"),
              (dc, "cover_dead_tracks", "layer")) if hasattr(mod, name)]  # (an older checkout has no edge_zone)
    runs, best_whole = [], float("inf")
    try:
        for _ in range(k):
            rec.clear()
            exact_maps.cache_clear()
            gc.collect()
            t = clock()
            _, prs, _ = pass_prints(d, hd, pl, PassOptions(RotarySetup(tilt_deg=tilt)))
            best_whole = min(best_whole, clock() - t)
            runs.append((float(np.mean(rec["images"])), sum(rec.get("layer", [])), len(prs)))
    finally:
        for mod, name, f in saved:
            setattr(mod, name, f)
    # the images and the per-layer work of one run: the run whose pass with them costs least
    best_img, best_layer, n_p = min(runs, key=lambda x: x[0] + x[1] / x[2])
    return best_img, best_layer, n_p, best_whole


def pass_prints_table(d, pl, head, tilts, k: int = 5, clock=time.perf_counter) -> None:
    """The default print's passes as :func:`~rotoprint.rotary.interlace.pass_prints` makes them
    (equalised, the dead-track cover, the edge restore: ``PassOptions()``), without and with the 5
    seeded dead nozzles, against today's layer (the exact transform at the head's native clock).

    Per pass: ``transform_restored`` of every pass (its maps at the pass's pivot, the thinned
    sampling, the edge restore), the mean over the passes of one call, best of ``k`` calls (the
    exact maps' cache emptied before each). Per layer, charged 1 / P to each pass: the shares
    (``track_fractions``), the dead-track cover (``cover_dead_tracks``) and the edge zone
    (``edge_zone``); the planner (``plan_passes``) is the rest of the whole call. Both from the one
    run of ``k`` whose pass with them costs least (the whole call: its own best). With ``--cpu``
    (the calling thread's time) the work an OpenBLAS worker does in the shares' products is not
    counted: the per-layer column may read a little low."""
    print()
    print("| tilt deg | nozzles | passes | native transform s | one pass's images (maps + thinned + edge restore) s | ratio | "
          "per-layer shares + dead cover + edge zone / P s | ratio with them | whole pass_prints / P s | ratio |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    r_in, r_out = pl.radial_range_mm()
    for tilt in tilts:
        sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)  # the film rows' seeded dead nozzles
        dead = tuple(sorted(int(x) for x in np.random.default_rng(14).choice(np.flatnonzero(sp.swathes[0].enabled), 5, replace=False)))
        t0 = _best(lambda: transform_exact(d, head, pl, tilt_deg=tilt), k, clock)
        for label, hd in (("all live", head), ("5 dead", head.model_copy(update={"dead_nozzles": dead}))):
            best_img, best_layer, n_p, best_whole = default_pass_cost(d, pl, hd, tilt, k, clock)
            print(f"| {tilt:g} | {label} | {n_p} | {t0:.4f} | {best_img:.4f} | {best_img / t0:.2f} | {best_layer / n_p:.4f} | "
                  f"{(best_img + best_layer / n_p) / t0:.2f} | {best_whole / n_p:.4f} | {best_whole / n_p / t0:.2f} |", flush=True)


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    n = int(args[0]) if args else 1200
    tilts = [float(t) for t in args[1].split(",")] if len(args) > 1 else [0.0, 20.0, 45.0, 70.0]
    head0 = load_device("omnidot760").head
    d = test_design(n)
    px = 25.4 / 360
    pl = Placement(n, n, px, px, inner_radius_mm=60.0)
    r_in, r_out = pl.radial_range_mm()
    strip = [int(a.split("=", 1)[1]) for a in sys.argv[1:] if a.startswith("--strip=")]
    if strip:  # a band of full design ROWS px high through the middle, over the same radial range
        d = np.full((strip[0], n), 255, np.uint8)
        pl = Placement(n, strip[0], px, px, inner_radius_mm=60.0)
    # the calling thread's CPU time: the kernels are single-threaded, and after a large enough matrix-vector
    # product (the shares') an OpenBLAS worker spins for a while (process_time 46-94 ms where a pass took 23-46 ms wall)
    cpu = {"clock": time.thread_time} if "--cpu" in sys.argv else {}
    if "--passes-cost-only" in sys.argv:
        pass_prints_table(d, pl, head0, tilts, **cpu)
        return
    if "--cost-only" in sys.argv:
        cost_table(d, pl, head0, tilts, **cpu)
        pass_prints_table(d, pl, head0, tilts, **cpu)
        return
    quick, level_on = "--quick" in sys.argv, "--no-level" not in sys.argv
    raise_opt = {"off": False, "on": True, "auto": "auto"}
    for a in sys.argv[1:]:
        if a == "--raise-sparse" or a.startswith("--raise="):  # the equalisation's raise of sparse stretches
            import rotoprint.rotary.equalise as _eq

            _eq.EQUALISE_RAISE = True if a == "--raise-sparse" else raise_opt[a.split("=", 1)[1]]
    edge = {}  # PassOptions' default (the edge restore on); --no-edge-restore: off
    for a in sys.argv[1:]:
        if a == "--no-edge-restore":
            edge = {"edge_restore": None}
        if a == "--edge-restore" or a.startswith("--edge-restore="):
            from rotoprint.rotary.edgecomp import EdgeRestore

            edge = {"edge_restore": EdgeRestore(*(float(x) for x in a.split("=", 1)[1].split(","))) if "=" in a else EdgeRestore()}
    sens_only, sens = "--sensitivity-only" in sys.argv, "--no-sensitivity" not in sys.argv
    if sens_only:
        tilt = next((t for t in tilts if t != 0.0), tilts[0])
        sp = plan_swathes(head0, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
        with tempfile.TemporaryDirectory() as td:
            transform_passes(d, head0, pl, Path(td) / "p.png", PassOptions(RotarySetup(tilt_deg=tilt), passes="auto"))
            prs = [read_print(q)[0] for q in read_passes(Path(td) / "p-passes.json")]
        sensitivity_table(prs, d, head0, tilt)
        return
    level = LevelOptions.from_head(head0, set_time_s=1.0) if level_on else None
    sens_tilt = next((t for t in tilts if t != 0.0), tilts[0])
    sens_prs = None
    print("| tilt deg | print | passes | largest track gap um | clock dpi | uncovered interior % | uncovered band % | "
          "thinnest / mean | mean um | 1 mm bins max dev % | volume error | drops | levelled thinnest / mean | "
          "levelled 1 mm bins max dev % | h0 um | levelling length um | levelled volume error | s | "
          "levelled bins, interior >= 1/4 median (secondary) % |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for tilt in tilts:
        sp = plan_swathes(head0, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
        rng = np.random.default_rng(14)
        dead = tuple(sorted(int(k) for k in rng.choice(np.flatnonzero(sp.swathes[0].enabled), 5, replace=False)))
        t = time.perf_counter()
        if not quick and "--equalised-only" not in sys.argv:  # else only the equalised rows (and their dead-nozzle row)
            pr = transform_exact(d, head0, pl, tilt_deg=tilt)
            f = deposit_print(pr, d, options=DepositOptions(level=level)).films[0]
            base = simulate(pr, d).report.disc_uncovered_fraction
            g1 = plan_passes(head0, sp, footprint_um=49.6, passes=4).single_pass_largest_gap_mm
            print(film_row("one pass, native clock", tilt, 1, g1 * 1000, head0.dpi_y, f, time.perf_counter() - t,
                           f" issue's baseline (60 um discs at pixel centres): {100 * base:.1f} % |"), flush=True)
        dead_head = head0.model_copy(update={"dead_nozzles": dead})
        for label, head, eq, inter in (("planned passes (the default: equalised)", head0, True, False),
                                       ("planned passes, 5 dead nozzles (the default: equalised)", dead_head, True, False),
                                       ("planned passes, plain (--no-equalise)", head0, False, False),
                                       ("planned passes, plain, 5 dead nozzles", dead_head, False, False),
                                       ("planned passes, equalised, phases + overlap", head0, True, True),
                                       ("planned passes, plain, angular phases + edge overlap", head0, False, True),
                                       ("planned passes, plain, 5 dead nozzles, phases + overlap", dead_head, False, True)):
            if "--equalised-only" in sys.argv and not eq:
                continue
            if "--default-only" in sys.argv and (inter or not eq):
                continue
            if "--dead-only" in sys.argv and head is head0:
                continue
            if "--live-only" in sys.argv and head is not head0:
                continue
            if quick and inter:
                continue
            if "--no-phases" in sys.argv and inter:
                continue
            for passes in ("auto", "6"):
                t = time.perf_counter()
                try:
                    with tempfile.TemporaryDirectory() as td:
                        m = transform_passes(d, head, pl, Path(td) / "p.png", PassOptions(RotarySetup(tilt_deg=tilt), passes=passes, equalise=eq,
                                                                                          phases=inter, edge_overlap=inter,
                                                                                          **edge))
                        prs = [read_print(q)[0] for q in read_passes(Path(td) / "p-passes.json")]
                except GeometryError as exc:
                    print(f"| {tilt:g} | {label} | auto (<= 4) | {exc.problem} |", flush=True)
                    continue
                f = deposit_print(prs, d, dead_nozzles=head.dead_nozzles,
                                  options=DepositOptions(level=level and replace(level, coats=len(prs)))).films[0]
                if tilt == sens_tilt and head is head0 and eq and not inter:
                    sens_prs = prs
                pp = m["pass_plan"]
                print(film_row(label, tilt, pp["passes"], pp["largest_gap_mm"] * 1000, m["dpi_y"], f, time.perf_counter() - t), flush=True)
                break
    if level_on and sens and sens_prs is not None:
        sensitivity_table(sens_prs, d, head0, sens_tilt)
    if not quick:
        cost_table(d, pl, head0, tilts, **cpu)
        pass_prints_table(d, pl, head0, tilts, **cpu)


if __name__ == "__main__":
    main()
