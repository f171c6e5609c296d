"""Per-pixel Python baseline of the exact mapping, the way it is written without numpy.

Same mapping as :func:`rotoprint.rotary.exact_maps` + apply: for every swathe, firing and
enabled nozzle, land the drop, convert it to design coordinates, sample nearest. Used by
bench_rotary.py (on a subset of firings, extrapolated) and checked there against the library.
"""

from __future__ import annotations

import math


def transform_rows(design, width, height, pitch_x, pitch_y, r0, r, phi, enabled, first_firing, dphi, direction, rows):
    """``rows``: firing offsets to compute; returns ``{b: [value per nozzle]}``."""
    out = {}
    n = len(r)
    for b in rows:
        i = first_firing + b
        line = [0] * n
        for k in range(n):
            if not enabled[k]:
                continue
            a = phi[k] - direction * i * dphi
            x = r[k] * math.cos(a)
            y = r[k] * math.sin(a)
            c = math.floor((x - r0) / pitch_x)
            j = math.floor(height / 2.0 - y / pitch_y)
            if 0 <= c < width and 0 <= j < height:
                line[k] = 1 if design[j][c] else 0
        out[b] = line
    return out
