"""Points keyed by their exact bits, and the one open-addressing hash table the chain search
looks their starts up in."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def _keys(x, y):  # pragma: no cover - jit
    """``(n,) int64`` hashes of points from their exact bits (equal points, equal keys)."""
    return x.view(np.int64) * np.int64(-7046029254386353131) ^ y.view(np.int64)
