"""Even track pitch on a rotary platform: tilt choice and interlaced passes.

A tilted dual-row head does not interleave evenly on a rotating platform: the exact track
radii ``|P_k|`` of the two rows drift against each other along the head, so the gaps between
neighbouring tracks range from almost 0 to almost two row pitches (``docs/rotary.md``).

- :func:`tilt_scan` measures, per tilt, the gaps between the live tracks inside the band where
  both rows print: the mean gap (the radial pitch the tilt offers) and the largest; a tilt is
  *even* when ``largest / mean <= even_ratio`` (default :data:`EVEN_RATIO`). :func:`best_tilt`
  names the even tilt with the finest mean pitch.
- :func:`plan_passes` prints a layer in ``N`` passes, each with every swathe's pivot moved
  radially by an offset ``delta_q`` (pass 0: 0). The offsets are found by coordinate descent
  over 128 offsets spanning one row period (``rows * pitch``: the tracks of one row repeat
  after about that), 3 rounds from the even split ``q * pitch / N`` and one finer round about
  each offset. A candidate is judged on the union of all passes' live tracks over the design's
  radial range: first its largest gap (to :data:`_GAP_QUANTUM_UM`), then the radial film
  profile the tracks' footprints sum to (:func:`_pass_profile`): the mean squared shortfall
  below :data:`PROFILE_TARGET` of its local mean (over +-0.25 mm, so that the ``1/r`` of one
  clock per swathe, which no offset changes, does not decide). Dead nozzles are left out of
  the union, so the optimum places live tracks of other passes over their tracks; the plan
  reports how far each dead track is from the nearest live one. The drop spacing along a track
  is then chosen with the footprint ``D``: drops at radial spacing ``a`` (the largest gap) and
  spacing ``b`` along the track leave no point farther than ``sqrt(a^2 + b^2) / 2`` from a
  drop, so ``b = sqrt((c D)^2 - a^2)`` with ``c =`` :data:`COVER_SHARE` keeps every point
  within ``c D / 2`` of a drop centre, where a spherical cap still holds ``1 - c^2`` of its
  peak height; ``b`` is never coarser than the head's native ``25.4 / dpi_y`` and never finer
  than :data:`MAX_CLOCK_FACTOR` times native (the cost floor of a pass's firing images).
- Angular interlace (``phases``): each pass also gets a phase, a fraction of the along-track firing step
  (:func:`interlace_phases`: 0, 1/2, 1/4, 3/4 in the passes' radial order), so that the drops
  of radially neighbouring passes fall between each other along the track instead of in phase.
  A pass's firing angles shifted by ``delta`` are the same firing data as a head whose mount
  angle is larger by ``delta``, so a pass is printed (exactly) with ``mount_angle_deg +
  delta`` (:func:`phase_angles`; the sidecar records it, the machine program's index offset
  takes it out again).
- Edges and seams (``edge_overlap``): :func:`pass_prints` plans the swathes with an overlap of one row period
  (:func:`pass_overlap_mm`, the offsets' span): each swathe's full-density band reaches that far
  inside its owned band, and a pass prints with the nozzles whose moved track lies in the band
  (:func:`~rotoprint.rotary.swathes.pass_enabled`). Every pass then prints the design's inner
  edge and both sides of every seam, each radius with one swathe per pass (no doubled volume).
- Dead nozzles (``spread_dead``, on by default): :func:`pass_prints` plans the swathes with an overlap of
  :data:`DEAD_SPREAD_PERIODS` row periods and :func:`plan_passes` may then shift the passes by whole row
  pitches, so that a dead nozzle's missing tracks (one per pass) lie apart instead of side by side; kept
  only where the largest gap stays within :data:`DEAD_GAP_TOLERANCE` (at tilt 0; a tilted head's
  interleave changes with whole shifts). Then (``dead_cover``, on by default, with ``equalise``) each
  dead track's drops go to the nearest live tracks of every pass (:func:`~rotoprint.rotary.deadcover.cover_dead_tracks`;
  ``dead_reserve`` does it for a plain print too, by a common share below 1).
- Even lines (``even_lines``, opt-in, in :func:`pass_prints` at a tilt whose rows do not interleave
  evenly): the swathes overlap by :data:`EVEN_OVERLAP_PERIODS` row periods, both swathes print each seam
  (:data:`EVEN_SEAM_PERIODS`), and whole tracks are left out where the union crowds
  (:func:`~rotoprint.rotary.equalise.even_line_shares`), so that every line one design pixel wide gets
  about the same ink (the levelled film is thinnest in such lines).

Equalised by default (``equalise``; ``equalise=False``: the plain print, every track keeps every drop);
phases and edge overlap are opt-in (:class:`PassOptions`). Measured on the test design (``docs/rotary.md``):
the interior closes at every tilt; levelled per coat the equalised print's thinnest point is at least
half the mean at every tilt, also with 5 dead nozzles (the plain print's at tilts 0 and 45 only).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..devices.models import InkjetHead
from ..errors import ConfigError, GeometryError
from ..ranges import PASSES, show_value
from .edgecomp import EdgeRestore, edge_zone, transform_restored
from .head import nozzle_layout
from .options import RotarySetup
from .swathes import SwathePlan, pass_enabled
# the equalisation lives in its own module; its names stay importable from here
from . import _interlace_kernels as _ik
from .equalise import (EQUALISE_CLOCK_FACTOR, EQUALISE_FLOOR, EQUALISE_ITERATIONS, EQUALISE_MIN_SHARE,  # noqa: F401
                       EQUALISE_TARGET_PERCENTILE, GREY_FLOOR, ReachFloor, even_line_shares, thin_print, track_fractions)

__all__ = ["EVEN_RATIO", "COVER_SHARE", "MAX_PASSES", "MAX_CLOCK_FACTOR", "DEAD_SPREAD_PERIODS", "DEAD_GAP_TOLERANCE", "EVEN_OVERLAP_PERIODS", "EVEN_SEAM_PERIODS", "PassOptions", "density_shares", "TiltRow", "tilt_scan", "best_tilt", "PassPlan", "union_radii", "plan_passes", "interlace_phases", "phase_angles", "pass_overlap_mm", "pass_prints", "pass_files", "parse_passes", "read_passes"]

#: A tilt interleaves evenly when its largest track gap is at most this times the mean gap.
EVEN_RATIO = 1.25
#: Drop lattice kept within this share of the footprint (see the module docstring).
COVER_SHARE = 0.85
#: Most passes the planner tries when it chooses the number itself.
MAX_PASSES = 4
#: A pass's clock is at most this times the head's native ``dpi_y`` (the cost floor: a pass's
#: firing images cost at most about twice one layer at the native clock).
MAX_CLOCK_FACTOR = 2.0
#: The radial film profile is scored against this share of its mean (see :func:`plan_passes`).
PROFILE_TARGET = 0.8
#: Offsets tried per pass and round of the coordinate descent (over one row period).
_CANDIDATES = 128
#: Starts of the coordinate descent (two even splits, the rest seeded random).
_STARTS = 4
_ROUNDS = 3
#: Radial step of the film profile, mm.
_PROFILE_STEP_MM = 0.002
#: Half-width of the local mean the profile is scored against, mm.
_LOCAL_MEAN_MM = 0.25
#: Largest gaps within this of each other count as equal (then the profile decides), um.
_GAP_QUANTUM_UM = 0.25
#: With dead nozzles the passes' offsets may span this many row periods (and the swathes are
#: planned with that overlap, :func:`pass_overlap_mm`): whole-pitch shifts between the passes
#: then put the passes' missing tracks (one per dead nozzle and pass, at ``r_k + delta_q``)
#: several pitches apart, each a single missing track among live ones, instead of side by side
#: within one row period (measured at tilt 0: there the 4 passes paired up, 2 x 2 coinciding,
#: and the 4 missing tracks of a dead nozzle lay within 106 um, a ring the equalisation could
#: not fill).
DEAD_SPREAD_PERIODS = 4
#: With spread dead tracks, largest gaps within this share of the smallest found count as equal
#: (then the film profile decides; see :func:`plan_passes`).
DEAD_GAP_TOLERANCE = 0.05
#: With ``PassOptions(even_lines=True)`` the swathes overlap by this many row periods, and every
#: swathe but the first also prints the last of them below its band (the seam, printed by both
#: swathes; the tracks in excess left out): measured at tilt 20 a seam without it held lines of
#: 0.38 of the mean line volume, with it none below 0.8.
EVEN_OVERLAP_PERIODS = 2
EVEN_SEAM_PERIODS = 1


@dataclass(frozen=True)
class TiltRow:
    """Track gaps of one tilt inside the band where every row prints (mm)."""

    tilt_deg: float
    tracks: int
    mean_pitch_mm: float
    largest_gap_mm: float
    smallest_gap_mm: float
    evenness: float
    even: bool

    def to_json(self) -> dict:
        return dict(self.__dict__)


def tilt_scan(head: InkjetHead, tilts_deg: Sequence[float], *, pivot_radius_mm: float, even_ratio: float = EVEN_RATIO) -> list[TiltRow]:
    """Mean and largest gap between neighbouring live tracks per tilt, and whether it is even.

    Parameters
    ----------
    head : InkjetHead
        Its ``dead_nozzles`` are left out.
    tilts_deg : sequence of float
    pivot_radius_mm : float
    even_ratio : float
        Largest gap over mean gap at or below which the tilt counts as even (> 1).

    Returns
    -------
    list of TiltRow

    Raises
    ------
    ConfigError
        ``even_ratio`` is not a number > 1.
    GeometryError
        A tilt is at or beyond the head's maximum, or a nozzle would cross the axis.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> rows = tilt_scan(load_device("omnidot760").head, [0.0, 20.0], pivot_radius_mm=60.0)
    >>> [r.even for r in rows], round(rows[1].largest_gap_mm * 1000)
    ([True, False], 137)
    """
    from .head import head_figures

    if not (math.isfinite(even_ratio) and even_ratio > 1):
        raise ConfigError(f"even ratio must be a number > 1, got {even_ratio!r}")
    out = []
    for t in tilts_deg:
        f = head_figures(head, tilt_deg=float(t), pivot_radius_mm=pivot_radius_mm)
        lo, hi = f.overlap_band_mm
        n = f.tracks_in_band
        mean = (hi - lo) / (n - 1) if n > 1 else float("nan")
        ev = f.largest_track_gap_mm / mean if n > 1 else float("nan")
        out.append(TiltRow(float(t), n, mean, f.largest_track_gap_mm, f.smallest_track_gap_mm, ev, bool(n > 1 and ev <= even_ratio)))
    return out


def best_tilt(rows: Sequence[TiltRow]) -> TiltRow | None:
    """The even tilt with the finest mean pitch (None when no tilt is even)."""
    even = [r for r in rows if r.even]
    return min(even, key=lambda r: (r.mean_pitch_mm, r.largest_gap_mm)) if even else None


def pass_overlap_mm(head: InkjetHead, *, dead_spread: bool = False) -> float:
    """The swathe overlap interlaced passes are planned with: the span of their offsets (one
    row period, ``rows * pitch``; :data:`DEAD_SPREAD_PERIODS` of them with ``dead_spread``), so
    every pass covers the design's edges and the seams."""
    return float(head.rows * head.pitch_mm) * (DEAD_SPREAD_PERIODS if dead_spread else 1)


def _pass_radii(head: InkjetHead, plan: SwathePlan, live: np.ndarray) -> list[np.ndarray]:
    """Per swathe: the platform positions (mm, ``(M, 2)``) of the live nozzles that can print in
    it at offset 0: the enabled ones, or with a swathe overlap every usable one (a pass keeps
    those whose moved track lies in the band, :func:`_in_band`)."""
    out = []
    for j, sw in enumerate(plan.swathes):
        lay = nozzle_layout(head, plan.mount(j))
        can = sw.usable if plan.overlap_mm > 0 and sw.usable is not None else sw.enabled
        out.append(lay.xy_mm[can & live])
    return out


def _in_band(plan: SwathePlan, j: int, r: np.ndarray) -> np.ndarray:
    """Which moved tracks ``r`` print in swathe ``j`` (all, without a swathe overlap)."""
    if plan.overlap_mm <= 0:
        return np.ones(r.shape, bool)
    lo, hi = plan.swathes[j].band_mm
    return (r >= lo - 1e-9) & (r < hi)


def union_radii(head: InkjetHead, plan: SwathePlan, offsets_mm: Sequence[float], *, dead_nozzles: Sequence[int] | None = None) -> np.ndarray:
    """Sorted radii (mm) of every live enabled track of every swathe and pass, ``(M,) float64``.

    A pass with offset ``delta`` moves every swathe's pivot by ``delta`` along the radial line
    of the mount (the nozzle positions shift by ``delta * e``); with a swathe overlap a pass
    prints the tracks of :func:`~rotoprint.rotary.swathes.pass_enabled`.
    """
    live = np.ones(head.nozzles, bool)
    dead = head.dead_nozzles if dead_nozzles is None else tuple(dead_nozzles)
    live[list(dead)] = False
    psi = math.radians(plan.mount_angle_deg)
    e = np.array([math.cos(psi), math.sin(psi)])
    parts = []
    for j, xy in enumerate(_pass_radii(head, plan, live)):
        for d in offsets_mm:
            p = xy + float(d) * e
            r = np.hypot(p[:, 0], p[:, 1])
            parts.append(r[_in_band(plan, j, r)])
    return np.sort(np.concatenate(parts)) if parts else np.zeros(0)


@dataclass(frozen=True)
class PassPlan:
    """Interlaced passes of one layer (lengths in mm).

    Attributes
    ----------
    offsets_mm : tuple of float
        Radial pivot offset of each pass (pass 0: 0).
    largest_gap_mm, mean_gap_mm : float
        Of the union of all passes' live tracks over the design's radial range.
    single_pass_largest_gap_mm : float
        The same for pass 0 alone (what printing without interlace leaves).
    dead_track_cover_mm : tuple of float
        Per dead nozzle (and pass), the distance from its track to the nearest live track of
        the union, the largest over swathes and passes.
    along_track_mm : float
        Chosen drop spacing along a track at the reference radius (``b``).
    dpi_y : float
        The clock: ``25.4 / along_track_mm``.
    footprint_um : float
    profile_min_to_mean : float
        Thinnest over mean of the radial film profile of the union the offsets were chosen by
        (no along-track ripple, no shares), over the design's radial range less half a footprint.
    phases : tuple of float
        Angular phase of each pass, a fraction of the along-track firing step (``[0, 1)``, pass
        0: 0): radial neighbours get phases half (then a quarter) of a step apart, so that their
        drops fall between each other along the track (:func:`interlace_phases`; realised per
        swathe by :func:`phase_angles`). Empty: no angular interlace.
    swathe_overlap_mm : float
        The swathe plan's overlap (:func:`~rotoprint.rotary.swathes.plan_swathes`): 0, or the
        offsets' span, so that every pass prints the design's edges and every seam.
    """

    offsets_mm: tuple[float, ...]
    largest_gap_mm: float
    mean_gap_mm: float
    single_pass_largest_gap_mm: float
    dead_nozzles: tuple[int, ...]
    dead_track_cover_mm: tuple[float, ...]
    along_track_mm: float
    dpi_y: float
    footprint_um: float
    profile_min_to_mean: float = float("nan")
    phases: tuple[float, ...] = ()
    swathe_overlap_mm: float = 0.0

    @property
    def passes(self) -> int:
        return len(self.offsets_mm)

    def to_json(self) -> dict:
        d = {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}
        d["passes"] = self.passes
        return d


def plan_passes(
    head: InkjetHead,
    plan: SwathePlan,
    *,
    footprint_um: float,
    passes: int | None = None,
    max_passes: int = MAX_PASSES,
    dead_nozzles: Sequence[int] | None = None,
    cover_share: float = COVER_SHARE,
    phases: bool = False,
) -> PassPlan:
    """Choose the number of passes (unless given), their radial offsets and the clock.

    Parameters
    ----------
    head : InkjetHead
        Nozzles and native clock; its ``dead_nozzles`` unless ``dead_nozzles`` is given.
    plan : SwathePlan
        The swathes of pass 0 (:func:`~rotoprint.rotary.plan_swathes`); its radial range is
        the range the union is judged over. With dead nozzles and an ``overlap_mm`` wider than
        one row period (:func:`pass_overlap_mm` ``(head, dead_spread=True)``) the offsets may
        span that overlap: whole row-pitch shifts between the passes are tried so that a dead
        nozzle's missing tracks lie apart (kept when the largest gap stays within
        :data:`DEAD_GAP_TOLERANCE` of the best plan's).
    footprint_um : float
        Footprint diameter of a drop (:mod:`rotoprint.rotary.deposit`).
    passes : int, optional
        Number of passes, 1..64; default the fewest (up to ``max_passes``) whose largest gap
        allows a square drop lattice within ``cover_share`` of the footprint
        (``largest gap <= cover_share * D / sqrt(2)``).
    max_passes : int
    dead_nozzles : sequence of int, optional
    cover_share : float
        ``c`` of the module docstring, in (0, 1].
    phases : bool
        Give the passes angular phases (:attr:`PassPlan.phases`, :func:`interlace_phases`); off
        by default, since the caller must print them (:func:`pass_prints` does, with
        :func:`phase_angles`).

    Returns
    -------
    PassPlan

    Raises
    ------
    ConfigError
        Passes outside 1..64, a footprint or cover share out of range.
    GeometryError
        The largest gap of the best plan is not narrower than the footprint (no clock closes it).

    Examples
    --------
    >>> from rotoprint import load_device
    >>> from rotoprint.rotary import plan_swathes
    >>> head = load_device("omnidot760").head
    >>> sp = plan_swathes(head, tilt_deg=20.0, inner_radius_mm=60.0, outer_radius_mm=80.0)
    >>> pp = plan_passes(head, sp, footprint_um=49.6)
    >>> pp.passes <= 4, pp.largest_gap_mm < pp.single_pass_largest_gap_mm / 2
    (True, True)
    """
    if passes is not None and int(passes) not in PASSES:
        raise ConfigError(f"passes must be {PASSES.lo}..{PASSES.hi}, got {passes!r}")
    if int(max_passes) not in PASSES:
        raise ConfigError(f"max passes must be {PASSES.lo}..{PASSES.hi}, got {max_passes!r}")
    if not (math.isfinite(footprint_um) and footprint_um > 0):
        raise ConfigError(f"footprint must be > 0 um, got {footprint_um!r}")
    if not (math.isfinite(cover_share) and 0 < cover_share <= 1):
        raise ConfigError(f"cover share must be in (0, 1], got {cover_share!r}")
    dead = tuple(sorted(set(head.dead_nozzles if dead_nozzles is None else dead_nozzles)))
    bad = [k for k in dead if not 0 <= k < head.nozzles]
    if bad:
        raise ConfigError(f"dead nozzle indices must be in 0..{head.nozzles - 1}, got {bad}")
    lo, hi = plan.inner_radius_mm, plan.outer_radius_mm
    live = np.ones(head.nozzles, bool)
    live[list(dead)] = False
    psi = math.radians(plan.mount_angle_deg)
    e = np.array([math.cos(psi), math.sin(psi)])
    xys = _pass_radii(head, plan, live)

    def radii(d: float | np.ndarray) -> np.ndarray:
        d = np.atleast_1d(np.asarray(d, np.float64))
        rows = []
        for j, xy in enumerate(xys):
            px = xy[None, :, 0] + d[:, None] * e[0]
            py = xy[None, :, 1] + d[:, None] * e[1]
            r = np.hypot(px, py)
            rows.append(np.where(_in_band(plan, j, r), r, np.nan))  # NaN: not printed in this pass
        return np.concatenate(rows, axis=1)  # (C, M)

    base = radii(0.0)
    g1 = _ik.max_gap(np.zeros(0), base, lo, hi)
    # the same tracks flat for the candidates' kernel: positions and the band each prints in
    all_xy = np.concatenate(xys) if xys else np.zeros((0, 2))
    all_x, all_y = np.ascontiguousarray(all_xy[:, 0]), np.ascontiguousarray(all_xy[:, 1])
    bands = [(-np.inf, np.inf) if plan.overlap_mm <= 0 else (sw.band_mm[0] - 1e-9, sw.band_mm[1]) for sw in plan.swathes]
    band_lo = np.concatenate([np.full(len(xy), bands[j][0]) for j, xy in enumerate(xys)]) if xys else np.zeros(0)
    band_hi = np.concatenate([np.full(len(xy), bands[j][1]) for j, xy in enumerate(xys)]) if xys else np.zeros(0)

    tracks, kept = (all_x, all_y, band_lo, band_hi, float(e[0]), float(e[1])), {}

    def candidate_gaps(rest: np.ndarray, cand: np.ndarray, key=None) -> np.ndarray:
        """``_ik.max_gap(rest, radii(cand), lo, hi)`` in one kernel (a set named by ``key``: its radii kept)."""
        return _ik.candidate_gaps(rest, tracks, cand, lo, hi, kept=kept, key=key)
    d_mm = footprint_um * 1e-3
    a_mm = 0.5 * d_mm
    period = head.rows * head.pitch_mm  # the tracks of one row repeat after about this
    # the offsets' range: one row period, or with dead nozzles and a swathe overlap that allows
    # it (pass_overlap_mm(head, dead_spread=True)) several, to spread the missing tracks apart
    span = max(period, float(plan.overlap_mm)) if dead and plan.overlap_mm > period + 1e-12 else period
    grid0 = lo + a_mm
    n_grid = max(2, int(math.floor((hi - a_mm - grid0) / _PROFILE_STEP_MM)) + 1)
    refs = [sw.last_track_mm for sw in plan.swathes]
    cache: dict[float, np.ndarray] = {}

    def profile(o: float) -> np.ndarray:
        key = round(float(o), 9)
        if key not in cache:
            cache[key] = _pass_profile(xys, refs, e, float(o), grid0, n_grid, a_mm, plan=plan)
        return cache[key]

    win = max(1, int(round(_LOCAL_MEAN_MM / _PROFILE_STEP_MM)))

    def ripple(t: np.ndarray) -> np.ndarray:
        """Mean squared deviation of the profile from its local mean, rows ``(C, G)``: passes
        paired over each other ripple at twice the pitch everywhere (below the shortfall
        target of :func:`score`, yet their drops leave pinholes along the track)."""
        c = np.cumsum(np.pad(t, ((0, 0), (1, 0))), axis=1)
        i = np.arange(t.shape[1])
        lo_i, hi_i = np.maximum(0, i - win), np.minimum(t.shape[1], i + win + 1)
        local = (c[:, hi_i] - c[:, lo_i]) / (hi_i - lo_i)
        return np.mean((t / np.maximum(local, 1e-300) - 1.0) ** 2, axis=1)

    def score(t: np.ndarray, fixed: np.ndarray | None = None) -> np.ndarray:
        """Shortfall of the profile below PROFILE_TARGET x its local mean (over _LOCAL_MEAN_MM:
        the 1/r trend of one clock per swathe is not the offsets' to change), rows ``(C, G)``
        (plus ``fixed``, ``(G,)``, when given); the terms by a kernel, their mean by numpy."""
        terms = np.empty(t.shape)
        _ik.shortfall_terms_jit(np.zeros(t.shape[1]) if fixed is None else fixed, np.ascontiguousarray(t), win, PROFILE_TARGET, terms)
        return np.mean(terms, axis=1)

    inside0 = np.sort(base[0][(base[0] >= lo) & (base[0] <= hi)])
    pitch = float((inside0[-1] - inside0[0]) / (inside0.size - 1)) if inside0.size > 1 else head.pitch_mm

    def optimise(n: int) -> list[float]:
        """The best of coordinate descents from a few starts (it finds local optima)."""
        if n <= 1:
            return [0.0]
        rng = np.random.default_rng(n)
        starts = [[q * pitch / n for q in range(n)], [q * period / n for q in range(n)]]
        starts += [[0.0] + sorted(rng.uniform(0.0, period, n - 1).tolist()) for _ in range(_STARTS - 2)]
        if dead:
            # dead tracks are missing in every pass at r_k + offset: whole-pitch shifts between
            # the passes spread them apart, so coordinate descent also starts from a few of those
            whole = max(1, int(round(period / pitch)))
            for perm in ([0, 1, 2, 3], [0, 2, 1, 3], [0, 3, 1, 2], [0, 2, 3, 1]):
                starts.append([(q * pitch / n + (perm[q % 4] % whole) * pitch) % period for q in range(n)])
        best, best_key = None, None
        for st0 in starts:
            offs = descend(list(st0))
            t = sum((profile(o) for o in offs), np.zeros(n_grid))
            key = (round(largest_gap(offs) * 1e3 / _GAP_QUANTUM_UM), float(score(t[None, :])[0]))
            if best_key is None or key < best_key:
                best, best_key = offs, key
        return best

    def descend(offs: list[float], base: Sequence[float] | None = None) -> list[float]:
        """Coordinate descent of pass q's offset over one row period (from ``base[q]``, default 0)."""
        n = len(offs)
        coarse = np.linspace(0.0, period, _CANDIDATES, endpoint=False)
        step = period / _CANDIDATES
        b0 = [0.0] * n if base is None else [float(b) for b in base]
        for rnd in range(_ROUNDS + 1 if n > 1 else 0):
            for q in range(1, n):
                # rounds over the whole row period, then one finer round about each offset
                cand = b0[q] + (coarse if rnd < _ROUNDS else np.mod(offs[q] - b0[q] + np.linspace(-step, step, 33), period))
                rest = _ik.inside_sorted(np.concatenate([radii(offs[p])[0] for p in range(n) if p != q]), lo, hi)
                gmax = candidate_gaps(rest, cand, key=b0[q] if rnd < _ROUNDS else None)  # the coarse set: b0[q] + coarse
                # the largest gap first (to _GAP_QUANTUM_UM); among equal ones the profile (measured
                # on the test design: the profile first gives larger gaps and no thinner film)
                g_q = np.round(gmax * 1e3 / _GAP_QUANTUM_UM)
                tie = np.flatnonzero(g_q == g_q.min())
                fixed = sum((profile(offs[p]) for p in range(n) if p != q), np.zeros(n_grid))
                pen = score(np.stack([profile(c) for c in cand[tie]]), fixed)
                key = [tie[int(np.argmin(pen))]]
                offs[q] = float(cand[key[0]])
        return offs

    def largest_gap(offs: list[float]) -> float:
        return float(_ik.max_gap(np.zeros(0), np.concatenate([radii(o)[0] for o in offs])[None, :], lo, hi)[0])

    def row_pitch() -> float:
        """Median radial spacing of neighbouring tracks of one row (swathe 0, offset 0), mm."""
        from .head import nozzle_offsets

        row = nozzle_offsets(head)[2]
        r = np.hypot(*nozzle_layout(head, plan.mount(0)).xy_mm.T)
        d = [np.diff(np.sort(r[row == k])) for k in range(head.rows)]
        return float(np.median(np.concatenate(d)))

    def spread_dead(offs: list[float]) -> list[float]:
        """With dead nozzles and offsets allowed over ``span`` (several row periods): the
        fractions the passes would take without dead nozzles, each pass shifted by a whole
        number of a row's pitches ``m_q`` (every combination within ``span``; the same for the
        even split of the track pitch), so that a dead nozzle's
        missing tracks (one per pass) lie apart; judged with ``offs`` (planned within one row
        period) by the largest gap, gaps within :data:`DEAD_GAP_TOLERANCE` of the smallest
        counting as equal, then by the distance between the passes' offsets (the missing tracks
        of one dead nozzle: the widest within 10 %), then by the film profile's ripple
        (:func:`ripple`)."""
        n = len(offs)
        # the whole shift: one nozzle of a row (its tracks are evenly spaced, the rows' not)
        unit = row_pitch()
        free = plan_passes(head, plan, footprint_um=footprint_um, passes=n, dead_nozzles=(), cover_share=cover_share)
        combos = [list(offs)]
        for base in (free.offsets_mm, [q * pitch / n for q in range(n)]):
            frac = [float(o) % unit for o in base]
            shifts = [[frac[q] + m * unit for m in range(int((span - frac[q]) // unit) + 1)] for q in range(1, n)]
            combos += [[0.0, *c] for c in itertools.product(*shifts)]
        # a tilted head's tracks do not all move by the pivot's shift (those off the mount's
        # radial line move less), so whole shifts change the interleave: descend again within
        # one row period about the widest whole shifts, from the free plan's fractions
        m = max(1, int(span / unit) // n)
        at = [q * m * unit for q in range(n)]
        if at[-1] + period <= span + 1e-9:
            frac = [float(o) % period for o in free.offsets_mm]
            combos.append(descend([w + f for w, f in zip(at, frac)], base=at))
        gaps = np.array([round(largest_gap(c) * 1e3 / _GAP_QUANTUM_UM) for c in combos], np.float64)
        ok = np.flatnonzero(gaps <= gaps.min() * (1.0 + DEAD_GAP_TOLERANCE))
        # the passes' missing tracks of one dead nozzle lie |delta_q - delta_q'| apart: as far as
        # the span allows (within 10 % of the widest), so each is one missing track among live
        # ones whose shares can make it up
        sep = np.array([min(abs(a - b) for a, b in itertools.combinations(combos[i], 2)) for i in ok])
        ok = ok[sep >= 0.9 * sep.max()]
        pen = ripple(np.stack([sum((profile(o) for o in combos[i]), np.zeros(n_grid)) for i in ok]))
        return combos[int(ok[int(np.argmin(pen))])]

    if passes is not None:
        offs = optimise(int(passes))
        gmax = largest_gap(offs)
    else:
        for n in range(1, int(max_passes) + 1):
            offs = optimise(n)
            gmax = largest_gap(offs)
            if gmax <= cover_share * d_mm / math.sqrt(2):
                break
    if span > period and len(offs) > 1:
        offs = spread_dead(offs)
        gmax = largest_gap(offs)
    t_union = sum((profile(o) for o in offs), np.zeros(n_grid))
    profile_ratio = float(t_union.min() / t_union.mean()) if t_union.mean() > 0 else 0.0
    union = np.concatenate([radii(o)[0] for o in offs])
    union = np.sort(union[np.isfinite(union)])
    ui = union[(union >= lo) & (union <= hi)]
    mean_gap = float((ui[-1] - ui[0]) / (ui.size - 1)) if ui.size > 1 else float("nan")
    reach = cover_share * d_mm
    if gmax >= 2.0 * a_mm:
        raise GeometryError(
            f"{len(offs)} pass(es) leave a largest track gap of {gmax * 1000:.1f} um, not less than "
            f"the {footprint_um:.1f} um footprint: more passes, a larger footprint or another tilt"
        )
    # along the track: close the lattice within the cover share where the gap allows, never
    # coarser than native nor finer than MAX_CLOCK_FACTOR x native (the cost floor)
    b_native = 25.4 / head.dpi_y
    b_fit = math.sqrt(reach * reach - gmax * gmax) if gmax < reach else 0.0
    b = min(b_native, max(b_fit, b_native / MAX_CLOCK_FACTOR))
    cover = []
    if dead:
        dl = np.zeros(head.nozzles, bool)
        dl[list(dead)] = True
        for j, sw in enumerate(plan.swathes):
            can = sw.usable if plan.overlap_mm > 0 and sw.usable is not None else sw.enabled
            xy = nozzle_layout(head, plan.mount(j)).xy_mm[can & dl]
            for o in offs:
                p = xy + o * e
                rd = np.hypot(p[:, 0], p[:, 1])
                rd = rd[(rd >= lo) & (rd <= hi) & _in_band(plan, j, rd)]
                if rd.size:
                    pos = np.clip(np.searchsorted(union, rd), 1, union.size - 1)
                    cover.append(float(np.max(np.minimum(np.abs(union[pos] - rd), np.abs(union[pos - 1] - rd)))))
    return PassPlan(
        offsets_mm=tuple(float(o) for o in offs),
        largest_gap_mm=float(gmax),
        mean_gap_mm=mean_gap,
        single_pass_largest_gap_mm=float(g1[0]),
        dead_nozzles=dead,
        dead_track_cover_mm=tuple(cover),
        along_track_mm=float(b),
        dpi_y=25.4 / b,
        footprint_um=float(footprint_um),
        profile_min_to_mean=profile_ratio,
        phases=interlace_phases(offs) if phases else (),
        swathe_overlap_mm=float(plan.overlap_mm),
    )


def interlace_phases(offsets_mm: Sequence[float]) -> tuple[float, ...]:
    """Angular phase of each pass (a fraction of the firing step) from its radial offset.

    Passes in order of their offset within the row period interleave radially, so neighbours
    in that order are radial neighbours: they get the bit-reversed fractions 0, 1/2, 1/4, 3/4,
    1/8, ... (neighbours half a step apart, next neighbours a quarter), pass 0 keeping 0.

    Examples
    --------
    >>> interlace_phases([0.0, 0.03, 0.01, 0.02])
    (0.0, 0.75, 0.5, 0.25)
    """
    n = len(offsets_mm)
    if n == 0:
        return ()
    if n & (n - 1) == 0:  # a power of two: bit-reversed
        bits = max(1, n.bit_length() - 1)
        rev = [int(format(i, f"0{bits}b")[::-1], 2) / (1 << bits) for i in range(1 << bits)]
    else:  # evenly spread
        rev = [i / n for i in range(n)]
    rank = np.argsort(np.argsort(np.asarray(offsets_mm, np.float64), kind="stable"), kind="stable")
    ph = [rev[int(rank[q])] for q in range(n)]
    base = ph[0]
    return tuple(float((p - base) % 1.0) for p in ph)


#: Whole firing steps of swathe 0 a pass's angular shift may add to its phase (so that the
#: other swathes, whose steps differ, get spread phases too).
_PHASE_STEPS = 48


def phase_angles(plan: SwathePlan, phases: Sequence[float], *, dpi_y: float, ref_radius_mm: float | None = None
                 ) -> tuple[tuple[float, ...], np.ndarray]:
    """The mount-angle shift (degrees) that gives each pass its phase, and the phases it gives.

    A pass whose firing angles are shifted by ``delta`` is the same firing data as a head whose
    mount angle is larger by ``delta`` (exact): pass ``q`` prints with
    ``mount_angle_deg + angles[q]``. One angle serves every swathe, whose firing steps
    ``dphi_j`` differ (one clock per swathe), so ``delta_q = (phases[q] + m_q) dphi_0`` with the
    whole steps ``m_q`` in ``0 .. _PHASE_STEPS - 1`` chosen so that on every swathe the passes'
    phases ``delta_q / dphi_j`` stay spread: the largest over swathes of
    ``|sum_q exp(2 pi i p_qj)|^2 / n^2`` (the in-phase along-track ripple of all passes) plus the
    mean ``(1 + cos 2 pi (p_q - p_q'))/2`` of passes neighbouring in phase order on swathe 0.

    Returns
    -------
    angles_deg : tuple of float
        Per pass, pass 0: 0.
    achieved : (passes, swathes) float64
        The phase (fraction of the firing step, ``[0, 1)``) of each pass on each swathe.
    """
    from .exact import swathe_clock

    n = len(phases)
    dphi = np.array([swathe_clock(plan, j, dpi_y=dpi_y, ref_radius_mm=ref_radius_mm)[0] for j in range(len(plan.swathes))])
    ph = np.asarray(phases, np.float64)
    if n <= 1:
        return tuple(0.0 for _ in range(n)), np.zeros((n, dphi.size))
    order = np.argsort(ph)
    nxt = np.roll(order, -1)
    m = np.arange(_PHASE_STEPS, dtype=np.float64)
    # every combination of whole steps for passes 1..n-1 (pass 0 stays at 0): at most 48^3
    grids = np.meshgrid(*([m] * (n - 1)), indexing="ij") if n - 1 <= 3 else None
    if grids is not None:
        ms = np.stack([np.zeros(grids[0].size)] + [g.ravel() for g in grids], axis=1)  # (C, n)
    else:
        rng = np.random.default_rng(0)
        ms = np.concatenate([np.zeros((20000, 1)), rng.integers(0, _PHASE_STEPS, (20000, n - 1)).astype(np.float64)], axis=1)
    delta = (ph[None, :] + ms) * dphi[0]  # (C, n) rad
    p = np.mod(delta[:, :, None] / dphi[None, None, :], 1.0)  # (C, n, J)
    ripple = np.abs(np.exp(2j * np.pi * p).sum(axis=1)) ** 2 / n ** 2  # (C, J)
    pair = 0.5 * (1.0 + np.cos(2 * np.pi * (p[:, order, :] - p[:, nxt, :]))).mean(axis=1)  # (C, J)
    best = int(np.argmin((ripple + pair).max(axis=1)))
    angles = tuple(float(math.degrees(d)) for d in delta[best])
    return angles, p[best]


def _pass_profile(xys: list[np.ndarray], refs: list[float], e: np.ndarray, offset_mm: float, grid0: float,
                  n_grid: int, a_mm: float, *, plan: SwathePlan | None = None) -> np.ndarray:
    """Radial film profile of one pass, ``(n_grid,) float64`` on ``grid0 + i * step``: every live
    track ``k`` adds ``(r_ref / r_k) * (1 - x^2 / a^2)^(3/2)`` (its drops per mm along the track,
    relative, times a cap's footprint averaged along the track), ``x`` the radial distance."""
    step = _PROFILE_STEP_MM
    t = np.zeros(n_grid)
    n_s = 2 * (int(math.ceil(a_mm / step)) + 1) + 1  # the grid points near each track
    for j, (xy, r_ref) in enumerate(zip(xys, refs)):
        if not xy.size:
            continue
        r = np.hypot(xy[:, 0] + offset_mm * e[0], xy[:, 1] + offset_mm * e[1])
        if plan is not None:
            r = np.ascontiguousarray(r[_in_band(plan, j, r)])
        idx, base = np.empty((n_s, r.size), np.int64), np.empty((n_s, r.size))
        _ik.profile_base_jit(r, grid0, step, a_mm, idx, base)
        _ik.profile_add_jit(t, idx, (r_ref / r) * base ** 1.5)  # t += bincount of each row in turn
    return t


PASSES_FORMAT = "rotoprint-rotary-passes"


def parse_passes(text: str | int) -> int | None:
    """``"auto"`` -> None (the planner's choice), else an integer 1..64."""
    if isinstance(text, str) and text.strip().lower() == "auto":
        return None
    try:
        n = int(text)
    except (TypeError, ValueError):
        raise ConfigError(f"passes must be a whole number {PASSES.lo}..{PASSES.hi} or 'auto', got {text!r}") from None
    if n not in PASSES:
        raise ConfigError(f"passes must be {PASSES.lo}..{PASSES.hi} or 'auto', got {show_value(n)}")
    return n


def pass_files(out_png, n: int) -> list:
    """``PRINT.png`` -> ``[PRINT-p1.png, ..., PRINT-pN.png]``."""
    from pathlib import Path

    p = Path(out_png)
    return [p.with_name(f"{p.stem}-p{q + 1}{p.suffix}") for q in range(n)]


@dataclass(frozen=True)
class PassOptions:
    """How a design is printed in interlaced passes (:func:`pass_prints`).

    Parameters
    ----------
    setup : RotarySetup
        Tilt, clock (``dpi_y``: default the plan's), reference radius, mount angle, direction,
        swathe limit, kernel; its ``pivot_offset_mm`` must be 0 (the plan sets each pass's).
    passes : int or 'auto'
        Number of passes 1..64, or the planner's choice (at most :data:`MAX_PASSES`).
    footprint_um : float, optional
        Footprint diameter of a full drop (default the head's, :mod:`rotoprint.rotary.deposit`).
    equalise : bool
        The same volume per area at every radius: by drop size on a grey-level head
        (:func:`~rotoprint.rotary.halftone.halftone_print`), else by keeping a share of each
        track's drops (:func:`track_fractions`, :func:`thin_print`). On by default; False: the plain print.
    balance : bool
        Without ``equalise``: every track keeps the share of its drops of
        :func:`density_shares` (the same drops per mm on every track, the clock unchanged).
        Off by default: measured on the test design it flattens the 1 mm bins (0.2 % at tilt
        0) but opens holes (0.1 % of the interior) where thinned tracks meet.
    phases : bool
        Angular interlace: each pass prints at its angular phase (:attr:`PassPlan.phases`), as a head with its
        mount angle shifted by :func:`phase_angles`. Off by default: measured on the test design
        (``docs/rotary.md``) it moves the thinnest point by +0.01 / +0.08 / -0.29 / -0.01 of the mean at tilts 0
        / 20 / 45 / 70 (with ``edge_overlap``), no steady gain.
    edge_overlap : bool
        Swathes planned with an overlap of :func:`pass_overlap_mm`, so that every pass prints the design's edges
        and the seams (less of the boundary band uncovered: 1.80 -> 0.35 % at tilt 0). Off by default (see
        ``phases``).
    even_lines : bool
        Without ``equalise`` and ``balance``: whole tracks are left out where the union of the
        passes crowds (:func:`~rotoprint.rotary.equalise.even_line_shares`, the clock and the
        kept tracks' drops unchanged), so that every line one design pixel wide gets about
        the same ink, and the swathes are planned with an overlap of :data:`EVEN_OVERLAP_PERIODS`
        row periods and a seam of :data:`EVEN_SEAM_PERIODS` (both swathes print the seam's
        tracks; the excess is left out). Only at a tilt whose rows do not interleave evenly
        (:func:`tilt_scan`; at tilt 0 the print is as without). Off by default, only with ``equalise=False``:
        it lifts tilt 20 but lowers tilt 45 (levelled per coat, ``docs/rotary.md``, "Even lines").
    spread_dead : bool
        With dead nozzles (and more than one pass): the passes' offsets may span :data:`DEAD_SPREAD_PERIODS` row
        periods, with the swathes planned with that overlap (:func:`pass_overlap_mm` ``(dead_spread=True)``, as
        ``edge_overlap`` does), so that a dead nozzle's missing tracks (one per pass) lie apart. On by default;
        False plans the offsets within one row period (as before).
    dead_cover : bool
        With dead nozzles (more than one pass, a binary head) and shares (``equalise``): the shares are
        equalised with the dead nozzles as live ones, then each dead track's drops go to the nearest live tracks
        of every pass (:func:`~rotoprint.rotary.deadcover.cover_dead_tracks`, realised by :func:`thin_print`).
        On by default; the manifest's ``dead_cover`` reports it.
    dead_reserve : bool
        With ``dead_cover`` and no shares (a plain print has no room): live tracks with room keep one common
        share below 1 so the dead tracks' drops fit (:func:`~rotoprint.rotary.deadcover.thin_by_landing`).
        Off by default: on the full test design it opened a pinhole at tilt 0 and lowered the levelled
        thinnest at tilt 20 (0.393 -> 0.360), though it takes out the dead rings (``docs/rotary.md``).
    edge_restore : EdgeRestore, optional
        With ``equalise`` (binary head): thinned-out drops near the design's edges restored (:mod:`~rotoprint.rotary.edgecomp`,
        :func:`~rotoprint.rotary.edgecomp.transform_restored`); the manifest's ``edge_restore`` records it. On by default; None: off.
    """

    setup: RotarySetup
    passes: str | int = "auto"
    footprint_um: float | None = None
    equalise: bool = True
    balance: bool = False
    phases: bool = False
    edge_overlap: bool = False
    spread_dead: bool = True
    dead_cover: bool = True
    dead_reserve: bool = False
    even_lines: bool = False
    edge_restore: EdgeRestore | None = EdgeRestore()

    def __post_init__(self) -> None:
        parse_passes(self.passes)
        if self.setup.pivot_offset_mm:
            raise ConfigError("the passes' pivot offsets come from the plan: setup.pivot_offset_mm must be 0")
        if self.footprint_um is not None and not (math.isfinite(self.footprint_um) and self.footprint_um > 0):
            raise ConfigError(f"footprint must be > 0 um, got {self.footprint_um!r}")


def density_shares(head: InkjetHead, plan: SwathePlan, offsets_mm: Sequence[float], setup: RotarySetup | None = None) -> list[list[np.ndarray]]:
    """Share of its drops each track keeps so that every track lays the same drops per mm.

    One angular clock ``dphi_j`` per swathe lays ``1 / (r_k dphi_j)`` drops per mm on track
    ``k``: the inner tracks of a swathe get up to ``r_out / r_in`` times the volume per area of
    its outermost track (1.9 x over 60-114 mm). Track ``k`` keeps ``f_k = min_m (r_m dphi_m) /
    (r_k dphi_k)`` of its drops (the sparsest track keeps all), so its kept drops are at most
    about the sparsest track's spacing apart and no hole opens along it (:func:`thin_print`
    keeps them evenly spaced).

    Returns
    -------
    list (pass) of list (swathe) of (N,) float64
        Shares in (0, 1] for enabled live nozzles, 0 elsewhere.
    """
    from .exact import swathe_clock

    st = setup or RotarySetup(tilt_deg=plan.tilt_deg)
    dpi_y = head.dpi_y if st.dpi_y is None else float(st.dpi_y)
    live = np.ones(head.nozzles, bool)
    live[list(head.dead_nozzles)] = False
    psi = math.radians(plan.mount_angle_deg)
    e = np.array([math.cos(psi), math.sin(psi)])
    spacing = []  # drop spacing along the track, mm
    for o in offsets_mm:
        row = []
        for j, sw in enumerate(plan.swathes):
            dphi, _ = swathe_clock(plan, j, dpi_y=dpi_y, ref_radius_mm=st.ref_radius_mm)
            xy = nozzle_layout(head, plan.mount(j)).xy_mm + float(o) * e
            r = np.hypot(xy[:, 0], xy[:, 1])
            s_ = r * dphi
            s_[~(pass_enabled(plan, j, r) & live)] = np.nan
            row.append(s_)
        spacing.append(row)
    widest = max(float(np.nanmax(s_)) for row in spacing for s_ in row if np.isfinite(s_).any())
    return [[np.where(np.isfinite(s_), np.minimum(1.0, np.nan_to_num(s_) / widest), 0.0) for s_ in row] for row in spacing]


def _even_seam(head: InkjetHead, options: PassOptions, inner_radius_mm: float) -> tuple[bool, float]:
    """Whether :func:`pass_prints` evens the lines (:attr:`PassOptions.even_lines`; not at a tilt
    whose rows interleave evenly, :func:`tilt_scan`: there the union is even already), and its seam, mm."""
    even = bool(options.even_lines and not options.equalise and not options.balance)
    if even:
        even = not tilt_scan(head, [float(options.setup.tilt_deg)], pivot_radius_mm=float(inner_radius_mm))[0].even
    return even, (EVEN_SEAM_PERIODS * head.rows * head.pitch_mm if even else 0.0)


def pass_prints(design: np.ndarray, device, placement, options: PassOptions) -> tuple[str, list, dict]:
    """Plan interlaced passes for ``design`` and make each pass's exact print (written by
    :func:`rotoprint.pipeline.prints.transform_passes`).

    Parameters
    ----------
    design : (H, W) uint8
    device : InkjetDevice, InkjetHead or str
        The printer (a preset name, a device, or a bare head: then no device name is recorded).
    placement : Placement
    options : PassOptions

    The clock is the plan's unless ``options.setup.dpi_y`` is given. With ``equalise`` and a
    grey-level head, every site keeps its drop and its size follows the track's share; with a
    binary head every track keeps the share of its drops of :func:`track_fractions` (the same
    volume per area everywhere; with floors by the lattice reach, so a crowded track may keep
    less than half or none) and the clock is made :data:`EQUALISE_CLOCK_FACTOR` times finer, so
    that no track's kept drops are farther apart than planned or than the reach allows. Without ``equalise``,
    ``balance`` keeps the shares of :func:`density_shares` at the plan's clock.

    Returns
    -------
    device_name : str
        ``""`` for a bare head.
    prints : list of RotaryPrint
        One per pass; every swathe records ``pass``, ``passes``, ``pass_offset_mm`` (its
        ``pivot_radius_mm`` is already moved by the offset), ``pass_phase`` and
        ``pass_phase_angle_deg``.
    manifest : dict
        The passes manifest (format :data:`PASSES_FORMAT`) without its ``files``.
    """
    import dataclasses

    from ..devices import InkjetDevice, load_device
    from .deposit import DepositOptions
    from .exact import ThinShares, transform_exact
    from .swathes import plan_swathes

    if isinstance(device, InkjetHead):
        head, device_name = device, ""
    else:
        dev = load_device(device) if isinstance(device, str) else device
        if not isinstance(dev, InkjetDevice):
            raise ConfigError(f"device {getattr(dev, 'name', dev)!r} is not an inkjet device")
        head, device_name = dev.head, dev.name
    st = options.setup
    n = parse_passes(options.passes)
    r_in, r_out = placement.radial_range_mm()
    spread = bool(options.spread_dead and head.dead_nozzles and n != 1)
    even, seam = _even_seam(head, options, r_in)
    overlap = pass_overlap_mm(head, dead_spread=spread) if (options.edge_overlap or spread) else 0.0
    overlap = max(overlap, EVEN_OVERLAP_PERIODS * head.rows * head.pitch_mm) if even else overlap
    sp = plan_swathes(head, tilt_deg=st.tilt_deg, inner_radius_mm=r_in, outer_radius_mm=r_out,
                      mount_angle_deg=st.mount_angle_deg, direction=st.direction, max_swathes=st.max_swathes,
                      overlap_mm=overlap).with_seam(seam)
    d_um = DepositOptions(footprint_um=options.footprint_um).full_footprint_um(head)
    pp = plan_passes(head, sp, footprint_um=d_um, passes=n, phases=options.phases)
    if spread and max(pp.offsets_mm) <= head.rows * head.pitch_mm:
        # missing tracks not spread (a tilted head: whole shifts change the interleave): plan without
        overlap = pass_overlap_mm(head) if options.edge_overlap else 0.0
        overlap = max(overlap, EVEN_OVERLAP_PERIODS * head.rows * head.pitch_mm) if even else overlap
        sp = plan_swathes(head, tilt_deg=st.tilt_deg, inner_radius_mm=r_in, outer_radius_mm=r_out,
                          mount_angle_deg=st.mount_angle_deg, direction=st.direction, max_swathes=st.max_swathes,
                          overlap_mm=overlap).with_seam(seam)
        pp = plan_passes(head, sp, footprint_um=d_um, passes=n, phases=options.phases)
    clock = pp.dpi_y if st.dpi_y is None else float(st.dpi_y)
    fracs = None
    kept = None
    equalise = options.equalise
    grey = equalise and head.grey_levels > 1
    if grey:  # by drop size: every site keeps its drop; the plan is made for the smallest drop used
        g_floor = max(1.0 / head.grey_levels, GREY_FLOOR)
        fracs = track_fractions(head, sp, pp.offsets_mm, dataclasses.replace(st, dpi_y=clock), footprint_um=d_um,
                                floor=g_floor)
        f_min = min(float(f[f > 0].min()) for per in fracs for f in per if (f > 0).any())
        pp = plan_passes(head, sp, footprint_um=d_um * f_min ** (1.0 / 3.0), passes=n, phases=options.phases)
        clock = pp.dpi_y if st.dpi_y is None else float(st.dpi_y)
        fracs = track_fractions(head, sp, pp.offsets_mm, dataclasses.replace(st, dpi_y=clock), footprint_um=d_um,
                                floor=g_floor)
    elif equalise:
        # clock EQUALISE_CLOCK_FACTOR x the plan's; kept drops at most ceil(1 / f) firings apart, so a share >= EQUALISE_FLOOR keeps
        # every track within the planned spacing (at the plan's clock alone, thinned clusters open holes), less only within the reach.
        cover_all = bool(options.dead_cover and head.dead_nozzles and pp.passes > 1)  # shares with all live, room kept for the cover below
        fracs = track_fractions(head, sp, pp.offsets_mm, dataclasses.replace(st, dpi_y=clock), footprint_um=d_um,
                                reach=ReachFloor(COVER_SHARE * d_um, EQUALISE_CLOCK_FACTOR),
                                dead_nozzles=() if cover_all else None)
        clock = clock * EQUALISE_CLOCK_FACTOR
    elif options.balance:
        fracs = density_shares(head, sp, pp.offsets_mm, dataclasses.replace(st, dpi_y=clock))
    elif even:
        fracs, kept = even_line_shares(head, sp, pp, dataclasses.replace(st, dpi_y=clock),
                                       line_mm=max(placement.pitch_x_mm, placement.pitch_y_mm, 1e-3 * d_um))
    dead_cover, thin_landing = None, False
    if options.dead_cover and head.dead_nozzles and pp.passes > 1 and not grey and (fracs is not None or options.dead_reserve):
        from .deadcover import cover_dead_tracks

        thin_landing = fracs is None
        fracs, dead_cover = cover_dead_tracks(head, sp, pp.offsets_mm, dataclasses.replace(st, dpi_y=clock), shares=fracs,
                                              footprint_um=d_um)
    if pp.phases:
        angles, achieved = phase_angles(sp, pp.phases, dpi_y=clock, ref_radius_mm=st.ref_radius_mm)
    else:
        angles, achieved = tuple(0.0 for _ in pp.offsets_mm), np.zeros((pp.passes, len(sp.swathes)))
    prints, restore = [], options.edge_restore.resolved(placement) if options.edge_restore and equalise and not grey else None
    zone = edge_zone(design, head, placement, restore) if restore is not None else None  # once for all the passes
    for q, off in enumerate(pp.offsets_mm):
        pst = dataclasses.replace(st, dpi_y=clock, pivot_offset_mm=off, swathe_overlap_mm=overlap, swathe_seam_mm=seam,
                                  mount_angle_deg=float(st.mount_angle_deg) + angles[q])
        thin = fracs is not None and not grey and not (dead_cover is not None and thin_landing)  # thin_print's, while sampling
        pr = transform_exact(design, head, placement, pst, thin=ThinShares(fracs[q], q) if thin else None) if restore is None \
            else transform_restored(design, head, placement, pst, fracs[q], options=restore, pass_index=q, zone=zone)  # + the zone's drops
        if grey:
            from .halftone import halftone_print

            pr = halftone_print(pr, fracs[q])
        sw = tuple(dataclasses.replace(s, extra={**s.extra, "pass": q, "passes": pp.passes, "pass_offset_mm": off,
                                                 "pass_phase": float(achieved[q, j]), "pass_phase_angle_deg": angles[q]})
                   for j, s in enumerate(pr.swathes))
        pr = dataclasses.replace(pr, swathes=sw)
        prints.append(pr)
    if dead_cover is not None and thin_landing:
        from .deadcover import thin_by_landing

        prints = thin_by_landing(prints, fracs)
    manifest = {
        "format": PASSES_FORMAT,
        "version": 1,
        "device": device_name,
        "tilt_deg": float(st.tilt_deg),
        "dpi_y": clock,
        "equalise": ("grey levels" if grey else "thinning") if equalise else None,
        "balance": bool(options.balance and not equalise),
        "even_lines": {"seam_mm": seam, "swathe_overlap_mm": overlap, "tracks": kept[1], "tracks_left_out": kept[1] - kept[0]}
        if even and kept is not None else None,
        "pass_plan": pp.to_json(),
        "phase_angles_deg": list(angles),
        "phases_by_swathe": [[float(x) for x in row] for row in achieved],
    }
    manifest.update({k: v for k, v in (("dead_cover", dead_cover), ("edge_restore", restore and dataclasses.asdict(restore))) if v is not None})
    return device_name, prints, manifest


def read_passes(path) -> list:
    """The sidecar paths of a passes manifest written by :func:`rotoprint.pipeline.prints.transform_passes` (or of
    ``slice --rotary --passes``), in pass order, resolved beside the manifest."""
    from pathlib import Path

    from ..errors import InputFileError
    from ..io.inputs import read_json_file
    p = Path(path)
    data = read_json_file(p, what="passes manifest")
    if not isinstance(data, dict) or data.get("format") != PASSES_FORMAT:
        raise InputFileError(f"not a passes manifest (format {PASSES_FORMAT!r} expected)", path=p)
    files = data.get("files")
    if not isinstance(files, list) or not files or not all(isinstance(f, str) and "/" not in f and "\\" not in f for f in files):
        raise InputFileError("passes manifest field files must be a non-empty list of file names", path=p)
    if len(set(files)) < len(files):  # one print deposited twice would pass for two passes
        raise InputFileError(f"passes manifest field files lists {next(f for f in files if files.count(f) > 1)} twice", path=p)
    return [p.parent / f for f in files]
