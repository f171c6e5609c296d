"""Dead-nozzle cover within one pass: a dead nozzle's drops moved to its neighbouring tracks.

A dead nozzle draws the same empty circle every revolution (a ring through the part). Within a
single pass its drops can go to the live tracks just inside and outside it (the EFI-style
redistribution of ``shared/design/film-and-machine.md`` s. 3): each drop of dead nozzle ``k``
at firing ``i`` lands at angle ``theta = phi_k - direction * i * dphi``; it is given to the
neighbour ``m`` (alternating inner and outer, nearer first) at the firing ``i'`` whose landing
angle is nearest ``theta``, as one more level there when the slot has room (``level <
grey_levels``), else at the nearest slot with room within ``search`` firings. The volume moves
in whole levels, so it is conserved exactly for every drop that finds room; drops that find none
are reported as lost. A binary head whose neighbours fire at every firing has no room: interlaced
passes (:mod:`rotoprint.rotary.interlace`) or an equalised print leave it. Moved drops land on
the neighbours' tracks, so they thicken the film beside the dead track but bridge it only where
the footprint spans the gap between the neighbours (about two track pitches); a narrower
footprint needs another pass over the dead track (:func:`~rotoprint.rotary.interlace.plan_passes`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from ..errors import ConfigError
from .head import Mount, nozzle_layout

__all__ = ["cover_dead_nozzles", "cover_dead_tracks", "DeadCoverOptions", "thin_by_landing", "DEAD_COVER_WINDOW_MM", "DEAD_COVER_MIN_SCALE"]

#: A dead track's drops go to live tracks of every pass within this radial distance, mm (about
#: 2.5 levelling lengths of one coat, ``docs/rotary.md``: the film evens out within about one).
#: Measured on the test design at tilt 45 with 5 dead nozzles (equalised): 0.15 mm left 7.9 % of the
#: dead tracks' drops without room, 0.3 mm 2.0 %.
DEAD_COVER_WINDOW_MM = 0.3
#: Smallest share of its drops every live track keeps to leave room for the dead tracks' drops
#: (:func:`cover_dead_tracks`, a print without shares).
DEAD_COVER_MIN_SCALE = 0.85


def cover_dead_nozzles(pr, dead_nozzles: Sequence[int], *, search: int = 3):
    """Move the drops of ``dead_nozzles`` in ``pr`` to their live neighbouring tracks.

    Parameters
    ----------
    pr : RotaryPrint
        A print in which the dead nozzles still carry the drops they should print (made with a
        head that does not know them as dead).
    dead_nozzles : sequence of int
    search : int
        Firings on each side of the nearest one that may take a moved drop, 0..64.

    Returns
    -------
    print : RotaryPrint
        The dead columns empty, their drops on the neighbours.
    report : dict
        ``dead_nozzles``, ``levels_to_move``, ``levels_moved``, ``levels_lost``,
        ``volume_lost_fraction`` (of the print's volume) and ``mean_shift_um`` (landing point
        moved, radial and along the track).

    Raises
    ------
    ConfigError
        A nozzle index out of range, ``search`` out of range.
    """
    n = pr.head.nozzles
    dead = sorted({int(k) for k in dead_nozzles})
    bad = [k for k in dead if not 0 <= k < n]
    if bad:
        raise ConfigError(f"dead nozzle indices must be in 0..{n - 1}, got {bad}")
    if not 0 <= int(search) <= 64:
        raise ConfigError(f"search must be 0..64 firings, got {search!r}")
    g = pr.head.grey_levels
    total = sum(int(s.levels.astype(np.int64).sum()) for s in pr.swathes)
    to_move = moved = 0
    shifts = []
    out = []
    sig = pr.direction
    for sw in pr.swathes:
        lev = sw.levels.copy()
        lay = nozzle_layout(pr.head, Mount(sw.pivot_radius_mm, tilt_deg=pr.tilt_deg, mount_angle_deg=pr.mount_angle_deg, direction=sig))
        en = sw.enabled if sw.enabled is not None else np.ones(n, bool)
        live = en.copy()
        live[dead] = False
        cand = np.flatnonzero(live)
        order = cand[np.argsort(lay.r_mm[cand])]
        r_sorted = lay.r_mm[order]
        f_n = lev.shape[0]
        for k in dead:
            b_fired = np.flatnonzero(lev[:, k])
            if not b_fired.size:
                continue
            pos = np.searchsorted(r_sorted, lay.r_mm[k])
            nb = [order[p] for p in (pos - 1, pos) if 0 <= p < order.size]
            nb.sort(key=lambda m: abs(lay.r_mm[m] - lay.r_mm[k]))
            for t, b in enumerate(b_fired):
                want = int(lev[b, k])
                to_move += want
                theta = lay.phi_rad[k] - sig * (b + sw.first_firing) * sw.dphi_rad
                seq = nb if t % 2 == 0 else nb[::-1]
                for m in seq:
                    if want == 0:
                        break
                    i_m = int(np.rint(sig * (lay.phi_rad[m] - theta) / sw.dphi_rad)) - sw.first_firing
                    for off in sorted(range(-search, search + 1), key=abs):
                        bb = i_m + off
                        if not 0 <= bb < f_n or want == 0:
                            continue
                        room = g - int(lev[bb, m])
                        if room > 0:
                            put = min(room, want)
                            lev[bb, m] += put
                            want -= put
                            moved += put
                            ang = lay.phi_rad[m] - sig * (bb + sw.first_firing) * sw.dphi_rad
                            shifts.append(float(np.hypot(lay.r_mm[m] - lay.r_mm[k], lay.r_mm[k] * (ang - theta))) * 1e3)
            lev[:, k] = 0
        out.append(dataclasses.replace(sw, levels=lev))
    lost = to_move - moved
    report = {
        "dead_nozzles": dead,
        "levels_to_move": to_move,
        "levels_moved": moved,
        "levels_lost": lost,
        "volume_lost_fraction": lost / total if total else 0.0,
        "mean_shift_um": float(np.mean(shifts)) if shifts else 0.0,
    }
    return dataclasses.replace(pr, swathes=tuple(out)), report


@dataclasses.dataclass(frozen=True)
class DeadCoverOptions:
    """How :func:`cover_dead_tracks` places a dead track's drops.

    Parameters
    ----------
    window_mm : float
        Radial reach of a dead track's drops, mm, (0, 1].
    min_scale : float
        Smallest common share of a print without shares, [0.5, 1].
    cover_share : float
        A live track has room (without shares) only where a missed drop leaves every point
        within this share of the footprint radius of the drops left, (0, 1].
    scale_shares : bool
        With shares (an equalised print): where the dead tracks' drops find no room within
        ``window_mm`` (the tracks keep nearly every drop: the sparse end of a swathe, where the
        equalised level is set), every share is scaled by the largest common ``s`` in
        ``[min_scale, 1]`` (to 1e-3) with which they all find room, so the film's mean comes down
        instead of the dead ring staying thin; a share ``f`` keeps at least ``1 / max(2,
        ceil(1 / f))`` (its longest run of missed firings no longer than before, or than 2).
        Measured on the test design at tilt 45 with 5 dead nozzles: ``s`` = 0.972, levelled
        thinnest / mean 0.495 -> 0.504 (``docs/rotary.md``). On by default.
    """

    window_mm: float = DEAD_COVER_WINDOW_MM
    min_scale: float = DEAD_COVER_MIN_SCALE
    cover_share: float = 0.85
    scale_shares: bool = True

    def __post_init__(self) -> None:
        import math

        if not (isinstance(self.window_mm, (int, float)) and math.isfinite(self.window_mm) and 0.0 < self.window_mm <= 1.0):
            raise ConfigError(f"dead cover window must be in (0, 1] mm, got {self.window_mm!r}")
        if not (isinstance(self.min_scale, (int, float)) and math.isfinite(self.min_scale) and 0.5 <= self.min_scale <= 1.0):
            raise ConfigError(f"dead cover scale must be in [0.5, 1], got {self.min_scale!r}")
        if not (isinstance(self.cover_share, (int, float)) and math.isfinite(self.cover_share) and 0.0 < self.cover_share <= 1.0):
            raise ConfigError(f"dead cover share must be in (0, 1], got {self.cover_share!r}")


def cover_dead_tracks(head, plan, offsets_mm: Sequence[float], setup=None, *, shares=None, footprint_um: float | None = None,
                      options: DeadCoverOptions | None = None):
    """Give each dead track's drops to the nearest live tracks of every pass (shares of drops).

    Interlaced passes print a dead nozzle's track once per pass, at ``r_k + delta_q``; the
    other passes' live tracks lie within a fraction of a pitch of it. Each dead track's drops
    per mm (the share it would keep, times ``1 / (r dphi)`` of its swathe's clock) are given,
    nearest first, to the live tracks of any pass and swathe within ``window_mm``, as long as
    they have room (a share below 1). A print without shares keeps every drop on every track,
    so there is no room: every live track whose missed drop a radial neighbour still covers
    (no point about the missed drop farther than ``cover_share`` of the footprint radius from
    the drops left: its own along the track and its radial neighbours', at their firing phases) then keeps the share ``s`` (the same everywhere, so the film stays
    as even as it was), the largest in ``[min_scale, 1]`` (to 1e-3) with which every dead
    track's drops find room; the others keep every drop. With shares, where the window has no room
    for them all, every share is scaled the same way (:attr:`DeadCoverOptions.scale_shares`). Such a print is thinned by
    :func:`thin_by_landing` (neighbouring tracks miss drops at different angles). The volume per mm moved is conserved (each track's
    share is realised exactly over any run of firings by :func:`~rotoprint.rotary.equalise.thin_print`).

    Parameters
    ----------
    head : InkjetHead
        Its ``dead_nozzles`` are the dead tracks.
    plan : SwathePlan
    offsets_mm : sequence of float
        The passes' radial offsets.
    setup : RotarySetup, optional
        The clock (``dpi_y``, default the head's) and reference radius of the swathes' clocks.
    shares : list (pass) of list (swathe) of (N,) float64, optional
        Shares the passes would print with were the dead nozzles live (an equalised print:
        :func:`~rotoprint.rotary.equalise.track_fractions` with ``dead_nozzles=()``); the dead
        tracks' own shares are what they give away. None: every drop.
    footprint_um : float, optional
        Footprint diameter of a drop (needed without ``shares``).
    options : DeadCoverOptions, optional
        The window, the smallest common share and the cover share (defaults above).

    Returns
    -------
    shares : list (pass) of list (swathe) of (N,) float64
        In [0, 1] for the enabled live nozzles, 0 elsewhere.
    report : dict
        ``dead_tracks``, ``scale`` (the common share, 1 with ``shares``), ``demand`` (the dead
        tracks' drops per mm, relative to one track at ``1 / (r dphi)`` of its swathe's clock,
        summed), ``moved`` and ``lost`` (of it) and ``lost_fraction``, ``window_mm``
        (``scale`` < 1 with shares: :attr:`DeadCoverOptions.scale_shares`).

    Raises
    ------
    ConfigError
        Shares of the wrong shape, no footprint without shares (bad options: when made).
    """
    import math

    from .exact import swathe_clock
    from .options import RotarySetup
    from .swathes import pass_enabled

    opts = options or DeadCoverOptions()
    window_mm, min_scale, cover_share = opts.window_mm, opts.min_scale, opts.cover_share
    if shares is None and not (footprint_um is not None and math.isfinite(footprint_um) and footprint_um > 0):
        raise ConfigError(f"dead cover without shares needs a footprint > 0 um, got {footprint_um!r}")
    st = setup or RotarySetup(tilt_deg=plan.tilt_deg)
    dpi_y = head.dpi_y if st.dpi_y is None else float(st.dpi_y)
    n = head.nozzles
    dead = np.zeros(n, bool)
    dead[list(head.dead_nozzles)] = True
    if shares is not None and (len(shares) != len(offsets_mm) or any(len(p) != len(plan.swathes) for p in shares)):
        raise ConfigError("shares must give one array per pass and swathe")
    psi = math.radians(plan.mount_angle_deg)
    e = np.array([math.cos(psi), math.sin(psi)])
    lr, lw, lf, lwhere, dr, dw, lphi, ldphi, dsh = [], [], [], [], [], [], [], [], []
    for q, o in enumerate(offsets_mm):
        for j in range(len(plan.swathes)):
            dphi, _ = swathe_clock(plan, j, dpi_y=dpi_y, ref_radius_mm=st.ref_radius_mm)
            xy = nozzle_layout(head, plan.mount(j)).xy_mm + float(o) * e
            r = np.hypot(xy[:, 0], xy[:, 1])
            en = pass_enabled(plan, j, r)
            k = np.flatnonzero(en & ~dead)
            lr.append(r[k])
            lphi.append(np.arctan2(xy[k, 1], xy[k, 0]))
            ldphi.append(np.full(k.size, dphi))
            lw.append(1.0 / (r[k] * dphi))
            lf.append(np.ones(k.size) if shares is None else np.asarray(shares[q][j], np.float64)[k])
            lwhere.append((q, j, k))
            kd = np.flatnonzero(en & dead)
            dr.append(r[kd])
            dsh.append(np.ones(kd.size) if shares is None else np.asarray(shares[q][j], np.float64)[kd])
            dw.append(1.0 / (r[kd] * dphi))
    r_l, w_l, f_l = np.concatenate(lr), np.concatenate(lw), np.concatenate(lf)
    r_d, w_d = np.concatenate(dr), np.concatenate(dw)
    order = np.argsort(r_l, kind="stable")
    rs = r_l[order]
    if shares is None:
        # room only on tracks where a missing drop leaves no point farther than the lattice
        # reach from the drops left (its own along the track, its radial neighbours')
        phi_s, dphi_s = np.concatenate(lphi)[order], np.concatenate(ldphi)[order]

        a_um = 0.5 * float(footprint_um)
        ok_s = _miss_covered(rs, phi_s, dphi_s, cover_share * a_um * 1e-3)
        eligible = np.empty(rs.size, bool)
        eligible[order] = ok_s
    else:
        eligible = np.ones(r_l.size, bool)
    # a dead track's share had it been live: its own in ``shares`` (equalised with the dead
    # nozzles as live ones), every drop without shares
    f_d = np.concatenate(dsh) if shares is not None else np.ones(r_d.size)
    demand = f_d * w_d
    # nearest live tracks first, for every dead track (in radial order)
    cand = []
    for x in r_d:
        lo, hi = np.searchsorted(rs, x - window_mm), np.searchsorted(rs, x + window_mm, side="right")
        idx = np.arange(lo, hi)
        cand.append(order[idx[np.argsort(np.abs(rs[idx] - x), kind="stable")]])

    # with shares, a common scale never widens a track's largest run of missed firings beyond
    # max(2, what its share had): a share f keeps at least 1 / max(2, ceil(1 / f))
    keep_lo = (np.where(f_l > 0, 1.0 / np.maximum(2.0, np.ceil(1.0 / np.maximum(f_l, 1e-300) - 1e-9)), 0.0)
               if shares is not None else np.zeros(f_l.size))

    def place(scale: float) -> tuple[np.ndarray, float]:
        f = np.where(eligible, np.maximum(f_l * scale, np.minimum(f_l, keep_lo)), f_l)
        lost = 0.0
        for dem, c in zip(demand * scale, cand):
            for t in c:
                if dem <= 0:
                    break
                room = (1.0 - f[t]) * w_l[t]
                if room > 0:
                    put = min(room, dem)
                    f[t] += put / w_l[t]
                    dem -= put
            lost += max(0.0, dem)
        return np.minimum(f, 1.0), lost

    total = float(demand.sum())
    f, lost = place(1.0)
    scale = 1.0
    if (shares is None or opts.scale_shares) and lost > 1e-9 * max(total, 1e-300):
        lo_s, hi_s = float(min_scale), 1.0
        f, lost = place(lo_s)
        scale = lo_s
        if lost <= 1e-9 * total:
            while hi_s - lo_s > 1e-3:
                mid = 0.5 * (lo_s + hi_s)
                fm, lm = place(mid)
                if lm <= 1e-9 * total:
                    lo_s, f, lost = mid, fm, lm
                else:
                    hi_s = mid
            scale = lo_s
    out = [[np.zeros(n) for _ in plan.swathes] for _ in offsets_mm]
    pos = 0
    for q, j, k in lwhere:
        out[q][j][k] = f[pos:pos + k.size]
        pos += k.size
    report = {
        "dead_tracks": int(r_d.size),
        "scale": float(scale),
        "demand": total * scale,
        "moved": total * scale - lost,
        "lost": float(lost),
        "lost_fraction": float(lost / (total * scale)) if total > 0 else 0.0,
        "window_mm": float(window_mm),
        "tracks_with_room": int(eligible.sum()),
        "tracks": int(eligible.size),
    }
    return out, report


_GOLDEN = 0.6180339887498949


def _miss_covered(r_mm: np.ndarray, phi_rad: np.ndarray, dphi_rad: np.ndarray, reach_mm: float) -> np.ndarray:
    """Per sorted track: does a missing drop leave every point about it within ``reach_mm`` of
    the drops left (its own at +-1 firing, the two radial neighbours' at their along-track
    phases, each neighbour taken to keep its drops there)? ``(M,) bool``; the ends: False."""
    m = r_mm.size
    out = np.zeros(m, bool)
    if m < 3:
        return out
    k = np.arange(1, m - 1)
    b = r_mm[k] * dphi_rad[k]  # along-track drop spacing, mm
    g1, g2 = r_mm[k] - r_mm[k - 1], r_mm[k + 1] - r_mm[k]

    def phase(nb: np.ndarray) -> np.ndarray:
        return r_mm[k] * np.mod(phi_rad[nb] - phi_rad[k], dphi_rad[nb])  # neighbour's drop offset along the track, mm

    u1, u2 = phase(k - 1), phase(k + 1)
    worst = np.zeros(k.size)
    for fx in np.linspace(-0.5, 0.5, 21):
        x = fx * b
        for fy in np.linspace(-0.5, 0.5, 5):
            y = np.where(fy < 0, fy * g1, fy * g2)
            d_own = np.hypot(b - np.abs(x), y)
            b1 = r_mm[k - 1] * dphi_rad[k - 1]
            b2 = r_mm[k + 1] * dphi_rad[k + 1]
            x1 = np.abs(np.mod(x - u1 + 0.5 * b1, b1) - 0.5 * b1)
            x2 = np.abs(np.mod(x - u2 + 0.5 * b2, b2) - 0.5 * b2)
            d = np.minimum(d_own, np.minimum(np.hypot(x1, y + g1), np.hypot(x2, g2 - y)))
            worst = np.maximum(worst, d)
    out[k] = worst <= reach_mm
    return out


def thin_by_landing(prints: Sequence, shares) -> list:
    """The passes ``prints`` with track ``k`` of swathe ``j`` of pass ``q`` keeping the share
    ``shares[q][j][k]`` of its firings, as an ordered pattern on the landing angle: with ``e =
    1 - f`` and ``t = i - sigma phi_k / dphi`` (the landing angle ``phi_k - sigma i dphi`` in
    firings), firing ``i`` is missed when ``frac(g - e t) < e``: one miss every ``1 / e``
    firings, exactly ``f`` of them over any run, at landing angles ``g / e`` (mod ``1 / e``),
    ``g`` a golden-ratio step of the track's radial rank among the swathe's tracks of every
    pass, so that radially neighbouring tracks miss drops far apart along the track, also
    where their firing lattices are offset by a fraction of a step (a head's two rows).

    Parameters
    ----------
    prints : sequence of RotaryPrint
        One per pass, the same swathes.
    shares : list (pass) of list (swathe) of (N,) float64

    Returns
    -------
    list of RotaryPrint
    """
    if len(shares) != len(prints):
        raise ConfigError("shares must give one list per pass")
    out = [list(p.swathes) for p in prints]
    n_sw = len(prints[0].swathes) if prints else 0
    for j in range(n_sw):
        rows = []
        for q, pr in enumerate(prints):
            sw = pr.swathes[j]
            lay = nozzle_layout(pr.head, Mount(sw.pivot_radius_mm, tilt_deg=pr.tilt_deg, mount_angle_deg=pr.mount_angle_deg,
                                               direction=pr.direction))
            rows.append((q, lay.r_mm, lay.phi_rad))
        r_all = np.concatenate([r for _, r, _ in rows])
        rank = np.empty(r_all.size, np.int64)
        rank[np.argsort(r_all, kind="stable")] = np.arange(r_all.size)
        pos = 0
        for q, r, phi in rows:
            sw = prints[q].swathes[j]
            f = np.asarray(shares[q][j], np.float64)
            g = np.mod(rank[pos:pos + r.size] * _GOLDEN, 1.0)
            pos += r.size
            eps = (1.0 - np.clip(f, 0.0, 1.0))[None, :]
            c = (prints[q].direction * phi / sw.dphi_rad)[None, :]  # landing angle = phi - sigma i dphi
            i = (np.arange(sw.levels.shape[0], dtype=np.float64) + sw.first_firing)[:, None]
            keep = np.mod(g[None, :] + eps * (c - i), 1.0) >= eps
            out[q][j] = dataclasses.replace(sw, levels=np.where(keep, sw.levels, 0).astype(np.uint8))
    return [dataclasses.replace(pr, swathes=tuple(sws)) for pr, sws in zip(prints, out)]
