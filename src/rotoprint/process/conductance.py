"""Resistance of a printed conductor between two named terminals, from a plan.

The conductor is the material's region in every layer (overlaps resolved), on the assembly's
Cartesian grid, in two versions:

- ``"design"``: the exact cross-section rasterised at pixel centres (optionally oversampled),
  each layer ``t_layer(r) = cycles * t_cycle(r)`` thick, the plan's thickness from the
  measured drop density at the pixel's radius (:func:`thickness_map_um`);
- ``"printed"``: the film the planned drops deposit (:func:`deposited_thickness_um`): every
  ink's drops of every interlaced pass, weighted by how often the pass prints, spread and
  merged by the deposit model (:mod:`rotoprint.rotary.deposit`), the limiting reagent's film
  turned into product (:func:`solid_thickness_um`); a pixel without film conducts nothing.

Stacked layers touch, so their films add: the sheet conductance of a pixel is
``sigma * sum over layers of t_layer``. Laplace's equation is solved on that sheet by
:func:`.estimates.solve_resistance`.
"""

from __future__ import annotations

import math

import numpy as np

from ..rotary.direct import PartPlacement
from ..rotary.placement import Placement
from .estimates import solve_resistance

__all__ = ["pixel_centres_model", "terminal_mask", "thickness_map_um", "solid_thickness_um", "deposited_thickness_um",
           "resistance_from_masks", "resistance_from_thickness", "coil_hand_check"]

def _resistance_deposit():
    """The deposit grid of the printed film's resistance: 3 cells per footprint (the film is
    averaged over each design pixel, so a coarser grid than the coverage figures' does)."""
    from ..rotary.deposit import DepositOptions

    return DepositOptions(cells_per_footprint=3.0)


#: A right-angle corner of a uniform track counts this many squares (conformal mapping; the
#: centreline counts it as one).
CORNER_SQUARES = 0.559


def pixel_centres_model(grid: Placement, part: PartPlacement) -> tuple[np.ndarray, np.ndarray]:
    """``(W,)`` model X of the columns' centres and ``(H,)`` model Y of the rows' centres.

    Parameters
    ----------
    grid : Placement
        Raster of ``height_px x width_px`` pixels of ``pitch_x_mm x pitch_y_mm``.
    part : PartPlacement
        Column 0 starts at the part's footprint X minimum; the rows are centred on its
        ``y_centre_mm``, row 0 at the top (largest Y).

    Returns
    -------
    x_mm : (W,) float64
    y_mm : (H,) float64
        Decreasing with the row index.
    """
    x = part.footprint_mm[0] + (np.arange(grid.width_px) + 0.5) * grid.pitch_x_mm
    y = part.y_centre_mm + (grid.height_px / 2.0 - np.arange(grid.height_px) - 0.5) * grid.pitch_y_mm
    return x, y


def terminal_mask(grid: Placement, part: PartPlacement, rect_mm) -> np.ndarray:
    """``(H, W) bool``: pixels whose centre lies in the model rectangle ``(x0, y0, x1, y1)``.

    Parameters
    ----------
    grid : Placement
    part : PartPlacement
        See :func:`pixel_centres_model`.
    rect_mm : (4,) float or shapely Polygon
        ``(x0, y0, x1, y1)`` in the model frame, mm; the edges count as inside. Or a pad's
        polygon (a layer part's terminal): the pixels whose centre is inside it.

    Returns
    -------
    (H, W) bool ndarray
    """
    x, y = pixel_centres_model(grid, part)
    if hasattr(rect_mm, "geom_type"):  # a pad polygon (layer parts): pixel centres inside it
        import shapely

        return shapely.contains_xy(rect_mm, x[None, :], y[:, None])
    x0, y0, x1, y1 = rect_mm
    return ((y >= y0) & (y <= y1))[:, None] & ((x >= x0) & (x <= x1))[None, :]


def thickness_map_um(plan, material: str, grid: Placement) -> np.ndarray:
    """``(H, W) float64``: the material's planned thickness per layer at every pixel, um.

    Parameters
    ----------
    plan : BuildPlan
        Gives the placement, the heads' drop density at each radius and the material's
        planned cycles per layer.
    material : str
        Name of one of the job's materials.
    grid : Placement

    Returns
    -------
    (H, W) float64 ndarray
        The estimate's planned thickness per layer (``cycles * cycle_thickness_um`` of the
        measured drop density, per radial bin) at every pixel centre's radius, linear between
        the bins' centres and held beyond them.
    """
    part = plan.placement
    x, y = pixel_centres_model(grid, part)
    xl, yl = part.model_to_local(x, y)
    r = np.hypot(xl[None, :], yl[:, None])
    est = plan.estimates[material]
    return np.interp(r, est.profile_r_mm, est.profile_per_layer_um)


def solid_thickness_um(material, wet_um: dict[str, np.ndarray]) -> np.ndarray:
    """Solid thickness from the deposited ink of each reagent: ``min_i(h_i c_i s_i) M / (rho (1 - porosity))``.

    Parameters
    ----------
    material : Material
    wet_um : dict of str to (H, W) float64
        Per ink, the deposited liquid film (um: 1e-3 L per m^2), every pass and repeat of the
        layer included.

    Returns
    -------
    (H, W) float64 ndarray
        Micrometres of product (the limiting reagent's).
    """
    n = None
    for ink in material.inks:
        m = np.asarray(wet_um[ink.name], np.float64) * 1e-3 * ink.concentration_mol_per_l * ink.stoichiometry  # mol / m^2
        n = m if n is None else np.minimum(n, m)
    p = material.product
    return n * (p.molar_mass_g_per_mol * 1e-3) / (p.density_g_per_cm3 * 1e3 * (1.0 - p.porosity)) * 1e6


def deposited_thickness_um(plan, material: str, prints: dict[str, list[tuple[object, float]]], grid: Placement) -> np.ndarray:
    """``(H, W) float64``: the solid film one layer of ``material`` deposits, per design pixel, um.

    Every ink's drops (:func:`rotoprint.rotary.simulate.place_drops` of each pass's print,
    weighted by how often the pass prints in the layer) are deposited by the deposit model
    (:func:`rotoprint.rotary.deposit.deposit_film`), the film averaged over each pixel's cells,
    and the reagents' films turned into product by :func:`solid_thickness_um`.

    Parameters
    ----------
    plan : BuildPlan
    material : str
    prints : dict of str to list of (RotaryPrint, float)
        Per ink, each interlaced pass's print and its weight (cycles at that pass x repeats).
    grid : Placement
        The design grid of the prints.
    """
    from ..rotary.deposit import InkDrops, deposit_film, ink_drops
    from ..rotary.simulate import place_drops

    mat = plan.job.materials[material]
    head = plan.device.head
    wet = {}
    mask = np.ones((grid.height_px, grid.width_px), bool)
    for ink in mat.inks:
        parts = []
        for pr, w in prints[ink.name]:
            d = ink_drops(place_drops(pr), head)
            parts.append(InkDrops(d.col, d.row, d.volume_pl * float(w)))
        dep = deposit_film(mask, grid, head, [InkDrops.concat(parts)], keep_map=True, options=_resistance_deposit())
        (nx, ny), (ox, oy) = dep.cells_per_pixel, dep.origin_cells
        t = dep.thickness[oy: oy + grid.height_px * ny, ox: ox + grid.width_px * nx]
        wet[ink.name] = t.reshape(grid.height_px, ny, grid.width_px, nx).mean(axis=(1, 3))
    return solid_thickness_um(mat, wet)


def resistance_from_masks(plan, spec, masks: list[np.ndarray], grid: Placement) -> dict:
    """Solve one resistance estimate.

    Parameters
    ----------
    plan : BuildPlan
    spec : ResistanceSpec
        Part and the two terminals.
    masks : list of (H, W) bool
        The material's conductor in each layer (on ``grid``).
    grid : Placement
    """
    material = plan.job.part(spec.part).material
    t_um = thickness_map_um(plan, material, grid)
    layers = [m for m in masks if m.any()]
    total = np.zeros(grid.height_px * grid.width_px).reshape(grid.height_px, grid.width_px)
    for m in layers:
        total += np.where(m, t_um, 0.0)
    return resistance_from_thickness(plan, spec, total, grid, layers=len(layers))


def resistance_from_thickness(plan, spec, total_um: np.ndarray, grid: Placement, *, layers: int) -> tuple[dict, object]:
    """Solve one resistance estimate on a film of ``total_um`` (``(H, W) float64``, the summed
    solid thickness of every layer, um; pixels with none are not conductor)."""
    part_spec = plan.job.part(spec.part)
    material = part_spec.material
    mat = plan.job.materials[material]
    terms = plan.part_terminals(spec.part)
    total = np.asarray(total_um, np.float64)
    g = mat.conductivity_s_per_m * total * 1e-6
    cond = total > 0
    ta = terminal_mask(grid, plan.placement, terms[spec.between[0]])
    tb = terminal_mask(grid, plan.placement, terms[spec.between[1]])
    res = solve_resistance(cond, sheet_conductance_s=g, terminal_a=ta, terminal_b=tb,
                           pitch_x_mm=grid.pitch_x_mm, pitch_y_mm=grid.pitch_y_mm)
    out = {
        "part": spec.part, "material": material, "between": list(spec.between),
        "conductivity_s_per_m": mat.conductivity_s_per_m, "layers": layers,
        "pixel_mm": [grid.pitch_x_mm, grid.pitch_y_mm],
        **res.to_json(),
    }
    return out, res


def coil_hand_check(plan, spec, *, track_layers: int, per_layer_um: float | None = None) -> dict | None:
    """``R = R_s (L / w - (1 - 0.559) corners)`` for a built-in square coil, with the sheet
    thickness of ``track_layers`` layers (the track's own layers; the pads are terminals).

    Parameters
    ----------
    plan : BuildPlan
    spec : ResistanceSpec
        Its part and its two terminals.
    track_layers : int
        Layers of the track; the thickness is ``track_layers`` times ``per_layer_um``.
    per_layer_um : float, optional
        Thickness per layer, um; default the material's smallest planned thickness per layer
        (the build gives the mean of the planned thickness over the part's pixels, the sheet
        the exact-region solution sees).

    Returns
    -------
    dict or None
        ``track_length_mm``, ``track_width_mm``, ``corners``, ``squares``, ``thickness_um``,
        ``sheet_resistance_ohm``, ``resistance_ohm``, ``formula``, ``straight_ohm``
        (``R_s L / w``, None when ``R_s`` is not finite). None unless the part is a
        built-in ``square_coil`` and the terminals are ``outer`` and ``inner``.
    """
    part_spec = plan.job.part(spec.part)
    sh = part_spec.shape
    if sh is None or sh.kind != "square_coil" or set(spec.between) != {"outer", "inner"}:
        return None
    mat = plan.job.materials[part_spec.material]
    est = plan.estimates[part_spec.material]
    t_um = track_layers * (est.per_layer_um[0] if per_layer_um is None else float(per_layer_um))
    rs = 1.0 / (mat.conductivity_s_per_m * t_um * 1e-6)
    L, w, n = sh.track_length_mm(), sh.track_width_mm, sh.corners()
    squares = L / w - (1 - CORNER_SQUARES) * n
    return {"track_length_mm": L, "track_width_mm": w, "corners": n, "squares": squares, "thickness_um": t_um,
            "sheet_resistance_ohm": rs, "resistance_ohm": rs * squares,
            "formula": "R_s * (L / w - 0.441 * corners), R_s = 1 / (sigma * t)",
            "straight_ohm": rs * L / w if math.isfinite(rs) else None}
