"""Print-ready images and their sidecar: what a machine (or the simulator) needs, no guessing.

A print-ready image ``B[i, k]`` has one row per firing and one column per nozzle; row ``b`` is
firing ``first_firing + b``. The drop of nozzle ``k`` at firing ``i`` lands at
``(r_k, phi_k - direction * i * dphi)`` in the platform frame (``rotary-geometry.md`` s. 3).
Values are drop levels, 0 = no drop, 1..grey_levels; PNG files store
``round(level * 255 / grey_levels)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .. import __version__
from ..devices.models import InkjetHead
from ..errors import ConfigError
from .placement import Placement

__all__ = ["SwatheImage", "RotaryPrint", "levels_to_png", "png_to_levels", "clock_dphi", "design_kind", "design_levels", "SIDECAR_FORMAT"]

SIDECAR_FORMAT = "rotoprint-rotary-print"


def clock_dphi(dpi_y: float, ref_radius_mm: float) -> float:
    """Platform rotation per firing, radians: ``(25.4 / dpi_y) / r_ref``.

    Parameters
    ----------
    dpi_y : float
        Drops per inch along the track at the reference radius.
    ref_radius_mm : float
        Reference radius ``r_ref`` at which the drop pitch is ``25.4 / dpi_y`` mm.

    Returns
    -------
    float
        Radians per firing.

    Raises
    ------
    ConfigError
        ``dpi_y`` or ``ref_radius_mm`` is not a finite number > 0.

    Examples
    --------
    >>> round(clock_dphi(360.0, 60.0), 9)
    0.001175926
    """
    if not (dpi_y > 0 and math.isfinite(dpi_y)):
        raise ConfigError(f"dpi_y must be a positive number, got {dpi_y}")
    if not (ref_radius_mm > 0 and math.isfinite(ref_radius_mm)):
        raise ConfigError(f"reference radius must be > 0 mm, got {ref_radius_mm}")
    return (25.4 / dpi_y) / ref_radius_mm


def levels_to_png(levels: np.ndarray, grey_levels: int) -> np.ndarray:
    """``(F, N) uint8`` levels 0..grey_levels to PNG values 0..255.

    Parameters
    ----------
    levels : (F, N) uint8
    grey_levels : int
        Largest level; with 1, every non-zero level becomes 255.

    Returns
    -------
    (F, N) uint8 ndarray
        ``round(level * 255 / grey_levels)``.
    """
    if grey_levels == 1:
        return (levels > 0).astype(np.uint8) * np.uint8(255)
    return np.rint(levels.astype(np.float64) * (255.0 / grey_levels)).astype(np.uint8)


def png_to_levels(png: np.ndarray, grey_levels: int) -> np.ndarray:
    """Inverse of :func:`levels_to_png`.

    Parameters
    ----------
    png : (F, N) uint8
        PNG values 0..255.
    grey_levels : int

    Returns
    -------
    (F, N) uint8 ndarray
        ``round(png * grey_levels / 255)``, through a 256-entry table (one byte a pixel of
        working memory, not the 16 of a float64 round trip).
    """
    lut = np.rint(np.arange(256, dtype=np.float64) * (grey_levels / 255.0)).astype(np.uint8)
    return lut[np.asarray(png, dtype=np.uint8)]


def design_kind(design: np.ndarray) -> str:
    """``"binary"`` when the design holds at most one non-zero value, else ``"grey"``.

    Parameters
    ----------
    design : array_like
        Design pixel values; an empty array is ``"binary"``.

    Returns
    -------
    {'binary', 'grey'}
    """
    d = np.asarray(design)
    m = d.max() if d.size else 0
    return "grey" if m and bool(np.any((d != 0) & (d != m))) else "binary"


def design_levels(samples: np.ndarray, grey_levels: int, *, kind: str) -> np.ndarray:
    """Sampled design values to drop levels, ``uint8``.

    Binary designs: any non-zero value prints the largest drop. Grey designs: value / 255 is
    the wanted coverage, rounded to the nearest level (for a one-level head: at least 50 %).

    Parameters
    ----------
    samples : ndarray
        Design values (0..255 for a grey design), any shape.
    grey_levels : int
        Largest drop level of the head.
    kind : {'binary', 'grey'}
        From :func:`design_kind`; any value other than ``'binary'`` is treated as grey.

    Returns
    -------
    uint8 ndarray
        Levels 0..grey_levels, the shape of ``samples``.
    """
    if kind == "binary":
        return np.where(samples > 0, np.uint8(grey_levels), np.uint8(0)).astype(np.uint8)
    cov = samples.astype(np.float32) / np.float32(255.0)
    return np.clip(np.floor(cov * grey_levels + 0.5), 0, grey_levels).astype(np.uint8)


def _runs(mask: np.ndarray) -> list[list[int]]:
    """``[[start, stop), ...]`` runs of True in a bool array."""
    m = np.concatenate([[False], np.asarray(mask, bool), [False]])
    d = np.flatnonzero(np.diff(m.astype(np.int8)))
    return [[int(a), int(b)] for a, b in zip(d[0::2], d[1::2])]


def runs_to_mask(runs: list[list[int]], n: int) -> np.ndarray:
    m = np.zeros(n, bool)
    for a, b in runs:
        m[a:b] = True
    return m


@dataclass(frozen=True, eq=False)
class SwatheImage:
    """One swathe's print-ready image and the data to place its drops.

    Attributes
    ----------
    levels : (F, N) uint8
        Drop levels, row = firing ``first_firing + row``, column = nozzle.
    """

    index: int
    levels: np.ndarray
    pivot_radius_mm: float
    first_firing: int
    dphi_rad: float
    ref_radius_mm: float
    band_mm: tuple[float, float]
    enabled_nozzles: int
    extra: dict = field(default_factory=dict)
    #: (N,) bool nozzles that print in this swathe (None: all)
    enabled: np.ndarray | None = None

    def to_json(self) -> dict:
        return {
            "index": self.index,
            "pivot_radius_mm": self.pivot_radius_mm,
            "first_firing_index": self.first_firing,
            "firings": int(self.levels.shape[0]),
            "nozzles": int(self.levels.shape[1]),
            "dphi_rad": self.dphi_rad,
            "angle_per_firing_deg": math.degrees(self.dphi_rad),
            "ref_radius_mm": self.ref_radius_mm,
            "band_mm": list(self.band_mm),
            "enabled_nozzles": self.enabled_nozzles,
            "enabled_nozzle_runs": _runs(self.enabled) if self.enabled is not None else None,
            "drops": int(np.count_nonzero(self.levels)),
            **self.extra,
        }


@dataclass(frozen=True, eq=False)
class RotaryPrint:
    """A transformed design: one :class:`SwatheImage` per radial swathe, plus its setting."""

    method: str
    head: InkjetHead
    tilt_deg: float
    mount_angle_deg: float
    direction: int
    dpi_y: float
    placement: Placement
    swathes: tuple[SwatheImage, ...]
    design_kind: str = "binary"

    def to_json(self, *, files: list[str] | None = None, device_name: str = "", design: dict | None = None) -> dict:
        sw = []
        for j, s in enumerate(self.swathes):
            d = s.to_json()
            if files is not None:
                d["file"] = files[j]
            sw.append(d)
        return {
            "format": SIDECAR_FORMAT,
            "version": 1,
            "rotoprint": __version__,
            "method": self.method,
            "device": device_name,
            "head": self.head.model_dump(mode="json"),
            "tilt_deg": self.tilt_deg,
            "mount_angle_deg": self.mount_angle_deg,
            "direction": self.direction,
            "dpi_y": self.dpi_y,
            "placement": self.placement.to_json(),
            "design": {"kind": self.design_kind, **(design or {})},
            "grey_levels": self.head.grey_levels,
            "png_value": "round(level * 255 / grey_levels); 0 = no drop",
            "landing": "nozzle k at firing i lands at (r_k, phi_k - direction * i * dphi_rad) in the platform frame; "
            "row b of a swathe image is firing first_firing_index + b; nozzle positions from head, tilt_deg, "
            "mount_angle_deg and the swathe's pivot_radius_mm (rotary-geometry.md s. 2)",
            "swathes": sw,
        }
