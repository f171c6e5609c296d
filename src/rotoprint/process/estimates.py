"""Estimates a plan can make before printing: film and solid thickness per pass, passes per
layer, drop density on a rotary platform, sheet resistance and the resistance between two
terminals of a printed conductor (Laplace's equation on its pixels).

Formulas (``shared/design/process-and-inks.md``):

- wet film per pass ``h_wet = V_drop * drops_per_area`` (``drops_per_area = dpi_x dpi_y / 25.4^2``
  on a Cartesian printer); 10 pL at 360 x 360 dpi is 2.0 um;
- moles of product per area and pass of one ink ``n_i = V_drop * c_i * drops_per_area *
  stoichiometry_i * repeats_i``; a cycle of a reactive system makes ``n = min_i n_i``;
- thickness ``t = n * M / (rho * (1 - porosity))``; 1 M silver nitrate at 10 pL, 360 x 360 dpi
  is about 21 nm;
- on a rotary platform with one angular clock a track at radius ``r`` gets ``r_ref / r`` times
  the drops per area of the reference radius (the direct slicer's ``TrackSet`` gives the exact
  area per drop of every track, :func:`track_density_per_mm2`);
- sheet resistance ``R_s = 1 / (sigma * t)``, a straight track ``R = R_s L / w``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.sparse import csgraph
from scipy.sparse.linalg import spsolve

from ..errors import ConfigError
from .materials import Material

__all__ = [
    "wet_film_um",
    "drops_per_mm2",
    "moles_per_m2",
    "cycle_moles_per_m2",
    "cycle_thickness_um",
    "cycles_for_height",
    "track_density_per_mm2",
    "sheet_resistance_ohm",
    "ResistanceResult",
    "solve_resistance",
]

_PL_TO_MM3 = 1e-6  # 1 pL = 1e-6 mm^3
_PL_TO_L = 1e-12


def drops_per_mm2(dpi_x: float, dpi_y: float) -> float:
    """Drops per mm^2 of a Cartesian ``dpi_x x dpi_y`` raster.

    Parameters
    ----------
    dpi_x, dpi_y : float
        Drops per inch along each axis.

    Returns
    -------
    float
        ``(dpi_x / 25.4) * (dpi_y / 25.4)``.

    Examples
    --------
    >>> round(drops_per_mm2(360, 360), 2)
    200.88
    """
    return (dpi_x / 25.4) * (dpi_y / 25.4)


def wet_film_um(drop_volume_pl: float, density_per_mm2) -> np.ndarray | float:
    """Wet film per pass, um: ``V_drop * drops per area``.

    Parameters
    ----------
    drop_volume_pl : float
        Volume of one drop, picolitres.
    density_per_mm2 : float or array_like
        Drops per mm^2.

    Returns
    -------
    float or float64 ndarray
        A float for a scalar density, else an array of the density's shape.

    Examples
    --------
    >>> round(wet_film_um(10.0, drops_per_mm2(360, 360)), 3)
    2.009
    """
    return drop_volume_pl * _PL_TO_MM3 * np.asarray(density_per_mm2, np.float64) * 1e3 if np.ndim(density_per_mm2) \
        else drop_volume_pl * _PL_TO_MM3 * float(density_per_mm2) * 1e3


def moles_per_m2(drop_volume_pl: float, concentration_mol_per_l: float, density_per_mm2, *, stoichiometry: float = 1.0,
                 repeats: int = 1):
    """Moles of product per m^2 one ink can make in ``repeats`` passes:
    ``V_drop c drops_per_area stoichiometry repeats``. Scalars or arrays (elementwise).

    Parameters
    ----------
    drop_volume_pl : float
        Volume of one drop, picolitres.
    concentration_mol_per_l : float
        Concentration of the ink's reactant.
    density_per_mm2 : float or array_like
        Drops per mm^2 in one pass.
    stoichiometry : float
        Moles of product per mole of the ink's reactant.
    repeats : int
        Passes of the ink.

    Returns
    -------
    float64 or float64 ndarray
        Moles per m^2, the shape of ``density_per_mm2``.
    """
    d = np.asarray(density_per_mm2, np.float64) * 1e6  # per m^2
    return drop_volume_pl * _PL_TO_L * concentration_mol_per_l * d * stoichiometry * repeats


def cycle_moles_per_m2(material: Material, drop_volume_pl: float, density_per_mm2: dict[str, np.ndarray] | float):
    """Moles of product per m^2 of one cycle (every ink, each ``repeats`` times): the minimum
    over the inks (the limiting reactant). ``density_per_mm2``: one value or array for all
    inks, or a dict ink name -> density (inks on different heads).

    Parameters
    ----------
    material : Material
        Its ``inks`` give the concentration, stoichiometry and repeats of each.
    drop_volume_pl : float
        Volume of one drop, picolitres.
    density_per_mm2 : float, array_like or dict of str to array_like
        Drops per mm^2; a dict must hold every ink's name.

    Returns
    -------
    float64 or float64 ndarray
        Moles per m^2, elementwise minimum over the inks.
    """
    vals = []
    for ink in material.inks:
        d = density_per_mm2[ink.name] if isinstance(density_per_mm2, dict) else density_per_mm2
        vals.append(moles_per_m2(drop_volume_pl, ink.concentration_mol_per_l, d, stoichiometry=ink.stoichiometry,
                                 repeats=ink.repeats))
    out = vals[0]
    for v in vals[1:]:
        out = np.minimum(out, v)
    return out


def cycle_thickness_um(material: Material, drop_volume_pl: float, density_per_mm2):
    """Solid thickness one cycle forms, um: ``n M / (rho (1 - porosity))``.

    Parameters
    ----------
    material : Material
        ``n`` from its inks (:func:`cycle_moles_per_m2`); ``M``, ``rho`` and the porosity
        from its ``product``.
    drop_volume_pl : float
        Volume of one drop, picolitres.
    density_per_mm2 : float, array_like or dict of str to array_like
        As for :func:`cycle_moles_per_m2`.

    Returns
    -------
    float64 or float64 ndarray
        Micrometres; a scalar for scalar densities, else the densities' shape.

    Examples
    --------
    >>> from rotoprint.process.materials import builtin_library
    >>> silver = builtin_library()["silver"]
    >>> round(float(cycle_thickness_um(silver, 10.0, drops_per_mm2(360, 360))) * 1000, 1)   # nm
    20.7
    """
    p = material.product
    n = cycle_moles_per_m2(material, drop_volume_pl, density_per_mm2)
    rho_kg_m3 = p.density_g_per_cm3 * 1e3
    return np.asarray(n) * (p.molar_mass_g_per_mol * 1e-3) / (rho_kg_m3 * (1.0 - p.porosity)) * 1e6


def cycles_for_height(height_um: float, per_cycle_um: float) -> int:
    """Whole cycles needed to reach ``height_um`` (at least 1).

    Parameters
    ----------
    height_um : float
    per_cycle_um : float
        Thickness one cycle forms, a finite number > 0.

    Returns
    -------
    int
        ``ceil(height_um / per_cycle_um)`` (a ratio within 1e-9 above a whole number counts
        as that number), at least 1.

    Raises
    ------
    ConfigError
        ``per_cycle_um`` is not a finite number > 0.

    Examples
    --------
    >>> cycles_for_height(20.0, 0.71)
    29
    """
    if not (per_cycle_um > 0 and math.isfinite(per_cycle_um)):
        raise ConfigError(f"thickness per cycle must be > 0 um, got {per_cycle_um}")
    return max(1, math.ceil(height_um / per_cycle_um - 1e-9))


def track_density_per_mm2(tracks, *, equalised: bool, shares=None) -> tuple[np.ndarray, np.ndarray]:
    """Drops per mm^2 along the tracks of a direct-slicer job, sorted by radius.

    Parameters
    ----------
    tracks : sequence of rotoprint.rotary.direct.TrackSet
    equalised : bool
        With density equalisation every track keeps ``a_k / max a`` of its drops.
    shares : sequence (swathe) of (N,) float64, optional
        The union's shares of an interlaced pass (by nozzle): every track keeps its share
        (replaces ``equalised``).

    Returns
    -------
    r_mm, density : (M,) float64
        Track radii (ascending) and drops per mm^2 there (``1 / (r dphi pitch)``, i.e. the
        ``r_ref / r`` law of one angular clock, with the exact local pitch of a tilted head).
    """
    r = np.concatenate([t.r_mm for t in tracks]) if tracks else np.zeros(0)
    a = np.concatenate([t.area_per_drop_mm2 for t in tracks]) if tracks else np.zeros(0)
    if not r.size:
        return r, a
    dens = 1.0 / a
    if shares is not None:
        dens = np.concatenate([np.asarray(f, np.float64)[t.nozzle] for f, t in zip(shares, tracks)]) / a
    elif equalised:
        dens = np.full_like(dens, 1.0 / float(a.max()))
    o = np.argsort(r, kind="stable")
    return r[o], dens[o]


def sheet_resistance_ohm(conductivity_s_per_m: float, thickness_um: float) -> float:
    """``R_s = 1 / (sigma t)``, ohm per square.

    Parameters
    ----------
    conductivity_s_per_m : float
        ``sigma``, > 0.
    thickness_um : float
        ``t``, > 0.

    Returns
    -------
    float
        Ohm per square.

    Raises
    ------
    ConfigError
        ``conductivity_s_per_m`` or ``thickness_um`` is not > 0.

    Examples
    --------
    >>> round(sheet_resistance_ohm(1.42e5, 1.0), 3)
    7.042
    """
    if not (conductivity_s_per_m > 0 and thickness_um > 0):
        raise ConfigError(f"conductivity and thickness must be > 0, got {conductivity_s_per_m} S/m, {thickness_um} um")
    return 1.0 / (conductivity_s_per_m * thickness_um * 1e-6)


@dataclass(frozen=True, eq=False)
class ResistanceResult:
    """Result of :func:`solve_resistance`.

    Attributes
    ----------
    resistance_ohm : float
        ``inf`` when the terminals are not connected, 0 when they touch.
    potential : (H, W) float64
        Potential (terminal A = 1, B = 0) on the conductor's pixels, NaN elsewhere and on
        pixels connected to neither terminal.
    connected : bool
    unknowns : int
        Pixels solved for.
    floating_pixels : int
        Conductor pixels connected to neither terminal.
    """

    resistance_ohm: float
    potential: np.ndarray
    connected: bool
    unknowns: int
    floating_pixels: int

    def to_json(self) -> dict:
        return {"resistance_ohm": self.resistance_ohm if math.isfinite(self.resistance_ohm) else None,
                "connected": self.connected, "unknowns": self.unknowns, "floating_pixels": self.floating_pixels}


def solve_resistance(
    conductor: np.ndarray,
    *,
    sheet_conductance_s: np.ndarray | float,
    terminal_a: np.ndarray,
    terminal_b: np.ndarray,
    pitch_x_mm: float,
    pitch_y_mm: float,
) -> ResistanceResult:
    """Resistance between two terminals of a printed conductor, from Laplace's equation.

    Each pixel is a cell of the film with sheet conductance ``g = sigma * t`` (S). Neighbouring
    cells (4-connected) are joined by the two half-cells in series,
    ``G = 1 / (dx / (2 g_1 dy) + dx / (2 g_2 dy))`` across a vertical edge (``dx, dy`` swapped
    across a horizontal one); terminal pixels are ideal conductors (held at 1 V and 0 V), so
    a cell next to a terminal connects to it with its half-cell only. Kirchhoff's current law
    at every other pixel is the five-point Laplace equation ``div(g grad V) = 0``; it is
    solved with a sparse direct solver and ``R = 1 / I``. With this rule a rectangle of
    ``n x m`` pixels between terminal columns on both ends gives exactly ``R_s n dx / (m dy)``.

    Parameters
    ----------
    conductor : (H, W) bool
        Printed conductor pixels (terminal pixels outside it are ignored).
    sheet_conductance_s : (H, W) float64 or float
        ``sigma * t`` per pixel, siemens (1 / ohm per square).
    terminal_a, terminal_b : (H, W) bool
        Terminal regions; only their pixels on the conductor count.
    pitch_x_mm, pitch_y_mm : float
        Pixel size across columns and rows.

    Returns
    -------
    ResistanceResult

    Examples
    --------
    >>> m = np.ones((10, 40), bool)                          # 40 x 10 squares of 1 ohm
    >>> a = np.zeros_like(m); a[:, 0] = True
    >>> b = np.zeros_like(m); b[:, -1] = True
    >>> round(solve_resistance(m, sheet_conductance_s=1.0, terminal_a=a, terminal_b=b,
    ...                        pitch_x_mm=0.1, pitch_y_mm=0.1).resistance_ohm, 9)   # 38 / 10
    3.8
    """
    m = np.asarray(conductor, bool)
    if m.ndim != 2:
        raise ConfigError(f"conductor must be a 2-D mask, got {m.ndim}-D")
    h, w = m.shape
    g = np.broadcast_to(np.asarray(sheet_conductance_s, np.float64), m.shape)
    if not (pitch_x_mm > 0 and pitch_y_mm > 0):
        raise ConfigError(f"pixel pitch must be > 0, got {pitch_x_mm} x {pitch_y_mm} mm")
    A = np.asarray(terminal_a, bool) & m
    B = np.asarray(terminal_b, bool) & m
    if A.shape != m.shape or B.shape != m.shape:
        raise ConfigError("terminal masks must have the conductor's shape")
    if not A.any():
        raise ConfigError("terminal A touches no conductor pixel")
    if not B.any():
        raise ConfigError("terminal B touches no conductor pixel")
    if (A & B).any():
        raise ConfigError("terminals A and B overlap")
    good = m & np.isfinite(g) & (g > 0)
    A &= good
    B &= good
    nan = np.full(m.shape, np.nan)
    idx = np.full(m.shape, -1, np.int64)
    ids = np.flatnonzero(good.ravel())
    idx.ravel()[ids] = np.arange(ids.size)
    gf = g.ravel()[ids]
    # links: (p, q, conductance) between 4-neighbours, both on the conductor
    ps, qs, gs = [], [], []
    for dr, dc, along, across in ((0, 1, pitch_x_mm, pitch_y_mm), (1, 0, pitch_y_mm, pitch_x_mm)):
        a_ = good[: h - dr, : w - dc] & good[dr:, dc:]
        p = idx[: h - dr, : w - dc][a_]
        q = idx[dr:, dc:][a_]
        ps.append(p)
        qs.append(q)
        gs.append(np.stack([gf[p], gf[q]], 1) * (across / along))  # full-cell conductances of both cells
    p = np.concatenate(ps)
    q = np.concatenate(qs)
    gc = np.concatenate(gs)  # (L, 2)
    ta = A.ravel()[ids]
    tb = B.ravel()[ids]
    term = ta | tb
    both_term = term[p] & term[q]
    if (both_term & (ta[p] != ta[q])).any():  # an A pixel next to a B pixel: a short
        return ResistanceResult(0.0, nan, True, 0, 0)
    # half-cells in series; the half-cell on a terminal has no resistance
    r_p = np.where(term[p], 0.0, 0.5 / gc[:, 0])
    r_q = np.where(term[q], 0.0, 0.5 / gc[:, 1])
    keep = ~both_term
    p, q, G = p[keep], q[keep], 1.0 / (r_p[keep] + r_q[keep])
    n = ids.size
    # connectivity: components of the conductor graph (terminal pixels included)
    adj = sparse.coo_matrix((np.ones(p.size), (p, q)), shape=(n, n))
    # terminal pixels of one terminal are one conductor: tie them together
    for t in (ta, tb):
        tt = np.flatnonzero(t)
        if tt.size > 1:
            adj = adj + sparse.coo_matrix((np.ones(tt.size - 1), (tt[:-1], tt[1:])), shape=(n, n))
    _, lab = csgraph.connected_components(adj, directed=False)
    has_a = np.zeros(lab.max() + 1, bool)
    has_b = np.zeros_like(has_a)
    has_a[lab[ta]] = True
    has_b[lab[tb]] = True
    live = has_a[lab] | has_b[lab]
    floating = int((~live).sum())
    connected = bool((has_a & has_b).any())
    if not connected:
        pot = nan.copy()
        pot.ravel()[ids[live & has_a[lab]]] = 1.0
        pot.ravel()[ids[live & ~has_a[lab]]] = 0.0
        return ResistanceResult(math.inf, pot, False, 0, floating)
    unk = live & ~term
    uid = np.full(n, -1, np.int64)
    uid[unk] = np.arange(int(unk.sum()))
    nu = int(unk.sum())
    vfix = np.where(ta, 1.0, 0.0)
    rows, cols, vals = [], [], []
    rhs = np.zeros(nu)
    for a_, b_ in ((p, q), (q, p)):
        sel = unk[a_]
        ia = uid[a_[sel]]
        rows.append(ia)
        cols.append(ia)
        vals.append(G[sel])
        other_unk = unk[b_[sel]]
        rows.append(ia[other_unk])
        cols.append(uid[b_[sel][other_unk]])
        vals.append(-G[sel][other_unk])
        fixed = ~other_unk & term[b_[sel]]
        np.add.at(rhs, ia[fixed], G[sel][fixed] * vfix[b_[sel][fixed]])
    L = sparse.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(nu, nu))
    v = spsolve(L.tocsc(), rhs) if nu else np.zeros(0)
    V = vfix.copy()
    V[unk] = v
    # current out of terminal A: through its links to non-A pixels
    la = ta[p] & ~ta[q]
    lb = ta[q] & ~ta[p]
    current = float((G[la] * (1.0 - V[q[la]])).sum() + (G[lb] * (1.0 - V[p[lb]])).sum())
    pot = nan.copy()
    vals_all = np.where(live, V, np.nan)
    pot.ravel()[ids] = vals_all
    r = 1.0 / current if current > 0 else math.inf
    return ResistanceResult(r, pot, True, nu, floating)
