"""The bundled sensor examples, written as job files (so ``rotoprint demo`` works after
``pip install``; ``examples/make_sensors.py`` writes the same files into the repository).

- ``coil-sensor``: a planar square-spiral induction coil (silver, 5 turns, 0.5 mm track and
  gap) in the top of a plaster body (a mesh file), its pads rising through an epoxy cover.
  Priorities: silver 3 > epoxy 2 > plaster 1, so the coil displaces the plaster where they
  overlap and the pads stay open through the cover.
- ``cad-coil``: the coil from electronics CAD (:mod:`.cad_examples`): a Gerber copper layer,
  an Excellon drill file of two vias and a DXF body outline, each a planar layer part.
- ``gas-sensor``: an interdigitated silver electrode (2 x 8 fingers, 0.3 mm wide, 0.3 mm
  gaps) on a plaster substrate, inside a polyamide well that holds the sensing film.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ConfigError
from ..io.stl import binary_stl_bytes
from ..primitives import box_triangles
from ._job_pieces import HEADS_PLASTER_SILVER, PRINTER_TABLE

__all__ = ["EXAMPLES", "example_files"]

_HEADS = HEADS_PLASTER_SILVER + """
[[printer.heads]]
name = "H5"
ink = "{ink5}"
mount_angle_deg = 240.0

[[printer.heads]]
name = "H6"
ink = "{ink6}"
mount_angle_deg = 300.0
"""

COIL_JOB = """# Planar induction coil sensor: silver coil in a plaster body under an epoxy cover.
# Made by rotoprint.process.examples (examples/make_sensors.py). Build it with
#   rotoprint build coil-sensor.toml --out coil-build
[job]
name = "coil sensor"
description = "5-turn square silver coil (0.5 mm track, 0.5 mm gap) in a plaster body, epoxy cover, pads open"
layer_height_mm = 0.02

[printer]
device = "omnidot760"
tilt_deg = 20.0
direction = 1
equalise = true          # the same ink per mm2 at every radius: the passes print their shares of the union-equalised film

passes = "auto"          # interlaced passes at the planner's radial offsets (docs/build.md)
# no [printer.clock] dpi_y: the drop spacing along the track follows from the pass plan, so the drops merge
""" + _HEADS.format(ink5="polyepoxide", ink6="diamine") + """
[placement]
inner_radius_mm = 60.0   # the assembly's inner edge (smallest X) on the platform
angle_deg = 0.0

[[parts]]
name = "body"
material = "plaster"
priority = 1
mesh = "coil-body.stl"   # 22 x 22 x 0.2 mm, min corner at (-3, -3, 0)

[[parts]]
name = "coil"
material = "silver"
priority = 3
shape = { kind = "square_coil", outer_mm = 16.0, track_width_mm = 0.5, gap_mm = 0.5, turns = 5, height_mm = 0.04, z0_mm = 0.16, pad_mm = 1.2, lead_mm = 0.6, pad_height_mm = 0.14 }

[[parts]]
name = "cover"
material = "epoxy"
priority = 2
shape = { kind = "box", size_mm = [22.0, 22.0, 0.1], origin_mm = [-3.0, -3.0, 0.2] }

[process]
order = ["plaster", "silver", "epoxy"]
max_passes_per_layer = 200
# silver forms about 17 nm per cycle: a full 20 um layer would need over 1000 cycles, so the
# coil is a thin film of 24 cycles per layer (the plan warns how far short of the layer it is;
# 24 is a multiple of 2, 3 and 4 interlaced passes, so every pass prints equally often)
cycles_per_layer = { silver = 24 }
simulate_layers = 2

[[resistance]]
part = "coil"
between = ["outer", "inner"]
"""

GAS_JOB = """# Gas sensor: interdigitated silver electrode on plaster, in a polyamide well.
# Made by rotoprint.process.examples (examples/make_sensors.py). Build it with
#   rotoprint build gas-sensor.toml --out gas-build
[job]
name = "gas sensor"
description = "interdigitated electrode, 2 x 8 fingers of 0.3 mm with 0.3 mm gaps, 8 mm overlap, in a polyamide well"
layer_height_mm = 0.02

""" + PRINTER_TABLE + _HEADS.format(ink5="acyl_thiol", ink6="polyamine") + """
[placement]
inner_radius_mm = 70.0
angle_deg = 0.0

[[parts]]
name = "substrate"
material = "plaster"
priority = 1
shape = { kind = "box", size_mm = [14.0, 14.0, 0.1], origin_mm = [-2.0, -2.0, 0.0] }

[[parts]]
name = "electrode"
material = "silver"
priority = 3
shape = { kind = "interdigitated", fingers = 8, finger_width_mm = 0.3, gap_mm = 0.3, overlap_mm = 8.0, bus_width_mm = 1.0, pad_mm = 1.5, height_mm = 0.04, z0_mm = 0.1 }

[[parts]]
name = "well"
material = "polyamide"
priority = 2
mesh = "gas-well.stl"    # a 14 x 14 mm frame, 1 mm wall, 0.1 mm high, on the substrate

[process]
order = ["plaster", "silver", "polyamide"]
cycles_per_layer = { silver = 24 }
simulate_layers = 2

[[resistance]]
part = "electrode"
between = ["A", "B"]     # must be open: the combs do not touch

[[resistance]]
part = "electrode"
between = ["A", "A_tip"] # comb A from its pad to its farthest finger tip
"""


def _coil_body() -> bytes:
    return box_triangles((22.0, 22.0, 0.2), (-3.0, -3.0, 0.0))


def _gas_well():
    import numpy as np

    z0, h = 0.1, 0.1
    return np.concatenate([
        box_triangles((14.0, 1.0, h), (-2.0, -2.0, z0)),
        box_triangles((14.0, 1.0, h), (-2.0, 11.0, z0)),
        box_triangles((1.0, 14.0, h), (-2.0, -2.0, z0)),
        box_triangles((1.0, 14.0, h), (11.0, -2.0, z0)),
    ])


#: name -> (job file name, job text, {mesh file: triangle maker})
EXAMPLES = {
    "coil-sensor": ("coil-sensor.toml", COIL_JOB, {"coil-body.stl": _coil_body}),
    "gas-sensor": ("gas-sensor.toml", GAS_JOB, {"gas-well.stl": _gas_well}),
}


def _cad_file(name: str):
    def make() -> bytes:
        from .cad_examples import cad_coil_files

        return cad_coil_files()[name]

    return make


def _add_cad_example() -> None:
    from .cad_examples import CAD_COIL_JOB

    EXAMPLES["cad-coil"] = ("cad-coil.toml", CAD_COIL_JOB, {n: _cad_file(n) for n in
                                                           ("coil-F_Cu.gbr", "coil-vias.drl", "coil-body.dxf")})


_add_cad_example()


def example_files(name: str) -> dict[str, bytes]:
    """The files of example ``name``: ``{file name: bytes}``, the meshes first, the job file last."""
    if name not in EXAMPLES:
        raise ConfigError(f"unknown example {name!r}; examples: {', '.join(EXAMPLES)}")
    job_name, text, meshes = EXAMPLES[name]
    files = {}
    for fname, make in meshes.items():
        data = make()
        files[fname] = data if isinstance(data, bytes) else binary_stl_bytes(data)  # CAD files come as bytes
    files[job_name] = text.encode("utf-8")
    return files


