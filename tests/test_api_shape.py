"""The public API's shape: option objects instead of long keyword lists, a device or its
preset name wherever a device is taken."""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import pkgutil

import numpy as np
import pytest

import rotoprint
from rotoprint.errors import ConfigError

MAX_PARAMETERS = 8
# the pipeline refactor replaced the three writers that were allowed here; none is left
_PENDING_PIPELINE: set[str] = set()
# interlaced passes: transform_passes and track_fractions take PassOptions / RotarySetup,
# slice_rotary_passes (pipeline/passes) RotarySliceOptions / RunOptions; none is left
_PENDING_INTERLACE: dict[str, int] = {}


def _public_functions():
    for mod in pkgutil.walk_packages(rotoprint.__path__, "rotoprint."):
        parts = mod.name.split(".")
        if parts[1] == "cli" or any(p.startswith("_") for p in parts[1:]):
            continue
        m = importlib.import_module(mod.name)
        for name, obj in vars(m).items():
            if name.startswith("_"):
                continue
            if inspect.isfunction(obj) and obj.__module__ == m.__name__:
                yield f"{m.__name__}.{name}", obj
            elif inspect.isclass(obj) and obj.__module__ == m.__name__ and not dataclasses.is_dataclass(obj):
                for mname, meth in vars(obj).items():
                    if inspect.isfunction(meth) and not mname.startswith("_"):
                        yield f"{m.__name__}.{name}.{mname}", meth


def _count(fn) -> int:
    ps = [p for p in inspect.signature(fn).parameters.values()
          if p.kind not in (p.VAR_POSITIONAL, p.VAR_KEYWORD) and p.name not in ("self", "cls")]
    return len(ps)


def test_no_public_function_outside_cli_takes_more_than_8_parameters():
    found = list(_public_functions())
    assert len(found) > 100  # the walk sees the package
    long = {name: _count(fn) for name, fn in found if _count(fn) > MAX_PARAMETERS and name not in _PENDING_PIPELINE}
    grown = {n: c for n, c in long.items() if c > _PENDING_INTERLACE.get(n, MAX_PARAMETERS)}
    assert not grown, grown


def test_parameter_count_sees_long_lists():
    def f(a, b, c, *, d, e, f, g, h, i, **kw):
        pass

    assert _count(f) == 9


def test_preset_name_wherever_a_device_is_taken():
    from rotoprint import load_device
    from rotoprint.check import check_printability
    from rotoprint.rotary.direct import slice_rotary
    from rotoprint.slicing import slice_mesh
    from rotoprint.testing import box_mesh

    mesh = box_mesh((2, 1, 1))
    by_name = slice_mesh(mesh, "perfactory-sxga", layer_height_mm=0.5)
    by_model = slice_mesh(mesh, load_device("perfactory-sxga"), layer_height_mm=0.5)
    assert by_name.device == by_model.device and by_name.slice_options == by_model.slice_options
    assert np.array_equal(by_name.layer(0).image, by_model.layer(0).image)
    rot = slice_rotary(box_mesh((10, 6, 1)), "omnidot760", layer_height_mm=0.5, tilt_deg=20.0, inner_radius_mm=60.0)
    assert rot.head == load_device("omnidot760").head
    rep = check_printability(mesh, "perfactory-sxga", layer_height_mm=0.5)
    assert rep.n_layers == 2
    with pytest.raises(rotoprint.errors.DeviceError, match="unknown device 'no-such-printer'"):
        slice_mesh(mesh, "no-such-printer", layer_height_mm=0.5)


def test_slice_options_object_equals_keywords():
    from rotoprint.slicing import SliceOptions, slice_mesh
    from rotoprint.testing import box_mesh

    mesh = box_mesh((2, 1, 1))
    opts = SliceOptions(layer_height_mm=0.5, fill="evenodd", offset_mm=(1, 0))
    a = slice_mesh(mesh, "perfactory-sxga", opts)
    b = slice_mesh(mesh, "perfactory-sxga", layer_height_mm=0.5, fill="evenodd", offset_mm=(1.0, 0.0))
    assert a.slice_options == b.slice_options == {
        "layer_height_mm": 0.5, "fibre_angle_deg": None, "fill": "evenodd", "offset_mm": (1.0, 0.0), "centre": True,
        "gap_radius_mm": opts.gap_radius_mm, "backend": "jit"}
    assert np.array_equal(a.layer(1).image, b.layer(1).image)
    c = slice_mesh(mesh, "perfactory-sxga", opts, fill="nonzero")  # a keyword replaces the field
    assert c.options.fill == "nonzero" and opts.fill == "evenodd"
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.fill = "nonzero"  # type: ignore[misc]
    with pytest.raises(ConfigError, match="fill must be one of"):
        SliceOptions(layer_height_mm=0.5, fill="xor")
    with pytest.raises(ConfigError, match="unknown option 'layer_height'"):
        slice_mesh(mesh, "perfactory-sxga", layer_height=0.5)
    with pytest.raises(ConfigError, match="layer_height_mm is needed"):
        slice_mesh(mesh, "perfactory-sxga")


def test_rotary_setup_object_equals_keywords():
    from rotoprint import load_device
    from rotoprint.rotary import Placement, RotarySetup, RotarySliceOptions, exact_maps, transform_exact
    from rotoprint.rotary.direct import slice_rotary
    from rotoprint.rotary.paper import transform_paper
    from rotoprint.testing import box_mesh

    head = load_device("omnidot760").head
    pl = Placement(40, 30, 0.0705, 0.0705, inner_radius_mm=60.0)
    setup = RotarySetup(tilt_deg=20.0, direction=-1, mount_angle_deg=5.0)
    assert exact_maps(head, pl, setup) is exact_maps(head, pl, tilt_deg=20.0, direction=-1, mount_angle_deg=5.0)
    design = np.full((30, 40), 255, np.uint8)
    a = transform_exact(design, head, pl, setup)
    b = transform_exact(design, head, pl, tilt_deg=20.0, direction=-1, mount_angle_deg=5.0, kind="binary")
    assert all(np.array_equal(x.levels, y.levels) for x, y in zip(a.swathes, b.swathes))
    p1 = transform_paper(design, head, pl, RotarySetup(tilt_deg=10.0))
    p2 = transform_paper(design, head, pl, tilt_deg=10.0)
    assert all(np.array_equal(x.levels, y.levels) for x, y in zip(p1.swathes, p2.swathes))
    with pytest.raises(ConfigError, match="backend must be one of"):
        RotarySetup(tilt_deg=1.0, backend="cuda")
    with pytest.raises(ConfigError, match="unknown option 'tilt'"):
        exact_maps(head, pl, tilt=20.0)
    opts = RotarySliceOptions(layer_height_mm=0.5, tilt_deg=20.0, inner_radius_mm=60.0, equalise=True)
    j1 = slice_rotary(box_mesh((10, 6, 1)), "omnidot760", opts)
    j2 = slice_rotary(box_mesh((10, 6, 1)), "omnidot760", layer_height_mm=0.5, tilt_deg=20.0, inner_radius_mm=60.0, equalise=True)
    assert j1.rotary_options == j2.rotary_options and j1.rotary_options["dpi_y"] == head.dpi_y
    assert list(j1.rotary_options) == ["layer_height_mm", "tilt_deg", "inner_radius_mm", "angle_deg", "dpi_y", "ref_radius_mm",
                                       "direction", "max_swathes", "equalise", "fill", "gap_radius_mm", "backend"]
    assert all(np.array_equal(x.levels, y.levels) for x, y in zip(j1.layer(0).swathes, j2.layer(0).swathes))
    with pytest.raises(AttributeError):
        j1.rotary_options = {}  # type: ignore[misc]  # made with the job, never set after
