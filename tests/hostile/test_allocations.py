"""Hostile sizes: every raster, swathe and firing count is sized before it is allocated (one
check, :func:`rotoprint._resources.check_raster_fits`), so a request that would not fit is one
line naming its size, and exit 2, in a child process whose address space is limited to 1 GiB
beyond what it has mapped at start (``ulimit -v``, which the check honours).

What is checked is the order, not the speed: the child traces its allocations (tracemalloc,
which numpy reports its buffers to) from the start of the command, and a refusal must come
before anything near the refused size was allocated (:func:`assert_sized_first`); where a
stage must not run at all before the refusal (the simulation, the image decoder), the child
replaces it with a trap that exits 99 (``forbid``). The timeouts are hang guards only.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import numpy as np
import pytest

GIB = 1 << 30
MIB = 1 << 20
#: a refusal's own work: imports are done before tracing starts, so this is the inputs read
#: (a 2500 x 2500 px design is 6 MiB) and the plan; the refused rasters are 1 GiB and more
SIZED_FIRST_MAX_BYTES = 64 * MIB
FORBIDDEN_EXIT = 99
CHILD = r"""
import importlib, json, os, resource, sys, tracemalloc
with open("/proc/self/statm") as fh:
    mapped = int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")
lim = mapped + (1 << 30)
resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
for spec in filter(None, os.environ.get("ROTOPRINT_TEST_FORBID", "").split(",")):
    mod, _, name = spec.rpartition(".")
    m = importlib.import_module(mod)
    assert callable(getattr(m, name)), spec
    def trap(*a, _spec=spec, **k):
        sys.stderr.write(f"forbidden stage reached: {_spec}\n")
        sys.stderr.flush()
        os._exit(%d)
    setattr(m, name, trap)
from rotoprint.cli.main import main
# the modules the commands import lazily, before tracing (their objects are not the command's work)
import numba, PIL.Image, rotoprint.cli.simulate, rotoprint.cli.transform, rotoprint.rotary.exact
import rotoprint.rotary.files, rotoprint.rotary.paper, rotoprint.rotary.simulate
peak_file = os.environ.get("ROTOPRINT_TEST_PEAK")
if peak_file:
    tracemalloc.start()
try:
    rc = main(sys.argv[1:])
finally:
    if peak_file:
        with open(peak_file, "w") as fh:
            json.dump({"traced_peak": tracemalloc.get_traced_memory()[1]}, fh)
sys.exit(rc)
""" % FORBIDDEN_EXIT


class Run:
    """A finished child: ``returncode``, ``stdout``, ``stderr``, its own peak resident memory
    ``peak_rss`` (bytes, from wait4) and its traced allocation peak ``traced_peak`` (bytes)."""

    def __init__(self, returncode: int, stdout: str, stderr: str, peak_rss: int, traced_peak: int | None) -> None:
        self.returncode, self.stdout, self.stderr = returncode, stdout, stderr
        self.peak_rss, self.traced_peak = peak_rss, traced_peak


def run_limited(argv: list[str], cwd: Path, timeout_s: float = 120.0, forbid: tuple[str, ...] = (),
                trace: bool = True) -> Run:
    """Run the CLI in a child with 1 GiB of extra address space; ``forbid``: dotted names of
    functions replaced by a trap (exit 99) before the command runs; ``trace``: trace its
    allocations (slows a long command several times). ``timeout_s`` is a hang guard (the
    child is killed), not a time limit on the work."""
    with tempfile.TemporaryDirectory() as tmp:
        peak_file = Path(tmp) / "peak.json"
        env = {**os.environ, "ROTOPRINT_TEST_FORBID": ",".join(forbid), "ROTOPRINT_TEST_PEAK": str(peak_file) if trace else ""}
        with open(Path(tmp) / "out", "w+") as out, open(Path(tmp) / "err", "w+") as err:
            proc = subprocess.Popen([sys.executable, "-c", CHILD, *argv], stdout=out, stderr=err, text=True, cwd=cwd, env=env)
            guard = threading.Timer(timeout_s, proc.kill)
            guard.start()
            try:
                _, status, usage = os.wait4(proc.pid, 0)
            finally:
                guard.cancel()
            proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here: Popen must not wait again
            out.seek(0)
            err.seek(0)
            stdout, stderr = out.read(), err.read()
        traced = json.loads(peak_file.read_text())["traced_peak"] if peak_file.exists() else None
    assert proc.returncode != -9, f"hang guard: killed after {timeout_s} s: {stderr[-2000:]}"
    return Run(proc.returncode, stdout, stderr, usage.ru_maxrss * 1024, traced)


_UNITS = {"B": 1, "KiB": 1 << 10, "MiB": 1 << 20, "GiB": 1 << 30, "TiB": 1 << 40}


def refused_bytes(line: str) -> int:
    """The size a refusal names ("would need 1.3 GiB"), in bytes."""
    m = re.search(r"would need ([0-9.]+) (B|KiB|MiB|GiB|TiB)", line)
    assert m, line
    return int(float(m.group(1)) * _UNITS[m.group(2)])


def assert_sized_first(r: Run, line: str) -> None:
    """The refusal came before any large allocation: the child's traced peak is small, both in
    itself and against the size the refusal names."""
    need = refused_bytes(line)
    assert r.traced_peak is not None, r.stderr[-2000:]
    assert r.traced_peak < min(SIZED_FIRST_MAX_BYTES, need // 10), (r.traced_peak, need, line)


def assert_refused(r, *names: str) -> str:
    lines = [ln for ln in r.stderr.splitlines() if ln.strip()]
    assert r.returncode != FORBIDDEN_EXIT, r.stderr[-2000:]
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
    """Issue 12: 11.6 GB. Now refused before the simulation starts, saying how big: the
    simulation and the overlay renderer are traps in the child, and nothing large was allocated."""
    before = _snapshot(big_print)
    r = run_limited(["simulate", "p.png", "-o", "ov.png", "--scale", "16"], big_print,
                    forbid=("rotoprint.rotary.simulate.simulate", "rotoprint.rotary.simulate.render_overlay"))
    line = assert_refused(r, "overlay at --scale 16", "40000 x 40000 px", "GiB")
    assert_sized_first(r, line)
    assert _snapshot(big_print) == before, line


def test_transform_at_the_top_of_the_dpi_range_is_sized(big_print):
    """dpi_y = 100000 (the top of its range) on a 17.6 mm design: 764 nozzles x ~2.4 M firings a
    swathe; refused up front in a 1 GiB child (before anything near its size is allocated), or
    made within it."""
    before = _snapshot(big_print)
    r = run_limited(["transform", "big.png", "-d", "omnidot760", "--tilt", "30", "--radius", "50",
                     "--design-dpi", "3600", "--dpi-y", "100000", "-o", "hi.png", "-q"], big_print)
    if r.returncode == 2:
        assert_sized_first(r, assert_refused(r, "would need"))
        assert _snapshot(big_print) == before
    else:
        assert r.returncode == 0, r.stderr[-2000:]
        assert r.peak_rss < 1.5 * GIB


def test_paper_transform_sizes_its_polar_image(big_print):
    before = _snapshot(big_print)
    r = run_limited(["transform", "big.png", "-d", "omnidot760", "--tilt", "30", "--radius", "50", "--method", "paper",
                     "--design-dpi", "3600", "--dpi-y", "100000", "-o", "pp.png", "-q"], big_print)
    if r.returncode == 2:
        assert_sized_first(r, assert_refused(r, "would need"))
        assert _snapshot(big_print) == before
    else:
        assert r.returncode == 0, r.stderr[-2000:]
        assert r.peak_rss < 1.5 * GIB


def test_largest_drop_diameter_takes_the_nearest_drop_query(tmp_path, monkeypatch):
    """--drop-diameter at the top of its range (10 mm discs): a nearest-drop query per pixel, not a
    window loop of (disc area x drops), and within the 1 GiB child; beyond the range it is refused."""
    import scipy.spatial
    from PIL import Image

    from rotoprint.cli.main import main

    d = np.zeros((40, 60), np.uint8)
    d[5:35, 10:50] = 255
    Image.fromarray(d).save(tmp_path / "d.png")
    assert main(["transform", str(tmp_path / "d.png"), "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", str(tmp_path / "p.png"), "-q"]) == 0
    r = run_limited(["simulate", "p.png", "-o", "ov.png", "--drop-diameter", "10000", "--json"], tmp_path, trace=False)
    assert r.returncode == 0, r.stderr[-2000:]
    rep = json.loads(r.stdout)
    assert rep["drop_diameter_um"] == 10000 and rep["disc_uncovered_fraction"] == 0.0
    assert r.peak_rss < 1.5 * GIB
    # which path marked the discs: the query builds a k-d tree of the drops, the loop does not
    trees = []
    real = scipy.spatial.cKDTree

    def counted(*a, **k):
        trees.append(1)
        return real(*a, **k)

    monkeypatch.setattr(scipy.spatial, "cKDTree", counted)
    assert main(["simulate", str(tmp_path / "p.png"), "-o", str(tmp_path / "ov-q.png"), "--drop-diameter", "10000", "--json"]) == 0
    assert trees, "10 mm discs were stamped drop by drop"
    r = run_limited(["simulate", "p.png", "-o", "ov2.png", "--drop-diameter", "1e7"], tmp_path)
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
    """``ulimit -v`` bounds what check_raster_fits lets through (the suite's children rely on it).

    The limit is set 1 GiB above what the child has mapped, so that it binds: a limit above the
    machine's memory (64 GiB once) left the figure to MemAvailable, which the other test worker
    moves between the child's two reads (CI once saw 23472951296 against 23472119808 before it)."""
    code = ("import resource, os\n"
            "from rotoprint._resources import available_memory_bytes as a\n"
            "free = a()\n"
            "mapped = int(open('/proc/self/statm').read().split()[0]) * os.sysconf('SC_PAGE_SIZE')\n"
            "resource.setrlimit(resource.RLIMIT_AS, (mapped + (1 << 30), resource.RLIM_INFINITY)); limited = a()\n"
            "print(free, limited)\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    free, limited = map(int, r.stdout.split())
    assert 0 < limited <= min(free, 1 << 30)


def test_sidecar_sizes_its_images_before_reading(tmp_path):
    """A sidecar that claims a swathe of 10^6 firings x 764 nozzles (a small file) is sized before
    the image is opened (the image decoder is a trap in the child): it must match the PNG, and
    the sum must fit."""
    from PIL import Image

    from rotoprint.cli.main import main

    d = np.zeros((40, 60), np.uint8)
    d[5:35, 10:50] = 255
    Image.fromarray(d).save(tmp_path / "d.png")
    assert main(["transform", str(tmp_path / "d.png"), "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", str(tmp_path / "p.png"), "-q"]) == 0
    side = json.loads((tmp_path / "p.json").read_text())
    side["swathes"][0]["firings"] = 2**39
    (tmp_path / "p.json").write_text(json.dumps(side))
    r = run_limited(["simulate", "p.png", "-o", "ov.png"], tmp_path, forbid=("rotoprint.rotary.files.open_image",))
    line = assert_refused(r, "p.json", "would need")
    assert_sized_first(r, line)
    assert not (tmp_path / "ov.png").exists()
    assert os.path.getsize(tmp_path / "p.png") > 0
