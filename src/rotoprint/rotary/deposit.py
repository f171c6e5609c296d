"""The deposit model: drops of ink become a film, and the film is compared with the design.

Every drop keeps its exact landing site (from :func:`~rotoprint.rotary.simulate.place_drops`)
and its volume ``V`` (pl): the head's ``drop_volume_pl`` for the largest level, ``level /
grey_levels`` of it for smaller ones. In flight it is a sphere of diameter
``d0 = (6 V / pi)^(1/3)`` (8 pl -> 24.8 um); on the substrate it spreads to a footprint of
diameter ``D = spread_factor * d0`` (the head's ``spread_factor``, an ink/substrate figure,
nominal in the presets) and takes the shape of a spherical cap of that base holding ``V``
(height ``h`` from ``V = pi h (3 a^2 + h^2) / 6``, ``a = D / 2``). Drops that overlap merge:
their thicknesses add on a fine grid (cell <= ``D / cells_per_footprint``, an integer fraction
of the design pixel). Each drop's cap is normalised on the grid so that its volume is deposited
exactly: the film holds the planned volume up to rounding (and up to drops falling beyond the
grid, reported).

Figures (:class:`FilmReport`), all on the design's mask (pixels the design asks to print, or,
exact to a cell, the design rasterised on the film grid: :func:`film_grid`):

- *interior*: design cells whose centre is at least half a footprint (``D / 2`` of the largest
  drop) plus half a cell from the nearest cell centre outside the design: the design less a
  boundary band in which a footprint centred inside may fall short of the edge. The band's
  figure is reported beside it.
- *uncovered fraction*: interior cells with no film (no footprint reaches their centre).
- *thinnest* and *mean* thickness over the interior, um; *radial bins*: mean thickness of the
  interior in 1 mm annuli of platform radius, and their spread ``max |bin / mean of bins - 1|``
  over bins holding at least a tenth of the median bin's area (slivers at the ends are listed
  but not counted).
- *drops outside*: drops whose site is outside the design mask; *volume outside*: the share of
  the deposited volume on cells outside the design.
- *reagent pairs*: for two films on the same grid, the fraction of one's covered design area not
  covered by the other.

Memory: the grid is processed in strips of rows (``strip_cells`` cells per film), so a design
of any size needs only a few strips' worth of memory; the grid's width is bounded.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..devices.models import InkjetHead
from ..errors import ConfigError, ImageError, RasterTooLargeError
from . import _deposit_kernels as _k
from .placement import Placement

__all__ = [
    "DepositOptions",
    "LevelOptions",
    "LevelledFilm",
    "levelling_rate_um4_per_s",
    "InkDrops",
    "FilmReport",
    "Deposit",
    "flight_diameter_um",
    "footprint_diameter_um",
    "cap_height_um",
    "ink_drops",
    "film_cells",
    "film_grid",
    "interior_mask",
    "radial_area_mm2",
    "deposit_film",
    "deposit_print",
]

#: Largest grid width, cells (a strip is at least one row of this).
MAX_GRID_COLS = 2_000_000
#: Largest grid, cells (about 2 minutes of deposition at the measured rate).
MAX_GRID_CELLS = 2_000_000_000
#: Smallest share of the median bin's area for a radial bin to count in the spread.
BIN_MIN_SHARE = 0.1
#: 1 pl in um^3.
UM3_PER_PL = 1000.0


def flight_diameter_um(volume_pl: float | np.ndarray) -> float | np.ndarray:
    """In-flight diameter of a drop, ``(6 V / pi)^(1/3)``, um (``V`` in pl; 1 pl = 1000 um^3).

    Examples
    --------
    >>> round(float(flight_diameter_um(8.0)), 1), round(float(flight_diameter_um(40.0)), 1)
    (24.8, 42.4)
    """
    return np.cbrt(6.0 * np.asarray(volume_pl, dtype=np.float64) * UM3_PER_PL / math.pi)[()]


def footprint_diameter_um(volume_pl: float | np.ndarray, spread_factor: float) -> float | np.ndarray:
    """Footprint diameter on the substrate, ``spread_factor * flight_diameter_um(V)``, um.

    Examples
    --------
    >>> round(float(footprint_diameter_um(8.0, 2.0)), 1)
    49.6
    """
    return spread_factor * flight_diameter_um(volume_pl)


def cap_height_um(volume_um3: np.ndarray, radius_um: np.ndarray) -> np.ndarray:
    """Height ``h`` of the spherical cap of base radius ``a`` and volume ``V``:
    the real root of ``h^3 + 3 a^2 h - 6 V / pi = 0`` (Cardano; one real root since the
    discriminant is positive), um.

    Examples
    --------
    >>> h = cap_height_um(np.array([8000.0]), np.array([24.8]))
    >>> round(float(h[0]), 2), round(float(np.pi * h[0] * (3 * 24.8**2 + h[0]**2) / 6), 6)
    (8.0, 8000.0)
    """
    v = np.asarray(volume_um3, dtype=np.float64)
    a = np.asarray(radius_um, dtype=np.float64)
    p = 3.0 * a * a
    q = -6.0 * v / math.pi
    disc = np.sqrt((q / 2.0) ** 2 + (p / 3.0) ** 3)
    return np.cbrt(-q / 2.0 + disc) + np.cbrt(-q / 2.0 - disc)


@dataclass(frozen=True)
class DepositOptions:
    """How drops spread and how finely the film is resolved.

    Parameters
    ----------
    spread_factor : float, optional
        Footprint diameter over in-flight diameter (default: the head's ``spread_factor``).
    footprint_um : float, optional
        Footprint diameter of a full drop, um, instead of the spread factor (smaller drops
        scale with the cube root of their volume).
    cells_per_footprint : float
        The grid cell is at most ``D / cells_per_footprint`` (and an integer fraction of the
        design pixel), 2..50.
    strip_cells : int
        Cells per strip and film processed at once (memory: 8 bytes each, a few arrays).
    level : LevelOptions or tuple of (LevelOptions or None), optional
        Level each film under surface tension after all its drops landed (``set_time_s >
        0``; one for all films, or one per drop set, e.g. per ink): such a film gets
        :attr:`FilmReport.levelled` beside its as-landed figures, which are unchanged. The
        convolutions run on a coarse grid (:attr:`LevelOptions.coarse_per_length`); the films
        as landed are kept for it or deposited again (:attr:`LevelOptions.window_cells`).
    """

    spread_factor: float | None = None
    footprint_um: float | None = None
    cells_per_footprint: float = 5.0
    strip_cells: int = 2_000_000
    level: "LevelOptions | tuple[LevelOptions | None, ...] | None" = None

    def __post_init__(self) -> None:
        for name in ("spread_factor", "footprint_um"):
            v = getattr(self, name)
            if v is not None and not (math.isfinite(v) and 0 < v <= 1e5):
                raise ConfigError(f"{name} must be a number in (0, 1e5], got {v!r}")
        if not (math.isfinite(self.cells_per_footprint) and 2 <= self.cells_per_footprint <= 50):
            raise ConfigError(f"cells_per_footprint must be in 2..50, got {self.cells_per_footprint!r}")
        if not 10_000 <= int(self.strip_cells) <= 1_000_000_000:
            raise ConfigError(f"strip_cells must be in 10000..1e9, got {self.strip_cells!r}")
        if isinstance(self.level, list):
            object.__setattr__(self, "level", tuple(self.level))

    def full_footprint_um(self, head: InkjetHead) -> float:
        """Footprint diameter of the head's full drop, um."""
        if self.footprint_um is not None:
            return float(self.footprint_um)
        sf = head.spread_factor if self.spread_factor is None else self.spread_factor
        return float(footprint_diameter_um(head.drop_volume_pl, sf))


def levelling_rate_um4_per_s(surface_tension_mn_m: float, viscosity_mpa_s: float, h0_um: float) -> float:
    """``D = sigma h0^3 / (3 eta)`` of the linearised thin-film equation, um^4/s.

    A thickness ripple of wavelength ``lambda`` decays as ``exp(-D (2 pi / lambda)^4 t)``
    (Orchard 1962).

    Examples
    --------
    >>> f"{levelling_rate_um4_per_s(30.0, 10.0, 10.0):.6g}"  # 30 mN/m, 10 mPa s, 10 um: 1e-15 m^4/s
    '1e+09'
    """
    # sigma [N/m] h0^3 [m^3] / (3 eta [Pa s]) [m^4/s] * 1e24 [um^4/m^4]
    return float(surface_tension_mn_m * 1e-3 * (h0_um * 1e-6) ** 3 / (3.0 * viscosity_mpa_s * 1e-3) * 1e24)


@dataclass(frozen=True)
class LevelOptions:
    """How the wet film levels under surface tension before it sets (see ``_levelling``).

    Parameters
    ----------
    set_time_s : float
        Time the wet film flows before it sets, s; 0: no levelling. 0..3600.
    viscosity_mpa_s : float
        Ink viscosity, mPa s, 0.1..1e6.
    surface_tension_mn_m : float
        Ink surface tension, mN/m, 1..200.
    h0_percentile : float
        The film thickness ``h0`` of the linear model is this percentile of the as-landed
        wet interior film (the rate goes with ``h0^3``, so a thin region levels slower: a low
        percentile is the conservative choice), 0..100.
    h0_um : float, optional
        A fixed ``h0`` instead of the percentile, um.
    coats : float
        The film is this many coats, each landed and set before the next lands (the cycles
        and interlaced passes of a layer: a pass's revolution takes about as long as the set
        time), so ``h0`` is one coat's: the percentile of the whole film over ``coats`` (not
        applied to a fixed ``h0_um``). Levelling the whole film at one coat's ``h0`` is the
        sum of the coats levelled one by one where they have one shape; levelling it at the
        whole film's ``h0`` (``coats = 1``) would let ink flow as if every coat stayed wet
        together, ``coats^(3/4)`` times farther. 1..1e6.
    halo_lengths : float
        The kernel is truncated at this many levelling lengths ``L = (D t)^(1/4)`` (its
        weight beyond 10 L is 0.5 %), 4..40.
    window_cells : int
        Cells of one levelling window (a strip plus halos, whole grid width), bounding the
        memory (about 40 bytes a cell); a window is at least ``4 halo`` rows. The films as
        landed are kept for the levelling pass (8 bytes a cell and levelled film) when they
        fit in this many cells together, else deposited again.
    coarse_per_length : float
        The convolutions of the model (``g * (w h)`` and ``g * w``) are computed on a grid
        ``f`` times coarser than the deposit's, ``f`` the largest whole number that keeps its
        cell within ``L / coarse_per_length`` (the kernel is smooth at ``L``): restricted by
        the adjoint of bilinear interpolation, convolved with the coarse kernel (which undoes
        the round trip's damping of long waves) and interpolated back, so the levelling
        still conserves the volume exactly, keeps dry cells dry and does not depend on the
        tiling. 2..100.
    exact : bool
        Convolve on the deposit grid itself (``f = 1``; slow when ``L`` spans many cells).
    """

    set_time_s: float = 0.0
    viscosity_mpa_s: float = 10.0
    surface_tension_mn_m: float = 30.0
    h0_percentile: float = 10.0
    h0_um: float | None = None
    coats: float = 1.0
    halo_lengths: float = 10.0
    window_cells: int = 24_000_000
    coarse_per_length: float = 3.5
    exact: bool = False

    def __post_init__(self) -> None:
        from .. import ranges as R

        for name, rg in (("set_time_s", R.SET_TIME_S), ("viscosity_mpa_s", R.VISCOSITY_MPA_S),
                         ("surface_tension_mn_m", R.SURFACE_TENSION_MN_M)):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and v in rg):
                raise ConfigError(f"{name} must be a number in {rg.text()}, got {v!r}")
        if not (isinstance(self.h0_percentile, (int, float)) and 0.0 <= self.h0_percentile <= 100.0):
            raise ConfigError(f"h0_percentile must be in 0..100, got {self.h0_percentile!r}")
        if self.h0_um is not None and not (math.isfinite(self.h0_um) and 0 < self.h0_um <= 1e5):
            raise ConfigError(f"h0_um must be a number in (0, 1e5], got {self.h0_um!r}")
        if not (isinstance(self.coats, (int, float)) and not isinstance(self.coats, bool)
                and math.isfinite(self.coats) and 1.0 <= self.coats <= 1e6):
            raise ConfigError(f"coats must be a number in 1..1e6, got {self.coats!r}")
        if not (math.isfinite(self.halo_lengths) and 4.0 <= self.halo_lengths <= 40.0):
            raise ConfigError(f"halo_lengths must be in 4..40, got {self.halo_lengths!r}")
        if not 10_000 <= int(self.window_cells) <= 2_000_000_000:
            raise ConfigError(f"window_cells must be in 10000..2e9, got {self.window_cells!r}")
        if not (isinstance(self.coarse_per_length, (int, float)) and 2.0 <= self.coarse_per_length <= 100.0):
            raise ConfigError(f"coarse_per_length must be in 2..100, got {self.coarse_per_length!r}")

    @classmethod
    def from_head(cls, head: InkjetHead, **overrides) -> LevelOptions:
        """The head's (preset's) ``set_time_s``, ``viscosity_mpa_s`` and ``surface_tension_mn_m``,
        with ``overrides`` (any field; ``None`` values are ignored)."""
        base = dict(set_time_s=head.set_time_s, viscosity_mpa_s=head.viscosity_mpa_s,
                    surface_tension_mn_m=head.surface_tension_mn_m)
        base.update({k: v for k, v in overrides.items() if v is not None})
        return cls(**base)

    @property
    def active(self) -> bool:
        return self.set_time_s > 0.0

    def coarse_factor(self, length_um: float, cell_um: float) -> int:
        """``f``: the coarse grid's cell in deposit cells for levelling length ``length_um``
        on cells of ``cell_um`` (the larger side), 1 if :attr:`exact`."""
        if self.exact:
            return 1
        return max(1, int(length_um / (self.coarse_per_length * cell_um)))


@dataclass(frozen=True)
class LevelledFilm:
    """Figures of the film after levelling (interior, as :class:`FilmReport`). Thicknesses in um.

    The uncovered fraction is the as-landed one: a dry cell stays dry (the linear model with a
    pinned contact line does not fill a pinhole), so it is not repeated here.
    """

    set_time_s: float
    viscosity_mpa_s: float
    surface_tension_mn_m: float
    h0_um: float
    h0_rule: str
    rate_um4_per_s: float
    levelling_length_um: float
    halo_cells: tuple[int, int]
    volume_error_fraction: float
    thinnest_um: float
    mean_um: float
    thinnest_to_mean: float
    radial_spread: float
    below_half_landed_mean_fraction: float
    #: the convolutions' grid in deposit cells (``f``; 1: the deposit grid itself)
    coarse_factor: int = 1
    radial_bins: tuple[tuple[float, float, float], ...] = field(default=())

    def to_json(self) -> dict:
        d = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}
        d["radial_bins"] = [{"r_mm": a, "mean_um": b, "area_mm2": c} for a, b, c in self.radial_bins]
        return d


@dataclass(frozen=True, eq=False)
class InkDrops:
    """Drops ready to deposit: ``col, row`` ``(M,) float64`` continuous design coordinates
    (the placement's pixels), ``volume_pl`` ``(M,) float64``."""

    col: np.ndarray
    row: np.ndarray
    volume_pl: np.ndarray

    def __post_init__(self) -> None:
        n = np.asarray(self.col).shape
        if np.asarray(self.row).shape != n or np.asarray(self.volume_pl).shape != n or len(n) != 1:
            raise ConfigError("InkDrops needs col, row and volume_pl of one shape (M,)")
        v = np.asarray(self.volume_pl)
        if v.size and not (np.isfinite(v).all() and (v >= 0).all()):
            raise ConfigError("drop volumes must be finite and >= 0 pl")
        c, r = np.asarray(self.col), np.asarray(self.row)
        if c.size and not (np.isfinite(c).all() and np.isfinite(r).all()):
            raise ConfigError("drop sites must be finite")

    def __len__(self) -> int:
        return int(np.asarray(self.col).size)

    @staticmethod
    def concat(parts: Sequence[InkDrops]) -> InkDrops:
        """One set from several (e.g. the passes of a layer)."""
        if not parts:
            return InkDrops(np.zeros(0), np.zeros(0), np.zeros(0))
        return InkDrops(*(np.concatenate([np.asarray(getattr(p, f), np.float64) for p in parts]) for f in ("col", "row", "volume_pl")))


def ink_drops(drops, head: InkjetHead) -> InkDrops:
    """:class:`InkDrops` from placed drops (:class:`~rotoprint.rotary.simulate.Drops`): level
    ``L`` of a head with ``G`` grey levels holds ``L / G`` of ``drop_volume_pl``."""
    vol = np.asarray(drops.level, np.float64) * (head.drop_volume_pl / head.grey_levels)
    return InkDrops(np.asarray(drops.col, np.float64), np.asarray(drops.row, np.float64), vol)


@dataclass(frozen=True)
class FilmReport:
    """Figures of one film (see the module docstring). Thicknesses in um, areas in mm2."""

    drops: int
    footprint_um: float
    spread_factor: float | None
    grid_um: tuple[float, float]
    planned_volume_pl: float
    deposited_volume_pl: float
    volume_error_fraction: float
    volume_beyond_grid_pl: float
    volume_outside_design_fraction: float
    drops_outside: int
    drops_outside_fraction: float
    design_area_mm2: float
    interior_area_mm2: float
    band_area_mm2: float
    uncovered_fraction: float
    uncovered_area_mm2: float
    band_uncovered_fraction: float
    design_uncovered_fraction: float
    thinnest_um: float
    mean_um: float
    thinnest_to_mean: float
    radial_spread: float
    radial_bins: tuple[tuple[float, float, float], ...] = field(default=())
    #: the film after levelling (:class:`LevelOptions` with ``set_time_s > 0``), else None
    levelled: LevelledFilm | None = None

    def to_json(self) -> dict:
        d = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items() if k != "levelled"}
        d["radial_bins"] = [{"r_mm": a, "mean_um": b, "area_mm2": c} for a, b, c in self.radial_bins]
        if self.levelled is not None:
            d["levelled"] = self.levelled.to_json()
        return d


@dataclass(frozen=True, eq=False)
class Deposit:
    """Films of one or more drop sets on one grid.

    Attributes
    ----------
    films : tuple of FilmReport
        One per drop set, in order.
    pairs : tuple of dict
        Per requested pair ``(i, j)``: ``a``, ``b``, ``a_not_b_fraction`` (share of film
        ``i``'s covered design area that film ``j`` does not cover) and ``b_not_a_fraction``.
    thickness : (rows, cols) float64 or None
        The first film's thickness map (um) when asked for (``keep_map=True``), grid cell
        ``(r, c)`` at design coordinates ``((c + 0.5 - origin[0]) / n[0], (r + 0.5 -
        origin[1]) / n[1])``.
    levelled_thickness : (rows, cols) float64 or None
        The first film's levelled map, likewise (``keep_map=True`` and levelling).
    """

    films: tuple[FilmReport, ...]
    pairs: tuple[dict, ...]
    cells_per_pixel: tuple[int, int]
    origin_cells: tuple[int, int]
    thickness: np.ndarray | None = None
    levelled_thickness: np.ndarray | None = None

    def to_json(self) -> dict:
        out = self.films[0].to_json() if len(self.films) == 1 else {"films": [f.to_json() for f in self.films]}
        if self.pairs:
            out["reagent_pairs"] = list(self.pairs)
        return out


def _drop_shapes(volume_pl: np.ndarray, head: InkjetHead, opts: DepositOptions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per drop: footprint radius, cap sphere radius, cap height (um)."""
    v = np.asarray(volume_pl, np.float64)
    if v.size > 1 and v.min() == v.max():  # one volume (a layer's drops, each pass printed as often): one shape
        return tuple(np.full(v.size, x[0]) for x in _drop_shapes(v[:1], head, opts))
    full = opts.full_footprint_um(head)
    rel = np.cbrt(np.maximum(v, 0.0) / head.drop_volume_pl)
    a = 0.5 * full * rel
    h = cap_height_um(v * UM3_PER_PL, np.maximum(a, 1e-12))
    h = np.maximum(h, 1e-12)
    rs = (a * a + h * h) / (2.0 * h)
    return a, rs, h


def film_cells(placement: Placement, head: InkjetHead, options: DepositOptions | None = None) -> tuple[int, int]:
    """``(nx, ny)``: the deposit grid's cells per design pixel across columns and rows, the
    fewest that keep a cell within ``D / cells_per_footprint`` (``D``: the full drop's
    footprint, :meth:`DepositOptions.full_footprint_um`).

    Examples
    --------
    >>> from rotoprint import load_device
    >>> film_cells(Placement(4, 4, 0.0704, 0.0176, inner_radius_mm=60.0), load_device("omnidot760").head)
    (8, 2)
    """
    opts = options or DepositOptions()
    d_um = opts.full_footprint_um(head)
    return (max(1, math.ceil(placement.pitch_x_mm * 1e3 * opts.cells_per_footprint / d_um)),
            max(1, math.ceil(placement.pitch_y_mm * 1e3 * opts.cells_per_footprint / d_um)))


def film_grid(placement: Placement, head: InkjetHead, options: DepositOptions | None = None) -> Placement:
    """The film grid over the design: every pixel of ``placement`` divided into
    :func:`film_cells` cells (``W * nx`` by ``H * ny`` cells, the same rectangle), the grid a
    design mask exact to a deposit cell is rasterised on (see :func:`deposit_film`)."""
    nx, ny = film_cells(placement, head, options)
    return Placement(placement.width_px * nx, placement.height_px * ny, placement.pitch_x_mm / nx, placement.pitch_y_mm / ny,
                     inner_radius_mm=placement.inner_radius_mm, angle_deg=placement.angle_deg)


def interior_mask(mask: np.ndarray, pitch_x_um: float, pitch_y_um: float, distance_um: float, *,
                  strip_cells: int = 4_000_000) -> np.ndarray:
    """``(H, W) bool``: cells of ``mask`` ``(H, W) bool`` whose centre is at least
    ``distance_um`` from the nearest cell centre outside it (beyond the array is outside), on
    cells of ``pitch_x_um`` x ``pitch_y_um``: the rule of the deposit model's interior
    (``distance_um``: half a footprint plus half a cell). Computed in strips of about
    ``strip_cells`` cells with halos reaching the distance (the kernel's memory: 4 bytes a cell).

    Examples
    --------
    >>> m = np.zeros((1, 9), bool); m[0, 1:8] = True
    >>> interior_mask(np.repeat(m, 9, axis=0), 1.0, 1.0, 2.0)[4].astype(int).tolist()
    [0, 0, 1, 1, 1, 1, 1, 0, 0]
    """
    m = np.asarray(mask, bool)
    if m.ndim != 2:
        raise ImageError(f"interior_mask needs a 2-D mask, got shape {m.shape}")
    if not (pitch_x_um > 0 and pitch_y_um > 0 and distance_um >= 0):
        raise ConfigError("interior_mask needs pitches > 0 and a distance >= 0 um")
    padded = np.zeros((m.shape[0] + 2, m.shape[1] + 2), bool)
    padded[1:-1, 1:-1] = m
    out = np.empty((m.shape[0], m.shape[1] + 2), bool)
    halo = math.ceil(distance_um / pitch_y_um) + 2
    step = max(1, int(strip_cells) // (m.shape[1] + 2))
    for r0 in range(0, m.shape[0], step):  # rows r0..r1 of the mask are rows r0 + 1.. of padded
        r1 = min(m.shape[0], r0 + step)
        e0, e1 = max(0, r0 + 1 - halo), min(m.shape[0] + 2, r1 + 1 + halo)
        _k.interior_rows_jit(padded[e0:e1], r0 + 1 - e0, r1 + 1 - e0, float(distance_um), float(pitch_x_um),
                             float(pitch_y_um), out[r0:r1])
    return out[:, 1:-1]


def radial_area_mm2(mask: np.ndarray, grid: Placement, edges_mm: np.ndarray) -> np.ndarray:
    """``(B,) float64``: the area of ``mask`` ``(H, W) bool`` on ``grid`` (its pixels, each at
    its centre's platform radius) in the radial bins of equal width ``edges_mm`` ``(B + 1,)``
    (increasing), mm^2."""
    m = np.asarray(mask, bool)
    e = np.asarray(edges_mm, np.float64)
    if m.shape != (grid.height_px, grid.width_px):
        raise ImageError(f"mask is {m.shape[1]} x {m.shape[0]} px, the grid {grid.width_px} x {grid.height_px} px")
    if e.ndim != 1 or e.size < 2 or not np.allclose(np.diff(e), e[1] - e[0]) or not e[1] > e[0]:
        raise ConfigError("radial_area_mm2 needs at least two increasing, equally spaced bin edges")
    ang = math.radians(grid.angle_deg)
    geo = np.array([0.0, 0.0, 1.0, 1.0, grid.inner_radius_mm, grid.pitch_x_mm, grid.pitch_y_mm, grid.height_px,
                    math.cos(ang), math.sin(ang)], np.float64)
    out = np.zeros(e.size - 1, np.int64)
    _k.radial_cell_counts_jit(m, geo, float(e[0]), float(e[1] - e[0]), out)
    return out * (grid.pitch_x_mm * grid.pitch_y_mm)


def deposit_film(
    design_mask: np.ndarray,
    placement: Placement,
    head: InkjetHead,
    drop_sets: Sequence[InkDrops],
    *,
    options: DepositOptions | None = None,
    pairs: Sequence[tuple[int, int]] = (),
    keep_map: bool = False,
    use_jit: bool = True,
) -> Deposit:
    """Deposit every drop set on a fine grid over the design and measure the films.

    Parameters
    ----------
    design_mask : (H, W) or (H * ny, W * nx) bool
        Pixels the design asks to print, on ``placement``'s grid (each cell takes its pixel's
        value), or cells of the film grid (:func:`film_grid`: ``nx, ny`` from
        :func:`film_cells`), e.g. the design rasterised at the cells' centres: a mask exact to a
        cell instead of a pixel.
    placement : Placement
        The design's grid in the platform frame (for the radial bins and the cell size).
    head : InkjetHead
        Its ``drop_volume_pl`` and ``spread_factor`` give the footprints.
    drop_sets : sequence of InkDrops
        One film per set (e.g. one per material or reagent); passes of one layer are one set.
    options : DepositOptions, optional
    pairs : sequence of (int, int)
        Index pairs of reactive reagents to compare.
    keep_map : bool
        Return the first film's whole thickness map (memory: 8 bytes per cell), and its
        levelled map when levelling.
    use_jit : bool
        numba kernels (default) or the numpy reference (slow; for tests).

    Returns
    -------
    Deposit

    Raises
    ------
    ImageError
        ``design_mask`` is not the placement's size.
    ConfigError
        No drop set, a pair index out of range, bad options.
    RasterTooLargeError
        The grid would exceed :data:`MAX_GRID_COLS` columns or :data:`MAX_GRID_CELLS` cells
        (the message gives the size).

    Examples
    --------
    >>> from rotoprint import load_device
    >>> head = load_device("omnidot760").head
    >>> pl = Placement(20, 20, 25.4 / 360, 25.4 / 360, inner_radius_mm=60.0)
    >>> mask = np.ones((20, 20), bool)
    >>> cc, rr = np.meshgrid(np.arange(20) + 0.5, np.arange(20) + 0.5)
    >>> drops = InkDrops(cc.ravel(), rr.ravel(), np.full(400, 8.0))
    >>> f = deposit_film(mask, pl, head, [drops]).films[0]
    >>> abs(f.volume_error_fraction) < 1e-9, f.uncovered_fraction > 0.5
    (True, True)
    """
    opts = options or DepositOptions()
    mask = np.asarray(design_mask, bool)
    h_px, w_px = placement.height_px, placement.width_px
    nx, ny = film_cells(placement, head, opts)
    on_cells = (nx, ny) != (1, 1) and mask.shape == (h_px * ny, w_px * nx)  # the mask on the film grid
    if mask.shape != (h_px, w_px) and not on_cells:
        raise ImageError(f"design mask is {mask.shape[1]} x {mask.shape[0]} px, the placement is {w_px} x {h_px} px "
                         f"(its film grid {w_px * nx} x {h_px * ny} cells)")
    if not drop_sets:
        raise ConfigError("deposit_film needs at least one drop set")
    for i, j in pairs:
        if not (0 <= i < len(drop_sets) and 0 <= j < len(drop_sets)) or i == j:
            raise ConfigError(f"reagent pair ({i}, {j}) must name two different drop sets of 0..{len(drop_sets) - 1}")
    d_full = opts.full_footprint_um(head)
    a_nom = d_full / 2.0
    px_um, py_um = placement.pitch_x_mm * 1e3, placement.pitch_y_mm * 1e3
    gx, gy = px_um / nx, py_um / ny
    shapes = [_drop_shapes(s.volume_pl, head, opts) for s in drop_sets]
    a_max = max([a_nom] + [float(sh[0].max()) for sh in shapes if sh[0].size])
    pad_x = math.ceil(a_max / gx) + 2
    pad_y = math.ceil(a_max / gy) + 2
    # the grid: the design rectangle and every drop site, plus a footprint
    c_lo, c_hi, r_lo, r_hi = 0.0, float(w_px), 0.0, float(h_px)
    for s in drop_sets:
        if len(s):
            c_lo, c_hi = min(c_lo, float(np.min(s.col))), max(c_hi, float(np.max(s.col)))
            r_lo, r_hi = min(r_lo, float(np.min(s.row))), max(r_hi, float(np.max(s.row)))
    ox = pad_x + math.ceil(-c_lo * nx)
    oy = pad_y + math.ceil(-r_lo * ny)
    cols = ox + math.ceil(c_hi * nx) + pad_x
    rows = oy + math.ceil(r_hi * ny) + pad_y
    if cols > MAX_GRID_COLS or rows * cols > MAX_GRID_CELLS:
        raise RasterTooLargeError(
            f"the film grid would be {cols} x {rows} cells ({rows * cols / 1e6:.0f} M, cell {gx:.1f} x {gy:.1f} um); "
            f"at most {MAX_GRID_COLS} columns and {MAX_GRID_CELLS / 1e6:.0f} M cells: use a larger footprint or fewer cells_per_footprint"
        )
    strip_fn = _k.deposit_strip_jit if use_jit else _k.deposit_strip_numpy
    prepared = []
    for s, (a, rs, hh) in zip(drop_sets, shapes):
        u = np.asarray(s.col, np.float64) * nx + ox
        v = np.asarray(s.row, np.float64) * ny + oy
        order = np.argsort(v, kind="stable")
        u, v = u[order], v[order]
        vol = np.asarray(s.volume_pl, np.float64)
        if vol.size and vol.min() == vol.max():  # one volume, one shape: nothing to reorder
            vol = vol * UM3_PER_PL
        else:
            a, rs, hh = a[order], rs[order], hh[order]
            vol = vol[order] * UM3_PER_PL
        # site inside the design mask?
        ci = np.floor(np.asarray(s.col, np.float64) * (nx if on_cells else 1)).astype(np.int64)
        ri = np.floor(np.asarray(s.row, np.float64) * (ny if on_cells else 1)).astype(np.int64)
        ok = (ci >= 0) & (ci < mask.shape[1]) & (ri >= 0) & (ri < mask.shape[0])
        on = np.zeros(ci.size, bool)
        on[ok] = mask[ri[ok], ci[ok]]
        prepared.append((u, v, vol, a, rs, hh, int(ci.size - on.sum())))
    # column -> design column (or -1 outside the design)
    gc = np.arange(cols)
    dcol = np.floor((gc + 0.5 - ox) / nx).astype(np.int64)
    dcol_ok = (dcol >= 0) & (dcol < w_px)
    dcol = np.clip(dcol, 0, w_px - 1)
    g_min = min(gx, gy)
    margin = math.ceil((a_nom + g_min) / gy) + 2
    strip_rows = max(1, int(opts.strip_cells) // cols)
    area_mm2 = gx * gy * 1e-6
    nsets = len(drop_sets)
    # the radius of a cell (the radial bins): its grid origin, cells per pixel and the placement
    ang = math.radians(placement.angle_deg)
    geo = np.array([ox, oy, nx, ny, placement.inner_radius_mm, placement.pitch_x_mm, placement.pitch_y_mm,
                    placement.height_px, math.cos(ang), math.sin(ang)], np.float64)
    n_bins = int(placement.radial_range_mm()[1]) + 2
    # per film (_k.strip_stats_jit): the sums of every cell, the design's and the interior's with
    # their compensations and the thinnest; the cells of the design, covered, interior,
    # uncovered, band, uncovered band; the interior's radial bins
    sums = [np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, math.inf]) for _ in range(nsets)]
    counts = [np.zeros(6, np.int64) for _ in range(nsets)]
    bins_acc = [(np.zeros(n_bins), np.zeros(n_bins, np.int64)) for _ in range(nsets)]
    pair_acc = [np.zeros(2, np.int64) for _ in pairs]
    full = np.zeros((rows, cols), np.float64) if keep_map else None
    def geometry(r0: int, r1: int):
        """Design and interior cells of grid rows r0..r1 (independent of the strips: the
        distance reaches ``margin``)."""
        e0, e1 = max(0, r0 - margin), min(rows, r1 + margin)
        if on_cells:  # the film grid's mask: a window of it, False beyond the design
            dmask = np.zeros((e1 - e0, cols), bool)
            m0, m1 = max(e0, oy), min(e1, oy + mask.shape[0])
            if m1 > m0:
                dmask[m0 - e0: m1 - e0, ox: ox + mask.shape[1]] = mask[m0 - oy: m1 - oy]
        else:
            gr = np.arange(e0, e1)
            drow = np.floor((gr + 0.5 - oy) / ny).astype(np.int64)
            drow_ok = (drow >= 0) & (drow < h_px)
            dmask = mask[np.clip(drow, 0, h_px - 1)][:, dcol] & drow_ok[:, None] & dcol_ok[None, :]
        core = slice(r0 - e0, r1 - e0)
        des = dmask[core]
        if des.any():  # distance_transform_edt(dmask, sampling=(gy, gx))[core] >= thr, without its temporaries
            inter = np.empty_like(des)
            _k.interior_rows_jit(dmask, r0 - e0, r1 - e0, a_nom + 0.5 * g_min, gx, gy, inter)
        else:
            inter = des
        return des, inter

    def deposit_rows(si: int, r0: int, r1: int, into: np.ndarray | None = None) -> np.ndarray:
        """Film rows r0..r1 of drop set ``si`` (into ``into``, zeros of that shape, if given)."""
        u, v, vol, a, rs, hh, _ = prepared[si]
        film = np.zeros((r1 - r0, cols), np.float64) if into is None else into
        lo = np.searchsorted(v, r0 - a_max / gy - 2.0, side="left")
        hi = np.searchsorted(v, r1 + a_max / gy + 2.0, side="right")
        if hi > lo:
            strip_fn(u[lo:hi], v[lo:hi], vol[lo:hi], a[lo:hi], rs[lo:hi], hh[lo:hi], gx, gy, r0, film)
        return film

    level = opts.level
    levels = list(level) if isinstance(level, (list, tuple)) else [level] * len(drop_sets)
    if len(levels) != len(drop_sets):
        raise ConfigError(f"level: {len(levels)} options for {len(drop_sets)} drop sets")
    levels = [lv if lv is not None and lv.active else None for lv in levels]
    n_design_cells = int(mask.sum()) * (1 if on_cells else nx * ny)
    sample_stride = max(1, n_design_cells // 2_000_000)
    samples: list[list[np.ndarray]] = [[] for _ in range(nsets)]
    inter_bits = np.zeros((rows, (cols + 7) // 8), np.uint8) if any(lv is not None for lv in levels) else None
    # the levelled films as landed and the interior's cells of each strip, kept for the
    # levelling pass when they fit in every levelled film's window_cells (else recomputed)
    n_lev = sum(lv is not None for lv in levels)
    keep_landed = n_lev > 0 and rows * cols * n_lev <= min(int(lv.window_cells) for lv in levels if lv is not None)
    landed: dict[int, np.ndarray] = {}
    if keep_landed:
        for si in range(nsets):
            if levels[si] is not None:
                landed[si] = full if (full is not None and si == 0) else np.zeros((rows, cols), np.float64)
    sample_buf = np.empty(strip_rows * cols // sample_stride + 1) if n_lev else np.empty(0)
    for r0 in range(0, rows, strip_rows):
        r1 = min(rows, r0 + strip_rows)
        des, inter = geometry(r0, r1)
        if inter_bits is not None:
            inter_bits[r0:r1] = np.packbits(inter, axis=1)
        strip_films = []
        for si in range(nsets):
            # deposited in place into the kept map or landed film (zeros), else into a new strip
            keep = landed.get(si, full if si == 0 else None)
            film = deposit_rows(si, r0, r1, None if keep is None else keep[r0:r1])
            if full is not None and si == 0 and keep is not full:
                full[r0:r1] = film
            stride = sample_stride if levels[si] is not None else 0
            ns = _k.strip_stats_jit(film, des, inter, r0, geo, stride, sums[si], counts[si], *bins_acc[si],
                                    sample_buf if stride else np.empty(0))
            if ns:
                samples[si].append(sample_buf[:ns].copy())
            if pairs:
                strip_films.append(film)
        for pi, (i, j) in enumerate(pairs):
            _k.pair_counts_jit(strip_films[i], strip_films[j], des, pair_acc[pi])
    acc = [dict(dep=float(sm[0] + sm[1]), out_dep=float((sm[0] + sm[1]) - (sm[2] + sm[3])), design=int(c[0]),
                covered_design=int(c[1]), interior=int(c[2]), unc=int(c[3]), band=int(c[4]), band_unc=int(c[5]),
                tsum=float(sm[4] + sm[5]), tmin=float(sm[6]), bins_sum=bs, bins_n=bn)
           for sm, c, (bs, bn) in zip(sums, counts, bins_acc)]

    def landed_rows(si: int, r0: int, r1: int) -> np.ndarray:
        return landed[si][r0:r1] if si in landed else deposit_rows(si, r0, r1)

    # the levelled figures' geometry: the interior (packed above) and each cell's radius (geo)

    levelled, full_lev = _level_films(levels, samples, acc, rows, cols, gx, gy, area_mm2, strip_rows,
                                      (inter_bits, geo, n_bins), landed_rows, keep_map)
    films = []
    for si, (s, ac, prep) in enumerate(zip(drop_sets, acc, prepared)):
        planned = float(np.sum(s.volume_pl))
        dep = ac["dep"] * gx * gy / UM3_PER_PL
        n_int = ac["interior"]
        mean = ac["tsum"] / n_int if n_int else float("nan")
        tmin = ac["tmin"] if n_int else float("nan")
        bins, spread = _bins_spread(ac["bins_sum"], ac["bins_n"], area_mm2)
        m = len(s)
        films.append(
            FilmReport(
                drops=m,
                footprint_um=d_full,
                spread_factor=None if opts.footprint_um is not None else (head.spread_factor if opts.spread_factor is None else opts.spread_factor),
                grid_um=(gx, gy),
                planned_volume_pl=planned,
                deposited_volume_pl=dep,
                volume_error_fraction=dep / planned - 1.0 if planned else 0.0,
                volume_beyond_grid_pl=max(0.0, planned - dep) if planned and dep < planned * (1 - 1e-9) else 0.0,
                volume_outside_design_fraction=ac["out_dep"] / ac["dep"] if ac["dep"] else 0.0,
                drops_outside=prep[6],
                drops_outside_fraction=prep[6] / m if m else 0.0,
                design_area_mm2=ac["design"] * area_mm2,
                interior_area_mm2=n_int * area_mm2,
                band_area_mm2=ac["band"] * area_mm2,
                uncovered_fraction=ac["unc"] / n_int if n_int else 0.0,
                uncovered_area_mm2=ac["unc"] * area_mm2,
                band_uncovered_fraction=ac["band_unc"] / ac["band"] if ac["band"] else 0.0,
                design_uncovered_fraction=1.0 - ac["covered_design"] / ac["design"] if ac["design"] else 0.0,
                thinnest_um=tmin,
                mean_um=mean,
                thinnest_to_mean=tmin / mean if n_int and mean > 0 else float("nan"),
                radial_spread=spread,
                radial_bins=bins,
                levelled=levelled[si],
            )
        )
    pair_out = []
    for (i, j), (a_nb, b_na) in zip(pairs, (tuple(int(x) for x in p) for p in pair_acc)):
        ca, cb = acc[i]["covered_design"], acc[j]["covered_design"]
        pair_out.append({"a": i, "b": j, "a_not_b_fraction": a_nb / ca if ca else 0.0, "b_not_a_fraction": b_na / cb if cb else 0.0})
    return Deposit(films=tuple(films), pairs=tuple(pair_out), cells_per_pixel=(nx, ny), origin_cells=(ox, oy), thickness=full,
                   levelled_thickness=full_lev)


def _bins_spread(bins_sum: np.ndarray, bins_n: np.ndarray, area_mm2: float):
    bins, spread = [], float("nan")
    nz = np.flatnonzero(bins_n)
    if nz.size:
        med = float(np.median(bins_n[nz]))
        means = bins_sum[nz] / bins_n[nz]
        bins = [(float(b), float(m), float(n * area_mm2)) for b, m, n in zip(nz, means, bins_n[nz])]
        keep = bins_n[nz] >= BIN_MIN_SHARE * med
        if keep.any():
            mk = means[keep]
            spread = float(np.max(np.abs(mk / mk.mean() - 1.0)))
    return tuple(bins), spread


class _LevelledStats:
    """The levelled film's interior figures, strip by strip (``_levelling_kernels.film_stats_jit``:
    the interior from the first pass's packed mask, the radial bins computed per cell)."""

    def __init__(self, landed_mean: float, inter_bits: np.ndarray, geo: np.ndarray, n_bins: int):
        self.landed_mean = landed_mean
        self.inter_bits, self.geo = inter_bits, geo
        self.acc = np.array([0.0, 0.0, 0.0, 0.0, math.inf, 0.0, 0.0])
        self.bins_sum, self.bins_n = np.zeros(n_bins), np.zeros(n_bins, np.int64)

    def add(self, lv: np.ndarray, r0: int) -> None:
        from . import _levelling_kernels as _lk

        _lk.film_stats_jit(lv, self.inter_bits[r0: r0 + lv.shape[0]], r0, self.geo, 0.5 * self.landed_mean, self.acc,
                           self.bins_sum, self.bins_n)

    @property
    def tot(self) -> float:
        return float(self.acc[0] + self.acc[1])

    @property
    def tsum(self) -> float:
        return float(self.acc[2] + self.acc[3])

    @property
    def tmin(self) -> float:
        return float(self.acc[4])

    @property
    def n_int(self) -> int:
        return int(self.acc[5])

    @property
    def below(self) -> int:
        return int(self.acc[6])

    def film(self, lev: LevelOptions, h0: float, rule: str, rate: float, halo: tuple[int, int], factor: int,
             deposited: float, area_mm2: float) -> LevelledFilm:
        n_int = self.n_int
        mean = self.tsum / n_int if n_int else float("nan")
        bins, spread = _bins_spread(self.bins_sum, self.bins_n, area_mm2)
        return LevelledFilm(
            set_time_s=float(lev.set_time_s),
            viscosity_mpa_s=float(lev.viscosity_mpa_s),
            surface_tension_mn_m=float(lev.surface_tension_mn_m),
            h0_um=h0,
            h0_rule=rule,
            rate_um4_per_s=rate,
            levelling_length_um=(rate * lev.set_time_s) ** 0.25,
            halo_cells=halo,
            volume_error_fraction=self.tot / deposited - 1.0 if deposited else 0.0,
            thinnest_um=self.tmin if n_int else float("nan"),
            mean_um=mean,
            thinnest_to_mean=self.tmin / mean if n_int and mean > 0 else float("nan"),
            radial_spread=spread,
            below_half_landed_mean_fraction=self.below / n_int if n_int else 0.0,
            coarse_factor=factor,
            radial_bins=bins,
        )


def _film_h0(lev: LevelOptions, samples) -> tuple[float, str] | None:
    if lev.h0_um is not None:
        return float(lev.h0_um), "fixed"
    wet = np.concatenate(samples) if samples else np.zeros(0)
    if not wet.size:
        return None
    h0 = float(np.percentile(wet, lev.h0_percentile)) / lev.coats
    rule = f"p{lev.h0_percentile:g} of the as-landed wet interior film" + (f" / {lev.coats:g} coats" if lev.coats != 1 else "")
    return (h0, rule) if h0 > 0.0 else None


def _level_films(levels, samples, acc, rows, cols, gx, gy, area_mm2, strip_rows, interior, landed_rows, keep_map):
    """Level every film with options in ``levels``: its :class:`LevelledFilm` (or None) per
    film, and the first film's levelled map (``keep_map``, else None).

    A film whose coarse factor is 1 (:meth:`LevelOptions.coarse_factor`) is levelled on the
    deposit grid in windows with halos (:func:`_level_film_exact`); the others share one
    pass restricting their wet films to their coarse grids, the coarse convolutions, and one
    pass interpolating back, strip by strip (``landed_rows`` gives a film's rows as landed,
    ``interior`` the packed interior mask, the radius geometry and the number of 1 mm bins for
    :class:`_LevelledStats`).
    """
    from . import _levelling as _lv
    from . import _levelling_kernels as _lk

    nsets = len(levels)
    out: list[LevelledFilm | None] = [None] * nsets
    full_lev = None
    coarse = {}
    for si, lev in enumerate(levels):
        if lev is None:
            continue
        got = _film_h0(lev, samples[si])
        if got is None:
            continue
        h0, rule = got
        rate = levelling_rate_um4_per_s(lev.surface_tension_mn_m, lev.viscosity_mpa_s, h0)
        dt = rate * lev.set_time_s
        f = lev.coarse_factor(dt ** 0.25, max(gx, gy))
        landed_mean = acc[si]["tsum"] / acc[si]["interior"] if acc[si]["interior"] else float("nan")
        if f == 1:
            stats, lmap = _level_film_exact(si, lev, dt, gx, gy, rows, cols, landed_mean, interior, landed_rows,
                                            keep_map and si == 0)
            out[si] = stats.film(lev, h0, rule, rate, stats.halo, 1, acc[si]["dep"], area_mm2)
            if lmap is not None:
                full_lev = lmap
            continue
        rc, cc = -(-rows // f) + 2, -(-cols // f) + 2
        need = 4 * rc * cc * 8
        if need > 2_000_000_000:
            raise RasterTooLargeError(f"levelling film {si}: the coarse grids would take {need / 1e9:.1f} GB "
                                      f"({cc} x {rc} nodes of {f} cells); raise coarse_per_length")
        coarse[si] = dict(lev=lev, h0=h0, rule=rule, rate=rate, dt=dt, f=f, landed_mean=landed_mean,
                          h=np.zeros((rc, cc)), w=np.zeros((rc, cc)), cols=_lk.axis_weights(cols, f))
    if not coarse:
        return out, full_lev
    for r0 in range(0, rows, strip_rows):
        r1 = min(rows, r0 + strip_rows)
        for si, c in coarse.items():
            _lk.restrict_wet_jit(landed_rows(si, r0, r1), r0, c["f"], c["cols"][0], c["cols"][1], c["h"], c["w"])
    for si, c in coarse.items():
        f = c["f"]
        kernel = _lv.levelling_kernel(c["dt"], gx, gy, c["lev"].halo_lengths, factor=f)
        c["halo"] = (f * ((kernel.shape[1] - 1) // 2), f * ((kernel.shape[0] - 1) // 2))
        c["g"], c["n"] = _lv.convolve_rows([c["h"], c["w"]], kernel, c["lev"].window_cells)
        scale = 1.0 / (f * f)
        c["g"] *= scale
        c["n"] *= scale
        del c["h"], c["w"]
        c["stats"] = _LevelledStats(c["landed_mean"], *interior)
    first = 0 if keep_map and 0 in coarse else None
    if first is not None:
        full_lev = np.zeros((rows, cols), np.float64)
    buf = np.empty((min(rows, strip_rows), cols), np.float64)  # one strip's levelled film, reused
    for r0 in range(0, rows, strip_rows):
        r1 = min(rows, r0 + strip_rows)
        for si, c in coarse.items():
            film = landed_rows(si, r0, r1)
            lv = full_lev[r0:r1] if si == first else buf[: r1 - r0]
            _lk.prolong_combine_jit(film, r0, c["f"], c["cols"][0], c["cols"][1], c["n"], c["g"], lv)
            c["stats"].add(lv, r0)
    for si, c in coarse.items():
        out[si] = c["stats"].film(c["lev"], c["h0"], c["rule"], c["rate"], c["halo"], c["f"], acc[si]["dep"], area_mm2)
    return out, full_lev


def _level_film_exact(si, lev: LevelOptions, dt, gx, gy, rows, cols, landed_mean, interior, landed_rows, keep_map):
    """Level film ``si`` on the deposit grid, window by window: its :class:`_LevelledStats`
    (with ``halo``, deposit cells) and (``keep_map``) its map."""
    from . import _levelling as _lv

    kernel = _lv.levelling_kernel(dt, gx, gy, lev.halo_lengths)
    hy, hx = (kernel.shape[0] - 1) // 2, (kernel.shape[1] - 1) // 2
    core_rows = max(2 * hy, int(lev.window_cells) // (cols + 2 * hx) - 2 * hy, 1)
    stats = _LevelledStats(landed_mean, *interior)
    stats.halo = (hx, hy)
    full = np.zeros((rows, cols), np.float64) if keep_map else None
    for r0 in range(0, rows, core_rows):
        r1 = min(rows, r0 + core_rows)
        e0, e1 = max(0, r0 - hy), min(rows, r1 + hy)
        film_w = landed_rows(si, e0, e1)
        lv = _lv.level_window(film_w, kernel, slice(r0 - e0, r1 - e0))
        del film_w
        if full is not None:
            full[r0:r1] = lv
        stats.add(lv, r0)
    return stats, full


def deposit_print(prints, design: np.ndarray, *, options: DepositOptions | None = None, dead_nozzles: tuple[int, ...] = (),
                  jitter_um: float = 0.0, seed: int = 0, keep_map: bool = False) -> Deposit:
    """The film of one or more prints of one design (e.g. the passes of a layer), as one set.

    Parameters
    ----------
    prints : RotaryPrint or sequence of RotaryPrint
        Prints on the same placement and head.
    design : (H, W) uint8
        The design (binary or grey; see :func:`~rotoprint.rotary.simulate.design_mask`).
    options, keep_map
        As in :func:`deposit_film` (``options.level`` levels the film).
    dead_nozzles, jitter_um, seed
        As in :func:`~rotoprint.rotary.simulate.place_drops`.

    Returns
    -------
    Deposit
    """
    from .simulate import design_mask, place_drops

    prs = [prints] if not isinstance(prints, (list, tuple)) else list(prints)
    if not prs:
        raise ConfigError("deposit_print needs at least one print")
    pl, head = prs[0].placement, prs[0].head
    for p in prs[1:]:
        if p.placement != pl or p.head.nozzles != head.nozzles:
            raise ConfigError("the prints of one film must share the placement and the head")
    parts = [ink_drops(place_drops(p, jitter_um=jitter_um, dead_nozzles=dead_nozzles, seed=seed + q), head) for q, p in enumerate(prs)]
    mask = design_mask(np.asarray(design), head.grey_levels)
    return deposit_film(mask, pl, head, [InkDrops.concat(parts)], options=options, keep_map=keep_map)
