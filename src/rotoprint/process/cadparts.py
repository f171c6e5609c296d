"""Planar-layer parts: a region from a Gerber, Excellon, DXF or SVG file extruded between two
heights (``layer = { file = "coil-F_Cu.gbr", z_mm = [0.2, 0.22] }`` in a job's part).

The region is read into exact polygons (:mod:`rotoprint.io.cad`) and placed in the job's model
frame: scaled by its units, mirrored (``mirror = true``: ``x -> -x``, a bottom layer seen from
above), turned by the part's ``rotate_deg`` (about Z only) and moved by ``translate_mm`` (its Z
shifts ``z_mm``). ``holes`` cut other files' regions out of it (drill files: holes through
every layer they are listed in).

The direct rotary slicer takes the polygon edges themselves as the layer's cross-section in
every layer whose mid-height lies inside ``z_mm``: a drop prints when its landing point is
inside the polygon (the slicer's winding test against the polygon's edges), with no mesh on the
way. Only the printability check and the assembly's footprint use a mesh: the polygon extruded
with vertical walls (constrained Delaunay caps), whose every cross-section is the same polygon.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import shapely
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from ..errors import CadError
from ..io.cad import CAD_SUFFIXES, PlanarLayer, read_layer
from ..io.cad._geometry import LENGTH_UNITS_MM, MIN_TOLERANCE_MM, as_multipolygon
from ..mesh import Mesh
from ..slicing._sections import Segments

__all__ = ["LayerFile", "PlacedLayer", "load_layer_part", "layer_segments", "extrude_layer", "DEFAULT_TOLERANCE_PITCH"]

#: Default arc tolerance as a fraction of the head's nozzle pitch.
DEFAULT_TOLERANCE_PITCH = 0.1


class LayerFile(BaseModel):
    """A part's planar layer: ``file`` extruded over ``z_mm = [z0, z1]``."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    file: str = Field(min_length=1)
    z_mm: tuple[float, float]
    units: str | None = None
    tolerance_mm: float | None = Field(default=None, ge=MIN_TOLERANCE_MM, le=1.0)
    mirror: bool = False
    holes: tuple[str, ...] = ()
    terminals: dict[str, tuple[float, float]] = Field(default_factory=dict)
    terminal_radius_mm: float = Field(default=0.25, gt=0, le=100)

    @field_validator("file")
    @classmethod
    def _suffix(cls, v: str) -> str:
        if Path(v).suffix.lower() not in CAD_SUFFIXES:
            raise ValueError(f"{v!r} is not a layer file; use one of {', '.join(sorted(CAD_SUFFIXES))}")
        return v

    @field_validator("units")
    @classmethod
    def _units(cls, v: str | None) -> str | None:
        if v is not None and v.strip().lower() not in LENGTH_UNITS_MM:
            raise ValueError(f"{v!r} is not a length unit; use one of {', '.join(LENGTH_UNITS_MM)}")
        return v

    @model_validator(mode="after")
    def _z(self) -> LayerFile:
        z0, z1 = self.z_mm
        if not z1 > z0:
            raise ValueError(f"z_mm must be [bottom, top] with top > bottom, got {list(self.z_mm)}")
        if z0 < 0:
            raise ValueError(f"z_mm must start at or above the platform (0 mm), got {z0:g}")
        return self


@dataclass(frozen=True, eq=False)
class PlacedLayer:
    """A layer part in the job's model frame: its region between ``z0_mm`` and ``z1_mm``."""

    name: str
    layer: PlanarLayer
    z0_mm: float
    z1_mm: float
    file: str
    holes: tuple[str, ...] = ()
    _segments: Segments | None = field(default=None, repr=False)

    def contains_z(self, z_mm: float) -> bool:
        return self.z0_mm < z_mm < self.z1_mm

    def segments(self) -> Segments:
        return layer_segments(self.layer)

    def mesh(self) -> Mesh:
        return extrude_layer(self.layer, self.z0_mm, self.z1_mm, source=f"layer {self.file} (part {self.name})")

    def to_json(self, material: str) -> dict:
        info = self.layer.info()
        return {"part": self.name, "material": material, "file": self.file, "format": self.layer.fmt,
                "z_mm": [self.z0_mm, self.z1_mm], "holes_from": list(self.holes), **{k: info[k] for k in (
                    "area_mm2", "bounds_mm", "regions", "holes", "vertices", "narrowest_track_mm", "narrowest_gap_mm",
                    "tolerance_mm")}, "terminals": sorted(self.layer.terminals)}


def layer_segments(layer: PlanarLayer) -> Segments:
    """The region's edges as the slicer's oriented segments (exteriors counter-clockwise,
    holes clockwise: the nonzero winding rule gives the region)."""
    starts, ends = [], []
    for ring in layer.oriented_rings():
        starts.append(ring[:-1])
        ends.append(ring[1:])
    if not starts:
        z = np.zeros((0, 2))
        return Segments(z, z.copy(), np.zeros(0, np.int64), np.zeros(0, np.int64))
    s = np.ascontiguousarray(np.concatenate(starts))
    e = np.ascontiguousarray(np.concatenate(ends))
    m = np.full(len(s), -1, np.int64)
    return Segments(s, e, m, m.copy())


def extrude_layer(layer: PlanarLayer, z0: float, z1: float, *, source: str) -> Mesh:
    """A closed prism mesh of the region between ``z0`` and ``z1``: constrained Delaunay caps
    and a vertical wall quad for every boundary edge (no new vertices in the plane, so every
    horizontal cross-section is the region's own polygon)."""
    tris = []
    for poly in layer.region.geoms:
        cdt = shapely.constrained_delaunay_triangles(poly)
        for t in shapely.get_parts(cdt):
            c = np.asarray(t.exterior.coords, np.float64)[:3]
            if (c[1, 0] - c[0, 0]) * (c[2, 1] - c[0, 1]) - (c[1, 1] - c[0, 1]) * (c[2, 0] - c[0, 0]) < 0:
                c = c[::-1]
            tris.append(np.column_stack([c, np.full(3, z1)]))
            tris.append(np.column_stack([c[::-1], np.full(3, z0)]))
    for ring in layer.oriented_rings():
        a, b = ring[:-1], ring[1:]
        n = len(a)
        A0 = np.column_stack([a, np.full(n, z0)])
        B0 = np.column_stack([b, np.full(n, z0)])
        A1 = np.column_stack([a, np.full(n, z1)])
        B1 = np.column_stack([b, np.full(n, z1)])
        tris.extend(np.stack([A0, B0, B1], 1))
        tris.extend(np.stack([A0, B1, A1], 1))
    if not tris:
        raise CadError("the layer has no area (nothing dark in it)", path=source)
    return Mesh.from_triangles(np.asarray(tris, np.float64), source=source, orient="keep")


def _resolve(base: Path, name: str) -> Path:
    p = Path(name)
    return p if p.is_absolute() else base / p


def load_layer_part(base_dir: Path, part, *, default_tolerance_mm: float) -> PlacedLayer:
    """Read a part's layer file (and its hole files) and place it in the model frame.

    Parameters
    ----------
    base_dir : Path
        Folder relative file names are resolved against.
    part : PartSpec
        With ``layer`` set; its ``rotate_deg`` must turn about Z only.
    default_tolerance_mm : float
        Arc tolerance when the layer gives none (a fraction of the head's pitch).

    Returns
    -------
    PlacedLayer

    Raises
    ------
    CadError, InputFileError
        The file cannot be read or its content cannot be used.
    """
    spec: LayerFile = part.layer
    rx, ry, rz = part.rotate_deg
    if rx or ry:
        raise CadError(f"a layer part turns about Z only; rotate_deg = {list(part.rotate_deg)}")
    tol = spec.tolerance_mm if spec.tolerance_mm is not None else default_tolerance_mm
    tx, ty, tz = part.translate_mm

    def placed(name: str) -> PlanarLayer:
        lay = read_layer(_resolve(base_dir, name), tolerance_mm=tol, units=spec.units)
        return lay.transformed(mirror_x=spec.mirror, rotate_deg=rz, translate_mm=(tx, ty))

    lay = placed(spec.file)
    for h in spec.holes:
        cut = placed(h)
        region = as_multipolygon(shapely.orient_polygons(lay.region.difference(cut.region), exterior_cw=False))
        lay = PlanarLayer(region, lay.terminals, lay.source, lay.fmt, lay.tolerance_mm, lay.counts)
    terms = dict(lay.terminals)
    for k, (x, y) in spec.terminals.items():
        disc = shapely.Point(x, y).buffer(spec.terminal_radius_mm, quad_segs=16)
        hit = disc.intersection(lay.region)
        if hit.is_empty:
            raise CadError(f"terminal {k!r} at ({x:g}, {y:g}) mm is not on the layer (nearest conductor "
                           f"{lay.region.distance(shapely.Point(x, y)):.3g} mm away)", path=lay.source)
        terms[k] = hit
    lay = PlanarLayer(lay.region, terms, lay.source, lay.fmt, lay.tolerance_mm, lay.counts)
    if lay.region.is_empty:
        raise CadError("the layer has no area (nothing dark in it)", path=lay.source)
    z0, z1 = spec.z_mm
    return PlacedLayer(name=part.name, layer=lay, z0_mm=float(z0 + tz), z1_mm=float(z1 + tz), file=spec.file,
                       holes=tuple(spec.holes))


def default_tolerance(pitch_mm: float) -> float:
    """The default arc tolerance for a head of nozzle pitch ``pitch_mm``."""
    return float(DEFAULT_TOLERANCE_PITCH * pitch_mm) if math.isfinite(pitch_mm) and pitch_mm > 0 else 0.005
