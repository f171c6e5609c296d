"""The `rotoprint` command. Subcommands live one per module and are registered here."""

from __future__ import annotations

import logging
import os
import sys
import warnings

# The command uses no pydantic plugin; without this pydantic scans every installed package's
# entry points when the device models are built (about 15 ms of each command's start-up).
# Set before anything imports pydantic (rotoprint's package import does not); a plugin the
# user asks for in the variable is left as asked.
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

import typer  # noqa: E402

from ..errors import RotoprintError  # noqa: E402
from ._base import error_line, log_warning  # noqa: E402
from ._common import EXIT_BAD_INPUT, console, styled  # noqa: E402
from .options import app_options  # noqa: E402

app = typer.Typer(
    name="rotoprint",
    help="Print data for rotary 3D printers and DLP projectors.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # plain help: no markup, no emoji codes (an 'A:B:STEP' is not ':b:')
)
app.callback()(app_options)


def _register() -> None:
    from . import info, slice as slice_cmd

    app.command("info")(info.info)
    app.command("slice")(slice_cmd.slice_command)
    from . import demo

    app.command("demo")(demo.demo)
    from . import check as check_cmd, dlp, head, simulate, transform

    app.command("dlp")(dlp.dlp_command)
    app.command("head")(head.head_command)
    app.command("transform")(transform.transform_command)
    app.command("simulate")(simulate.simulate_command)
    app.command("check")(check_cmd.check_command)
    from . import build as build_cmd

    app.command("build")(build_cmd.build_command)
    from . import replay

    app.command("replay")(replay.replay_command)


_register()


_log_warning = log_warning  # the name it had here


def main(argv: list[str] | None = None) -> int:
    """Entry point: runs the app; a RotoprintError becomes one line on stderr and exit 2.

    Python warnings raised while the command runs are logged at INFO level instead of being
    printed as stray lines on stderr. ``rotoprint dlp`` is read by its fast entry
    (:mod:`rotoprint.cli._fast`) when it can be, else by the typer app.
    """
    from ._fast import try_dlp

    with warnings.catch_warnings():  # the filters in force stay (under pytest: warnings are errors)
        warnings.showwarning = _log_warning
        code = try_dlp(sys.argv[1:] if argv is None else list(argv))
        return _run(argv) if code is None else code


def _run(argv: list[str] | None) -> int:
    from .. import _jitnotice

    _jitnotice.install(console)  # a first run's jit compiles show a progress line
    try:
        return _run_app(argv)
    finally:
        _jitnotice.finish(console)


def _run_app(argv: list[str] | None) -> int:
    try:
        result = app(args=argv, prog_name="rotoprint", standalone_mode=False)
        if isinstance(result, int) and not isinstance(result, bool):  # typer.Exit(code) lands here
            return result
    except (RotoprintError, OSError) as exc:  # OSError: a file system refusal we did not foresee
        console.print(styled(("rotoprint: error:", "red"), f" {error_line(exc)}"), soft_wrap=True)
        return EXIT_BAD_INPUT
    except typer.Exit as exc:
        return int(exc.exit_code or 0)
    except typer.Abort:
        console.print("rotoprint: aborted")
        return 130
    except typer.TyperException as exc:  # usage errors carry their own exit code (2)
        show = getattr(exc, "show", None)
        if type(exc).__name__ == "NoArgsIsHelpError" and show is not None:
            show()  # a bare command: its help, as asked
        else:  # anything else that could not be parsed: one line, like every other error
            fmt = getattr(exc, "format_message", None)
            msg = " ".join((fmt() if fmt is not None else str(exc)).split())
            ctx = getattr(exc, "ctx", None)
            cmd = getattr(ctx, "command_path", "") or "rotoprint"
            console.print(styled(("rotoprint: error:", "red"), f" {cmd}: {msg}"), soft_wrap=True)
        return int(getattr(exc, "exit_code", EXIT_BAD_INPUT))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
