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

__all__ = ["cover_dead_nozzles"]


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
