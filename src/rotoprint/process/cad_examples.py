"""Writers of small Gerber, Excellon and DXF files for the bundled CAD example and the tests
(plain RS-274X X2 / Excellon text written here, DXF through ezdxf), and the ``cad-coil``
example: a square-spiral silver coil drawn as a KiCad-style copper layer (``coil-F_Cu.gbr``:
0.5 mm round-aperture draws, 1.2 mm square pads flashed with net attributes ``COIL_OUT`` and
``COIL_IN``), two plated vias under the pads (``coil-vias.drl``) through a plaster body whose
outline is a DXF rounded rectangle (``coil-body.dxf``).
"""

from __future__ import annotations

import io

import numpy as np

from ._job_pieces import HEADS_PLASTER_SILVER, PRINTER_TABLE
from .shapes import SquareCoilShape

__all__ = ["gerber_coil", "excellon_holes", "dxf_outline", "CAD_COIL", "CAD_COIL_JOB", "cad_coil_files"]


def _c(v: float) -> str:
    """A coordinate in the 4.6 format (mm): integer micrometres x 1000."""
    return str(int(round(v * 1e6)))


def gerber_coil(shape: SquareCoilShape, *, track: str = "draw", net_names=("COIL_OUT", "COIL_IN")) -> str:
    """RS-274X text of a :class:`SquareCoilShape` copper layer (mm, 4.6 format).

    Parameters
    ----------
    shape : SquareCoilShape
    track : {'draw', 'region'}
        ``draw``: the centreline drawn with a round aperture of the track width (round ends
        and corners, as a PCB tool writes tracks); ``region``: the track as one G36 contour,
        the exact outline of the built-in shape's rectangles.
    net_names : (str, str)
        Net attributes (``TO.N``) of the outer and inner pads.

    Returns
    -------
    str
    """
    c = shape.centreline()
    w = shape.track_width_mm
    out = ["G04 made by rotoprint.process.cad_examples*", "%TF.GenerationSoftware,rotoprint,cad_examples*%",
           "%TF.FileFunction,Copper,L1,Top*%", "%FSLAX46Y46*%", "%MOMM*%", "%LPD*%", "G75*", "G01*"]
    pads = shape.terminals()
    p = shape.pad_mm
    out.append(f"%TA.AperFunction,SMDPad,CuDef*%")
    out.append(f"%ADD10R,{p:.6f}X{p:.6f}*%")
    out.append("%TD*%")
    out.append(f"%TA.AperFunction,Conductor*%")
    out.append(f"%ADD11C,{w:.6f}*%")
    out.append("%TD*%")
    if track == "draw":
        out.append("D11*")
        out.append(f"X{_c(c[0, 0])}Y{_c(c[0, 1])}D02*")
        for x, y in c[1:]:
            out.append(f"X{_c(x)}Y{_c(y)}D01*")
    elif track == "region":
        import shapely

        hw = w / 2
        rects = [shapely.box(*(np.minimum(a, b) - hw), *(np.maximum(a, b) + hw)) for a, b in zip(c[:-1], c[1:])]
        poly = shapely.orient_polygons(shapely.union_all(rects), exterior_cw=False)
        ring = np.asarray(poly.exterior.coords)
        out.append("G36*")
        out.append(f"X{_c(ring[0, 0])}Y{_c(ring[0, 1])}D02*")
        for x, y in ring[1:]:
            out.append(f"X{_c(x)}Y{_c(y)}D01*")
        out.append("G37*")
    else:
        raise ValueError(f"track must be 'draw' or 'region', got {track!r}")
    out.append("D10*")
    for (key, net) in zip(("outer", "inner"), net_names):
        x0, y0, x1, y1 = pads[key]
        out.append(f"%TO.N,{net}*%")
        out.append(f"%TO.P,L1,{1 if key == 'outer' else 2}*%")
        out.append(f"X{_c((x0 + x1) / 2)}Y{_c((y0 + y1) / 2)}D03*")
        out.append("%TD*%")
    out.append("M02*")
    return "\n".join(out) + "\n"


def excellon_holes(holes, *, plated: bool = True) -> str:
    """Excellon text (metric, decimal coordinates) of drill hits ``[(x, y, diameter), ...]``."""
    diam = sorted({round(float(d), 6) for _, _, d in holes})
    out = ["M48", "; made by rotoprint.process.cad_examples", f"; #@! TF.FileFunction,{'Plated' if plated else 'NonPlated'},1,2,PTH",
           "FMAT,2", "METRIC"]
    for i, d in enumerate(diam, 1):
        out.append(f"T{i}C{d:.3f}")
    out += ["%", "G90", "G05"]
    for i, d in enumerate(diam, 1):
        out.append(f"T{i}")
        for x, y, dd in holes:
            if round(float(dd), 6) == d:
                out.append(f"X{x:.4f}Y{y:.4f}")
    out += ["T0", "M30"]
    return "\n".join(out) + "\n"


def dxf_outline(x0: float, y0: float, x1: float, y1: float, *, corner_mm: float = 0.0, holes=()) -> bytes:
    """DXF (R2010, mm) of a rectangle outline with rounded corners (a closed LWPOLYLINE with
    bulges) and optional circular cut-outs ``[(x, y, r), ...]``. The same bytes every time
    (ezdxf's fixed meta data: no creation time, random GUIDs or time stamps), so a rewritten
    example is recognised as unchanged."""
    import ezdxf

    old = ezdxf.options.write_fixed_meta_data_for_testing
    ezdxf.options.write_fixed_meta_data_for_testing = True
    try:
        return _dxf_outline(x0, y0, x1, y1, corner_mm=corner_mm, holes=holes)
    finally:
        ezdxf.options.write_fixed_meta_data_for_testing = old


def _dxf_outline(x0, y0, x1, y1, *, corner_mm, holes) -> bytes:
    import ezdxf

    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    msp = doc.modelspace()
    r = corner_mm
    b = np.tan(np.pi / 8)  # a quarter circle's bulge
    if r > 0:
        pts = [(x0 + r, y0, 0, 0, 0), (x1 - r, y0, 0, 0, b), (x1, y0 + r, 0, 0, 0), (x1, y1 - r, 0, 0, b),
               (x1 - r, y1, 0, 0, 0), (x0 + r, y1, 0, 0, b), (x0, y1 - r, 0, 0, 0), (x0, y0 + r, 0, 0, b)]
    else:
        pts = [(x0, y0, 0, 0, 0), (x1, y0, 0, 0, 0), (x1, y1, 0, 0, 0), (x0, y1, 0, 0, 0)]
    msp.add_lwpolyline(pts, format="xyseb", close=True)
    for x, y, rr in holes:
        msp.add_circle((x, y), rr)
    buf = io.StringIO()
    doc.write(buf)
    return buf.getvalue().encode("utf-8")


#: The example's coil: the bundled coil sensor's (16 mm, 5 turns, 0.5 mm track and gap).
CAD_COIL = SquareCoilShape(kind="square_coil", outer_mm=16.0, track_width_mm=0.5, gap_mm=0.5, turns=5, height_mm=0.04)
VIA_DIAMETER_MM = 0.6


def via_positions(shape: SquareCoilShape = CAD_COIL) -> list[tuple[float, float, float]]:
    """Centres of the two pads with the via diameter: ``[(x, y, d), ...]``."""
    out = []
    for k in ("outer", "inner"):
        x0, y0, x1, y1 = shape.terminals()[k]
        out.append(((x0 + x1) / 2, (y0 + y1) / 2, VIA_DIAMETER_MM))
    return out


CAD_COIL_JOB = """# Planar coil sensor from electronics CAD: a KiCad-style copper layer (Gerber), plated vias
# (Excellon drill file) through a plaster body whose outline is a DXF drawing.
# Made by rotoprint.process.cad_examples (examples/make_sensors.py). Build it with
#   rotoprint build cad-coil.toml --out cad-coil-build
#   rotoprint info coil-F_Cu.gbr
[job]
name = "cad coil"
description = "5-turn silver coil from a Gerber layer on a plaster body (DXF outline), vias from the drill file"
layer_height_mm = 0.02

""" + PRINTER_TABLE + HEADS_PLASTER_SILVER + """
[placement]
inner_radius_mm = 60.0
angle_deg = 0.0

[[parts]]
name = "body"
material = "plaster"
priority = 1
# the body's outline, with the drill file's holes cut through it
layer = { file = "coil-body.dxf", z_mm = [0.0, 0.12], holes = ["coil-vias.drl"] }

[[parts]]
name = "vias"
material = "silver"
priority = 3
layer = { file = "coil-vias.drl", z_mm = [0.0, 0.12] }

[[parts]]
name = "coil"
material = "silver"
priority = 3
layer = { file = "coil-F_Cu.gbr", z_mm = [0.12, 0.16], tolerance_mm = 0.005 }

[process]
order = ["plaster", "silver"]
cycles_per_layer = { silver = 24 }   # a multiple of 2, 3 and 4 interlaced passes
simulate_layers = 2

[[resistance]]
part = "coil"
between = ["COIL_OUT", "COIL_IN"]   # the pads' net names in the Gerber file
"""


def cad_coil_files() -> dict[str, bytes]:
    """The ``cad-coil`` example's CAD files: ``{name: bytes}``."""
    return {
        "coil-F_Cu.gbr": gerber_coil(CAD_COIL, track="draw").encode("ascii"),
        "coil-vias.drl": excellon_holes(via_positions()).encode("ascii"),
        "coil-body.dxf": dxf_outline(-3.0, -3.0, 19.0, 19.0, corner_mm=2.0),
    }
