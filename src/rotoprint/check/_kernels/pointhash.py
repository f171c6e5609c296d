"""Points keyed by their exact bits, and the one open-addressing hash table the chain search
looks their starts up in."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _keys(x, y):  # pragma: no cover - jit
    """``(n,) int64`` hashes of points from their exact bits (equal points, equal keys)."""
    return x.view(np.int64) * np.int64(-7046029254386353131) ^ y.view(np.int64)


#: Multiplier of the table's (Fibonacci) hashing.
_MUL = np.uint64(0x9E3779B97F4A7C15)


@njit(cache=True, nogil=True)
def _key_table(keys):  # pragma: no cover - jit
    """Open-addressing hash table of ``keys`` (``(n,) int64``), each slot heading a list of
    the indices with that key: ``(slot_key, slot_head, nxt, shift)``, read with
    :func:`_first`; ``nxt[i]`` is the next index with the key of ``i`` (-1: the last)."""
    n = keys.shape[0]
    bits = 1
    while (1 << bits) < 2 * n:
        bits += 1
    size = 1 << bits
    slot_key = np.empty(size, np.int64)
    slot_head = np.full(size, -1, np.int64)
    nxt = np.full(n, -1, np.int64)
    shift = np.uint64(64 - bits)
    for i in range(n):
        k = keys[i]
        h = _slot(slot_key, slot_head, shift, k)
        if slot_head[h] < 0:
            slot_key[h] = k
        nxt[i] = slot_head[h]
        slot_head[h] = i
    return slot_key, slot_head, nxt, shift


@njit(cache=True, nogil=True, inline="always")
def _slot(slot_key, slot_head, shift, k):  # pragma: no cover - jit
    """The slot of key ``k``: where it is, or the empty slot where it goes."""
    mask = slot_head.shape[0] - 1
    h = np.int64((np.uint64(k) * _MUL) >> shift)
    while slot_head[h] >= 0 and slot_key[h] != k:
        h = (h + 1) & mask
    return h


@njit(cache=True, nogil=True, inline="always")
def _first(slot_key, slot_head, shift, k):  # pragma: no cover - jit
    """The first index with key ``k`` in a :func:`_key_table` (-1: none)."""
    return slot_head[_slot(slot_key, slot_head, shift, k)]
