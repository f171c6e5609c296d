"""Pieces the film band tools share (``bench/film_thin.py``, ``bench/film_dead.py``): which of
the thinnest cells to print, and the union's track gap at a radius."""

from __future__ import annotations

import numpy as np


def thinnest_apart(values: np.ndarray, rad_mm: np.ndarray, count: int, apart_mm: float) -> list[int]:
    """Indices of up to ``count`` cells, thinnest first (``values`` (M,) float), each at least
    ``apart_mm`` in radius from every one chosen before it (``rad_mm`` (M,) float, mm): the
    worst places, not the worst cells of one place."""
    shown: list[float] = []
    picked: list[int] = []
    for i in np.argsort(values):
        if len(picked) >= count:
            break
        if any(abs(rad_mm[i] - s) < apart_mm for s in shown):
            continue
        shown.append(float(rad_mm[i]))
        picked.append(int(i))
    return picked


def union_gap_um(union_mm: np.ndarray, r_mm: float) -> float:
    """The gap (um) between the two tracks of the sorted union radii ``union_mm`` (mm) either
    side of ``r_mm``; NaN outside the union."""
    g_i = np.searchsorted(union_mm, r_mm)
    return float((union_mm[g_i] - union_mm[g_i - 1]) * 1000) if 0 < g_i < union_mm.size else float("nan")
