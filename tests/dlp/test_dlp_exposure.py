"""Exposure check on the generated test piece: the paper's finding, and where the modes stand."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rotoprint.masks import exposure_table, feature_exposure, narrowest_kept_um
from rotoprint.pieces import Feature
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def rows():
    return exposure_table(phases=2, widths_mm=(0.010, 0.020, 0.030, 0.050, 0.100), ring_segments=360)


def _row(rows, kind, um):
    return next(r for r in rows if r["kind"] == kind and r["width_um"] == um)


def test_smooth_lowers_thin_walls_below_what_binary_gives(rows):
    for um in (20, 30, 50):
        r = _row(rows, "wall", um)
        assert r["binary_level"] == 1.0  # a full pixel column at every placement
        assert r["smooth_level"] < 0.8  # smoothing takes 23-46 % of the light away
    # the paper's failure: with a cure threshold of 0.6, smoothing loses 20-30 um walls
    assert narrowest_kept_um(rows, "smooth", "wall", cure_threshold=0.6) == 50
    assert narrowest_kept_um(rows, "binary", "wall", cure_threshold=0.6) == 20
    assert narrowest_kept_um(rows, "coverage", "wall", cure_threshold=0.6) == 20
    # at every threshold coverage keeps at least what smoothing keeps
    for thr in (0.3, 0.5, 0.6, 0.7, 0.9):
        for kind in ("wall", "ring_wall"):
            s = narrowest_kept_um(rows, "smooth", kind, cure_threshold=thr)
            c = narrowest_kept_um(rows, "coverage", kind, cure_threshold=thr)
            assert c is not None and (s is None or c <= s)


def test_coverage_is_proportional_to_width(rows):
    # a 10 um wall is half a pixel: its peak is between a quarter and a half of full light
    r = _row(rows, "wall", 10)
    assert 0.24 <= r["coverage_level"] <= 0.51
    assert _row(rows, "wall", 100)["coverage_level"] == 1.0
    assert _row(rows, "channel", 100)["coverage_level"] == 0.0
    # binary sampling drops the 10 um wall at some placements and keeps it as a full pixel at others
    assert 0 < r["binary_kept"] < 1


def test_feature_exposure_on_synthetic_mask():
    m = np.zeros((40, 40), np.uint8)
    m[:, 10] = 200
    m[:, 20:23] = 255
    A = np.array([[1.0, 0, 0], [0, 1.0, 0]])  # pixel = model mm
    feats = [
        Feature("wall", 0.5, x0=9.8, x1=10.2, y0=0, y1=39),
        Feature("channel", 1.0, x0=15, x1=16, y0=0, y1=39),
        Feature("wall", 0.5, x0=30.0, x1=30.4, y0=0, y1=39),
    ]
    a, b, c = feature_exposure(m, feats, A, pitch_mm=1.0, cure_threshold=0.5)
    assert a.level == pytest.approx(200 / 255) and a.kept and a.samples >= 30
    assert b.level == 0.0 and b.kept
    assert c.level == 0.0 and not c.kept and c.kept_fraction == 0.0


def test_example_script_writes_the_committed_piece(tmp_path):
    out = tmp_path / "piece.stl"
    subprocess.run([sys.executable, str(ROOT / "examples" / "make_test_piece.py"), str(out)], check=True, capture_output=True)
    from rotoprint.io.stl import BINARY_RECORD

    def tris(path):
        data = path.read_bytes()
        return np.frombuffer(data[84:], dtype=BINARY_RECORD)["vertices"].astype(np.float64)

    new, committed = tris(out), tris(ROOT / "examples" / "test_piece.stl")
    # the generator's parameters: a 12-triangle box for the plate, each wall and each of the
    # w + 1 channel blocks; an 8 n-triangle ring prism for each of the w ring walls and the
    # w + 1 walls around the ring gaps (n = ring_segments)
    import inspect

    from rotoprint.pieces import DEFAULT_WIDTHS_MM, feature_test_piece

    w = len(DEFAULT_WIDTHS_MM)
    n = inspect.signature(feature_test_piece).parameters["ring_segments"].default
    expected = 12 * (1 + w + (w + 1)) + 8 * n * (w + (w + 1))
    assert new.shape == committed.shape == (expected, 3, 3)
    # float32 in the file; sin/cos may differ in the last bit between numpy builds
    assert np.abs(new - committed).max() <= 1e-6
    assert (tmp_path / "piece_features.json").exists()
