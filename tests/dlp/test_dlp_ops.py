"""Mask operations: PIL SMOOTH replica, ERM shift, invert, mirror, first-layer inset."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image, ImageFilter

from rotoprint.errors import ConfigError, ImageError
from rotoprint.masks import (
    MaskOptions,
    erm_shift,
    first_layer_offsets_um,
    inset_mask,
    invert_mask,
    mirror_mask,
    smooth_mask,
)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("binary", [True, False])
def test_smooth_is_pil_smooth_bit_for_bit(seed, binary):
    rng = np.random.default_rng(seed)
    shape = (31 + seed, 47 - seed)
    m = (rng.random(shape) < 0.4).astype(np.uint8) * 255 if binary else rng.integers(0, 256, shape, dtype=np.uint8)
    want = np.asarray(Image.fromarray(m).filter(ImageFilter.SMOOTH))
    np.testing.assert_array_equal(smooth_mask(m), want)


def test_smooth_lowers_thin_walls():
    m = np.zeros((7, 9), np.uint8)
    m[:, 4] = 255
    s = smooth_mask(m)
    assert s[3, 4] == round(7 * 255 / 13)  # one-pixel wall: peak 7/13
    m[:, 5] = 255
    assert smooth_mask(m)[3, 4] == round(10 * 255 / 13)
    assert smooth_mask(np.zeros((2, 2), np.uint8)).shape == (2, 2)
    with pytest.raises(ImageError, match="2-D uint8"):
        smooth_mask(np.zeros((3, 3), np.float32))


def test_erm_shift_moves_one_pixel_right_and_down():
    m = np.zeros((4, 5), np.uint8)
    m[0, 0] = 200
    m[3, 4] = 9
    s = erm_shift(m)
    assert s[1, 1] == 200 and s.sum() == 200
    assert erm_shift(m, shift_px=(-1, 0))[3, 3] == 9
    assert not erm_shift(m, shift_px=(9, 9)).any()


def test_invert_and_mirror():
    m = np.arange(12, dtype=np.uint8).reshape(3, 4)
    assert (invert_mask(m) == 255 - m).all()
    np.testing.assert_array_equal(mirror_mask(m, mirror_x=True), m[:, ::-1])
    np.testing.assert_array_equal(mirror_mask(m, mirror_y=True), m[::-1])
    np.testing.assert_array_equal(mirror_mask(m, mirror_x=True, mirror_y=True), m[::-1, ::-1])
    assert mirror_mask(m, mirror_x=True).flags.c_contiguous


def _square_coverage(x0, x1, y0, y1, shape):
    from rotoprint.masks import coverage_mask

    xy = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)
    return coverage_mask(xy, np.roll(xy, -1, 0), shape)


@pytest.mark.parametrize("inset_px", [0.3, 1.0, 2.6, 5.0])
def test_inset_moves_edges_inward(inset_px):
    pitch = 0.02
    cov = _square_coverage(10.3, 50.6, 8.2, 40.9, (50, 60))
    got = inset_mask(cov, inset_mm=inset_px * pitch, pitch_x_mm=pitch, pitch_y_mm=pitch)
    want = _square_coverage(10.3 + inset_px, 50.6 - inset_px, 8.2 + inset_px, 40.9 - inset_px, (50, 60))
    # grid-aligned edges: exact up to grey rounding (corners within half a pixel)
    assert abs(got.sum(dtype=np.int64) - want.sum(dtype=np.int64)) / 255 <= 2.0
    assert np.abs(got.astype(int) - want.astype(int))[:, 25].max() <= 1
    assert (got <= cov).all()
    # binary masks: the edge is taken halfway between centres, within half a pixel
    binary = np.where(cov >= 128, 255, 0).astype(np.uint8)
    b = inset_mask(binary, inset_mm=inset_px * pitch, pitch_x_mm=pitch, pitch_y_mm=pitch)
    assert set(np.unique(b)) <= {0, 255}
    width_before = (binary[25] > 0).sum()
    width_after = (b[25] > 0).sum()
    assert abs((width_before - width_after) - 2 * inset_px) <= 2.0


def test_inset_edge_cases():
    z = np.zeros((5, 5), np.uint8)
    assert not inset_mask(z, inset_mm=0.1, pitch_x_mm=0.02, pitch_y_mm=0.02).any()
    f = np.full((5, 5), 255, np.uint8)
    assert (inset_mask(f, inset_mm=0.0, pitch_x_mm=0.02, pitch_y_mm=0.02) == 255).all()
    with pytest.raises(ConfigError, match="inset"):
        inset_mask(f, inset_mm=-1, pitch_x_mm=0.02, pitch_y_mm=0.02)


def test_first_layer_schedule():
    np.testing.assert_allclose(first_layer_offsets_um(6, first_layers=3, first_layer_offset_um=90), [90, 60, 30, 0, 0, 0])
    assert not first_layer_offsets_um(3, first_layers=0, first_layer_offset_um=0).any()
    with pytest.raises(ConfigError, match="first layers"):
        first_layer_offsets_um(3, first_layers=-1, first_layer_offset_um=10)


def test_mask_options_validate():
    with pytest.raises(ConfigError, match="mode must be one of binary, coverage, smooth, got 'blur'"):
        MaskOptions(mode="blur")
    with pytest.raises(ConfigError, match="--first-layers"):
        MaskOptions(first_layer_offset_um=50)
    assert MaskOptions(erm=True).copies == 2
