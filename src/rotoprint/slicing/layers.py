"""Layer planning: which heights are sliced."""

from __future__ import annotations

import math

import numpy as np

from .._dataclass import dataclass
from ..constants import MIN_LAST_LAYER_FRACTION
from ..errors import ConfigError

__all__ = ["LayerPlan", "plan_layers"]


@dataclass(frozen=True)
class LayerPlan:
    """Layers as ``(n,) float64`` arrays: bottom, top and the height that is sliced (mm).

    Layer ``i`` spans ``[z_bottom[i], z_top[i]]`` and is sliced at its middle. Every layer is
    ``layer_height_mm`` thick except the last, which ends at the top of the part (it is
    thinner when the height is not a whole number of layers).
    """

    z_bottom_mm: np.ndarray
    z_top_mm: np.ndarray
    z_slice_mm: np.ndarray
    layer_height_mm: float

    def __len__(self) -> int:
        return int(self.z_slice_mm.shape[0])


def plan_layers(z_min_mm: float, z_max_mm: float, layer_height_mm: float, *, max_layers: int = 10_000_000) -> LayerPlan:
    """Plan layers from ``z_min_mm`` to ``z_max_mm`` at mid-layer heights.

    Layers are ``layer_height_mm`` thick from ``z_min_mm`` up; the last one ends at
    ``z_max_mm`` and is merged into the one below when it would be thinner than
    ``MIN_LAST_LAYER_FRACTION`` of a layer.

    Parameters
    ----------
    z_min_mm, z_max_mm : float
        Bottom and top of the part, mm (``z_max_mm > z_min_mm``).
    layer_height_mm : float
        Nominal layer thickness, mm (finite, ``> 0``).
    max_layers : int
        Refuse a plan with more layers than this.

    Returns
    -------
    LayerPlan
        ``z_bottom``, ``z_top``, ``z_slice_mm`` ``(n,) float64`` (mm) and the nominal height.

    Raises
    ------
    ConfigError
        A non-positive or non-finite layer height, a part with no height, too many layers.

    Examples
    --------
    >>> plan_layers(0.0, 1.0, 0.25).z_slice_mm.tolist()
    [0.125, 0.375, 0.625, 0.875]
    >>> plan_layers(0.0, 1.0, 0.3).z_slice_mm.round(3).tolist()
    [0.15, 0.45, 0.75, 0.95]
    """
    if not (math.isfinite(layer_height_mm) and layer_height_mm > 0):
        raise ConfigError(f"layer height must be a positive number of mm, got {layer_height_mm}")
    height = float(z_max_mm) - float(z_min_mm)
    if not height > 0:
        raise ConfigError(f"the part has no height to slice (z from {z_min_mm} to {z_max_mm} mm)")
    n = math.ceil(height / layer_height_mm * (1 - 1e-12))
    if height - (n - 1) * layer_height_mm < MIN_LAST_LAYER_FRACTION * layer_height_mm:
        n -= 1
    n = max(n, 1)
    if n > max_layers:
        raise ConfigError(f"{n} layers of {layer_height_mm} mm over {height:.3f} mm is more than {max_layers}")
    bottom = z_min_mm + np.arange(n) * layer_height_mm
    top = np.minimum(bottom + layer_height_mm, z_max_mm)
    top[-1] = z_max_mm
    return LayerPlan(bottom, top, 0.5 * (bottom + top), float(layer_height_mm))
