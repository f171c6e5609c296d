"""What a slicing run is asked to do (:class:`SliceOptions`), checked when made."""

from __future__ import annotations

import math
from dataclasses import asdict, fields, replace
from typing import Any

from .._dataclass import dataclass
from ..constants import DEFAULT_GAP_RADIUS_MM
from ..errors import ConfigError
from ._fill import FILL_RULES

__all__ = ["SliceOptions", "BACKENDS", "slice_options_from"]

#: The compiled kernels or the pure-numpy references (identical output). The one name for
#: this choice across slicing, masks and the rotary transforms.
BACKENDS = ("jit", "numpy")


@dataclass(frozen=True)
class SliceOptions:
    """How to slice a mesh (see :func:`rotoprint.slicing.slice_mesh`).

    Parameters
    ----------
    layer_height_mm : float
    fibre_angle_deg : float, optional
        Direction of the fibres in the model's XY plane, degrees counter-clockwise from +X.
        Default: the device's own fibre direction with the model unrotated.
    fill : {'nonzero', 'evenodd'}
    offset_mm : (2,) float
        Where the part's footprint centre goes, relative to the field centre (``centre=True``),
        or the translation of the model's origin (``centre=False``).
    centre : bool
    gap_radius_mm : float
        Open ends of a cross-section closer than this are joined (open meshes).
    backend : {'jit', 'numpy'}
        The compiled kernel or the pure-numpy reference; their output is identical.

    Raises
    ------
    ConfigError
        An unknown fill rule or backend, a negative gap radius, a fibre angle that is not finite.
    """

    layer_height_mm: float
    fibre_angle_deg: float | None = None
    fill: str = "nonzero"
    offset_mm: tuple[float, float] = (0.0, 0.0)
    centre: bool = True
    gap_radius_mm: float = DEFAULT_GAP_RADIUS_MM
    backend: str = "jit"

    def __post_init__(self) -> None:
        if self.fill not in FILL_RULES:
            raise ConfigError(f"fill must be one of {', '.join(FILL_RULES)}, got {self.fill!r}")
        if self.backend not in BACKENDS:
            raise ConfigError(f"backend must be one of {', '.join(BACKENDS)}, got {self.backend!r}")
        if not self.gap_radius_mm >= 0:
            raise ConfigError(f"gap radius must be >= 0 mm, got {self.gap_radius_mm}")
        if self.fibre_angle_deg is not None and not math.isfinite(self.fibre_angle_deg):
            raise ConfigError(f"fibre angle must be finite, got {self.fibre_angle_deg}")
        try:
            layer_height_mm = float(self.layer_height_mm)
        except (TypeError, ValueError):
            raise ConfigError(f"layer height must be a number of mm, got {self.layer_height_mm!r}") from None
        # normalised once here, so the manifest records the same values as before
        object.__setattr__(self, "layer_height_mm", layer_height_mm)
        object.__setattr__(self, "offset_mm", tuple(float(v) for v in self.offset_mm))
        object.__setattr__(self, "gap_radius_mm", float(self.gap_radius_mm))

    def as_dict(self) -> dict[str, Any]:
        """The options as keywords of :func:`~rotoprint.slicing.slice_mesh` (JSON-ready: the
        layer manifest records them)."""
        return asdict(self)


_FIELDS = frozenset(f.name for f in fields(SliceOptions))


def slice_options_from(options: SliceOptions | None, keywords: dict[str, Any], *, what: str = "slice_mesh") -> SliceOptions:
    """``options`` with the fields named in ``keywords`` replaced (or a new object when
    ``options`` is None). Raises :class:`~rotoprint.errors.ConfigError` on an unknown keyword
    or a missing layer height."""
    unknown = sorted(set(keywords) - _FIELDS)
    if unknown:
        raise ConfigError(f"{what}: unknown option {unknown[0]!r}; options: {', '.join(sorted(_FIELDS))}")
    if options is None:
        if "layer_height_mm" not in keywords:
            raise ConfigError(f"{what}: layer_height_mm is needed")
        return SliceOptions(**keywords)
    if not isinstance(options, SliceOptions):
        raise ConfigError(f"{what}: options must be a SliceOptions, got {type(options).__name__}")
    return replace(options, **keywords) if keywords else options
