"""Options and helpers shared by the subcommands. Only the CLI prints and exits."""

from __future__ import annotations

import json
from dataclasses import dataclass
import math
import logging
import sys
import unicodedata
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.text import Text

from .. import ranges as R
from ..errors import ConfigError
from ..ranges import check_direction, check_range

def escape_controls(text: str, *, keep_newlines: bool = False) -> str:
    """``text`` with control characters shown, not sent: ESC as ``\\x1b``, DEL, C1 controls,
    bidirectional and other format characters (U+202E ...) and lone surrogates (bytes of a
    file name that are not UTF-8) as ``\\xNN`` / ``\\uNNNN``; a backslash stays as it is.

    File names and other user strings reach the terminal through this, so a name holding
    ``\\e[2J`` cannot clear the screen. ``keep_newlines`` keeps ``\\n`` and ``\\t`` (multi-line
    reports); errors are one line, so there they are escaped too.
    """
    if text.isprintable():
        return text
    out = []
    for ch in text:
        if ch.isprintable() or (keep_newlines and ch in "\n\t"):
            out.append(ch)
        elif unicodedata.category(ch) == "Zs":  # a non-breaking or other space: harmless
            out.append(ch)
        else:
            o = ord(ch)
            out.append(f"\\x{o:02x}" if o < 0x100 else f"\\u{o:04x}" if o < 0x10000 else f"\\U{o:08x}")
    return "".join(out)


class _SafeConsole(Console):
    """A Console whose strings have their control characters escaped (see :func:`escape_controls`);
    rich's own styling codes are added after, so colours still work."""

    def render_str(self, text: str, **kwargs: Any) -> Text:
        return super().render_str(escape_controls(text, keep_newlines=True), **kwargs)


# No markup and no emoji codes: paths and option values are printed as they are (a "[" or
# ":b:" in a file name must not be read as rich markup). Styles go through rich.text.Text.
console = _SafeConsole(stderr=True, highlight=False, markup=False, emoji=False)
out_console = _SafeConsole(highlight=False, markup=False, emoji=False)

EXIT_BAD_INPUT = 2

DeviceOpt = Annotated[str, typer.Option("--device", "-d", help="Preset name (omnidot760, perfactory-sxga) or a device .toml file.")]


def in_range(rng: R.Range):
    """A typer option callback: the value checked against ``rng`` as it is parsed, the error
    naming the option (``--min-wall must be in (0, 100] mm, got 1e+19``)."""

    def _check(param: typer.CallbackParam, value):
        if value is None:
            return None
        return check_range(value, rng, _opt_name(param))

    return _check


def direction_cb(param: typer.CallbackParam, value):
    """Option callback: +1 or -1."""
    return None if value is None else check_direction(value, _opt_name(param))


def scale_cb(param: typer.CallbackParam, value):
    """Option callback: a uniform scale whose magnitude is in :data:`rotoprint.ranges.SCALE`
    (negative mirrors)."""
    if value is None:
        return None
    name = _opt_name(param)
    if not (isinstance(value, float) and math.isfinite(value) and abs(value) in R.SCALE):
        raise ConfigError(f"{name} must be a number whose size is {R.SCALE.text()}, got {value:g}")
    return value


def _opt_name(param) -> str:
    opts = [o for o in getattr(param, "opts", []) if o.startswith("--")]
    return opts[0] if opts else str(getattr(param, "name", "option"))


LayerHeightOpt = Annotated[float, typer.Option("--layer-height", help="Layer height, mm.", callback=in_range(R.LAYER_HEIGHT_MM))]
UnitsOpt = Annotated[str, typer.Option("--units", help="Units of the mesh file: mm, cm, m, um, inch.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print the result as JSON on stdout.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Replace an existing output even if it is not provably an earlier rotoprint output.")]


def device_input(device: str) -> Path | None:
    """The device file named by ``--device`` (None for a preset name): an input the output must not replace."""
    p = Path(device)
    return p if p.suffix.lower() == ".toml" or p.exists() else None


def parse_triple(text: str | None, name: str, default: tuple[float, float, float], rng: R.Range | None = None) -> tuple[float, float, float]:
    """'X,Y,Z' into three floats (each in ``rng`` if given), or a ConfigError naming the option."""
    if text is None:
        return default
    try:
        vals = tuple(float(t) for t in text.split(","))
    except ValueError:
        raise ConfigError(f"{name} must be three numbers 'X,Y,Z', got {text!r}") from None
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise ConfigError(f"{name} must be three finite numbers 'X,Y,Z', got {text!r}")
    if rng is not None:
        for axis, v in zip("XYZ", vals):
            check_range(v, rng, f"{name} {axis}")
    return vals  # type: ignore[return-value]


def parse_pair(text: str | None, name: str, rng: R.Range | None = R.COORD_MM) -> tuple[float, float]:
    """'X,Y' into two floats (each in ``rng``), or a ConfigError naming the option."""
    if text is None:
        return (0.0, 0.0)
    try:
        vals = tuple(float(t) for t in text.split(","))
    except ValueError:
        raise ConfigError(f"{name} must be two numbers 'X,Y', got {text!r}") from None
    if len(vals) != 2 or not all(math.isfinite(v) for v in vals):
        raise ConfigError(f"{name} must be two finite numbers 'X,Y', got {text!r}")
    if rng is not None:
        for axis, v in zip("XY", vals):
            check_range(v, rng, f"{name} {axis}")
    return vals  # type: ignore[return-value]


def print_json(data: Any) -> None:
    sys.stdout.write(json.dumps(data, indent=2, sort_keys=False) + "\n")


@dataclass
class _AppFlags:
    """The app-level ``--quiet`` / ``--verbose`` (set by :func:`rotoprint.cli.options.app_options`)."""

    quiet: bool = False
    verbose: bool = False


_FLAGS = _AppFlags()


def is_quiet(quiet: bool = False) -> bool:
    """The command's ``--quiet`` or the app's."""
    return bool(quiet) or _FLAGS.quiet


def is_verbose(verbose: bool = False) -> bool:
    """The command's ``--verbose`` or the app's."""
    return bool(verbose) or _FLAGS.verbose


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


class _SafeFormatter(logging.Formatter):
    """Log lines with control characters escaped (they hold file names)."""

    def format(self, record: logging.LogRecord) -> str:
        return escape_controls(super().format(record), keep_newlines=True)


def setup_logging(verbose: bool) -> None:
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")
    for h in logging.getLogger().handlers:
        if isinstance(h, logging.StreamHandler) and type(h.formatter) is logging.Formatter:
            h.setFormatter(_SafeFormatter(h.formatter._fmt))


def load_mesh_from_options(path: Path, units: str, scale: float, rotate: str | None, translate: str | None,
                           fill_holes: bool = True):
    from ..io.mesh import load_mesh, make_transform

    T = make_transform(
        translate_mm=parse_triple(translate, "--translate", (0.0, 0.0, 0.0), R.COORD_MM),
        rotate_deg=parse_triple(rotate, "--rotate", (0.0, 0.0, 0.0), R.ANGLE_DEG),
        scale=scale,
    )
    return load_mesh(path, units=units, transform=T, fill_holes=fill_holes)


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
    size of ``data`` (``bounds_mm``, ``size_mm``) after the first two ``rows`` entries, the
    other rows after them; printed whole (:func:`print_table`)."""
    from rich.table import Table

    t = Table(title=title, show_header=False)
    t.add_column("quantity", style="bold")
    t.add_column("value")
    b = data["bounds_mm"]
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
        con.print(table)
        return
    if table.title:
        con.print(table.title)  # wrapped at words, never cut
    heads = [" ".join(str(c.header).split()) or f"column {i + 1}" for i, c in enumerate(table.columns)]
    cols = [[str(v) for v in c.cells] for c in table.columns]
    show = table.show_header
    for r in range(table.row_count):
        lines = []
        for h, cells in zip(heads, cols):
            v = " ".join(cells[r].split()) if r < len(cells) else ""
            lines.append(f"  {h}: {v}" if show else f"  {v}")
        con.print(("" if r == 0 else "\n") + "\n".join(lines))
