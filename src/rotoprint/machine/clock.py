"""The firing clock as a controller makes it: the platform encoder scaled by integer ratios.

The controller fires once every ``divider / multiplier`` encoder counts, so a revolution of
``N`` counts has ``N * multiplier / divider`` firings where the image wants ``2 pi / dphi``.
The ratio left by integers turns each firing by ``2 pi * divider / (N * multiplier)`` instead
of ``dphi``; over one revolution of firings that adds up to the *angle error per revolution*
``(2 pi / dphi) * |2 pi * divider / (N * multiplier) - dphi|``, reported in degrees and in
firing steps. A step whose error is not below one tenth of a firing step is flagged.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

from ..errors import ConfigError

__all__ = ["ClockRatio", "clock_ratio", "FLAG_FRACTION"]

#: An angle error per revolution at or above this fraction of a firing step is flagged.
FLAG_FRACTION = 0.1


@dataclass(frozen=True)
class ClockRatio:
    """``multiplier / divider`` for one swathe's firing clock and what it leaves."""

    multiplier: int
    divider: int
    counts_per_rev: int
    dphi_rad: float
    #: angle per firing the integers give, rad
    clocked_dphi_rad: float
    #: |error| summed over one revolution of firings, rad and in firing steps
    error_per_rev_rad: float
    error_per_rev_steps: float
    flagged: bool

    def to_json(self) -> dict:
        return {"multiplier": self.multiplier, "divider": self.divider, "counts_per_rev": self.counts_per_rev,
                "firings_per_rev": 2 * math.pi / self.dphi_rad,
                "clocked_firings_per_rev": self.counts_per_rev * self.multiplier / self.divider,
                "angle_error_per_rev_deg": math.degrees(self.error_per_rev_rad),
                "angle_error_per_rev_steps": self.error_per_rev_steps, "flagged": self.flagged}


def clock_ratio(dphi_rad: float, counts_per_rev: int, *, max_multiplier: int = 65_535, max_divider: int = 65_535) -> ClockRatio:
    """The integer ratio nearest to ``2 pi / dphi / counts_per_rev`` within the limits.

    Parameters
    ----------
    dphi_rad : float
        Platform rotation per firing, rad (> 0).
    counts_per_rev : int
        Encoder counts per platform revolution.
    max_multiplier, max_divider : int
        The controller's largest multiplier and divider.

    Returns
    -------
    ClockRatio

    Raises
    ------
    ConfigError
        No ratio within the limits comes within 1 % of the wanted one (the controller cannot
        make this clock).

    Examples
    --------
    >>> c = clock_ratio(2 * math.pi / 1000, 4000)
    >>> (c.multiplier, c.divider, c.error_per_rev_rad)
    (1, 4, 0.0)
    """
    if not (dphi_rad > 0 and math.isfinite(dphi_rad)):
        raise ConfigError(f"angle per firing must be > 0 rad, got {dphi_rad!r}")
    want = 2 * math.pi / dphi_rad / counts_per_rev  # multiplier / divider
    best = None
    # best rational approximations with the divider bounded, then with the multiplier bounded
    for lim_d in (max_divider,):
        fr = Fraction(want).limit_denominator(lim_d)
        cands = [fr]
        if fr.numerator > max_multiplier:
            inv = Fraction(1 / want).limit_denominator(max_multiplier)
            cands = [Fraction(inv.denominator, inv.numerator)] if inv.numerator else []
        for c in cands:
            if c.numerator < 1 or c.numerator > max_multiplier or c.denominator > max_divider:
                continue
            err = abs(float(c) - want)
            if best is None or err < best[0]:
                best = (err, c)
    if best is None or abs(float(best[1]) / want - 1) > 0.01:
        raise ConfigError(f"no encoder multiplier <= {max_multiplier} and divider <= {max_divider} makes "
                          f"{want * counts_per_rev:.6g} firings per revolution from {counts_per_rev} counts")
    m, d = best[1].numerator, best[1].denominator
    clocked = 2 * math.pi * d / (counts_per_rev * m)
    err = (2 * math.pi / dphi_rad) * abs(clocked - dphi_rad)
    steps = err / dphi_rad
    return ClockRatio(multiplier=m, divider=d, counts_per_rev=counts_per_rev, dphi_rad=dphi_rad, clocked_dphi_rad=clocked,
                      error_per_rev_rad=err, error_per_rev_steps=steps, flagged=steps >= FLAG_FRACTION)
