"""Image buffers handed out again once the caller has let go of them.

A direct rotary layer's swathe images are a few MB each, and a layer of a build is made, written
and dropped before the next. A new block of that size comes from new pages of the system: a page
fault and a zeroed 4 KiB page each (numpy asks for huge pages only from 4 MiB). Measured on an AVX2
EPYC, ``sphere_openscad.stl`` at 45 deg, 3 swathes of 2.0-2.8 MB: 1784 faults, and the layer took
4.4-5.3 ms against 1.4 ms when its pages were reused (``bench/film_cost_filing.py``).

:class:`ReusedBuffers` keeps the blocks it handed out and gives one out again, for the same shape
and dtype, when nothing else refers to it: no array, view, memoryview or print of the caller's
holds it (CPython's reference count says so), so overwriting it cannot change anything the caller
can see. It keeps at most ``keep`` blocks, the newest, and is emptied when pickled.
"""

from __future__ import annotations

import sys
import threading

import numpy as np

__all__ = ["ReusedBuffers"]


def _free_count() -> int:
    """The reference count :meth:`ReusedBuffers.take` reads for a block that only its list holds
    (the list, the local name, the call's argument), measured the way it reads it."""
    held = [np.empty(1, np.uint8)]
    for i in range(len(held)):
        a = held[i]
        return sys.getrefcount(a)
    return 3  # pragma: no cover - the list is not empty


_FREE = _free_count()


class ReusedBuffers:
    """Uninitialised ``np.empty`` blocks, reused once their caller has dropped them.

    Parameters
    ----------
    keep : int
        The most blocks held (oldest forgotten first); 0 keeps none (every :meth:`take` a new block).
    """

    def __init__(self, keep: int) -> None:
        self.keep = max(0, int(keep))
        self._held: list[np.ndarray] = []
        self._lock = threading.Lock()

    def take(self, shape: tuple[int, ...], dtype=np.uint8) -> np.ndarray:
        """A ``shape`` array of ``dtype``, its contents undefined (the caller writes every element):
        a held block nothing else refers to, else a new one (then held)."""
        shape = tuple(int(s) for s in shape)
        dtype = np.dtype(dtype)
        with self._lock:
            held = self._held
            for i in range(len(held)):
                a = held[i]
                if a.shape == shape and a.dtype == dtype and sys.getrefcount(a) == _FREE:
                    del held[i]
                    held.append(a)  # the newest again
                    return a
            a = np.empty(shape, dtype)
            if self.keep:
                held.append(a)
                del held[:-self.keep]
            return a

    def clear(self) -> None:
        """Forget every block (those the caller still holds stay its own)."""
        with self._lock:
            self._held.clear()

    def __len__(self) -> int:
        return len(self._held)

    def __getstate__(self) -> dict:
        return {"keep": self.keep}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["keep"])
