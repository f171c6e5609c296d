"""Hostile sizes: every raster, swathe and firing count is sized before it is allocated (one
check, :func:`rotoprint._resources.check_raster_fits`), so a request that would not fit is one
line and exit 2 within seconds, in a child process whose address space is limited to 1 GiB
beyond what it has mapped at start (``ulimit -v``, which the check honours) and whose peak
resident memory is measured.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

GIB = 1 << 30
CHILD = r"""
import os, resource, sys
with open("/proc/self/statm") as fh:
    mapped = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
lim = mapped + (1 << 30)
resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
from rotoprint.cli.main import main
sys.exit(main(sys.argv[1:]))
"""


def run_limited(argv: list[str], cwd: Path, timeout_s: float = 60.0) -> tuple[subprocess.CompletedProcess, float, int]:
    """Run the CLI in a child with 1 GiB of extra address space; (result, seconds, peak RSS bytes)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    t0 = time.monotonic()
    r = subprocess.run([sys.executable, "-c", CHILD, *argv], capture_output=True, text=True, timeout=timeout_s, cwd=cwd)
    dt = time.monotonic() - t0
    peak = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss
    # ru_maxrss of the children is the largest of any child so far: only a bound when it grew
    return r, dt, max(peak, before) * 1024


def assert_refused(r, *names: str) -> str:
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert len(lines) == 1 and "Traceback" not in r.stderr, r.stderr[-2000:]
    for n in names:
        assert n in lines[0], (n, lines[0])
    return lines[0]


@pytest.fixture(scope="module")
def big_print(tmp_path_factory) -> Path:
    """A 2500 x 2500 px design at 3600 dpi (17.6 mm square) and its print (transform, ~5 s)."""
    from PIL import Image

    from rotoprint.cli.main import main

    root = tmp_path_factory.mktemp("bigprint")
    d = np.zeros((2500, 2500), np.uint8)
    d[100:2400, 100:2400] = 255
    Image.fromarray(d).save(root / "big.png")
    code = main(["transform", str(root / "big.png"), "-d", "omnidot760", "--tilt", "30", "--radius", "50",
                 "--design-dpi", "3600", "-o", str(root / "p.png"), "-q"])
    assert code == 0
    return root


def _snapshot(folder: Path) -> dict[str, int]:
    return {p.name: p.stat().st_mtime_ns for p in folder.iterdir()}


def test_overlay_scale_16_on_a_2500_px_design_is_sized_first(big_print):
    """Issue 12: 11.6 GB. Now refused before the simulation starts, saying how big."""
    before = _snapshot(big_print)
    r, dt, _ = run_limited(["simulate", "p.png", "-o", "ov.png", "--scale", "16"], big_print)
    line = assert_refused(r, "overlay at --scale 16", "40000 x 40000 px", "GiB")
    assert dt < 30, dt
    assert _snapshot(big_print) == before, line


def test_transform_at_the_top_of_the_dpi_range_is_sized(big_print):
    """dpi_y = 100000 (the top of its range) on a 17.6 mm design: 764 nozzles x ~2.4 M firings a
    swathe; refused up front in a 1 GiB child, or made within it."""
    before = _snapshot(big_print)
    r, dt, peak = run_limited(["transform", "big.png", "-d", "omnidot760", "--tilt", "30", "--radius", "50",
                               "--design-dpi", "3600", "--dpi-y", "100000", "-o", "hi.png", "-q"], big_print, timeout_s=120)
    if r.returncode == 2:
        assert_refused(r, "would need")
        assert _snapshot(big_print) == before
    else:
        assert r.returncode == 0, r.stderr[-2000:]
        assert peak < 1.5 * GIB
    assert dt < 60, dt


def test_paper_transform_sizes_its_polar_image(big_print):
    before = _snapshot(big_print)
    r, dt, _ = run_limited(["transform", "big.png", "-d", "omnidot760", "--tilt", "30", "--radius", "50", "--method", "paper",
                            "--design-dpi", "3600", "--dpi-y", "100000", "-o", "pp.png", "-q"], big_print, timeout_s=120)
    if r.returncode == 2:
        assert_refused(r, "would need")
        assert _snapshot(big_print) == before
    else:
        assert r.returncode == 0, r.stderr[-2000:]
    assert dt < 60, dt


def test_largest_drop_diameter_is_fast(tmp_path):
    """--drop-diameter at the top of its range (10 mm discs): a nearest-drop query per pixel, not a
    window loop of (disc area x drops); beyond the range it is refused."""
    from PIL import Image

    from rotoprint.cli.main import main

    d = np.zeros((40, 60), np.uint8)
    d[5:35, 10:50] = 255
    Image.fromarray(d).save(tmp_path / "d.png")
    assert main(["transform", str(tmp_path / "d.png"), "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", str(tmp_path / "p.png"), "-q"]) == 0
    r, dt, _ = run_limited(["simulate", "p.png", "-o", "ov.png", "--drop-diameter", "10000", "--json"], tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    rep = json.loads(r.stdout)
    assert rep["drop_diameter_um"] == 10000 and rep["disc_uncovered_fraction"] == 0.0
    assert dt < 30, dt
    r, _, _ = run_limited(["simulate", "p.png", "-o", "ov2.png", "--drop-diameter", "1e7"], tmp_path)
    assert_refused(r, "--drop-diameter")
    assert not (tmp_path / "ov2.png").exists()


def test_disc_mask_query_equals_the_stamp_loop():
    """The two ways of marking the pixels within a drop's radius give the same mask."""
    import importlib

    S = importlib.import_module("rotoprint.rotary.simulate")

    rng = np.random.default_rng(3)
    n = 300
    drops = S.Drops(x_mm=np.zeros(n), y_mm=np.zeros(n), col=rng.uniform(-5, 45, n), row=rng.uniform(-5, 35, n),
                    level=np.ones(n, np.uint8), swathe=np.zeros(n, np.int16), nozzle=np.zeros(n, np.int64), firing=np.zeros(n, np.int64))
    for radius in (0.03, 0.2, 0.7):
        old = S._DISC_LOOP_FACTOR
        try:
            S._DISC_LOOP_FACTOR = 10**12
            loop = S._printed_mask(drops, (30, 40), 0.07, 0.05, radius)
            S._DISC_LOOP_FACTOR = 0
            query = S._printed_mask(drops, (30, 40), 0.07, 0.05, radius)
        finally:
            S._DISC_LOOP_FACTOR = old
        assert loop.any() and np.array_equal(loop, query), radius


def test_the_check_honours_the_address_space_limit():
    """``ulimit -v`` bounds what check_raster_fits lets through (the suite's children rely on it)."""
    code = ("import resource, os\n"
            "from rotoprint._resources import available_memory_bytes as a\n"
            "free = a(); resource.setrlimit(resource.RLIMIT_AS, (1 << 36, 1 << 36)); limited = a()\n"
            "print(free, limited)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    free, limited = map(int, r.stdout.split())
    assert limited <= min(free, 1 << 36)


def test_sidecar_sizes_its_images_before_reading(tmp_path):
    """A sidecar that claims a swathe of 10^6 firings x 764 nozzles (a small file) is sized before
    the image is opened: it must match the PNG, and the sum must fit."""
    from PIL import Image

    from rotoprint.cli.main import main

    d = np.zeros((40, 60), np.uint8)
    d[5:35, 10:50] = 255
    Image.fromarray(d).save(tmp_path / "d.png")
    assert main(["transform", str(tmp_path / "d.png"), "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", str(tmp_path / "p.png"), "-q"]) == 0
    side = json.loads((tmp_path / "p.json").read_text())
    side["swathes"][0]["firings"] = 2**39
    (tmp_path / "p.json").write_text(json.dumps(side))
    r, dt, _ = run_limited(["simulate", "p.png", "-o", "ov.png"], tmp_path)
    assert_refused(r, "p.json", "would need")
    assert dt < 30
    assert not (tmp_path / "ov.png").exists()
    assert os.path.getsize(tmp_path / "p.png") > 0
