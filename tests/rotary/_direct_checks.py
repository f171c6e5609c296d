"""Checks of the direct rotary slicer against independent references (shared by the tests and
``bench/direct_acceptance.py``).

- ``lattice``: every drop site (swathe, firing, track) of a job, with its landing point.
- ``shapely_mismatches``: sites where "fired" differs from "landing point inside the exact
  cross-section" (trimesh + shapely, ``tests/_reference.py``), with their distance to the
  boundary.
- ``two_step``: the same layer sliced to a Cartesian bitmap (oversampled design grid), then the
  exact transform; its drops are compared site by site with the direct print.
- ``iou_pair``: the simulator's cell-model IoU of both prints against the exact cross-section
  rasterised (shapely) on a common evaluation grid.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import shapely

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _reference import exact_section  # noqa: E402

from rotoprint.rotary import simulate, transform_exact  # noqa: E402
from rotoprint.rotary.direct import rasterize_section  # noqa: E402
from rotoprint.rotary.head import Mount, nozzle_layout  # noqa: E402


def section_geom(job, index):
    m = job.slice_job.mesh
    return exact_section(m.vertices[m.faces], float(job.layers.z_slice_mm[index]))


def check_track_geometry(job, ts, swathe=None):
    """Assert that the track set's radii and angles are those of an independent
    ``nozzle_layout`` of its swathe (pivot, the job's tilt and direction, head 0's mount), so
    that the "exact" checks, which place drops with ``ts.r_mm`` / ``ts.psi0_rad``, cannot pass
    on a wrong track geometry. ``swathe``: the print's swathe, whose pivot and clock must match."""
    lay = nozzle_layout(job.head, Mount(ts.pivot_radius_mm, tilt_deg=job.plan.tilt_deg, mount_angle_deg=0.0,
                                        direction=job.plan.direction))
    live = np.ones(job.head.nozzles, bool)
    live[list(job.head.dead_nozzles)] = False
    want = np.flatnonzero(ts.enabled & live)
    assert sorted(ts.nozzle.tolist()) == want.tolist()  # every enabled live nozzle, once
    np.testing.assert_array_equal(ts.r_mm, lay.r_mm[ts.nozzle])
    np.testing.assert_allclose(ts.psi0_rad, lay.phi_rad[ts.nozzle] - np.radians(job.part.angle_deg), rtol=0, atol=1e-12)
    assert np.all(np.diff(ts.r_mm) >= 0)
    if swathe is not None:
        assert swathe.pivot_radius_mm == ts.pivot_radius_mm and swathe.dphi_rad == ts.dphi_rad
        assert swathe.first_firing == ts.first_firing and swathe.levels.shape[0] == ts.firings


def lattice(job, ts, firings=None):
    """Model XY ``(F, M)`` of every site of track set ``ts`` (rows: firing ``first_firing + b``);
    the track geometry is checked first (:func:`check_track_geometry`)."""
    check_track_geometry(job, ts)
    b = np.arange(ts.firings) if firings is None else np.asarray(firings)
    i = (b + ts.first_firing)[:, None].astype(np.float64)
    sig = job.plan.direction
    ang = (ts.psi0_rad[None, :] + np.radians(job.part.angle_deg)) - sig * i * ts.dphi_rad
    x = ts.r_mm[None, :] * np.cos(ang)
    y = ts.r_mm[None, :] * np.sin(ang)
    return job.part.platform_to_model(x, y)


def shapely_mismatches(job, pr, geom, *, n_random=None, seed=0):
    """``(checked, mismatches, max distance of a mismatch to the boundary in mm)``."""
    rng = np.random.default_rng(seed)
    checked = bad_n = 0
    worst = 0.0
    assert len(job.tracks) == len(pr.swathes)
    for ts, sw in zip(job.tracks, pr.swathes):
        check_track_geometry(job, ts, sw)
        fired_all = sw.levels[:, ts.nozzle] > 0
        if n_random is None:
            X, Y = lattice(job, ts)
            fired = fired_all
        else:
            n = n_random // len(job.tracks)
            bi = rng.integers(0, ts.firings, n)
            mi = rng.integers(0, ts.nozzle.size, n)
            Xa, Ya = lattice(job, ts, bi)
            X, Y = Xa[np.arange(n), mi], Ya[np.arange(n), mi]
            fired = fired_all[bi, mi]
        inside = shapely.contains_xy(geom, X, Y) if not geom.is_empty else np.zeros(np.shape(X), bool)
        bad = inside != fired
        checked += int(np.size(X))
        if bad.any():
            d = shapely.distance(geom.boundary, shapely.points(X[bad], Y[bad]))
            bad_n += int(bad.sum())
            worst = max(worst, float(d.max()))
    return checked, bad_n, worst


def two_step(job, index, *, oversample):
    """The layer sliced to a Cartesian bitmap ``oversample`` times finer than the head's grid,
    then the exact transform (same head, tilt, placement, clock, swathes)."""
    seg, _ = job.slice_job.segments(index)
    pl = job.part.design_placement(job.design.pitch_x_mm, job.design.pitch_y_mm, oversample=oversample)
    img = rasterize_section(seg, job.part, pl, fill=job.fill)
    pr = transform_exact(img, job.head, pl, tilt_deg=job.plan.tilt_deg, dpi_y=job.dpi_y, direction=job.plan.direction, kind="binary")
    return pr, img, pl


def compare_sites(job, direct, other, geom):
    """Sites where the two prints differ: ``(count, max distance to the boundary in units of the
    local firing step or track pitch, whichever is larger)``. Both prints must share the lattice."""
    assert len(direct.swathes) == len(other.swathes)
    n_diff = 0
    worst = 0.0
    for ts, a, b in zip(job.tracks, direct.swathes, other.swathes):
        assert a.pivot_radius_mm == b.pivot_radius_mm and a.dphi_rad == b.dphi_rad
        lo = min(a.first_firing, b.first_firing)
        hi = max(a.first_firing + a.levels.shape[0], b.first_firing + b.levels.shape[0])
        A = np.zeros((hi - lo, a.levels.shape[1]), bool)
        B = np.zeros_like(A)
        A[a.first_firing - lo : a.first_firing - lo + a.levels.shape[0]] = a.levels > 0
        B[b.first_firing - lo : b.first_firing - lo + b.levels.shape[0]] = b.levels > 0
        rows, cols = np.nonzero(A != B)
        if rows.size == 0:
            continue
        lut = np.full(a.levels.shape[1], -1, np.int64)
        lut[ts.nozzle] = np.arange(ts.nozzle.size)
        q = lut[cols]
        assert (q >= 0).all(), "a print fires a nozzle that is not a track of its swathe"
        sig = job.plan.direction
        i = (rows + lo).astype(np.float64)
        ang = (ts.psi0_rad[q] + np.radians(job.part.angle_deg)) - sig * i * ts.dphi_rad
        X, Y = job.part.platform_to_model(ts.r_mm[q] * np.cos(ang), ts.r_mm[q] * np.sin(ang))
        d = shapely.distance(geom.boundary, shapely.points(X, Y))
        step = np.maximum(ts.r_mm[q] * ts.dphi_rad, ts.pitch_mm[q])
        n_diff += rows.size
        worst = max(worst, float((d / step).max()))
    return n_diff, worst


def exact_raster(job, geom, *, oversample):
    """The exact cross-section (shapely point-in-polygon at pixel centres) on an evaluation grid."""
    pl = job.part.design_placement(job.design.pitch_x_mm, job.design.pitch_y_mm, oversample=oversample)
    jj, cc = np.mgrid[0 : pl.height_px, 0 : pl.width_px]
    x, y = pl.to_platform(cc + 0.5, jj + 0.5)
    X, Y = job.part.platform_to_model(x, y)
    inside = shapely.contains_xy(geom, X, Y) if not geom.is_empty else np.zeros(X.shape, bool)
    return (inside.astype(np.uint8) * 255), pl


def iou_pair(job, prints, geom, *, oversample=2):
    """Simulator IoU of each print against the exact cross-section on one evaluation grid."""
    design, pl = exact_raster(job, geom, oversample=oversample)
    return [simulate(dataclasses.replace(p, placement=pl), design).report.iou for p in prints]
