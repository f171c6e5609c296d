"""The demo's films (issue 14): the plan's drops per area measured over the design's interior
at the landing radius, and the build's film measured on the film grid (the assembly grid
divided into deposit cells) against the design rasterised at the cells' centres."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint.pipeline import build as B
from rotoprint.pipeline.examples import write_example
from rotoprint.process import load_job, parse_job
from rotoprint.process.plan import THICKNESS_SPREAD_WARN, plan_job
from rotoprint.rotary.deposit import DepositOptions, InkDrops, deposit_film, film_cells, film_grid
from rotoprint.rotary.placement import Placement


@pytest.fixture(scope="module")
def coil(tmp_path_factory):
    """The demo's job (the coil sensor) written by write_example, loaded and planned."""
    root = tmp_path_factory.mktemp("coil")
    job = load_job(write_example("coil-sensor", root / "job"))
    return job, plan_job(job), root


def test_silver_drops_per_area_are_measured_over_the_interior(coil):
    job, plan, _ = coil
    sil, pla = plan.estimates["silver"], plan.estimates["plaster"]
    # every material prints on the same equalised lattice, so the coil's interior gets the
    # plaster body's drops per area; counted over tracks grazing the 0.5 mm traces' edges and
    # over whole 70 um pixels, silver's bins spread 774..982 per mm2 (27 %) and the plan warned
    ref = float(np.mean(np.concatenate(list(pla.drops_per_mm2.values()))))
    for ink, dens in sil.drops_per_mm2.items():
        assert dens.size >= 15 and np.all(np.abs(dens / ref - 1) < 0.06), (ink, dens.round(1), ref)
    lo, hi = sil.per_cycle_um
    assert hi / lo - 1 < THICKNESS_SPREAD_WARN
    assert not any(w.startswith("silver: the thickness per cycle varies") for w in plan.warnings)
    # the cycles of the body and the cover stay what they were
    assert (pla.cycles, plan.estimates["epoxy"].cycles, sil.cycles) == (8, 12, 24)
    src = sil.density_source
    g = plan.design_grid()
    assert src["cell_um"][0] < g.pitch_x_mm * 1e3 / 4 and "interior" in src["rule"]
    assert 0 < src["area_mm2"] < 0.95 * 122.9  # the interior: less than the coil's design area


def test_the_spread_warning_names_the_radii_and_what_to_do():
    job = parse_job({"job": {"name": "wide", "layer_height_mm": 0.05},
                     "printer": {"device": "omnidot760", "tilt_deg": 20.0, "equalise": False, "passes": 1,
                                 "heads": [{"name": "H1", "ink": "ammonium_sulphate"},
                                           {"name": "H2", "ink": "calcium_chloride", "mount_angle_deg": 90.0}]},
                     "placement": {"inner_radius_mm": 40.0},
                     "parts": [{"name": "b", "material": "plaster", "priority": 1,
                                "shape": {"kind": "box", "size_mm": [12, 2, 0.05], "origin_mm": [0, 0, 0]}}]},
                    source="wide.toml")
    plan = plan_job(job)
    est = plan.estimates["plaster"]
    lo, hi = est.per_cycle_um
    assert hi / lo - 1 > 0.2  # one angular clock: 1/r over 40..52 mm
    (w,) = [w for w in plan.warnings if "varies by" in w]
    r_thin = float(est.profile_r_mm[np.argmin(est.profile_per_layer_um)])
    r_thick = float(est.profile_r_mm[np.argmax(est.profile_per_layer_um)])
    assert r_thin > 50 and r_thick < 42  # the outer radii get the fewest drops per area
    assert f"thinnest in the 1 mm bin at {r_thin:.1f} mm, thickest at {r_thick:.1f} mm" in w
    assert "set printer.equalise = true" in w


def test_a_mask_on_the_film_grid_is_the_pixel_mask_where_it_repeats_each_pixel():
    from rotoprint import load_device

    head = load_device("omnidot760").head
    pl = Placement(30, 80, 25.4 / 360, 25.4 / 1440, inner_radius_mm=60.0)
    nx, ny = film_cells(pl, head)
    fg = film_grid(pl, head)
    assert (nx, ny) == (8, 2) and (fg.width_px, fg.height_px) == (30 * nx, 80 * ny)
    assert fg.width_mm == pytest.approx(pl.width_mm) and fg.height_mm == pytest.approx(pl.height_mm)
    mask = np.zeros((80, 30), bool)
    mask[10:70, 5:25] = True
    rng = np.random.default_rng(3)
    cc, rr = np.meshgrid(np.arange(5, 25, 0.7), np.arange(10, 70, 0.25))
    drops = InkDrops(cc.ravel() + rng.uniform(0, 0.3, cc.size), rr.ravel(), np.full(cc.size, 8.0))
    a = deposit_film(mask, pl, head, [drops]).films[0]
    b = deposit_film(np.repeat(np.repeat(mask, ny, axis=0), nx, axis=1), pl, head, [drops]).films[0]
    assert a.to_json() == b.to_json()
    # a mask exact to a cell: a slanted edge moves the design by fractions of a pixel
    cells = np.zeros((80 * ny, 30 * nx), bool)
    cells[20:140, 40:200] = True
    cells[:, 40:200] &= (np.arange(40, 200)[None, :] < 120 + np.arange(160)[:, None] // 2)
    c = deposit_film(cells, pl, head, [drops]).films[0]
    assert c.design_area_mm2 == pytest.approx(cells.sum() * fg.pitch_x_mm * fg.pitch_y_mm)
    with pytest.raises(Exception, match="film grid 240 x 160 cells"):
        deposit_film(np.zeros((81, 30), bool), pl, head, [drops])


def test_the_demo_film_is_measured_on_the_film_grid(coil):
    job, plan, root = coil
    (root / "overlays").mkdir(exist_ok=True)
    head = plan.device.head
    g = plan.design_grid()
    fg = film_grid(g, head, DepositOptions())
    assert fg.width_px == 8 * g.width_px and fg.height_px == 2 * g.height_px  # finer than the assembly grid
    (o,) = B.stage_simulate(job, plan, {"silver": [8]}, root, lambda *a: None)  # the coil's first layer
    secs = plan.sections(8)
    cells = plan.reference_image("silver", secs, grid=fg)
    pixels = plan.reference_image("silver", secs)
    for ink, f in o["inks"].items():
        assert f["grid_um"] == pytest.approx([fg.pitch_x_mm * 1e3, fg.pitch_y_mm * 1e3])
        # the design exact to a cell, not to a 70 um pixel
        assert f["design_area_mm2"] == pytest.approx(cells.sum() * fg.pitch_x_mm * fg.pitch_y_mm)
        assert abs(f["design_area_mm2"] - pixels.sum() * g.pitch_x_mm * g.pitch_y_mm) > 0.3
        # sane figures: every drop's volume on the grid, the interior covered, no thin cell at
        # a trace's edge (on the pixel mask the thinnest was 0.22 of the mean as landed, 0.47
        # levelled: cells up to 35 um beyond the exact edge counted as design)
        assert abs(f["volume_error_fraction"]) < 1e-9 and f["uncovered_fraction"] <= 0.01
        assert f["band_uncovered_fraction"] <= 0.01 and f["volume_outside_design_fraction"] < 0.05
        assert f["thinnest_to_mean"] >= 0.5 and f["levelled"]["thinnest_to_mean"] >= 0.7
        assert f["radial_spread"] < 0.05 and 0.9 < f["levelled"]["mean_um"] / f["mean_um"] < 1.1


def test_interior_mask_is_the_distance_rule_strip_by_strip():
    from scipy.ndimage import distance_transform_edt

    from rotoprint.rotary.deposit import interior_mask

    rng = np.random.default_rng(5)
    m = np.zeros((300, 120), bool)
    for _ in range(40):
        r, c = rng.integers(0, 300), rng.integers(0, 120)
        m[max(0, r - 20): r + 20, max(0, c - 15): c + 15] = True
    whole = interior_mask(m, 8.8, 8.82, 30.0, strip_cells=10**9)
    # the cells' centres at least 30 um from every centre outside (beyond the array is outside)
    ref = (distance_transform_edt(np.pad(m, 1), sampling=(8.82, 8.8)) >= 30.0)[1:-1, 1:-1]
    assert np.array_equal(whole, ref) and 0 < whole.sum() < m.sum()
    for cells in (10_000, 1_000, 200):  # strips of 81, 8 and 1 rows with their halos
        assert np.array_equal(interior_mask(m, 8.8, 8.82, 30.0, strip_cells=cells), whole), cells
