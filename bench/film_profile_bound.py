"""The best radial film profile any per-track volumes could give for the planned passes (an
upper bound for thinnest / mean: the along-track ripple only lowers it), by linear programming:
maximise min T(x) / mean T over a 1 um grid, T(x) = sum_k v_k (1 - (x - r_k)^2 / a^2)^(3/2),
v_k >= 0 free (no 1/r, no floor on a track's share). Beside it the profile with equal volumes.

    PYTHONPATH=src python bench/film_profile_bound.py TILT [R_LO R_HI]    # default 61 144 mm

The tracks are those of plan_passes on the test design's radial range (60-145 mm) with the
swathe overlap of transform_passes(edge_overlap=True).
"""
import sys, numpy as np, scipy.sparse as sps
from scipy.optimize import linprog
from rotoprint import load_device
from rotoprint.rotary import plan_swathes
from rotoprint.rotary.interlace import plan_passes, union_radii, pass_overlap_mm
head = load_device("omnidot760").head
tilt = float(sys.argv[1])
lo_r, hi_r = (float(sys.argv[2]), float(sys.argv[3])) if len(sys.argv) > 3 else (61.0, 144.0)
ov = True
sp = plan_swathes(head, tilt_deg=tilt, inner_radius_mm=60.0, outer_radius_mm=145.0, overlap_mm=pass_overlap_mm(head) if ov else 0.0)
pp = plan_passes(head, sp, footprint_um=49.6)
r = union_radii(head, sp, pp.offsets_mm)
a = 0.0248
r = r[(r > lo_r - a) & (r < hi_r + a)]
g = np.arange(lo_r, hi_r, 0.001)
rows, cols, vals = [], [], []
for k, rk in enumerate(r):
    i0, i1 = np.searchsorted(g, rk - a), np.searchsorted(g, rk + a)
    x = (g[i0:i1] - rk) / a
    rows += list(range(i0, i1)); cols += [k] * (i1 - i0); vals += list((1 - x * x) ** 1.5)
K = sps.csr_matrix((vals, (rows, cols)), shape=(g.size, r.size))
n = r.size
# vars: v (n), t ; max t  s.t. t - K v <= 0 ; mean(K v) = 1
A_ub = sps.hstack([-K, sps.csr_matrix(np.ones((g.size, 1)))])
A_eq = sps.hstack([sps.csr_matrix(K.mean(axis=0)), sps.csr_matrix([[0.0]])])
c = np.zeros(n + 1); c[-1] = -1
res = linprog(c, A_ub=A_ub, b_ub=np.zeros(g.size), A_eq=A_eq, b_eq=[1.0], bounds=[(0, None)] * n + [(0, None)], method="highs")
v = res.x[:n]
print(f"tilt {tilt} passes {pp.passes} gap {pp.largest_gap_mm*1000:.1f} um tracks {n}: best radial min/mean {res.x[-1]:.3f}; uniform v: {(K@np.ones(n)).min()/(K@np.ones(n)).mean():.3f}; v>0 share {np.mean(v>1e-9*v.max()):.2f}")
