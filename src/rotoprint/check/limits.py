"""The smallest wall and gap a device prints for sure, and what a tilted head changes.

For a raster of pitch ``p`` sampled at pixel centres, a wall at least ``p`` wide always holds a
pixel centre (a drop track or an exposed pixel), whatever its position; a narrower one can fall
between two centres and vanish. The same holds for gaps. An inkjet drop of diameter ``d``
spreads over its neighbours: a gap of ``n`` empty tracks stays open by ``(n + 1) p - d``, so
``n`` must satisfy ``(n + 1) p > d``. With an exposure model (a function making a grey mask of
a binary image, e.g. the paper's SMOOTH filter) the number of pixels a wall needs to cure and a
gap needs to stay dark is found by simulating strips of 1, 2, ... pixels.

Rotary figures follow ``shared/design/rotary-geometry.md`` sections 2, 3, 6 and 7. They are
computed here from those few formulas (nozzle positions of a tilted head, track radii, firing
clock) so that the check does not depend on the rotary transform module.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..errors import ConfigError

__all__ = ["default_minimum_mm", "device_limits", "rotary_tracks"]


def default_minimum_mm(device) -> tuple[float, str]:
    """The default minimum wall and gap for ``device`` (mm) and where it comes from.

    The larger pixel pitch; for an inkjet head the drop diameter when it is larger.

    Examples
    --------
    >>> from rotoprint.devices import load_device
    >>> round(default_minimum_mm(load_device("perfactory-sxga"))[0] * 1000, 2)
    19.84
    >>> round(default_minimum_mm(load_device("omnidot760"))[0] * 1000, 2)
    70.56
    """
    from ..devices import as_device

    device = as_device(device)
    pitch = max(device.pitch_x_mm, device.pitch_y_mm)
    if getattr(device, "kind", None) == "inkjet":
        drop = device.head.drop_diameter_um / 1000.0
        if drop > pitch:
            return drop, f"drop diameter {device.head.drop_diameter_um:g} um"
    return pitch, f"pixel pitch {pitch * 1000:.2f} um"


def _strip_pixels_needed(mask_fn: Callable[[np.ndarray], np.ndarray], threshold: float, *, gap: bool, axis: int) -> int | None:
    """Smallest number of pixels ``n`` (1..8) for which a strip of ``n`` material pixels
    cures (``gap=False``: peak grey >= threshold) or ``n`` empty pixels between material stay
    dark (``gap=True``: lowest grey < threshold), across ``axis`` (1: a column strip)."""
    size = 32
    for n in range(1, 9):
        img = np.full((size, size), 255 if gap else 0, np.uint8)
        lo = size // 2 - n // 2
        sl = (slice(None), slice(lo, lo + n)) if axis == 1 else (slice(lo, lo + n), slice(None))
        img[sl] = 0 if gap else 255
        grey = np.asarray(mask_fn(img), dtype=np.float64) / 255.0
        band = grey[sl][4:-4, :] if axis == 1 else grey[sl][:, 4:-4]
        if gap:
            # the gap is open if along its whole length some pixel across it stays dark
            ok = bool(np.all(band.min(axis=axis) < threshold))
        else:
            ok = bool(np.all(band.max(axis=axis) >= threshold))
        if ok:
            return n
    return None


def rotary_tracks(device, *, tilt_deg: float, radius_mm: float) -> dict:
    """Track radii of a tilted inkjet head over the rotary platform and the figures they give.

    Parameters
    ----------
    device : InkjetDevice
    tilt_deg : float
        Head tilt from the radial line through the pivot, degrees.
    radius_mm : float
        Pivot radius ``R_p`` (the paper's ``cx``): where nozzle 0 sits.

    Returns
    -------
    dict
        ``track_pitch_nominal_mm`` (``p cos(tilt)``), ``row_offset_mm``
        (``p cos(tilt) + d_nzr sin(tilt)``), ``largest_track_gap_mm`` (between neighbouring
        tracks, over the band where every row prints), ``largest_track_gap_all_mm`` (over every
        track), ``projected_swathe_mm`` (paper eq. 2), ``dpi_x_projected`` (eq. 3),
        ``along_track_spacing_mm`` at the inner and outer track for a clock set at the inner
        track, ``track_radii_mm`` range.

    Examples
    --------
    >>> from rotoprint.devices import load_device
    >>> r = rotary_tracks(load_device("omnidot760"), tilt_deg=0.0, radius_mm=60.0)
    >>> round(r["largest_track_gap_mm"] * 1000, 1)
    70.4
    """
    from ..devices import as_device

    device = as_device(device)
    if getattr(device, "kind", None) != "inkjet":
        raise ConfigError(f"rotary figures need an inkjet head, got a {getattr(device, 'kind', '?')} device")
    if not (math.isfinite(tilt_deg) and -90.0 < tilt_deg < 90.0):
        raise ConfigError(f"tilt must be between -90 and 90 degrees, got {tilt_deg}")
    if not (math.isfinite(radius_mm) and radius_mm > 0):
        raise ConfigError(f"radius must be a positive number of mm, got {radius_mm}")
    h = device.head
    p = h.pitch_mm
    d = h.row_separation_mm
    th = math.radians(tilt_deg)
    k = np.arange(h.nozzles)
    alive = np.ones(h.nozzles, bool)
    alive[list(h.dead_nozzles)] = False
    row = k % h.rows
    s = k * p
    t = (row - (h.rows - 1) / 2.0) * d
    a = np.array([math.cos(th), math.sin(th)])
    n = np.array([-math.sin(th), math.cos(th)])
    P = np.array([radius_mm, 0.0]) + s[:, None] * a + t[:, None] * n
    r = np.hypot(P[:, 0], P[:, 1])
    r_alive = np.sort(r[alive])
    gaps = np.diff(r_alive)
    lo = max(r[(row == j) & alive].min() for j in range(h.rows))
    hi = min(r[(row == j) & alive].max() for j in range(h.rows))
    inband = (r_alive[:-1] >= lo - 1e-12) & (r_alive[1:] <= hi + 1e-12)
    gap_band = float(gaps[inband].max()) if inband.any() else float("nan")
    dphi = (25.4 / h.dpi_y) / float(r_alive[0])
    return {
        "tilt_deg": float(tilt_deg),
        "radius_mm": float(radius_mm),
        "nozzle_pitch_mm": p,
        "track_pitch_nominal_mm": p * math.cos(th),
        "row_offset_mm": p * math.cos(th) + d * math.sin(abs(th)),
        "largest_track_gap_mm": gap_band,
        "largest_track_gap_all_mm": float(gaps.max()) if gaps.size else float("nan"),
        "smallest_track_gap_mm": float(gaps[inband].min()) if inband.any() else float("nan"),
        "projected_swathe_mm": h.swathe_mm * math.cos(th) - d * math.sin(abs(th)),
        "dpi_x_projected": 25.4 * (h.nozzles / h.swathe_mm) / math.cos(th),
        "track_radii_mm": [float(r_alive[0]), float(r_alive[-1])],
        "along_track_spacing_mm": [float(r_alive[0] * dphi), float(r_alive[-1] * dphi)],
        "note": "clock set for dpi_y at the innermost track; drops thin out as 1/r outward",
    }


def device_limits(
    device,
    *,
    mask_fn: Callable[[np.ndarray], np.ndarray] | None = None,
    cure_threshold: float | None = None,
    tilt_deg: float | None = None,
    radius_mm: float | None = None,
) -> dict:
    """The smallest wall and gap that survive on ``device`` whatever their position (mm).

    Parameters
    ----------
    device : InkjetDevice or ProjectorDevice
    mask_fn : callable, optional
        ``(H, W) uint8`` binary image (255 material) to ``(H, W) uint8`` grey mask; projectors
        only. Without it every material pixel is taken to cure.
    cure_threshold : float, optional
        Fraction of full exposure a pixel needs to cure; default the projector's own.
    tilt_deg, radius_mm : float, optional
        Inkjet on the rotary platform: adds :func:`rotary_tracks` figures, and the radial
        (ring-wall) limit becomes the largest gap between neighbouring tracks.

    Returns
    -------
    dict
        ``min_wall_mm`` and ``min_gap_mm`` (any direction), per direction ``*_x_mm`` /
        ``*_y_mm``, and ``basis`` (one sentence on where they come from).

    Examples
    --------
    >>> from rotoprint.devices import load_device
    >>> lim = device_limits(load_device("omnidot760"))
    >>> round(lim["min_wall_mm"] * 1000, 1), round(lim["min_gap_mm"] * 1000, 1)
    (70.6, 70.6)
    """
    from ..devices import as_device

    device = as_device(device)
    px, py = device.pitch_x_mm, device.pitch_y_mm
    out: dict = {"device": device.name, "kind": device.kind, "pitch_x_mm": px, "pitch_y_mm": py}
    if device.kind == "projector":
        thr = device.projector.cure_threshold if cure_threshold is None else float(cure_threshold)
        nwx = nwy = ngx = ngy = 1
        basis = "one pixel: a feature at least one pitch wide always covers a pixel centre"
        if mask_fn is not None:
            nwx = _strip_pixels_needed(mask_fn, thr, gap=False, axis=1)
            nwy = _strip_pixels_needed(mask_fn, thr, gap=False, axis=0)
            ngx = _strip_pixels_needed(mask_fn, thr, gap=True, axis=1)
            ngy = _strip_pixels_needed(mask_fn, thr, gap=True, axis=0)
            basis = f"pixels a strip needs under the exposure model to cure (walls) or stay dark (gaps) at threshold {thr:g}"
        out["cure_threshold"] = thr
        vals = {"min_wall_x_mm": nwx, "min_wall_y_mm": nwy, "min_gap_x_mm": ngx, "min_gap_y_mm": ngy}
        for key, nn in vals.items():
            out[key] = None if nn is None else nn * (px if key.endswith("x_mm") else py)
    else:
        drop = device.head.drop_diameter_um / 1000.0
        n_gap_x = max(1, math.floor(drop / px - 1.0) + 1)
        n_gap_y = max(1, math.floor(drop / py - 1.0) + 1)
        out.update(
            {
                "drop_diameter_mm": drop,
                "min_wall_x_mm": px,
                "min_wall_y_mm": py,
                "min_gap_x_mm": n_gap_x * px,
                "min_gap_y_mm": n_gap_y * py,
            }
        )
        basis = (
            "one track across the head (nozzle pitch) and one firing along it; a gap needs n empty tracks "
            "with (n + 1) pitch > drop diameter so that spreading drops do not bridge it"
        )
        if tilt_deg is not None or radius_mm is not None:
            if tilt_deg is None or radius_mm is None:
                raise ConfigError("rotary figures need both a tilt (deg) and a pivot radius (mm)")
            rot = rotary_tracks(device, tilt_deg=tilt_deg, radius_mm=radius_mm)
            out["rotary"] = rot
            g = rot["largest_track_gap_mm"]
            along = rot["along_track_spacing_mm"][1]
            n_gap_r = max(1, math.floor(drop / g - 1.0) + 1) if g > 0 else 1
            out["min_wall_x_mm"] = g  # across the tracks (radial)
            out["min_wall_y_mm"] = along  # along the tracks, at the outermost track
            out["min_gap_x_mm"] = n_gap_r * g
            out["min_gap_y_mm"] = max(1, math.floor(drop / along - 1.0) + 1) * along
            basis = (
                f"rotary, tilt {tilt_deg:g} deg: across tracks the largest gap between neighbouring tracks, "
                "along them the firing spacing at the outermost track"
            )
    walls = [v for k, v in out.items() if k.startswith("min_wall_") and v is not None]
    gaps = [v for k, v in out.items() if k.startswith("min_gap_") and v is not None]
    missing = any(out.get(k) is None for k in ("min_wall_x_mm", "min_wall_y_mm"))
    out["min_wall_mm"] = None if missing or not walls else max(walls)
    missing_g = any(out.get(k) is None for k in ("min_gap_x_mm", "min_gap_y_mm"))
    out["min_gap_mm"] = None if missing_g or not gaps else max(gaps)
    out["basis"] = basis
    return out
