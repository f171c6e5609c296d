"""The planar-layer part type: placement (mirror, rotate, translate), holes from drill files,
the slicer's cross-section from the polygon edges, the extruded mesh, exact printability."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely

from rotoprint.errors import CadError
from rotoprint.io.cad import read_layer
from rotoprint.pipeline.build import _layer_printability
from rotoprint.process.cad_examples import dxf_outline, excellon_holes
from rotoprint.process.cadparts import LayerFile, layer_segments, load_layer_part
from rotoprint.process.job import PartSpec

HEAD = "%FSLAX46Y46*%\n%MOMM*%\n%LPD*%\nG75*\n"


def _part(**layer):
    extra = layer.pop("_part", {})
    return PartSpec(name="p", material="silver", layer=LayerFile(**layer), **extra)


def test_mirror_rotate_translate(tmp_path):
    (tmp_path / "r.gbr").write_text(HEAD + "%ADD10R,2.000000X1.000000*%\nD10*\nX2000000Y1000000D03*\nM02*\n")
    pl = load_layer_part(tmp_path, _part(file="r.gbr", z_mm=(0.0, 0.02), mirror=True,
                                         _part={"rotate_deg": (0, 0, 90), "translate_mm": (10, 0, 0.1)}),
                         default_tolerance_mm=0.001)
    # centre (2, 1) -> mirror (-2, 1) -> rotate 90 deg (-1, -2) -> translate (9, -2); 2 x 1 becomes 1 x 2
    np.testing.assert_allclose(pl.layer.region.bounds, (8.5, -3.0, 9.5, -1.0), atol=1e-12)
    assert (pl.z0_mm, pl.z1_mm) == pytest.approx((0.1, 0.12))
    with pytest.raises(CadError, match="about Z only"):
        load_layer_part(tmp_path, _part(file="r.gbr", z_mm=(0.0, 0.02), _part={"rotate_deg": (10, 0, 0)}),
                        default_tolerance_mm=0.001)


def test_holes_from_drill_file_and_extruded_mesh(tmp_path):
    (tmp_path / "b.dxf").write_bytes(dxf_outline(0, 0, 10, 10))
    (tmp_path / "v.drl").write_text(excellon_holes([(3, 3, 1.0), (7, 7, 1.0)]))
    tol = 0.001
    pl = load_layer_part(tmp_path, _part(file="b.dxf", z_mm=(0.0, 0.2), holes=("v.drl",), tolerance_mm=tol),
                         default_tolerance_mm=0.01)
    drills = read_layer(tmp_path / "v.drl", tolerance_mm=tol)
    assert pl.layer.holes == 2
    assert pl.layer.area_mm2 == pytest.approx(100 - drills.area_mm2, rel=1e-12)
    m = pl.mesh()
    info = m.info()
    assert info["watertight"] and info["open_edges"] == 0
    assert info["volume_mm3"] == pytest.approx(pl.layer.area_mm2 * 0.2, rel=1e-9)


def test_slicer_cross_section_is_the_polygon(tmp_path):
    """The slicer's fill of the layer's segments (nonzero winding, the direct slicer's inside
    rule) equals shapely's point-in-polygon at every pixel centre."""
    from rotoprint.process.conductance import pixel_centres_model
    from rotoprint.rotary.direct import PartPlacement, rasterize_section

    (tmp_path / "b.dxf").write_bytes(dxf_outline(0, 0, 6, 4, corner_mm=1.0, holes=[(2, 2, 0.7), (4.2, 2, 0.5)]))
    lay = read_layer(tmp_path / "b.dxf", tolerance_mm=0.002)
    seg = layer_segments(lay)
    part = PartPlacement(60.0, 0.0, tuple(lay.region.bounds))
    grid = part.design_placement(0.01, 0.013)
    img = rasterize_section(seg, part, grid) > 0
    x, y = pixel_centres_model(grid, part)
    want = shapely.contains_xy(lay.region, x[None, :], y[:, None])
    assert img.sum() > 100_000
    assert np.array_equal(img, want)


def test_exact_printability_of_a_thin_track(tmp_path):
    from rotoprint.process.cadparts import PlacedLayer

    g = HEAD + "%ADD10C,0.030000*%\n%ADD11C,0.300000*%\nD10*\nX0Y0D02*\nX5000000Y0D01*\nD11*\nX0Y1000000D02*\nX5000000Y1000000D01*\nM02*\n"
    (tmp_path / "t.gbr").write_text(g)
    lay = read_layer(tmp_path / "t.gbr", tolerance_mm=0.0005)
    pl = PlacedLayer("t", lay, 0.0, 0.02, "t.gbr")
    r = _layer_printability(pl, {"min_wall_mm": 0.0706, "min_gap_mm": 0.0706})
    assert r["narrowest_track_mm"] == pytest.approx(0.03, abs=0.001)
    assert not r["track_ok"] and r["gap_ok"] and not r["ok"]
    # the gap between the two tracks: 1 mm between centrelines minus the half widths
    assert r["narrowest_gap_mm"] == pytest.approx(1 - 0.015 - 0.15, abs=0.001)


def test_job_validation_of_layer_parts():
    from pydantic import ValidationError

    with pytest.raises(ValidationError, match="not a length unit"):
        LayerFile(file="a.gbr", z_mm=(0, 1), units="kg")
    with pytest.raises(ValidationError, match="top > bottom"):
        LayerFile(file="a.gbr", z_mm=(1, 0.5))
    with pytest.raises(ValidationError, match="not a layer file"):
        LayerFile(file="a.stl", z_mm=(0, 1))
    with pytest.raises(ValidationError, match="exactly one of"):
        PartSpec(name="p", material="silver", mesh="a.stl", layer=LayerFile(file="a.gbr", z_mm=(0, 1)))
    assert math.isfinite(LayerFile(file="a.svg", z_mm=(0, 1)).z_mm[1])
