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


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
