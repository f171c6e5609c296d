"""One bounded, ordered window of futures: results in submission order, at most ``window``
in flight, so memory does not grow with the number of items.

Used by the layer producer (:mod:`rotoprint.pipeline.producer`) and by the archive writer's
PNG encoding threads (:mod:`rotoprint.io.archives`); it imports nothing of rotoprint, so both
layers can use it."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterable, Iterator
from typing import Any

__all__ = ["ordered"]


def ordered(submit: Callable[[Any], Any], items: Iterable, window: int) -> Iterator:
    """Yield ``submit(item).result()`` for every item, in the order of ``items``.

    Parameters
    ----------
    submit : callable
        ``submit(item)`` returns a future (``concurrent.futures`` or Dask).
    items : iterable
        Consumed lazily: an item is taken only when there is room in the window.
    window : int
        Futures in flight at most (at least 1).

    Yields
    ------
    object
        The futures' results, in order. Futures not yet collected are cancelled when the
        consumer stops early or an error propagates.
    """
    window = max(1, int(window))
    pending: deque = deque()
    it = iter(items)
    try:
        for item in it:
            pending.append(submit(item))
            if len(pending) >= window:
                break
        while pending:
            fut = pending.popleft()
            yield fut.result()
            for item in it:
                pending.append(submit(item))
                break
    finally:
        for fut in pending:
            fut.cancel()
