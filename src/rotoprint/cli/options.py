"""The options several subcommands share, each defined once with one help text (as
rasterio's ``rio/options.py``). A command declares ``quiet: QuietOpt = False`` and so on;
``--verbose`` and ``--quiet`` also exist on the app itself (``rotoprint -v slice ...``), for
every command: :func:`app_options` and :func:`is_quiet`/:func:`is_verbose` combine the two.

Help texts are plain: the help is printed without rich markup or emoji codes (an ``A:B:STEP``
is not read as ``:b:``)."""

from __future__ import annotations

from typing import Annotated

import typer

from .. import ranges as R
from ..constants import DEFAULT_GAP_RADIUS_MM
from ._common import _FLAGS, in_range, is_quiet, is_verbose

__all__ = [
    "QuietOpt", "VerboseOpt", "WorkersOpt", "SchedulerOpt", "ResumeOpt", "FillOpt", "GapRadiusOpt", "OffsetOpt",
    "DpiYOpt", "FibreAngleOpt", "DEFAULT_GAP_RADIUS_MM", "app_options", "is_quiet", "is_verbose",
]

QUIET_HELP = "No progress bar or summary."
VERBOSE_HELP = "Log what happens (resume, workers, estimates, library warnings) on stderr."

QuietOpt = Annotated[bool, typer.Option("--quiet", "-q", help=QUIET_HELP)]
VerboseOpt = Annotated[bool, typer.Option("--verbose", "-v", help=VERBOSE_HELP)]
WorkersOpt = Annotated[int, typer.Option("--workers", "-j", help="Layers in parallel in this many processes.", callback=in_range(R.WORKERS))]
SchedulerOpt = Annotated[str | None, typer.Option("--scheduler", help="Address of a Dask distributed scheduler to run the layers on (rotoprint[dask]).")]
ResumeOpt = Annotated[bool, typer.Option("--resume", help="Continue an interrupted run: keep the layers it verified, make the rest.")]
FillOpt = Annotated[str, typer.Option("--fill", help="Fill rule: nonzero (overlapping shells union) or evenodd.")]
GapRadiusOpt = Annotated[float, typer.Option("--gap-radius", help="Open meshes: join open ends of a section closer than this, mm.", callback=in_range(R.GAP_RADIUS_MM))]
OffsetOpt = Annotated[str | None, typer.Option("--offset", help="'X,Y' mm: the part's centre relative to the field centre.")]
DpiYOpt = Annotated[float | None, typer.Option("--dpi-y", help="Inkjet: drops per inch along the print direction (circumferential, at the reference radius); default the head's.", callback=in_range(R.DPI))]
FibreAngleOpt = Annotated[float | None, typer.Option("--fibre-angle", help="Fibre direction in the model's XY plane, degrees from +X (DLP: the model direction put along image rows). Default: the device's own direction.", callback=in_range(R.ANGLE_DEG))]


def app_options(
    verbose: VerboseOpt = False,
    quiet: QuietOpt = False,
) -> None:
    """Print data for rotary 3D printers and DLP projectors."""
    from ._common import setup_logging

    _FLAGS.quiet, _FLAGS.verbose = bool(quiet), bool(verbose)
    if verbose:
        setup_logging(True)
