"""Radial swathes: a design wider than the projected swathe printed in several revolutions.

:func:`plan_swathes` works on radii only, so the bitmap transforms and the direct rotary
slicer (issue 4) share it. Each swathe prints only with the nozzles inside the band where
every row prints (full density); the head is stepped outwards so that the next swathe's first
track lies one local track pitch beyond the previous swathe's last track. Every radius is owned
by exactly one swathe: no gap wider than a pitch, no double track.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..devices.models import InkjetHead
from ..errors import ConfigError, GeometryError
from .head import Mount, check_tilt, nozzle_layout, nozzle_offsets

__all__ = ["Swathe", "SwathePlan", "plan_swathes", "shared_plan", "pass_enabled"]

#: Radii closer than this (mm) count as equal when assigning tracks to bands.
_EPS_MM = 1e-9
_BISECT_STEPS = 80
_MAX_SWATHES_HARD = 10_000


@dataclass(frozen=True, eq=False)
class Swathe:
    """One revolution of the head at one pivot radius.

    Attributes
    ----------
    index : int
    pivot_radius_mm : float
    band_mm : (float, float)
        Radial band this swathe owns, ``[lo, hi)``.
    enabled : (N,) bool
        Nozzles that print in this swathe (inside the full-density band and the owned band).
    first_track_mm, last_track_mm : float
        Radii of the innermost and outermost enabled tracks.
    pitch_mm : float
        Mean radial pitch of the last tracks (the step to the next swathe's first track).
    usable : (N,) bool, optional
        Nozzles inside the full-density band (a superset of ``enabled``): an interlaced pass
        whose pivot is moved prints with those of them whose moved track lies in ``band_mm``
        (:func:`pass_enabled`, when the plan has an ``overlap_mm``).
    """

    index: int
    pivot_radius_mm: float
    band_mm: tuple[float, float]
    enabled: np.ndarray
    first_track_mm: float
    last_track_mm: float
    pitch_mm: float
    usable: np.ndarray | None = None

    def to_json(self) -> dict:
        en = np.flatnonzero(self.enabled)
        return {
            "index": self.index,
            "pivot_radius_mm": self.pivot_radius_mm,
            "band_mm": list(self.band_mm),
            "first_track_mm": self.first_track_mm,
            "last_track_mm": self.last_track_mm,
            "pitch_mm": self.pitch_mm,
            "enabled_nozzles": int(en.size),
            "enabled_nozzle_range": [int(en.min()), int(en.max())] if en.size else [],
        }


@dataclass(frozen=True, eq=False)
class SwathePlan:
    head: InkjetHead
    tilt_deg: float
    mount_angle_deg: float
    direction: int
    inner_radius_mm: float
    outer_radius_mm: float
    swathes: tuple[Swathe, ...]
    #: Each swathe's full-density band reaches this far inside its owned band (mm), so that a
    #: pass with a pivot offset in ``[0, overlap_mm]`` still covers the whole band.
    overlap_mm: float = 0.0
    #: With an overlap: every swathe but the first also prints (:func:`pass_enabled`) this far
    #: below its owned band (mm, at most ``overlap_mm``: the usable nozzles reach no further),
    #: where the previous swathe prints too, so a seam's tracks are those of both swathes, for a
    #: caller that leaves the excess out (:func:`~rotoprint.rotary.equalise.even_line_shares`).
    #: 0 (default): one swathe per radius. Set with :meth:`with_seam`.
    seam_mm: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.seam_mm) and 0 <= self.seam_mm <= self.overlap_mm + 1e-12):
            raise ConfigError(f"swathe seam must be in 0 .. the overlap ({self.overlap_mm!r} mm), got {self.seam_mm!r}")

    def with_seam(self, seam_mm: float) -> SwathePlan:
        """This plan with every swathe but the first also printing ``seam_mm`` below its band."""
        import dataclasses

        return self if float(seam_mm) == self.seam_mm else dataclasses.replace(self, seam_mm=float(seam_mm))

    def __len__(self) -> int:
        return len(self.swathes)

    def mount(self, j: int) -> Mount:
        """The head's mount for swathe ``j``."""
        return Mount(self.swathes[j].pivot_radius_mm, tilt_deg=self.tilt_deg, mount_angle_deg=self.mount_angle_deg, direction=self.direction)

    def to_json(self) -> list[dict]:
        return [s.to_json() for s in self.swathes]


def _radii(R: float, X: np.ndarray, Y: np.ndarray) -> np.ndarray:
    return np.hypot(R + X, Y)


def _band(r: np.ndarray, row: np.ndarray, rows: int) -> tuple[float, float]:
    lo = max(float(r[row == q].min()) for q in range(rows))
    hi = min(float(r[row == q].max()) for q in range(rows))
    return lo, hi


def shared_plan(head: InkjetHead, *, tilt_deg: float, inner_radius_mm: float, outer_radius_mm: float, mount_angle_deg: float = 0.0,
                direction: int = 1, max_swathes: int | None = None, overlap_mm: float = 0.0) -> SwathePlan:
    """:func:`plan_swathes`, one plan object for each set of arguments (the last 16 kept): the passes of
    a layer and the jobs of a build differ in pivot offset and clock only, so their exact maps and
    direct slicing jobs share one plan (:meth:`SwathePlan.with_seam` of it shares its arrays). Its
    arrays are read-only (the prints' ``SwatheImage.enabled`` may be a plan's own array).
    ``shared_plan.cache_clear()`` empties it."""
    return _shared_plan(head, float(tilt_deg), float(inner_radius_mm), float(outer_radius_mm), float(mount_angle_deg),
                        int(direction), max_swathes, float(overlap_mm))


@functools.lru_cache(maxsize=16)
def _shared_plan(head: InkjetHead, tilt_deg: float, r_in: float, r_out: float, mount_angle_deg: float, direction: int,
                 max_swathes, overlap_mm: float) -> SwathePlan:
    plan = plan_swathes(head, tilt_deg=tilt_deg, inner_radius_mm=r_in, outer_radius_mm=r_out, mount_angle_deg=mount_angle_deg,
                        direction=direction, max_swathes=max_swathes, overlap_mm=overlap_mm)
    for sw in plan.swathes:
        for a in (sw.enabled, sw.usable):
            if isinstance(a, np.ndarray):
                a.flags.writeable = False
    return plan


shared_plan.cache_clear = _shared_plan.cache_clear  # type: ignore[attr-defined]
shared_plan.cache_info = _shared_plan.cache_info  # type: ignore[attr-defined]


def plan_swathes(
    head: InkjetHead,
    *,
    tilt_deg: float,
    inner_radius_mm: float,
    outer_radius_mm: float,
    mount_angle_deg: float = 0.0,
    direction: int = 1,
    max_swathes: int | None = None,
    overlap_mm: float = 0.0,
) -> SwathePlan:
    """Pivot radii and nozzle sets covering the radial range ``[inner, outer]`` mm.

    The first swathe's innermost track lies half a track pitch outside ``inner_radius_mm``;
    swathes are added until a track lies within half a pitch of ``outer_radius_mm``.

    Parameters
    ----------
    head : InkjetHead
    tilt_deg : float
        Head tilt, degrees; ``|tilt_deg|`` below :func:`~rotoprint.rotary.head.max_tilt_deg`.
    inner_radius_mm, outer_radius_mm : float
        The radial range to cover, mm, ``0 < inner < outer``.
    mount_angle_deg : float
        Angle of the radial line through the pivots, degrees.
    direction : {1, -1}
        +1 the platform turns counter-clockwise seen from above, -1 clockwise.
    max_swathes : int, optional
        Refuse a plan needing more swathes than this (``>= 1``).
    overlap_mm : float
        Interlaced passes (:mod:`rotoprint.rotary.interlace`): every swathe's first track is
        placed this much further in, so that its full-density band reaches ``overlap_mm``
        inside its owned band (inside the design's inner edge for the first swathe). A pass
        whose pivot is moved outwards by up to ``overlap_mm`` then still covers its swathe's
        whole band with the tracks of :func:`pass_enabled`: the design's edge and every seam
        are printed by every pass, each radius by one swathe per pass. 0 (default): as before.

    Returns
    -------
    SwathePlan
        The setting and ``swathes``, a tuple of :class:`Swathe`: ``pivot_radius_mm`` (float),
        ``band_mm`` ``(low, high)`` radii the swathe prints, ``enabled`` ``(nozzles,) bool``
        (the nozzles that print in the band), ``first_track_mm``/``last_track_mm``, ``pitch_mm``.

    Raises
    ------
    GeometryError
        Tilt at or beyond the maximum, a range that would put nozzles over the axis, a
        full-density band with fewer than two tracks, or more swathes than ``max_swathes``
        (the message says how many are needed).

    Examples
    --------
    >>> from rotoprint import load_device
    >>> head = load_device("omnidot760").head
    >>> plan = plan_swathes(head, tilt_deg=0.0, inner_radius_mm=60.0, outer_radius_mm=100.0)
    >>> len(plan), int(plan.swathes[0].enabled.sum())
    (1, 568)
    """
    check_tilt(head, tilt_deg)
    if not (math.isfinite(inner_radius_mm) and math.isfinite(outer_radius_mm) and 0 < inner_radius_mm < outer_radius_mm):
        raise GeometryError(f"radial range must satisfy 0 < inner < outer, got {inner_radius_mm} .. {outer_radius_mm} mm")
    if max_swathes is not None and max_swathes < 1:
        raise ConfigError(f"max_swathes must be at least 1, got {max_swathes}")
    if not (math.isfinite(overlap_mm) and overlap_mm >= 0):
        raise ConfigError(f"swathe overlap must be >= 0 mm, got {overlap_mm!r}")
    s, t, row = nozzle_offsets(head)
    th = math.radians(tilt_deg)
    X = s * math.cos(th) - t * math.sin(th)
    Y = s * math.sin(th) + t * math.cos(th)
    R_axis = float(-X.min())  # below this pivot radius some nozzle is at or behind the axis

    rows_idx = [np.flatnonzero(row == q) for q in range(head.rows)]

    def lo_and_binding(R: float) -> tuple[float, int]:
        r = _radii(R, X, Y)
        best, kb = -np.inf, -1
        for ix in rows_idx:
            k = int(ix[np.argmin(r[ix])])
            if r[k] > best:
                best, kb = float(r[k]), k
        return best, kb

    def solve(target: float) -> float:
        a = R_axis + 1e-6
        if lo_and_binding(a)[0] > target:
            raise GeometryError(
                f"a first track at radius {target:.3f} mm needs the head's pivot so close to the axis "
                f"that nozzles would be over it (tilt {tilt_deg:g} deg); place the design further out"
            )
        # fixed point on the binding nozzle (the one that sets the band's inner edge): exact in a
        # few steps; bisection if it does not settle
        R = target - float(X[0])
        for _ in range(20):
            _, k = lo_and_binding(R)
            if target <= abs(Y[k]):
                break
            R_new = -float(X[k]) + math.sqrt(target * target - float(Y[k]) ** 2)
            if R_new == R or abs(R_new - R) < 1e-12:
                if abs(lo_and_binding(R_new)[0] - target) < 1e-9:
                    return R_new
                break
            R = R_new
        b = target - float(X.min()) + 1.0
        for _ in range(_BISECT_STEPS):
            m = 0.5 * (a + b)
            if lo_and_binding(m)[0] < target:
                a = m
            else:
                b = m
        return b

    def band_tracks(R: float):
        r = _radii(R, X, Y)
        lo, hi = _band(r, row, head.rows)
        inb = (r >= lo - _EPS_MM) & (r <= hi + _EPS_MM)
        T = np.sort(r[inb])
        if T.size < 3:
            raise GeometryError(
                f"at tilt {tilt_deg:g} deg the band where all {head.rows} rows print holds {T.size} track(s); "
                "use a smaller tilt"
            )
        return r, lo, hi, inb, T

    # first target: half a local pitch outside the inner edge (pitch estimated, then refined)
    pitch0 = head.pitch_mm * math.cos(th)
    R0 = solve(inner_radius_mm + pitch0 / 2)
    _, lo, hi, _, T = band_tracks(R0)
    pitch0 = (T[2] - T[0]) / 2
    target = inner_radius_mm + pitch0 / 2 - overlap_mm
    b_lo = inner_radius_mm

    swathes: list[Swathe] = []
    while True:
        R = solve(target)
        r, lo, hi, inb, T = band_tracks(R)
        pitch = float((T[-1] - T[-3]) / 2)
        last = hi + pitch / 2 >= outer_radius_mm
        b_hi = outer_radius_mm if last else hi + pitch / 2
        enabled = inb & (r >= b_lo - _EPS_MM) & (r < b_hi)
        nz = np.flatnonzero(enabled)
        # the layout check also rejects mounts that put nozzles over the axis
        nozzle_layout(head, Mount(R, tilt_deg=tilt_deg, mount_angle_deg=mount_angle_deg, direction=direction))
        swathes.append(
            Swathe(
                index=len(swathes),
                pivot_radius_mm=float(R),
                band_mm=(float(b_lo), float(b_hi)),
                enabled=enabled,
                first_track_mm=float(r[nz].min()),
                last_track_mm=float(r[nz].max()),
                pitch_mm=pitch,
                usable=inb,
            )
        )
        if last or len(swathes) >= _MAX_SWATHES_HARD:
            break
        b_lo = b_hi
        target = hi + pitch - overlap_mm
    if max_swathes is not None and len(swathes) > max_swathes:
        band = swathes[0].last_track_mm - swathes[0].first_track_mm
        raise GeometryError(
            f"the design spans radii {inner_radius_mm:.2f} .. {outer_radius_mm:.2f} mm "
            f"({outer_radius_mm - inner_radius_mm:.2f} mm) and needs {len(swathes)} swathes of about {band:.2f} mm "
            f"at tilt {tilt_deg:g} deg, but at most {max_swathes} allowed"
        )
    return SwathePlan(
        head=head,
        tilt_deg=float(tilt_deg),
        mount_angle_deg=float(mount_angle_deg),
        direction=int(direction),
        inner_radius_mm=float(inner_radius_mm),
        outer_radius_mm=float(outer_radius_mm),
        swathes=tuple(swathes),
        overlap_mm=float(overlap_mm),
    )


def pass_enabled(plan: SwathePlan, j: int, r_mm: np.ndarray) -> np.ndarray:
    """Nozzles that print in swathe ``j`` of a pass whose nozzles lie at radii ``r_mm``.

    Parameters
    ----------
    plan : SwathePlan
    j : int
    r_mm : (N,) float64
        Track radius of every nozzle with the pass's pivot.

    Returns
    -------
    (N,) bool
        ``plan.swathes[j].enabled`` when the plan has no overlap (as before); else the usable
        nozzles whose track lies in the swathe's band ``[lo, hi)`` (``[lo - seam_mm, hi)`` for
        every swathe but the first).
    """
    sw = plan.swathes[j]
    if plan.overlap_mm <= 0 or sw.usable is None:
        return sw.enabled
    lo, hi = sw.band_mm
    if j > 0:
        lo -= plan.seam_mm
    return sw.usable & (r_mm >= lo - _EPS_MM) & (r_mm < hi)
