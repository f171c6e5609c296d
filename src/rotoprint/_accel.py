"""The optional C extension :mod:`rotoprint._native` (built at install with the machine's C
compiler and zlib; see ``_native.c``). ``native`` is the module, or None where it was not
built, and then the numba kernels run instead. ``ROTOPRINT_NATIVE=0`` turns it off (tests of
the fallback, comparisons).
"""

from __future__ import annotations

import os

native = None
if os.environ.get("ROTOPRINT_NATIVE", "1") != "0":
    try:
        from . import _native as native  # noqa: F401
    except ImportError:  # not built (no compiler at install): numba kernels instead
        native = None
