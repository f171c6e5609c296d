"""A layer's material as runs of pixels per row by the slicer's own fill
(:func:`fill_runs`, :func:`section_runs`: equal to its image), and the islands on them
(:func:`island_runs`: 8-connected regions with no material directly below, by union-find over
the runs of neighbouring rows)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ...slicing._kernels import bucket_crossings
from .unionfind import _find, _relabel, _union


@njit(cache=True, nogil=True)
def fill_runs(ua, va, ub, vb, n_fib, n_samp, evenodd):  # pragma: no cover - jit
    """The slicer's fibre fill (:func:`rotoprint.slicing._kernels.fill_jit`, same crossings,
    same rule) as maximal runs instead of an image: ``(n_fib + 1,) int64`` CSR row starts and
    ``(R,) int64`` first and past-the-end columns of each run of material, rows in order and
    columns increasing. Work is proportional to the crossings, not to the image."""
    start, pos, sgn, jlo, jhi = bucket_crossings(ua, va, ub, vb, n_fib, n_samp)
    acc = pos.shape[0]
    rs = np.zeros(n_fib + 1, np.int64)
    r0 = np.empty(acc, np.int64)  # a row's runs are at most its crossings
    r1 = np.empty(acc, np.int64)
    nr = 0
    for j in range(jlo, jhi):
        rs[j] = nr
        a = start[j]
        b = start[j + 1]
        if a == b:
            continue
        w = 0
        prev = 0
        for k in range(a, b + 1):
            i = pos[k] if k < b else n_samp
            inside = (w & 1) != 0 if evenodd else w != 0
            if inside and i > prev:
                if nr > rs[j] and r1[nr - 1] == prev:
                    r1[nr - 1] = i  # touching spans make one run
                else:
                    r0[nr] = prev
                    r1[nr] = i
                    nr += 1
            if k < b:
                w += sgn[k]
                prev = i
    rs[jhi:] = nr
    return rs, r0[:nr].copy(), r1[:nr].copy()


@njit(cache=True, nogil=True)
def island_runs(rs, r0, r1, ps, p0, p1):  # pragma: no cover - jit
    """Islands of a layer given as runs (``rs, r0, r1``, see :func:`fill_runs`) over the layer
    below (``ps, p0, p1``): the 8-connected regions of material none of whose pixels has
    material directly below.

    Returns, per island in raster order of its first pixel: ``(I,)`` pixel count, sums of the
    rows and of the columns of its pixels (float64), first and last row, first and last
    column; and ``(R,) int64`` the island (``0..I-1``) of every run, ``-1`` if supported.
    """
    H = rs.shape[0] - 1
    n = r0.shape[0]
    parent = np.arange(n)
    sup = np.zeros(n, np.bool_)
    # the rows that hold runs
    jlo = np.searchsorted(rs, 1) - 1 if n else 0
    jhi = np.searchsorted(rs, n) if n else 0
    for j in range(max(jlo, 0), jhi):
        # support: overlap with a run of the layer below in the same row (both sorted)
        q = ps[j]
        qe = ps[j + 1]
        for k in range(rs[j], rs[j + 1]):
            while q < qe and p1[q] <= r0[k]:
                q += 1
            if q < qe and p0[q] < r1[k]:
                sup[k] = True
        # 8-connection with the runs of the row above: columns within one
        if j == 0:
            continue
        q = rs[j - 1]
        qe = rs[j]
        for k in range(rs[j], rs[j + 1]):
            while q < qe and r1[q] < r0[k]:  # ends more than one column left of k
                q += 1
            t = q
            while t < qe and r0[t] <= r1[k]:
                _union(parent, k, t)
                t += 1
    root_sup = np.zeros(n, np.bool_)
    for k in range(n):
        if sup[k]:
            root_sup[_find(parent, k)] = True
    # raster order of the first pixel: the first run of each component, runs in raster order
    isl, ni = _relabel(parent, root_sup)
    cnt = np.zeros(ni, np.int64)
    srow = np.zeros(ni)
    scol = np.zeros(ni)
    rlo = np.full(ni, H, np.int64)
    rhi = np.full(ni, -1, np.int64)
    clo = np.full(ni, np.iinfo(np.int64).max, np.int64)
    chi = np.full(ni, -1, np.int64)
    for j in range(max(jlo, 0), jhi):
        for k in range(rs[j], rs[j + 1]):
            i = isl[k]
            if i < 0:
                continue
            L = r1[k] - r0[k]
            cnt[i] += L
            srow[i] += float(j) * L
            scol[i] += 0.5 * float(r0[k] + r1[k] - 1) * L
            rlo[i] = min(rlo[i], j)
            rhi[i] = max(rhi[i], j)
            clo[i] = min(clo[i], r0[k])
            chi[i] = max(chi[i], r1[k] - 1)
    return cnt, srow, scol, rlo, rhi, clo, chi, isl


@njit(cache=True, nogil=True)
def section_runs(start, end, m, n_fib, n_samp, evenodd):  # pragma: no cover - jit
    """:func:`fill_runs` of a section in model mm (``(S, 2)`` starts and ends) through the
    ``(2, 3)`` model-to-pixel affine ``m``, evaluated with the slicer's operations in the
    slicer's order (``(m00 x + m01 y) + m02``), so the crossings are the image's."""
    n = start.shape[0]
    ua = np.empty(n)
    va = np.empty(n)
    ub = np.empty(n)
    vb = np.empty(n)
    for k in range(n):
        ua[k] = (m[0, 0] * start[k, 0] + m[0, 1] * start[k, 1]) + m[0, 2]
        va[k] = (m[1, 0] * start[k, 0] + m[1, 1] * start[k, 1]) + m[1, 2]
        ub[k] = (m[0, 0] * end[k, 0] + m[0, 1] * end[k, 1]) + m[0, 2]
        vb[k] = (m[1, 0] * end[k, 0] + m[1, 1] * end[k, 1]) + m[1, 2]
    return fill_runs(ua, va, ub, vb, n_fib, n_samp, evenodd)


@njit(cache=True, nogil=True)
def _island_stats(rs, r0, r1, ps, p0, p1, below):  # pragma: no cover - jit
    """:func:`island_runs` when ``below`` (else no islands) as ``(7, I)`` per island (pixels,
    mean row, mean column, first and last row, first and last column) and the island of
    every run (-1: supported)."""
    if below and r0.shape[0] > 0:
        cnt, srow, scol, rlo, rhi, clo, chi, isl = island_runs(rs, r0, r1, ps, p0, p1)
    else:
        cnt = np.zeros(0, np.int64)
        srow = np.zeros(0)
        scol = np.zeros(0)
        rlo = rhi = clo = chi = cnt
        isl = np.full(r0.shape[0], -1, np.int64)
    ni = cnt.shape[0]
    st = np.empty((7, ni))
    for i in range(ni):
        st[0, i] = cnt[i]
        st[1, i] = srow[i] / cnt[i]
        st[2, i] = scol[i] / cnt[i]
        st[3, i] = rlo[i]
        st[4, i] = rhi[i]
        st[5, i] = clo[i]
        st[6, i] = chi[i]
    return st, isl
