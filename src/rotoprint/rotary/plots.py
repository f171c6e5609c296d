"""The paper's Figure 5 with matplotlib: (a) projected density and swathe, (b) nozzle pitch."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..devices.models import InkjetHead
from ..errors import ConfigError
from ..io.atomic import check_output_path, write_owned_file
from ..errors import RotoprintError
from .head import head_figures, max_tilt_deg, paper_figures

__all__ = ["figure5", "save_figure"]


def figure5(head: InkjetHead, *, pivot_radius_mm: float = 60.0, step_deg: float = 0.5, title: str = ""):
    """A ``matplotlib.figure.Figure`` with the paper's Figure 5 (a) and (b).

    (a) ``dpi_xp`` (eq. 3) and ``ps_p`` (eq. 2) against tilt, with the exact full-density band
    at ``pivot_radius_mm``; (b) the nozzle pitch ``p cos(theta)`` against tilt, with the exact
    largest gap between neighbouring tracks at ``pivot_radius_mm``.

    Parameters
    ----------
    head : InkjetHead
    pivot_radius_mm : float
        Pivot radius of the exact figures.
    step_deg : float
        Tilt step of the closed-form curves, from 0 up to :func:`~rotoprint.rotary.head.max_tilt_deg`;
        the exact figures are drawn about every 2 degrees and stop at the first tilt that
        has none.
    title : str
        Figure title; none when empty.

    Returns
    -------
    matplotlib.figure.Figure
        Not attached to pyplot; save it with :func:`save_figure`.
    """
    from matplotlib.figure import Figure

    tmax = max_tilt_deg(head)
    tilts = np.arange(0.0, tmax, step_deg)
    pap = [paper_figures(head, t, pivot_radius_mm=pivot_radius_mm, check=False) for t in tilts]
    ex_tilts = tilts[:: max(1, int(round(2.0 / step_deg)))]
    ex = []
    for t in ex_tilts:
        try:
            ex.append(head_figures(head, tilt_deg=float(t), pivot_radius_mm=pivot_radius_mm))
        except RotoprintError:  # a tilt near the maximum may leave no band; stop there
            break
    ex_t = ex_tilts[: len(ex)]
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    ax_a, ax_b = fig.subplots(1, 2)
    ax_a.plot(tilts, [f["dpi_xp"] for f in pap], color="tab:blue", label="dpi_xp, eq. (3)")
    ax_a.set_xlabel("print head tilt (deg)")
    ax_a.set_ylabel("projected print density dpi_xp (dpi)", color="tab:blue")
    ax_a.set_ylim(0, min(6000, max(f["dpi_xp"] for f in pap)))
    ax2 = ax_a.twinx()
    ax2.plot(tilts, [f["ps_p_mm"] for f in pap], color="tab:red", label="ps_p, eq. (2)")
    ax2.plot(ex_t, [e.overlap_band_mm[1] - e.overlap_band_mm[0] for e in ex], "o", ms=3, color="tab:red", alpha=0.6,
             label=f"exact band at cx = {pivot_radius_mm:g} mm")
    ax2.set_ylabel("projected print swathe ps_p (mm)", color="tab:red")
    ax2.set_ylim(0, head.swathe_mm * 1.05)
    ax2.axvline(tmax, color="grey", ls=":", lw=1)
    ax2.annotate(f"max tilt {tmax:.1f} deg", (tmax, head.swathe_mm * 0.9), ha="right", fontsize=8)
    ax2.legend(loc="center left", fontsize=8)
    ax_a.set_title("(a) projected density and swathe")
    ax_b.plot(tilts, [f["pitch_radial_mm"] * 1000 for f in pap], color="tab:green", label="p cos(tilt)")
    ax_b.plot(ex_t, [e.largest_track_gap_mm * 1000 for e in ex], "o-", ms=3, color="tab:orange",
              label=f"exact largest track gap at cx = {pivot_radius_mm:g} mm")
    ax_b.set_xlabel("print head tilt (deg)")
    ax_b.set_ylabel("radial nozzle pitch (um)")
    ax_b.set_ylim(0, None)
    ax_b.legend(fontsize=8)
    ax_b.set_title("(b) nozzle pitch")
    if title:
        fig.suptitle(title)
    return fig


def save_figure(fig, path: str | Path, *, force: bool = False, inputs=()) -> None:
    """Save a figure atomically; the format follows the suffix (png, svg, pdf).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        Rendered at 150 dpi.
    path : str or Path
        Written with our marker (PNG, SVG); an existing file there is replaced only if it is
        ours (a PDF never is) or with ``force``.
    force : bool
    inputs : iterable of path
        Files the run read: ``path`` must not be one.

    Raises
    ------
    ConfigError
        The suffix is not ``.png``, ``.svg`` or ``.pdf``.
    InputFileError
        The folder of ``path`` does not exist, ``path`` is an input, or it exists and is not
        provably ours (without ``force``).
    """
    path = Path(path)
    fmt = path.suffix.lower().lstrip(".")
    if fmt not in ("png", "svg", "pdf"):
        raise ConfigError(f"plot file must end in .png, .svg or .pdf, got {path.name!r}")
    check_output_path(path, is_dir=False, inputs=inputs, force=force)
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=150)
    write_owned_file(path, buf.getvalue(), kind="figure", inputs=inputs, force=force)
