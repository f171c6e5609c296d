"""The documented range of every numeric input, and the one validator that enforces it.

Every number that enters rotoprint -- a CLI option, a field of a device, job, materials file
or print sidecar -- is checked against one of the ranges below where it enters, with the
option or field named in the error. The ranges are wide enough for any real printer and
narrow enough that no value inside them overflows an integer, a pixel count or an array size
further on (sizes that depend on several values are checked again, before allocation, by
:func:`rotoprint._resources.check_raster_fits` and :func:`check_count`).

========================  ===================  =============================================
quantity                  range                used for
========================  ===================  =============================================
``COORD_MM``              [-10000, 10000] mm   translations, offsets, mesh coordinates
``ANGLE_DEG``             [-3600, 3600] deg    rotations, fibre and platform angles
``TILT_DEG``              (-90, 90) deg        head tilt
``LAYER_HEIGHT_MM``       [1e-4, 100] mm       layer height
``RADIUS_MM``             [1e-3, 1e4] mm       pivot, design and reference radii
``WIDTH_MM``              [1e-4, 100] mm       thinnest wall / narrowest gap
``GAP_RADIUS_MM``         [0, 100] mm          open-mesh gap radius
``RESOLUTION_MM``         [0, 10] mm           width-measurement resolution
``SCALE``                 [1e-6, 1e6] (abs)    uniform mesh scale
``DPI``                   [1, 100000] dpi      print-direction and design densities
``EXPOSURE_S``            [1e-3, 3600] s       exposure times
``FRACTION``              [0, 1]               cure threshold
``OFFSET_UM``             [0, 2000] um         first-layer (elephant-foot) inset
``DROP_UM``               [0.1, 1e4] um        drop diameter
``JITTER_UM``             [0, 10000] um        drop misdirection
``SPREAD``                (0, 20]              footprint / in-flight diameter
``VISCOSITY_MPA_S``       [0.1, 1e6] mPa s     ink viscosity (film levelling)
``SURFACE_TENSION_MN_M``  [1, 200] mN/m        ink surface tension (film levelling)
``SET_TIME_S``            [0, 3600] s          wet film's flow time before it sets (0: none)
``PERCENT``               [0, 100] %           percentiles (film levelling h0)
``EVEN_RATIO``            [1, 100]             largest / mean track gap taken as even
``WORKERS``               1 ... 1024           worker processes
``COUNT``                 0 ... 1000000        layer and overlay counts
``SWATHES``               1 ... 10000          radial swathes
``SEED``                  0 ... 2**32 - 1      random seeds
``OVERLAY_SCALE``         1 ... 16             overlay pixels per design pixel
``MACHINE_BITS``          1 ... 4 (1, 2 or 4)  bits per nozzle of machine/ firing data
``PASSES``                1 ... 64             interlaced passes per layer (or "auto")
========================  ===================  =============================================
"""

from __future__ import annotations

import math
import numbers
from pathlib import Path

from ._dataclass import dataclass
from .errors import ConfigError, RotoprintError

__all__ = ["Range", "check_range", "check_count", "check_direction", "field", "show_value", "MAX_COUNT"]

#: The largest count of swathes, firings, drops or pixels any array may be sized for.
MAX_COUNT = 2**40


@dataclass(frozen=True)
class Range:
    """A closed or open interval ``lo .. hi`` of finite numbers, with a unit for messages."""

    lo: float
    hi: float
    unit: str = ""
    lo_open: bool = False
    hi_open: bool = False
    integer: bool = False

    def __contains__(self, v: float) -> bool:
        try:
            if not math.isfinite(v):
                return False
        except OverflowError:  # an int past the float range
            return False
        above = v > self.lo if self.lo_open else v >= self.lo
        below = v < self.hi if self.hi_open else v <= self.hi
        return above and below

    def text(self) -> str:
        """The interval as a reader sees it: ``(0, 100] mm`` or ``1 ... 1024``."""
        if self.integer:
            return f"an integer in {self.lo:g} ... {self.hi:g}"
        left, right = "(" if self.lo_open else "[", ")" if self.hi_open else "]"
        return f"in {left}{self.lo:g}, {self.hi:g}{right}" + (f" {self.unit}" if self.unit else "")


COORD_MM = Range(-10_000.0, 10_000.0, "mm")
ANGLE_DEG = Range(-3600.0, 3600.0, "deg")
TILT_DEG = Range(-90.0, 90.0, "deg", lo_open=True, hi_open=True)
LAYER_HEIGHT_MM = Range(1e-4, 100.0, "mm")
RADIUS_MM = Range(1e-3, 10_000.0, "mm")
WIDTH_MM = Range(1e-4, 100.0, "mm")
GAP_RADIUS_MM = Range(0.0, 100.0, "mm")
RESOLUTION_MM = Range(0.0, 10.0, "mm")
SCALE = Range(1e-6, 1e6)
DPI = Range(1.0, 100_000.0, "dpi")
EXPOSURE_S = Range(1e-3, 3600.0, "s")
FRACTION = Range(0.0, 1.0)
OFFSET_UM = Range(0.0, 2000.0, "um")  # = masks.pipeline.FIRST_LAYER_OFFSET_MAX_UM
DROP_UM = Range(0.1, 10_000.0, "um")
JITTER_UM = Range(0.0, 10_000.0, "um")
SPREAD = Range(0.0, 20.0, lo_open=True)  # footprint / in-flight diameter (devices.models spread_factor)
VISCOSITY_MPA_S = Range(0.1, 1e6, "mPa s")  # ink viscosity (film levelling, rotary.deposit)
SURFACE_TENSION_MN_M = Range(1.0, 200.0, "mN/m")  # ink surface tension (film levelling)
PERCENT = Range(0.0, 100.0, "%")
SET_TIME_S = Range(0.0, 3600.0, "s")  # time the wet film flows before it sets; 0 = no levelling
EVEN_RATIO = Range(1.0, 100.0)
WORKERS = Range(1, 1024, integer=True)
COUNT = Range(0, 1_000_000, integer=True)
SWATHES = Range(1, 10_000, integer=True)
SEED = Range(0, 2**32 - 1, integer=True)
OVERLAY_SCALE = Range(1, 16, integer=True)
MACHINE_BITS = Range(1, 4, integer=True)  # and 1, 2 or 4: see machine.program.MachineOptions
PASSES = Range(1, 64, integer=True)  # interlaced passes per layer (rotary.interlace, [printer] passes)
NOZZLE_INDEX = Range(0, 100_000, integer=True)  # the largest head (devices.models)
DIRECTION = Range(-1, 1, integer=True)  # and not 0: see check_direction


def field(rng: Range, **kw):
    """A pydantic ``Field`` bounded by ``rng`` (the same range in a model as at the CLI)."""
    from pydantic import Field

    lo = {"gt": rng.lo} if rng.lo_open else {"ge": rng.lo}
    hi = {"lt": rng.hi} if rng.hi_open else {"le": rng.hi}
    return Field(**lo, **hi, **kw)


def check_range(
    value: object,
    rng: Range,
    name: str,
    *,
    error: type[RotoprintError] = ConfigError,
    path: str | Path | None = None,
) -> float:
    """``value`` as a float (an int if ``rng.integer``) when it is a finite number in ``rng``.

    Parameters
    ----------
    value : object
        The number as it came (bool and str are refused: ``true`` is not 1).
    rng : Range
        The allowed interval.
    name : str
        The option or field named in the error, e.g. ``"--min-wall"`` or ``"head.dpi_y"``.
    error : type of RotoprintError
        Raised on a bad value (ConfigError for options, InputFileError/DeviceError for files).
    path : str or Path, optional
        The file the field came from, named in the error.

    Raises
    ------
    RotoprintError
        (``error``) naming ``name``, the range and the value.
    """
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    if ok:
        try:
            v = float(value)  # type: ignore[arg-type]
        except OverflowError:  # an int past the float range
            ok = False
        else:
            ok = v in rng and (not rng.integer or isinstance(value, numbers.Integral) or v.is_integer())
    if not ok:
        raise error(f"{name} must be {rng.text()}, got {show_value(value)}", path=path)
    return int(value) if rng.integer else float(value)  # type: ignore[arg-type]


def check_direction(value: object, name: str, **kw) -> int:
    """+1 or -1 (the sense of rotation)."""
    v = check_range(value, DIRECTION, name, **kw)
    if v == 0:
        raise kw.get("error", ConfigError)(f"{name} must be +1 or -1, got 0", path=kw.get("path"))
    return int(v)


def check_count(n: float, what: str, limit: float = MAX_COUNT, *, error: type[RotoprintError] = ConfigError) -> int:
    """A count computed from inputs (swathes, firings, pixels, angles) before anything is sized
    for it: a finite number at most ``limit``, as an int; else an error saying how many."""
    if not (isinstance(n, numbers.Real) and (isinstance(n, numbers.Integral) or math.isfinite(float(n)))) or n > limit:
        shown = show_value(float(n) if isinstance(n, float) else n) if isinstance(n, numbers.Real) else repr(n)
        raise error(f"{what} would be {shown}, more than {limit:.3g}")
    return int(n)


def show_value(value: object) -> str:
    """A value as an error message shows it: short whatever it is (an integer of thousands of
    digits as ``1.23e+4567``, its size; any other repr cut at 40 characters).

    Examples
    --------
    >>> show_value(10**3000 + 7), show_value(2.5), show_value("x" * 100)[-5:]
    ('1.00e+3000', '2.5', 'xx...')
    """
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**15:
        sign = "-" if value < 0 else ""
        if abs(value).bit_length() > 12_000:  # str() refuses more than 4300 digits: the size from the bits
            return f"{sign}about 1e+{int(abs(value).bit_length() * math.log10(2))}"
        digits = str(abs(value))
        return f"{sign}{digits[0]}.{digits[1:3]}e+{len(digits) - 1}"
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
