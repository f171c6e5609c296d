"""The sites the edge restore may give back, found in one sweep of a pass's track windows (numba
kernel and its numpy reference; :func:`rotoprint.rotary.edgecomp.transform_restored` calls them).

A drop of track ``k`` at absolute firing ``i`` is a *candidate* when

- the thinning left it out: not ``floor((i + 1) f_k + p_k) > floor(i f_k + p_k)`` (share ``f_k``,
  thinning phase ``p_k``: the rule of :func:`rotoprint.rotary._thin_kernels.kept_jit`), while the
  same rule keeps it at share 1 and the track keeps some drops and not all (``0 < f_k < 1``: the
  restore rate ``gain_k`` is 0 otherwise, and the caller makes it 0 for dead nozzles);
- the restore pattern fires: ``floor((i + 1) g_k + o_k) > floor(i g_k + o_k)`` (``g_k`` the
  restore rate, ``o_k`` its phase: :func:`rotoprint.rotary.edgecomp.restore_pattern`);
- the design pixel it is sampled from (the exact transform's landing index) is in the edge zone
  (``zone_flat`` non-zero: the design masked to :func:`~rotoprint.rotary.edgecomp.edge_zone_mask`).

These are exactly the drops of the unthinned transform of the zone-masked design that the thinned
pass lacks and that the pattern restores (the earlier route: two images of every firing, their
difference, every difference's landing point). The caller then tests each candidate's landing
point against the design's edge along the radius (:func:`~rotoprint.rotary.edgecomp.radial_edge_near`),
as before, on the candidates only. Pieces of track whose drops can land on no zone pixel are
skipped by the zone's ink blocks (:func:`~rotoprint.rotary._exact_kernels.ink_blocks`), as the
sampling kernel skips pieces off the ink.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ._exact_kernels import _ink_state, _landing_index, _pointwise_index_numpy, _window_drops
from ._thin_kernels import kept_jit, kept_numpy, thin_floors_jit

__all__ = ["restore_candidates_jit", "restore_candidates_numpy", "radial_near_jit", "RESTORE_PIECE"]

#: Firing rows per piece whose zone blocks are looked at before its drops are (at most 64: one bit a row).
RESTORE_PIECE = 64

#: De Bruijn's 64-bit constant: ``(w * _DE_BRUIJN) >> 58`` differs for every one-bit word ``w``, and
#: ``_LOW_BIT`` maps it back to the bit's position.
_DE_BRUIJN = np.uint64(0x03F79D71B4CA8B09)
_LOW_BIT = np.zeros(64, np.int64)
_LOW_BIT[((np.uint64(1) << np.arange(64, dtype=np.uint64)) * _DE_BRUIJN) >> np.uint64(58)] = np.arange(64)


@njit(cache=True, nogil=True)
def restore_candidates_jit(A, B, C, D, E, F, nozzle, row, count, cos_r, sin_r, width, height, zone_flat, zone_sat,
                           f, p, gain, o, first, claim_rows, out_row, out_k):  # pragma: no cover - jit
    """Write the candidates' print rows and nozzles to ``out_row``, ``out_k`` (window order, rows
    ascending within a window); returns their number ``M``. The buffers: ``(count.sum(),) int32``
    (at most one candidate a window drop).

    Parameters as :func:`rotoprint.rotary._exact_kernels.windows_sample_thin_numba`'s (``A .. F``
    the coefficients, the windows, the firing rows' cos / sin, the design's size), with
    ``zone_flat`` ``(H W + 1,) uint8`` (the zone-masked design's levels and the 0 sentinel) and
    ``zone_sat`` its ink blocks; ``f``, ``p`` the thinning's shares and phases, ``gain``, ``o``
    the restore's rates and phases (each ``(N,) float64``), ``first`` the first firing's index,
    ``claim_rows`` the longest piece whose blocks can be claimed (longer ones are looked at drop by drop).
    """
    # Per piece of RESTORE_PIECE rows that can land on the zone: both rules' floors, one per firing
    # (thin_floors_jit's form: firing t is kept where g[t + 1] > g[t]); the drops that pass both as the bits
    # of one word (an or-reduction, vectorised; RESTORE_PIECE <= 64), walked lowest first (de Bruijn), each
    # then tested against the zone at its landing index and the share-1 rule.
    m = 0
    piece = max(1, min(RESTORE_PIECE, claim_rows))
    gt = np.empty(RESTORE_PIECE + 1, np.float64)
    gr = np.empty(RESTORE_PIECE + 1, np.float64)
    low_bit = _LOW_BIT
    one = np.uint64(1)
    for q in range(nozzle.shape[0]):
        k = nozzle[q]
        g = gain[k]
        if g <= 0.0:
            continue
        fk = f[k]
        pk = p[k]
        ok = o[k]
        a = A[k]
        b = B[k]
        d = D[k]
        e = E[k]
        r_end = row[q] + count[q]
        for lo in range(row[q], r_end, piece):
            hi = min(lo + piece, r_end)
            if _ink_state(a, b, d, e, C, F, cos_r[lo], sin_r[lo], cos_r[hi - 1], sin_r[hi - 1], width, height, zone_sat) == 0:
                continue
            n = hi - lo
            i0 = float(lo + first)
            thin_floors_jit(gt, i0, n, fk, pk)
            thin_floors_jit(gr, i0, n, g, ok)
            bits = np.uint64(0)
            for t in range(n):  # thinned out and restored by the pattern
                bits |= np.uint64((gt[t + 1] <= gt[t]) & (gr[t + 1] > gr[t])) << np.uint64(t)
            while bits:
                low = bits & (~bits + one)
                t = low_bit[(low * _DE_BRUIJN) >> np.uint64(58)]
                bits ^= low
                r = lo + t
                # sampled from the zone, kept at share 1 (the earlier route's unthinned pass)
                if zone_flat[_landing_index(a, b, d, e, C, F, cos_r[r], sin_r[r], width, height)] != 0 and \
                        kept_jit(i0 + t, 1.0, pk):
                    out_row[m] = r
                    out_k[m] = k
                    m += 1
    return m


def restore_candidates_numpy(A, B, C, D, E, F, nozzle, row, count, cos_r, sin_r, width, height, zone_flat, zone_sat,
                             f, p, gain, o, first, claim_rows, out_row, out_k):
    """:func:`restore_candidates_jit` drop by drop on arrays (the reference; ``zone_sat`` and
    ``claim_rows`` unused: no piece is skipped)."""
    k, r = _window_drops(nozzle, row, count)  # window order, rows ascending
    i = r + float(first)
    f, p, gain, o = (np.asarray(x, np.float64)[k] for x in (f, p, gain, o))
    sel = (gain > 0.0) & ~kept_numpy(i, f, p) & kept_numpy(i, 1.0, p) & kept_numpy(i, gain, o)
    k, r = k[sel], r[sel]
    sel = zone_flat[_pointwise_index_numpy(A, B, C, D, E, F, k, cos_r[r], sin_r[r], width, height)] != 0
    m = int(sel.sum())
    out_row[:m], out_k[:m] = r[sel], k[sel]
    return m


@njit(cache=True, nogil=True)
def radial_near_jit(mask, rim, col, row, inner_mm, pitch_x_mm, pitch_y_mm, half_h, c, s, zone_um, out):  # pragma: no cover - jit
    """:func:`rotoprint.rotary.edgecomp.radial_edge_near` of the sites ``col``, ``row`` ``(M,)
    float64`` into ``out`` ``(M,) bool``, the same float operations in the same order (the
    placement's frame: inner radius, pitches, ``half_h`` = half its height in pixels, ``c``, ``s``
    the cos / sin of its angle); ``mask``, ``rim`` ``(H, W) bool``."""
    h, w = mask.shape
    for q in range(col.shape[0]):
        out[q] = False
        i = np.floor(row[q])
        j = np.floor(col[q])
        if not (i >= 0 and i < h and j >= 0 and j < w) or not rim[int(i), int(j)]:
            continue
        xl = inner_mm + col[q] * pitch_x_mm
        yl = (half_h - row[q]) * pitch_y_mm
        x = c * xl - s * yl
        y = s * xl + c * yl
        rad = max(np.hypot(x, y), 1e-12)
        for t in (-1.0, 1.0):
            x2 = x + t * 1e-3 * zone_um * x / rad
            y2 = y + t * 1e-3 * zone_um * y / rad
            xl2 = c * x2 + s * y2
            yl2 = -s * x2 + c * y2
            c2 = (xl2 - inner_mm) / pitch_x_mm
            r2 = half_h - yl2 / pitch_y_mm
            i2 = np.floor(r2)
            j2 = np.floor(c2)
            if not (i2 >= 0 and i2 < h and j2 >= 0 and j2 < w) or not mask[int(i2), int(j2)]:
                out[q] = True
                break
