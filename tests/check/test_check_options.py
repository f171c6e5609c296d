"""CheckOptions: checked when made, frozen, the same check whether given as an object or by
keyword; the public functions of rotoprint.check take at most 8 parameters."""

from __future__ import annotations

import dataclasses
import inspect

import pytest

from rotoprint import check
from rotoprint.check import CheckOptions, check_printability
from rotoprint.devices import load_device
from rotoprint.errors import ConfigError
from rotoprint.testing import box_mesh


def test_options_object_equals_keywords():
    dev = load_device("omnidot760")
    part = box_mesh((2.0, 0.05, 0.2))
    a = check_printability(part, dev, CheckOptions(min_wall_mm=0.06, islands=False), layer_height_mm=0.1).to_json()
    b = check_printability(part, dev, layer_height_mm=0.1, min_wall_mm=0.06, islands=False).to_json()
    c = check_printability(part, dev, CheckOptions(min_wall_mm=1.0), layer_height_mm=0.1, min_wall_mm=0.06, islands=False).to_json()
    assert a == b == c
    assert a["settings"]["min_wall_mm"] == 0.06 and a["settings"]["min_wall_source"] == "given"
    assert a["settings"]["islands"] is False


def test_options_checked_when_made_and_frozen():
    with pytest.raises(ConfigError, match=r"min_wall_mm must be in \[0.0001, 100\] mm, got -1"):
        CheckOptions(min_wall_mm=-1)
    with pytest.raises(ConfigError, match="a cure threshold needs an exposure model"):
        CheckOptions(cure_threshold=0.5)
    with pytest.raises(ConfigError, match=r"cure threshold must be in \(0, 1\]"):
        CheckOptions(mask_fn=lambda im: im, cure_threshold=1.5)
    with pytest.raises(ConfigError, match="islands must be True or False"):
        CheckOptions(islands=1)
    opts = CheckOptions()
    with pytest.raises(dataclasses.FrozenInstanceError):
        opts.islands = False  # type: ignore[misc]


def test_resolve_fills_the_device_defaults():
    dev = load_device("perfactory-sxga")
    st = CheckOptions(mask_fn=lambda im: im, mask_name="binary").resolve(dev)
    assert st.cure_threshold == dev.projector.cure_threshold and st.exposure_model == "binary"
    assert st.min_wall_source != "given" and st.resolution_mm == pytest.approx(0.01 * min(dev.pitch_x_mm, dev.pitch_y_mm))
    with pytest.raises(ConfigError, match="resolution must be from 0"):
        CheckOptions(resolution_mm=1.0).resolve(dev)


def test_unknown_keyword_is_a_type_error():
    with pytest.raises(TypeError, match="unexpected keyword argument 'min_wall'"):
        check_printability(box_mesh((1.0, 1.0, 0.2)), load_device("omnidot760"), layer_height_mm=0.1, min_wall=0.1)


def test_public_functions_take_at_most_8_parameters():
    for name in check.__all__:
        obj = getattr(check, name)
        if inspect.isfunction(obj):
            n = len(inspect.signature(obj).parameters)
            assert n <= 8, f"{name} takes {n} parameters"
