"""CAD layer readers: areas against independent shapely geometry, arcs within the tolerance,
bad input refused with one line naming the file and the problem."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from rotoprint.errors import CadError
from rotoprint.io.cad import read_layer
from rotoprint.process.cad_examples import dxf_outline, excellon_holes

HEAD = "%FSLAX46Y46*%\n%MOMM*%\n%LPD*%\nG75*\nG01*\n"


def _c(v):
    return str(int(round(v * 1e6)))


def _write(tmp_path, name, text):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_gerber_straight_primitives_area_exact(tmp_path):
    # rect flash, polygon region, clear rect on top of them, a rotated-free second flash
    g = HEAD + "%ADD10R,2.000000X1.000000*%\n%ADD11R,0.500000X0.500000*%\n"
    g += "D10*\nX1000000Y1000000D03*\nX6000000Y1000000D03*\n"
    g += "G36*\nX0Y3000000D02*\nX4000000Y3000000D01*\nX4000000Y5000000D01*\nX2000000Y6000000D01*\nX0Y3000000D01*\nG37*\n"
    g += "%LPC*%\nD11*\nX1000000Y1000000D03*\nX2000000Y4000000D03*\n%LPD*%\nM02*\n"
    lay = read_layer(_write(tmp_path, "a.gbr", g), tolerance_mm=0.01)
    want = shapely.union_all([shapely.box(0, 0.5, 2, 1.5), shapely.box(5, 0.5, 7, 1.5),
                              shapely.Polygon([(0, 3), (4, 3), (4, 5), (2, 6)])])
    want = want.difference(shapely.union_all([shapely.box(0.75, 0.75, 1.25, 1.25), shapely.box(1.75, 3.75, 2.25, 4.25)]))
    assert lay.area_mm2 == pytest.approx(want.area, rel=1e-9)
    assert lay.region.symmetric_difference(want).area < 1e-9 * want.area
    assert lay.regions == 3 and lay.holes == 2


@pytest.mark.parametrize("tol", [0.01, 0.001])
def test_gerber_arcs_within_tolerance(tmp_path, tol):
    # a circle flash r = 1, a region with a semicircular end (G03), a round-aperture draw
    g = HEAD + "%ADD10C,2.000000*%\n%ADD11C,0.400000*%\n"
    g += "D10*\nX0Y0D03*\n"
    g += "G36*\nX10000000Y-1000000D02*\nX12000000Y-1000000D01*\nG03X12000000Y1000000I0J1000000D01*\nG01X10000000Y1000000D01*\nX10000000Y-1000000D01*\nG37*\n"
    g += "D11*\nX0Y5000000D02*\nX5000000Y5000000D01*\nM02*\n"
    lay = read_layer(_write(tmp_path, "arc.gbr", g), tolerance_mm=tol)
    disc = shapely.Point(0, 0).buffer(1.0, quad_segs=4096)
    cap = shapely.box(10, -1, 12, 1).union(shapely.Point(12, 0).buffer(1.0, quad_segs=4096))
    track = shapely.LineString([(0, 5), (5, 5)]).buffer(0.2, quad_segs=4096)
    exact_area = math.pi + (4 + math.pi / 2) + (5 * 0.4 + math.pi * 0.04)
    perim = 2 * math.pi + (4 + 2 + math.pi) + (10 + 2 * math.pi * 0.2)
    # inscribed chords: the area misses at most perimeter x tolerance, never more
    assert exact_area - perim * tol <= lay.area_mm2 <= exact_area
    ref = shapely.union_all([disc, cap, track])
    assert lay.region.hausdorff_distance(ref) <= tol * 1.01
    assert lay.regions == 3


def test_gerber_terminals_by_net_pin_and_aperture_attribute(tmp_path):
    g = HEAD + "%TATerminal,sense*%\n%ADD10C,1.000000*%\n%TD*%\n%ADD11R,1.000000X1.000000*%\n"
    g += "D10*\nX0Y0D03*\nD11*\n%TO.N,GND*%\n%TO.P,J1,2*%\nX5000000Y0D03*\n%TD*%\nM02*\n"
    lay = read_layer(_write(tmp_path, "t.gbr", g), tolerance_mm=0.01)
    assert set(lay.terminals) == {"sense", "GND", "J1.2"}
    assert lay.terminals["GND"].equals(shapely.box(4.5, -0.5, 5.5, 0.5))


@pytest.mark.parametrize("text, words", [
    (HEAD + "D12*\nX0Y0D03*\nM02*\n", "undefined aperture 12"),
    (HEAD + "G36*\nX0Y0D02*\nX1000000Y0D01*\nX1000000Y1000000D01*\nG37*\nM02*\n", "unclosed contour"),
    (HEAD + "G36*\nX0Y0D02*\nX1000000Y1000000D01*\nX1000000Y0D01*\nX0Y1000000D01*\nX0Y0D01*\nG37*\nM02*\n",
     "self-intersecting"),
])
def test_gerber_bad_input_one_line_exit_2(tmp_path, run_cli, text, words):
    p = _write(tmp_path, "bad.gbr", text)
    with pytest.raises(CadError, match=words):
        read_layer(p, tolerance_mm=0.01)
    code, out, err = run_cli("info", p)
    assert code == 2 and out == ""
    lines = [ln for ln in err.strip().splitlines() if ln]
    assert len(lines) == 1 and "bad.gbr" in lines[0] and words in lines[0], err


def test_gerber_cut_in_hole_is_accepted(tmp_path):
    # a square with a square hole, drawn as one contour with a cut-in
    pts = [(0, 0), (4, 0), (4, 4), (0, 4), (0, 1), (1, 1), (1, 3), (3, 3), (3, 1), (1, 1), (0, 1), (0, 0)]
    g = HEAD + "G36*\n" + f"X{_c(pts[0][0])}Y{_c(pts[0][1])}D02*\n"
    g += "".join(f"X{_c(x)}Y{_c(y)}D01*\n" for x, y in pts[1:]) + "G37*\nM02*\n"
    lay = read_layer(_write(tmp_path, "cut.gbr", g), tolerance_mm=0.01)
    assert lay.area_mm2 == pytest.approx(16 - 4, rel=1e-12)
    assert lay.holes == 1


def test_excellon_drills_area_and_units(tmp_path):
    p = _write(tmp_path, "d.drl", excellon_holes([(0, 0, 0.8), (3, 0, 0.8), (0, 4, 1.0)]))
    tol = 0.001
    lay = read_layer(p, tolerance_mm=tol)
    exact = 2 * math.pi * 0.4**2 + math.pi * 0.5**2
    assert exact - tol * 2 * math.pi * (0.4 + 0.4 + 0.5) <= lay.area_mm2 <= exact
    assert lay.regions == 3
    ref = shapely.union_all([shapely.Point(0, 0).buffer(0.4, quad_segs=2048), shapely.Point(3, 0).buffer(0.4, quad_segs=2048),
                             shapely.Point(0, 4).buffer(0.5, quad_segs=2048)])
    assert lay.region.hausdorff_distance(ref) <= tol * 1.01
    inch = _write(tmp_path, "i.drl", "M48\nINCH\nT1C0.0400\n%\nT1\nX1.0000Y0.0000\nM30\n")
    li = read_layer(inch, tolerance_mm=tol)
    assert li.region.centroid.x == pytest.approx(25.4, abs=1e-9)
    r = 0.02 * 25.4
    assert math.pi * r * r - 2 * math.pi * r * tol <= li.area_mm2 <= math.pi * r * r


def test_dxf_rounded_outline_hole_and_width(tmp_path):
    import ezdxf

    p = tmp_path / "o.dxf"
    p.write_bytes(dxf_outline(0, 0, 20, 10, corner_mm=2.0, holes=[(5, 5, 1.0)]))
    tol = 0.001
    lay = read_layer(p, tolerance_mm=tol)
    exact = 200 - (4 - math.pi) * 4 - math.pi
    assert exact - 2 * tol * (60 + 2 * math.pi) <= lay.area_mm2 <= exact + 2 * tol * 60
    assert lay.holes == 1 and lay.regions == 1
    # an open polyline with a width is a track; a chain of lines that closes is an outline
    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 4
    m = doc.modelspace()
    m.add_lwpolyline([(0, 20), (10, 20)], dxfattribs={"const_width": 0.4})
    for a, b in [((0, 30), (5, 30)), ((5, 30), (5, 31.5)), ((5, 31.5), (0, 31.5)), ((0, 31.5), (0, 30))]:
        m.add_line(a, b)
    q = tmp_path / "t.dxf"
    doc.saveas(q)
    lt = read_layer(q, tolerance_mm=tol)
    want = 10 * 0.4 + math.pi * 0.2**2 + 7.5
    assert lt.area_mm2 == pytest.approx(want, abs=2 * tol * 11)
    # the round caps' chords lie inside the circle by at most the tolerance
    assert 0.4 - 2 * tol <= lt.info()["narrowest_track_mm"] <= 0.4 + 1e-9


def test_dxf_unclosed_chain_and_cm_units(tmp_path):
    import ezdxf

    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 5  # cm
    m = doc.modelspace()
    m.add_line((0, 0), (1, 0))
    m.add_line((1, 0), (1, 1))
    p = tmp_path / "u.dxf"
    doc.saveas(p)
    with pytest.raises(CadError, match="unclosed contour"):
        read_layer(p, tolerance_mm=0.01)
    doc2 = ezdxf.new()
    doc2.header["$INSUNITS"] = 5
    doc2.modelspace().add_lwpolyline([(0, 0), (1, 0), (1, 2), (0, 2)], close=True)
    q = tmp_path / "cm.dxf"
    doc2.saveas(q)
    assert read_layer(q, tolerance_mm=0.01).area_mm2 == pytest.approx(200.0, rel=1e-12)


def _svg(body, width="20mm", height="10mm", view="0 0 20 10"):
    return (f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="{view}">'
            f"{body}</svg>")


def test_svg_fill_stroke_and_units(tmp_path):
    body = ('<rect x="1" y="1" width="6" height="4" fill="black"/>'
            '<path d="M10 2 L18 2" stroke="black" stroke-width="0.5" fill="none"/>'
            '<g transform="translate(0,5) scale(2)"><rect x="0" y="0" width="1" height="1" fill="#000"/></g>')
    p = _write(tmp_path, "a.svg", _svg(body))
    lay = read_layer(p, tolerance_mm=0.001)
    assert lay.area_mm2 == pytest.approx(24 + 8 * 0.5 + 4, rel=1e-9)
    # Y up: the first rect spans y = -5 .. -1 mm
    want = shapely.union_all([shapely.box(1, -5, 7, -1), shapely.box(10, -2.25, 18, -1.75), shapely.box(0, -7, 2, -5)])
    assert lay.region.symmetric_difference(want).area < 1e-9
    circ = _write(tmp_path, "c.svg", _svg('<circle cx="10" cy="5" r="3" fill="none" stroke="black" stroke-width="1"/>'))
    lc = read_layer(circ, tolerance_mm=0.001)
    exact = math.pi * (3.5**2 - 2.5**2)
    assert lc.area_mm2 == pytest.approx(exact, abs=0.001 * 2 * math.pi * 6.2)
    assert lc.holes == 1


def test_svg_bad_input(tmp_path, run_cli):
    deep = "".join('<g transform="translate(0.01,0)">' for _ in range(40)) + '<rect width="1" height="1"/>' + "</g>" * 40
    p = _write(tmp_path, "deep.svg", _svg(deep))
    with pytest.raises(CadError, match="transforms are nested more than 32 deep"):
        read_layer(p, tolerance_mm=0.01)
    q = _write(tmp_path, "kg.svg", _svg('<rect width="1" height="1"/>', width="20kg"))
    code, out, err = run_cli("info", q)
    assert code == 2 and "kg.svg" in err and "not a length" in err
    assert len(err.strip().splitlines()) == 1


def test_info_json_reports_area(tmp_path, run_cli):
    import json

    g = HEAD + "%ADD10R,2.000000X1.000000*%\nD10*\nX0Y0D03*\nX0Y2000000D03*\nM02*\n"
    p = _write(tmp_path, "i.gbr", g)
    code, out, err = run_cli("info", p, "--json")
    assert code == 0, err
    d = json.loads(out)
    assert d["area_mm2"] == pytest.approx(4.0, rel=1e-12)
    assert d["regions"] == 2 and d["holes"] == 0
    assert d["narrowest_track_mm"] == pytest.approx(1.0, abs=1e-9)
    assert d["narrowest_gap_mm"] == pytest.approx(1.0, abs=1e-9)
    assert d["bounds_mm"] == {"min": [-1.0, -0.5], "max": [1.0, 2.5]}
    np.testing.assert_allclose(d["size_mm"], [2.0, 3.0])


def test_tolerance_range_and_units_for_gerber_refused(tmp_path):
    p = _write(tmp_path, "r.gbr", HEAD + "%ADD10C,1.000000*%\nD10*\nX0Y0D03*\nM02*\n")
    with pytest.raises(CadError, match="tolerance must be"):
        read_layer(p, tolerance_mm=1e-9)
    with pytest.raises(CadError, match="states its own units"):
        read_layer(p, tolerance_mm=0.01, units="in")
    with pytest.raises(CadError, match="not a length"):
        read_layer(_write(tmp_path, "x.svg", _svg('<rect width="1" height="1"/>')), tolerance_mm=0.01, units="kg")


def test_gerber_arc_draw_and_macro_exposure_off(tmp_path):
    tol = 0.001
    # quarter-circle draw (G02, clockwise) of radius 2 with a 0.4 mm round aperture
    g = HEAD + "%ADD10C,0.400000*%\nD10*\nX0Y2000000D02*\nG02X2000000Y0I0J-2000000D01*\nG01*\nM02*\n"
    lay = read_layer(_write(tmp_path, "arc.gbr", g), tolerance_mm=tol)
    t = np.linspace(math.pi / 2, 0, 20001)
    ref = shapely.LineString(np.stack([2 * np.cos(t), 2 * np.sin(t)], 1)).buffer(0.2, quad_segs=1024)
    exact = math.pi / 4 * (2.2**2 - 1.8**2) + math.pi * 0.2**2
    assert exact - tol * (2 * math.pi * 2.2 / 4 + 2 * math.pi * 1.8 / 4 + 2 * math.pi * 0.2) <= lay.area_mm2 <= exact
    assert lay.region.hausdorff_distance(ref) <= tol * 1.01
    # a macro's exposure-off circle clears only inside the macro, not the rectangle under it
    m = HEAD + "%AMDONUT*1,1,2,0,0*1,0,1,0,0*%\n%ADD10R,4.000000X4.000000*%\n%ADD11DONUT*%\n"
    m += "D10*\nX0Y0D03*\nD11*\nX0Y0D03*\nX5000000Y0D03*\nM02*\n"
    lm = read_layer(_write(tmp_path, "macro.gbr", m), tolerance_mm=tol)
    ring = math.pi * (1.0 - 0.25)
    assert 16 + ring - tol * 2 * math.pi * 1.5 <= lm.area_mm2 <= 16 + ring + 1e-9
    assert lm.holes == 1 and lm.regions == 2


def test_info_prints_a_layers_and_a_meshs_bounds_in_one_table_form(run_cli, tmp_path):
    """`rotoprint info` on a DXF layer and on an STL of the same outline: the same quantity |
    value table (cli._common.print_quantities), bounds rows alike, in order after two rows."""
    from rotoprint.examples import write_binary_stl
    from rotoprint.primitives import box_triangles

    dxf = tmp_path / "o.dxf"
    dxf.write_bytes(dxf_outline(0, 0, 20, 10))
    stl = tmp_path / "o.stl"
    write_binary_stl(stl, box_triangles((20, 10, 1)))
    tables = {}
    for p in (dxf, stl):
        code, out, err = run_cli("info", p)
        assert code == 0, err
        lines = [ln for ln in out.splitlines() if "(mm)" in ln and ("bounds" in ln or "size" in ln)]
        tables[p.suffix] = lines
        rows = [ln for ln in out.splitlines() if "│" in ln or "|" in ln]
        names = [r.strip("│| ").split("│")[0].strip() for r in rows]
        assert names.index("bounds min (mm)") == 2 and names[3:5] == ["bounds max (mm)", "size (mm)"], names
    assert "20.0000 x 10.0000" in tables[".dxf"][2] and "20.0000 x 10.0000 x 1.0000" in tables[".stl"][2]
    assert "0.0000, 0.0000" in tables[".dxf"][0] and "0.0000, 0.0000, 0.0000" in tables[".stl"][0]


def test_dxf_without_a_header_is_unitless_mm(tmp_path):
    # a minimal R12 file (ENTITIES only, as small writers make): ezdxf gives it its own default
    # $INSUNITS (metres); the file declares none, so it is unitless: millimetres, not 1000 x larger
    q = tmp_path / "c.dxf"
    q.write_text("0\nSECTION\n2\nENTITIES\n0\nCIRCLE\n8\n0\n10\n5.0\n20\n5.0\n30\n0.0\n40\n2.0\n0\nENDSEC\n0\nEOF\n")
    lay = read_layer(q, tolerance_mm=0.001)
    assert lay.area_mm2 == pytest.approx(math.pi * 2.0**2, rel=1e-3)
