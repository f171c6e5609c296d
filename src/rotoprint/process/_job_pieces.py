"""Pieces of TOML the bundled jobs share (process/examples.py, process/cad_examples.py)."""

from __future__ import annotations

#: The [printer] table of the gas sensor and the cad coil (before their heads).
PRINTER_TABLE = """[printer]
device = "omnidot760"
tilt_deg = 20.0
equalise = true

passes = "auto"          # interlaced passes at the planner's radial offsets (docs/build.md)
# no [printer.clock] dpi_y: the drop spacing along the track follows from the pass plan, so the drops merge
"""

#: The heads H1-H4 (plaster's and silver's inks) at 60 degree steps, as every bundled job has
#: them (process/cad_examples.py too).
HEADS_PLASTER_SILVER = """
[[printer.heads]]
name = "H1"
ink = "ammonium_sulphate"
mount_angle_deg = 0.0

[[printer.heads]]
name = "H2"
ink = "calcium_chloride"
mount_angle_deg = 60.0

[[printer.heads]]
name = "H3"
ink = "silver_nitrate"
mount_angle_deg = 120.0

[[printer.heads]]
name = "H4"
ink = "ascorbate"
mount_angle_deg = 180.0
"""
