"""The rotary setup as option objects: :class:`RotarySetup` (what the transforms and their
maps depend on: tilt, clock, reference radius, mount angle, direction, swathe limit, backend)
and :class:`RotarySliceOptions` (direct rotary slicing: the part's placement, the layer
height, the fill, plus the setup). Frozen: nothing is set on them after they are made."""

from __future__ import annotations

import functools
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

from ..constants import DEFAULT_GAP_RADIUS_MM
from ..errors import ConfigError

__all__ = ["RotarySetup", "RotarySliceOptions", "BACKENDS", "options_from"]

#: The jit kernels or the pure-numpy references (identical output).
BACKENDS = ("jit", "numpy")


def _check_backend(backend: str) -> None:
    if backend not in BACKENDS:
        raise ConfigError(f"backend must be one of {', '.join(BACKENDS)}; got {backend!r}")


@dataclass(frozen=True)
class RotarySetup:
    """How a head prints over the rotating platform.

    Parameters
    ----------
    tilt_deg : float
        Head tilt, |tilt| below the head's maximum.
    dpi_y : float, optional
        Circumferential density at the reference radius; default the head's ``dpi_y``.
    ref_radius_mm : float, optional
        One reference radius for every swathe; default each swathe's outermost track (the
        paper's method: its first column).
    mount_angle_deg : float
        Angle of the head's radial line, degrees.
    direction : {1, -1}
        +1: platform turns counter-clockwise seen from above; -1 clockwise.
    max_swathes : int, optional
        Refuse designs that need more radial swathes.
    backend : {'jit', 'numpy'}
        The jit kernel or the pure-numpy reference; their output is identical.
    pivot_offset_mm : float
        Radial offset of every swathe's pivot from the planned one (an interlaced pass,
        :mod:`rotoprint.rotary.interlace`); the swathes keep their nozzles and bands.
    swathe_overlap_mm : float
        Swathes planned with this overlap (:func:`~rotoprint.rotary.swathes.plan_swathes`):
        then a pass prints, per swathe, the full-density nozzles whose moved track lies in the
        swathe's band (the design's edges and the seams covered by every pass). 0: as before.
    swathe_seam_mm : float
        With ``swathe_overlap_mm``: every swathe but the first also prints this far below its
        band (both swathes print the seam; :meth:`~rotoprint.rotary.swathes.SwathePlan.with_seam`). 0: as before.
    """

    tilt_deg: float
    dpi_y: float | None = None
    ref_radius_mm: float | None = None
    mount_angle_deg: float = 0.0
    direction: int = 1
    max_swathes: int | None = None
    backend: str = "jit"
    pivot_offset_mm: float = 0.0
    swathe_overlap_mm: float = 0.0
    swathe_seam_mm: float = 0.0

    def __post_init__(self) -> None:
        _check_backend(self.backend)


@dataclass(frozen=True)
class RotarySliceOptions:
    """Direct rotary slicing (see :func:`rotoprint.rotary.direct.slice_rotary`).

    Parameters
    ----------
    layer_height_mm : float
    tilt_deg : float
        Head tilt, |tilt| below the head's maximum.
    inner_radius_mm : float
        Radius of the part's inner edge (see :class:`~rotoprint.rotary.direct.PartPlacement`).
    angle_deg : float
        Angle of the part's centre line on the platform.
    dpi_y : float, optional
        Circumferential density at each swathe's reference radius (default: the head's).
    ref_radius_mm : float, optional
        One reference radius for every swathe (default: each swathe's outermost track).
    direction : {1, -1}
    max_swathes : int, optional
    equalise : bool
        Thin inner tracks so that drops per unit area are the same on every track.
    fill : {'nonzero', 'evenodd'}
    gap_radius_mm : float
        Open meshes: see :func:`rotoprint.slice_mesh`.
    backend : {'jit', 'numpy'}
    pivot_offset_mm : float
        Radial offset of every swathe's pivot from the planned one: one interlaced pass
        (:func:`rotoprint.rotary.interlace.plan_passes`); the swathes keep their nozzles.
    """

    layer_height_mm: float
    tilt_deg: float
    inner_radius_mm: float
    angle_deg: float = 0.0
    dpi_y: float | None = None
    ref_radius_mm: float | None = None
    direction: int = 1
    max_swathes: int | None = None
    equalise: bool = False
    fill: str = "nonzero"
    gap_radius_mm: float = DEFAULT_GAP_RADIUS_MM
    backend: str = "jit"
    pivot_offset_mm: float = 0.0

    def __post_init__(self) -> None:
        from ..slicing import FILL_RULES
        from .head import DIRECTIONS

        _check_backend(self.backend)
        if self.fill not in FILL_RULES:
            raise ConfigError(f"fill must be one of {', '.join(FILL_RULES)}, got {self.fill!r}")
        if self.direction not in DIRECTIONS:
            raise ConfigError(f"direction must be +1 or -1, got {self.direction!r}")

    @property
    def setup(self) -> RotarySetup:
        """The head's setup (mount angle 0: the part's angle places it)."""
        return RotarySetup(tilt_deg=self.tilt_deg, dpi_y=self.dpi_y, ref_radius_mm=self.ref_radius_mm,
                           direction=self.direction, max_swathes=self.max_swathes, backend=self.backend,
                           pivot_offset_mm=self.pivot_offset_mm)

    def as_dict(self) -> dict[str, Any]:
        """The options as :func:`~rotoprint.rotary.direct.slice_rotary` keywords, JSON-ready."""
        d = asdict(self)
        for k in ("layer_height_mm", "tilt_deg", "inner_radius_mm", "angle_deg", "gap_radius_mm"):
            d[k] = float(d[k])
        d["direction"] = int(d["direction"])
        d["equalise"] = bool(d["equalise"])
        off = d.pop("pivot_offset_mm")
        if off:  # recorded only when set (an interlaced pass), as before
            d["pivot_offset_mm"] = float(off)
        return d


@functools.cache
def _field_names(cls) -> frozenset[str]:
    return frozenset(f.name for f in fields(cls))


def options_from(cls, options, keywords: dict[str, Any], *, what: str):
    """``options`` (a ``cls`` or None) with the fields named in ``keywords`` replaced.
    Raises :class:`~rotoprint.errors.ConfigError` on an unknown keyword, a missing required
    field or an ``options`` of another type."""
    names = _field_names(cls)
    if options is not None and not keywords and isinstance(options, cls):
        return options
    unknown = sorted(keywords.keys() - names)
    if unknown:
        raise ConfigError(f"{what}: unknown option {unknown[0]!r}; options: {', '.join(sorted(names))}")
    if options is None:
        try:
            return cls(**keywords)
        except TypeError as exc:  # a required field missing
            raise ConfigError(f"{what}: {exc}") from None
    if not isinstance(options, cls):
        raise ConfigError(f"{what}: options must be a {cls.__name__}, got {type(options).__name__}")
    return replace(options, **keywords) if keywords else options
