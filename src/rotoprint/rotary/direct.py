"""Direct rotary slicing (issue 4): from a mesh to per-nozzle firing data in one step.

For every layer, every swathe and every enabled nozzle ``k``, the nozzle's track is the circle
of radius ``r_k`` in the platform frame. The layer's exact cross-section (oriented segments
from :mod:`rotoprint.slicing`) is intersected with that circle and filled by winding along the
arc, at the firing angles ``phi_k - direction * i * dphi``; so ``B[i, k]`` comes straight
from the mesh, with no Cartesian bitmap and no resampling. The rule: a drop is printed
exactly when its landing point is inside the cross-section. Ties (a landing point exactly on
the boundary) follow two half-open rules, documented in :mod:`._direct_kernels`: radially a
point with ``|p| >= r_k`` counts as outside the track, and along the track a drop exactly on a
crossing takes the state just after it in firing order.

Placement (:class:`PartPlacement`), the same as slicing to a Cartesian image and running
``rotoprint transform --radius R --angle A`` on it: model +X points radially outwards and
model +Y counter-clockwise along the platform; the part's footprint (its XY bounding box over
all layers) has its inner edge (smallest X) at radius ``R`` on the centre line at angle ``A``,
and the centre line runs through the middle of the footprint's Y range. The model is not
rotated (use ``--rotate`` when loading it).

Swathes come from :func:`rotoprint.rotary.plan_swathes` (shared with the bitmap transforms),
and each swathe's clock from the same rule as the exact transform (default reference radius:
the swathe's outermost track). Output is a :class:`~rotoprint.rotary.RotaryPrint` per layer,
readable by the simulator unchanged; its ``placement`` is a bitmap grid at the head's native
pitch covering the footprint (:meth:`PartPlacement.design_placement`), used only to place the
simulator's reference image.
"""

from __future__ import annotations

import dataclasses
import hashlib
import logging
import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from .._buffers import ReusedBuffers
from .._version import __version__
from .._resources import check_raster_fits
from ..errors import ConfigError, GeometryError
from ..mesh import Mesh
from ..slicing import slice_mesh
from ..slicing._sections import Segments
from . import _direct_kernels as _k
from ._thin_kernels import thin_phases
from .exact import firing_range, swathe_clock
from .head import check_tilt, nozzle_layout
from .options import RotarySliceOptions, options_from
from .placement import Placement
from .printdata import RotaryPrint, SwatheImage
from .swathes import SwathePlan, shared_plan

__all__ = [
    "PartPlacement",
    "TrackSet",
    "DirectSliceJob",
    "slice_rotary",
    "union_pass_shares",
    "edge_offsets_mm",
    "rasterize_section",
    "rotary_layer_files",
    "rotary_manifest",
    "KERNEL_NAMES",
    "MANIFEST_FORMAT",
]

log = logging.getLogger(__name__)

KERNEL_NAMES = tuple(_k.KERNELS)
MANIFEST_FORMAT = "rotoprint-rotary-slice"
#: Tracks on each side averaged for the local radial pitch used by density equalisation.
EQUALISE_PITCH_WINDOW = 8
_GOLDEN = 0.6180339887498949
_PLASTIC = 0.7548776662466927
#: Step of :func:`~rotoprint.rotary.equalise.thin_print`'s pass index per layer with union shares.
_SHARE_LAYER_STEP = 64
#: Radial step (um) at most between the offsets the edge restore looks at (:func:`edge_offsets_mm`):
#: 50 um, so the default zone is looked at on ``r +- 50 um`` only, as edgecomp's test on the image
#: route (measured, docs/benchmarks.md: each finer step adds about a tenth of the fill's time).
EDGE_STEP_UM = 50.0


@dataclass(frozen=True)
class PartPlacement:
    """Where a part's cross-sections sit on the platform (see the module doc).

    Parameters
    ----------
    inner_radius_mm : float
        Radius of the footprint's inner edge (smallest model X), on the centre line.
    angle_deg : float
        Angle of the centre line in the platform frame (0: head 0's radial line).
    footprint_mm : (float, float, float, float)
        ``(x_min, y_min, x_max, y_max)`` of the part in model XY.

    Examples
    --------
    >>> pl = PartPlacement(60.0, 90.0, (-5.0, -2.0, 5.0, 2.0))
    >>> [round(float(v[0]), 9) for v in pl.model_to_platform(np.array([-5.0]), np.array([0.0]))]
    [0.0, 60.0]
    """

    inner_radius_mm: float
    angle_deg: float
    footprint_mm: tuple[float, float, float, float]

    def __post_init__(self) -> None:
        if not (math.isfinite(self.inner_radius_mm) and self.inner_radius_mm > 0):
            raise GeometryError(f"radius of the part's inner edge must be > 0 mm, got {self.inner_radius_mm}")
        if not math.isfinite(self.angle_deg):
            raise ConfigError(f"angle must be a finite number of degrees, got {self.angle_deg}")
        x0, y0, x1, y1 = self.footprint_mm
        if not all(math.isfinite(v) for v in self.footprint_mm) or not (x1 > x0 and y1 > y0):
            raise GeometryError(f"the part's footprint must have a positive area, got {self.footprint_mm}")

    @classmethod
    def for_mesh(cls, mesh: Mesh, *, inner_radius_mm: float, angle_deg: float = 0.0) -> PartPlacement:
        """Placement of ``mesh``'s whole footprint (the same for every layer)."""
        lo, hi = mesh.bounds
        return cls(float(inner_radius_mm), float(angle_deg), (float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])))

    @property
    def y_centre_mm(self) -> float:
        return 0.5 * (self.footprint_mm[1] + self.footprint_mm[3])

    @property
    def width_mm(self) -> float:
        return self.footprint_mm[2] - self.footprint_mm[0]

    @property
    def height_mm(self) -> float:
        return self.footprint_mm[3] - self.footprint_mm[1]

    def model_to_local(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Model XY to the local frame (platform frame turned so the centre line is +X).

        Elementwise (a translation only), so equal inputs give bit-identical outputs.
        """
        return (np.asarray(x, np.float64) - self.footprint_mm[0]) + self.inner_radius_mm, np.asarray(y, np.float64) - self.y_centre_mm

    def model_to_platform(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        xl, yl = self.model_to_local(x, y)
        a = math.radians(self.angle_deg)
        c, s = math.cos(a), math.sin(a)
        return c * xl - s * yl, s * xl + c * yl

    def platform_to_model(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        a = math.radians(self.angle_deg)
        c, s = math.cos(a), math.sin(a)
        x = np.asarray(x, np.float64)
        y = np.asarray(y, np.float64)
        xl = c * x + s * y
        yl = -s * x + c * y
        return xl - self.inner_radius_mm + self.footprint_mm[0], yl + self.y_centre_mm

    def design_placement(self, pitch_x_mm: float, pitch_y_mm: float, *, oversample: int = 1) -> Placement:
        """A bitmap grid covering the footprint: first column's inner edge at the inner radius,
        rows centred on the centre line. ``oversample`` divides the pitch and multiplies the
        size, so every oversampled grid covers exactly the same rectangle."""
        if oversample < 1:
            raise ConfigError(f"oversample must be >= 1, got {oversample}")
        w = max(1, math.ceil(self.width_mm / pitch_x_mm - 1e-9))
        h = max(1, math.ceil(self.height_mm / pitch_y_mm - 1e-9))
        return Placement(
            w * oversample, h * oversample, pitch_x_mm / oversample, pitch_y_mm / oversample,
            inner_radius_mm=self.inner_radius_mm, angle_deg=self.angle_deg,
        )

    def to_json(self) -> dict:
        return {
            "inner_radius_mm": self.inner_radius_mm,
            "angle_deg": self.angle_deg,
            "footprint_mm": list(self.footprint_mm),
            "convention": "model +X radially outwards, +Y counter-clockwise; platform = rotate(angle_deg) @ "
            "(X - x_min + inner_radius_mm, Y - (y_min + y_max) / 2)",
        }


def rasterize_section(seg: Segments, part: PartPlacement, design: Placement, *, fill: str = "nonzero", backend: str = "jit") -> np.ndarray:
    """``(H, W) uint8`` image of a cross-section on a :class:`Placement` grid (255 inside).

    Pixel centres are sampled with the slicer's exact fibre rules; this is the first step of
    the two-step path (Cartesian bitmap, then transform) and the simulator's reference image.

    Parameters
    ----------
    seg : Segments
        The cross-section in model XY, mm.
    part : PartPlacement
        Maps model XY to the part's local frame.
    design : Placement
        The grid: ``height_px x width_px`` pixels of ``pitch_x_mm x pitch_y_mm``, column 0
        starting at ``inner_radius_mm``, rows centred on the part's centre line.
    fill : {'nonzero', 'evenodd'}
        Not checked: any value other than ``'evenodd'`` fills by the nonzero rule.
    backend : {'jit', 'numpy'}
        Not checked: any value other than ``'numpy'`` uses the compiled kernel.

    Returns
    -------
    (H, W) uint8 ndarray
        255 where the pixel centre is inside, else 0.

    Raises
    ------
    RasterTooLargeError
        The image would not fit in the available memory.
    """
    xl0, yl0 = part.model_to_local(seg.start[:, 0], seg.start[:, 1])
    xl1, yl1 = part.model_to_local(seg.end[:, 0], seg.end[:, 1])
    # local (x, y) -> pixel (u = col, v = row) of the pixel centres (elementwise arithmetic)
    px, py = design.pitch_x_mm, design.pitch_y_mm
    ox = design.inner_radius_mm
    oy = design.height_px / 2.0

    def u(x):
        return (x - ox) / px - 0.5

    def v(y):
        return (oy - 0.5) - y / py

    check_raster_fits(design.width_px, design.height_px, 5, what="reference image")
    args = (u(xl0), v(yl0), u(xl1), v(yl1), design.height_px, design.width_px, fill)
    if backend == "numpy":
        from ..slicing._fill import fill_numpy

        return fill_numpy(*args)
    from ..slicing._fill import fill_fast

    return fill_fast(*args)


@dataclass(frozen=True, eq=False)
class TrackSet:
    """The tracks of one swathe, sorted by radius.

    Attributes
    ----------
    nozzle : (M,) int64
        Nozzle (image column) of each track: enabled in the swathe and not dead.
    r_mm : (M,) float64
        Track radius, ascending.
    psi0_rad : (M,) float64
        Angle of the nozzle at firing 0 relative to the centre line, ``phi_k - angle``.
    pitch_mm : (M,) float64
        Local radial track pitch (averaged over ``EQUALISE_PITCH_WINDOW`` tracks each side).
    """

    index: int
    pivot_radius_mm: float
    dphi_rad: float
    ref_radius_mm: float
    first_firing: int
    firings: int
    band_mm: tuple[float, float]
    enabled: np.ndarray
    nozzle: np.ndarray
    r_mm: np.ndarray
    psi0_rad: np.ndarray
    pitch_mm: np.ndarray

    @property
    def area_per_drop_mm2(self) -> np.ndarray:
        """``(M,) float64``: drop spacing along the track times the local track pitch."""
        return self.r_mm * self.dphi_rad * self.pitch_mm


def _local_pitch(r_sorted: np.ndarray, h: int) -> np.ndarray:
    n = r_sorted.size
    if n < 2:
        return np.ones(n)
    q = np.arange(n)
    a = np.clip(q - h, 0, n - 1)
    b = np.clip(q + h, 0, n - 1)
    return (r_sorted[b] - r_sorted[a]) / (b - a)


class DirectSliceJob:
    """A planned direct rotary slicing run; :meth:`layer` (or iteration) gives one
    :class:`RotaryPrint` per layer. Build one with :func:`slice_rotary`.

    Threads may share a job (the slice job's face sweep takes its steps under a lock; the sections
    and fills run side by side)."""

    def __init__(self, job, head, part: PartPlacement, design: Placement, plan: SwathePlan, tracks: tuple[TrackSet, ...], *,
                 options: RotarySliceOptions, dpi_y: float, shares: tuple[np.ndarray, ...] | None = None,
                 pass_index: int = 0, edge_restore=None) -> None:
        self.slice_job = job
        self.head = head
        self.part = part
        self.design = design
        self.plan = plan
        self.tracks = tracks
        self.options = options
        self.dpi_y = dpi_y
        self.fill = options.fill
        self.equalise = bool(options.equalise)
        self.backend = options.backend
        equalise = self.equalise
        # density equalisation: keep the fraction area_per_drop / largest area_per_drop
        apd = [t.area_per_drop_mm2 for t in tracks]
        top = max((float(a.max()) for a in apd if a.size), default=1.0)
        #: shares of the union of interlaced passes (:meth:`with_shares`), per swathe (N,) by nozzle, or None
        self.shares = None if shares is None else tuple(np.asarray(f, np.float64) for f in shares)
        self.pass_index = int(pass_index)
        if self.shares is not None:
            if equalise:
                raise ConfigError("union shares replace the direct slicer's own equalisation: options.equalise must be False")
            if len(self.shares) != len(tracks) or any(f.shape != (head.nozzles,) for f in self.shares):
                raise ConfigError(f"shares must give one ({head.nozzles},) array per swathe ({len(tracks)})")
            if not all(np.isfinite(f).all() and (f >= 0.0).all() for f in self.shares):
                raise ConfigError("shares must be finite and >= 0 (a share of 1 or more keeps every drop)")
        self._frac = tuple((a / top) if equalise else np.ones_like(a) for a in apd)
        #: the edge restore of the thinned tracks (:class:`~rotoprint.rotary.edgecomp.EdgeRestore`), or None
        self.edge_restore = _edge_options(edge_restore)
        if self.edge_restore is not None and not (equalise or self.shares is not None):
            raise ConfigError("edge restore needs thinned tracks: equalise, or the union's shares (with_shares)")
        #: the radial offsets (mm) the edge restore looks at: ``+-zone * s / n`` (:func:`edge_offsets_mm`)
        self.edge_offsets_mm = None if self.edge_restore is None else edge_offsets_mm(self.edge_restore.zone_um)
        # the swathe images of the layers the caller has dropped, written again (new pages cost a fault each
        # 4 KiB: 3.9 of a 5.3 ms layer): two layers' worth, for the builds' two threads
        self._buffers = ReusedBuffers(2 * len(tracks))

    def with_shares(self, shares, *, pass_index: int = 0, edge_restore=None) -> DirectSliceJob:
        """This job printing interlaced pass ``pass_index`` with the union's shares.

        Parameters
        ----------
        shares : list (swathe) of (N,) float64
            The pass's shares (:func:`~rotoprint.rotary.equalise.track_fractions`, possibly
            with :func:`~rotoprint.rotary.deadcover.cover_dead_tracks`: one entry of their
            per-pass list), in [0, 1] by nozzle; realised on each layer's firing images as
            :func:`~rotoprint.rotary.equalise.thin_print` does (its rule and offsets, pass index
            ``pass_index + P * layer``, ``P`` = 64, so the pattern moves from layer to layer),
            by the fill kernel while it fills (8 x faster on the coil demo; tested identical).
        pass_index : int
        edge_restore : EdgeRestore or dict, optional
            Of the drops the shares thin out, those inside the section within ``zone_um`` of an
            edge met along the platform radius come back at the gain of
            :func:`~rotoprint.rotary.edgecomp.restore_near_edges` (its rule, zone and pattern;
            see :mod:`._direct_edge`), made while filling; None: the thinned print as it is.

        Returns
        -------
        DirectSliceJob
            Sharing the slicer, lattice and options (``equalise`` must be off: the shares replace it).
        """
        return DirectSliceJob(self.slice_job, self.head, self.part, self.design, self.plan, self.tracks, options=self.options,
                              dpi_y=self.dpi_y, shares=shares, pass_index=pass_index, edge_restore=edge_restore)

    @property
    def layers(self):
        return self.slice_job.plan

    @property
    def rotary_options(self) -> dict:
        """The options as :func:`slice_rotary` keywords (JSON-ready), ``dpi_y`` resolved."""
        d = {**self.options.as_dict(), "dpi_y": self.dpi_y}
        if self.shares is not None:  # so a worker rebuilds the same pass (``slice_rotary(..., shares=, pass_index=)``)
            d.update(shares=[f.tolist() for f in self.shares], pass_index=self.pass_index)
        if self.edge_restore is not None:
            d.update(edge_restore=dataclasses.asdict(self.edge_restore))
        return d

    def __len__(self) -> int:
        return len(self.slice_job)

    def density_spread(self, *, equalised: bool | None = None) -> float:
        """Expected spread of drops per unit area over the tracks, ``max / min - 1``."""
        eq = (self.equalise or self.shares is not None) if equalised is None else equalised
        dens = []
        apd_top = max((float(t.area_per_drop_mm2.max()) for t in self.tracks if t.r_mm.size), default=1.0)
        for j, t in enumerate(self.tracks):
            a = t.area_per_drop_mm2
            f = (a / apd_top if self.shares is None else self.shares[j][t.nozzle]) if eq else np.ones_like(a)
            keep = f > 0
            dens.append(f[keep] / a[keep])
        d = np.concatenate(dens) if dens else np.ones(1)
        return float(d.max() / d.min() - 1.0)

    def segments(self, index: int):
        return self.slice_job.segments(index)

    def print_from_segments(self, seg: Segments, *, layer_index: int = 0, cut=()) -> RotaryPrint:
        """The print of one cross-section (model-XY segments).

        ``cut``: sections (Segments) whose inside is not part of the design for the edge restore
        (the build's higher-priority parts, whose drops it removes afterwards): their edges are
        the design's edges too. Without an edge restore it changes nothing."""
        xl0, yl0 = self.part.model_to_local(seg.start[:, 0], seg.start[:, 1])
        xl1, yl1 = self.part.model_to_local(seg.end[:, 0], seg.end[:, 1])
        cuts = []
        if self.edge_restore is not None:
            for c in cut:
                if len(c):
                    cuts.append(np.stack([*self.part.model_to_local(c.start[:, 0], c.start[:, 1]),
                                          *self.part.model_to_local(c.end[:, 0], c.end[:, 1])]))
        if xl0.size and (min(xl0.min(), xl1.min()) <= 0.0):
            raise GeometryError("the cross-section reaches the axis of rotation; use a larger --radius")
        fn = _k.KERNELS[self.backend]
        dead = np.array(self.head.dead_nozzles, dtype=np.int64)
        out = []
        p_i = self.pass_index + _SHARE_LAYER_STEP * layer_index
        for j, (ts, frac) in enumerate(zip(self.tracks, self._frac)):
            if self.shares is None:
                offs = np.mod(ts.nozzle * _GOLDEN + layer_index * _PLASTIC, 1.0)
            else:  # thin_print's pattern (its rule and offsets, pass index p_i), made while filling: tested identical
                frac = self.shares[j][ts.nozzle]
                offs = thin_phases(ts.nozzle, p_i)
            lev = fn(
                xl0, yl0, xl1, yl1, ts.r_mm * ts.r_mm, ts.psi0_rad, ts.nozzle, frac, offs,
                dphi=ts.dphi_rad, direction=self.plan.direction, i0=ts.first_firing, n_f=ts.firings,
                n_cols=self.head.nozzles, fill=self.fill, level=self.head.grey_levels,
                edge=self._edge_spec(ts, frac, p_i, cuts),
                **({"out": self._buffers.take((ts.firings, self.head.nozzles))} if self.backend == "jit" else {}),
            )
            if dead.size:
                lev[:, dead] = 0
            out.append(
                SwatheImage(
                    index=ts.index, levels=lev, pivot_radius_mm=ts.pivot_radius_mm, first_firing=ts.first_firing,
                    dphi_rad=ts.dphi_rad, ref_radius_mm=ts.ref_radius_mm, band_mm=ts.band_mm,
                    enabled_nozzles=int(ts.enabled.sum()), enabled=ts.enabled,
                )
            )
        pr = RotaryPrint(
            method="direct", head=self.head, tilt_deg=self.plan.tilt_deg, mount_angle_deg=self.plan.mount_angle_deg,
            direction=self.plan.direction, dpi_y=self.dpi_y, placement=self.design, swathes=tuple(out), design_kind="binary",
        )
        return pr

    def _edge_spec(self, ts: TrackSet, frac: np.ndarray, p_i: int, cuts) -> tuple | None:
        """The fill's ``edge`` argument for one swathe (:func:`._direct_kernels.direct_fill_jit`):
        the rule of :func:`~rotoprint.rotary.edgecomp.restore_near_edges` on its thinned tracks
        (gain ``min(1, c f / (1 - f))``, phases ``((k + 7919 p) * GOLDEN2) mod 1``, ``p`` the
        thinning's pass index), or None."""
        if self.edge_restore is None:
            return None
        from .edgecomp import restore_pattern

        thin = np.flatnonzero((frac > 0.0) & (frac < 1.0))
        if not thin.size:
            return None
        gain, phase = restore_pattern(ts.nozzle[thin], frac[thin], self.edge_restore.coefficient, p_i)
        return cuts, thin, self.edge_offsets_mm, gain, phase

    def layer(self, index: int) -> RotaryPrint:
        """Layer ``index``'s print (one swathe image per radial swathe)."""
        if not 0 <= index < len(self):
            raise IndexError(f"layer {index} out of range 0..{len(self) - 1}")
        seg, _ = self.segments(index)
        return self.print_from_segments(seg, layer_index=index)

    def reference_image(self, index: int, *, oversample: int = 1) -> np.ndarray:
        """``(H, W) uint8`` Cartesian image of layer ``index`` on the design grid (for checks)."""
        seg, _ = self.segments(index)
        pl = self.part.design_placement(self.design.pitch_x_mm, self.design.pitch_y_mm, oversample=oversample)
        return rasterize_section(seg, self.part, pl, fill=self.fill)

    def __iter__(self) -> Iterator[RotaryPrint]:
        for i in range(len(self)):
            yield self.layer(i)

    def edge_restore_record(self) -> dict | None:
        """The edge restore for the manifests (its options, the rule, the radial offsets looked at), or None."""
        if self.edge_restore is None:
            return None
        return {**dataclasses.asdict(self.edge_restore), "offsets_um": [round(1e3 * d, 6) for d in self.edge_offsets_mm],
                "rule": "thinned-out drops inside the section whose site has a point outside at r +- d, |d| <= zone "
                        "(looked at on the offsets), restored by edgecomp's pattern to min(1, (1 + c) f)"}

    def to_json(self) -> dict:
        return {
            "tilt_deg": self.plan.tilt_deg,
            "mount_angle_deg": self.plan.mount_angle_deg,
            "direction": self.plan.direction,
            "dpi_y": self.dpi_y,
            "fill": self.fill,
            "placement": self.part.to_json(),
            "design_grid": self.design.to_json(),
            "equalise": "union shares" if self.shares is not None else self.equalise,
            **({} if self.edge_restore is None else {"edge_restore": self.edge_restore_record()}),
            "density_spread": {"without_equalisation": self.density_spread(equalised=False),
                               "with_equalisation": self.density_spread(equalised=True)},
            "swathes": [
                {
                    **sw.to_json(),
                    "first_firing_index": ts.first_firing,
                    "firings": ts.firings,
                    "dphi_rad": ts.dphi_rad,
                    "angle_per_firing_deg": math.degrees(ts.dphi_rad),
                    "ref_radius_mm": ts.ref_radius_mm,
                    "tracks": int(ts.r_mm.size),
                }
                for sw, ts in zip(self.plan.swathes, self.tracks)
            ],
        }


def slice_rotary(mesh: Mesh, device, options: RotarySliceOptions | None = None, *, shares=None, pass_index: int = 0,
                 edge_restore=None, **keywords) -> DirectSliceJob:
    """Plan direct rotary slicing of ``mesh`` for an inkjet ``device``.

    Parameters
    ----------
    mesh : Mesh
    device : InkjetDevice or str
        An inkjet device, or a preset name or device .toml file to load.
    options : RotarySliceOptions, optional
        Layer height, tilt, the part's inner radius and angle, the clock (``dpi_y``,
        ``ref_radius_mm``), direction, swathe limit, density equalisation, fill, gap radius,
        kernel (see :class:`~rotoprint.rotary.options.RotarySliceOptions`).
    shares, pass_index, edge_restore
        Interlaced pass ``pass_index`` printed with the union's shares, its edge restore
        (:meth:`DirectSliceJob.with_shares`; with ``equalise`` and no shares, the edge restore
        of the equalised tracks).
    **keywords
        Its fields by name (``layer_height_mm=0.1, tilt_deg=20.0, inner_radius_mm=60.0``),
        replacing those of ``options``.

    Returns
    -------
    DirectSliceJob

    Examples
    --------
    >>> from rotoprint import load_device
    >>> from rotoprint.testing import box_mesh
    >>> job = slice_rotary(box_mesh((10, 6, 1)), load_device("omnidot760"), layer_height_mm=0.5,
    ...                    tilt_deg=20.0, inner_radius_mm=60.0)
    >>> pr = job.layer(0)
    >>> len(job), len(pr.swathes), pr.swathes[0].levels.shape[1], pr.swathes[0].levels.dtype
    (2, 1, 764, dtype('uint8'))
    """
    from ..devices import InkjetDevice, as_device

    device = as_device(device)
    if not isinstance(device, InkjetDevice):
        raise ConfigError(f"device {getattr(device, 'name', device)!r} is not an inkjet device; direct rotary slicing needs a print head")
    opts = options_from(RotarySliceOptions, options, keywords, what="slice_rotary")
    tilt_deg, inner_radius_mm, angle_deg = opts.tilt_deg, opts.inner_radius_mm, opts.angle_deg
    dpi_y, ref_radius_mm, direction, max_swathes = opts.dpi_y, opts.ref_radius_mm, opts.direction, opts.max_swathes
    backend, pivot_offset_mm = opts.backend, opts.pivot_offset_mm
    head = device.head
    check_tilt(head, float(tilt_deg))
    dpi_y = float(head.dpi_y if dpi_y is None else dpi_y)
    if not (math.isfinite(dpi_y) and dpi_y > 0):
        raise ConfigError(f"dpi_y must be a positive number, got {dpi_y}")
    part = PartPlacement.for_mesh(mesh, inner_radius_mm=inner_radius_mm, angle_deg=angle_deg)
    design = part.design_placement(head.pitch_mm, 25.4 / dpi_y)
    job = slice_mesh(mesh, device, layer_height_mm=opts.layer_height_mm, fill=opts.fill, gap_radius_mm=opts.gap_radius_mm,
                     backend=backend)
    r_in, r_out = design.radial_range_mm()
    plan = shared_plan(  # the passes' jobs share one plan
        head, tilt_deg=float(tilt_deg), inner_radius_mm=r_in, outer_radius_mm=r_out,
        mount_angle_deg=0.0, direction=int(direction), max_swathes=max_swathes)
    a_lo, a_hi = design.angular_range_rad()
    alpha = math.radians(part.angle_deg)
    live = np.ones(head.nozzles, bool)
    live[list(head.dead_nozzles)] = False
    tracks = []
    for j, sw in enumerate(plan.swathes):
        mount = plan.mount(j)
        if pivot_offset_mm:
            if not math.isfinite(pivot_offset_mm):
                raise ConfigError(f"pivot offset must be a finite number of mm, got {pivot_offset_mm!r}")
            mount = dataclasses.replace(mount, pivot_radius_mm=mount.pivot_radius_mm + float(pivot_offset_mm))
        lay = nozzle_layout(head, mount)
        dphi, r_ref = swathe_clock(plan, j, dpi_y=dpi_y, ref_radius_mm=ref_radius_mm)
        en = sw.enabled
        i0, i1 = firing_range(lay.phi_rad[en], a_lo, a_hi, dphi, int(direction))
        n_f = i1 - i0 + 1
        check_raster_fits(head.nozzles, n_f, 2, what=f"print image of swathe {j}")
        k = np.flatnonzero(en & live)
        order = np.argsort(lay.r_mm[k], kind="stable")
        k = k[order]
        r = lay.r_mm[k]
        tracks.append(
            TrackSet(
                index=j, pivot_radius_mm=mount.pivot_radius_mm, dphi_rad=dphi, ref_radius_mm=r_ref, first_firing=i0,
                firings=n_f, band_mm=sw.band_mm, enabled=en, nozzle=k.astype(np.int64), r_mm=r,
                psi0_rad=lay.phi_rad[k] - alpha, pitch_mm=_local_pitch(r, EQUALISE_PITCH_WINDOW),
            )
        )
    log.debug("direct rotary slicing: %d layers, %d swathe(s)", len(job), len(tracks))
    if shares is None:
        return DirectSliceJob(job, head, part, design, plan, tuple(tracks), options=opts, dpi_y=dpi_y, edge_restore=edge_restore)
    out = DirectSliceJob(job, head, part, design, plan, tuple(tracks), options=opts, dpi_y=dpi_y)
    return out.with_shares(shares, pass_index=pass_index, edge_restore=edge_restore)


def edge_offsets_mm(zone_um: float, step_um: float | None = None) -> np.ndarray:
    """``(2 n,) float64``: the radial offsets (mm) the direct slicer's edge restore looks at,
    ``+-zone * s / n`` for ``s = 1 .. n``, ``n = ceil(zone / step)`` (``step`` default
    :data:`EDGE_STEP_UM`): an outside stretch at least ``zone / n`` wide along the radius within
    the zone is seen."""
    step = EDGE_STEP_UM if step_um is None else float(step_um)
    if not (math.isfinite(step) and step > 0):
        raise ConfigError(f"edge sample step must be > 0 um, got {step_um!r}")
    n = max(1, math.ceil(float(zone_um) / step - 1e-9))
    d = 1e-3 * float(zone_um) * np.arange(1, n + 1) / n
    return np.concatenate([-d[::-1], d])


def _edge_options(edge_restore):
    from .edgecomp import EdgeRestore

    if edge_restore is None or isinstance(edge_restore, EdgeRestore):
        er = edge_restore
    elif isinstance(edge_restore, dict):  # from rotary_options' JSON
        er = EdgeRestore(**edge_restore)
    else:
        raise ConfigError(f"edge_restore must be an EdgeRestore, got {type(edge_restore).__name__}")
    if er is not None and not er.radial_only:
        raise ConfigError("the direct slicer's edge restore looks along the platform radius only (radial_only=True)")
    if er is not None and er.zone_um is None:  # the exact section has no pixel: the zone is edgecomp's 50 um
        from .edgecomp import EDGE_ZONE_UM

        er = dataclasses.replace(er, zone_um=EDGE_ZONE_UM)
    return er


def union_pass_shares(head, plan: SwathePlan, offsets_mm, *, dpi_y: float, ref_radius_mm: float | None = None,
                      footprint_um: float | None = None) -> tuple[list[list[np.ndarray]], float, dict]:
    """The equalised shares of interlaced direct-slicer passes, over the union of the passes.

    The same shares as ``transform --passes ... --equalise`` prints
    (:func:`~rotoprint.rotary.interlace.pass_prints`): :func:`~rotoprint.rotary.equalise.track_fractions`
    over every pass's live tracks (floors by the lattice reach ``COVER_SHARE x D`` at the clock
    made :data:`~rotoprint.rotary.equalise.EQUALISE_CLOCK_FACTOR` times finer), and with dead
    nozzles and more than one pass the dead tracks' drops given to the other passes' live
    tracks (:func:`~rotoprint.rotary.deadcover.cover_dead_tracks`, the shares equalised with
    the dead nozzles as live ones). Computed once per plan; each pass's job prints its entry
    (:meth:`DirectSliceJob.with_shares`).

    Parameters
    ----------
    head : InkjetHead
    plan : SwathePlan
        The direct slicer's swathes (:attr:`DirectSliceJob.plan`, no overlap).
    offsets_mm : sequence of float
        The passes' pivot offsets (:attr:`~rotoprint.rotary.interlace.PassPlan.offsets_mm`).
    dpi_y : float
        The clock the passes were planned for (the plan's or the job's).
    ref_radius_mm : float, optional
        Reference radius of the swathes' clocks (default each swathe's outermost track).
    footprint_um : float, optional
        A full drop's footprint (default the head's, :mod:`rotoprint.rotary.deposit`).

    Returns
    -------
    shares : list (pass) of list (swathe) of (N,) float64
        In [0, 1] for the enabled live nozzles, 0 elsewhere.
    clock_dpi : float
        The clock to print them at: ``dpi_y * EQUALISE_CLOCK_FACTOR``.
    record : dict
        For the manifests: ``rule``, ``plan_dpi_y``, ``dpi_y``, ``clock_factor``, ``tracks``,
        ``tracks_left_out``, ``mean_share`` and ``dead_cover`` (the cover's report or None).
    """
    from .deposit import DepositOptions
    from .equalise import EQUALISE_CLOCK_FACTOR, ReachFloor, track_fractions
    from .interlace import COVER_SHARE
    from .options import RotarySetup

    offsets = [float(o) for o in offsets_mm]
    d_um = DepositOptions(footprint_um=footprint_um).full_footprint_um(head)
    st = RotarySetup(tilt_deg=plan.tilt_deg, dpi_y=float(dpi_y), ref_radius_mm=ref_radius_mm, direction=plan.direction)
    cover = bool(head.dead_nozzles) and len(offsets) > 1
    shares = track_fractions(head, plan, offsets, st, footprint_um=d_um, reach=ReachFloor(COVER_SHARE * d_um, EQUALISE_CLOCK_FACTOR),
                             dead_nozzles=() if cover else None)
    clock = float(dpi_y) * EQUALISE_CLOCK_FACTOR
    report = None
    if cover:
        from .deadcover import cover_dead_tracks

        shares, report = cover_dead_tracks(head, plan, offsets, dataclasses.replace(st, dpi_y=clock), shares=shares, footprint_um=d_um)
    live = np.ones(head.nozzles, bool)
    live[list(head.dead_nozzles)] = False
    on = [f[sw.enabled & live] for per in shares for f, sw in zip(per, plan.swathes)]
    f_all = np.concatenate(on) if on else np.zeros(0)
    record = {"rule": "track_fractions over the union of the passes (as transform --passes --equalise)",
              "plan_dpi_y": float(dpi_y), "dpi_y": clock, "clock_factor": EQUALISE_CLOCK_FACTOR,
              "footprint_um": d_um, "tracks": int(f_all.size), "tracks_left_out": int((f_all <= 0).sum()),
              "mean_share": float(f_all.mean()) if f_all.size else 0.0, "dead_cover": report}
    return shares, clock, record


def rotary_layer_files(job: DirectSliceJob, index: int, *, device_name: str,
                       reference_images: bool) -> tuple[dict[str, bytes], dict]:
    """Layer ``index``'s files as bytes (swathe PNGs, the sidecar, optionally the reference
    image, named in the sidecar relative to it) and its manifest entry; the same bytes
    wherever it runs and wherever the folder is put."""
    from ..io.images import png_bytes
    from .files import print_files

    seg, rep = job.segments(index)
    pr = job.print_from_segments(seg, layer_index=index)
    stem = f"layer_{index:05d}"
    design = {"source": "mesh cross-section (direct rotary slicing)", "layer": index, "invert": False,
              "design_dpi_x": 25.4 / job.design.pitch_x_mm, "design_dpi_y": 25.4 / job.design.pitch_y_mm}
    files: dict[str, bytes] = {}
    if reference_images:
        ref = png_bytes(rasterize_section(seg, job.part, job.design, fill=job.fill))
        files[f"{stem}-design.png"] = ref
        design.update(path=f"{stem}-design.png", sha256=hashlib.sha256(ref).hexdigest())
    blobs, side = print_files(pr, f"{stem}.png", device_name=device_name, design=design)
    files.update(blobs)
    plan_layers = job.layers
    record = {
        "index": index,
        "z_mm": float(plan_layers.z_slice_mm[index]),
        "z_bottom_mm": float(plan_layers.z_bottom_mm[index]),
        "z_top_mm": float(plan_layers.z_top_mm[index]),
        "sidecar": f"{stem}.json",
        "reference_image": f"{stem}-design.png" if reference_images else None,
        "gaps": rep.to_json(),
        "images": [
            {
                "head": 0,
                "swathe": sw["index"],
                "file": sw["file"],
                "first_firing_index": sw["first_firing_index"],
                "firings": sw["firings"],
                "angle_per_firing_deg": sw["angle_per_firing_deg"],
                "pivot_radius_mm": sw["pivot_radius_mm"],
                "drops": sw["drops"],
                "sha256": sw["sha256"],
            }
            for sw in side["swathes"]
        ],
    }
    return files, record


def rotary_manifest(job: DirectSliceJob, entries: list[dict], *, device_name: str, options: dict,
                    mesh_info: dict | None = None) -> dict:
    """The ``manifest.json`` of a folder of direct rotary slices (written by
    :func:`rotoprint.pipeline.write_rotary_slices`).

    Parameters
    ----------
    job : DirectSliceJob
    entries : list of dict
        Every layer's entry, in layer order (from :func:`rotary_layer_files`).
    device_name : str
    options : dict
        The command's options (JSON-ready values).
    mesh_info : dict, optional
        :meth:`~rotoprint.mesh.Mesh.info` of the source mesh.

    Returns
    -------
    dict
        Format, head, heads, the job's placement, swathes and tracks, the mesh, the options,
        the landing rule and the layers.
    """
    return {
        "format": MANIFEST_FORMAT,
        "version": 1,
        "rotoprint": __version__,
        "device": device_name,
        "head": job.head.model_dump(mode="json"),
        "heads": [{"index": 0, "mount_angle_deg": job.plan.mount_angle_deg}],
        **job.to_json(),
        "mesh": mesh_info or {},
        "options": options,
        "landing": "nozzle k at firing i lands at (r_k, phi_k - direction * i * dphi_rad) in the platform frame; "
        "row b of a swathe image is firing first_firing_index + b (rotary-geometry.md s. 3)",
        "layers": entries,
    }
