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

from .. import ranges as R
from ..errors import ConfigError
from ..ranges import check_direction, check_range

# No markup and no emoji codes: paths and option values are printed as they are (a "[" or
# ":b:" in a file name must not be read as rich markup). Styles go through rich.text.Text.
console = Console(stderr=True, highlight=False, markup=False, emoji=False)
out_console = Console(highlight=False, markup=False, emoji=False)

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
    """A line of plain pieces and ``(text, style)`` pieces; nothing in it is read as markup."""
    return Text.assemble(*parts)
