"""Matplotlib figures for the build report, returned as PNG bytes (Agg, no display)."""

from __future__ import annotations

import io
import math

import numpy as np

from ..rotary.head import Mount, nozzle_layout

__all__ = ["figure_png", "thickness_figure", "density_figure", "head_geometry_figure", "time_figure"]


def figure_png(fig) -> bytes:
    """PNG bytes of a ``matplotlib.figure.Figure`` (100 dpi)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def _fig(w=7.0, h=3.6):
    from matplotlib.figure import Figure

    return Figure(figsize=(w, h), layout="constrained")


def thickness_figure(plan, colours) -> bytes:
    """Thickness per layer against radius for every material (left) and per cycle (right)."""
    fig = _fig(10, 3.8)
    a, b = fig.subplots(1, 2)
    lh = plan.job.spec.job.layer_height_mm * 1000
    for name, est in plan.estimates.items():
        c = np.asarray(colours[name]) / 255
        a.plot(est.profile_r_mm, est.profile_per_layer_um, color=c, lw=2, label=f"{name} ({est.cycles} cycles)")
        b.plot(est.profile_r_mm, est.profile_per_layer_um / est.cycles * 1000, color=c, lw=2, label=name)
    a.axhline(lh, color="k", ls=":", lw=1, label=f"layer height {lh:g} um")
    a.set_xlabel("radius on the platform (mm)")
    a.set_ylabel("thickness per layer (um)")
    a.set_yscale("log")
    a.set_title("planned thickness per layer")
    a.legend(fontsize=7)
    b.set_xlabel("radius on the platform (mm)")
    b.set_ylabel("solid per cycle (nm)")
    b.set_yscale("log")
    b.set_title("one cycle of each material")
    b.legend(fontsize=7)
    return figure_png(fig)


def density_figure(plan) -> bytes:
    """Drops per mm^2 against radius for each head, with and without equalisation."""
    from ..process.estimates import track_density_per_mm2

    fig = _fig(10, 3.6)
    ax = fig.subplots()
    for h in plan.heads:
        r, d0 = track_density_per_mm2(h.lattice.tracks, equalised=False)
        ax.plot(r, d0, lw=1, alpha=0.7, label=f"{h.name} ({h.ink}), one clock: 1/r")
        if plan.job.spec.printer.equalise:
            ax.plot(h.r_mm, h.density_per_mm2, lw=2, ls="--", label=f"{h.name} equalised")
    ax.set_xlabel("radius on the platform (mm)")
    ax.set_ylabel("drops per mm$^2$")
    ax.set_title("drop density over the tracks (the r_ref / r law of one angular clock)")
    ax.legend(fontsize=6, ncol=2)
    return figure_png(fig)


def head_geometry_figure(plan, colours) -> bytes:
    """Top view of the platform: the assembly's footprint and every head's nozzles (each
    swathe's pivot) at its mount angle and tilt."""
    fig = _fig(7, 7)
    ax = fig.subplots()
    part = plan.placement
    x0, y0, x1, y1 = part.footprint_mm
    corners = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])
    px, py = part.model_to_platform(corners[:, 0], corners[:, 1])
    ax.fill(px, py, color=(0.85, 0.8, 0.7), alpha=0.8, label="assembly footprint")
    rmax = 0.0
    for h in plan.heads:
        head = plan.device.head
        for j, sw in enumerate(h.lattice.plan.swathes):
            lay = nozzle_layout(head, Mount(sw.pivot_radius_mm, tilt_deg=h.tilt_deg, mount_angle_deg=h.mount_angle_deg,
                                            direction=plan.job.spec.printer.direction))
            xy = lay.xy_mm
            ax.plot(xy[::8, 0], xy[::8, 1], ".", ms=1.5, label=f"{h.name} ({h.ink})" if j == 0 else None)
            rmax = max(rmax, float(lay.r_mm.max()))
    t = np.linspace(0, 2 * math.pi, 360)
    ax.plot(rmax * 1.05 * np.cos(t), rmax * 1.05 * np.sin(t), color="grey", lw=0.8)
    ax.plot([0], [0], "k+", ms=10)
    ax.set_aspect("equal")
    ax.set_xlabel("platform x (mm)")
    ax.set_ylabel("platform y (mm)")
    ax.set_title(f"heads over the platform (tilt {plan.heads[0].tilt_deg:g} deg), axis at +")
    ax.legend(fontsize=6, loc="upper left", markerscale=6)
    return figure_png(fig)


def time_figure(layers_json: list[dict]) -> bytes:
    """Estimated printing time per layer."""
    fig = _fig(10, 2.6)
    ax = fig.subplots()
    t = [L["time_s"] / 60 for L in layers_json]
    ax.bar(range(len(t)), t, color="tab:blue")
    ax.set_xlabel("layer")
    ax.set_ylabel("minutes")
    ax.set_title(f"estimated time per layer (total {sum(t) / 60:.1f} h)")
    return figure_png(fig)
