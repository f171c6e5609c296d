"""The parts of the command-line layer that need neither typer nor rich: control-character
escaping, the app-level flags, option-value parsing, logging set-up and mesh loading. The
typer commands (through :mod:`._common`, which re-exports all of this) and the fast entry of
``rotoprint dlp`` (:mod:`._fast`) share them, so both read options and print the same."""

from __future__ import annotations

import logging
import math
import unicodedata
from pathlib import Path

from .._dataclass import dataclass
from .. import ranges as R
from ..errors import ConfigError
from ..ranges import check_range

EXIT_BAD_INPUT = 2


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


def check_scale(value, name: str):
    """A uniform scale whose magnitude is in :data:`rotoprint.ranges.SCALE` (negative mirrors),
    or a ConfigError naming the option."""
    if not (isinstance(value, float) and math.isfinite(value) and abs(value) in R.SCALE):
        raise ConfigError(f"{name} must be a number whose size is {R.SCALE.text()}, got {value:g}")
    return value


def device_input(device: str) -> Path | None:
    """The device file named by ``--device`` (None for a preset name): an input the output must not replace."""
    p = Path(device)
    return p if p.suffix.lower() == ".toml" or p.exists() else None


_COUNT_WORDS = {2: "two", 3: "three"}


def _parse_numbers(text: str, name: str, axes: str, rng: R.Range | None) -> tuple[float, ...]:
    """Comma-separated numbers, one per letter of ``axes`` (each in ``rng`` if given), or a
    ConfigError naming the option."""
    word, form = _COUNT_WORDS[len(axes)], ",".join(axes)
    try:
        vals = tuple(float(t) for t in text.split(","))
    except ValueError:
        raise ConfigError(f"{name} must be {word} numbers '{form}', got {text!r}") from None
    if len(vals) != len(axes) or not all(math.isfinite(v) for v in vals):
        raise ConfigError(f"{name} must be {word} finite numbers '{form}', got {text!r}")
    if rng is not None:
        for axis, v in zip(axes, vals):
            check_range(v, rng, f"{name} {axis}")
    return vals


def parse_triple(text: str | None, name: str, default: tuple[float, float, float], rng: R.Range | None = None) -> tuple[float, float, float]:
    """'X,Y,Z' into three floats (each in ``rng`` if given), or a ConfigError naming the option."""
    return default if text is None else _parse_numbers(text, name, "XYZ", rng)  # type: ignore[return-value]


def parse_pair(text: str | None, name: str, rng: R.Range | None = R.COORD_MM) -> tuple[float, float]:
    """'X,Y' into two floats (each in ``rng``), or a ConfigError naming the option."""
    return (0.0, 0.0) if text is None else _parse_numbers(text, name, "XY", rng)  # type: ignore[return-value]


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


def error_line(exc: BaseException) -> str:
    """What follows ``rotoprint: error:`` for a RotoprintError or an unforeseen OSError (a file
    system refusal): one line, naming the file when there is one."""
    if isinstance(exc, OSError):
        where = exc.filename if exc.filename is not None else ""
        what = exc.strerror or str(exc)
        return f"{where}: {what}" if where else f"{what}"
    return f"{exc}"


def log_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Library warnings (matplotlib, numpy, ...) go to the log (seen with --verbose), not stderr."""
    logging.getLogger("rotoprint.warnings").info("%s: %s (%s:%d)", category.__name__, message, filename, lineno)
