"""Jit-compiled fibre fill (numba); same contract as :mod:`._fill` (the numpy reference),
but output-sensitive: crossings are bucketed per fibre, sorted, and only the spans that the
fill rule puts inside are written. Work is proportional to crossings plus filled pixels,
not to the image size.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, inline="always")
def _fibre_range(lv, hv, n_fib):  # pragma: no cover - jit
    j0 = math.ceil(lv) if lv > 0.0 else 0
    j1 = (math.ceil(hv) if hv < n_fib else n_fib) if hv > 0.0 else 0
    return j0, max(j1, j0) if j0 < n_fib else j0


@njit(cache=True, nogil=True)
def bucket_crossings(ua, va, ub, vb, n_fib, n_samp):  # pragma: no cover - jit
    """Every crossing of a segment with a fibre, bucketed per fibre and sorted along it.

    Returns ``start`` ``(n_fib + 1,) int64`` (fibre ``j``'s crossings are
    ``start[j]:start[j + 1]``), ``pos`` ``(C,) int64`` (the first sample each crossing counts
    for, clipped to ``0..n_samp``), ``sgn`` ``(C,) int8`` (its winding sign), and ``jlo``,
    ``jhi``: the fibres ``jlo <= j < jhi`` that hold any crossing.
    """
    n_seg = ua.shape[0]
    # pass 1: crossings per fibre, by a difference array over fibres
    per = np.zeros(n_fib + 1, np.int64)
    jlo = n_fib
    jhi = 0
    for s in range(n_seg):
        v0 = va[s]
        v1 = vb[s]
        if v0 == v1:
            continue
        lv, hv = (v0, v1) if v0 < v1 else (v1, v0)
        j0, j1 = _fibre_range(lv, hv, n_fib)
        if j0 < j1:
            per[j0] += 1
            per[j1] -= 1
            jlo = min(jlo, j0)
            jhi = max(jhi, j1)
    jhi = max(jhi, jlo)
    start = np.zeros(n_fib + 1, np.int64)
    acc = 0
    run = 0
    for j in range(jlo, jhi):
        run += per[j]
        start[j] = acc
        acc += run
    start[jhi:] = acc
    pos = np.empty(acc, np.int64)
    sgn = np.empty(acc, np.int8)
    cur = start[:n_fib].copy()
    # pass 2: where each crossing counts from (first sample with u >= u_c), and its sign
    for s in range(n_seg):
        v0 = va[s]
        v1 = vb[s]
        if v0 == v1:
            continue
        if v0 < v1:
            sign = -1
            lu, lv, hu, hv = ua[s], v0, ub[s], v1
        else:
            sign = 1
            lu, lv, hu, hv = ub[s], v1, ua[s], v0
        j0, j1 = _fibre_range(lv, hv, n_fib)
        slope = (hu - lu) / (hv - lv)
        for j in range(j0, j1):
            u = lu + (j - lv) * slope
            if u <= 0.0:
                i = 0
            elif u >= n_samp:
                i = n_samp
            else:
                i = math.ceil(u)
            k = cur[j]
            pos[k] = i
            sgn[k] = sign
            cur[j] = k + 1
    # pass 3: sort each fibre's crossings along it (insertion sort: fibres hold few)
    for j in range(jlo, jhi):
        a = start[j]
        b = start[j + 1]
        for k in range(a + 1, b):
            p = pos[k]
            q = sgn[k]
            m = k - 1
            while m >= a and pos[m] > p:
                pos[m + 1] = pos[m]
                sgn[m + 1] = sgn[m]
                m -= 1
            pos[m + 1] = p
            sgn[m + 1] = q
    return start, pos, sgn, jlo, jhi


@njit(cache=True, nogil=True)
def _fill_spans(ua, va, ub, vb, n_fib, n_samp, evenodd, out):  # pragma: no cover - jit
    start, pos, sgn, jlo, jhi = bucket_crossings(ua, va, ub, vb, n_fib, n_samp)
    # per fibre, write the spans the fill rule puts inside
    for j in range(jlo, jhi):
        a = start[j]
        b = start[j + 1]
        w = 0
        prev = 0
        for k in range(a, b):
            i = pos[k]
            inside = (w & 1) != 0 if evenodd else w != 0
            if inside and i > prev:
                out[j, prev:i] = 255
            w += sgn[k]
            prev = i
        inside = (w & 1) != 0 if evenodd else w != 0
        if inside and prev < n_samp:
            out[j, prev:n_samp] = 255
    return out


def fill_jit(ua, va, ub, vb, n_fib: int, n_samp: int, rule: str) -> np.ndarray:
    """``(n_fib, n_samp) uint8`` image, 255 inside; see :func:`._fill.fill_numpy` for the
    contract."""
    out = np.zeros((n_fib, n_samp), np.uint8)
    as64 = [np.ascontiguousarray(x, dtype=np.float64) for x in (ua, va, ub, vb)]
    return _fill_spans(*as64, n_fib, n_samp, rule == "evenodd", out)


@njit(cache=True, nogil=True)
def _crossing(V, lo, hi, z, out, k):  # pragma: no cover - jit
    # the same operations, in the same order, as _sections.section_numpy
    zl = V[lo, 2]
    t = (z - zl) / (V[hi, 2] - zl)
    out[k, 0] = V[lo, 0] + t * (V[hi, 0] - V[lo, 0])
    out[k, 1] = V[lo, 1] + t * (V[hi, 1] - V[lo, 1])


@njit(cache=True, nogil=True)
def section_kernel(V, F, FE, faces, z):  # pragma: no cover - jit
    """Segments of ``faces`` (all crossing ``z``): ``(K, 2)`` start and end, ``(K,)`` edges."""
    k_n = faces.shape[0]
    start = np.empty((k_n, 2))
    end = np.empty((k_n, 2))
    se = np.empty(k_n, np.int64)
    ee = np.empty(k_n, np.int64)
    for k in range(k_n):
        f = faces[k]
        a0 = V[F[f, 0], 2] >= z
        a1 = V[F[f, 1], 2] >= z
        a2 = V[F[f, 2], 2] >= z
        ab = (a0, a1, a2)
        for side in range(3):
            nxt = (side + 1) % 3
            va = F[f, side]
            vb = F[f, nxt]
            if (not ab[side]) and ab[nxt]:  # from below to above: the segment ends here
                _crossing(V, va, vb, z, end, k)
                ee[k] = FE[f, side]
            elif ab[side] and not ab[nxt]:  # from above to below: the segment starts here
                _crossing(V, vb, va, z, start, k)
                se[k] = FE[f, side]
    return start, end, se, ee


@njit(cache=True, nogil=True)
def union_labels(a, b, n_nodes):  # pragma: no cover - jit
    """Connected components of the graph with edges ``a[k] - b[k]``; the label of ``a[k]``."""
    parent = np.arange(n_nodes)
    for k in range(a.shape[0]):
        x = a[k]
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        y = b[k]
        while parent[y] != y:
            parent[y] = parent[parent[y]]
            y = parent[y]
        if x != y:
            parent[max(x, y)] = min(x, y)
    out = np.empty(a.shape[0], np.int64)
    for k in range(a.shape[0]):
        x = a[k]
        while parent[x] != x:
            x = parent[x]
        out[k] = x
    return out
