"""Kernels of the exact transform: landing points to design coordinates, and sampling.

Private: :mod:`rotoprint.rotary.exact` validates inputs and calls these with contiguous arrays
of the documented dtypes. Every kernel has a numba and a numpy form with the same contract;
tests run both.

The landing point of nozzle ``k`` at firing ``i`` is linear in ``(cos(i*dphi), sin(i*dphi))``,
so the design coordinates are ``col = A_k c_i + B_k s_i + C`` and ``row = D_k c_i + E_k s_i + F``
with per-nozzle coefficients computed once.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from ._thin_kernels import kept_numpy, thin_floors_jit


def coefficients(r, phi, direction, angle_rad, inner_radius_mm, pitch_x_mm, pitch_y_mm, height_px):
    """Per-nozzle coefficients ``(A, B, D, E)`` (each ``(N,) float64``) and constants ``(C, F)``.

    Landing point ``(r cos(phi - sigma a), r sin(phi - sigma a))`` with ``a = i*dphi``;
    ``x = r cos(phi) c + sigma r sin(phi) s``, ``y = r sin(phi) c - sigma r cos(phi) s``.
    Then rotate by ``-angle`` and scale into design pixels.
    """
    rc = r * np.cos(phi)
    rs = r * np.sin(phi)
    sg = float(direction)
    ca, sa = math.cos(angle_rad), math.sin(angle_rad)
    # x = rc*c + sg*rs*s ; y = rs*c - sg*rc*s
    # xl = ca*x + sa*y ; yl = -sa*x + ca*y
    xl_c = ca * rc + sa * rs
    xl_s = sg * (ca * rs - sa * rc)
    yl_c = -sa * rc + ca * rs
    yl_s = sg * (-sa * rs - ca * rc)
    A = xl_c / pitch_x_mm
    B = xl_s / pitch_x_mm
    C = -inner_radius_mm / pitch_x_mm
    D = -yl_c / pitch_y_mm
    E = -yl_s / pitch_y_mm
    F = height_px / 2.0
    return A, B, C, D, E, F


@njit(cache=True, parallel=True, nogil=True)
def _coords_nb(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height, col_out, row_out, idx_out):  # pragma: no cover - jit
    n_f = cos_i.shape[0]
    n_k = A.shape[0]
    sentinel = width * height
    for i in prange(n_f):
        c = cos_i[i]
        s = sin_i[i]
        for k in range(n_k):
            u = A[k] * c + B[k] * s + C
            v = D[k] * c + E[k] * s + F
            col_out[i, k] = u
            row_out[i, k] = v
            if not enabled[k]:
                idx_out[i, k] = sentinel
                continue
            cu = math.floor(u)
            rv = math.floor(v)
            if cu < 0 or rv < 0 or cu >= width or rv >= height:
                idx_out[i, k] = sentinel
            else:
                idx_out[i, k] = rv * width + cu


def coords_numba(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height):
    n_f, n_k = cos_i.shape[0], A.shape[0]
    col = np.empty((n_f, n_k), np.float32)
    row = np.empty((n_f, n_k), np.float32)
    idx = np.empty((n_f, n_k), np.int32 if width * height < 2**31 - 1 else np.int64)
    _coords_nb(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height, col, row, idx)
    return col, row, idx


def coords_numpy(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height):
    c = cos_i[:, None]
    s = sin_i[:, None]
    u = A[None, :] * c + B[None, :] * s + C
    v = D[None, :] * c + E[None, :] * s + F
    cu = np.floor(u)
    rv = np.floor(v)
    ok = (cu >= 0) & (rv >= 0) & (cu < width) & (rv < height) & enabled[None, :]
    dt = np.int32 if width * height < 2**31 - 1 else np.int64
    idx = np.where(ok, rv * width + cu, width * height).astype(dt)
    return u.astype(np.float32), v.astype(np.float32), idx


@njit(cache=True, parallel=True, nogil=True)
def _bilinear_nb(img, col, row, idx, out):  # pragma: no cover - jit
    h, w = img.shape
    sentinel = w * h
    n_f, n_k = col.shape
    for i in prange(n_f):
        for k in range(n_k):
            if idx[i, k] == sentinel:
                out[i, k] = 0.0
                continue
            x = col[i, k] - 0.5
            y = row[i, k] - 0.5
            x0 = math.floor(x)
            y0 = math.floor(y)
            fx = x - x0
            fy = y - y0
            acc = 0.0
            for dy in range(2):
                yy = min(max(y0 + dy, 0), h - 1)
                wy = fy if dy == 1 else 1.0 - fy
                for dx in range(2):
                    xx = min(max(x0 + dx, 0), w - 1)
                    wx = fx if dx == 1 else 1.0 - fx
                    acc += wy * wx * img[yy, xx]
            out[i, k] = acc


def bilinear_numba(img, col, row, idx):
    out = np.empty(col.shape, np.float32)
    _bilinear_nb(img, col, row, idx, out)
    return out


def bilinear_numpy(img, col, row, idx):
    h, w = img.shape
    x = col.astype(np.float64) - 0.5
    y = row.astype(np.float64) - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = x - x0
    fy = y - y0
    x0 = x0.astype(np.int64)
    y0 = y0.astype(np.int64)
    acc = np.zeros(col.shape, np.float64)
    for dy in (0, 1):
        yy = np.clip(y0 + dy, 0, h - 1)
        wy = fy if dy else 1.0 - fy
        for dx in (0, 1):
            xx = np.clip(x0 + dx, 0, w - 1)
            wx = fx if dx else 1.0 - fx
            acc += wy * wx * img[yy, xx]
    acc[idx == w * h] = 0.0
    return acc.astype(np.float32)


KERNELS = {
    "jit": (coords_numba, bilinear_numba),
    "numpy": (coords_numpy, bilinear_numpy),
}


def index_dense_numpy(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height):
    """Brute force over every firing and nozzle: ``(F, N)`` index map and per-firing hit flags.

    The reference the windowed kernels are tested against (it evaluates every drop).
    """
    _, _, idx = coords_numpy(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height)
    return idx, (idx != width * height).any(axis=1)


# --- output-sensitive maps: per-track firing windows ---------------------------------------------
#
# Nozzle k draws a circle of radius r_k; its drops can land in the design only where that circle
# crosses the design's rectangle, which is at most two arcs. `track_windows` finds those arcs
# analytically (with a safety margin) as firing windows; the index kernels evaluate the exact
# landing formula (the same float operations as `coords_numpy`) only inside them; every other
# nozzle-firing is "no drop" without being computed. Work scales with the design's size.


def index_dtype(width, height):
    return np.int32 if width * height < 2**31 - 1 else np.int64


@njit(cache=True, nogil=True)
def _track_windows_nb(r, phi, enabled, direction, angle_rad, x0_mm, x1_mm, yh_mm, dphi, i0, i1, margin, wk, wlo, whi):  # pragma: no cover - jit
    e = 1e-6
    x0 = x0_mm - e
    x1 = x1_mm + e
    yh = yh_mm + e
    m = margin * dphi
    n = 0
    for k in range(r.shape[0]):
        rk = r[k]
        if not enabled[k] or rk < x0 or rk <= 0.0:
            continue
        hi = min(math.acos(min(max(x0 / rk, -1.0), 1.0)), math.asin(min(max(yh / rk, -1.0), 1.0)))
        lo = math.acos(min(max(x1 / rk, -1.0), 1.0))
        if lo > hi:
            continue
        lo -= m
        hi += m
        base = phi[k] - angle_rad
        # local angle alpha = phi_k - direction * i * dphi - angle  <=>  i = direction * (phi_k - angle - alpha) / dphi
        n0 = n
        for arc in range(2):
            if lo > 0.0:  # two arcs, below and above the design's axis
                a1, a2 = (-hi, -lo) if arc == 0 else (lo, hi)
            elif arc == 0:
                a1, a2 = -hi, hi
            else:
                break
            ia = direction * (base - a2) / dphi
            ib = direction * (base - a1) / dphi
            f_lo = min(max(math.floor(min(ia, ib)) - margin, i0), i1 + 1)
            f_hi = min(max(math.ceil(max(ia, ib)) + margin + 1, i0), i1 + 1)
            if f_hi > f_lo:
                wk[n] = k
                wlo[n] = int(f_lo) - i0
                whi[n] = int(f_hi) - i0
                n += 1
        if n - n0 == 2:
            if wlo[n0] > wlo[n0 + 1]:  # in firing order
                wlo[n0], wlo[n0 + 1] = wlo[n0 + 1], wlo[n0]
                whi[n0], whi[n0 + 1] = whi[n0 + 1], whi[n0]
            if wlo[n0 + 1] <= whi[n0]:  # the margins made them meet: one window, no drop twice
                whi[n0] = max(whi[n0], whi[n0 + 1])
                n -= 1
    return n


def track_windows(r, phi, enabled, direction, angle_rad, x0_mm, x1_mm, yh_mm, dphi, i0, i1, margin=2):
    """Firing windows ``(k, lo, hi)`` per track, as offsets from firing ``i0`` (``hi`` exclusive).

    Outside its windows no drop of nozzle ``k`` can land in the rectangle
    ``x0 <= xl <= x1, |yl| <= yh`` (mm) of the design frame, which is the platform frame turned
    by ``angle_rad``. A circle of radius ``r`` meets the rectangle (``x0 > 0``) where
    ``acos(min(1, x1/r)) <= |alpha| <= min(acos(x0/r), asin(min(1, yh/r)))``: one arc, or two
    when ``r > x1``. The windows are conservative (rectangle grown by 1 nm, arcs by ``margin``
    firings) and clipped to ``[i0, i1]``; the exact test is done per drop by the index kernels.
    Returns three ``int64`` arrays sorted by nozzle then firing. Shared by both kernels.

    Nozzle 0 at 1 mm never reaches the design; nozzle 1 at 50 mm crosses it in one arc; a track
    at 62 mm, beyond the design's outer edge (60 mm), crosses only its two corners:

    >>> k, lo, hi = track_windows(np.array([1.0, 50.0]), np.zeros(2), np.ones(2, bool), 1, 0.0, 10.0, 60.0, 5.0, 0.01, -20, 20)
    >>> k.tolist(), lo.tolist(), hi.tolist()
    ([1], [5], [36])
    >>> k, lo, hi = track_windows(np.array([62.0]), np.zeros(1), np.ones(1, bool), 1, 0.0, 10.0, 60.0, 20.0, 0.01, -50, 50)
    >>> k.tolist(), lo.tolist(), hi.tolist()
    ([0, 0], [13, 71], [30, 88])
    """
    r = np.ascontiguousarray(r, np.float64)
    nmax = 2 * r.shape[0]
    wk = np.empty(nmax, np.int64)
    wlo = np.empty(nmax, np.int64)
    whi = np.empty(nmax, np.int64)
    n = _track_windows_nb(r, np.ascontiguousarray(phi, np.float64), np.ascontiguousarray(enabled, np.bool_), float(direction),
                          float(angle_rad), float(x0_mm), float(x1_mm), float(yh_mm), float(dphi), int(i0), int(i1), int(margin),
                          wk, wlo, whi)
    return wk[:n], wlo[:n], whi[:n]


@njit(cache=True, nogil=True, inline="always")
def _landing_index(a, b, d, e, C, F, c, s, width, height):  # pragma: no cover - jit
    # the same float operations as coords_numpy: col = A c + B s + C, row = D c + E s + F
    u = a * c + b * s + C
    v = d * c + e * s + F
    ok = (u >= 0.0) & (v >= 0.0) & (u < width) & (v < height)
    # where ok, 0 <= u < width < 2**31: truncated to int32 exactly as to int64, and a packed float64 -> int32
    # conversion exists on AVX2 (-> int64 needs AVX-512), so the callers' loops vectorise there too
    return (np.int64(np.int32(v)) * width + np.int64(np.int32(u))) if ok else width * height


@njit(cache=True, nogil=True)
def _window_bounds_nb(A, B, C, D, E, F, wk, wlo, whi, cos_i, sin_i, width, height, first, last):  # pragma: no cover - jit
    sentinel = width * height
    for q in range(wk.shape[0]):
        k = wk[q]
        f = wlo[q]
        while f < whi[q] and _landing_index(A[k], B[k], D[k], E[k], C, F, cos_i[f], sin_i[f], width, height) == sentinel:
            f += 1
        l = whi[q]
        while l > f and _landing_index(A[k], B[k], D[k], E[k], C, F, cos_i[l - 1], sin_i[l - 1], width, height) == sentinel:
            l -= 1
        first[q] = f
        last[q] = l


def window_bounds_numba(A, B, C, D, E, F, wk, wlo, whi, cos_i, sin_i, width, height):
    """First and last+1 firing (offsets into ``cos_i``) of each window whose drop lands in the design.

    Scans inwards from both ends of each window (a few drops each: the windows are tight).
    ``first == last`` when no drop of the window lands in the design.
    """
    first = np.empty(wk.shape[0], np.int64)
    last = np.empty(wk.shape[0], np.int64)
    _window_bounds_nb(A, B, C, D, E, F, wk, wlo, whi, cos_i, sin_i, width, height, first, last)
    return first, last


def window_bounds_numpy(A, B, C, D, E, F, wk, wlo, whi, cos_i, sin_i, width, height):
    n = whi - wlo
    off = np.zeros(n.shape[0], np.int64)
    if n.shape[0] > 1:
        np.cumsum(n[:-1], out=off[1:])
    m = int(n.sum())
    if not m:
        return wlo.copy(), wlo.copy()
    q = np.repeat(np.arange(wk.shape[0]), n)
    t = np.arange(m) - off[q]
    i = wlo[q] + t
    ok = _pointwise_index_numpy(A, B, C, D, E, F, wk[q], cos_i[i], sin_i[i], width, height) != width * height
    f = np.minimum(np.minimum.reduceat(np.where(ok, t, m), off), n)
    l = np.maximum(np.maximum.reduceat(np.where(ok, t + 1, 0), off), f)
    return wlo + f, wlo + l


def _pointwise_index_numpy(A, B, C, D, E, F, k, c, s, width, height):
    """Flat index (``width * height`` = outside) of drops given per drop: nozzle ``k``, cos, sin."""
    u = A[k] * c + B[k] * s + C
    v = D[k] * c + E[k] * s + F
    ok = (u >= 0.0) & (v >= 0.0) & (u < width) & (v < height)
    return np.where(ok, np.floor(v) * width + np.floor(u), width * height).astype(index_dtype(width, height))


def _window_drops(nozzle, row, count):
    """Per drop of the packed windows: nozzle and print row."""
    q = np.repeat(np.arange(nozzle.shape[0]), count)
    t = np.arange(q.shape[0]) - np.repeat(np.cumsum(count) - count, count)
    return nozzle[q], row[q] + t


@njit(cache=True, nogil=True)
def _windows_fill_nb(A, B, C, D, E, F, nozzle, row, count, start, cos_r, sin_r, width, height, idx):  # pragma: no cover - jit
    # Single-threaded on purpose: the inner loop vectorises (SIMD), and no OpenMP runtime is
    # involved (numba's OpenMP threads slowed ~6x when cv2 was loaded in the same process).
    for q in range(nozzle.shape[0]):
        k = nozzle[q]
        a = A[k]
        b = B[k]
        d = D[k]
        e = E[k]
        r0 = row[q]
        n = count[q]
        cs = cos_r[r0:r0 + n]  # slices: zero-based loop, no negative-index checks, so it vectorises
        ss = sin_r[r0:r0 + n]
        dst = idx[start[q]:start[q] + n]
        for t in range(n):
            dst[t] = _landing_index(a, b, d, e, C, F, cs[t], ss[t], width, height)


@njit(cache=True, nogil=True)
def _windows_fill_gather_nb(A, B, C, D, E, F, nozzle, row, count, start, cos_r, sin_r, width, height, idx, flat, out, tile):  # pragma: no cover - jit
    # The first layer: fill the index and gather from it while it is in L1, tile by tile.
    n_rows = out.shape[0]
    for r0 in range(0, n_rows, tile):
        r1 = min(r0 + tile, n_rows)
        for q in range(nozzle.shape[0]):
            lo = max(row[q], r0)
            hi = min(row[q] + count[q], r1)
            if hi <= lo:
                continue
            k = nozzle[q]
            a = A[k]
            b = B[k]
            d = D[k]
            e = E[k]
            cs = cos_r[lo:hi]
            ss = sin_r[lo:hi]
            dst = idx[start[q] + lo - row[q]:start[q] + hi - row[q]]
            for t in range(hi - lo):
                dst[t] = _landing_index(a, b, d, e, C, F, cs[t], ss[t], width, height)
            col = out[lo:hi, k]
            for t in range(hi - lo):
                col[t] = flat[dst[t]]


@njit(cache=True, nogil=True)
def _windows_gather_nb(flat, nozzle, row, count, start, idx, out, tile):  # pragma: no cover - jit
    # Tiles of `tile` firing rows: the (tile, N) block of the output stays in L1 while every
    # window writes its column piece into it (a column walk over all rows would miss L1 each write).
    n_rows = out.shape[0]
    for r0 in range(0, n_rows, tile):
        r1 = min(r0 + tile, n_rows)
        for q in range(nozzle.shape[0]):
            lo = max(row[q], r0)
            hi = min(row[q] + count[q], r1)
            if hi <= lo:
                continue
            s = idx[start[q] + lo - row[q]:start[q] + hi - row[q]]
            col = out[lo:hi, nozzle[q]]
            for t in range(hi - lo):
                col[t] = flat[s[t]]


GATHER_TILE = 64


def windows_fill_numba(coef, nozzle, row, count, start, cos_r, sin_r, width, height, idx):
    """``idx[start[q] + t]`` = design pixel of the drop of nozzle ``nozzle[q]`` at print row ``row[q] + t``."""
    _windows_fill_nb(*coef, nozzle, row, count, start, cos_r, sin_r, width, height, idx)


def windows_fill_numpy(coef, nozzle, row, count, start, cos_r, sin_r, width, height, idx):
    A, B, C, D, E, F = coef
    k, r = _window_drops(nozzle, row, count)
    idx[:] = _pointwise_index_numpy(A, B, C, D, E, F, k, cos_r[r], sin_r[r], width, height)


def windows_gather_numba(flat, nozzle, row, count, start, idx, out):
    """``out[row[q] + t, nozzle[q]] = flat[idx[start[q] + t]]`` for ``t < count[q]``.

    ``out`` is a zeroed ``(F, N) uint8``; ``flat`` holds the drop level of every design pixel
    and ends with a 0 sentinel (index ``width * height``).
    """
    _windows_gather_nb(flat, nozzle, row, count, start, idx, out, GATHER_TILE)
    return out


def windows_gather_numpy(flat, nozzle, row, count, start, idx, out):
    k, r = _window_drops(nozzle, row, count)
    out[r, k] = flat[idx]
    return out


def windows_fill_gather_numba(coef, nozzle, row, count, start, cos_r, sin_r, width, height, idx, flat, out):
    """:func:`windows_fill_numba` and :func:`windows_gather_numba` in one pass (the first layer)."""
    _windows_fill_gather_nb(*coef, nozzle, row, count, start, cos_r, sin_r, width, height, idx, flat, out, GATHER_TILE)
    return out


def windows_fill_gather_numpy(coef, nozzle, row, count, start, cos_r, sin_r, width, height, idx, flat, out):
    windows_fill_numpy(coef, nozzle, row, count, start, cos_r, sin_r, width, height, idx)
    return windows_gather_numpy(flat, nozzle, row, count, start, idx, out)


#: Design pixels per side of the ink blocks by which :func:`windows_sample_thin_numba` skips pieces of
#: track (a power of two, a constant of the compiled kernel; 8 px: 6.96 ms at 0 deg, 1440 dpi, 16 px: 7.64).
INK_BLOCK = 8


@njit(cache=True, nogil=True, inline="always")
def _ink_state(a, b, d, e, C, F, c0, s0, c1, s1, width, height, sat):  # pragma: no cover - jit
    # Of a piece of track from (c0, s0) to (c1, s1): 0 when no drop can land on ink, 2 when every drop lands
    # on ink, else 1. From the box of its end points, grown by the arc's sagitta (bounded by chord^2 / 4 on
    # the unit circle, scaled by the map's gain) and 1 px: outside the design, or no block with ink in it
    # (0); inside the design and all its blocks all ink (2)
    ch2 = (c1 - c0) * (c1 - c0) + (s1 - s0) * (s1 - s0)
    mu = math.sqrt(a * a + b * b) * ch2 * 0.25 + 1.0
    mv = math.sqrt(d * d + e * e) * ch2 * 0.25 + 1.0
    u0 = a * c0 + b * s0 + C
    u1 = a * c1 + b * s1 + C
    v0 = d * c0 + e * s0 + F
    v1 = d * c1 + e * s1 + F
    ua = min(u0, u1) - mu
    ub = max(u0, u1) + mu
    va = min(v0, v1) - mv
    vb = max(v0, v1) + mv
    if not (ub == ub and vb == vb and ua == ua and va == va):  # NaN: no claim
        return 1
    if not (ub >= 0.0 and vb >= 0.0 and ua < width and va < height):
        return 0
    x0 = int(math.floor(max(ua, 0.0))) // INK_BLOCK  # clamped before the conversion to int
    x1 = int(math.floor(min(ub, width - 1.0))) // INK_BLOCK + 1
    y0 = int(math.floor(max(va, 0.0))) // INK_BLOCK
    y1 = int(math.floor(min(vb, height - 1.0))) // INK_BLOCK + 1
    if sat[0, y1, x1] - sat[0, y0, x1] - sat[0, y1, x0] + sat[0, y0, x0] == 0:
        return 0
    if ua >= 0.0 and va >= 0.0 and ub < width and vb < height and \
            sat[1, y1, x1] - sat[1, y0, x1] - sat[1, y1, x0] + sat[1, y0, x0] == (y1 - y0) * (x1 - x0):
        return 2
    return 1


@njit(cache=True, nogil=True)
def _windows_sample_thin_nb(A, B, C, D, E, F, nozzle, row, count, cos_r, sin_r, width, height, flat, out, tile, f, o, first,
                            sat, level, claim_rows):  # pragma: no cover - jit
    # Track-major in tiles of `tile` firing rows: a tile's cos / sin (2 x 8 x tile bytes) stay in L1 and the
    # (tile, N) block of `out` in L2 while every window writes its column piece. A piece whose drops can
    # land on no ink (`_ink_state`, from its end points and the design's blocks) stays 0; one whose drops
    # all land on ink gets `level` where kept. Otherwise: the thinning floors (one per firing), then the
    # landing index of the kept drops (the others point at the 0 sentinel), vectorised; then the gather.
    # No index is stored (a pass's maps serve one print). `level`: the non-zero value of `flat` (binary);
    # `claim_rows`: the longest piece whose arc spans at most pi / 2 (the sagitta bound holds), longer ones are computed.
    n_rows = out.shape[0]
    sentinel = width * height
    g = np.empty(tile + 1, np.float64)
    tmp = np.empty(tile, np.int64)
    for r0 in range(0, n_rows, tile):
        r1 = min(r0 + tile, n_rows)
        for q in range(nozzle.shape[0]):
            lo = max(row[q], r0)
            hi = min(row[q] + count[q], r1)
            if hi <= lo:
                continue
            k = nozzle[q]
            a = A[k]
            b = B[k]
            d = D[k]
            e = E[k]
            state = _ink_state(a, b, d, e, C, F, cos_r[lo], sin_r[lo], cos_r[hi - 1], sin_r[hi - 1], width, height, sat) \
                if hi - lo <= claim_rows else 1
            if state == 0:
                continue
            n = hi - lo
            thin_floors_jit(g, float(lo + first), n, f[k], o[k])
            col = out[lo:hi, k]
            if state == 2:  # every drop on ink: the level where kept, no landing point needed
                for t in range(n):  # (arithmetic, not a select: the same bytes, and vectorised on AVX2 too)
                    col[t] = np.uint8(g[t + 1] > g[t]) * level
                continue
            cs = cos_r[lo:hi]
            ss = sin_r[lo:hi]
            for t in range(n):
                tmp[t] = _landing_index(a, b, d, e, C, F, cs[t], ss[t], width, height) if g[t + 1] > g[t] else sentinel
            for t in range(n):
                col[t] = flat[tmp[t]]


#: Firing rows per tile of :func:`windows_sample_thin_numba` (measured at 0 deg, 1440 dpi: 64 rows 9.0, 128 rows 8.6 ms).
SAMPLE_TILE = 128


@njit(cache=True, nogil=True)
def _ink_blocks_nb(flat, width, height, sat):  # pragma: no cover - jit
    # per block row: "or" and "and" of its INK_BLOCK pixels (a constant: the loops unroll and vectorise; flat
    # holds one non-zero value, so the "and" is non-zero exactly when every pixel is ink)
    nby = sat.shape[1] - 1
    nbx = sat.shape[2] - 1
    some = np.zeros((nby, nbx), np.uint8)
    full = np.ones((nby, nbx), np.uint8)
    nfull = width // INK_BLOCK
    for y in range(height):
        by = y // INK_BLOCK
        row = flat[y * width:(y + 1) * width]
        for bx in range(nfull):
            m_or = np.uint8(0)
            m_and = np.uint8(255)
            for x in range(INK_BLOCK):
                v = row[bx * INK_BLOCK + x]
                m_or |= v
                m_and &= v
            some[by, bx] |= m_or != 0
            full[by, bx] &= m_and != 0
        if nfull < nbx:  # the last, narrower block
            for x in range(nfull * INK_BLOCK, width):
                v = row[x]
                some[by, nfull] |= v != 0
                full[by, nfull] &= v != 0
    sat[:, :, :] = 0
    for by in range(nby):
        for bx in range(nbx):
            sat[0, by + 1, bx + 1] = some[by, bx] + sat[0, by, bx + 1] + sat[0, by + 1, bx] - sat[0, by, bx]
            sat[1, by + 1, bx + 1] = full[by, bx] + sat[1, by, bx + 1] + sat[1, by + 1, bx] - sat[1, by, bx]


def ink_blocks(flat, width, height):
    """Summed-area tables ``(2, ceil(H / B) + 1, ceil(W / B) + 1) int32`` of the design's ``B x B``
    pixel blocks (``B`` = :data:`INK_BLOCK`): ``[0]`` those holding ink (``flat`` non-zero), ``[1]``
    those all ink (every pixel of the block that is in the design); ``flat`` as for
    :func:`windows_gather_numba`, one non-zero value (a binary design's)."""
    sat = np.empty((2, -(-height // INK_BLOCK) + 1, -(-width // INK_BLOCK) + 1), np.int32)
    _ink_blocks_nb(flat, int(width), int(height), sat)
    return sat


def windows_sample_thin_numba(coef, nozzle, row, count, cos_r, sin_r, width, height, flat, out, f, o, first_firing, sat=None, level=None):
    """The windows' drops sampled and thinned in one sweep, without the index (binary designs).

    ``out[row[q] + t, k] = flat[pixel]`` (``k = nozzle[q]``, ``pixel`` the design pixel the drop of
    print row ``row[q] + t`` lands in) where firing ``first_firing + row[q] + t`` of track ``k``
    is kept by the rule of :func:`rotoprint.rotary._thin_kernels.kept_jit` with share ``f[k]``
    and phase ``o[k]`` (``f``, ``o``: ``(N,) float64``), else 0. ``out``: zeroed ``(F, N) uint8``;
    ``flat``: as for :func:`windows_gather_numba`, one non-zero value; ``sat``:
    :func:`ink_blocks` of ``flat`` and ``level`` its non-zero value (found when not given).
    The same image as the gather, then :func:`rotoprint.rotary.equalise.thin_print`.
    """
    if sat is None:
        sat = ink_blocks(flat, width, height)
    level = np.uint8(flat.max() if level is None else level)
    _windows_sample_thin_nb(*coef, nozzle, row, count, cos_r, sin_r, width, height, flat, out, SAMPLE_TILE,
                            np.ascontiguousarray(f, np.float64), np.ascontiguousarray(o, np.float64), int(first_firing),
                            sat, level, claim_rows(cos_r, sin_r))
    return out


def claim_rows(cos_r, sin_r) -> int:
    """The longest piece of firing rows (``cos_r``, ``sin_r``: ``(F,) float64``) whose ink blocks
    :func:`_ink_state` may claim: the platform's turn per firing row, from the first two rows; a
    piece's sagitta bound holds while its arc turns at most pi (a window's arc inside the design
    always does); pieces turning more than pi / 2 make no claim."""
    dphi = abs(math.atan2(cos_r[0] * sin_r[1] - sin_r[0] * cos_r[1], cos_r[0] * cos_r[1] + sin_r[0] * sin_r[1])) \
        if cos_r.shape[0] > 1 else 0.0
    return int(min(0.5 * math.pi / dphi, 2.0**40)) if dphi > 0 else 2**40


def windows_sample_thin_numpy(coef, nozzle, row, count, cos_r, sin_r, width, height, flat, out, f, o, first_firing, sat=None, level=None):
    A, B, C, D, E, F = coef
    k, r = _window_drops(nozzle, row, count)
    keep = kept_numpy(r + float(first_firing), np.asarray(f, np.float64)[k], np.asarray(o, np.float64)[k])
    k, r = k[keep], r[keep]
    out[r, k] = flat[_pointwise_index_numpy(A, B, C, D, E, F, k, cos_r[r], sin_r[r], width, height)]
    return out


@njit(cache=True, nogil=True)
def _binary_levels_nb(src, level, dst):  # pragma: no cover - jit
    # one vectorised pass: levels, and the largest and the smallest non-zero value
    n = src.shape[0]
    hi = np.uint8(0)
    lo = np.uint8(255)
    for i in range(n):
        x = src[i]
        dst[i] = level if x != 0 else np.uint8(0)
        hi = max(hi, x)
        lo = min(lo, x if x != 0 else np.uint8(255))
    dst[n] = 0
    return hi == 0 or lo == hi


def binary_levels_numba(design, level):
    """``(flat, is_binary)``: ``level`` where the design is non-zero, else 0, plus a 0 sentinel.

    ``is_binary``: the design holds at most one non-zero value (``design_kind`` = "binary").
    """
    src = np.ascontiguousarray(design).ravel()
    flat = np.empty(src.shape[0] + 1, np.uint8)
    ok = _binary_levels_nb(src, np.uint8(level), flat)
    return flat, bool(ok)


def binary_levels_numpy(design, level):
    src = np.asarray(design).ravel()
    nz = src != 0
    flat = np.concatenate([np.where(nz, np.uint8(level), np.uint8(0)), np.zeros(1, np.uint8)])
    m = src.max() if src.size else 0
    return flat, not bool(np.any(nz & (src != m)))


WINDOW_BOUNDS = {"jit": window_bounds_numba, "numpy": window_bounds_numpy}
WINDOWS_FILL = {"jit": windows_fill_numba, "numpy": windows_fill_numpy}
WINDOWS_GATHER = {"jit": windows_gather_numba, "numpy": windows_gather_numpy}
WINDOWS_FILL_GATHER = {"jit": windows_fill_gather_numba, "numpy": windows_fill_gather_numpy}
WINDOWS_SAMPLE_THIN = {"jit": windows_sample_thin_numba, "numpy": windows_sample_thin_numpy}
BINARY_LEVELS = {"jit": binary_levels_numba, "numpy": binary_levels_numpy}
