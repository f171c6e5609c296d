"""A deterministic test design like the paper's: squares, rectangles, circles, text-sized bars."""

from __future__ import annotations

import numpy as np

__all__ = ["test_design"]


def test_design(size_px: int = 1200, *, seed: int = 7) -> np.ndarray:
    """``(size, size) uint8`` binary design (255 = ink) of squares, rectangles, rings, discs
    and text-sized features (1-4 px bars and gaps, small glyph-like blocks).

    Parameters
    ----------
    size_px : int
        Side of the square image, pixels; a 6 x 6 grid of cells of ``max(size // 6, 10)``
        pixels is drawn from the top-left corner.
    seed : int
        Seed of the random rectangles and blocks; the same seed gives the same image.

    Returns
    -------
    (size_px, size_px) uint8 ndarray
        0 or 255.

    Examples
    --------
    >>> d = test_design(120)
    >>> d.shape, d.dtype, sorted(set(np.unique(d).tolist()))
    ((120, 120), dtype('uint8'), [0, 255])
    """
    n = int(size_px)
    img = np.zeros((n, n), np.uint8)
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:n, 0:n]
    cell = max(n // 6, 10)
    for gy in range(6):
        for gx in range(6):
            y0, x0 = gy * cell, gx * cell
            kind = (gx + 2 * gy) % 5
            m = cell // 8
            if kind == 0:  # square
                img[y0 + m : y0 + cell - m, x0 + m : x0 + cell - m] = 255
            elif kind == 1:  # rectangles of random aspect
                hh = int(rng.integers(cell // 6, cell // 2))
                img[y0 + m : y0 + m + hh, x0 + m : x0 + cell - m] = 255
                img[y0 + m + hh + m : y0 + cell - m, x0 + m : x0 + cell // 2] = 255
            elif kind == 2:  # disc
                cy, cx, r = y0 + cell / 2, x0 + cell / 2, cell / 2 - m
                img[(yy - cy) ** 2 + (xx - cx) ** 2 <= r * r] = 255
            elif kind == 3:  # ring
                cy, cx, r = y0 + cell / 2, x0 + cell / 2, cell / 2 - m
                d2 = (yy - cy) ** 2 + (xx - cx) ** 2
                img[(d2 <= r * r) & (d2 >= (0.6 * r) ** 2)] = 255
            else:  # text-sized: bars of 1..4 px with equal gaps, and small blocks
                x = x0 + m
                for wdt in (1, 2, 3, 4, 4, 3, 2, 1):
                    img[y0 + m : y0 + cell // 2, x : x + wdt] = 255
                    x += 2 * wdt + 1
                for by in range(y0 + cell // 2 + m, y0 + cell - m - 5, 7):
                    for bx in range(x0 + m, x0 + cell - m - 5, 6):
                        if rng.random() < 0.6:
                            img[by : by + 5, bx : bx + 4] = 255
    return img
