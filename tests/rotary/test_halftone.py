"""Grey levels: 1/r equalisation by drop size (rotary/halftone.py)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import ConfigError
from rotoprint.rotary import Placement, transform_exact
from rotoprint.rotary import _halftone_kernels as K
from rotoprint.rotary.deposit import deposit_print
from rotoprint.rotary.files import read_print
from rotoprint.rotary.halftone import halftone_print
from rotoprint.rotary.interlace import PassOptions, read_passes
from rotoprint.pipeline.prints import transform_passes
from rotoprint.rotary.options import RotarySetup

PX = 25.4 / 360


def test_diffusion_keeps_the_mean_per_track():
    rng = np.random.default_rng(2)
    mask = rng.random((300, 20)) < 0.7
    want = rng.uniform(0, 8, 20)
    a, b = np.zeros((300, 20), np.uint8), np.zeros((300, 20), np.uint8)
    K.diffuse_jit(mask, want, 8, 1, a)
    K.diffuse_numpy(mask, want, 8, 1, b)
    assert np.array_equal(a, b)
    assert ((a > 0) == mask).all()  # every printing site keeps a drop, no other site gets one
    sums = a.sum(axis=0).astype(float)
    wanted = np.maximum(want, 1.0) * mask.sum(axis=0)  # at least level 1 at every printing site
    assert np.all(np.abs(sums - wanted) <= 1.0 + 1e-9)


def test_grey_head_film_is_flat_over_a_3_to_1_span(tmp_path):
    """A 40 x 4 mm band from radius 20 to 60 mm (3:1), tilt 0, 8 grey levels, planned passes,
    equalised by drop size: the 1 mm radial bins of the deposited film within 2 % of their mean,
    the interior closed; the binary head's film over the same span is not flat."""
    grey = load_device("omnidot760").head.model_copy(update={"grey_levels": 8})
    w, h = round(40 / PX), round(4 / PX)
    d = np.full((h, w), 255, np.uint8)
    pl = Placement(w, h, PX, PX, inner_radius_mm=20.0)
    m = transform_passes(d, grey, pl, tmp_path / "g.png", PassOptions(RotarySetup(tilt_deg=0.0), passes="auto", equalise=True))
    assert m["equalise"] == "grey levels"
    prs = [read_print(f)[0] for f in read_passes(tmp_path / "g-passes.json")]
    f = deposit_print(prs, d).films[0]
    assert f.uncovered_fraction == 0.0
    assert f.radial_spread <= 0.02, f.radial_bins
    assert abs(f.volume_error_fraction) < 0.005
    lv = np.concatenate([s.levels[s.levels > 0] for p in prs for s in p.swathes])
    assert lv.min() >= 1 and lv.max() == 8 and 2 < lv.mean() < 7
    man = json.loads((tmp_path / "g-passes.json").read_text())
    plain = transform_passes(d, grey.model_copy(update={"grey_levels": 1}), pl, tmp_path / "b.png",
                             PassOptions(RotarySetup(tilt_deg=0.0), passes=man["pass_plan"]["passes"], equalise=False))
    fb = deposit_print([read_print(q)[0] for q in read_passes(tmp_path / "b-passes.json")], d).films[0]
    assert fb.radial_spread > 0.3 and plain["equalise"] is None


def test_bad_input():
    head = load_device("omnidot760").head
    pr = transform_exact(np.full((10, 10), 255, np.uint8), head, Placement(10, 10, PX, PX, inner_radius_mm=60.0), tilt_deg=0.0)
    with pytest.raises(ConfigError, match="grey_levels"):
        halftone_print(pr, [np.ones(764)])
    g = transform_exact(np.full((10, 10), 255, np.uint8), head.model_copy(update={"grey_levels": 4}),
                        Placement(10, 10, PX, PX, inner_radius_mm=60.0), tilt_deg=0.0)
    with pytest.raises(ConfigError, match="shares"):
        halftone_print(g, [np.full(764, 1.5)])
    with pytest.raises(ConfigError, match="per swathe"):
        halftone_print(g, [])
