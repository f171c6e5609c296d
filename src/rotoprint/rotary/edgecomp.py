"""Design-aware edge compensation of an equalised print: a share of the thinned-out drops
restored near the design's edges.

The wet film levels under surface tension before it sets, pinned at its edge: within about a
levelling length (~0.1 mm) of an edge, ink flows from the interior into the thinner boundary
band (the caps' taper). Where a 1 mm radial bin's interior is a thin sliver beside an edge
(the gaps between the test design's cells), that bin loses 3-6 % levelled while it is flat as
landed (``docs/rotary.md``, "Equalised 1 mm bins"). :func:`restore_near_edges` gives such
places back ink: of the drops an equalised pass thinned out (:func:`~rotoprint.rotary.equalise.thin_print`),
those landing inside the design within :attr:`EdgeRestore.zone_um` of its edge (by default an
edge met along the platform radius, :attr:`EdgeRestore.radial_only`) are restored so
that a track keeping the share ``f`` keeps ``min(1, (1 + c) f)`` there (``c`` =
:attr:`EdgeRestore.coefficient`: the same relative gain at every radius, though the equalisation
thins the inner tracks more), by an ordered pattern on each track's firing index (as the
thinning's). On by default in the equalised passes of binary heads
(:attr:`~rotoprint.rotary.interlace.PassOptions.edge_restore`), made by :func:`transform_restored`:
the fused thinned transform of the whole design, then one sweep of the pass's track windows for
the thinned-out drops that the pattern restores and that are sampled from the zone's pixels
(:func:`edge_zone_mask`; ``_edgecomp_kernels``), whose landing points alone are tested against
the edge: the same print as :func:`restore_near_edges` of the unthinned one without making it.
What the restore needs of the design (:class:`EdgeZone`) is made once for all the passes of a layer.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConfigError

__all__ = ["EDGE_ZONE_UM", "EDGE_COEFFICIENT", "EdgeRestore", "EdgeZone", "design_rim", "edge_distance_um", "edge_zone", "edge_zone_mask",
           "radial_edge_near", "restore_pattern", "restore_near_edges", "transform_restored"]

#: Width of the zone inside the design's edge where thinned-out drops are restored, um.
EDGE_ZONE_UM = 50.0
#: Relative gain of a thinned track's drops in the zone.
EDGE_COEFFICIENT = 0.3
_GOLDEN2 = 0.3819660112501051  # 2 - golden ratio: the restore pattern's phase step, apart from the thinning's


@dataclass(frozen=True)
class EdgeRestore:
    """Options of :func:`restore_near_edges`.

    Parameters
    ----------
    zone_um : float, optional
        Zone inside the design's edge, um (0 < zone <= 1000). None (the default): :data:`EDGE_ZONE_UM`,
        or one design pixel (the smaller pitch) where the pixels are finer and ``radial_only`` (the
        radial look-up's reach), :meth:`resolved` by the placement.
    coefficient : float
        Relative gain ``c`` of a thinned track's drops in the zone, (0, 1]: share ``f`` -> ``min(1, (1 + c) f)``.
    radial_only : bool
        Only edges met along the platform radius count (:func:`radial_edge_near`, the default):
        an edge along the track takes ink from every 1 mm radial bin alike, so compensating it
        would move the bins apart where the equalised shares differ. False: every edge
        (:func:`edge_distance_um`).
    """

    zone_um: float | None = None
    coefficient: float = EDGE_COEFFICIENT
    radial_only: bool = True

    def __post_init__(self) -> None:
        if self.zone_um is not None and not (isinstance(self.zone_um, (int, float)) and math.isfinite(self.zone_um) and 0.0 < self.zone_um <= 1000.0):
            raise ConfigError(f"edge zone must be in (0, 1000] um, got {self.zone_um!r}")
        if not (isinstance(self.coefficient, (int, float)) and math.isfinite(self.coefficient) and 0.0 < self.coefficient <= 1.0):
            raise ConfigError(f"edge coefficient must be in (0, 1], got {self.coefficient!r}")

    def resolved(self, placement) -> "EdgeRestore":
        """These options with the zone given (``zone_um=None``: 50 um, at most a design pixel when ``radial_only``)."""
        if self.zone_um is not None:
            return self
        zone = min(EDGE_ZONE_UM, 1000.0 * min(placement.pitch_x_mm, placement.pitch_y_mm)) if self.radial_only else EDGE_ZONE_UM
        return dataclasses.replace(self, zone_um=zone)

    def thin(self, pr, shares, design: np.ndarray, *, pass_index: int = 0):
        """``pr`` thinned by ``shares`` (:func:`~rotoprint.rotary.equalise.thin_print`), then
        :func:`restore_near_edges` with these options."""
        from .equalise import thin_print

        return restore_near_edges(pr, thin_print(pr, shares, pass_index=pass_index), design, shares, options=self,
                                  pass_index=pass_index)


def edge_distance_um(mask: np.ndarray, col: np.ndarray, row: np.ndarray, pitch_x_mm: float, pitch_y_mm: float,
                     reach_um: float) -> np.ndarray:
    """Distance (um) of sites inside the design to its edge, looked for up to ``reach_um``.

    Parameters
    ----------
    mask : (H, W) bool
        The design's printing pixels (outside the image counts as empty).
    col, row : (M,) float64
        Continuous design coordinates (pixel ``(floor(row), floor(col))``).
    pitch_x_mm, pitch_y_mm : float
        The pixel pitches.
    reach_um : float
        Distances are exact up to this (every empty pixel within it is looked at).

    Returns
    -------
    (M,) float64
        0 for a site outside the design (or outside the image), else the distance to the nearest
        empty pixel's square (``inf`` where none lies within ``reach_um``).
    """
    m = np.asarray(mask, bool)
    h, w = m.shape
    col, row = np.asarray(col, np.float64), np.asarray(row, np.float64)
    i, j = np.floor(row).astype(np.int64), np.floor(col).astype(np.int64)
    ni = int(math.ceil(reach_um * 1e-3 / pitch_y_mm))
    nj = int(math.ceil(reach_um * 1e-3 / pitch_x_mm))
    pad = np.zeros((h + 2 * ni + 2, w + 2 * nj + 2), bool)
    pad[ni + 1:ni + 1 + h, nj + 1:nj + 1 + w] = m
    ii = np.clip(i, -ni - 1, h + ni) + ni + 1
    jj = np.clip(j, -nj - 1, w + nj) + nj + 1
    out = np.full(col.size, np.inf)
    out[~pad[ii, jj]] = 0.0
    for di in range(-ni, ni + 1):
        for dj in range(-nj, nj + 1):
            if di == 0 and dj == 0:
                continue
            empty = ~pad[ii + di, jj + dj]
            if not empty.any():
                continue
            # distance from the site to the square of pixel (i + di, j + dj)
            dy = np.maximum(0.0, np.maximum((i + di) - row, row - (i + di + 1))) * pitch_y_mm
            dx = np.maximum(0.0, np.maximum((j + dj) - col, col - (j + dj + 1))) * pitch_x_mm
            out = np.where(empty, np.minimum(out, 1e3 * np.hypot(dx, dy)), out)
    return out


def _check_radial_zone(placement, zone_um: float) -> None:
    """One-line :class:`ConfigError` unless the radial zone is at most the smaller pixel pitch."""
    px_um = 1e3 * min(placement.pitch_x_mm, placement.pitch_y_mm)
    if zone_um * 1e-3 > min(placement.pitch_x_mm, placement.pitch_y_mm) + 1e-12:
        raise ConfigError(f"a radial edge zone must be at most a pixel ({px_um:.1f} um), got {zone_um!r}")


def radial_edge_near(mask: np.ndarray, placement, col: np.ndarray, row: np.ndarray, zone_um: float, *,
                     rim: np.ndarray | None = None, backend: str = "numpy") -> np.ndarray:
    """Sites inside the design with an edge within ``zone_um`` along the platform radius.

    Parameters
    ----------
    mask : (H, W) bool
        The design's printing pixels (outside the image counts as empty).
    placement : Placement
    col, row : (M,) float64
        Continuous design coordinates.
    zone_um : float
        At most the smaller pixel pitch (then the design at ``+-zone_um`` along the radius
        tells it: an empty stretch is at least a pixel wide).
    rim : (H, W) bool, optional
        :func:`design_rim` of ``mask`` (made here when not given).
    backend : {"numpy", "jit"}
        ``"jit"``: the same float operations in one loop (``_edgecomp_kernels.radial_near_jit``).

    Returns
    -------
    (M,) bool
    """
    pl = placement
    _check_radial_zone(pl, zone_um)
    m = np.asarray(mask, bool)
    h, w = m.shape
    col, row = np.asarray(col, np.float64), np.asarray(row, np.float64)
    rim = design_rim(m) if rim is None else rim
    if backend == "jit":
        from ._edgecomp_kernels import radial_near_jit

        near = np.empty(col.size, bool)
        a = math.radians(pl.angle_deg)
        radial_near_jit(m, rim, col, row, pl.inner_radius_mm, pl.pitch_x_mm, pl.pitch_y_mm, pl.height_px / 2.0,
                        math.cos(a), math.sin(a), float(zone_um), near)
        return near

    def inside(c: np.ndarray, r: np.ndarray) -> np.ndarray:
        i, j = np.floor(r).astype(np.int64), np.floor(c).astype(np.int64)
        ok = (i >= 0) & (i < h) & (j >= 0) & (j < w)
        out = np.zeros(c.size, bool)
        out[ok] = m[i[ok], j[ok]]
        return out

    # only a printing pixel with an empty one among its 8 neighbours can hold a site within a
    # pixel of an edge (the rim): the rest is not looked at again
    i, j = np.floor(row).astype(np.int64), np.floor(col).astype(np.int64)
    ok = (i >= 0) & (i < h) & (j >= 0) & (j < w)
    cand = np.zeros(col.size, bool)
    cand[ok] = rim[i[ok], j[ok]]
    idx = np.flatnonzero(cand)
    x, y = pl.to_platform(col[idx], row[idx])
    rad = np.maximum(np.hypot(x, y), 1e-12)
    hit = np.zeros(idx.size, bool)
    for t in (-1.0, 1.0):
        c2, r2 = pl.to_design(x + t * 1e-3 * zone_um * x / rad, y + t * 1e-3 * zone_um * y / rad)
        hit |= ~inside(c2, r2)
    near = np.zeros(col.size, bool)
    near[idx[hit]] = True
    return near


def design_rim(mask: np.ndarray) -> np.ndarray:
    """``(H, W) bool``: the printing pixels of ``mask`` ``(H, W) bool`` with an empty one (or the
    image's surround) among their 8 neighbours."""
    m = np.asarray(mask, bool)
    h, w = m.shape
    pad = np.zeros((h + 2, w + 2), bool)
    pad[1:-1, 1:-1] = m
    return m & ~np.logical_and.reduce([pad[1 + di:h + 1 + di, 1 + dj:w + 1 + dj] for di in (-1, 0, 1) for dj in (-1, 0, 1)])


def restore_near_edges(full, thinned, design: np.ndarray, shares, *, options: EdgeRestore | None = None, pass_index: int = 0):
    """``thinned`` with some of the drops it lost from ``full`` restored near the design's edges.

    A drop of ``full`` that ``thinned`` left out (nozzle ``k`` of swathe ``j``, absolute firing
    ``i``) comes back when its site (:func:`~rotoprint.rotary.simulate.place_drops`) lies inside
    the design within ``zone_um`` of its edge (:func:`edge_distance_um`) and ``floor((i + 1) s +
    o_k) > floor(i s + o_k)``, ``s = min(1, c f / (1 - f))`` (``f = shares[j][k]``, ``c`` the
    coefficient, ``o_k`` a phase per nozzle and pass): ``s`` of the ``1 - f`` thinned out over any
    run of firings, so the track keeps about ``min(1, (1 + c) f)`` in the zone (a track left out,
    ``f = 0``, stays out). Every other site is as in ``thinned``.

    Parameters
    ----------
    full, thinned : RotaryPrint
        One pass before and after thinning (same swathes, shapes and placement).
    design : (H, W) uint8
        The design (:func:`~rotoprint.rotary.simulate.design_mask`).
    shares : sequence (swathe) of (N,) float64
        The shares ``thinned`` was thinned by (:func:`~rotoprint.rotary.equalise.thin_print`).
    options : EdgeRestore, optional
    pass_index : int
        The pass (its phases differ from the other passes').

    Returns
    -------
    RotaryPrint
        ``thinned`` with the restored drops (their ``full`` levels).

    Raises
    ------
    ConfigError
        Prints that do not match.
    """
    opts = (options or EdgeRestore()).resolved(full.placement)
    if len(shares) != len(full.swathes) or any(np.shape(f) != (full.head.nozzles,) for f in shares):
        raise ConfigError("edge restore needs one share per nozzle for every swathe")
    if len(full.swathes) != len(thinned.swathes) or any(a.levels.shape != b.levels.shape or a.first_firing != b.first_firing
                                                         for a, b in zip(full.swathes, thinned.swathes)):
        raise ConfigError("edge restore needs the print before and after thinning, swathe for swathe")
    return _restore_lost(thinned, _lost(full, thinned), design, shares, opts, pass_index)


def restore_pattern(nozzle: np.ndarray, share: np.ndarray, coefficient: float, pass_index: int) -> tuple[np.ndarray, np.ndarray]:
    """The restore's ordered pattern for drops of ``nozzle`` on tracks keeping ``share``: firing
    ``i`` of a thinned-out drop comes back where ``floor((i + 1) s + o) > floor(i s + o)``.

    Returns ``(s, o)``, float64 like ``share``: the share of the thinned-out drops restored,
    ``min(1, c f / (1 - f))`` (so the track keeps ``min(1, (1 + c) f)``; 0 where ``f >= 1``), and
    the phase ``((k + 7919 p) (2 - golden ratio)) mod 1``. Shared by the image route and the direct
    slicer's fill (:mod:`rotoprint.rotary.direct`)."""
    f = np.asarray(share, np.float64)
    s = np.where(f < 1.0, np.minimum(1.0, float(coefficient) * f / np.maximum(1.0 - f, 1e-300)), 0.0)
    return s, np.mod((nozzle + 7919 * int(pass_index)) * _GOLDEN2, 1.0)


def _lost(full, thinned):
    """``full``'s drops that ``thinned`` has not (their ``full`` levels), swathe for swathe."""
    return dataclasses.replace(full, swathes=tuple(dataclasses.replace(a, levels=np.where(b.levels == 0, a.levels, 0).astype(np.uint8))
                                                   for a, b in zip(full.swathes, thinned.swathes)))


def _restore_lost(thinned, lost, design: np.ndarray, shares, opts: EdgeRestore, pass_index: int):
    """``thinned`` with the drops of ``lost`` (thinned-out drops, levels as printed unthinned) that
    the rule of :func:`restore_near_edges` gives back (``opts`` resolved)."""
    from .simulate import design_mask, place_drops

    dr = place_drops(lost)
    if len(dr.nozzle) == 0:
        return thinned
    pl = lost.placement
    mask = design_mask(np.asarray(design), lost.head.grey_levels)
    if opts.radial_only:
        near = radial_edge_near(mask, pl, dr.col, dr.row, opts.zone_um)
    else:
        near = edge_distance_um(mask, dr.col, dr.row, pl.pitch_x_mm, pl.pitch_y_mm, opts.zone_um)
        near = (near > 0.0) & (near <= opts.zone_um)
    k, i = dr.nozzle, dr.firing.astype(np.float64)
    pos = {sw.index: j for j, sw in enumerate(lost.swathes)}
    f = np.stack([np.asarray(x, np.float64) for x in shares])[np.array([pos[int(x)] for x in np.unique(dr.swathe)])[
        np.searchsorted(np.unique(dr.swathe), dr.swathe)], k]
    s_, o = restore_pattern(k, f, opts.coefficient, pass_index)
    back = near & (np.floor((i + 1.0) * s_ + o) > np.floor(i * s_ + o))
    out = []
    for a, b in zip(lost.swathes, thinned.swathes):
        sel = back & (dr.swathe == a.index)
        if not sel.any():
            out.append(b)
            continue
        lev = b.levels.copy()
        rows, cols = dr.firing[sel] - a.first_firing, dr.nozzle[sel]
        lev[rows, cols] = a.levels[rows, cols]
        out.append(dataclasses.replace(b, levels=lev))
    return dataclasses.replace(thinned, swathes=tuple(out))


def edge_zone_mask(mask: np.ndarray, placement, options: EdgeRestore | None = None) -> np.ndarray:
    """The design pixels a restored drop can be sampled from, with one pixel to spare.

    A site :func:`radial_edge_near` (or :func:`edge_distance_um`) can count lies in a printing pixel
    with an empty one (or the image's surround) within ``n = ceil(zone / pitch)`` pixels along each
    axis (``n = 1`` for the radial zone, at most a pixel); this mask holds those within ``n + 1``,
    so that a drop whose landing point (:func:`~rotoprint.rotary.simulate.place_drops`) and sampled
    pixel (the exact transform's) differ by less than a pixel is in it either way.

    Parameters
    ----------
    mask : (H, W) bool
        The design's printing pixels (:func:`~rotoprint.rotary.simulate.design_mask`).
    placement : Placement
    options : EdgeRestore, optional

    Returns
    -------
    (H, W) bool
    """
    opts = (options or EdgeRestore()).resolved(placement)
    m = np.asarray(mask, bool)
    h, w = m.shape
    reach = 1e-3 * float(opts.zone_um)
    ni = 1 + (1 if opts.radial_only else int(math.ceil(reach / placement.pitch_y_mm - 1e-9)))
    nj = 1 + (1 if opts.radial_only else int(math.ceil(reach / placement.pitch_x_mm - 1e-9)))
    empty = np.ones((h + 2 * ni, w + 2 * nj), bool)  # outside the image counts as empty
    empty[ni:ni + h, nj:nj + w] = ~m
    rows = np.zeros((h, w + 2 * nj), bool)  # an empty pixel within ni rows (separable box: ORs of shifted views)
    for di in range(2 * ni + 1):
        rows |= empty[di:di + h]
    box = np.zeros((h, w), bool)
    for dj in range(2 * nj + 1):
        box |= rows[:, dj:dj + w]
    return m & box


@dataclass(frozen=True, eq=False)
class EdgeZone:
    """What the edge restore needs of a binary design, made once for all the passes of a layer
    (:func:`edge_zone`).

    Attributes
    ----------
    design : (H, W) uint8
        A read-only copy of the design it was made of (a pass of another design is refused).
    placement : Placement
    grey_levels : int
        The head's drop levels (``level`` follows from them).
    mask, rim : (H, W) bool
        The printing pixels (:func:`~rotoprint.rotary.simulate.design_mask`) and those of them
        beside an empty one (:func:`design_rim`; None for the all-edges zone, which does not use it).
    level : int
        The drop level of the design's ink.
    zone_flat : (H W + 1,) uint8
        The design masked to :func:`edge_zone_mask`, as levels, with the 0 "no drop" sentinel.
    zone_blocks : (2, ceil(H / 8) + 1, ceil(W / 8) + 1) int32
        Its ink blocks (:func:`~rotoprint.rotary._exact_kernels.ink_blocks`).
    options : EdgeRestore
        Resolved for the placement.
    """

    design: np.ndarray
    placement: object
    grey_levels: int
    mask: np.ndarray
    rim: np.ndarray | None
    level: int
    zone_flat: np.ndarray
    zone_blocks: np.ndarray
    options: EdgeRestore


def edge_zone(design: np.ndarray, head, placement, options: EdgeRestore | None = None) -> EdgeZone | None:
    """The :class:`EdgeZone` of ``design`` ``(H, W) uint8`` for ``head`` (binary), or None when the
    design is grey (:func:`transform_restored` thins a grey design whole)."""
    from ._exact_kernels import BINARY_LEVELS, ink_blocks
    from .printdata import design_kind, design_levels
    from .simulate import design_mask

    opts = (options or EdgeRestore()).resolved(placement)
    design = np.ascontiguousarray(design)
    if design_kind(design) != "binary":
        return None
    if opts.radial_only:
        _check_radial_zone(placement, opts.zone_um)  # radial_edge_near's rule, before any pass is made
    mask = design_mask(design, head.grey_levels)
    level = int(design_levels(np.array([255], np.uint8), head.grey_levels, kind="binary")[0])
    zone_flat, _ = BINARY_LEVELS["jit"](np.where(edge_zone_mask(mask, placement, opts), design, 0).astype(np.uint8), level)
    h, w = design.shape
    own = design.copy()
    own.flags.writeable = False
    return EdgeZone(design=own, placement=placement, grey_levels=int(head.grey_levels), mask=mask, rim=design_rim(mask) if opts.radial_only else None, level=level, zone_flat=zone_flat,
                    zone_blocks=ink_blocks(zone_flat, w, h), options=opts)


def transform_restored(design: np.ndarray, head, placement, setup, shares, *, options: EdgeRestore | None = None,
                       pass_index: int = 0, zone: EdgeZone | None = None):
    """One equalised pass with the edge restore: the print :func:`restore_near_edges` makes of
    ``transform_exact(design, head, placement, setup)`` and its :func:`~rotoprint.rotary.equalise.thin_print`
    by ``shares``, without the unthinned print of the whole design.

    The thinned print is sampled thinning (``transform_exact(..., thin=ThinShares(shares, pass_index))``);
    the drops it left out that the restore's pattern gives back and that are sampled from the
    zone's pixels (:func:`edge_zone_mask`) are found in one sweep of the pass's track windows
    (:func:`~rotoprint.rotary._edgecomp_kernels.restore_candidates_jit`), and only their landing
    points are tested against the design's edge (as :func:`restore_near_edges` tests every lost
    drop's). Binary designs only (a grey design is sampled bilinear: masking it would change the
    samples beside the zone), a grey one is transformed whole and thinned (as :meth:`EdgeRestore.thin`).

    Parameters
    ----------
    design : (H, W) uint8
    head : InkjetHead
        A binary head.
    placement : Placement
    setup : RotarySetup
        The pass's setting (clock, pivot offset, mount angle, ...).
    shares : sequence (swathe) of (N,) float64
        The pass's shares (:func:`~rotoprint.rotary.interlace.track_fractions`).
    options : EdgeRestore, optional
    pass_index : int
    zone : EdgeZone, optional
        :func:`edge_zone` of this design, head, placement and options (made here when not given;
        the passes of a layer share one).

    Returns
    -------
    RotaryPrint
        The thinned pass with the restored drops.
    """
    from . import _edgecomp_kernels as _ek
    from ._exact_kernels import claim_rows
    from ._thin_kernels import thin_phases
    from .exact import ThinShares, exact_maps, transform_exact
    from .simulate import landing_xy

    opts = (options or EdgeRestore()).resolved(placement)
    design = np.asarray(design)
    z = edge_zone(design, head, placement, opts) if zone is None else zone
    if z is not None and (z.options != opts or z.placement != placement or z.grey_levels != head.grey_levels
                          or not np.array_equal(z.design, design)):
        raise ConfigError("edge restore: the edge zone was made for another design, placement, head or other options")
    if z is None:
        return opts.thin(transform_exact(design, head, placement, setup), shares, design, pass_index=pass_index)
    thinned = transform_exact(design, head, placement, setup, kind="binary", thin=ThinShares(shares, pass_index))
    if len(shares) != len(thinned.swathes) or any(np.shape(f) != (head.nozzles,) for f in shares):
        raise ConfigError("edge restore needs one share per nozzle for every swathe")
    maps = exact_maps(head, placement, setup)  # the maps the thinned print was sampled through (cached)
    kern = _ek.restore_candidates_jit if maps.backend == "jit" else _ek.restore_candidates_numpy
    nozzles = np.arange(head.nozzles)
    p = thin_phases(head.nozzles, pass_index)
    dead = np.array(head.dead_nozzles, dtype=np.int64)
    for sm, sw, f in zip(maps.swathes, thinned.swathes, shares):
        f = np.ascontiguousarray(f, np.float64)
        gain, o = restore_pattern(nozzles, f, opts.coefficient, pass_index)  # gain 0 unless 0 < f < 1 (c > 0)
        gain[dead] = 0.0  # a dead nozzle has no drop to restore
        w = sm.windows
        cap = int(w.count.sum())  # at most one candidate a window drop (8 bytes each; pages touched only as written)
        rows, ks = np.empty(cap, np.int32), np.empty(cap, np.int32)
        m = kern(*w.coefficients, w.nozzle, w.row, w.count, w.cos_row, w.sin_row, w.width, w.height, z.zone_flat, z.zone_blocks,
                 f, p, gain, o, int(sm.first_firing), claim_rows(w.cos_row, w.sin_row), rows, ks)
        if m == 0:
            continue
        rows, ks = rows[:m], ks[:m]
        col, row = placement.to_design(*landing_xy(thinned, sw, ks, rows.astype(np.int64) + sw.first_firing))
        if opts.radial_only:
            near = radial_edge_near(z.mask, placement, col, row, opts.zone_um, rim=z.rim, backend=maps.backend)
        else:
            near = edge_distance_um(z.mask, col, row, placement.pitch_x_mm, placement.pitch_y_mm, opts.zone_um)
            near = (near > 0.0) & (near <= opts.zone_um)
        sw.levels[rows[near], ks[near]] = z.level
    return thinned
