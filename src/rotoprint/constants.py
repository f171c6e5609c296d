"""Tolerances and fixed numbers, named once.

Geometry is exact wherever it can be (symbolic rules instead of epsilons); the few numeric
tolerances that remain live here so that every module agrees on them.
"""

from __future__ import annotations

#: Units accepted by :func:`rotoprint.load_mesh`, as millimetres per unit.
UNITS_TO_MM: dict[str, float] = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "um": 1e-3, "inch": 25.4, "in": 25.4}

#: Triangles whose area is at most this fraction of the squared bounding-box diagonal count as
#: degenerate (zero-area) in reports. They are kept as topology links: they carry no area.
DEGENERATE_AREA_REL: float = 1e-14

#: Default radius (mm) within which open ends of a cross-section of an open mesh are joined.
DEFAULT_GAP_RADIUS_MM: float = 0.5

#: Layer count below which a final, thinner layer is merged into the one before it, as a
#: fraction of the layer height (a sliver thinner than this is not worth a layer).
MIN_LAST_LAYER_FRACTION: float = 1e-6

#: Fraction of available memory a single raster may take before it is refused.
MAX_RASTER_MEMORY_FRACTION: float = 0.5

#: Largest coordinate magnitude (mm) a mesh may have: beyond it (1000 km) products of
#: coordinates in areas, volumes and winding numbers would lose all precision or overflow.
MAX_COORDINATE_MM: float = 1e9

#: A shell open on more than this fraction of its face sides has no meaningful volume sign
#: and is never turned outside-in by the orientation rule.
MAX_OPEN_SIDE_FRACTION: float = 0.1
