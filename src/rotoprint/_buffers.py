"""Image buffers handed out again once the caller has let go of them.

A direct rotary layer's swathe images are a few MB each, and a layer of a build is made, written
and dropped before the next. A new block of that size comes from new pages of the system: a page
fault and a zeroed 4 KiB page each (numpy asks for huge pages only from 4 MiB). Measured on an AVX2
EPYC, ``sphere_openscad.stl`` at 45 deg, 3 swathes of 2.0-2.8 MB: 1784 faults, and the layer took
4.4-5.3 ms against 1.4 ms when its pages were reused (``bench/film_cost_filing.py``).

:class:`ReusedBuffers` keeps the blocks it handed out and gives one out again, for the same shape
and dtype, when nothing else refers to it: no array, view, memoryview or print of the caller's
holds it (CPython's reference count says so) and no weak reference does (a weakly held block stays
the caller's), so overwriting it cannot change anything the caller can see. It keeps at most
``keep`` blocks, the newest, and is emptied when pickled.

The count is read on the list's item, never through a local name: a debugger or tracer that reads
a frame's locals (``frame.f_locals`` copies them onto the frame on Python 3.11) would otherwise hold
one more reference at that moment, and a baseline measured then would make a block held once by the
caller look free. A probe block held only by its own list is counted the same
way on every call; when its count is not the baseline, nothing is reused.
"""

from __future__ import annotations

import sys
import threading
import weakref

import numpy as np

__all__ = ["ReusedBuffers"]


def _free_count() -> int:
    """The reference count :meth:`ReusedBuffers.take` reads for a block that only its list holds
    (the list and the call's argument), read the way it reads it: on the list's item."""
    held = [np.empty(1, np.uint8)]
    return sys.getrefcount(held[0])


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
        self._probe = [np.empty(1, np.uint8)]  # held by this list only: its count is the baseline's
        self._lock = threading.Lock()

    def take(self, shape: tuple[int, ...], dtype=np.uint8) -> np.ndarray:
        """A ``shape`` array of ``dtype``, its contents undefined (the caller writes every element):
        a held block nothing else refers to, else a new one (then held)."""
        shape = tuple(int(s) for s in shape)
        dtype = np.dtype(dtype)
        with self._lock:
            held = self._held
            if sys.getrefcount(self._probe[0]) == _FREE:  # (else the counts read otherwise here: reuse nothing)
                for i in range(len(held)):
                    # the item's count, not a local name's (see the module doc)
                    if held[i].shape == shape and held[i].dtype == dtype and sys.getrefcount(held[i]) == _FREE \
                            and weakref.getweakrefcount(held[i]) == 0:
                        a = held.pop(i)
                        held.append(a)  # the newest again
                        return a
            a = np.empty(shape, dtype)
            if self.keep:
                held.append(a)
                del held[:-self.keep]
            return a

    def __len__(self) -> int:
        return len(self._held)

    def __getstate__(self) -> dict:
        return {"keep": self.keep}

    def __setstate__(self, state: dict) -> None:
        self.__init__(state["keep"])
