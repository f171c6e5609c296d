"""The ``rotoprint`` console script: ``rotoprint dlp`` through its fast entry
(:mod:`rotoprint.cli._fast`, no typer, rich, pydantic or numba at start-up) when it can read
the command line, everything else through the typer app (:func:`rotoprint.cli.main.main`)."""

from __future__ import annotations

import gc
import os
import sys
import warnings


def main(argv: list[str] | None = None) -> int:
    """Entry point; as :func:`rotoprint.cli.main.main` (which is imported only when needed)."""
    os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")  # as rotoprint.cli.main does
    if _looks_like_dlp(sys.argv[1:] if argv is None else argv):
        _preload_numpy()
    # The imports of a short job make a few hundred thousand objects and almost no cycles (a
    # 600-layer DLP job leaves a few dozen): the cyclic collector, run every 700 objects,
    # was about 5 % of a 10-layer job's CPU. Rarer collections while the fast entry runs.
    thresholds = gc.get_threshold()
    gc.set_threshold(100_000, 50, 100)
    try:
        from ._base import log_warning
        from ._fast import try_dlp

        with warnings.catch_warnings():
            warnings.showwarning = log_warning
            code = try_dlp(sys.argv[1:] if argv is None else list(argv))
    finally:
        gc.set_threshold(*thresholds)
    if code is not None:
        if argv is None:
            # the console script, about to exit: the interpreter's last full collection would
            # walk every object the imports made (about 30 ms of a 10-layer job's 0.2 s of
            # CPU) to find the few dozen cycles the job left, which the exit frees anyway
            gc.freeze()
        return code
    from .main import _run, _log_warning

    with warnings.catch_warnings():
        warnings.showwarning = _log_warning
        return _run(argv)


def _looks_like_dlp(args) -> bool:
    """``[-q|-v ...] dlp ...``, the fast entry's command (it reads the rest; this only decides
    whether numpy's core is worth loading ahead)."""
    k = 0
    while k < len(args) and args[k] in ("-q", "--quiet", "-v", "--verbose"):
        k += 1
    return k < len(args) and args[k] == "dlp" and os.environ.get("ROTOPRINT_FAST_CLI", "1") != "0"


def _preload_numpy() -> None:
    """Load numpy's core extension (and OpenBLAS, gfortran, ... that it links) on another core
    while this thread goes on importing: ``dlopen`` with the GIL released
    (:func:`rotoprint._native.preload`). The dynamic loader's relocations and the libraries'
    constructors were about 6 ms of a 10-layer job's start, in its serial part; numpy's import
    then finds the library loaded. The environment is set first as numpy's import sets it
    before it loads the library (``OPENBLAS_MAIN_FREE``, which numpy unsets again after) and
    as the fast entry wants it (one BLAS thread, unless the user set a number). Nothing
    happens when numpy is already imported, the C extension is off or not built, or numpy's
    layout is not the one known here."""
    if "numpy" in sys.modules or os.environ.get("ROTOPRINT_NATIVE", "1") == "0":
        return
    try:
        from importlib.machinery import EXTENSION_SUFFIXES
        from importlib.util import find_spec

        spec = find_spec("numpy")
        where = list(spec.submodule_search_locations or ()) if spec is not None else []
    except (ImportError, ValueError):
        return
    paths = [os.path.join(w, "_core", "_multiarray_umath" + suffix) for w in where for suffix in EXTENSION_SUFFIXES[:1]]
    path = next((p for p in paths if os.path.isfile(p)), None)
    if path is None:
        return
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # (see rotoprint.cli._fast: the DLP path's products are 3 x 3)
    if "OPENBLAS_MAIN_FREE" not in os.environ:
        os.putenv("OPENBLAS_MAIN_FREE", "1")  # what numpy/_core/__init__.py puts (and takes back) around its load
    import threading

    def load() -> None:
        try:
            from .. import _native

            _native.preload(path)
        except (ImportError, AttributeError, OSError):  # not built, or an older build: numpy loads it itself
            pass

    threading.Thread(target=load, name="rotoprint-preload", daemon=True).start()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
