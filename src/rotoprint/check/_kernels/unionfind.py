"""Union-find over ``(n,) int64`` parent arrays: find with path halving, union keeping the
smaller root, and the relabelling of the sets as ``0..k-1`` in order of first member (the
chains, the islands and the cavities all label their sets so)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _find(parent, i):  # pragma: no cover - jit
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
