"""Hostile Gerber, Excellon, SVG and DXF layers through `rotoprint info`, as a user runs it.

Each refusal: exit 2, one line naming the file and the problem, no traceback, nothing written.
An empty but well-formed layer (a header and an end, as a CAD tool writes an unused paste or
drill layer) is legitimate: its figures are printed without a NaN, its JSON parses strictly.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from _bounds_helpers import assert_refused, run_cli_bounded, tree

HEADER_GERBER = "%FSLAX26Y26*%\n%MOMM*%\nM02*\n"
HEADER_EXCELLON = "M48\nMETRIC\n%\nM30\n"


def _refused(tmp_path, name: str, text: str | bytes, *fragments: str) -> str:
    p = tmp_path / name
    p.write_bytes(text if isinstance(text, bytes) else text.encode())
    before = tree(tmp_path)
    line = assert_refused(run_cli_bounded("info", name, cwd=tmp_path), f"{name}:", *fragments)
    assert tree(tmp_path) == before
    return line


@pytest.mark.parametrize(("name", "text", "said"), [
    ("empty.gbr", "", "no Gerber content (empty)"),
    ("blank.gtl", "\n \n\t\n", "no Gerber content (empty)"),
    ("empty.drl", "", "no Excellon content (empty)"),
    ("prose.gbr", "hello world\nthis is no Gerber\n", "no Gerber units and nothing drawn (truncated, or not a Gerber file)"),
])
def test_empty_or_statementless_gerber_and_excellon_are_refused(tmp_path, name, text, said):
    _refused(tmp_path, name, text, said)


def _strict_json(text: str) -> dict:
    def no_constant(c):
        raise AssertionError(f"{c} in the JSON")

    return json.loads(text, parse_constant=no_constant)


@pytest.mark.parametrize(("name", "text"), [("paste.gbr", HEADER_GERBER), ("none.drl", HEADER_EXCELLON),
                                            ("blank.svg", '<svg xmlns="http://www.w3.org/2000/svg" width="10mm" height="5mm"/>')])
def test_an_empty_well_formed_layer_has_sane_figures(tmp_path, name, text):
    (tmp_path / name).write_text(text)
    run = run_cli_bounded("info", name, cwd=tmp_path)
    assert run.code == 0, run.err
    assert "nan" not in run.out.lower() and "inf" not in run.out.lower(), run.out
    assert "empty layer" in run.out
    run = run_cli_bounded("info", "--json", name, cwd=tmp_path)
    assert run.code == 0, run.err
    d = _strict_json(run.out)
    assert d["area_mm2"] == 0.0 and d["regions"] == 0
    assert d["bounds_mm"] is None and d["size_mm"] is None


def _svg(root_attrs: str, body: str = '<rect x="0" y="0" width="10" height="10" fill="black"/>') -> str:
    return f'<svg xmlns="http://www.w3.org/2000/svg" {root_attrs}>{body}</svg>'


@pytest.mark.parametrize(("attrs", "body", "said"), [
    ('width="1e300mm" height="1e300mm" viewBox="0 0 10 10"', None, "width='1e300mm' of the <svg> element makes the page 1e+300 mm"),
    ('width="10mm" height="1e300in" viewBox="0 0 10 10"', None, "height='1e300in' of the <svg> element makes the page 2.54e+301 mm"),
    ('width="1e300mm" height="1e300mm"', None, "makes the page 1e+300 mm"),  # no viewBox: the page alone
    ('viewBox="0 0 1e300 1e300"', None, "viewBox='0 0 1e300 1e300' (width) of the <svg> element makes the page 2.65e+299 mm"),
    ('width="10mm" height="10mm" viewBox="0 0 nan 10"', None, "viewBox='0 0 nan 10' of the <svg> element is not four finite numbers"),
    ('width="10mm" height="10mm" viewBox="0 0 10 10"', '<rect width="1e300" height="1e300" fill="black"/>',
     "the layer would be 1e+300 x 1e+300 mm"),
    ('width="10mm" height="10mm" viewBox="0 0 10 10"', '<rect width="1" height="1" transform="scale(1e300)" fill="black"/>',
     "the layer would be 1e+300 x 1e+300 mm"),
    ('width="10mm" height="10mm" viewBox="0 0 10 10"', '<rect x="20000" width="1" height="1" fill="black"/>',
     "from (2e+04, -1) to (2e+04, 0) mm; a layer must lie in [-10000, 10000] mm"),
    ('width="10mm" height="10mm" viewBox="0 0 10 10"', '<circle cx="0" cy="0" r="1e300" fill="black"/>', "not a finite number"),
    ('width="10mm" height="10mm" viewBox="0 0 10 10"', '<path d="M 0 0 A 1e300 1e300 0 0 1 10 10 Z" fill="black"/>',
     "not a finite number"),
    ('width="10mm" height="10mm" viewBox="0 0 10 10"', '<circle cx="0" cy="0" r="1e20" fill="black"/>', "use a larger tolerance"),
])
def test_svg_of_a_huge_size_is_refused_with_the_size(tmp_path, attrs, body, said):
    _refused(tmp_path, "big.svg", _svg(attrs, *(() if body is None else (body,))), said)


def test_a_huge_page_in_the_users_own_units_is_measured_in_them(tmp_path):
    (tmp_path / "p.svg").write_text(_svg('width="1000" height="10"'))  # 1000 px: 264.6 mm, or 1000 m with --units m
    assert run_cli_bounded("info", "p.svg", cwd=tmp_path).code == 0
    line = assert_refused(run_cli_bounded("info", "p.svg", "--units", "m", cwd=tmp_path), "p.svg:")
    assert "makes the page 1e+06 mm" in line, line


def test_far_gerber_excellon_and_dxf_coordinates_are_refused(tmp_path):
    _refused(tmp_path, "far.drl", "M48\nMETRIC\nT1C1.0\n%\nT1\nX1.0Y1.0\nX9999999.0Y1.0\nM30\n",
             "the layer would be 1e+07 x 0.998 mm", "METRIC or INCH")
    _refused(tmp_path, "far.gbr", "%FSLAX66Y66*%\n%MOIN*%\n%ADD10C,0.01*%\nD10*\nX999999000000Y0D03*\nM02*\n",
             "from (2.54e+07, -0.126)", "%FS and %MO")
    dxf = "\n".join(["0", "SECTION", "2", "ENTITIES", "0", "CIRCLE", "8", "0", "10", "1e200", "20", "0.0", "30", "0.0",
                     "40", "1.0", "0", "ENDSEC", "0", "EOF", ""])
    _refused(tmp_path, "far.dxf", dxf, "the layer would be", "$INSUNITS")


CAD_COIL = Path(__file__).resolve().parents[2] / "examples" / "cad-coil"


@pytest.mark.parametrize("name", ["coil-F_Cu.gbr", "coil-vias.drl", "coil-body.dxf"])
def test_a_cut_short_layer_file_is_refused_at_every_cut(tmp_path, name):
    """A copy that stopped part way lacks what comes after the cut: never a smaller layer. The
    Gerber and Excellon cuts lack their end statement (M02, M30); the DXF its EOF (ezdxf's
    tag reader ran out inside a section: it was a StopIteration traceback)."""
    from rotoprint.errors import RotoprintError
    from rotoprint.io.cad import read_layer

    data = (CAD_COIL / name).read_bytes()
    whole = read_layer(CAD_COIL / name, tolerance_mm=0.01)
    assert whole.area_mm2 > 0
    cuts = sorted({int(len(data) * f) for f in np.linspace(0.02, 0.98, 25)} | {len(data) - 5})
    p = tmp_path / name
    for cut in cuts:
        p.write_bytes(data[:cut])
        with pytest.raises(RotoprintError) as ei:
            read_layer(p, tolerance_mm=0.01)
        assert str(ei.value).startswith(f"{p}: "), (cut, str(ei.value))


@pytest.mark.parametrize(("name", "cut", "said"), [
    ("coil-F_Cu.gbr", 400, "no M02* or M00* end statement at its end: the file is cut short"),
    ("coil-vias.drl", 60, "no Excellon units and nothing drilled (truncated, or not an Excellon file)"),
    ("coil-body.dxf", 2000, "not a readable DXF file: it ends inside a section (truncated)"),
])
def test_a_cut_short_layer_is_one_line_from_the_cli(tmp_path, name, cut, said):
    _refused(tmp_path, name, (CAD_COIL / name).read_bytes()[:cut], said)


def test_an_excellon_rewind_stop_after_m30_is_read(tmp_path):
    """Some CAM tools end a drill file with a rewind-stop '%' after M30: it is complete; without M30 it is not."""
    from rotoprint.io.cad import read_layer

    body = "M48\nMETRIC\nT1C1.0\n%\nT1\nX1.0Y1.0\n"
    (tmp_path / "a.drl").write_text(body + "M30\n%\n\n")
    (tmp_path / "b.drl").write_text(body + "M30\n")
    a, b = (read_layer(tmp_path / n, tolerance_mm=0.001) for n in ("a.drl", "b.drl"))
    assert a.region.area == b.region.area > 0.78
    _refused(tmp_path, "c.drl", body + "%\n", "no M30 or M00 end statement at its end: the file is cut short")


def _dxf(tmp_path, name: str, add) -> str:
    import ezdxf

    doc = ezdxf.new()
    doc.header["$INSUNITS"] = 4  # mm
    add(doc.modelspace())
    doc.saveas(tmp_path / name)
    return (tmp_path / name).read_text()


@pytest.mark.parametrize(("case", "said"), [
    ("circle r=0", "CIRCLE (handle"),  # were shapely's 'A linearring requires at least 4 coordinates' tracebacks
    ("circle r=-1", "has radius -1; a circle needs a positive radius"),
    ("spline, singular", "SPLINE (handle"),  # was numpy's LinAlgError traceback
    ("ellipse 1e300", "ELLIPSE (handle"),  # was a RecursionError traceback
])
def test_a_degenerate_dxf_entity_is_one_line_naming_it(tmp_path, case, said):
    adds = {
        "circle r=0": lambda m: m.add_circle((0, 0), 0),
        "circle r=-1": lambda m: m.add_circle((0, 0), -1),
        "spline, singular": lambda m: m.add_spline([(0, 0), (1e300, 1), (2, 0), (0, 0)]),
        "ellipse 1e300": lambda m: m.add_ellipse((0, 0), major_axis=(1e300, 0), ratio=0.5),
    }
    text = _dxf(tmp_path, "src.dxf", adds[case])
    line = _refused(tmp_path, "e.dxf", text, said)
    assert "Traceback" not in line


SVG_ROOT = 'width="10mm" height="10mm" viewBox="0 0 10 10"'


@pytest.mark.parametrize(("body", "said"), [
    ('<circle r="-1" fill="black"/>', "<circle> r='-1' is a negative length"),  # was drawn as a circle of radius 1
    ('<path d="M 0 0 L 1 1" stroke="black" stroke-width="-1"/>', "<path> stroke-width='-1' is a negative length"),
    ('<path d="M 0 0 C 1e300 1e300 2 2 3 3 Z" fill="black"/>', "a curve needs 4.61e+151 chords"),  # was a 150-digit count
    ('<use href="#a"/><g id="a"><use href="#a"/></g>', "its <use> references loop"),  # was a RecursionError traceback
    # were svgelements' 'tuple index out of range' and a GEOSException traceback
    ('<rect width="1" height="1" transform="matrix(nan 0 0 1 0 0)" fill="black"/>',
     "transform='matrix(nan 0 0 1 0 0)' of a <rect> holds a number that is not finite"),
    ('<rect width="1" height="1" transform="translate(1,1e999)" fill="black"/>',
     "transform='translate(1,1e999)' of a <rect> holds a number that is not finite"),
    # each of these was left out of the layer without a word
    ('<path d="M 1 1 L nan 5 L 5 5 Z" fill="black"/>', "<path> d='M 1 1 L nan 5 L 5 5 Z': character 9 ('nan 5 L 5 5 ') is not path data"),
    ('<path id="t1" d="M 1 1 L 5 x 5 Z"/>', '<path id="t1"> d=\'M 1 1 L 5 x 5 Z\': character 11'),
    ('<path d="L 1 1 2 2"/>', "path data starts with 'L', not a moveto"),
    ('<path d="M 1 1 C 2 2 3 3 Z"/>', "'C' takes numbers in groups of 6, got 4"),
    ('<path d="M 1 1 a 1 1 0 2 1 3 3"/>', "arc flag expected at character 15"),
    ('<path d="M 1 1 L 1e308 5 L 5 5 Z"/>', "<path> has a point beyond the float range"),
    ('<rect x="5" y="5" width="abc" height="3"/>', "<rect> width='abc' is not a length"),
    ('<circle cx="5" cy="5" r="1e999"/>', "<circle> r='1e999' is not a length"),
    ('<polygon points="5,5 6,q 7,7"/>', "<polygon> points='5,5 6,q 7,7': 'q' is not a number"),
    ('<polyline points="5,5 6,6 7" stroke="black"/>', "an odd number of coordinates (5): the last point has no y"),
])
def test_a_hostile_svg_element_is_one_line(tmp_path, body, said):
    _refused(tmp_path, "e.svg", _svg(SVG_ROOT, body), said)


def test_svg_path_data_forms_and_empty_shapes(tmp_path):
    """Legal path data in its terse forms reads as its long form; shapes that draw nothing are counted."""
    from rotoprint.io.cad.svg import read_svg

    long_ = '<path d="M 1 1 A 1 1 0 0 1 3 3 L 3 1 Z M 10 10 L 11.5 10.5 L 13 13 Z M 0.5 5.5 L 2 5.5 L 2 7 Z" fill="black"/>'
    terse = '<path d="M1,1a1 1 0 012 2L3,1zM10 10 11.5 10.5 13 13zM.5 5.5 2 5.5 2 7z" fill="black"/>'
    empty = '<path d=""/><polygon points="5,5"/><rect width="4" height="4" fill="none"/>'
    areas = []
    for i, body in enumerate((long_, terse, terse + empty)):
        (tmp_path / f"{i}.svg").write_text(_svg(SVG_ROOT, body))
        layer = read_svg(tmp_path / f"{i}.svg", tolerance_mm=0.001)
        areas.append(layer.region.area)
        assert layer.counts["empty"] == (3 if i == 2 else 0), layer.counts
    assert areas[0] > 1.0
    np.testing.assert_allclose(areas[1:], areas[0], rtol=1e-12)


GERBER_HEAD = "%FSLAX46Y46*%\n%MOMM*%\n"


@pytest.mark.parametrize(("name", "text", "said"), [
    # 10^12 copies would have run the machine out of memory; gerbonara draws an SR block once
    ("sr.gbr", GERBER_HEAD + "%SRX1000000Y1000000I1J1*%\n%ADD10C,1*%\nD10*\nX0Y0D03*\n%SR*%\nM02*\n",
     "line 3: %SR step and repeat of 1,000,000 x 1,000,000 copies is not read"),
    ("sr6.gbr", GERBER_HEAD + "%ADD10C,1*%\n%SRX3Y2I5J5*%\nD10*\nX0Y0D03*\nX2000000Y0D03*\n%SR*%\nM02*\n",
     "line 4: %SR step and repeat of 3 x 2 copies is not read (the Gerber reader would draw one copy)"),
    # a polygon is built vertex by vertex: 10^9 of them never finished
    ("gon.gbr", GERBER_HEAD + "%ADD10P,1X1000000000*%\nD10*\nX0Y0D03*\nM02*\n",
     "line 3: a polygon aperture of 1000000000 vertices; a Gerber polygon has 3 to 12"),
    ("gon2.gbr", GERBER_HEAD + "%ADD10P,1X2*%\nD10*\nX0Y0D03*\nM02*\n", "a polygon aperture of 2 vertices"),
    ("am.gbr", GERBER_HEAD + "%AMGON*5,1,100000000,0,0,1,0*%\n%ADD10GON*%\nD10*\nX0Y0D03*\nM02*\n",
     "line 3: a macro polygon (primitive 5) of 100000000 vertices"),
    ("rep.drl", "M48\nMETRIC\nT1C1.0\n%\nT1\nX1.0Y1.0\nR1000000000X0.1Y0\nM30\n",
     "line 7: R1000000000 repeats a hole 1,000,000,000 times"),
])
def test_a_declared_expansion_is_bounded_before_reading(tmp_path, name, text, said):
    _refused(tmp_path, name, text, said)


def test_a_single_step_and_a_polygon_still_read(tmp_path):
    from rotoprint.io.cad import read_layer

    p = tmp_path / "ok.gbr"
    p.write_text(GERBER_HEAD + "%SRX1Y1I0J0*%\n%ADD10P,1X6*%\nD10*\nX0Y0D03*\n%SR*%\nM02*\n")
    lay = read_layer(p, tolerance_mm=0.001)
    hexagon = 6 * 0.5 * 0.5**2 * math.sin(2 * math.pi / 6)  # a regular hexagon of circumradius 0.5 mm
    assert lay.regions == 1 and lay.area_mm2 == pytest.approx(hexagon, rel=1e-9)
