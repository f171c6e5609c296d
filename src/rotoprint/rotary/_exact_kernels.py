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
    "numba": (coords_numba, bilinear_numba),
    "numpy": (coords_numpy, bilinear_numpy),
}


@njit(cache=True, parallel=True, nogil=True)
def _index_nb(A, B, C, D, E, F, ks, cos_i, sin_i, width, height, idx_out, hit_out):  # pragma: no cover - jit
    n_f = cos_i.shape[0]
    n_k = idx_out.shape[1]
    sentinel = width * height
    for i in prange(n_f):
        for k in range(n_k):
            idx_out[i, k] = sentinel
        c = cos_i[i]
        s = sin_i[i]
        hit = False
        for q in range(ks.shape[0]):
            k = ks[q]
            u = A[k] * c + B[k] * s + C
            v = D[k] * c + E[k] * s + F
            if u >= 0.0 and v >= 0.0 and u < width and v < height:
                idx_out[i, k] = int(v) * width + int(u)
                hit = True
        hit_out[i] = hit


def index_numba(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height):
    """Nearest-pixel index map ``(F, N) int32`` and per-firing hit flags ``(F,) bool``."""
    n_f, n_k = cos_i.shape[0], A.shape[0]
    idx = np.empty((n_f, n_k), np.int32)
    hit = np.empty(n_f, np.bool_)
    _index_nb(A, B, C, D, E, F, np.flatnonzero(enabled).astype(np.int64), cos_i, sin_i, width, height, idx, hit)
    return idx, hit


def index_numpy(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height):
    _, _, idx = coords_numpy(A, B, C, D, E, F, enabled, cos_i, sin_i, width, height)
    return idx, (idx != width * height).any(axis=1)


@njit(cache=True, parallel=True, nogil=True)
def _gather_nb(flat, lut, idx, out):  # pragma: no cover - jit
    n_f, n_k = idx.shape
    for i in prange(n_f):
        for k in range(n_k):
            out[i, k] = lut[flat[idx[i, k]]]


def gather_numba(flat, lut, idx):
    """``out[i, k] = lut[flat[idx[i, k]]]``, ``(F, N) uint8``; ``flat`` ends with a 0 sentinel."""
    out = np.empty(idx.shape, np.uint8)
    _gather_nb(flat, lut, idx, out)
    return out


def gather_numpy(flat, lut, idx):
    return lut[flat[idx]]


INDEX = {"numba": index_numba, "numpy": index_numpy}
GATHER = {"numba": gather_numba, "numpy": gather_numpy}
