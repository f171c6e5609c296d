"""The exact transform (``rotary-geometry.md`` section 5): every drop samples where it lands.

For every swathe, nozzle ``k`` and firing ``i`` the landing point in the platform frame is
converted into design coordinates and the design is sampled there (nearest for binary
designs, bilinear coverage for grey ones). Any tilt, row count, parallax and dead nozzle is
handled by the one formula. The maps depend only on the head, the setting, the placement and
the design size; :func:`exact_maps` builds them once and caches them, so every layer of a job
costs one gather.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np

from .._resources import check_raster_fits
from ..devices.models import InkjetHead
from ..errors import ConfigError, ImageError
from . import _exact_kernels as _k
from ._thin_kernels import thin_levels_jit, thin_phases
from .head import Mount, NozzleLayout, nozzle_layout
from .options import RotarySetup, options_from
from .placement import Placement
from .printdata import RotaryPrint, SwatheImage, clock_dphi, design_levels
from .swathes import SwathePlan, pass_enabled, shared_plan

__all__ = ["SwatheMap", "TrackWindows", "ExactMaps", "ThinShares", "exact_maps", "transform_exact", "firing_range", "KERNEL_NAMES"]

log = logging.getLogger(__name__)

KERNEL_NAMES = tuple(_k.KERNELS)


def firing_range(phi_rad: np.ndarray, angle_lo_rad: float, angle_hi_rad: float, dphi_rad: float, direction: int) -> tuple[int, int]:
    """Smallest and largest firing index at which some nozzle can land in ``[lo, hi]`` (radians).

    Nozzle ``k`` lands at ``phi_k - direction * i * dphi``.

    Parameters
    ----------
    phi_rad : (N,) float64
        Angle ``phi_k`` of every nozzle at firing 0; must not be empty.
    angle_lo_rad, angle_hi_rad : float
        The angular window ``[lo, hi]``.
    dphi_rad : float
        Platform rotation per firing, > 0 (see :func:`~rotoprint.rotary.printdata.clock_dphi`).
    direction : int
        +1 (counter-clockwise); any other value is taken as -1.

    Returns
    -------
    (int, int)
        ``(i_min, i_max)``, inclusive; rounded outwards, with a 1e-9 tolerance.

    Examples
    --------
    >>> firing_range(np.array([0.0]), -0.01, 0.01, 0.001, 1)
    (-10, 10)
    """
    if direction == 1:
        a = (phi_rad - angle_hi_rad) / dphi_rad
        b = (phi_rad - angle_lo_rad) / dphi_rad
    else:
        a = (angle_lo_rad - phi_rad) / dphi_rad
        b = (angle_hi_rad - phi_rad) / dphi_rad
    return int(math.floor(float(a.min()) + 1e-9)), int(math.ceil(float(b.max()) - 1e-9))


@dataclass(frozen=True, eq=False)
class ThinShares:
    """Shares a print is thinned by while it is sampled (:func:`transform_exact` ``thin=``).

    The image is the one :func:`~rotoprint.rotary.equalise.thin_print` makes of the unthinned
    print with the same ``fractions`` and ``pass_index`` (tested identical), made in one sweep:
    the full image at the (doubled) clock of an equalised pass is never built.

    Parameters
    ----------
    fractions : sequence (swathe) of (N,) float64
        Share of its firings each track keeps, in [0, 1], by nozzle.
    pass_index : int
        Sets the phases (:func:`~rotoprint.rotary._thin_kernels.thin_phases`).
    """

    fractions: tuple
    pass_index: int = 0

    def __post_init__(self) -> None:
        fr = tuple(np.ascontiguousarray(f, np.float64) for f in self.fractions)
        if any(f.ndim != 1 for f in fr) or not all(np.isfinite(f).all() for f in fr):
            raise ConfigError("thinning shares must be one finite (N,) array per swathe")
        object.__setattr__(self, "fractions", fr)
        object.__setattr__(self, "pass_index", int(self.pass_index))

    def check(self, n_swathes: int, n_nozzles: int) -> None:
        """One-line :class:`ConfigError` unless there are ``n_swathes`` arrays of ``(n_nozzles,)``."""
        if len(self.fractions) != n_swathes or any(f.shape != (n_nozzles,) for f in self.fractions):
            raise ConfigError(f"thinning shares must give one ({n_nozzles},) array per swathe ({n_swathes}), "
                              f"got {len(self.fractions)} of shapes {[f.shape for f in self.fractions]}")


@dataclass(frozen=True, eq=False)
class TrackWindows:
    """Where the drops of a swathe land in the design, track by track (output-sensitive map).

    Window ``q``: nozzle ``nozzle[q]`` at print rows ``row[q] .. row[q] + count[q] - 1`` samples
    design pixels ``flat_index[start[q] : start[q] + count[q]]`` (flat ``row * width + col``;
    ``width * height`` = no drop, rare inside a window). Every other nozzle-firing of the print
    image is "no drop". A track has at most two windows (where its circle crosses the design).

    The windows' ends are exact (first and last drop in the design). ``flat_index`` is filled on
    first use: by the first :meth:`gather`, in the same pass as that gather (the first layer
    costs one pass, not two), or on first access.
    """

    nozzle: np.ndarray
    row: np.ndarray
    count: np.ndarray
    start: np.ndarray
    coefficients: tuple
    cos_row: np.ndarray
    sin_row: np.ndarray
    width: int
    height: int
    backend: str
    _index: np.ndarray = field(repr=False)
    _filled: list = field(default_factory=lambda: [False], repr=False)

    @property
    def n_drops(self) -> int:
        """Nozzle-firings that are looked up in the design (the per-layer work)."""
        return int(self.count.sum())

    @property
    def flat_index(self) -> np.ndarray:
        self._fill()
        return self._index

    def _args(self) -> tuple:
        return (self.coefficients, self.nozzle, self.row, self.count, self.start, self.cos_row, self.sin_row, self.width, self.height, self._index)

    def _fill(self, flat: np.ndarray | None = None, out: np.ndarray | None = None) -> bool:
        """Fill the index once; given ``flat`` and ``out``, gather in the same pass. True if it gathered."""
        # No lock (the maps stay picklable): two threads filling at once write the same values,
        # and the flag is set only after a complete fill.
        if self._filled[0]:
            return False
        if flat is None:
            _k.WINDOWS_FILL[self.backend](*self._args())
        else:
            _k.WINDOWS_FILL_GATHER[self.backend](*self._args(), flat, out)
        self._filled[0] = True
        return flat is not None

    def gather(self, flat: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``out[row + t, nozzle] = flat[flat_index[start + t]]`` for every window; ``out`` zeroed ``(F, N) uint8``."""
        if not self._fill(flat, out):
            _k.WINDOWS_GATHER[self.backend](flat, self.nozzle, self.row, self.count, self.start, self._index, out)
        return out

    def sample_thin(self, flat: np.ndarray, out: np.ndarray, fractions: np.ndarray, phases: np.ndarray, first_firing: int,
                    ink_blocks: np.ndarray | None = None, level: int | None = None) -> np.ndarray:
        """:meth:`gather`, then thinned (firing ``first_firing + row`` of track ``k`` kept by share
        ``fractions[k]`` and phase ``phases[k]``, each ``(N,) float64``), in one sweep that stores no
        index (the landing points of the kept drops only are computed; pieces of track that can
        land on no ink skipped and those that land on ink only given ``level``, by ``ink_blocks``:
        :func:`~rotoprint.rotary._exact_kernels.ink_blocks` of ``flat``, whose non-zero value is ``level``)."""
        return _k.WINDOWS_SAMPLE_THIN[self.backend](self.coefficients, self.nozzle, self.row, self.count, self.cos_row,
                                                    self.sin_row, self.width, self.height, flat, out, fractions, phases, first_firing,
                                                    ink_blocks, level)

    def dense(self, n_firings: int, n_nozzles: int, sentinel: int) -> np.ndarray:
        """The ``(F, N)`` index map, ``sentinel`` where no drop lands in the design."""
        idx = self.flat_index
        out = np.full((n_firings, n_nozzles), sentinel, idx.dtype)
        k, r = _k._window_drops(self.nozzle, self.row, self.count)
        out[r, k] = idx
        return out


@dataclass(frozen=True, eq=False)
class SwatheMap:
    """Sampling maps of one swathe.

    Attributes
    ----------
    windows : TrackWindows
        Per track, the print rows whose drops land in the design and the pixels they sample.
    n_firings : int
        Rows of the print image (firings ``first_firing .. first_firing + n_firings - 1``).
    index : (F, N) int32
        Dense form, built on first use (grey sampling, tests): flat index of the design pixel
        each drop lands in; ``width * height`` (one past the end) when it lands outside the
        design or the nozzle is disabled in this swathe.
    """

    mount: Mount
    layout: NozzleLayout
    enabled: np.ndarray
    dphi_rad: float
    ref_radius_mm: float
    first_firing: int
    band_mm: tuple[float, float]
    coefficients: tuple
    windows: TrackWindows
    n_firings: int
    sentinel: int

    @functools.cached_property
    def index(self) -> np.ndarray:
        return self.windows.dense(self.n_firings, self.layout.r_mm.shape[0], self.sentinel)

    def coords(self, placement: Placement) -> tuple[np.ndarray, np.ndarray]:
        """Continuous design coordinates ``(col, row)``, each ``(F, N) float32`` (for grey sampling)."""
        ii = np.arange(self.first_firing, self.first_firing + self.n_firings, dtype=np.float64) * self.dphi_rad
        col, row, _ = _k.coords_numba(*self.coefficients, np.ascontiguousarray(self.enabled), np.cos(ii), np.sin(ii),
                                      placement.width_px, placement.height_px)
        return col, row


@dataclass(frozen=True, eq=False)
class ExactMaps:
    """Maps for a head, a setting, a placement and a design size; apply with :meth:`apply`."""

    head: InkjetHead
    placement: Placement
    tilt_deg: float
    mount_angle_deg: float
    direction: int
    dpi_y: float
    plan: SwathePlan
    swathes: tuple[SwatheMap, ...]
    backend: str

    def apply(self, design: np.ndarray, *, kind: str | None = None, thin: ThinShares | None = None) -> RotaryPrint:
        """Sample ``design`` ``(H, W) uint8`` through the maps; returns a :class:`RotaryPrint`.

        ``thin``: the print thinned by these shares as it is sampled (:class:`ThinShares`).
        """
        design = _check_design(design, self.placement)
        if thin is not None:
            thin.check(len(self.swathes), self.head.nozzles)
        flat = None
        if kind in (None, "binary"):
            # one pass: the drop level of every design pixel (+ the 0 "no drop" sentinel the maps
            # point at), and whether the design is binary (the same answer as design_kind)
            level = design_levels(np.array([255], np.uint8), self.head.grey_levels, kind="binary")[0]
            flat, binary = _k.BINARY_LEVELS[self.backend](design, level)
            kind = kind or ("binary" if binary else "grey")
        if kind not in ("binary", "grey"):
            raise ConfigError(f"kind must be one of binary, grey; got {kind!r}")
        dead = np.array(self.head.dead_nozzles, dtype=np.int64)
        _, bilinear = _k.KERNELS[self.backend]
        ink = _k.ink_blocks(flat, self.placement.width_px, self.placement.height_px) \
            if thin is not None and kind == "binary" and self.backend == "jit" else None
        out = []
        for j, sm in enumerate(self.swathes):
            zeros = np.zeros((sm.n_firings, sm.layout.r_mm.shape[0]), np.uint8)
            if kind == "binary" and thin is not None:
                lev = sm.windows.sample_thin(flat, zeros, thin.fractions[j], thin_phases(zeros.shape[1], thin.pass_index), sm.first_firing,
                                             ink, level)
            elif kind == "binary":
                lev = sm.windows.gather(flat, zeros)
            else:
                col, row = sm.coords(self.placement)
                lev = design_levels(bilinear(design, col, row, sm.index), self.head.grey_levels, kind=kind)
                if thin is not None:
                    thin_levels_jit(lev, int(sm.first_firing), thin.fractions[j], thin_phases(lev.shape[1], thin.pass_index), zeros)
                    lev = zeros
            if dead.size:
                lev[:, dead] = 0
            out.append(
                SwatheImage(
                    index=j,
                    levels=lev,
                    pivot_radius_mm=sm.mount.pivot_radius_mm,
                    first_firing=sm.first_firing,
                    dphi_rad=sm.dphi_rad,
                    ref_radius_mm=sm.ref_radius_mm,
                    band_mm=sm.band_mm,
                    enabled_nozzles=int(sm.enabled.sum()),
                    enabled=sm.enabled,
                )
            )
        return RotaryPrint(
            method="exact",
            head=self.head,
            tilt_deg=self.tilt_deg,
            mount_angle_deg=self.mount_angle_deg,
            direction=self.direction,
            dpi_y=self.dpi_y,
            placement=self.placement,
            swathes=tuple(out),
            design_kind=kind,
        )


def _check_design(design: np.ndarray, placement: Placement) -> np.ndarray:
    a = np.asarray(design)
    if a.ndim != 2:
        raise ImageError(f"design must be a 2-D (H, W) greyscale array, got {a.ndim}-D with shape {a.shape}")
    if a.dtype != np.uint8:
        raise ImageError(f"design must be uint8 (8-bit greyscale), got {a.dtype}")
    if a.shape != (placement.height_px, placement.width_px):
        raise ImageError(f"design is {a.shape[1]} x {a.shape[0]} px but the placement is for {placement.width_px} x {placement.height_px} px")
    return np.ascontiguousarray(a)


def swathe_clock(plan: SwathePlan, j: int, *, dpi_y: float, ref_radius_mm: float | None) -> tuple[float, float]:
    """``(dphi_rad, ref_radius_mm)`` of swathe ``j``.

    Default reference radius: the swathe's outermost track, so that drops along every track
    are at most ``25.4 / dpi_y`` apart (inner tracks get more drops per mm; see s. 7).
    """
    r_ref = plan.swathes[j].last_track_mm if ref_radius_mm is None else float(ref_radius_mm)
    return clock_dphi(dpi_y, r_ref), r_ref


def exact_maps(head: InkjetHead, placement: Placement, setup: RotarySetup | None = None, **keywords) -> ExactMaps:
    """Build (or fetch from the cache) the sampling maps of the exact transform.

    Parameters
    ----------
    head : InkjetHead
    placement : Placement
        Where the design lies; its radial range decides the swathes (:func:`~rotoprint.rotary.swathes.plan_swathes`).
    setup : RotarySetup, optional
        Tilt, clock (``dpi_y``, ``ref_radius_mm``), mount angle, direction, swathe limit,
        kernel.
    **keywords
        Fields of :class:`~rotoprint.rotary.options.RotarySetup` by name (``tilt_deg=20.0``,
        ...), replacing those of ``setup``.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> head = load_device("omnidot760").head
    >>> m = exact_maps(head, Placement(40, 30, 0.0705, 0.0705, inner_radius_mm=60.0), tilt_deg=20.0)
    >>> len(m.swathes), m.swathes[0].index.shape[1]
    (1, 764)
    """
    st = options_from(RotarySetup, setup, keywords, what="exact_maps")
    if not (type(st.tilt_deg) is float and type(st.mount_angle_deg) is float and type(st.direction) is int
            and type(st.pivot_offset_mm) is float):
        st = replace(st, tilt_deg=float(st.tilt_deg), mount_angle_deg=float(st.mount_angle_deg), direction=int(st.direction),
                     pivot_offset_mm=float(st.pivot_offset_mm))
    return _exact_maps(head, placement, st)



@functools.lru_cache(maxsize=8)
def _exact_maps(head: InkjetHead, placement: Placement, setup: RotarySetup) -> ExactMaps:
    tilt_deg, dpi_y, ref_radius_mm = setup.tilt_deg, setup.dpi_y, setup.ref_radius_mm
    mount_angle_deg, direction, max_swathes, backend = setup.mount_angle_deg, setup.direction, setup.max_swathes, setup.backend
    pivot_offset_mm = setup.pivot_offset_mm
    dpi_y = float(head.dpi_y if dpi_y is None else dpi_y)
    r_in, r_out = placement.radial_range_mm()
    # the passes of a layer differ in pivot offset (and clock) only: their maps share one plan
    plan = shared_plan(head, tilt_deg=tilt_deg, inner_radius_mm=r_in, outer_radius_mm=r_out, mount_angle_deg=mount_angle_deg,
                       direction=direction, max_swathes=max_swathes, overlap_mm=setup.swathe_overlap_mm).with_seam(setup.swathe_seam_mm)
    a_lo, a_hi = placement.angular_range_rad()
    angle = math.radians(placement.angle_deg)
    width, height = placement.width_px, placement.height_px
    if max(width, height) >= 2**31:  # the kernels' landing indices truncate a pixel's column and row through int32
        raise ImageError(f"a design of {width} x {height} px: the exact transform takes at most {2**31 - 1} px a side")
    # the design's rectangle in its own frame (mm): x0 <= xl <= x1, |yl| <= yh
    x0, x1, yh = placement.inner_radius_mm, placement.inner_radius_mm + placement.width_mm, placement.height_mm / 2.0
    setup = []
    for j, sw in enumerate(plan.swathes):
        mount = plan.mount(j)
        if pivot_offset_mm:
            mount = dataclasses.replace(mount, pivot_radius_mm=mount.pivot_radius_mm + float(pivot_offset_mm))
        lay = nozzle_layout(head, mount)
        en = pass_enabled(plan, j, lay.r_mm)
        dphi, r_ref = swathe_clock(plan, j, dpi_y=dpi_y, ref_radius_mm=ref_radius_mm)
        i0, i1 = firing_range(lay.phi_rad[en], a_lo, a_hi, dphi, direction)
        setup.append((sw, en, mount, lay, dphi, r_ref, i0, i1))
    # at most the whole firing range of every swathe (dense index for grey designs: 12 bytes each)
    check_raster_fits(head.nozzles, sum(i1 - i0 + 1 for *_, i0, i1 in setup), 12, what="exact maps")
    maps = []
    for sw, en, mount, lay, dphi, r_ref, i0, i1 in setup:
        ii = np.arange(i0, i1 + 1, dtype=np.float64) * dphi
        A, B, C, D, E, F = _k.coefficients(
            lay.r_mm, lay.phi_rad, direction, angle,
            placement.inner_radius_mm, placement.pitch_x_mm, placement.pitch_y_mm, placement.height_px,
        )
        # only where each track crosses the design (analytic, conservative), trimmed to its first
        # and last drop in the design by the exact test; the index itself is filled on first use
        wk, wlo, whi = _k.track_windows(lay.r_mm, lay.phi_rad, en, direction, angle, x0, x1, yh, dphi, i0, i1)
        cos_i, sin_i = np.cos(ii), np.sin(ii)
        first, last = _k.WINDOW_BOUNDS[backend](A, B, C, D, E, F, wk, wlo, whi, cos_i, sin_i, width, height)
        has = last > first
        if has.any():
            b0 = int(first[has].min())
            b1 = int(last[has].max())
        else:  # this swathe sees nothing of the design: keep one empty firing
            b0, b1 = 0, 1
        count = (last - first)[has]
        start = np.zeros(count.shape[0], np.int64)
        if count.shape[0] > 1:
            np.cumsum(count[:-1], out=start[1:])
        windows = TrackWindows(
            nozzle=wk[has],
            row=first[has] - b0,
            count=count,
            start=start,
            coefficients=(A, B, C, D, E, F),
            cos_row=cos_i[b0:b1].copy(),
            sin_row=sin_i[b0:b1].copy(),
            width=width,
            height=height,
            backend=backend,
            _index=np.empty(int(count.sum()), _k.index_dtype(width, height)),
        )
        maps.append(
            SwatheMap(
                mount=mount,
                layout=lay,
                enabled=en,
                dphi_rad=dphi,
                ref_radius_mm=r_ref,
                first_firing=i0 + b0,
                band_mm=sw.band_mm,
                coefficients=(A, B, C, D, E, F),
                windows=windows,
                n_firings=b1 - b0,
                sentinel=width * height,
            )
        )
    log.debug("exact maps: %d swathe(s) for %s", len(maps), placement)
    return ExactMaps(
        head=head,
        placement=placement,
        tilt_deg=float(tilt_deg),
        mount_angle_deg=float(mount_angle_deg),
        direction=int(direction),
        dpi_y=dpi_y,
        plan=plan,
        swathes=tuple(maps),
        backend=backend,
    )

# the cache (8 maps, keyed by head, placement and setup) is emptied and inspected as before
def _cache_clear() -> None:
    _exact_maps.cache_clear()
    shared_plan.cache_clear()


exact_maps.cache_clear = _cache_clear  # type: ignore[attr-defined]
exact_maps.cache_info = _exact_maps.cache_info  # type: ignore[attr-defined]


def transform_exact(design: np.ndarray, head: InkjetHead, placement: Placement, setup: RotarySetup | None = None, *,
                    kind: str | None = None, thin: ThinShares | None = None, **keywords) -> RotaryPrint:
    """Make ``design`` print-ready for a (tilted) head over a rotating platform.

    Parameters
    ----------
    design : (H, W) uint8
        Non-zero = ink. Binary designs are sampled nearest, grey ones bilinear.
    head, placement, setup, **keywords : see :func:`exact_maps` (the maps are cached).
    kind : {"binary", "grey"}, optional
        Default: ``"binary"`` when the design holds one non-zero value.
    thin : ThinShares, optional
        Thin the print by these shares while sampling it: the same images as
        :func:`~rotoprint.rotary.equalise.thin_print` of the unthinned print (binary designs in
        one sweep, without the unthinned image).

    Returns
    -------
    RotaryPrint
        One ``(F_j, N) uint8`` level image per swathe with its first firing index and clock.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> head = load_device("omnidot760").head
    >>> design = np.full((30, 40), 255, np.uint8)
    >>> pr = transform_exact(design, head, Placement(40, 30, 0.0705, 0.0705, inner_radius_mm=60.0), tilt_deg=20.0)
    >>> pr.swathes[0].levels.dtype, pr.swathes[0].levels.shape[1], int(pr.swathes[0].levels.max())
    (dtype('uint8'), 764, 1)
    """
    design = _check_design(design, placement)
    maps = exact_maps(head, placement, options_from(RotarySetup, setup, keywords, what="transform_exact"))
    return maps.apply(design, kind=kind, thin=thin)
