"""Per-bin deposited volume per area of the equalised passes, per tilt, on a band of the test
design (issue 14, the +-3 % bins): fast (no film grid), to see what sets the 1 mm bins.

    PYTHONPATH=src python bench/film_bins.py [TILTS] [--rows=ROWS] [--passes=N|auto] [--plain] [--dead=5]

The design is a band ``ROWS`` px high (default 30) of the 1200 px test design's width (84.7 mm at
360 dpi, first column at 60 mm). For every tilt the passes are planned and printed as
``transform_passes`` does (``pass_prints``, equalised unless ``--plain``); every drop is landed
(``place_drops``) and its volume counted in the 1 mm radial bin of its site; each bin's volume is
divided by the bin's area of the band (the band's pixels subdivided 8 x 8). Printed per tilt:
the largest deviation of the bins from their mean (bins with at least a tenth of the median
area, as the deposit model counts them), the bins themselves in groups of 5 mm, and, per bin,
the model's prediction (the planner's shares, after the dead-track cover where ``pass_prints``
applies it, times each track's drops per mm, summed over the tracks in the bin, over the bin's
width; only bins the band fills) so that a planner error and a realisation error
(thinning pattern, band edges) can be told apart. Seconds per tilt, not minutes.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

from rotoprint import load_device
from rotoprint.rotary import Placement
from rotoprint.rotary.interlace import PassOptions, pass_prints
from rotoprint.rotary.options import RotarySetup
from rotoprint.rotary.simulate import place_drops

BIN_MIN_SHARE = 0.1


def bin_areas(pl: Placement, sub: int = 8) -> np.ndarray:
    """Area (mm2) of the band in each 1 mm radial bin, ``(B,)`` indexed by ``floor(r)``."""
    c = (np.arange(pl.width_px * sub) + 0.5) / sub
    r = (np.arange(pl.height_px * sub) + 0.5) / sub
    cc, rr = np.meshgrid(c, r)
    x, y = pl.to_platform(cc.ravel(), rr.ravel())
    b = np.floor(np.hypot(x, y)).astype(np.int64)
    return np.bincount(b) * pl.pitch_x_mm * pl.pitch_y_mm / sub / sub


def _cap_cdf(x: np.ndarray) -> np.ndarray:
    """Share of a cap's radial profile ``(1 - x^2)^(3/2)`` (``x`` in footprint radii) below ``x``."""
    x = np.clip(x, -1.0, 1.0)
    s = np.sqrt(1.0 - x * x)
    return (x * s ** 3 / 4 + 3.0 / 8.0 * (x * s + np.arcsin(x))) / (3.0 * math.pi / 8.0) + 0.5


def radial_bins(r_mm: np.ndarray, w: np.ndarray, a_mm: float, nbins: int) -> np.ndarray:
    """``w`` of sites at radii ``r_mm`` spread over 1 mm bins by the radial profile of a footprint
    of radius ``a_mm`` (what the film puts in each bin, without the point-count aliasing)."""
    b = np.floor(r_mm).astype(np.int64)
    up = _cap_cdf((b + 1 - r_mm) / a_mm)  # share below the bin's upper edge
    lo = _cap_cdf((b - r_mm) / a_mm)  # share below its lower edge
    out = np.zeros(nbins + 2)
    ok = (b >= 1) & (b < nbins)
    np.add.at(out, b[ok], w[ok] * (up[ok] - lo[ok]))
    np.add.at(out, b[ok] + 1, w[ok] * (1.0 - up[ok]))
    np.add.at(out, b[ok] - 1, w[ok] * lo[ok])
    return out[:nbins]


def model_bins(head, pl: Placement, man: dict, tilt: float, d_um: float, nbins: int, eq: bool) -> np.ndarray:
    """The planner's own prediction of volume per radial unit per bin: each track's share times its
    drops per mm (``1 / (r dphi)``), spread as above."""
    import dataclasses

    from rotoprint.rotary import plan_swathes
    from rotoprint.rotary.exact import swathe_clock
    from rotoprint.rotary.head import nozzle_layout
    from rotoprint.rotary.interlace import track_fractions
    from rotoprint.rotary.swathes import pass_enabled

    r_in, r_out = pl.radial_range_mm()
    sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out,
                      overlap_mm=man["pass_plan"]["swathe_overlap_mm"])
    offs = man["pass_plan"]["offsets_mm"]
    from rotoprint.rotary.equalise import EQUALISE_CLOCK_FACTOR, ReachFloor
    from rotoprint.rotary.interlace import COVER_SHARE

    st = RotarySetup(tilt_deg=tilt, dpi_y=man["dpi_y"] / (EQUALISE_CLOCK_FACTOR if eq else 1))
    cover = bool(eq and head.dead_nozzles and len(offs) > 1)  # as pass_prints: shares with all live, dead drops moved
    fr = track_fractions(head, sp, offs, st, footprint_um=d_um, reach=ReachFloor(COVER_SHARE * d_um, EQUALISE_CLOCK_FACTOR),
                         dead_nozzles=() if cover else None) if eq else None
    if cover:
        from rotoprint.rotary.deadcover import cover_dead_tracks

        fr, _ = cover_dead_tracks(head, sp, offs, st, shares=fr, footprint_um=d_um)
    e = np.array([1.0, 0.0])
    rs, ws = [], []
    live = np.ones(head.nozzles, bool)
    live[list(head.dead_nozzles)] = False
    for q, o in enumerate(offs):
        for j in range(len(sp.swathes)):
            dphi, _ = swathe_clock(sp, j, dpi_y=man["dpi_y"], ref_radius_mm=None)
            xy = nozzle_layout(head, sp.mount(j)).xy_mm + o * e
            r = np.hypot(xy[:, 0], xy[:, 1])
            k = pass_enabled(sp, j, r) & live
            f = fr[q][j][k] if fr is not None else 1.0
            rs.append(r[k])
            ws.append(f / (r[k] * dphi))
    return radial_bins(np.concatenate(rs), np.concatenate(ws), 0.5e-3 * d_um, nbins)


def spread(v: np.ndarray, area: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    nz = area > 0
    keep = nz & (area >= BIN_MIN_SHARE * np.median(area[nz]))
    t = np.where(keep, v / np.where(area > 0, area, 1.0), np.nan)
    m = np.nanmean(t)
    return float(np.nanmax(np.abs(t / m - 1.0))), t / m, keep


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tilts = [float(t) for t in args[0].split(",")] if args else [0.0, 20.0, 45.0, 70.0]
    opt = dict(a[2:].split("=", 1) if "=" in a else (a[2:], "1") for a in sys.argv[1:] if a.startswith("--"))
    rows = int(opt.get("rows", 30))
    passes = opt.get("passes", "auto")
    eq = "plain" not in opt
    n_dead = int(opt.get("dead", 0))
    head0 = load_device("omnidot760").head
    px = 25.4 / 360
    pl = Placement(1200, rows, px, px, inner_radius_mm=60.0)
    d = np.full((rows, 1200), 255, np.uint8)
    area = bin_areas(pl)
    for tilt in tilts:
        t0 = time.perf_counter()
        head = head0
        if n_dead:
            from rotoprint.rotary import plan_swathes

            r_in, r_out = pl.radial_range_mm()
            sp = plan_swathes(head0, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
            rng = np.random.default_rng(14)
            dead = tuple(sorted(int(k) for k in rng.choice(np.flatnonzero(sp.swathes[0].enabled), n_dead, replace=False)))
            head = head0.model_copy(update={"dead_nozzles": dead})
        _, prints, man = pass_prints(d, head, pl, PassOptions(RotarySetup(tilt_deg=tilt), passes=passes, equalise=eq,
                                                              balance=("balance" in opt)))
        vol = np.zeros(area.size)
        d_um = 49.6
        for p in prints:
            dr = place_drops(p, dead_nozzles=head.dead_nozzles)
            vol += radial_bins(np.hypot(dr.x_mm, dr.y_mm), dr.level.astype(np.float64), 0.5e-3 * d_um, area.size)
        dev, rel, keep = spread(vol, area)
        mod = model_bins(head, pl, man, tilt, d_um, area.size, eq)
        # per mm of radius -> per area; only bins the band fills (the model has no band edges: in a
        # partly filled end bin it would read the band's shape, not the planner's shares)
        full = keep & (area >= 0.9 * np.median(area[keep]))
        mdev, mrel, _ = spread(mod * np.median(area[keep]), np.where(full, area, 0.0))
        pp = man["pass_plan"]
        print(f"tilt {tilt:g}: passes {pp['passes']} clock {man['dpi_y']:.0f} dpi, 1 mm bins max dev {100 * dev:.1f} % "
              f"(the planner's model: {100 * mdev:.1f} %; {time.perf_counter() - t0:.1f} s)", flush=True)
        idx = np.flatnonzero(keep)
        for g0 in range(idx[0] - idx[0] % 5, idx[-1] + 1, 5):
            sel = [i for i in range(g0, g0 + 5) if i < rel.size and keep[i]]
            if sel:
                print(f"  {g0:4d}-{g0 + 4:<4d} " + " ".join(f"{rel[i]:.3f}" for i in sel)
                      + "   model " + " ".join(f"{mrel[i]:.3f}" if full[i] else "  -  " for i in sel))


if __name__ == "__main__":
    main()
