"""The paper's two-step transform (``rotary-geometry.md`` section 6), kept to compare against.

Step 1, polar: an image ``P`` of ``sv x su`` pixels, column ``u`` at radius
``cx_T + u * p cos(theta)`` (eqs (1), (3)), row ``v`` at angle ``(c - v) * dphi``, sampled
from the design (nearest; a gather, so the holes a pixel-by-pixel push would leave are not
counted against the paper). Step 2, linear: nozzle ``k`` prints column ``u_k`` (its radial
projection on the centre line), shifted in ``v`` by a whole number of pixels that runs linearly
along its row from ``coff_0`` to ``coff_1`` (eqs (4)-(6)).

Reading of the paper where it is ambiguous: ``sx sin(theta)`` is the cross-head offset of
the row's last nozzle, so ``sx`` is the row's along-head length in pixels of ``25.4/dpi_y``;
the parallax term uses the row's radial projection ``sx cos(theta)``; ``cx_T + px_T`` is the
first track of the swathe. Swathes, clock and placement are the exact method's, so only the
geometric model differs.
"""

from __future__ import annotations

import math

import numpy as np

from ..devices.models import InkjetHead
from .._resources import check_raster_fits
from ..ranges import check_count
from ..errors import ConfigError
from .exact import _check_design
from .head import nozzle_layout, nozzle_offsets
from .placement import Placement
from .printdata import RotaryPrint, SwatheImage, clock_dphi, design_kind, design_levels
from .swathes import plan_swathes

__all__ = ["paper_shifts", "transform_paper"]


def paper_shifts(head: InkjetHead, *, tilt_deg: float, cx_T_mm: float, pitch_y_mm: float) -> np.ndarray:
    """Linear-transform shift ``coff_k`` of every nozzle, in pixels of ``pitch_y_mm``, ``(N,) float64``.

    Row ``q`` runs from ``coff_0 = (t_q / p_y) cos(theta)`` at its first nozzle to
    ``coff_1 = sx sin(theta) + coff_0 - (t_q / p_y) tan(delta)``-style parallax, eqs (4)-(6)
    with ``t_q = -/+ d_nzr / 2`` for rows A and B.

    Parameters
    ----------
    head : InkjetHead
    tilt_deg : float
        ``theta``, signed.
    cx_T_mm : float
        The paper's ``cx_T`` (see :func:`~rotoprint.rotary.head.paper_figures`); used only in
        the parallax term.
    pitch_y_mm : float
        Design pixel pitch the shifts are expressed in.

    Returns
    -------
    (N,) float64 ndarray
        Shift of every nozzle, pixels; linear along each row from ``coff_0`` to ``coff_1``.

    Examples
    --------
    >>> from rotoprint import load_device
    >>> head = load_device("omnidot760").head
    >>> c = paper_shifts(head, tilt_deg=0.0, cx_T_mm=60.0, pitch_y_mm=25.4 / 360)
    >>> round(float(c[0]), 3), round(float(c[1]), 3)   # -/+ nzt_off / 2 = d_nzr / (2 p_y)
    (-30.0, 30.0)
    """
    th = math.radians(tilt_deg)
    s, t, row = nozzle_offsets(head)
    out = np.empty(head.nozzles)
    for q in range(head.rows):
        m = row == q
        sq = s[m]
        tq = float(t[m][0])
        La = float(sq.max() - sq.min())
        Lr = La * math.cos(th)
        coff0 = (tq / pitch_y_mm) * math.cos(th)
        par = (-tq / pitch_y_mm) * Lr / (cx_T_mm + Lr)  # sx tan(delta_par), eq (6), signed by row
        coff1 = (La / pitch_y_mm) * math.sin(th) + coff0 + par
        f = (sq - sq.min()) / La if La > 0 else np.zeros_like(sq)
        out[m] = coff0 + f * (coff1 - coff0)
    return out


def transform_paper(
    design: np.ndarray,
    head: InkjetHead,
    placement: Placement,
    *,
    tilt_deg: float,
    dpi_y: float | None = None,
    ref_radius_mm: float | None = None,
    mount_angle_deg: float = 0.0,
    direction: int = 1,
    max_swathes: int | None = None,
    kind: str | None = None,
) -> RotaryPrint:
    """The paper's polar + linear transform; same inputs and output as :func:`transform_exact`.

    Only tilts >= 0 (the paper's sign convention).

    Parameters
    ----------
    design : (H, W) uint8
        Non-zero = ink; ``H x W`` must be the placement's size.
    head : InkjetHead
    placement : Placement
        Where the design lies on the platform (pitches in mm, inner radius, angle).
    tilt_deg : float
        Head tilt, degrees, ``0 <= tilt_deg`` below the head's maximum.
    dpi_y : float, optional
        Drops per inch along the track at the reference radius (default: the head's).
    ref_radius_mm : float, optional
        Reference radius of the clock, mm (default: each swathe's first column, as the paper).
    mount_angle_deg : float
        Angle of the head's radial line, degrees.
    direction : {1, -1}
        +1 counter-clockwise platform, -1 clockwise.
    max_swathes : int, optional
        Refuse a design needing more swathes.
    kind : {"binary", "grey"}, optional
        Default: ``"binary"`` when the design holds one non-zero value.

    Returns
    -------
    RotaryPrint
        One ``(F_j, N) uint8`` level image per swathe (``N = head.nozzles``) with its first
        firing index, angle per firing (``dphi_rad``) and pivot radius.

    Raises
    ------
    ConfigError
        A negative tilt, a design of the wrong size or dtype.
    GeometryError
        A tilt at or beyond the head's maximum, nozzles over the axis, too many swathes.
    """
    if tilt_deg < 0:
        raise ConfigError(f"the paper method takes tilts >= 0 (its sign convention), got {tilt_deg}; use --method exact")
    design = _check_design(design, placement)
    kind = kind or design_kind(design)
    dpi_y = float(head.dpi_y if dpi_y is None else dpi_y)
    r_in, r_out = placement.radial_range_mm()
    plan = plan_swathes(head, tilt_deg=tilt_deg, inner_radius_mm=r_in, outer_radius_mm=r_out,
                        mount_angle_deg=mount_angle_deg, direction=direction, max_swathes=max_swathes)
    th = math.radians(tilt_deg)
    s, t, row = nozzle_offsets(head)
    d_ext = (head.rows - 1) * head.row_separation_mm
    pc = head.pitch_mm * math.cos(th)
    a_lo, a_hi = placement.angular_range_rad()
    h, w = placement.height_px, placement.width_px
    flat = np.concatenate([design.ravel(), np.zeros(1, np.uint8)])
    dead = list(head.dead_nozzles)
    out = []
    for j, sw in enumerate(plan.swathes):
        mount = plan.mount(j)
        lay = nozzle_layout(head, mount)  # only to check the mount
        del lay
        # the paper's clock: dpi_y at the image's first column, r_ref = cx_T + px_T (s. 3)
        r_ref = sw.first_track_mm if ref_radius_mm is None else float(ref_radius_mm)
        dphi = clock_dphi(dpi_y, r_ref)
        p_y = 25.4 / dpi_y
        cx = sw.pivot_radius_mm
        cx_T = cx + d_ext * math.sin(th) / 2  # eq (1)
        x_proj = cx + s * math.cos(th) - t * math.sin(th)  # nozzle's radial projection
        u_k = np.rint((x_proj - cx_T) / pc).astype(np.int64)
        en = sw.enabled
        u0, u1 = int(u_k[en].min()), int(u_k[en].max())
        su = u1 - u0 + 1
        c = check_count(math.ceil(a_hi / dphi), f"firings of swathe {j}")
        sv = c - check_count(math.floor(a_lo / dphi), f"firings of swathe {j}") + 1
        # X, Y, col, row, their floors and the index: about 56 bytes a polar pixel
        check_raster_fits(su, sv, 56, what=f"polar image of swathe {j}")
        # step 1: polar image P[v, u] (columns u0..u1)
        rho = cx_T + np.arange(u0, u1 + 1) * pc
        alpha = (c - np.arange(sv)) * dphi
        X = rho[None, :] * np.cos(alpha)[:, None]
        Y = rho[None, :] * np.sin(alpha)[:, None]
        col, rw = placement.to_design(X, Y)
        ci, ri = np.floor(col).astype(np.int64), np.floor(rw).astype(np.int64)
        ok = (ci >= 0) & (ci < w) & (ri >= 0) & (ri < h)
        pidx = np.where(ok, ri * w + ci, h * w)
        if kind == "binary":
            P = flat[pidx]
        else:
            from ._exact_kernels import bilinear_numpy

            P = bilinear_numpy(design, col.astype(np.float32), rw.astype(np.float32), pidx)
        # step 2: linear shifts, eqs (4)-(6)
        shift = np.rint(paper_shifts(head, tilt_deg=tilt_deg, cx_T_mm=cx_T, pitch_y_mm=p_y)).astype(np.int64)
        if direction == 1:
            i0 = int(shift[en].min()) - c
            i1 = int(shift[en].max()) - c + sv - 1
        else:
            i0 = c - int(shift[en].max()) - sv + 1
            i1 = c - int(shift[en].min())
        # v (int64), the mask, the samples and the levels: about 11 bytes a print pixel
        check_raster_fits(head.nozzles, i1 - i0 + 1, 11, what=f"print image of swathe {j}")
        ii = np.arange(i0, i1 + 1)[:, None]
        v = (c - shift[None, :] + ii) if direction == 1 else (c - shift[None, :] - ii)
        u = (u_k - u0)[None, :]
        good = (v >= 0) & (v < sv) & (u >= 0) & (u < su) & en[None, :]
        samples = np.zeros(good.shape, P.dtype)
        vv, uu = np.broadcast_arrays(v, u)
        samples[good] = P[vv[good], uu[good]]
        lev = design_levels(samples, head.grey_levels, kind=kind)
        if dead:
            lev[:, dead] = 0
        hit = good.any(axis=1)
        b0 = int(np.argmax(hit)) if hit.any() else 0
        b1 = int(good.shape[0] - np.argmax(hit[::-1])) if hit.any() else 1
        out.append(
            SwatheImage(
                index=j,
                levels=np.ascontiguousarray(lev[b0:b1]),
                pivot_radius_mm=cx,
                first_firing=i0 + b0,
                dphi_rad=dphi,
                ref_radius_mm=r_ref,
                band_mm=sw.band_mm,
                enabled_nozzles=int(en.sum()),
                enabled=en,
                extra={"paper": {"cx_T_mm": cx_T, "polar_image_px": [su, sv], "shift_px_range": [int(shift[en].min()), int(shift[en].max())]}},
            )
        )
    return RotaryPrint(
        method="paper",
        head=head,
        tilt_deg=float(tilt_deg),
        mount_angle_deg=float(mount_angle_deg),
        direction=int(direction),
        dpi_y=dpi_y,
        placement=placement,
        swathes=tuple(out),
        design_kind=kind,
    )
