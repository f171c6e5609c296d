"""Helpers for the tests of multi-material jobs (tests/process)."""

from __future__ import annotations

import copy

HEADS = [
    {"name": "H1", "ink": "ammonium_sulphate", "mount_angle_deg": 0.0},
    {"name": "H2", "ink": "calcium_chloride", "mount_angle_deg": 60.0},
    {"name": "H3", "ink": "silver_nitrate", "mount_angle_deg": 120.0},
    {"name": "H4", "ink": "ascorbate", "mount_angle_deg": 180.0},
    {"name": "H5", "ink": "polyepoxide", "mount_angle_deg": 240.0},
    {"name": "H6", "ink": "diamine", "mount_angle_deg": 300.0},
]


def job_dict(parts, *, layer_height_mm=0.05, tilt_deg=20.0, equalise=True, heads=None, passes=None, **extra) -> dict:
    """A small job as a dict (the parsed TOML); ``passes`` sets ``printer.passes`` (default:
    left out, i.e. ``"auto"``)."""
    d = {
        "job": {"name": "test", "layer_height_mm": layer_height_mm},
        "printer": {"device": "omnidot760", "tilt_deg": tilt_deg, "equalise": equalise,
                    "heads": copy.deepcopy(HEADS if heads is None else heads)},
        "placement": {"inner_radius_mm": 60.0, "angle_deg": 0.0},
        "parts": copy.deepcopy(parts),
    }
    if passes is not None:
        d["printer"]["passes"] = passes
    d.update(copy.deepcopy(extra))
    return d


def box_part(name, material, priority, size, origin=(0.0, 0.0, 0.0)) -> dict:
    return {"name": name, "material": material, "priority": priority,
            "shape": {"kind": "box", "size_mm": list(size), "origin_mm": list(origin)}}
