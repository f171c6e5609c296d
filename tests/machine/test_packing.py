"""Packing firing images into controller words and TIFF planes: bit-for-bit round trips."""

import io

import numpy as np
import pytest

from rotoprint.errors import ConfigError, ImageError
from rotoprint.io.machine import (bits_for_levels, nozzle_order, pack_levels, packed_bytes, read_packed, tiff_bytes,
                                  unpack_levels, words_per_row)
from rotoprint.io.machine.packing import max_level


@pytest.mark.parametrize("bits", [1, 2, 4])
@pytest.mark.parametrize("nozzles", [1, 31, 32, 33, 95, 764])
@pytest.mark.parametrize("odd_row,descending", [(0, False), (1, False), (0, True), (1, True)])
def test_pack_unpack_round_trip_bit_for_bit(bits, nozzles, odd_row, descending):
    rng = np.random.default_rng(nozzles * 7 + bits)
    lv = rng.integers(0, max_level(bits) + 1, (13, nozzles)).astype(np.uint8)
    order = nozzle_order(nozzles, 2, odd_row=odd_row, descending=descending)
    assert sorted(order.tolist()) == list(range(nozzles))
    words = pack_levels(lv, bits, order)
    assert words.dtype == np.uint32 and words.shape == (13, words_per_row(nozzles, bits))
    raw = packed_bytes(words)
    assert len(raw) == 13 * -(-nozzles * bits // 32) * 4
    back = unpack_levels(read_packed(raw, 13, nozzles, bits), bits, order)
    assert back.dtype == np.uint8 and np.array_equal(back, lv)


def test_msb_first_words_and_head_order():
    # nozzles 0 and 2 fire; 1 bit: bits 31 and 29 of the first word
    lv = np.array([[1, 0, 1]], np.uint8)
    assert pack_levels(lv, 1, np.arange(3))[0, 0] == 0xA0000000
    # the head counts odd numbers in row 1: its first nozzle is rotoprint nozzle 1
    assert pack_levels(lv, 1, nozzle_order(3, 2, odd_row=1))[0, 0] == 0x60000000
    # 2 bits: level 3 then level 1
    assert pack_levels(np.array([[3, 1]], np.uint8), 2, np.arange(2))[0, 0] == 0xD0000000
    # 4 bits: level 7 then 5 in the low 3 bits of each nibble
    assert pack_levels(np.array([[7, 5]], np.uint8), 4, np.arange(2))[0, 0] == 0x75000000
    # little-endian words on disk
    assert packed_bytes(np.array([[0xA0000000]], np.uint32)) == bytes([0, 0, 0, 0xA0])
    # 33 nozzles at 1 bit: the second word holds nozzle 32 in its top bit
    lv = np.zeros((1, 33), np.uint8)
    lv[0, 32] = 1
    assert pack_levels(lv, 1, np.arange(33)).tolist() == [[0, 0x80000000]]


def test_nozzle_order_groups_and_directions():
    assert nozzle_order(5, 2, odd_row=1).tolist() == [1, 0, 3, 2, 4]
    assert nozzle_order(6, 2, odd_row=1, descending=True).tolist() == [5, 4, 3, 2, 1, 0]
    assert nozzle_order(6, 2, descending=True).tolist() == [4, 5, 2, 3, 0, 1]
    assert nozzle_order(7, 3, odd_row=2).tolist() == [2, 0, 1, 5, 3, 4, 6]
    with pytest.raises(ConfigError, match="odd_row"):
        nozzle_order(4, 2, odd_row=2)


def test_levels_that_do_not_fit_and_bad_files_are_refused():
    assert (bits_for_levels(1), bits_for_levels(2), bits_for_levels(3), bits_for_levels(7)) == (1, 2, 2, 4)
    with pytest.raises(ConfigError, match="grey levels"):
        bits_for_levels(8)
    with pytest.raises(ImageError, match="does not fit 1 bit"):
        pack_levels(np.array([[2]], np.uint8), 1, np.arange(1))
    with pytest.raises(ImageError, match="need 8"):
        read_packed(b"\0" * 7, 2, 32, 1)
    bad = np.array([[0x1]], np.uint32)  # a padding bit after nozzle 0 of 1
    with pytest.raises(ImageError, match="padding"):
        unpack_levels(bad, 1, np.arange(1))
    with pytest.raises(ImageError, match="high"):
        unpack_levels(np.array([[0x80000000]], np.uint32), 4, np.arange(1))


@pytest.mark.parametrize("bits", [1, 2, 4])
@pytest.mark.parametrize("nozzles", [13, 33])
def test_tiff_planes_read_back_with_tifffile_and_pillow_at_the_declared_depth(bits, nozzles):
    import tifffile
    from PIL import Image

    rng = np.random.default_rng(bits + nozzles)
    lv = rng.integers(0, max_level(bits) + 1, (11, nozzles)).astype(np.uint8)
    order = nozzle_order(nozzles, 2, odd_row=1)
    data = tiff_bytes(lv, bits, order, description="test")
    with tifffile.TiffFile(io.BytesIO(data)) as tf:
        page = tf.pages[0]
        assert page.bitspersample == bits and page.shape == (11, nozzles)
        got = page.asarray()
    assert np.array_equal(got.astype(np.uint8), lv[:, order])
    with Image.open(io.BytesIO(data)) as im:
        im.load()
        assert im.tag_v2[258] == (bits,)
        assert im.size == (nozzles, 11)
        arr = np.asarray(im)
    if bits == 1:
        assert im.mode == "1" and np.array_equal(arr, lv[:, order] > 0)
    else:  # Pillow scales 2- and 4-bit samples to 0..255
        assert np.array_equal(arr.astype(np.int64), lv[:, order].astype(np.int64) * (255 // (2**bits - 1)))
