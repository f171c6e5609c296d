"""The bounded ordered window of futures (rotoprint._window)."""

from __future__ import annotations

import threading
import time
from concurrent.futures import ThreadPoolExecutor

import pytest

from rotoprint._window import ordered


def test_results_in_order_with_at_most_window_in_flight():
    lock = threading.Lock()
    state = {"now": 0, "max": 0}

    def work(i):
        with lock:
            state["now"] += 1
            state["max"] = max(state["max"], state["now"])
        time.sleep(0.002 * ((7 * i) % 5))  # finish out of order
        with lock:
            state["now"] -= 1
        return i * i

    pulled = []

    def items():
        for i in range(40):
            pulled.append(i)
            yield i

    with ThreadPoolExecutor(max_workers=8) as ex:
        got = []
        for r in ordered(lambda i: ex.submit(work, i), items(), 3):
            got.append(r)
            assert len(pulled) <= len(got) + 3  # items are taken only when there is room
    assert got == [i * i for i in range(40)]
    assert state["max"] <= 3


def test_an_error_propagates_and_the_rest_is_cancelled():
    started = []

    def work(i):
        started.append(i)
        if i == 2:
            raise ValueError("layer 2")
        time.sleep(0.01)
        return i

    with ThreadPoolExecutor(max_workers=1) as ex, pytest.raises(ValueError, match="layer 2"):
        list(ordered(lambda i: ex.submit(work, i), range(100), 4))
    assert max(started) < 10  # the window bounded what was submitted; the rest never ran
