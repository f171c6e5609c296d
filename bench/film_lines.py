"""Ink of every one-pixel radial line, per tilt, with and without the even lines (issue 14, the
thinnest >= 50 % of the mean floor at tilted heads): seconds per tilt, no film grid.

    PYTHONPATH=src python bench/film_lines.py [TILTS] [--line-um=70.56]

On the levelled film of the 1200 px test design (levelled per coat) the thinnest interior point
is inside the narrowest features: one-pixel lines (70.6 um) at constant radius, whose film holds
only the ink of the 2-5 union tracks inside them (measured, full design: the thinnest levelled
cell 35 um from the edge of a one-pixel line at every tilt; 0.71-0.73 of its line's ink share,
so a line holding 0.7 of the mean line's ink gives about 0.5). For the planned passes of the test
design (``plan_passes`` on its swathes; with the even lines, the swathes as ``pass_prints`` plans
them: an overlap of ``EVEN_OVERLAP_PERIODS`` row periods and a seam of ``EVEN_SEAM_PERIODS``, and
the tracks ``even_line_shares`` keeps) it prints the *line volumes*: for lines ``[c, c + w)``
every 2 um over the design's radial range, ``sum_k n_k p_k(c)`` (``n_k`` drops per mm of track
``k``, ``p_k`` the share of its footprint's cross-section inside the line), over their mean:
the smallest, the 0.1 and 1st percentiles and the largest, and where the smallest lies.
"""

from __future__ import annotations

import dataclasses
import sys
import time

import numpy as np

from rotoprint import load_device
from rotoprint.rotary import Placement, plan_swathes
from rotoprint.rotary.exact import swathe_clock
from rotoprint.rotary.head import nozzle_layout
from rotoprint.rotary.interlace import EVEN_OVERLAP_PERIODS, EVEN_SEAM_PERIODS, even_line_shares, plan_passes
from rotoprint.rotary.options import RotarySetup
from rotoprint.rotary.swathes import pass_enabled

STEP_MM = 0.002


def line_volumes(r: np.ndarray, n: np.ndarray, lo: float, hi: float, w: float, a: float) -> tuple[np.ndarray, np.ndarray]:
    """``(vol, c)``: the ink of lines ``[c, c + w)`` from tracks at ``r`` (mm) with ``n`` drops per mm."""
    x = np.linspace(-a, a, 401)
    k = np.clip(1 - (x / a) ** 2, 0, None) ** 1.5
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (k[1:] + k[:-1]))])
    cdf /= cdf[-1]
    c = np.arange(lo, hi - w, STEP_MM)
    vol = np.zeros(c.size)
    for rk, nk in zip(r, n):
        i, j = np.searchsorted(c, rk - a - w), np.searchsorted(c, rk + a)
        u = c[i:j] - rk
        vol[i:j] += nk * (np.interp(u + w, x, cdf) - np.interp(u, x, cdf))
    return vol, c


def main() -> None:
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    tilts = [float(t) for t in args[0].split(",")] if args else [0.0, 20.0, 45.0, 70.0]
    opt = dict(a[2:].split("=", 1) for a in sys.argv[1:] if a.startswith("--") and "=" in a)
    head = load_device("omnidot760").head
    px = 25.4 / 360
    w = float(opt.get("line-um", 1000 * px)) * 1e-3
    pl = Placement(1200, 1200, px, px, inner_radius_mm=60.0)
    r_in, r_out = pl.radial_range_mm()
    per = head.rows * head.pitch_mm
    d_um = 49.6
    print("| tilt deg | print | passes | tracks kept | line volume min / mean | at mm | p0.1 | p1 | max | s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for tilt in tilts:
        for even in (False, True):
            t0 = time.perf_counter()
            sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out,
                              overlap_mm=EVEN_OVERLAP_PERIODS * per if even else 0.0)
            sp = sp.with_seam(EVEN_SEAM_PERIODS * per if even else 0.0)
            pp = plan_passes(head, sp, footprint_um=d_um)
            fr, kept = (even_line_shares(head, sp, pp, RotarySetup(tilt_deg=tilt, dpi_y=pp.dpi_y), line_mm=max(px, 1e-3 * d_um))
                        if even else (None, None))
            rs, ns = [], []
            for q, o in enumerate(pp.offsets_mm):
                for j in range(len(sp.swathes)):
                    dphi, _ = swathe_clock(sp, j, dpi_y=pp.dpi_y, ref_radius_mm=None)
                    xy = nozzle_layout(head, dataclasses.replace(sp.mount(j), pivot_radius_mm=sp.mount(j).pivot_radius_mm + o)).xy_mm
                    r = np.hypot(xy[:, 0], xy[:, 1])
                    on = pass_enabled(sp, j, r) & (fr[q][j] > 0 if fr is not None else True)
                    rs.append(r[on])
                    ns.append(1.0 / (r[on] * dphi))
            vol, c = line_volumes(np.concatenate(rs), np.concatenate(ns), r_in + 0.2, r_out - 0.2, w, 0.5e-3 * d_um)
            m = vol.mean()
            label = "even lines (default)" if even else "radial offsets only (before)"
            kt = f"{kept[0]} of {kept[1]}" if kept else "all"
            print(f"| {tilt:g} | {label} | {pp.passes} | {kt} | {vol.min() / m:.3f} | {c[int(np.argmin(vol))]:.2f} | "
                  f"{np.percentile(vol, 0.1) / m:.3f} | {np.percentile(vol, 1) / m:.3f} | {vol.max() / m:.3f} | "
                  f"{time.perf_counter() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main()
