"""Nozzle positions of a (tilted) print head over a rotating platform, and the paper's figures.

Conventions are those of ``shared/design/rotary-geometry.md`` section 2: nozzle ``k`` sits at
``s_k = k * p`` along the head and ``t_k`` across it (row ``k % rows``; rows evenly spaced
``row_separation_mm`` apart and centred on the head's centre line). With the pivot at radius
``R_p`` on the mount angle ``psi`` and a tilt ``theta``::

    a = (cos(psi + theta), sin(psi + theta))       # along the head
    n = (-sin(psi + theta), cos(psi + theta))      # across the head
    P_k = R_p * (cos psi, sin psi) + s_k * a + t_k * n

The paper's closed forms (equations (1)-(3)) are kept beside the exact values: the closed
forms project the nozzles onto the centre line, the exact values use ``|P_k|``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..devices.models import InkjetHead
from ..errors import ConfigError, GeometryError

__all__ = [
    "Mount",
    "NozzleLayout",
    "HeadFigures",
    "nozzle_offsets",
    "nozzle_layout",
    "max_tilt_deg",
    "check_tilt",
    "paper_figures",
    "head_figures",
]

DIRECTIONS = (1, -1)


@dataclass(frozen=True)
class Mount:
    """Where a head sits over the platform.

    Parameters
    ----------
    pivot_radius_mm : float
        Radius of the pivot (the paper's ``cx``): the point of the head's centre line at
        nozzle 0's along-head position.
    tilt_deg : float
        Angle between the head axis and the radial line through the pivot, counter-clockwise
        positive.
    mount_angle_deg : float
        Angle ``psi`` of the radial line through the pivot (0 for head 0).
    direction : int
        +1 platform turns counter-clockwise seen from above, -1 clockwise.
    """

    pivot_radius_mm: float
    tilt_deg: float = 0.0
    mount_angle_deg: float = 0.0
    direction: int = 1

    def __post_init__(self) -> None:
        if self.direction not in DIRECTIONS:
            raise ConfigError(f"direction must be +1 or -1, got {self.direction!r}")
        for name in ("pivot_radius_mm", "tilt_deg", "mount_angle_deg"):
            v = getattr(self, name)
            if not math.isfinite(v):
                raise ConfigError(f"{name} must be a finite number, got {v!r}")


@dataclass(frozen=True)
class NozzleLayout:
    """Nozzle positions in the platform frame at firing index 0.

    Attributes
    ----------
    xy_mm : (N, 2) float64
    r_mm : (N,) float64
        ``|P_k|``.
    phi_rad : (N,) float64
        ``atan2(P_k)``.
    row : (N,) int64
        Row of each nozzle (0 = row A, the leading row for ``direction = +1``).
    """

    xy_mm: np.ndarray
    r_mm: np.ndarray
    phi_rad: np.ndarray
    row: np.ndarray

    def row_ranges(self) -> list[tuple[float, float]]:
        """``(min r, max r)`` of each row, mm."""
        return [(float(self.r_mm[self.row == q].min()), float(self.r_mm[self.row == q].max())) for q in np.unique(self.row)]

    def overlap_band(self) -> tuple[float, float]:
        """Exact radial band ``(lo, hi)`` in which every row prints (empty when lo > hi)."""
        rr = self.row_ranges()
        return max(a for a, _ in rr), min(b for _, b in rr)


def nozzle_offsets(head: InkjetHead) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Along-head ``s`` (mm), across-head ``t`` (mm) and row of every nozzle.

    Parameters
    ----------
    head : InkjetHead
        Nozzle ``k`` is at ``s = k * pitch_mm`` in row ``k % rows``; rows are
        ``row_separation_mm`` apart, centred on ``t = 0``.

    Returns
    -------
    s_mm : (N,) float64
    t_mm : (N,) float64
    row : (N,) int64

    Examples
    --------
    >>> from rotoprint import load_device
    >>> s, t, row = nozzle_offsets(load_device("omnidot760").head)
    >>> s.shape, float(t[0]) == -float(t[1]), int(row[3])
    ((764,), True, 1)
    """
    k = np.arange(head.nozzles)
    row = k % head.rows
    s = k * head.pitch_mm
    t = (row - (head.rows - 1) / 2.0) * head.row_separation_mm
    return s.astype(np.float64), t.astype(np.float64), row.astype(np.int64)


def _row_extent_mm(head: InkjetHead) -> float:
    return (head.rows - 1) * head.row_separation_mm


def max_tilt_deg(head: InkjetHead) -> float:
    """Tilt at which the projected swathe ``ps cos(theta) - d sin(theta)`` reaches 0.

    Parameters
    ----------
    head : InkjetHead
        ``ps`` is its ``swathe_mm``, ``d`` the distance between its first and last rows.

    Returns
    -------
    float
        Degrees, ``atan2(ps, d)``; 90.0 for a single-row head.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> round(max_tilt_deg(load_device("omnidot760").head), 1)
    85.5
    """
    d = _row_extent_mm(head)
    return 90.0 if d == 0 else math.degrees(math.atan2(head.swathe_mm, d))


def check_tilt(head: InkjetHead, tilt_deg: float) -> None:
    """Raise :class:`GeometryError` when ``|tilt_deg|`` is at or beyond the maximum tilt.

    Parameters
    ----------
    head : InkjetHead
    tilt_deg : float
        Head tilt; only its magnitude is checked.

    Raises
    ------
    ConfigError
        ``tilt_deg`` is not finite.
    GeometryError
        ``|tilt_deg|`` is at or beyond :func:`max_tilt_deg`, or 90 degrees or more, or leaves a
        projected swathe ``ps_p_mm`` shorter than one nozzle pitch.
    """
    if not math.isfinite(tilt_deg):
        raise ConfigError(f"tilt must be a finite number of degrees, got {tilt_deg!r}")
    tmax = max_tilt_deg(head)
    ps_p = paper_figures(head, abs(tilt_deg), check=False)["ps_p_mm"] if abs(tilt_deg) < 90 else -1.0
    # "at the maximum": less than one nozzle pitch of projected swathe is left
    if abs(tilt_deg) >= tmax or ps_p < head.pitch_mm:
        raise GeometryError(
            f"tilt {tilt_deg:g} deg is at or beyond the maximum tilt {tmax:.2f} deg of this head "
            f"(the projected swathe ps*cos(tilt) - d_nzr*sin(tilt) is {ps_p:.4f} mm, less than one nozzle pitch)"
        )


def nozzle_layout(head: InkjetHead, mount: Mount) -> NozzleLayout:
    """Nozzle positions in the platform frame (firing index 0).

    Nozzle ``k`` sits at ``pivot_radius_mm * e + s_k * a + t_k * n``: ``e`` the unit radial
    line at the mount angle, ``a`` the head axis (``e`` turned by the tilt), ``n`` its normal,
    ``s_k, t_k`` the along-head and across-head offsets of :func:`nozzle_offsets`.

    Parameters
    ----------
    head : InkjetHead
        ``nozzles`` nozzles in ``rows`` staggered rows over ``swathe_mm``.
    mount : Mount
        Pivot radius (mm), tilt and mount angle (deg), direction of the platform.

    Returns
    -------
    NozzleLayout
        ``xy_mm`` ``(N, 2) float64``, ``r_mm`` and ``phi_rad`` ``(N,) float64`` (radius and
        angle of each nozzle), ``row`` ``(N,) int64``; ``N = head.nozzles``.

    Raises
    ------
    GeometryError
        A nozzle would sit at or behind the axis of rotation.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> lay = nozzle_layout(load_device("omnidot760").head, Mount(60.0, tilt_deg=0.0))
    >>> round(float(lay.xy_mm[0, 0]), 6), round(float(lay.xy_mm[0, 1]), 4)
    (60.0, -2.1167)
    """
    s, t, row = nozzle_offsets(head)
    psi = math.radians(mount.mount_angle_deg)
    th = psi + math.radians(mount.tilt_deg)
    a = np.array([math.cos(th), math.sin(th)])
    n = np.array([-math.sin(th), math.cos(th)])
    e = np.array([math.cos(psi), math.sin(psi)])
    xy = mount.pivot_radius_mm * e + s[:, None] * a + t[:, None] * n
    along_radial = xy @ e
    if (along_radial <= 0).any():
        bad = np.flatnonzero(along_radial <= 0)
        raise GeometryError(
            f"pivot radius {mount.pivot_radius_mm:.3f} mm at tilt {mount.tilt_deg:g} deg puts "
            f"{bad.size} nozzle(s) (e.g. k={int(bad[0])}) over or behind the axis of rotation; "
            "use a larger radius or a smaller tilt"
        )
    r = np.hypot(xy[:, 0], xy[:, 1])
    phi = np.arctan2(xy[:, 1], xy[:, 0])
    return NozzleLayout(xy_mm=xy, r_mm=r, phi_rad=phi, row=row)


def paper_figures(head: InkjetHead, tilt_deg: float, *, pivot_radius_mm: float = 0.0, check: bool = True) -> dict:
    """The paper's closed forms (1)-(3) at one tilt (sign of the tilt ignored).

    Returns a dict with ``cx_T_mm`` (1), ``ps_p_mm`` (2), ``dpi_xp`` (3), ``pitch_radial_mm``
    (``p cos(theta)``, Figure 5 (b)), ``single_row_band_mm`` (``d sin(theta)``).

    Parameters
    ----------
    head : InkjetHead
    tilt_deg : float
        Head tilt; the formulas use ``|tilt_deg|``.
    pivot_radius_mm : float
        Radius of the pivot; only ``cx_T_mm`` depends on it.
    check : bool
        First call :func:`check_tilt` (and raise what it raises).

    Returns
    -------
    dict
        The keys above as floats (lengths in mm, ``dpi_xp`` in drops per inch), and
        ``tilt_deg`` as given.

    Raises
    ------
    ConfigError, GeometryError
        With ``check=True``: see :func:`check_tilt`.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> f = paper_figures(load_device("omnidot760").head, 60.0, pivot_radius_mm=50.0)
    >>> round(f["dpi_xp"], 2), round(f["ps_p_mm"], 3), round(f["cx_T_mm"], 4)
    (721.4, 23.234, 51.8331)
    """
    if check:
        check_tilt(head, tilt_deg)
    th = math.radians(abs(tilt_deg))
    d = _row_extent_mm(head)
    p = head.pitch_mm
    return {
        "tilt_deg": float(tilt_deg),
        "cx_T_mm": pivot_radius_mm + d * math.sin(th) / 2.0,
        "ps_p_mm": head.swathe_mm * math.cos(th) - d * math.sin(th),
        "dpi_xp": 25.4 * (head.nozzles / head.swathe_mm) / math.cos(th),
        "pitch_radial_mm": p * math.cos(th),
        "single_row_band_mm": d * math.sin(th),
    }


@dataclass(frozen=True)
class HeadFigures:
    """Paper and exact figures of a head at one tilt and pivot radius (see :func:`head_figures`)."""

    tilt_deg: float
    pivot_radius_mm: float
    paper: dict
    overlap_band_mm: tuple[float, float]
    inner_single_row_band_mm: tuple[float, float]
    outer_single_row_band_mm: tuple[float, float]
    tracks_in_band: int
    pitch_radial_min_mm: float
    pitch_radial_max_mm: float
    largest_track_gap_mm: float
    smallest_track_gap_mm: float
    max_tilt_deg: float
    dead_nozzles: tuple[int, ...] = field(default=())

    def to_json(self) -> dict:
        lo, hi = self.overlap_band_mm
        return {
            "tilt_deg": self.tilt_deg,
            "pivot_radius_mm": self.pivot_radius_mm,
            "paper": self.paper,
            "exact": {
                "overlap_band_mm": [lo, hi],
                "projected_swathe_mm": max(0.0, hi - lo),
                "inner_single_row_band_mm": list(self.inner_single_row_band_mm),
                "outer_single_row_band_mm": list(self.outer_single_row_band_mm),
                "tracks_in_band": self.tracks_in_band,
                "pitch_radial_min_mm": self.pitch_radial_min_mm,
                "pitch_radial_max_mm": self.pitch_radial_max_mm,
                "largest_track_gap_mm": self.largest_track_gap_mm,
                "smallest_track_gap_mm": self.smallest_track_gap_mm,
                "dead_nozzles": list(self.dead_nozzles),
            },
            "max_tilt_deg": self.max_tilt_deg,
        }


def track_gaps(radii_mm: np.ndarray) -> np.ndarray:
    """Gaps between neighbouring tracks, ``(M-1,) float64``, from track radii in any order."""
    r = np.sort(np.asarray(radii_mm, dtype=np.float64))
    return np.diff(r)


def head_figures(head: InkjetHead, *, tilt_deg: float, pivot_radius_mm: float, mount_angle_deg: float = 0.0) -> HeadFigures:
    """Paper closed forms and exact figures from the nozzle positions, for one tilt.

    The exact figures: the band in which every row prints (``overlap_band_mm``), the bands
    where only one row prints, the radial pitch between successive nozzles of a row
    (divided by ``rows`` so it compares with ``p cos(theta)``), and the largest and smallest
    gap between neighbouring live tracks inside the band (a dead nozzle widens the gap).

    Parameters
    ----------
    head : InkjetHead
        Its ``dead_nozzles`` are left out of ``tracks_in_band`` and the track gaps.
    tilt_deg : float
    pivot_radius_mm : float
    mount_angle_deg : float
        Angle of the radial line through the pivot (see :class:`Mount`).

    Returns
    -------
    HeadFigures
        Lengths in mm; the pitch and gap figures are NaN when there is nothing to measure.

    Raises
    ------
    ConfigError
        ``tilt_deg``, ``pivot_radius_mm`` or ``mount_angle_deg`` is not finite.
    GeometryError
        The tilt is at or beyond the head's maximum (see :func:`check_tilt`), or a nozzle
        would sit at or behind the axis of rotation.
    """
    paper = paper_figures(head, tilt_deg, pivot_radius_mm=pivot_radius_mm)
    lay = nozzle_layout(head, Mount(pivot_radius_mm, tilt_deg=tilt_deg, mount_angle_deg=mount_angle_deg))
    lo, hi = lay.overlap_band()
    rr = lay.row_ranges()
    inner = (min(a for a, _ in rr), lo)
    outer = (hi, max(b for _, b in rr))
    live = np.ones(head.nozzles, dtype=bool)
    live[list(head.dead_nozzles)] = False
    eps = 1e-9
    in_band = (lay.r_mm >= lo - eps) & (lay.r_mm <= hi + eps)
    gaps = track_gaps(lay.r_mm[in_band & live])
    steps = []
    for q in range(head.rows):
        rq = lay.r_mm[lay.row == q]
        steps.append(np.abs(np.diff(rq)) / head.rows)
    steps_all = np.concatenate(steps) if steps else np.zeros(0)
    return HeadFigures(
        tilt_deg=float(tilt_deg),
        pivot_radius_mm=float(pivot_radius_mm),
        paper=paper,
        overlap_band_mm=(float(lo), float(hi)),
        inner_single_row_band_mm=(float(inner[0]), float(inner[1])),
        outer_single_row_band_mm=(float(outer[0]), float(outer[1])),
        tracks_in_band=int((in_band & live).sum()),
        pitch_radial_min_mm=float(steps_all.min()) if steps_all.size else float("nan"),
        pitch_radial_max_mm=float(steps_all.max()) if steps_all.size else float("nan"),
        largest_track_gap_mm=float(gaps.max()) if gaps.size else float("nan"),
        smallest_track_gap_mm=float(gaps.min()) if gaps.size else float("nan"),
        max_tilt_deg=max_tilt_deg(head),
        dead_nozzles=tuple(head.dead_nozzles),
    )
