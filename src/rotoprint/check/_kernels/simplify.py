"""The section simplified to a resolution before widths are measured
(:func:`simplify_section`): chains of segments replaced greedily by chords within ``tol``."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


#: :func:`simplify_section` replaces at most this many chained segments by one chord.
_SIMPLIFY_SPAN = 64


@njit(cache=True, nogil=True)
def _greedy_emit(px, py, a, b, tol, out_s, out_e, m):  # pragma: no cover - jit
    """Write to ``out_s[m:], out_e[m:]`` the chords of the polyline ``px[a..b], py[a..b]``
    (``b`` included) that a greedy pass keeps, and return the new count: from each kept
    point, the farthest point (at most ``_SIMPLIFY_SPAN`` on) such that every point in between lies within ``tol`` of the chord
    to it and no farther from the kept point than the chord's end (so it projects onto the
    chord). The directions a chord may take form a wedge narrowed by each point passed (the
    tangents from the kept point to the point's ``tol`` disc): one pass, no trigonometry."""
    i = a
    while i < b:
        ax = px[i]
        ay = py[i]
        # wedge of allowed directions (lo: clockwise bound, hi: counter-clockwise), open at first
        lox = loy = hix = hiy = 0.0
        wedge = False
        dmax2 = 0.0
        tol2 = tol * tol
        j = i + 1
        c = i + 1
        vx = px[c] - ax
        vy = py[c] - ay
        d2 = vx * vx + vy * vy
        while True:
            # the chord i..c is valid; can it reach c + 1?
            if c >= b or c + 1 - i > _SIMPLIFY_SPAN:
                break
            # point c (at vx, vy from i, d2 = its distance squared) joins the points in
            # between: narrow the wedge by the tangents to its disc (the direction to it
            # turned by -/+ asin(tol / d), scaled by d)
            if d2 > dmax2:
                dmax2 = d2
            if d2 > tol2:
                cs = math.sqrt(d2 - tol2)
                lx = cs * vx + tol * vy
                ly = -tol * vx + cs * vy
                hx = cs * vx - tol * vy
                hy = tol * vx + cs * vy
                if not wedge:
                    lox, loy, hix, hiy = lx, ly, hx, hy
                    wedge = True
                else:
                    if lox * ly - loy * lx > 0.0:  # the new bound is counter-clockwise of lo
                        lox, loy = lx, ly
                    if hix * hy - hiy * hx < 0.0:  # the new bound is clockwise of hi
                        hix, hiy = hx, hy
                    if lox * hiy - loy * hix < 0.0:
                        break  # empty wedge: no chord past c
            qx = px[c + 1] - ax
            qy = py[c + 1] - ay
            q2 = qx * qx + qy * qy
            if q2 < dmax2:
                break
            if wedge and (lox * qy - loy * qx < 0.0 or qx * hiy - qy * hix < 0.0):
                break
            c += 1
            j = c
            vx = qx
            vy = qy
            d2 = q2
        out_s[m, 0] = px[i]
        out_s[m, 1] = py[i]
        out_e[m, 0] = px[j]
        out_e[m, 1] = py[j]
        m += 1
        i = j
    return m


@njit(cache=True, nogil=True)
def simplify_section(start, end, start_edge, end_edge, tol, pos):  # pragma: no cover - jit
    """The section ``(S, 2)`` starts and ends (model mm) with its chains simplified: chained
    segments (one ends on the mesh edge the next starts on, bit-identical joint, neither edge
    shared by another segment) are replaced by chords along which every dropped joint lies
    within ``tol`` mm (and between the chord's ends). Joints are never moved, chains are never
    joined to others, a closed chain keeps at least three chords (a loop smaller than the
    tolerance is kept whole rather than flattened to nothing), and segments that do not chain
    (gap closing, non-manifold edges) are kept as they are, so every point of the result lies within ``tol`` of the section and
    every point of the section within ``tol`` of the result.

    ``pos`` is an ``int32`` buffer of entries all -1, and is left so (one buffer serves every
    layer of a job); it needs ``max(edge) + 1`` entries.

    Returns ``(S', 2)`` starts and ends, ``S' <= S``, chain by chain in order, and 0; or, when
    ``pos`` is too short, two empty arrays and the length it needs.
    """
    n = start.shape[0]
    top = -1
    for i in range(n):
        top = max(top, start_edge[i], end_edge[i])
    if top >= pos.shape[0]:
        return np.empty((0, 2)), np.empty((0, 2)), top + 1
    succ = np.full(n, -1, np.int32)
    npred = np.zeros(n, np.int32)
    dup = False
    for i in range(n):
        e = start_edge[i]
        if e >= 0:
            if pos[e] != -1:
                pos[e] = -2  # two segments start on this edge: neither is chained to
            else:
                pos[e] = i
    for i in range(n):
        e = end_edge[i]
        if e >= 0:
            j = pos[e]
            if j >= 0 and j != i and start[j, 0] == end[i, 0] and start[j, 1] == end[i, 1]:
                succ[i] = j
                npred[j] += 1
    for i in range(n):
        e = start_edge[i]
        if e >= 0:
            pos[e] = -1
    for i in range(n):
        j = succ[i]
        if j >= 0 and npred[j] > 1:
            dup = True
    if dup:  # two segments end where one starts: break both
        for i in range(n):
            j = succ[i]
            if j >= 0 and npred[j] > 1:
                succ[i] = -1
        for j in range(n):
            if npred[j] > 1:
                npred[j] = 0
    # walk the chains: open ones from their heads, then the cycles
    px = np.empty(n + 1)
    py = np.empty(n + 1)
    seen = np.zeros(n, np.bool_)
    out_s = np.empty((n, 2))
    out_e = np.empty((n, 2))
    m = 0
    for phase in range(2):
        for h in range(n):
            if seen[h] or (phase == 0 and npred[h] > 0):
                continue
            # points of the chain from h
            k = 0
            i = h
            while True:
                seen[i] = True
                px[k] = start[i, 0]
                py[k] = start[i, 1]
                k += 1
                j = succ[i]
                if j < 0 or j == h:  # an open chain's end, or back to a cycle's start
                    px[k] = end[i, 0]
                    py[k] = end[i, 1]
                    break
                i = j
            # k segments, points 0..k (a cycle's last point is its first: it is kept)
            m0 = m
            m = _greedy_emit(px, py, 0, k, tol, out_s, out_e, m)
            if j == h and m - m0 < 3 and k >= 3:
                # a loop within the tolerance of a line would become a sliver with no inside
                # (out and back): it is kept as it is
                m = m0
                for q in range(k):
                    out_s[m, 0] = px[q]
                    out_s[m, 1] = py[q]
                    out_e[m, 0] = px[q + 1]
                    out_e[m, 1] = py[q + 1]
                    m += 1
    return out_s[:m], out_e[:m], 0
