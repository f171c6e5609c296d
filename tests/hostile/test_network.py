"""The Dask scheduler: invalid addresses refused up front, a silent server times out cleanly.

The silent server listens on loopback only, accepts every connection and never sends a byte;
it runs in a daemon thread for the length of one test.
"""

from __future__ import annotations

import os
import socket
import threading
import time

import pytest

from _bounds_helpers import assert_refused, run_cli_bounded
from rotoprint.examples import write_binary_stl
from rotoprint.testing import box_triangles

pytest.importorskip("distributed", reason="the --scheduler tests need dask distributed (rotoprint[test])")


@pytest.fixture
def box(tmp_path):
    write_binary_stl(tmp_path / "box.stl", box_triangles((2, 2, 1.0)))  # 10 layers: some go to the scheduler
    return tmp_path / "box.stl"


@pytest.mark.parametrize(("cmd", "address"), [
    ("slice", "tcp://127.0.0.1:99999"), ("slice", "tcp://127.0.0.1:0"), ("slice", "127.0.0.1:65536"),
    ("slice", "tcp://127.0.0.1:http"), ("slice", "tcp://127.0.0.1"), ("slice", "tcp://:8786"),
    ("dlp", "tcp://127.0.0.1:99999"), ("dlp", "tcp://127.0.0.1:0"),
])
def test_invalid_scheduler_address_is_refused_up_front(tmp_path, box, address, cmd):
    out = "out" if cmd == "slice" else "out.sl1"
    run = run_cli_bounded(cmd, "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.1", "-o", out,
                          "--scheduler", address, cwd=tmp_path)
    line = assert_refused(run, repr(address))
    assert "port" in line or "must look like tcp://HOST:PORT" in line
    assert sorted(os.listdir(tmp_path)) == ["box.stl"]


class SilentServer:
    """Loopback TCP server that accepts and never answers."""

    def __init__(self) -> None:
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.accepted: list[socket.socket] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                c, _ = self.sock.accept()
            except OSError:
                continue
            self.accepted.append(c)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(5)
        for c in self.accepted:
            c.close()
        self.sock.close()


@pytest.fixture
def silent():
    s = SilentServer()
    yield s
    s.close()


@pytest.mark.parametrize("cmd", ["slice", "dlp"])
def test_scheduler_that_never_answers_times_out_and_leaves_no_partial(run_cli, monkeypatch, tmp_path, box, silent, cmd):
    from rotoprint.pipeline import producer

    monkeypatch.setattr(producer, "DASK_CONNECT_TIMEOUT_S", 2.0)
    out = tmp_path / ("out" if cmd == "slice" else "out.sl1")
    t0 = time.perf_counter()
    code, _, err = run_cli(cmd, box, "-d", "perfactory-sxga", "--layer-height", "0.1", "-o", out,
                           "--scheduler", f"tcp://127.0.0.1:{silent.port}")
    dt = time.perf_counter() - t0
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert f"tcp://127.0.0.1:{silent.port} did not answer within 2 s" in lines[0]
    assert silent.accepted, "the client never connected: the test did not test the hang"
    assert dt < 15, dt
    assert sorted(os.listdir(tmp_path)) == ["box.stl"]  # no out, no out.partial
