"""What a printability check is asked to do (:class:`CheckOptions`), and the same resolved for a
device (:class:`CheckSettings`: the thresholds, the exposure model's cure level, the width up
to which widths are measured, the resolution), which the report prints as its ``settings``."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, fields

import numpy as np

from ..errors import ConfigError
from ..ranges import WIDTH_MM, Range, check_range
from .limits import default_minimum_mm

__all__ = ["CheckOptions", "CheckSettings", "resolution_for"]

#: Walls and gaps narrower than this many pixels are tested against the raster. A chord's
#: test rectangle (the width across, one pixel either side along) holds a pixel centre at any
#: angle and offset once it is one pitch wide (tests/check/test_check_raster.py shows it), so a
#: wall 1.1 pixels wide cannot vanish nor a gap that wide close: 2 pixels measured for nothing.
RASTER_TEST_PX = 1.1
#: Walls and gaps narrower than this many pixels are tested against the exposure.
EXPOSURE_TEST_PX = 3.0
#: Default resolution: widths are measured on the section simplified to this fraction of the
#: smaller pixel pitch (``resolution_mm``; 0 measures on the section as sliced).
RESOLUTION_PX = 0.01


_CAP_MM = Range(0.0, 1000.0, "mm", lo_open=True)


def _positive(name: str, value, *, allow_none: bool = True, rng: Range = WIDTH_MM) -> float | None:
    """A width in ``rng`` (:mod:`rotoprint.ranges`): widths past it would overflow the pixel
    counts of the ray kernels."""
    if value is None and allow_none:
        return None
    return check_range(value, rng, name)


def resolution_for(device, resolution_mm: float | None) -> float:
    """The resolution (mm) widths are measured at on ``device``: ``resolution_mm`` checked
    (a finite number from 0 to a quarter of the smaller pixel pitch), or by default 1/100 of
    that pitch. Raises :class:`~rotoprint.errors.ConfigError` naming the option."""
    pmin = min(device.pitch_x_mm, device.pitch_y_mm)
    if resolution_mm is None:
        return RESOLUTION_PX * pmin
    try:
        res = float(resolution_mm)
    except (TypeError, ValueError):
        raise ConfigError(f"resolution must be a number of mm >= 0, got {resolution_mm!r}") from None
    if not (math.isfinite(res) and 0.0 <= res <= 0.25 * pmin):
        raise ConfigError(f"resolution must be from 0 (the section as sliced) to a quarter pixel ({0.25 * pmin:.6g} mm), got {resolution_mm!r}")
    return res


@dataclass(frozen=True)
class CheckOptions:
    """What to check, as given (``None``: the device's default). Checked when made, except
    what needs the device (the resolution's upper bound), checked by :meth:`resolve`.

    Parameters
    ----------
    min_wall_mm, min_gap_mm : float, optional
        Thresholds; default :func:`~rotoprint.check.limits.default_minimum_mm` (the pitch, or
        an inkjet's drop diameter when larger).
    mask_fn : callable, optional
        Exposure model: ``(H, W) uint8`` binary image to the ``(H, W) uint8`` grey mask the
        projector shows. Without it no exposure check is made.
    mask_name : str
        Its name, for the report.
    cure_threshold : float, optional
        Fraction of full exposure a pixel needs to cure; default the projector's (0.5). Needs
        ``mask_fn``.
    islands : bool
        Look for regions with nothing below them.
    measure_up_to_mm : float, optional
        Widths are measured up to this; the thinnest wall and gap are reported when below it.
        Default ``max(4 * threshold, 8 pixels)``.
    resolution_mm : float, optional
        Widths are measured on the section with its chains simplified to this deviation (a
        dropped joint is at most this far from the chord replacing it); measured widths are
        then within twice this of the section's. Default 1/100 of the smaller pixel pitch;
        0 measures on the section as sliced (slower on finely tessellated parts).
    cavities : bool
        Look for empty space the part shuts in on every side (resin traps).
    tilt_deg, radius_mm : float, optional
        Inkjet on the rotary platform: the report's ``limits`` get the track figures.

    Examples
    --------
    >>> CheckOptions(min_wall_mm=0.05, islands=False).min_wall_mm
    0.05
    >>> CheckOptions(cure_threshold=0.4)
    Traceback (most recent call last):
    ...
    rotoprint.errors.ConfigError: a cure threshold needs an exposure model (mask_fn)
    """

    min_wall_mm: float | None = None
    min_gap_mm: float | None = None
    mask_fn: Callable[[np.ndarray], np.ndarray] | None = None
    mask_name: str = "custom"
    cure_threshold: float | None = None
    islands: bool = True
    measure_up_to_mm: float | None = None
    resolution_mm: float | None = None
    cavities: bool = True
    tilt_deg: float | None = None
    radius_mm: float | None = None

    def __post_init__(self) -> None:
        _positive("min_wall_mm", self.min_wall_mm)
        _positive("min_gap_mm", self.min_gap_mm)
        if self.mask_fn is not None:
            if self.cure_threshold is not None:
                _cure_level(self.cure_threshold)
        elif self.cure_threshold is not None:
            raise ConfigError("a cure threshold needs an exposure model (mask_fn)")
        if not isinstance(self.islands, bool):
            raise ConfigError(f"islands must be True or False, got {self.islands!r}")
        if not isinstance(self.cavities, bool):
            raise ConfigError(f"cavities must be True or False, got {self.cavities!r}")
        _positive("measure_up_to_mm", self.measure_up_to_mm, rng=_CAP_MM)

    @classmethod
    def of(cls, options: CheckOptions | None, given: dict) -> CheckOptions:
        """``options`` with the fields named in ``given`` (keyword arguments of the public
        functions) replacing its own; a name that is no field is a ``TypeError``."""
        names = {f.name for f in fields(cls)}
        bad = sorted(set(given) - names)
        if bad:
            raise TypeError(f"unexpected keyword argument {bad[0]!r} (check options are: {', '.join(sorted(names))})")
        if options is None:
            return cls(**given)
        if not isinstance(options, CheckOptions):
            raise ConfigError(f"options must be CheckOptions, got {type(options).__name__}")
        if not given:
            return options
        return cls(**{**{f.name: getattr(options, f.name) for f in fields(cls)}, **given})

    def resolve(self, device) -> CheckSettings:
        """The settings on ``device``: the defaults filled in, the resolution checked."""
        default, source = default_minimum_mm(device)
        wall = _positive("min_wall_mm", self.min_wall_mm)
        gap = _positive("min_gap_mm", self.min_gap_mm)
        thr = None
        if self.mask_fn is not None:
            cure = self.cure_threshold
            if cure is None:
                cure = device.projector.cure_threshold if device.kind == "projector" else 0.5
            thr = _cure_level(cure)
        w = default if wall is None else wall
        g = default if gap is None else gap
        pmax = max(device.pitch_x_mm, device.pitch_y_mm)
        cap = _positive("measure_up_to_mm", self.measure_up_to_mm, rng=_CAP_MM)
        cap = max(4.0 * max(w, g), 8.0 * pmax) if cap is None else max(cap, w, g, RASTER_TEST_PX * pmax, EXPOSURE_TEST_PX * pmax)
        return CheckSettings(
            min_wall_mm=w,
            min_gap_mm=g,
            min_wall_source=source if wall is None else "given",
            min_gap_source=source if gap is None else "given",
            exposure_model=self.mask_name if self.mask_fn is not None else None,
            cure_threshold=thr,
            islands=self.islands,
            cavities=self.cavities,
            measured_up_to_mm=cap,
            resolution_mm=resolution_for(device, self.resolution_mm),
        )


def _cure_level(value) -> float:
    try:
        thr = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"cure threshold must be in (0, 1], got {value!r}") from None
    if not (math.isfinite(thr) and 0.0 < thr <= 1.0):
        raise ConfigError(f"cure threshold must be in (0, 1], got {value!r}")
    return thr


@dataclass(frozen=True)
class CheckSettings:
    """:class:`CheckOptions` resolved for a device (:meth:`CheckOptions.resolve`): thresholds
    (mm) and where they come from (``"given"`` or the device's basis), the exposure model's
    name and cure level (``None``: no exposure check), what to look for, the width up to which
    widths are measured and the resolution they are measured at."""

    min_wall_mm: float
    min_gap_mm: float
    min_wall_source: str
    min_gap_source: str
    exposure_model: str | None
    cure_threshold: float | None
    islands: bool
    cavities: bool
    measured_up_to_mm: float
    resolution_mm: float

    def to_json(self) -> dict:
        """The report's ``settings`` (before the slicing's are added), in this order."""
        return {f.name: getattr(self, f.name) for f in fields(self)}
