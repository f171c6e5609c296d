"""Union-find over ``(n,) int64`` parent arrays: find with path halving, union keeping the
smaller root, and the relabelling of the sets as ``0..k-1`` in order of first member (the
chains, the islands and the cavities all label their sets so)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _find(parent, i):  # pragma: no cover - jit
    """The root of ``i``'s set (path halving)."""
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, nogil=True)
def _union(parent, a, b):  # pragma: no cover - jit
    """Join the sets of ``a`` and ``b``; the smaller root stays root."""
    a = _find(parent, a)
    b = _find(parent, b)
    if a != b:
        if a < b:
            parent[b] = a
        else:
            parent[a] = b


@njit(cache=True, nogil=True)
def _relabel(parent, skip):  # pragma: no cover - jit
    """The sets of ``parent`` numbered ``0..k-1`` in order of their first member: ``(n,)
    int64`` labels and ``k``. With ``skip`` non-empty (``(n,) bool`` per root), the members
    of a set whose root is flagged get -1 and the set no number."""
    n = parent.shape[0]
    lab = np.full(n, -1, np.int64)
    root_lab = np.full(n, -1, np.int64)
    some = skip.shape[0] > 0
    k = 0
    for i in range(n):
        r = _find(parent, i)
        if some and skip[r]:
            continue
        if root_lab[r] < 0:
            root_lab[r] = k
            k += 1
        lab[i] = root_lab[r]
    return lab, k
