"""Equalised interlaced passes: the share of its drops each track keeps (binary heads, by thinning)
or its drop size follows (grey levels), so that every radius gets the same volume per area.

Split from :mod:`rotoprint.rotary.interlace` (which re-exports these names): :func:`track_fractions`
equalises the union's radial film profile on a uniform grid (see its docstring and
``docs/rotary.md``, "Equalised 1 mm bins"); :func:`thin_print` realises the shares as an ordered
pattern on the firing index.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..devices.models import InkjetHead
from ..errors import ConfigError
from .head import nozzle_layout
from .options import RotarySetup
from .swathes import SwathePlan, pass_enabled

__all__ = ["EQUALISE_FLOOR", "EQUALISE_CLOCK_FACTOR", "EQUALISE_MIN_SHARE", "GREY_FLOOR", "EVEN_LINE_PERCENTILE", "ReachFloor",
           "track_fractions", "model_bin_deviation", "even_line_shares", "thin_print"]


@dataclass(frozen=True)
class ReachFloor:
    """Floors of :func:`track_fractions` set by the drop lattice's reach.

    Parameters
    ----------
    reach_um : float
        The reach ``c D`` (um): a track's kept drops, ``m`` firings apart at the printed clock,
        stay within ``sqrt((c D)^2 - g^2)`` beside its wider gap ``g``.
    clock_factor : int
        The printed clock over the setup's (:data:`EQUALISE_CLOCK_FACTOR` in
        :func:`~rotoprint.rotary.interlace.pass_prints`), 1..64.
    """

    reach_um: float
    clock_factor: int = 2

    def __post_init__(self) -> None:
        if not (isinstance(self.reach_um, (int, float)) and math.isfinite(self.reach_um) and self.reach_um > 0):
            raise ConfigError(f"lattice reach must be > 0 um, got {self.reach_um!r}")
        if not (isinstance(self.clock_factor, (int, np.integer)) and 1 <= int(self.clock_factor) <= 64):
            raise ConfigError(f"clock factor must be a whole number 1..64, got {self.clock_factor!r}")


#: Smallest share of its drops a track keeps under equalisation.
EQUALISE_FLOOR = 0.5
#: Smallest share of the full volume a grey-level site keeps under equalisation (its footprint,
#: ``cbrt`` of it, sets the passes and the clock; 0.3 allows a 3:1 radius span).
GREY_FLOOR = 0.3
#: Percentile of the unthinned radial profile's running mean that equalisation aims at (0: its lowest).
EQUALISE_TARGET_PERCENTILE = 0.0
#: The clock of an equalised binary print over the plan's (``ceil(1 / EQUALISE_FLOOR)``).
EQUALISE_CLOCK_FACTOR = 2
#: Smallest share any track keeps when :func:`track_fractions` sets floors by the lattice reach.
EQUALISE_MIN_SHARE = 0.25
#: Multiplicative updates of :func:`track_fractions`.
EQUALISE_ITERATIONS = 60
#: Whether :func:`track_fractions`' mm-scale step also raises sparse stretches: False, True, or
#: ``"auto"`` (the default): equalise without the raise, and where the model's 1 mm bins
#: (:func:`model_bin_deviation`, after the dead-track cover when it follows) deviate more than
#: :data:`EQUALISE_AUTO_THRESHOLD`, also with it, keeping the flatter (``docs/rotary.md``).
EQUALISE_RAISE: bool | str = "auto"
#: Model 1 mm bins' largest deviation from their mean above which ``"auto"`` tries the raise too.
EQUALISE_AUTO_THRESHOLD = 0.015


def track_fractions(head: InkjetHead, plan: SwathePlan, offsets_mm: Sequence[float], setup: RotarySetup | None = None, *,
                    footprint_um: float | None = None, dead_nozzles: Sequence[int] | None = None,
                    floor: float | None = None, reach: ReachFloor | None = None) -> list[list[np.ndarray]]:
    """Share of its drops each track keeps so that the film is as even across the radius as the tracks allow.

    Track ``k`` (of any swathe and pass) at radius ``r_k`` with clock ``dphi_k`` and kept share
    ``f_k`` lays ``f_k / (r_k dphi_k)`` drops per mm; averaged along the track, a drop of
    footprint radius ``a`` adds across the radius the profile ``(1 - x^2 / a^2)^(3/2)`` (a
    paraboloid cap integrated along the track). The profile ``T(x) = sum_k f_k / (r_k dphi_k)
    K(x - r_k)`` is taken on a uniform radial grid (:data:`_EQ_STEP_MM`), so that its mean over
    any stretch is the volume per area there (at the track radii alone it is not: where a tilted
    head's tracks crowd or pair up, their peaks stand for less area). Multiplicative updates
    ``f_k <- clip(f_k * T* / Tbar_k, floor_k, 1)`` (:data:`EQUALISE_ITERATIONS` times), ``Tbar_k``
    the profile averaged over track ``k``'s footprint, drive it towards ``T*``: the
    :data:`EQUALISE_TARGET_PERCENTILE` percentile (0: the lowest) of the unthinned profile's
    running mean over :data:`_EQ_WINDOW_MM`, over the band where every pass prints: sparse
    tracks keep every drop, crowded ones share theirs; then a few updates by the running mean
    itself lower the mm-scale level where it is still above ``T*`` (with :data:`EQUALISE_RAISE`,
    also raise it where it is below, a window in from the band's ends and where no track is left
    out within a window: a 30 px band's 1 mm bins 1.8 / 1.9 / 1.9 / 1.5 % at tilts 0 / 20 / 45 /
    70, off 1.3 / 2.7 / 1.5 / 3.7; ``"auto"``, the default: without the raise, and where the
    model's 1 mm bins, :func:`model_bin_deviation`, exceed :data:`EQUALISE_AUTO_THRESHOLD`, also
    with it, the flatter kept; never with dead tracks left out of the union (no cover follows);
    ``docs/rotary.md``).

    Floors: every track keeps at least ``floor`` (default :data:`EQUALISE_FLOOR`; e.g. ``1 /
    grey_levels`` for halftoning). With ``reach`` (:class:`ReachFloor`: the drop lattice's reach
    ``c D``, :data:`~rotoprint.rotary.interlace.COVER_SHARE`), a track may keep down to ``1 / m`` (never below
    :data:`EQUALISE_MIN_SHARE`) when ``m`` firings at the printed clock (``reach.clock_factor`` x
    the setup's) are no farther apart than ``sqrt((c D)^2 - g^2)``, ``g`` the wider gap beside it to
    the kept tracks; and where the mm-scale level is still above ``T*`` (a steeply tilted head's
    tracks crowd at one end of a swathe: at 70 deg twice the tracks per mm), whole tracks are left
    out (share 0), error-diffused by the excess, only where the gap they leave is no wider than
    the union's largest (up to :data:`_DROP_ROUNDS` rounds). Measured (``bench/film_bins.py``,
    a 30 px band of the test design, 60-145 mm): the planned drops per area of the 1 mm bins
    within 1.3 / 2.7 / 1.5 / 3.7 % of their mean at tilts 0 / 20 / 45 / 70; on the grid with one
    floor of 1/2: 1.2 / 2.8 / 10.7 / 37.6 %; at the track radii (before): 3.3 / 7.0 % at 0 / 20.

    Parameters
    ----------
    head : InkjetHead
        Its ``dead_nozzles`` unless ``dead_nozzles`` is given.
    plan : SwathePlan
    offsets_mm : sequence of float
        The passes' radial offsets (:attr:`PassPlan.offsets_mm`).
    setup : RotarySetup, optional
        Its clock (``dpi_y``, default the head's) and ``ref_radius_mm``; only the ratio of the
        swathes' clocks matters (the shares do not change with the clock).
    footprint_um, floor
        As above.
    dead_nozzles : sequence of int, optional
        Nozzles left out of the union (default the head's; ``()``: every nozzle as live, the
        dead-track cover then gives the dead ones' drops to live tracks,
        :func:`~rotoprint.rotary.deadcover.cover_dead_tracks`, which scales the shares where
        it finds no room: :attr:`~rotoprint.rotary.deadcover.DeadCoverOptions.scale_shares`;
        ``"auto"`` then judges each variant's model bins after that cover).
    reach : ReachFloor, optional
        ``reach_um`` and ``clock_factor`` of the floors above (None: one floor for every track,
        no track left out).

    Returns
    -------
    list (pass) of list (swathe) of (N,) float64
        Shares in [0, 1] for enabled live nozzles (0: a crowded track left out, only with
        ``reach``), 0 elsewhere.
    """
    from .deposit import DepositOptions

    st = setup or RotarySetup(tilt_deg=plan.tilt_deg)
    dpi_y = head.dpi_y if st.dpi_y is None else float(st.dpi_y)
    ref_radius_mm = st.ref_radius_mm

    lo_f = EQUALISE_FLOOR if floor is None else float(floor)
    if not 0 < lo_f <= 1:
        raise ConfigError(f"floor must be in (0, 1], got {floor!r}")

    live = np.ones(head.nozzles, bool)
    dead = head.dead_nozzles if dead_nozzles is None else tuple(dead_nozzles)
    live[list(dead)] = False
    a_mm = 0.5e-3 * (DepositOptions().full_footprint_um(head) if footprint_um is None else float(footprint_um))
    rs, ws, where = _printing_tracks(plan, head, offsets_mm, live, dpi_y, ref_radius_mm)
    r = np.concatenate(rs)
    w = np.concatenate(ws)
    order = np.argsort(r, kind="stable")
    r_s, w_s = r[order], w[order]
    reach_mm = None if reach is None else 1e-3 * float(reach.reach_um)

    mode = EQUALISE_RAISE
    if mode not in (False, True, "auto"):
        raise ConfigError(f"EQUALISE_RAISE must be False, True or 'auto', got {mode!r}")

    memo: dict = {}  # what the two variants share (the footprint matrix, the first settling)

    def shares(raise_sparse: bool) -> list[list[np.ndarray]]:
        f = _equalise_profile(r_s, w_s, a_mm, plan, offsets_mm, lo_f, EQUALISE_TARGET_PERCENTILE, reach_mm=reach_mm,
                              clock_factor=2 if reach is None else int(reach.clock_factor), raise_sparse=raise_sparse,
                              memo=memo)
        f_all = np.empty_like(f)
        f_all[order] = f
        out = [[np.zeros(head.nozzles) for _ in plan.swathes] for _ in offsets_mm]
        pos = 0
        for q, j, k in where:
            out[q][j][k] = f_all[pos:pos + k.size]
            pos += k.size
        return out

    if mode != "auto":
        return shares(bool(mode))
    cover = bool(head.dead_nozzles and not dead and len(offsets_mm) > 1)  # () with dead nozzles: the cover follows
    if dead:
        # dead tracks left out of the union (no cover): the raise fills their rings on the mm
        # scale but thins the film beside them (10 mm band, 3 dead, tilt 0: thinnest / mean 0.10
        # against 0.42 without), so auto keeps it off
        return shares(False)

    def deviation(fr: list[list[np.ndarray]]) -> float:
        if cover:
            from .deadcover import cover_dead_tracks

            fr, _ = cover_dead_tracks(head, plan, offsets_mm, st, shares=fr, footprint_um=2e3 * a_mm)
        return model_bin_deviation(head, plan, offsets_mm, fr, st, footprint_um=2e3 * a_mm,
                                   dead_nozzles=head.dead_nozzles if cover else dead)

    off = shares(False)
    d_off = deviation(off)
    if not d_off > EQUALISE_AUTO_THRESHOLD:
        return off
    on = shares(True)
    return on if deviation(on) < d_off else off


def _cap_cdf(x: np.ndarray) -> np.ndarray:
    """Share of a cap's radial profile ``(1 - x^2)^(3/2)`` (``x`` in footprint radii) below ``x``."""
    x = np.clip(x, -1.0, 1.0)
    s = np.sqrt(1.0 - x * x)
    return (x * s ** 3 / 4 + 3.0 / 8.0 * (x * s + np.arcsin(x))) / (3.0 * math.pi / 8.0) + 0.5


def model_bin_deviation(head: InkjetHead, plan: SwathePlan, offsets_mm: Sequence[float], shares, setup: RotarySetup | None = None, *,
                        footprint_um: float, dead_nozzles: Sequence[int] | None = None) -> float:
    """The planner's own 1 mm radial bins of shares: their largest deviation from their mean.

    Track ``k`` lays ``f_k / (r_k dphi_k)`` drops per mm of track (its share times the swathe's
    clock), spread across the radius by a footprint's profile ``(1 - x^2 / a^2)^(3/2)`` (``a``
    half of ``footprint_um``) and summed into 1 mm bins ``[b, b + 1)`` of radius; only bins
    wholly inside the band where every pass prints, a footprint in from its ends, count (their
    volume per mm of radius is the film's volume per area there, up to ``1 / r``, which the
    drops per mm already hold). No film, no drops: milliseconds.

    Parameters
    ----------
    head, plan, offsets_mm, setup
        As in :func:`track_fractions`.
    shares : list (pass) of list (swathe) of (N,) float64
        E.g. :func:`track_fractions`' (after the dead-track cover, if any).
    footprint_um : float
        Footprint diameter of a full drop, um (> 0).
    dead_nozzles : sequence of int, optional
        Nozzles that do not print (default the head's).

    Returns
    -------
    float
        ``max |bin / mean - 1|`` (0 with fewer than one whole bin).
    """
    if not (math.isfinite(footprint_um) and footprint_um > 0):
        raise ConfigError(f"footprint must be > 0 um, got {footprint_um!r}")
    if len(shares) != len(offsets_mm) or any(len(p) != len(plan.swathes) for p in shares):
        raise ConfigError("shares must give one array per pass and swathe")
    st = setup or RotarySetup(tilt_deg=plan.tilt_deg)
    dpi_y = head.dpi_y if st.dpi_y is None else float(st.dpi_y)
    live = np.ones(head.nozzles, bool)
    live[list(head.dead_nozzles if dead_nozzles is None else tuple(dead_nozzles))] = False
    rs, ws, where = _printing_tracks(plan, head, offsets_mm, live, dpi_y, st.ref_radius_mm)
    r = np.concatenate(rs)
    if r.size == 0:
        return 0.0
    v = np.concatenate([w * np.asarray(shares[q][j], np.float64)[k] for w, (q, j, k) in zip(ws, where)])
    a_mm = 0.5e-3 * float(footprint_um)
    lo = max(float(r.min()), plan.inner_radius_mm + max(0.0, max(offsets_mm))) + a_mm
    hi = min(float(r.max()), plan.outer_radius_mm + min(0.0, min(offsets_mm))) - a_mm
    edges = np.arange(math.ceil(lo), math.floor(hi) + 1, dtype=np.float64)
    if edges.size < 2:
        return 0.0
    x = (edges[None, :] - r[:, None]) / a_mm
    cdf = (x >= 1.0).astype(np.float64)  # _cap_cdf is exactly 0 / 1 at and beyond -1 / 1: computed only between
    near = np.abs(x) < 1.0
    cdf[near] = _cap_cdf(x[near])
    below = v @ cdf  # ink below each bin edge, (edges,)
    bins = np.diff(below)
    m = float(bins.mean())
    return float(np.max(np.abs(bins / m - 1.0))) if m > 0 else 0.0


#: Rounds of leaving whole tracks out (:func:`track_fractions` with ``reach``) and the
#: share of the target the mm-scale level may exceed before they start.
_DROP_ROUNDS = 6
_DROP_TOLERANCE = 0.005
#: Radial step of the profile :func:`track_fractions` equalises, mm.
_EQ_STEP_MM = 0.002
#: Width of the running mean whose smallest value (over the band every pass prints) is the
#: target of :func:`track_fractions`, mm: a mm-scale level, not a single track's peak.
_EQ_WINDOW_MM = 0.5


def _equalise_profile(r_s: np.ndarray, w_s: np.ndarray, a_mm: float, plan: SwathePlan, offsets_mm: Sequence[float],
                      lo_f: float, target_percentile: float, *, reach_mm: float | None = None,
                      clock_factor: int = 2, raise_sparse: bool = False, memo: dict | None = None) -> np.ndarray:
    """Shares ``(M,)`` of sorted tracks ``r_s`` (mm) with drops per mm ``w_s`` so that their radial
    profile on a uniform grid is as flat as the shares ``[lo_f, 1]`` allow (see :func:`track_fractions`).

    ``memo``: a dict shared by the calls for the two variants of one union (``raise_sparse``
    False and True, the same other arguments): the footprint matrix, the target and the first
    settling's footprint-scale updates (which the raise does not change) are made once.
    """
    from ._equalise_kernels import drop_round_jit, level_at_jit, settle_jit

    memo = {} if memo is None else memo
    if "band" not in memo:
        memo.update(_profile_setup(r_s, w_s, a_mm, plan, offsets_mm, target_percentile))
    band, start, k_sum, n_g = memo["band"], memo["start"], memo["k_sum"], memo["n_g"]
    target, lo_t, hi_t = memo["target"], memo["lo_t"], memo["hi_t"]
    a_i, b_i, printed, n_w, s_k = memo["a_i"], memo["b_i"], memo["printed"], memo["n_w"], memo["s_k"]
    t = np.empty(n_g + band.shape[1])
    c = np.empty(n_g + 1)
    lev = np.empty(r_s.size)
    f = np.ones(r_s.size)
    hi_f = np.ones(r_s.size)
    drop_tracks = reach_mm is not None

    def floors() -> np.ndarray:
        """Per track the smallest share: ``lo_f``, or with a lattice reach ``1 / m`` when ``m``
        firings at the printed clock (``clock_factor`` x the one ``w_s`` is at) still lie within
        the reach beside the wider gap to the kept neighbouring tracks (0 for tracks left out)."""
        out = np.full(r_s.size, lo_f)
        on = np.flatnonzero(hi_f > 0)
        if reach_mm is not None and on.size > 1:
            gaps = np.diff(r_s[on])
            g = np.maximum(np.concatenate([[gaps[0]], gaps]), np.concatenate([gaps, [gaps[-1]]]))
            b_max = np.sqrt(np.clip(reach_mm * reach_mm - g * g, 0.0, None))
            m = np.floor(b_max * w_s[on] * clock_factor + 1e-9)
            m = np.clip(m, 1.0 / lo_f, 1.0 / EQUALISE_MIN_SHARE)
            out[on] = np.minimum(lo_f, 1.0 / m)
        return np.minimum(out, hi_f)

    raise_k = bool(raise_sparse) & (r_s >= lo_t + _EQ_WINDOW_MM / 2) & (r_s <= hi_t - _EQ_WINDOW_MM / 2)

    def settle(f: np.ndarray, first: bool = False) -> np.ndarray:
        """Multiplicative updates of the profile averaged over each track's footprint towards the
        target (``_equalise_kernels.settle_jit``): ``f <- clip(f * T* / Tbar_k, floor_k, hi_k)``."""
        lo_k = floors()
        f = np.array(f, np.float64)  # the kernel updates in place
        no_up = np.zeros(r_s.size, bool)
        if first and "first" in memo:
            f = memo["first"].copy()
        else:
            settle_jit(band, start, k_sum, w_s, target, lo_k, hi_f, EQUALISE_ITERATIONS, 0, printed, a_i, b_i, n_w,
                       s_k, no_up, f, t, c, lev)
            if first:
                memo["first"] = f.copy()
        # the footprint-scale updates leave sparse stretches (tracks keeping every drop beside
        # thinned peaks) below the target on the mm scale: scale the shares by the mm-scale level
        # (down everywhere; up, where the level is below the target, only a window in from the
        # band's ends and where no track is left out within a window: beside a left-out track's
        # gap a raise overshoots on the mm scale)
        c_out = np.concatenate([[0], np.cumsum(np.bincount(s_k[hi_f <= 0], minlength=n_g))])
        up = raise_k & ((c_out[b_i] - c_out[a_i])[s_k] == 0)
        settle_jit(band, start, k_sum, w_s, target, lo_k, hi_f, 0, EQUALISE_ITERATIONS // 3, printed, a_i, b_i, n_w,
                   s_k, up, f, t, c, lev)
        return f

    f = settle(f, first=True)
    if drop_tracks:
        # where even the floors leave the mm-scale level above the target (tracks crowd at one end
        # of a steeply tilted head), whole tracks are left out, error-diffused by the excess, and
        # only where the gap they leave is no wider than the union's largest gap (so the drop
        # lattice the plan chose still closes); then the shares settle again
        inside = (r_s >= lo_t) & (r_s <= hi_t)
        gaps = np.diff(r_s)
        both = inside[1:] & inside[:-1]
        g_lim = float(gaps[both].max()) if both.any() else float(gaps.max())
        for _ in range(_DROP_ROUNDS):
            level_at_jit(band, start, f, w_s, printed, a_i, b_i, n_w, s_k, t, c, lev)
            need = 1.0 - target * (1.0 + _DROP_TOLERANCE) / np.maximum(lev, 1e-300)
            if not (need > 0).any():
                break
            left_out = drop_round_jit(need, r_s, hi_f, g_lim)
            if raise_sparse and left_out == 0:
                # no track left out this round: with the raise, settling again only re-raises the
                # same stretches (6 rounds of it were 80 % of the time at 20-45 deg); without it
                # the rounds go on as before (later rounds may still leave tracks out)
                break
            f = settle(np.where(hi_f > 0, np.maximum(f, 0.5), 0.0))
    return f


def _profile_setup(r_s: np.ndarray, w_s: np.ndarray, a_mm: float, plan: SwathePlan, offsets_mm: Sequence[float],
                   target_percentile: float) -> dict:
    """What both variants of :func:`_equalise_profile` share: the footprint matrix ``K`` ``(M,
    n_g)`` (CSR) of the sorted tracks on the grid, its row sums, the band where every pass
    prints, the target and the running mean's windows."""
    from ._equalise_kernels import profile_jit

    step = _EQ_STEP_MM
    g0 = float(r_s[0]) - a_mm
    n_g = int(math.ceil((float(r_s[-1]) + a_mm - g0) / step)) + 1
    reach = int(math.ceil(a_mm / step)) + 1
    base = np.floor((r_s - g0) / step).astype(np.int64)
    # the footprint matrix K (M, n_g): row k holds the cap profile at the grid points
    # base_k + s (s in -reach..reach) it reaches; kept as a band (M, W) from each row's first
    # column (what scipy.sparse's CSR of these entries holds, row by row, in the same order)
    vals = np.empty((r_s.size, 2 * reach + 1))
    oks = np.empty((r_s.size, 2 * reach + 1), bool)
    for i, s_ in enumerate(range(-reach, reach + 1)):
        idx = base + s_
        x = (g0 + idx * step - r_s) / a_mm
        k = np.clip(1.0 - x * x, 0.0, None) ** 1.5
        vals[:, i] = k
        oks[:, i] = (k > 0) & (idx >= 0) & (idx < n_g)
    cnt = oks.sum(axis=1)
    first = np.argmax(oks, axis=1)  # a row's entries are consecutive (the cap is > 0 on one interval)
    wd = int(cnt.max())
    data = vals[oks]  # row by row, ascending columns
    indptr = np.concatenate([[0], np.cumsum(cnt)])
    k_sum = np.zeros(r_s.size)
    nz = np.flatnonzero(cnt)
    k_sum[nz] = np.add.reduceat(data, indptr[nz])  # as scipy.sparse's K.sum(axis=1)
    col = np.arange(wd)
    band = np.where(col[None, :] < cnt[:, None], np.take_along_axis(vals, np.minimum(first[:, None] + col[None, :], 2 * reach), 1), 0.0)
    start = base - reach + first
    grid = g0 + np.arange(n_g) * step
    # the band where every pass prints, a footprint in from either end (tracks there lack
    # neighbours on one side)
    lo_t = max(float(r_s[0]), plan.inner_radius_mm + max(0.0, max(offsets_mm))) + a_mm
    hi_t = min(float(r_s[-1]), plan.outer_radius_mm + min(0.0, min(offsets_mm))) - a_mm
    t0 = np.empty(n_g + wd)
    profile_jit(band, start, np.ones(r_s.size), w_s, t0)  # the unthinned profile K^T w
    t0 = t0[:n_g]
    win = max(1, int(round(_EQ_WINDOW_MM / step)))
    c = np.concatenate([[0.0], np.cumsum(t0)])
    centre = np.arange(n_g)
    a_i, b_i = np.clip(centre - win // 2, 0, n_g), np.clip(centre + win // 2 + 1, 0, n_g)
    smooth = (c[b_i] - c[a_i]) / np.maximum(b_i - a_i, 1)
    mid = (grid - _EQ_WINDOW_MM / 2 >= lo_t) & (grid + _EQ_WINDOW_MM / 2 <= hi_t)
    if not mid.any():
        mid = (grid >= lo_t) & (grid <= hi_t)
    if not mid.any():
        mid[:] = True
    target = float(np.percentile(smooth[mid], float(target_percentile)))
    printed = (grid >= float(r_s[0])) & (grid <= float(r_s[-1]))
    c_n = np.concatenate([[0], np.cumsum(printed)])
    return {"band": np.ascontiguousarray(band), "start": start, "k_sum": k_sum, "n_g": n_g, "target": target, "lo_t": lo_t, "hi_t": hi_t, "a_i": a_i, "b_i": b_i,
            "printed": printed, "n_w": np.maximum(c_n[b_i] - c_n[a_i], 1),
            "s_k": np.clip(np.floor((r_s - g0) / step).astype(np.int64), 0, n_g - 1)}


#: :func:`even_line_shares` keeps every line's volume at or above this percentile of the lines'
#: volumes before any track is left out (a low percentile: the sparse stretches, not the seams).
EVEN_LINE_PERCENTILE = 1.0
#: Step of the line positions :func:`even_line_shares` checks, mm.
_LINE_STEP_MM = 0.002


def even_line_shares(head: InkjetHead, plan: SwathePlan, pass_plan, setup: RotarySetup | None = None, *,
                     line_mm: float, dead_nozzles: Sequence[int] | None = None) -> tuple[list[list[np.ndarray]], tuple[int, int]]:
    """Whole tracks left out where the union of the passes crowds, so that every narrow line gets about the same ink.

    The film of a narrow feature (a line ``line_mm`` wide along the track, e.g. one design
    pixel) holds the ink of the tracks inside it: ``sum_k n_k p_k(c)``, ``p_k`` the share of
    track ``k``'s footprint cross-section inside ``[c, c + line_mm)``, ``n_k = 1 / (r_k dphi_k)`` drops per mm (one angular clock per swathe:
    a swathe's inner tracks lay up to ``r_out / r_in`` times more). A tilted head's tracks pair
    up and crowd, so these *line volumes* range 0.5-2 x their mean (``docs/rotary.md``), while
    the levelled film flows only ~0.1 mm. Tracks are left out (share 0; the clock and every
    kept track's drops unchanged), densest first, while every line that holds the track keeps
    at least ``T``, the :data:`EVEN_LINE_PERCENTILE` percentile of the line volumes before
    (lines are checked every :data:`_LINE_STEP_MM`), and the gap the track leaves, ``g``,
    keeps the drop lattice no coarser than the plan's worst cell: ``g^2 + s^2 <=
    largest_gap^2 + along_track^2``, ``s`` the neighbours' drop spacing along their tracks
    (smaller at a swathe's inner end, so gaps there may be wider than the plan's largest).
    So the sparse lines keep their ink, the crowded ones come down towards them, the mean
    comes down, and no point is farther from a drop than in the plan's widest lattice cell.

    Parameters
    ----------
    head : InkjetHead
        Its ``dead_nozzles`` unless ``dead_nozzles`` is given (dead tracks are not in the union).
    plan : SwathePlan
        The passes' swathes (with a ``seam_mm``, both swathes' tracks of a seam are in the union).
    pass_plan : PassPlan
        Its ``offsets_mm``, ``largest_gap_mm`` and ``footprint_um`` (a track adds to a line the
        share of its drops' cross-section ``(1 - x^2/a^2)^(3/2)`` that falls inside it).
    setup : RotarySetup, optional
        The printed clock (``dpi_y``, default the plan's) and ``ref_radius_mm``.
    line_mm : float
        Width of the lines, mm (> 0).
    dead_nozzles : sequence of int, optional

    Returns
    -------
    shares : list (pass) of list (swathe) of (N,) float64
        1 for kept tracks, 0 for tracks left out and for nozzles that do not print.
    kept : (int, int)
        Tracks kept, and tracks of the union before.
    """
    if not (math.isfinite(line_mm) and line_mm > 0):
        raise ConfigError(f"line width must be > 0 mm, got {line_mm!r}")
    st = setup or RotarySetup(tilt_deg=plan.tilt_deg)
    dpi_y = float(pass_plan.dpi_y) if st.dpi_y is None else float(st.dpi_y)
    offsets_mm = pass_plan.offsets_mm
    live = np.ones(head.nozzles, bool)
    live[list(head.dead_nozzles if dead_nozzles is None else tuple(dead_nozzles))] = False
    rs, ns, where = _printing_tracks(plan, head, offsets_mm, live, dpi_y, st.ref_radius_mm)
    out = [[np.zeros(head.nozzles) for _ in plan.swathes] for _ in offsets_mm]
    r_all = np.concatenate(rs)
    if r_all.size < 3:
        for q, j, k in where:
            out[q][j][k] = 1.0
        return out, (int(r_all.size), int(r_all.size))
    order = np.argsort(r_all, kind="stable")
    r, n = r_all[order], np.concatenate(ns)[order]
    keep = _leave_out(r, n, plan.inner_radius_mm, plan.outer_radius_mm, float(line_mm), 0.5e-3 * float(pass_plan.footprint_um),
                      float(pass_plan.largest_gap_mm) ** 2 + (25.4 / dpi_y) ** 2)
    k_all = np.empty(r.size)
    k_all[order] = keep
    pos = 0
    for q, j, k in where:
        out[q][j][k] = k_all[pos:pos + k.size]
        pos += k.size
    return out, (int(keep.sum()), int(keep.size))


def _printing_tracks(plan: SwathePlan, head: InkjetHead, offsets_mm, live: np.ndarray, dpi_y: float,
                     ref_radius_mm) -> tuple[list, list, list]:
    """The tracks the passes print: per pass ``q`` (offset ``offsets_mm[q]`` along the mount
    direction) and swathe ``j``, the live nozzles ``k`` (int64 indices; ``live`` (N,) bool) that
    ``pass_enabled`` lets print, their radii (mm) and drops per mm of track ``1 / (r dphi)`` at
    the swathe's clock. Returns the lists ``(radii, drops_per_mm, [(q, j, k), ...])``, one item
    per (pass, swathe)."""
    from .exact import swathe_clock

    psi = math.radians(plan.mount_angle_deg)
    e = np.array([math.cos(psi), math.sin(psi)])
    rs, ns, where = [], [], []
    for q, o in enumerate(offsets_mm):
        for j in range(len(plan.swathes)):
            dphi, _ = swathe_clock(plan, j, dpi_y=dpi_y, ref_radius_mm=ref_radius_mm)
            xy = nozzle_layout(head, plan.mount(j)).xy_mm + float(o) * e
            r = np.hypot(xy[:, 0], xy[:, 1])
            k = np.flatnonzero(pass_enabled(plan, j, r) & live)
            rs.append(r[k])
            ns.append(1.0 / (r[k] * dphi))
            where.append((q, j, k))
    return rs, ns, where


def _leave_out(r: np.ndarray, n: np.ndarray, lo: float, hi: float, line_mm: float, a_mm: float, cell2: float) -> np.ndarray:
    """Kept tracks ``(M,) float64`` (1/0) of sorted radii ``r`` (mm) with ``n`` drops per mm (see
    :func:`even_line_shares`; ``a_mm`` the footprint radius, ``cell2`` the squared diagonal of the
    plan's widest lattice cell)."""
    step = _LINE_STEP_MM
    c = np.arange(lo, max(lo + step, hi - line_mm), step)
    # share of a drop's ink (its cross-section (1 - x^2/a^2)^(3/2) along the track) inside the
    # line [c, c + line) for a track at c - u
    x = np.linspace(-a_mm, a_mm, 401)
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (np.clip(1 - (x[1:] / a_mm) ** 2, 0, None) ** 1.5
                                                  + np.clip(1 - (x[:-1] / a_mm) ** 2, 0, None) ** 1.5))])
    cdf /= cdf[-1]

    def share(u: np.ndarray) -> np.ndarray:
        return np.interp(u + line_mm, x, cdf) - np.interp(u, x, cdf)

    ka = np.searchsorted(c, r - a_mm - line_mm, side="right")
    kb = np.searchsorted(c, r + a_mm, side="right")
    parts = [share(c[ka[k]:kb[k]] - r[k]) for k in range(r.size)]
    vol = np.zeros(c.size)
    for k in range(r.size):
        vol[ka[k]:kb[k]] += n[k] * parts[k]
    target = float(np.percentile(vol, EVEN_LINE_PERCENTILE))
    dens = np.array([float(vol[ka[k]:kb[k]] @ parts[k]) / max(float(parts[k].sum()), 1e-300) for k in range(r.size)])
    inside = (r >= lo) & (r < hi) & (kb > ka)
    spacing = 1.0 / n  # drops' spacing along the track, mm
    keep = np.ones(r.size)
    prev = np.arange(r.size) - 1
    nxt = np.arange(r.size) + 1
    for k in np.argsort(-dens, kind="stable"):
        if not inside[k] or dens[k] <= target:
            continue
        p, q = prev[k], nxt[k]
        if p < 0 or q >= r.size:
            continue
        g = r[q] - r[p]
        s_ = max(spacing[p], spacing[q])
        if g * g + s_ * s_ > cell2:
            continue
        i, j = ka[k], kb[k]
        after = vol[i:j] - n[k] * parts[k]
        if (after[parts[k] > 1e-6] < target).any():
            continue
        keep[k] = 0.0
        vol[i:j] = after
        nxt[p], prev[q] = q, p
    return keep


def thin_print(pr, fractions: Sequence[np.ndarray], *, pass_index: int = 0):
    """``pr`` with track ``k`` of swathe ``j`` keeping firing ``i`` only when
    ``floor((i + 1) f + o) > floor(i f + o)`` (``f = fractions[j][k]``, ``o`` a golden-ratio
    step per nozzle and pass: :func:`~rotoprint.rotary._thin_kernels.thin_phases`): an ordered,
    even pattern on the absolute firing index, exactly ``f`` of the firings over any run.

    The rule is :func:`~rotoprint.rotary._thin_kernels.kept_jit`, the one the exact transform
    thins by while it samples (``transform_exact(..., thin=ThinShares(fractions, pass_index))``,
    identical images without the unthinned one: what :func:`~rotoprint.rotary.interlace.pass_prints` uses).
    """
    import dataclasses

    from ._thin_kernels import thin_levels_jit, thin_phases

    out = []
    for sw, f in zip(pr.swathes, fractions):
        o = thin_phases(sw.levels.shape[1], pass_index)
        lev = np.ascontiguousarray(sw.levels, dtype=np.uint8)
        kept = np.empty_like(lev)
        thin_levels_jit(lev, int(sw.first_firing), np.ascontiguousarray(f, dtype=np.float64), o, kept)
        out.append(dataclasses.replace(sw, levels=kept))
    return dataclasses.replace(pr, swathes=tuple(out))
