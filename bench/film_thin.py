"""Where is the film thinnest, and why? (issue 14, the thinnest >= 50 % of the mean floor)

    PYTHONPATH=src python bench/film_thin.py [TILTS] [--rows=ROWS] [--passes=N|auto] [--equalise] [--dead=5]
                                            [--nospread] [--worst=8]

A band ``ROWS`` px high (default 30) of the 1200 px test design's width (84.7 mm at 360 dpi, first
column at 60 mm) is printed in the planned passes (``pass_prints``, the options as given) and
deposited with the thickness map kept. Printed per tilt, on the deposit model's interior:

- thinnest / mean, and the share of the interior below half the mean;
- the *radial* part: the thinnest 10 um radial ring's mean over the mean (what no along-track
  change can lift), and the *local* part: the thinnest cell over its own ring's mean (the
  along-track ripple and pinholes);
- the cells below half the mean, split by what lies beside them: a dead nozzle's track (within a
  footprint radius), a seam between swathes (within 0.2 mm of a band edge of any pass), the outer
  end of a swathe (its last 2 mm), or none of these;
- the ``--worst`` thinnest cells with their radius, their ring's mean, the union gap around them
  and the nearest seam and dead track.

Seconds to a minute per tilt (deposit on the 8.8 um grid of the band).
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from _film_cells import thinnest_apart, union_gap_um

from rotoprint import load_device
from rotoprint.rotary import Placement, plan_swathes
from rotoprint.rotary.deposit import deposit_print
from rotoprint.rotary.head import nozzle_layout
from rotoprint.rotary.interlace import PassOptions, pass_overlap_mm, pass_prints, union_radii
from rotoprint.rotary.options import RotarySetup

RING_MM = 0.01


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tilts = [float(t) for t in args[0].split(",")] if args else [0.0, 20.0, 45.0, 70.0]
    opt = dict(a[2:].split("=", 1) if "=" in a else (a[2:], "1") for a in sys.argv[1:] if a.startswith("--"))
    rows = int(opt.get("rows", 30))
    n_dead = int(opt.get("dead", 0))
    worst = int(opt.get("worst", 8))
    head0 = load_device("omnidot760").head
    px = 25.4 / 360
    pl = Placement(1200, rows, px, px, inner_radius_mm=60.0)
    d = np.full((rows, 1200), 255, np.uint8)
    r_in, r_out = pl.radial_range_mm()
    extra = {"spread_dead": False} if "nospread" in opt else {}
    for tilt in tilts:
        t0 = time.perf_counter()
        head = head0
        if n_dead:
            sp0 = plan_swathes(head0, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
            rng = np.random.default_rng(14)
            dead = tuple(sorted(int(k) for k in rng.choice(np.flatnonzero(sp0.swathes[0].enabled), n_dead, replace=False)))
            head = head0.model_copy(update={"dead_nozzles": dead})
        po = PassOptions(RotarySetup(tilt_deg=tilt), passes=opt.get("passes", "auto"), equalise="equalise" in opt,
                         phases="phases" in opt, edge_overlap="overlap" in opt, **extra)
        _, prints, man = pass_prints(d, head, pl, po)
        dep = deposit_print(prints, d, dead_nozzles=head.dead_nozzles, keep_map=True)
        f = dep.films[0]
        th = dep.thickness
        nx, ny = dep.cells_per_pixel
        ox, oy = dep.origin_cells
        a_mm = 0.5e-3 * f.footprint_um
        gx, gy = f.grid_um
        # interior of a full rectangle: cells at least a + g/2 inside every edge
        m_px = (a_mm + 0.5e-3 * min(gx, gy)) / px
        cc = (np.arange(th.shape[1]) + 0.5 - ox) / nx
        rr = (np.arange(th.shape[0]) + 0.5 - oy) / ny
        inside_c = (cc >= m_px) & (cc <= pl.width_px - m_px)
        inside_r = (rr >= m_px) & (rr <= pl.height_px - m_px)
        C, R = np.meshgrid(cc[inside_c], rr[inside_r])
        X, Y = pl.to_platform(C.ravel(), R.ravel())
        rad = np.hypot(X, Y)
        t = th[np.ix_(inside_r, inside_c)].ravel()
        mean = float(t.mean())
        ring = np.floor((rad - rad.min()) / RING_MM).astype(np.int64)
        ring_mean = np.bincount(ring, weights=t) / np.maximum(np.bincount(ring), 1)
        ring_n = np.bincount(ring)
        rm = ring_mean[ring]
        ok = ring_n >= 0.5 * np.median(ring_n[ring_n > 0])
        pp = man["pass_plan"]
        sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out,
                          overlap_mm=pp["swathe_overlap_mm"])
        offs = pp["offsets_mm"]
        union = union_radii(head, sp, offs)
        seams = sorted({float(sw.band_mm[0]) for sw in sp.swathes[1:]})
        ends = [float(sw.band_mm[1]) for sw in sp.swathes]
        dead_r = []
        for j in range(len(sp.swathes)):
            xy = nozzle_layout(head, sp.mount(j)).xy_mm
            for o in offs:
                for k in head.dead_nozzles:
                    r = float(np.hypot(xy[k, 0] + o, xy[k, 1]))
                    lo_b, hi_b = sp.swathes[j].band_mm
                    if lo_b <= r < hi_b:
                        dead_r.append(r)
        dead_r = np.sort(np.array(dead_r))

        def nearest(v: np.ndarray, x: np.ndarray) -> np.ndarray:
            if v.size == 0:
                return np.full(x.shape, np.inf)
            i = np.clip(np.searchsorted(v, x), 1, max(1, v.size - 1))
            return np.minimum(np.abs(v[np.minimum(i, v.size - 1)] - x), np.abs(v[i - 1] - x))

        thin = t < 0.5 * mean
        near_dead = nearest(dead_r, rad) <= a_mm
        near_seam = nearest(np.array(seams), rad) <= 0.2
        at_end = np.zeros(rad.shape, bool)
        for sw in sp.swathes:
            lo_b, hi_b = sw.band_mm
            at_end |= (rad >= hi_b - 2.0) & (rad < hi_b)
        cat_dead = thin & near_dead
        cat_seam = thin & ~near_dead & near_seam
        cat_end = thin & ~near_dead & ~near_seam & at_end
        cat_other = thin & ~near_dead & ~near_seam & ~at_end
        rmin_i = int(np.argmin(np.where(ok, ring_mean, np.inf)))
        loc = t / np.maximum(rm, 1e-300)
        print(f"tilt {tilt:g}: passes {pp['passes']} offsets um {[round(1000 * o, 1) for o in offs]} clock {man['dpi_y']:.0f} dpi, "
              f"thinnest / mean {t.min() / mean:.3f}, below half the mean {100 * thin.mean():.3f} % of the interior "
              f"({time.perf_counter() - t0:.0f} s)")
        print(f"  radial: thinnest 10 um ring {ring_mean[rmin_i] / mean:.3f} of the mean at {rad.min() + (rmin_i + 0.5) * RING_MM:.2f} mm; "
              f"rings range {np.min(ring_mean[ok]) / mean:.3f} .. {np.max(ring_mean[ok]) / mean:.3f}; "
              f"local: thinnest cell over its ring {loc.min():.3f}")
        n_thin = max(1, int(thin.sum()))
        print(f"  below half: beside a dead track {100 * cat_dead.sum() / n_thin:.0f} %, at a seam {100 * cat_seam.sum() / n_thin:.0f} %, "
              f"swathe's last 2 mm {100 * cat_end.sum() / n_thin:.0f} %, elsewhere {100 * cat_other.sum() / n_thin:.0f} % "
              f"(seams at {[round(s, 2) for s in seams]}, band ends {[round(e, 2) for e in ends]})")
        for i in thinnest_apart(t, rad, worst, 0.05):
            gap = union_gap_um(union, rad[i])
            print(f"    r {rad[i]:8.3f} mm: {t[i] / mean:.3f} of the mean, {loc[i]:.3f} of its ring (ring {rm[i] / mean:.3f}); "
                  f"union gap {gap:.1f} um; seam {1000 * float(nearest(np.array(seams), rad[i:i + 1])[0]):.0f} um; "
                  f"dead track {1000 * float(nearest(dead_r, rad[i:i + 1])[0]):.0f} um")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
