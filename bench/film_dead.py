"""Where is the *levelled* film thinnest with dead nozzles, and why? (issue 14, dead-nozzle cover)

    PYTHONPATH=src python bench/film_dead.py [TILTS] [--rows=ROWS] [--dead=5] [--passes=N|auto]
                                            [--equalise] [--nospread] [--nodead] [--worst=6] [--set-time=1] [--full | --crop=ROWS] [--nocover]

A band ``ROWS`` px high (default 40) of the 1200 px test design's width (84.7 mm at 360 dpi, first
column at 60 mm) is printed in the planned passes (``pass_prints`` with the options given; the
5 dead nozzles drawn with seed 14 from swathe 0's enabled nozzles as in
``bench/film_acceptance.py``), deposited and levelled per coat (the acceptance's levelling: the
head's nominal set time, 10 mPa s, 30 mN/m, ``h0`` the 10th percentile over the passes), with
both maps kept (``--full``: the whole 1200 x 1200 test design of the acceptance instead of the
band; about 2 GB and a few minutes per tilt; ``--crop=ROWS``: its middle ROWS rows). Printed per tilt, on the deposit model's interior:

- as landed and levelled thinnest / mean; the levelled thinnest at least 0.3 mm from the design's
  edges (what the pinned edge does not set);
- the levelled 20 um radial rings: the thinnest ring over the mean, and per dead track (every
  pass and swathe) the ring at it over the rings' mean within +-1 mm (its local dip);
- the ``--worst`` thinnest levelled cells with their radius, distance to the design's edge,
  their ring over the local rings' mean, and the nearest dead tracks (which nozzle, pass,
  swathe, and the union gap there).

Seconds to a minute per tilt.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from _film_cells import thinnest_apart, union_gap_um

from rotoprint import load_device
from rotoprint.rotary import Placement, plan_swathes
from rotoprint.rotary.deposit import DepositOptions, LevelOptions, deposit_print
from rotoprint.rotary.head import nozzle_layout
from rotoprint.rotary.interlace import PassOptions, pass_prints, union_radii
from rotoprint.rotary.options import RotarySetup

RING_MM = 0.02


def dead_tracks(head, sp, offs):
    """(radius mm, nozzle, pass, swathe) of every dead nozzle's moved track inside its band."""
    psi = math.radians(sp.mount_angle_deg)
    e = np.array([math.cos(psi), math.sin(psi)])
    out = []
    for j, sw in enumerate(sp.swathes):
        xy = nozzle_layout(head, sp.mount(j)).xy_mm
        lo_b, hi_b = sw.band_mm if sp.overlap_mm > 0 else (sp.inner_radius_mm - 1, sp.outer_radius_mm + 1)
        can = sw.usable if sp.overlap_mm > 0 and sw.usable is not None else sw.enabled
        for q, o in enumerate(offs):
            for k in head.dead_nozzles:
                if not can[k]:
                    continue
                r = float(np.hypot(*(xy[k] + o * e)))
                if lo_b <= r < hi_b:
                    out.append((r, int(k), q, j))
    return sorted(out)


def scan_cells(th, tl, dep, f, pl, design, keep: int) -> dict:
    """The interior cells of the maps in strips (the deposit model's interior: design cells at
    least half a footprint plus half a cell from the nearest cell outside the design): the
    ``keep`` thinnest levelled cells (radius, distance to the design's edge mm, as landed and
    levelled um), the levelled 20 um rings' sums and counts from the inner radius, and the
    levelled thinnest at least 0.3 mm from every edge."""
    from scipy import ndimage

    nx, ny = dep.cells_per_pixel
    ox, oy = dep.origin_cells
    gx, gy = f.grid_um
    a_um = 0.5 * f.footprint_um
    rows, cols = th.shape
    mask = np.asarray(design) > 0
    h_px, w_px = mask.shape
    dcol = np.floor((np.arange(cols) + 0.5 - ox) / nx).astype(np.int64)
    dcol_ok = (dcol >= 0) & (dcol < w_px)
    dcol = np.clip(dcol, 0, w_px - 1)
    margin = int(math.ceil(400.0 / gy)) + 2  # rows: the edge distance is exact to 0.4 mm
    r0 = pl.inner_radius_mm
    n_ring = int(math.ceil((pl.radial_range_mm()[1] - r0) / RING_MM)) + 2
    ring_sum, ring_n = np.zeros(n_ring), np.zeros(n_ring)
    best = {k: np.zeros(0) for k in ("rad", "edge_mm", "t", "lv", "edge_deg", "x", "y")}
    away_min = math.inf
    step = max(64, 2_000_000 // cols)
    for a in range(0, rows, step):
        b = min(rows, a + step)
        e0, e1 = max(0, a - margin), min(rows, b + margin)
        drow = np.floor((np.arange(e0, e1) + 0.5 - oy) / ny).astype(np.int64)
        drow_ok = (drow >= 0) & (drow < h_px)
        dm = mask[np.clip(drow, 0, h_px - 1)][:, dcol] & drow_ok[:, None] & dcol_ok[None, :]
        if not dm[a - e0:b - e0].any():
            continue
        dist, near = ndimage.distance_transform_edt(dm, sampling=(gy, gx), return_indices=True)
        dist, near = dist[a - e0:b - e0], near[:, a - e0:b - e0]
        inter = dm[a - e0:b - e0] & (dist >= a_um + 0.5 * min(gx, gy))
        ii, jj = np.nonzero(inter)
        if not ii.size:
            continue
        X, Y = pl.to_platform((jj + 0.5 - ox) / nx, (ii + a + 0.5 - oy) / ny)
        rad = np.hypot(X, Y)
        lv = tl[a:b][ii, jj]
        ri = np.clip(np.floor((rad - r0) / RING_MM).astype(np.int64), 0, n_ring - 1)
        ring_sum += np.bincount(ri, weights=lv, minlength=n_ring)
        ring_n += np.bincount(ri, minlength=n_ring)
        dd = dist[ii, jj] * 1e-3
        far = dd >= 0.3
        if far.any():
            away_min = min(away_min, float(lv[far].min()))
        sel = np.argsort(lv)[:keep]
        # the nearest cell outside the design: its direction against the radial one (0: the
        # edge runs along the tracks, at the next radius out; 180: in; 90: the edge crosses them)
        ni, nj = near[0][ii[sel], jj[sel]] + e0, near[1][ii[sel], jj[sel]]
        Xn, Yn = pl.to_platform((nj + 0.5 - ox) / nx, (ni + 0.5 - oy) / ny)
        ang = np.degrees(np.arctan2(X[sel] * (Yn - Y[sel]) - Y[sel] * (Xn - X[sel]), X[sel] * (Xn - X[sel]) + Y[sel] * (Yn - Y[sel])))
        new = {"rad": rad[sel], "edge_mm": dd[sel], "t": th[a:b][ii[sel], jj[sel]], "lv": lv[sel], "edge_deg": np.abs(ang),
               "x": X[sel], "y": Y[sel]}
        for k in best:
            best[k] = np.concatenate([best[k], new[k]])
        o = np.argsort(best["lv"])[:keep]
        best = {k: v[o] for k, v in best.items()}
    return {**best, "ring_sum": ring_sum, "ring_n": ring_n, "r0": r0, "away_min": away_min}


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tilts = [float(t) for t in args[0].split(",")] if args else [0.0, 20.0, 45.0, 70.0]
    opt = dict(a[2:].split("=", 1) if "=" in a else (a[2:], "1") for a in sys.argv[1:] if a.startswith("--"))
    rows = int(opt.get("rows", 40))
    n_dead = 0 if "nodead" in opt else int(opt.get("dead", 5))
    worst = int(opt.get("worst", 6))
    head0 = load_device("omnidot760").head
    px = 25.4 / 360
    if "full" in opt or "crop" in opt:  # the acceptance's test design (its middle CROP rows)
        from rotoprint.rotary.testimage import test_design

        d = test_design(1200)
        if "crop" in opt:
            c = int(opt["crop"])
            d = np.ascontiguousarray(d[600 - c // 2:600 - c // 2 + c])
        pl = Placement(1200, d.shape[0], px, px, inner_radius_mm=60.0)
    else:
        pl = Placement(1200, rows, px, px, inner_radius_mm=60.0)
        d = np.full((rows, 1200), 255, np.uint8)
    r_in, r_out = pl.radial_range_mm()
    extra = {"spread_dead": False} if "nospread" in opt else {}
    if "nocover" in opt:
        extra["dead_cover"] = False
    for tilt in tilts:
        t0 = time.perf_counter()
        sp0 = plan_swathes(head0, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
        rng = np.random.default_rng(14)
        dead = tuple(sorted(int(k) for k in rng.choice(np.flatnonzero(sp0.swathes[0].enabled), 5, replace=False)))[:n_dead]
        head = head0.model_copy(update={"dead_nozzles": dead})
        po = PassOptions(RotarySetup(tilt_deg=tilt), passes=opt.get("passes", "auto"), equalise="equalise" in opt, **extra)
        _, prints, man = pass_prints(d, head, pl, po)
        lev = LevelOptions.from_head(head0, set_time_s=float(opt.get("set-time", 1.0)), coats=len(prints))
        dep = deposit_print(prints, d, dead_nozzles=head.dead_nozzles, keep_map=True, options=DepositOptions(level=lev))
        f = dep.films[0]
        th, tl = dep.thickness, dep.levelled_thickness
        cells = scan_cells(th, tl, dep, f, pl, d, worst * 40)
        rad, edge_mm, t, lv = cells["rad"], cells["edge_mm"], cells["t"], cells["lv"]
        mean, lmean = f.mean_um, f.levelled.mean_um
        ring_l = cells["ring_sum"] / np.maximum(cells["ring_n"], 1)
        rn = cells["ring_n"]
        ok = rn >= 0.5 * np.median(rn[rn > 0])
        r0_ring = cells["r0"]
        ring = np.clip(np.floor((rad - r0_ring) / RING_MM).astype(np.int64), 0, ring_l.size - 1)
        pp = man["pass_plan"]
        offs = pp["offsets_mm"]
        sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out, overlap_mm=pp["swathe_overlap_mm"])
        union = union_radii(head, sp, offs)
        dt = dead_tracks(head, sp, offs)
        print(f"tilt {tilt:g}: dead {list(dead)} passes {pp['passes']} offsets um {[round(1000 * o, 1) for o in offs]} "
              f"overlap {pp['swathe_overlap_mm']:.3f} mm, clock {man['dpi_y']:.0f} dpi; as landed {f.thinnest_to_mean:.3f}, "
              f"levelled {lv.min() / lmean:.3f} (report {f.levelled.thinnest_to_mean:.3f}, L {f.levelled.levelling_length_um:.0f} um), "
              f">= 0.3 mm from the design's edges {cells['away_min'] / lmean:.3f}; uncovered {100 * f.uncovered_fraction:.3f} %, "
              f"mean {f.mean_um:.2f} um, bins {100 * f.radial_spread:.1f} %, volume error {f.volume_error_fraction:+.1e} "
              f"({time.perf_counter() - t0:.0f} s)")
        if man.get("dead_cover"):
            print(f"  dead cover: {man['dead_cover']}")
        w = int(round(1.0 / RING_MM))
        csum = np.cumsum(np.pad(np.where(ok, ring_l, 0.0), (1, 0)))
        cn = np.cumsum(np.pad(ok.astype(np.float64), (1, 0)))
        idx = np.arange(ring_l.size)
        lo_i, hi_i = np.maximum(0, idx - w), np.minimum(ring_l.size, idx + w + 1)
        local = (csum[hi_i] - csum[lo_i]) / np.maximum(cn[hi_i] - cn[lo_i], 1)
        rmin = int(np.argmin(np.where(ok, ring_l, np.inf)))
        print(f"  levelled rings: thinnest {ring_l[rmin] / lmean:.3f} of the mean at {r0_ring + (rmin + 0.5) * RING_MM:.2f} mm "
              f"({ring_l[rmin] / local[rmin]:.3f} of its +-1 mm)")
        if dt:
            dips = []
            for r, k, q, j in dt:
                i = int((r - r0_ring) / RING_MM)
                if 0 <= i < ring_l.size and ok[i]:
                    sl = slice(max(0, i - 2), i + 3)
                    mi = int(np.argmin(ring_l[sl])) + sl.start
                    dips.append((ring_l[mi] / local[mi], r, k, q, j))
            dips.sort()
            print("  dead tracks, levelled ring dip (ring / +-1 mm mean): "
                  + ", ".join(f"{v:.3f} @ {r:.2f} mm (n{k} p{q} s{j})" for v, r, k, q, j in dips[:8]))
        for i in thinnest_apart(lv, rad, worst, 0.1):
            gap = union_gap_um(union, rad[i])
            ri = ring[i]
            near = sorted(dt, key=lambda x: abs(x[0] - rad[i]))[:3]
            print(f"    r {rad[i]:8.3f} mm ({cells['x'][i]:.2f}, {cells['y'][i]:.2f}), {1000 * edge_mm[i]:4.0f} um from the edge "
                  f"at {cells['edge_deg'][i]:3.0f} deg from radial: levelled {lv[i] / lmean:.3f} "
                  f"(as landed {t[i] / mean:.3f}), ring {ring_l[ri] / max(local[ri], 1e-300):.3f} of its +-1 mm; union gap {gap:.1f} um; "
                  "dead " + ", ".join(f"{1000 * (x[0] - rad[i]):+.0f} um n{x[1]} p{x[2]} s{x[3]}" for x in near))
        sys.stdout.flush()


if __name__ == "__main__":
    main()
