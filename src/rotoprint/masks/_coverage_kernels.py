"""Jit-compiled exact area coverage (numba); same contract as
:func:`rotoprint.masks.coverage.accumulate_numpy`, which is the reference it is tested against.

Coordinates are continuous pixel indices shifted by +0.5, so that pixel ``(c, r)`` is the
unit square ``[c, c+1] x [r, r+1]``. Every segment is cut into pieces, one per pixel row it
crosses; a piece of signed height ``d`` whose x runs over ``[a, b]`` adds to pixel ``k`` of
its row the signed area ``C(k) = d * mean_x clamp(k + 1 - x, 0, 1)`` (the part of the pixel
right of the piece), and ``d`` to every pixel further right. These are written as
differences into ``acc`` (``(H, W + 1) float64``) so that a running sum along each row gives,
per pixel, the integral of the winding number over the pixel: exact for polygons.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True, inline="always")
def _piece_cover(a, b, k):  # pragma: no cover - jit
    """``mean over x in [a, b] of clamp(k + 1 - x, 0, 1)`` for ``a <= b``."""
    if b - a <= 0.0:
        t = k + 1.0 - a
        return 0.0 if t < 0.0 else (1.0 if t > 1.0 else t)
    left = min(b, float(k)) - a
    if left < 0.0:
        left = 0.0
    lo = max(a, float(k))
    hi = min(b, k + 1.0)
    mid = 0.0
    if hi > lo:
        mid = (hi - lo) * (k + 1.0 - 0.5 * (lo + hi))
    return (left + mid) / (b - a)


@njit(cache=True, nogil=True)
def accumulate_jit(x0s, y0s, x1s, y1s, height, width, acc):  # pragma: no cover - jit
    """Add every segment's signed area differences to ``acc`` (see module doc)."""
    for s in range(x0s.shape[0]):
        ya = y0s[s] + 0.5
        yb = y1s[s] + 0.5
        if ya == yb:
            continue
        xa = x0s[s] + 0.5
        xb = x1s[s] + 0.5
        sign = 1.0
        if ya > yb:
            sign = -1.0
            xa, xb = xb, xa
            ya, yb = yb, ya
        if yb <= 0.0 or ya >= height:
            continue
        slope = (xb - xa) / (yb - ya)
        r0 = int(math.floor(ya)) if ya > 0.0 else 0
        r1 = int(math.ceil(yb)) if yb < height else height
        for r in range(r0, r1):
            top = ya if ya > r else float(r)
            bot = yb if yb < r + 1.0 else r + 1.0
            if bot <= top:
                continue
            # x at both ends of the piece, measured from the segment's own ends for accuracy
            if top == ya:
                xt = xa
            elif top == yb:
                xt = xb
            else:
                xt = xa + (top - ya) * slope
            if bot == yb:
                xbm = xb
            else:
                xbm = xa + (bot - ya) * slope
            d = sign * (bot - top)
            a = xt if xt <= xbm else xbm
            b = xbm if xt <= xbm else xt
            fa = math.floor(a)
            fb = math.floor(b)
            if fb < 0.0:
                acc[r, 0] += d
                continue
            if fa >= width:
                continue
            k0 = int(fa) if fa > 0.0 else 0
            k1 = int(fb) if fb < width - 1 else width - 1
            for k in range(k0, k1 + 1):
                c = d * _piece_cover(a, b, k)
                acc[r, k] += c
                acc[r, k + 1] -= c
            acc[r, k1 + 1] += d
    return acc


@njit(cache=True, nogil=True)
def resolve_jit(acc, width, snap, out):  # pragma: no cover - jit
    """Running sums along rows; ``out`` gets ``min(|sum|, 1)`` (nonzero rule, clamped), with
    values within ``snap`` of 0 or 1 set to 0 or 1 (rounding residue of the running sum)."""
    for r in range(acc.shape[0]):
        run = 0.0
        for k in range(width):
            run += acc[r, k]
            v = abs(run)
            if v < snap:
                v = 0.0
            elif v > 1.0 - snap:
                v = 1.0
            out[r, k] = v
    return out


@njit(cache=True, nogil=True)
def resolve_grey_jit(acc, width, snap, out):  # pragma: no cover - jit
    """As :func:`resolve_jit`, straight to ``uint8`` grey levels with sum-preserving rounding.

    Pixels within ``snap`` of 0 or 1 are 0 or 255. Every other pixel's level ``x = 255 *
    coverage`` is rounded together with the rounding error carried so far (row-major over
    ``out``): ``q = floor(x + carry + 0.5)``, then ``carry += x - q``. So every level is within
    one of ``x`` and the sum of ``out`` is the sum of ``x`` to within half a level.
    """
    carry = 0.0
    for r in range(acc.shape[0]):
        run = 0.0
        for k in range(width):
            run += acc[r, k]
            v = abs(run)
            if v > 1.0 - snap:
                out[r, k] = 255
            elif v < snap:
                out[r, k] = 0
            else:
                x = v * 255.0
                q = math.floor(x + carry + 0.5)
                if q < 0.0:
                    q = 0.0
                elif q > 255.0:
                    q = 255.0
                carry += x - q
                out[r, k] = np.uint8(q)
    return out


@njit(cache=True, nogil=True)
def resolve_nearest_jit(acc, width, out):  # pragma: no cover - jit
    """As :func:`resolve_jit`, to ``uint8`` levels ``round(255 * coverage)`` (half up), each
    pixel on its own (the level right of a window of open loops)."""
    for r in range(acc.shape[0]):
        run = 0.0
        for k in range(width):
            run += acc[r, k]
            v = abs(run)
            if v >= 1.0:
                out[r, k] = 255
            else:
                out[r, k] = np.uint8(math.floor(v * 255.0 + 0.5))
    return out
