"""Grey levels on the polar lattice: the 1/r equalisation by drop size instead of by skipping drops.

A head with ``grey_levels = G > 1`` fires drops of ``L / G`` of its full volume, ``L = 1..G``.
With one angular clock a track at radius ``r_k`` gets a drop every ``r_k * dphi``, so the
volume per area falls as ``1 / r`` (and varies with the local track pitch of a tilted head).
:func:`halftone_print` gives every printing site of track ``k`` the level ``G * f_k`` on
average, ``f_k`` the track's share from :func:`~rotoprint.rotary.interlace.track_fractions`
(the sparsest tracks print full drops), quantised by error diffusion along the track (the error
of each site carried to the next one of the same track, kernel in ``_halftone_kernels``): over
any run of sites the levels sum to the wanted volume within one level, every site keeps a drop
of at least ``min_level``, and no site is skipped, so the drop lattice (and the coverage the
plan chose) is unchanged.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ..errors import ConfigError
from . import _halftone_kernels as _k

__all__ = ["halftone_print"]


def halftone_print(pr, fractions: Sequence[np.ndarray], *, min_level: int = 1, use_jit: bool = True):
    """``pr`` with every printing site of track ``k`` of swathe ``j`` at ``G * fractions[j][k]`` levels on average.

    Parameters
    ----------
    pr : RotaryPrint
        A print whose sites that print carry any level > 0 (a binary design's print).
    fractions : sequence of (N,) float
        One per swathe, shares in [0, 1].
    min_level : int
        Smallest level a printing site keeps, 0..G.
    use_jit : bool

    Returns
    -------
    RotaryPrint

    Raises
    ------
    ConfigError
        The head has one level, shares outside [0, 1] or of the wrong length, ``min_level`` out of range.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> from rotoprint.rotary import Placement, transform_exact
    >>> head = load_device("omnidot760").head.model_copy(update={"grey_levels": 8})
    >>> pr = transform_exact(np.full((20, 20), 255, np.uint8), head, Placement(20, 20, 0.0705, 0.0705, inner_radius_mm=60.0), tilt_deg=0.0)
    >>> g = halftone_print(pr, [np.full(764, 0.3)])
    >>> lv = g.swathes[0].levels[pr.swathes[0].levels > 0]
    >>> round(float(lv.mean()), 1), int(lv.min()), int(lv.max())
    (2.4, 2, 3)
    """
    g = pr.head.grey_levels
    if g < 2:
        raise ConfigError("halftoning needs a head with grey_levels > 1")
    if not 0 <= int(min_level) <= g:
        raise ConfigError(f"min_level must be 0..{g}, got {min_level!r}")
    if len(fractions) != len(pr.swathes):
        raise ConfigError(f"one share array per swathe: {len(pr.swathes)} expected, got {len(fractions)}")
    fn = _k.diffuse_jit if use_jit else _k.diffuse_numpy
    out = []
    for sw, f in zip(pr.swathes, fractions):
        f = np.asarray(f, np.float64)
        if f.shape != (sw.levels.shape[1],) or not (np.isfinite(f).all() and (f >= 0).all() and (f <= 1).all()):
            raise ConfigError(f"shares must be {sw.levels.shape[1]} numbers in [0, 1] per swathe")
        mask = sw.levels > 0
        lev = np.zeros_like(sw.levels)
        fn(mask, f * g, g, int(min_level), lev)
        out.append(dataclasses.replace(sw, levels=lev))
    return dataclasses.replace(pr, swathes=tuple(out))
