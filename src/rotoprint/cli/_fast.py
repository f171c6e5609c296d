"""A fast start for ``rotoprint dlp``: its options read by a small parser of its own, without
typer, rich, pydantic or numba, so that a short job (a 10-layer plate) is not mostly start-up.

:func:`try_dlp` reads the command line the way the typer command does (:data:`DLP_OPTIONS`
is the command's option table: the same names, defaults, flags and range checks;
``tests/test_fast_dlp.py`` builds its check from the typer command's own parameters, so an
option added there and not here fails the tests) and calls the same
:func:`rotoprint.cli._dlp_run.run_dlp`. Whatever it does not read plainly -- ``--help``, an
unknown or malformed option, a missing one, a value out of range, app options other than
``-v``/``-q`` -- it hands back (returns None) and the typer command runs instead, so usage
errors and help are typer's own, word for word. ``ROTOPRINT_FAST_CLI=0`` turns it off.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

from .. import ranges as R

__all__ = ["DLP_OPTIONS", "parse_dlp", "try_dlp"]

# (parameter, option strings, value type or "flag", default, check); a flag's option strings
# are (on, ...) or, for an on/off pair, ((on,), (off,)). "range:NAME" checks against
# rotoprint.ranges.NAME as the typer callback in_range(R.NAME) does; "scale" as scale_cb.
_REQUIRED = object()
DLP_OPTIONS: tuple[tuple[str, Any, Any, Any, str | None], ...] = (
    ("device", ("--device", "-d"), str, _REQUIRED, None),
    ("layer_height", ("--layer-height",), float, _REQUIRED, "range:LAYER_HEIGHT_MM"),
    ("out", ("--out", "-o"), Path, _REQUIRED, None),
    ("mode", ("--mode",), str, "coverage", None),
    ("erm", ("--erm",), "flag", False, None),
    ("invert", ("--invert",), "flag", False, None),
    ("mirror_x", ("--mirror-x",), "flag", False, None),
    ("mirror_y", ("--mirror-y",), "flag", False, None),
    ("first_layers", ("--first-layers",), int, 0, "range:COUNT"),
    ("first_layer_offset", ("--first-layer-offset",), float, 0.0, "range:OFFSET_UM"),
    ("fmt", ("--format",), str, "auto", None),
    ("exposure", ("--exposure",), float, None, "range:EXPOSURE_S"),
    ("first_exposure", ("--first-exposure",), float, None, "range:EXPOSURE_S"),
    ("fibre_angle", ("--fibre-angle",), float, None, "range:ANGLE_DEG"),
    ("offset", ("--offset",), str, None, None),
    ("units", ("--units",), str, "mm", None),
    ("scale", ("--scale",), float, 1.0, "scale"),
    ("rotate", ("--rotate",), str, None, None),
    ("translate", ("--translate",), str, None, None),
    ("fill_holes", (("--fill-holes",), ("--no-fill-holes",)), "flag", True, None),
    ("workers", ("--workers", "-j"), int, 1, "range:WORKERS"),
    ("scheduler", ("--scheduler",), str, None, None),
    ("resume", ("--resume",), "flag", False, None),
    ("quiet", ("--quiet", "-q"), "flag", False, None),
    ("verbose", ("--verbose", "-v"), "flag", False, None),
    ("force", ("--force",), "flag", False, None),
)
DLP_ARGUMENT = ("mesh", Path)


class _NotPlain(Exception):
    """The command line is not one the fast parser reads: the typer command takes it."""


def _table() -> tuple[dict[str, tuple[str, Any, bool]], dict[str, Any]]:
    opts: dict[str, tuple[str, Any, bool]] = {}
    for name, strings, kind, default, _ in DLP_OPTIONS:
        if kind == "flag" and isinstance(strings[0], tuple):
            for s in strings[0]:
                opts[s] = (name, kind, True)
            for s in strings[1]:
                opts[s] = (name, kind, False)
        else:
            for s in strings:
                opts[s] = (name, kind, True)
    return opts, {name: default for name, _, _, default, _ in DLP_OPTIONS}


def parse_dlp(args: list[str]) -> dict[str, Any]:
    """The keyword arguments of :func:`~rotoprint.cli._dlp_run.run_dlp` from the words after
    ``dlp``, converted and checked as the typer command does; raises :class:`_NotPlain` for
    anything else (the typer command then reads it and says what is wrong)."""
    table, params = _table()
    positional: list[str] = []
    i = 0
    while i < len(args):
        a = args[i]
        i += 1
        if a == "--":
            positional.extend(args[i:])
            break
        if a[:1] != "-" or a == "-":
            positional.append(a)
            continue
        if a.startswith("--"):
            key, eq, inline = a.partition("=")
        elif len(a) > 2 and a[:2] in table and table[a[:2]][1] != "flag":
            key, eq, inline = a[:2], "=", a[2:]  # -ojob.sl1s
        else:
            key, eq, inline = a, "", ""
        if key not in table or key == "--help":
            raise _NotPlain(a)
        name, kind, on = table[key]
        if kind == "flag":
            if eq:
                raise _NotPlain(a)  # a flag takes no value: typer says so
            params[name] = on
            continue
        if eq:
            text = inline
        elif i < len(args):
            text = args[i]
            i += 1
        else:
            raise _NotPlain(a)  # the option's value is missing
        try:
            params[name] = kind(text)
        except ValueError:
            raise _NotPlain(a) from None
    if len(positional) != 1 or any(v is _REQUIRED for v in params.values()):
        raise _NotPlain("arguments")
    params[DLP_ARGUMENT[0]] = DLP_ARGUMENT[1](positional[0])
    _check(params)
    return params


def _check(params: dict[str, Any]) -> None:
    """The typer callbacks' range checks; a value out of range goes to the typer command
    (which checks in its own order, so that the first error named is the same)."""
    from ..errors import ConfigError
    from ._base import check_scale

    try:
        for name, strings, _, _, check in DLP_OPTIONS:
            value = params[name]
            if check is None or value is None:
                continue
            if check == "scale":
                check_scale(value, strings[0])
            else:
                R.check_range(value, getattr(R, check.split(":", 1)[1]), strings[0])
    except ConfigError:
        raise _NotPlain("range") from None


class _LazyConsole:
    """The rich console, made on first use (a jit-compile notice): rich is not imported unless
    something is shown through it."""

    def __getattr__(self, name: str):
        from ._console import console

        return getattr(console, name)


def try_dlp(argv: list[str]) -> int | None:
    """Run ``rotoprint [-v|-q] dlp ...`` here and return its exit code, or None when the
    command line is for the typer app (not dlp, help, a usage error, ``ROTOPRINT_FAST_CLI=0``)."""
    if os.environ.get("ROTOPRINT_FAST_CLI", "1") == "0":
        return None
    app_quiet = app_verbose = False
    k = 0
    while k < len(argv) and argv[k] in ("-q", "--quiet", "-v", "--verbose"):
        if argv[k] in ("-q", "--quiet"):
            app_quiet = True
        else:
            app_verbose = True
        k += 1
    if k >= len(argv) or argv[k] != "dlp":
        return None
    try:
        params = parse_dlp(list(argv[k + 1:]))
    except _NotPlain:
        return None
    return _run(params, app_quiet, app_verbose)


def _run(params: dict[str, Any], app_quiet: bool, app_verbose: bool) -> int:
    from ..errors import RotoprintError
    from ._base import _FLAGS, EXIT_BAD_INPUT, error_line, setup_logging
    from ._dlp_run import PlainUI, RichUI, run_dlp

    if "numpy" not in sys.modules:
        # OpenBLAS starts a thread per core when numpy is imported (about a third of numpy's
        # import); the DLP path's only matrix products are 3 x 3, which it never threads.
        # A value the user set is kept.
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    _FLAGS.quiet, _FLAGS.verbose = app_quiet, app_verbose  # as the app callback sets them
    if app_verbose:
        setup_logging(True)
    quiet = params["quiet"] or app_quiet
    # rich only when something may be drawn on a terminal (the progress bar); else plain lines
    ui = RichUI() if not quiet and _maybe_terminal() else PlainUI()
    console = _LazyConsole()
    notice = None
    if _maybe_terminal() or os.environ.get("ROTOPRINT_COMPILE_NOTICE") == "1":
        from .. import _jitnotice as notice

        notice.install(console)  # (it asks the console whether it is a terminal)
    try:
        run_dlp(**params, ui=ui)
        return 0
    except (RotoprintError, OSError) as exc:
        _say_error(error_line(exc))
        return EXIT_BAD_INPUT
    except KeyboardInterrupt:
        sys.stderr.write("rotoprint: aborted\n")
        return 130
    finally:
        if notice is not None:
            notice.finish(console)


def _maybe_terminal() -> bool:
    """Whether rich could take stderr for a terminal: a tty, or one of the variables by which
    rich is told so. When this is False the rich console would print plain lines, and so do we."""
    if any(os.environ.get(v) for v in ("FORCE_COLOR", "TTY_INTERACTIVE", "TTY_COMPATIBLE", "JUPYTER_COLUMNS", "JUPYTER_LINES")):
        return True
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # no stderr, or a closed one
        return False


def _say_error(text: str) -> None:
    """``rotoprint: error: ...`` as the typer app prints it (red on a terminal)."""
    if _maybe_terminal() or not (text.isascii() and text.isprintable()):  # (rich's layout of the rest)
        from ._console import console
        from ._common import styled

        console.print(styled(("rotoprint: error:", "red"), f" {text}"), soft_wrap=True)
    else:
        from ._base import escape_controls

        sys.stderr.write(f"rotoprint: error: {escape_controls(text)}\n")
