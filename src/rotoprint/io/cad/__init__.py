"""Planar layers from electronics and 2-D CAD files, as exact shapely polygons in mm.

=========  ==========================  ===============================================
format     suffixes                    read with
=========  ==========================  ===============================================
Gerber     .gbr .ger .gtl .gbl .gko …  gerbonara (apertures, regions, arcs, polarity)
Excellon   .drl .xln .exc .xnc         gerbonara (drill hits and routed slots)
DXF        .dxf                        ezdxf (closed contours, polylines with width)
SVG        .svg                        svgelements (fills, stroke widths, transforms)
=========  ==========================  ===============================================

:func:`read_layer` picks the reader from the suffix. Arcs and curves become chords within
``tolerance_mm`` of the curve; straight edges are kept exactly.
"""

from __future__ import annotations

from pathlib import Path

from ...errors import CadError, InputFileError
from ._geometry import MIN_TOLERANCE_MM, PlanarLayer, length_unit_mm

__all__ = ["read_layer", "PlanarLayer", "CAD_SUFFIXES", "is_cad_file"]

GERBER_SUFFIXES = {".gbr", ".ger", ".gtl", ".gbl", ".gto", ".gbo", ".gts", ".gbs", ".gtp", ".gbp", ".gko", ".gm1",
                   ".gml", ".pho", ".art"}
EXCELLON_SUFFIXES = {".drl", ".xln", ".exc", ".xnc"}
CAD_SUFFIXES = GERBER_SUFFIXES | EXCELLON_SUFFIXES | {".dxf", ".svg"}


def is_cad_file(path: str | Path) -> bool:
    """True when ``path``'s suffix is one :func:`read_layer` reads."""
    return Path(path).suffix.lower() in CAD_SUFFIXES


def read_layer(path: str | Path, *, tolerance_mm: float, units: str | None = None) -> PlanarLayer:
    """Read one planar layer file into exact polygons (mm).

    Parameters
    ----------
    path : str or Path
        Gerber, Excellon, DXF or SVG file (by suffix).
    tolerance_mm : float
        Largest distance of arc and curve chords from the curve, mm.
    units : str, optional
        Length unit of the file's coordinates where the file does not say (DXF without
        ``$INSUNITS``, SVG pixels); overrides the file's own for DXF and SVG. Gerber and
        Excellon state theirs: giving one for them is refused.

    Returns
    -------
    PlanarLayer

    Raises
    ------
    InputFileError
        Missing file, a directory, or an unknown suffix.
    CadError
        The content cannot be used (the message names the problem).
    """
    p = Path(path)
    if not p.exists():
        raise InputFileError("no such layer file", path=p)
    if p.is_dir():
        raise InputFileError("is a directory, expected a Gerber, Excellon, DXF or SVG file", path=p)
    suf = p.suffix.lower()
    if not (isinstance(tolerance_mm, int | float) and MIN_TOLERANCE_MM <= tolerance_mm <= 1.0):
        raise CadError(f"the arc tolerance must be {MIN_TOLERANCE_MM:g} to 1 mm, got {tolerance_mm!r}", path=p)
    if units is not None:
        length_unit_mm(units, path=p)
        if suf in GERBER_SUFFIXES | EXCELLON_SUFFIXES:
            raise CadError(f"units = {units!r} given, but a Gerber or Excellon file states its own units", path=p)
    try:
        if suf in GERBER_SUFFIXES:
            from .gerber import read_gerber

            return read_gerber(p, tolerance_mm=tolerance_mm)
        if suf in EXCELLON_SUFFIXES:
            from .gerber import read_excellon

            return read_excellon(p, tolerance_mm=tolerance_mm)
        if suf == ".dxf":
            from .dxf import read_dxf

            return read_dxf(p, tolerance_mm=tolerance_mm, units=units)
        if suf == ".svg":
            from .svg import read_svg

            return read_svg(p, tolerance_mm=tolerance_mm, units=units)
    except CadError as exc:  # a geometry helper's refusal does not know the file: named here
        if exc.path is None:
            raise CadError(exc.problem, path=p) from None
        raise
    raise InputFileError(f"unknown layer file type {suf!r}; use one of {', '.join(sorted(CAD_SUFFIXES))}", path=p)
