"""Forward drop placement and a comparison with the design (``rotary-geometry.md`` s. 3 and 8).

Every drop of a :class:`RotaryPrint` is placed with the forward formula
``(r_k, phi_k - direction * i * dphi)``, optionally misdirected (Gaussian jitter) and with
extra dead nozzles, then rendered on the design's pixel grid and compared with the design.

Definitions (design grid, pixel ``(j, c)`` covering ``[c, c+1) x [j, j+1)``):

- *printed* (cell model, the one behind ``iou``): a pixel whose centre is nearer to a fired
  drop site than to any site that did not fire. The sites are every (firing, enabled nozzle)
  of every swathe, i.e. the lattice the machine can print; the model assumes drops merge
  into a film that fills the lattice cells, so it judges where the transform puts ink.
- *printed* (disc model, ``disc_*``): a pixel in which a drop lands or whose centre lies
  within half a drop diameter of a drop. With small drops it shows the stripes that open
  where the tracks of two rows nearly coincide.
- *IoU*: |printed and inked| / |printed or inked|; *area ratio*: |printed| / |inked|.
- *placement error* of a drop: distance from its landing point to the centre of the nearest
  inked design pixel (the pixel it stands for when it lands on ink; for a stray drop, the
  nearest pixel it could have stood for).
- *uncovered*: inked pixels that are not printed; *drops outside*: drops whose landing point
  is not on an inked pixel.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .._resources import check_raster_fits
from ..ranges import DROP_UM, JITTER_UM, check_range
from ..errors import ConfigError, ImageError
from .head import Mount, nozzle_layout
from .printdata import RotaryPrint, design_kind, design_levels

__all__ = ["Drops", "FiringClock", "SimulationReport", "Simulation", "place_drops", "landing_xy", "simulate", "render_overlay", "design_mask"]


@dataclass(frozen=True)
class FiringClock:
    """When a swathe's firings fire, as a machine's clock gives it (not the nominal ``i * dphi``).

    Firing ``i`` fires when the platform has turned ``turn_at_ref_rad + (i - ref_firing) *
    dphi_rad`` (rad, from the index pulse); e.g. a firing clock made from an encoder by an
    integer multiplier and divider, started a whole number of encoder counts after the index
    (:mod:`rotoprint.machine.replay`).
    """

    ref_firing: int
    turn_at_ref_rad: float
    dphi_rad: float

    def turn_rad(self, firing: np.ndarray) -> np.ndarray:
        """``(M,) float64``: the angle turned at each of ``firing`` ``(M,) int64``."""
        return self.turn_at_ref_rad + (firing - self.ref_firing) * self.dphi_rad


@dataclass(frozen=True, eq=False)
class Drops:
    """Placed drops. ``x_mm, y_mm`` ``(M,) float64`` in the platform frame; ``col, row``
    ``(M,) float64`` continuous design coordinates; ``level, swathe`` ``(M,) uint8 / int16``;
    ``nozzle, firing`` ``(M,) int64``."""

    x_mm: np.ndarray
    y_mm: np.ndarray
    col: np.ndarray
    row: np.ndarray
    level: np.ndarray
    swathe: np.ndarray
    nozzle: np.ndarray
    firing: np.ndarray

    def __len__(self) -> int:
        return int(self.x_mm.size)


def place_drops(pr: RotaryPrint, *, jitter_um: float = 0.0, dead_nozzles: tuple[int, ...] = (), seed: int = 0,
                clocks: dict[int, FiringClock] | None = None) -> Drops:
    """Land every drop of ``pr`` with the forward formula (no knowledge of the transform used).

    Nozzle ``k`` of swathe ``s`` fired at firing ``i`` lands at radius ``r_k`` and angle
    ``phi_k - direction * i * dphi_rad`` in the platform frame (``nozzle_layout`` of the
    swathe's pivot, the print's tilt, mount angle and direction).

    Parameters
    ----------
    pr : RotaryPrint
        The print; each swathe's ``levels`` is ``(firings, nozzles) uint8``, 0 = no drop.
    jitter_um : float
        Standard deviation of a Gaussian landing error added to x and y, um (``>= 0``).
    dead_nozzles : tuple of int
        Nozzle indices (``0 <= k < nozzles``) that do not fire.
    seed : int
        Seed of the jitter's random generator.
    clocks : dict of int to FiringClock, optional
        Per swathe index, the angle each firing really fires at (instead of ``i * dphi_rad``).

    Returns
    -------
    Drops
        ``M`` drops: ``x_mm, y_mm`` ``(M,) float64`` platform frame; ``col, row`` ``(M,)
        float64`` continuous design coordinates; ``level`` ``(M,) uint8``; ``swathe`` ``(M,)
        int16``; ``nozzle, firing`` ``(M,) int64``. Swathe by swathe, row-major within one.

    Raises
    ------
    ConfigError
        Negative or non-finite jitter, a dead nozzle index out of range.
    ImageError
        A swathe image whose column count is not the head's nozzle count.
    """
    if jitter_um < 0 or not math.isfinite(jitter_um):
        raise ConfigError(f"jitter must be >= 0 um, got {jitter_um}")
    n = pr.head.nozzles
    bad = [k for k in dead_nozzles if not 0 <= k < n]
    if bad:
        raise ConfigError(f"dead nozzle indices must be in 0..{n - 1}, got {bad}")
    rng = np.random.default_rng(seed)
    parts = []
    for sw in pr.swathes:
        if sw.levels.shape[1] != n:
            raise ImageError(f"swathe {sw.index} image has {sw.levels.shape[1]} columns, the head has {n} nozzles")
        lev = sw.levels
        if dead_nozzles:
            lev = lev.copy()
            lev[:, list(dead_nozzles)] = 0
        b, k = np.nonzero(lev)
        i = b.astype(np.int64) + sw.first_firing
        x, y = landing_xy(pr, sw, k, i, clocks.get(sw.index) if clocks else None)
        if jitter_um > 0:
            x = x + rng.normal(0.0, jitter_um * 1e-3, x.size)
            y = y + rng.normal(0.0, jitter_um * 1e-3, y.size)
        parts.append((x, y, lev[b, k], np.full(b.size, sw.index, np.int16), k.astype(np.int64), i))
    if parts:
        x, y, lv, s, k, i = (np.concatenate(p) for p in zip(*parts))
    else:  # pragma: no cover - a print always has a swathe
        x = y = np.zeros(0)
        lv, s, k, i = np.zeros(0, np.uint8), np.zeros(0, np.int16), np.zeros(0, np.int64), np.zeros(0, np.int64)
    col, row = pr.placement.to_design(x, y)
    return Drops(x_mm=x, y_mm=y, col=col, row=row, level=lv, swathe=s, nozzle=k, firing=i)


def landing_xy(pr: RotaryPrint, sw, nozzle: np.ndarray, firing: np.ndarray, clock: FiringClock | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Platform ``(x, y)`` mm, each ``(M,) float64``, of the drops of swathe ``sw`` of ``pr`` fired by
    ``nozzle`` at absolute ``firing`` (``(M,) int64`` each): the forward formula of :func:`place_drops`
    (``clock``: the angle each firing really fires at, instead of ``i * dphi_rad``)."""
    lay = nozzle_layout(pr.head, Mount(sw.pivot_radius_mm, tilt_deg=pr.tilt_deg, mount_angle_deg=pr.mount_angle_deg, direction=pr.direction))
    ang = lay.phi_rad[nozzle] - pr.direction * (firing * sw.dphi_rad if clock is None else clock.turn_rad(firing))
    return lay.r_mm[nozzle] * np.cos(ang), lay.r_mm[nozzle] * np.sin(ang)


def design_mask(design: np.ndarray, grey_levels: int) -> np.ndarray:
    """``(H, W) bool``: pixels the design asks to print (binary: non-zero; grey: >= one level).

    Parameters
    ----------
    design : (H, W) uint8
        The design image; see :func:`~rotoprint.rotary.printdata.design_kind`.
    grey_levels : int
        Drop levels of the head; a grey pixel prints when it rounds to at least level 1
        (see :func:`~rotoprint.rotary.printdata.design_levels`).

    Returns
    -------
    (H, W) bool ndarray
    """
    kind = design_kind(design)
    return design_levels(design, grey_levels, kind=kind) > 0


@dataclass(frozen=True)
class SimulationReport:
    drops: int
    drops_per_swathe: tuple[int, ...]
    design_pixels: int
    printed_pixels: int
    iou: float
    area_ratio: float
    mean_error_px: float
    max_error_px: float
    mean_error_um: float
    max_error_um: float
    uncovered_pixels: int
    uncovered_fraction: float
    uncovered_area_mm2: float
    drops_outside: int
    drops_outside_fraction: float
    disc_iou: float
    disc_uncovered_fraction: float
    drop_diameter_um: float
    jitter_um: float

    def to_json(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in self.__dict__.items()}


@dataclass(frozen=True, eq=False)
class Simulation:
    report: SimulationReport
    drops: Drops
    printed: np.ndarray  # (H, W) bool
    inked: np.ndarray  # (H, W) bool
    drop_on_ink: np.ndarray  # (M,) bool
    error_px: np.ndarray  # (M,) float64


_DISC_LOOP_FACTOR = 64  # stamp loop while its work is under this many passes over the design


def _printed_mask(drops: Drops, shape: tuple[int, int], px: float, py: float, radius_mm: float) -> np.ndarray:
    h, w = shape
    printed = np.zeros(shape, bool)
    c0 = np.floor(drops.col).astype(np.int64)
    r0 = np.floor(drops.row).astype(np.int64)
    inside = (c0 >= 0) & (c0 < w) & (r0 >= 0) & (r0 < h)
    printed[r0[inside], c0[inside]] = True
    wx = int(math.ceil(radius_mm / px)) + 1
    wy = int(math.ceil(radius_mm / py)) + 1
    r2 = radius_mm * radius_mm
    if (2 * wx + 1) * (2 * wy + 1) * max(len(c0), 1) > _DISC_LOOP_FACTOR * h * w:
        # large discs: the stamp loop would cost (window x drops); a nearest-drop query costs
        # one lookup per pixel whatever the radius, and marks the same pixels (a pixel centre
        # within the radius of some drop is within it of the nearest one)
        from scipy.spatial import cKDTree

        if len(c0):
            jj, cc = np.divmod(np.arange(h * w, dtype=np.int64), w)
            tree = cKDTree(np.column_stack((drops.col * px, drops.row * py)))
            dist, _ = tree.query(np.column_stack(((cc + 0.5) * px, (jj + 0.5) * py)), distance_upper_bound=radius_mm * (1 + 1e-12))
            near = dist <= radius_mm
            printed.reshape(-1)[near] = True
        return printed
    for dr in range(-wy, wy + 1):
        for dc in range(-wx, wx + 1):
            c = c0 + dc
            r = r0 + dr
            ok = (c >= 0) & (c < w) & (r >= 0) & (r < h)
            dx = (drops.col - (c + 0.5)) * px
            dy = (drops.row - (r + 0.5)) * py
            ok &= dx * dx + dy * dy <= r2
            printed[r[ok], c[ok]] = True
    return printed


def _cell_mask(pr: RotaryPrint, shape: tuple[int, int], dead_nozzles, drops: Drops, jittered: bool) -> np.ndarray:
    """Cell model: each pixel centre takes the state of its nearest drop site (see module doc).

    Candidates are the two tracks on each side of the pixel's radius in the swathe owning that
    radius, each at its nearest firing; jittered drops are used where they fired.
    """
    h, w = shape
    pl = pr.placement
    jj, cc = np.divmod(np.arange(h * w, dtype=np.int64), w)
    X, Y = pl.to_platform(cc + 0.5, jj + 0.5)
    rho = np.hypot(X, Y)
    phi = np.arctan2(Y, X)
    printed = np.zeros(h * w, bool)
    sig = pr.direction
    # fired drops with jitter: look up by (swathe, firing, nozzle)
    jit = {}
    if jittered:
        for s in np.unique(drops.swathe):
            m = drops.swathe == s
            jit[int(s)] = (drops.firing[m], drops.nozzle[m], drops.x_mm[m], drops.y_mm[m])
    nsw = len(pr.swathes)
    for sw in pr.swathes:
        lo, hi = sw.band_mm
        sel = np.ones(h * w, bool)
        if sw.index > 0:
            sel &= rho >= lo
        if sw.index < nsw - 1:
            sel &= rho < hi
        if not sel.any():
            continue
        lay = nozzle_layout(pr.head, Mount(sw.pivot_radius_mm, tilt_deg=pr.tilt_deg, mount_angle_deg=pr.mount_angle_deg, direction=sig))
        lev = sw.levels
        if dead_nozzles:
            lev = lev.copy()
            lev[:, list(dead_nozzles)] = 0
        en = np.flatnonzero(sw.enabled) if sw.enabled is not None else np.arange(pr.head.nozzles)
        order = np.argsort(lay.r_mm[en], kind="stable")
        ks = en[order]
        rk = lay.r_mm[ks]
        px_, py_, rho_s, phi_s = X[sel], Y[sel], rho[sel], phi[sel]
        pos = np.searchsorted(rk, rho_s)
        best = np.full(rho_s.size, np.inf)
        fired_best = np.zeros(rho_s.size, bool)
        n_f = lev.shape[0]
        if jittered and sw.index in jit:
            fi, fk, fx, fy = jit[sw.index]
            key = (fi - sw.first_firing) * pr.head.nozzles + fk
            srt = np.argsort(key)
            key_s, fx_s, fy_s = key[srt], fx[srt], fy[srt]
        for off in (-2, -1, 0, 1):
            q = np.clip(pos + off, 0, ks.size - 1)
            k = ks[q]
            # the angle turned since firing 0, taken within half a turn of the swathe's middle
            # firing (not of firing 0: a design half a turn from the head has i near pi / dphi)
            mid = sig * (sw.first_firing + 0.5 * n_f) * sw.dphi_rad
            dphi = np.mod(lay.phi_rad[k] - phi_s - mid + np.pi, 2 * np.pi) - np.pi + mid
            i = np.rint(sig * dphi / sw.dphi_rad).astype(np.int64)
            ang = lay.phi_rad[k] - sig * i * sw.dphi_rad
            sx = lay.r_mm[k] * np.cos(ang)
            sy = lay.r_mm[k] * np.sin(ang)
            b = i - sw.first_firing
            inr = (b >= 0) & (b < n_f)
            fired = inr & (lev[np.clip(b, 0, n_f - 1), k] > 0)
            if jittered and sw.index in jit and fired.any():
                kk = b[fired] * pr.head.nozzles + k[fired]
                t = np.searchsorted(key_s, kk)
                sx[fired] = fx_s[t]
                sy[fired] = fy_s[t]
            d2 = (sx - px_) ** 2 + (sy - py_) ** 2
            better = d2 < best
            best = np.where(better, d2, best)
            fired_best = np.where(better, fired, fired_best)
        printed[np.flatnonzero(sel)] = fired_best
    return printed.reshape(h, w)


def simulate(
    pr: RotaryPrint,
    design: np.ndarray,
    *,
    drop_diameter_um: float | None = None,
    jitter_um: float = 0.0,
    dead_nozzles: tuple[int, ...] = (),
    seed: int = 0,
    clocks: dict[int, FiringClock] | None = None,
) -> Simulation:
    """Place the drops of ``pr`` and compare them with ``design`` ``(H, W) uint8``.

    Parameters
    ----------
    pr : RotaryPrint
        The print to simulate; its ``placement`` is ``H x W`` px.
    design : (H, W) uint8 array
        The design the print was made from (binary 0/255 or grey levels).
    drop_diameter_um : float, optional
        Dot diameter for the disc model, um (default: the head's ``drop_diameter_um``).
    jitter_um, dead_nozzles, seed, clocks
        As in :func:`place_drops`. Drops moved off their sites (jitter, ``clocks``) print the
        cells of their sites from where they land.

    Returns
    -------
    Simulation
        ``report`` (:class:`SimulationReport`: IoU, area ratio, placement errors in px and um,
        uncovered area, drops outside the design), ``drops`` (:class:`Drops`, ``M`` drops),
        ``printed`` and ``inked`` ``(H, W) bool`` (cell model and design), ``drop_on_ink``
        ``(M,) bool``, ``error_px`` ``(M,) float64`` (distance of each drop to the nearest
        inked pixel centre, in design pixels).

    Raises
    ------
    ImageError
        ``design`` is not the size the print was made for.
    ConfigError
        Negative or non-finite drop diameter or jitter, a dead nozzle out of range.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> from rotoprint.rotary import Placement, transform_exact
    >>> head = load_device("omnidot760").head
    >>> design = np.zeros((60, 60), np.uint8); design[10:50, 10:50] = 255
    >>> pl = Placement(60, 60, 25.4 / 360, 25.4 / 360, inner_radius_mm=60.0)
    >>> sim = simulate(transform_exact(design, head, pl, tilt_deg=20.0), design)
    >>> sim.report.iou > 0.95, sim.report.mean_error_px < 0.5
    (True, True)
    """
    pl = pr.placement
    design = np.asarray(design)
    if design.shape != (pl.height_px, pl.width_px):
        raise ImageError(f"design is {design.shape[1]} x {design.shape[0]} px, the print was made for {pl.width_px} x {pl.height_px} px")
    d_um = pr.head.drop_diameter_um if drop_diameter_um is None else float(drop_diameter_um)
    if drop_diameter_um is not None:
        d_um = check_range(d_um, DROP_UM, "drop diameter (um)")
    check_range(jitter_um, JITTER_UM, "jitter (um)")
    # the cell model and the disc model keep about 14 float64 arrays per design pixel
    check_raster_fits(pl.width_px, pl.height_px, 112, what="the simulation of a design")
    drops = place_drops(pr, jitter_um=jitter_um, dead_nozzles=dead_nozzles, seed=seed, clocks=clocks)
    inked = design_mask(design, pr.head.grey_levels)
    px, py = pl.pitch_x_mm, pl.pitch_y_mm
    printed_disc = _printed_mask(drops, inked.shape, px, py, d_um * 1e-3 / 2)
    printed = _cell_mask(pr, inked.shape, dead_nozzles, drops, jitter_um > 0 or bool(clocks))
    h, w = inked.shape
    c0 = np.clip(np.floor(drops.col).astype(np.int64), 0, w - 1)
    r0 = np.clip(np.floor(drops.row).astype(np.int64), 0, h - 1)
    in_img = (drops.col >= 0) & (drops.col < w) & (drops.row >= 0) & (drops.row < h)
    on_ink = in_img & inked[r0, c0]
    n_ink = int(inked.sum())
    if n_ink:
        _, (ir, ic) = ndimage.distance_transform_edt(~inked, sampling=(py, px), return_indices=True)
        nr, nc = ir[r0, c0], ic[r0, c0]
        err_mm = np.hypot((drops.col - (nc + 0.5)) * px, (drops.row - (nr + 0.5)) * py)
    else:
        err_mm = np.full(len(drops), np.nan)
    pitch = math.sqrt(px * py)
    err_px = err_mm / pitch
    inter = int((printed & inked).sum())
    union = int((printed | inked).sum())
    uncovered = int((inked & ~printed).sum())
    d_union = int((printed_disc | inked).sum())
    disc_iou = int((printed_disc & inked).sum()) / d_union if d_union else 1.0
    disc_unc = int((inked & ~printed_disc).sum()) / n_ink if n_ink else 0.0
    m = len(drops)
    rep = SimulationReport(
        drops=m,
        drops_per_swathe=tuple(int((drops.swathe == s.index).sum()) for s in pr.swathes),
        design_pixels=n_ink,
        printed_pixels=int(printed.sum()),
        iou=inter / union if union else 1.0,
        area_ratio=float(printed.sum()) / n_ink if n_ink else float("nan"),
        mean_error_px=float(err_px.mean()) if m and n_ink else float("nan"),
        max_error_px=float(err_px.max()) if m and n_ink else float("nan"),
        mean_error_um=float(err_mm.mean() * 1e3) if m and n_ink else float("nan"),
        max_error_um=float(err_mm.max() * 1e3) if m and n_ink else float("nan"),
        uncovered_pixels=uncovered,
        uncovered_fraction=uncovered / n_ink if n_ink else 0.0,
        uncovered_area_mm2=uncovered * px * py,
        drops_outside=int(m - on_ink.sum()),
        drops_outside_fraction=float(m - on_ink.sum()) / m if m else 0.0,
        disc_iou=disc_iou,
        disc_uncovered_fraction=disc_unc,
        drop_diameter_um=d_um,
        jitter_um=float(jitter_um),
    )
    return Simulation(report=rep, drops=drops, printed=printed, inked=inked, drop_on_ink=on_ink, error_px=err_px)


#: Overlay colours (RGB).
COLOURS = {
    "background": (255, 255, 255),
    "design_printed": (170, 205, 255),
    "design_uncovered": (255, 165, 0),
    "printed_outside": (255, 190, 190),
    "drop_on_ink": (20, 40, 160),
    "drop_outside": (220, 20, 20),
}


def check_overlay_fits(shape: tuple[int, int], scale: int) -> int:
    """Refuse, before anything is simulated, an overlay of a ``shape = (H, W)`` design at
    ``scale`` that would not fit in memory; returns ``scale`` as an int.

    Raises
    ------
    ConfigError
        ``scale`` is not an integer in 1..16.
    RasterTooLargeError
        The ``(H*scale, W*scale, 3)`` picture and its working copies would not fit.
    """
    if isinstance(scale, bool) or not isinstance(scale, numbers.Integral) or scale < 1 or scale > 16:
        raise ConfigError(f"overlay scale must be 1..16, got {scale}")
    scale = int(scale)
    h, w = shape
    # the picture, its row-repeated half-way copy and the PNG encoder's copy: about 7 bytes a pixel
    check_raster_fits(w * scale, h * scale, 7, what=f"the overlay at --scale {scale}")
    return scale


def render_overlay(sim: Simulation, *, scale: int = 2) -> np.ndarray:
    """``(H*scale, W*scale, 3) uint8`` picture: design printed (light blue), design left
    uncovered (orange), printed outside the design (pink), drops on ink (dark blue) and
    stray drops (red), each drop drawn in the sub-pixel it lands in.

    Parameters
    ----------
    sim : Simulation
        Its ``inked`` and ``printed`` ``(H, W) bool`` masks give the background; its drops
        (design pixel coordinates) are drawn on top, those landing outside the picture
        left out.
    scale : int
        Output pixels per design pixel along each axis, 1 to 16.

    Returns
    -------
    (H*scale, W*scale, 3) uint8 ndarray
        RGB, colours from :data:`COLOURS`.

    Raises
    ------
    ConfigError
        ``scale`` is outside 1..16.
    """
    scale = check_overlay_fits(sim.inked.shape, scale)
    h, w = sim.inked.shape
    img = np.empty((h, w, 3), np.uint8)
    img[:] = COLOURS["background"]
    img[sim.inked & sim.printed] = COLOURS["design_printed"]
    img[sim.inked & ~sim.printed] = COLOURS["design_uncovered"]
    img[~sim.inked & sim.printed] = COLOURS["printed_outside"]
    big = np.repeat(np.repeat(img, scale, axis=0), scale, axis=1)
    d = sim.drops
    cc = np.floor(d.col * scale).astype(np.int64)
    rr = np.floor(d.row * scale).astype(np.int64)
    ok = (cc >= 0) & (cc < w * scale) & (rr >= 0) & (rr < h * scale)
    big[rr[ok & sim.drop_on_ink], cc[ok & sim.drop_on_ink]] = COLOURS["drop_on_ink"]
    big[rr[ok & ~sim.drop_on_ink], cc[ok & ~sim.drop_on_ink]] = COLOURS["drop_outside"]
    return big
