"""Chains of a section: pieces joined end to start at ordinary joints (bit-identical points):
their components (:func:`chain_components`), each piece's successor (:func:`chain_successors`)
and runs of chained, nearly collinear segments tested as a whole (:func:`_chain_runs`)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .pointhash import _first, _key_table
from .unionfind import _relabel, _union


#: Runs of chained segments tested as a whole (:func:`_chain_runs`): at most this many
#: segments, each at least this long, every direction within acos(_RUN_COS) = 35 degrees of
#: the first one; runs of fewer than _RUN_MIN_SEGS segments are not tested as a whole.
_RUN_MAX = 48


_RUN_MIN_LEN_MM = 1e-5


_RUN_COS = 0.8191520442889918


_RUN_MIN_SEGS = 3


#: Sections with fewer segments than this are searched and measured without runs (finding
#: the chains costs more than it saves).
_RUNS_FROM = 16384


@njit(cache=True, nogil=True)
def chain_components(sx, sy, ex, ey, join_s, join_e, key_s, key_e):  # pragma: no cover - jit
    """Label the pieces joined end to start at ordinary joints (bit-identical points flagged
    joinable at both sides): ``(Q,) int64`` labels ``0..k-1`` and ``k``. Along such a chain
    nothing crosses or touches, so the fill rule's verdict is the same for all its pieces.
    ``key_s``, ``key_e`` are ``(Q,) int64`` hashes of the start and end points."""
    n = sx.shape[0]
    parent = np.arange(n)
    slot_key, slot_head, nxt, shift = _key_table(key_s)  # the starts with each key
    for i in range(n):
        if not join_e[i]:
            continue
        o = _first(slot_key, slot_head, shift, key_e[i])
        while o >= 0:
            if join_s[o] and sx[o] == ex[i] and sy[o] == ey[i]:
                _union(parent, i, o)
            o = nxt[o]
    return _relabel(parent, np.zeros(0, np.bool_))


@njit(cache=True, nogil=True)
def chain_successors(sx, sy, ex, ey, join_s, join_e, key_s, key_e):  # pragma: no cover - jit
    """The next piece along each chain: ``(Q,) int64``, the one piece whose start is this
    piece's end (bit-identical point, an ordinary joint at both sides), or -1 (a chain end, a
    cut, or a point where several pieces start or end). Keys as :func:`chain_components`."""
    n = sx.shape[0]
    succ = np.full(n, -1, np.int64)
    if n == 0:
        return succ
    slot_key, slot_head, nxt, shift = _key_table(key_s)  # the starts with each key
    npred = np.zeros(n, np.int64)
    for i in range(n):
        if not join_e[i]:
            continue
        o = _first(slot_key, slot_head, shift, key_e[i])
        found = -1
        cnt = 0
        while o >= 0:
            if join_s[o] and sx[o] == ex[i] and sy[o] == ey[i]:
                found = o
                cnt += 1
            o = nxt[o]
        if cnt == 1 and found != i:
            succ[i] = found
            npred[found] += 1
    for i in range(n):
        if succ[i] >= 0 and npred[succ[i]] != 1:
            succ[i] = -1
    return succ


@njit(cache=True, nogil=True)
def _chain_runs(sx, sy, ex, ey, keep, succ, min_len):  # pragma: no cover - jit
    """Cut the chains (``succ`` from :func:`chain_successors`) of kept segments into runs of
    at most ``_RUN_MAX`` consecutive segments, each at least ``min_len`` mm long, whose
    directions all lie within ``_RUN_COS`` (35 degrees) of the run's first: any two differ by
    less than 90 degrees, so no normal ray from a point of the run meets the run again.

    Returns the run of every segment (-1: none), and the runs' members in chain order (CSR:
    ``ptr``, ``mem``)."""
    n = sx.shape[0]
    run = np.full(n, -1, np.int64)
    has_pred = np.zeros(n, np.bool_)
    chained = False
    for k in range(n):
        if succ[k] >= 0 and keep[k]:
            has_pred[succ[k]] = True
            chained = True
    ptr = np.zeros(n + 1, np.int64)
    mem = np.empty(n, np.int64)
    if not chained:  # no chain order: every kept segment is a run of its own, in index order
        nr = 0
        for k in range(n):
            if keep[k]:
                run[k] = nr
                mem[nr] = k
                nr += 1
                ptr[nr] = nr
        return run, ptr[: nr + 1], mem[:nr]
    nr = 0
    pos = 0
    for sweep in range(2):  # chain heads first, then what is left (closed chains)
        for k0 in range(n):
            if not keep[k0] or run[k0] >= 0 or (sweep == 0 and has_pred[k0]):
                continue
            k = k0
            while k >= 0 and keep[k] and run[k] < 0:
                L0 = max(math.hypot(ex[k] - sx[k], ey[k] - sy[k]), 1e-300)
                t0x = (ex[k] - sx[k]) / L0
                t0y = (ey[k] - sy[k]) / L0
                cnt = 0
                while k >= 0 and keep[k] and run[k] < 0 and cnt < _RUN_MAX:
                    L = math.hypot(ex[k] - sx[k], ey[k] - sy[k])
                    if L < min_len and cnt > 0:
                        break
                    if cnt > 0 and ((ex[k] - sx[k]) * t0x + (ey[k] - sy[k]) * t0y) < _RUN_COS * L:
                        break
                    run[k] = nr
                    mem[pos] = k
                    pos += 1
                    cnt += 1
                    k = succ[k]
                    if L < min_len:
                        break  # a tiny segment is a run of its own
                nr += 1
                ptr[nr] = pos
    return run, ptr[: nr + 1], mem[:pos]
