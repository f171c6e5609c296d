"""Options and helpers shared by the subcommands. Only the CLI prints and exits."""

from __future__ import annotations

import json
import sys
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.text import Text

from .. import ranges as R
from ..ranges import check_direction, check_range

# The typer- and rich-free helpers live in ._base (the fast `rotoprint dlp` entry uses them
# without importing typer); they are re-exported here for the commands.
from ._base import (  # noqa: F401
    EXIT_BAD_INPUT,
    _FLAGS,
    _AppFlags,
    _SafeFormatter,
    check_scale,
    device_input,
    escape_controls,
    is_quiet,
    is_verbose,
    load_mesh_from_options,
    parse_pair,
    parse_triple,
    setup_logging,
)
from ._console import _SafeConsole, console, out_console  # noqa: F401

DeviceOpt = Annotated[str, typer.Option("--device", "-d", help="Preset name (omnidot760, perfactory-sxga) or a device .toml file.")]


def in_range(rng: R.Range):
    """A typer option callback: the value checked against ``rng`` as it is parsed, the error
    naming the option (``--min-wall must be in (0, 100] mm, got 1e+19``)."""

    def _check(param: typer.CallbackParam, value):
        if value is None:
            return None
        return check_range(value, rng, _opt_name(param))

    _check.range = rng  # read by the fast dlp entry's tests (tests/test_fast_dlp.py)
    return _check


def direction_cb(param: typer.CallbackParam, value):
    """Option callback: +1 or -1."""
    return None if value is None else check_direction(value, _opt_name(param))


def scale_cb(param: typer.CallbackParam, value):
    """Option callback: a uniform scale whose magnitude is in :data:`rotoprint.ranges.SCALE`
    (negative mirrors)."""
    return None if value is None else check_scale(value, _opt_name(param))


def _opt_name(param) -> str:
    opts = [o for o in getattr(param, "opts", []) if o.startswith("--")]
    return opts[0] if opts else str(getattr(param, "name", "option"))


LayerHeightOpt = Annotated[float, typer.Option("--layer-height", help="Layer height, mm.", callback=in_range(R.LAYER_HEIGHT_MM))]
UnitsOpt = Annotated[str, typer.Option("--units", help="Units of the mesh file: mm, cm, m, um, inch.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print the result as JSON on stdout.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Replace an existing output even if it is not provably an earlier rotoprint output.")]


def print_json(data: Any) -> None:
    sys.stdout.write(json.dumps(data, indent=2, sort_keys=False) + "\n")


def progress(quiet: bool = False):
    """A rich ``Progress`` bar on the console (disabled when quiet or not a terminal); rich's
    progress module is imported here, not by every command's start-up."""
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=console,
        disable=is_quiet(quiet) or not console.is_terminal,
        transient=True,
    )


ScaleOpt = Annotated[float, typer.Option("--scale", help="Uniform scale applied after unit conversion (size 1e-6 to 1e6; negative mirrors).", callback=scale_cb)]
RotateOpt = Annotated[str | None, typer.Option("--rotate", help="Rotation 'X,Y,Z' in degrees (applied X, then Y, then Z).")]
FillHolesOpt = Annotated[bool, typer.Option("--fill-holes/--no-fill-holes", help="Fill the mesh's holes (closed loops of open edges) before slicing; open sheets stay open.")]
TranslateOpt = Annotated[str | None, typer.Option("--translate", help="Translation 'X,Y,Z' in mm, applied last.")]


def styled(*parts: str | tuple[str, str]) -> Text:
    """One line of plain pieces and ``(text, style)`` pieces; nothing in it is read as markup,
    and control characters (newlines too) are escaped (:func:`escape_controls`)."""
    return Text.assemble(*(escape_controls(p) if isinstance(p, str) else (escape_controls(p[0]), p[1]) for p in parts))


def print_quantities(title: str, data: dict, rows: list[tuple[str, str]]) -> None:
    """`rotoprint info`'s table (meshes and CAD layers): ``quantity | value``, the bounds and
    size of ``data`` (``bounds_mm``, ``size_mm``; None for an empty layer, shown as '-') after the first two ``rows`` entries, the
    other rows after them; printed whole (:func:`print_table`)."""
    from rich.table import Table

    t = Table(title=title, show_header=False)
    t.add_column("quantity", style="bold")
    t.add_column("value")
    b = data["bounds_mm"]
    if b is None:  # an empty layer: nothing to bound
        bounds = [("bounds min (mm)", "-"), ("bounds max (mm)", "-"), ("size (mm)", "- (empty layer)")]
    else:
        bounds = [("bounds min (mm)", ", ".join(f"{v:.4f}" for v in b["min"])),
                  ("bounds max (mm)", ", ".join(f"{v:.4f}" for v in b["max"])),
                  ("size (mm)", " x ".join(f"{v:.4f}" for v in data["size_mm"]))]
    for k, v in [*rows[:2], *bounds, *rows[2:]]:
        t.add_row(k, v)
    print_table(t)


def print_table(table, con: Console | None = None) -> None:
    """Print a rich ``Table`` whole: as a table when its natural width fits the console (a
    pipe is 80 columns), else as one block per row, ``column: value`` a line, so that no
    figure is cut to an ellipsis."""
    from rich.measure import Measurement

    con = out_console if con is None else con
    need = Measurement.get(con, con.options.update_width(1_000_000), table).maximum
    if need <= con.width:
        con.print(table, soft_wrap=False)  # laid out in its columns (it fits)
        return
    if table.title:
        con.print(table.title, soft_wrap=False)  # wrapped at words, never cut
    heads = [" ".join(str(c.header).split()) or f"column {i + 1}" for i, c in enumerate(table.columns)]
    cols = [[str(v) for v in c.cells] for c in table.columns]
    show = table.show_header
    for r in range(table.row_count):
        lines = []
        for h, cells in zip(heads, cols):
            v = " ".join(cells[r].split()) if r < len(cells) else ""
            lines.append(f"  {h}: {v}" if show else f"  {v}")
        con.print(("" if r == 0 else "\n") + "\n".join(lines))
