"""Edge restore of the direct slicer's thinned tracks: the jit kernel and its numpy reference.

The rule of :func:`rotoprint.rotary.edgecomp.restore_near_edges` on the exact cross-section
(:meth:`rotoprint.rotary.direct.DirectSliceJob.print_from_segments` calls it): a thinned track
``m`` (radius ``r_m``, share ``0 < f < 1``) gets firing ``i`` back when its site ``(r_m, psi_i)``
is inside the *region* and some point ``(r_m + d, psi_i)`` with ``|d| <= zone`` is not, and the
restore pattern fires there: ``floor((i + 1) g + o) > floor(i g + o)`` (``g`` the restore rate
``min(1, c f / (1 - f))``, ``o`` the track's restore phase).

The region is the section's inside (the direct fill's rules: radial half-open, winding along the
arc, nonzero or even-odd) minus the inside of each *cut* section (the build's higher-priority
parts). "Some point along the radius is outside" is looked at on the circles ``r_m + d_s``,
``d_s`` the given offsets (``+-zone * s / n``, ``s = 1 .. n``): each is a virtual track with the
parent's firing angles, whose inside spans come from the fill's own span pass
(:func:`._direct_kernels._track_spans`: they are merged into the fill's tracks with share 0,
so one span pass serves both), and an outside stretch at least ``zone / n`` wide along the radius
is always seen. The zone of track ``m`` is its region spans minus the intersection of its
virtual tracks' region spans: sorted span lists only, no image pass; only the zone's firings
are written (pass 6 of the jit fill, ``_direct_kernels._restore_edges``). This module holds the
numpy reference.
"""

from __future__ import annotations

import numpy as np


__all__ = ["edge_restore_numpy"]


def edge_restore_numpy(part, cuts, r_mm, psi0, cols, gain, phase, d_mm, *, dphi, direction, i0, n_f, fill, level, out, fill_numpy):
    """Restore the zone's drops of thinned tracks on ``out`` in place; returns the drops written.

    The reference of the jit fill's pass 6 (``_direct_kernels._restore_edges``, the same result):
    the inside of every real and virtual track from ``fill_numpy`` (:func:`~._direct_kernels.direct_fill_numpy`,
    given by its caller: the kernels module imports this one), as images.

    Parameters
    ----------
    part : (4, S) float64
        The section's segments in the local frame: rows ``x0, y0, x1, y1`` (mm).
    cuts : sequence of (4, S_g) float64
        Sections whose inside is not the region (may be empty).
    r_mm, psi0 : (T,) float64
        The thinned tracks' radii and local angles at firing 0.
    cols : (T,) int64
        Their image columns.
    gain, phase : (T,) float64
        Restore rate ``g`` in [0, 1] and phase ``o`` in [0, 1) of each track.
    d_mm : (S,) float64
        The radial offsets looked at (non-zero).
    out : (n_f, N) uint8
        The swathe image (row ``b``: firing ``i0 + b``), written where restored.
    """
    r_mm = np.asarray(r_mm, np.float64)
    psi0 = np.asarray(psi0, np.float64)
    d_mm = np.asarray(d_mm, np.float64)
    n_t, n_s = r_mm.size, d_mm.size
    if n_t == 0:
        return 0
    rad = np.concatenate([r_mm, (r_mm[:, None] + d_mm[None, :]).ravel()])
    ang = np.concatenate([psi0, np.repeat(psi0, n_s)])
    order = np.argsort(rad, kind="stable")
    n_all = rad.size

    def inside(seg):
        s = np.asarray(seg, np.float64).reshape(4, -1)
        img = fill_numpy(*s, rad[order] ** 2, ang[order], np.arange(n_all), np.ones(n_all), np.zeros(n_all), dphi=dphi,
                                direction=direction, i0=i0, n_f=n_f, n_cols=n_all, fill=fill, level=1)
        back = np.empty_like(img, dtype=bool)
        back[:, order] = img > 0
        return back

    region = inside(part)
    for c in cuts:
        region &= ~inside(c)
    site = region[:, :n_t]
    every = region[:, n_t:].reshape(n_f, n_t, n_s).all(axis=2)
    zone = site & ~every
    i = (np.arange(n_f, dtype=np.float64) + i0)[:, None]
    g = np.asarray(gain, np.float64)[None, :]
    o = np.asarray(phase, np.float64)[None, :]
    fire = (np.floor((i + 1.0) * g + o) > np.floor(i * g + o)) & (g > 0.0)
    rows, tr = np.nonzero(zone & fire)
    cc = np.asarray(cols, np.int64)[tr]
    new = out[rows, cc] != level
    out[rows, cc] = level
    return int(new.sum())

