"""Options and helpers shared by the subcommands. Only the CLI prints and exits."""

from __future__ import annotations

import json
import math
import logging
import sys
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.console import Console
from rich.text import Text
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from ..errors import ConfigError

# No markup and no emoji codes: paths and option values are printed as they are (a "[" or
# ":b:" in a file name must not be read as rich markup). Styles go through rich.text.Text.
console = Console(stderr=True, highlight=False, markup=False, emoji=False)
out_console = Console(highlight=False, markup=False, emoji=False)

EXIT_BAD_INPUT = 2

DeviceOpt = Annotated[str, typer.Option("--device", "-d", help="Preset name (omnidot760, perfactory-sxga) or a device .toml file.")]
LayerHeightOpt = Annotated[float, typer.Option("--layer-height", help="Layer height, mm.")]
UnitsOpt = Annotated[str, typer.Option("--units", help="Units of the mesh file: mm, cm, m, um, inch.")]
JsonOpt = Annotated[bool, typer.Option("--json", help="Print the result as JSON on stdout.")]
ForceOpt = Annotated[bool, typer.Option("--force", help="Replace an existing output even if it is not provably an earlier rotoprint output.")]


def device_input(device: str) -> Path | None:
    """The device file named by ``--device`` (None for a preset name): an input the output must not replace."""
    p = Path(device)
    return p if p.suffix.lower() == ".toml" or p.exists() else None


def parse_triple(text: str | None, name: str, default: tuple[float, float, float]) -> tuple[float, float, float]:
    """'X,Y,Z' into three floats, or a ConfigError naming the option."""
    if text is None:
        return default
    try:
        vals = tuple(float(t) for t in text.split(","))
    except ValueError:
        raise ConfigError(f"{name} must be three numbers 'X,Y,Z', got {text!r}") from None
    if len(vals) != 3 or not all(math.isfinite(v) for v in vals):
        raise ConfigError(f"{name} must be three finite numbers 'X,Y,Z', got {text!r}")
    return vals  # type: ignore[return-value]


def parse_pair(text: str | None, name: str) -> tuple[float, float]:
    if text is None:
        return (0.0, 0.0)
    try:
        vals = tuple(float(t) for t in text.split(","))
    except ValueError:
        raise ConfigError(f"{name} must be two numbers 'X,Y', got {text!r}") from None
    if len(vals) != 2 or not all(math.isfinite(v) for v in vals):
        raise ConfigError(f"{name} must be two finite numbers 'X,Y', got {text!r}")
    return vals  # type: ignore[return-value]


def print_json(data: Any) -> None:
    sys.stdout.write(json.dumps(data, indent=2, sort_keys=False) + "\n")


def progress(quiet: bool = False) -> Progress:
    return Progress(
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
        console=console,
        disable=quiet or not console.is_terminal,
        transient=True,
    )


def setup_logging(verbose: bool) -> None:
    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING, format="%(levelname)s %(name)s: %(message)s")


def load_mesh_from_options(path: Path, units: str, scale: float, rotate: str | None, translate: str | None,
                           fill_holes: bool = True):
    from ..io.mesh import load_mesh, make_transform

    T = make_transform(
        translate_mm=parse_triple(translate, "--translate", (0.0, 0.0, 0.0)),
        rotate_deg=parse_triple(rotate, "--rotate", (0.0, 0.0, 0.0)),
        scale=scale,
    )
    return load_mesh(path, units=units, transform=T, fill_holes=fill_holes)


ScaleOpt = Annotated[float, typer.Option("--scale", help="Uniform scale applied after unit conversion.")]
RotateOpt = Annotated[str | None, typer.Option("--rotate", help="Rotation 'X,Y,Z' in degrees (applied X, then Y, then Z).")]
FillHolesOpt = Annotated[bool, typer.Option("--fill-holes/--no-fill-holes", help="Fill the mesh's holes (closed loops of open edges) before slicing; open sheets stay open.")]
TranslateOpt = Annotated[str | None, typer.Option("--translate", help="Translation 'X,Y,Z' in mm, applied last.")]


def styled(*parts: str | tuple[str, str]) -> Text:
    """A line of plain pieces and ``(text, style)`` pieces; nothing in it is read as markup."""
    return Text.assemble(*parts)
