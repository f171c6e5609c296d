"""The pass plan: for every layer, the ordered passes (head, ink, print-ready image, repeats),
waits and post-steps, from a job (:mod:`.job`).

How a plan is made:

1. Every part is loaded (mesh file or built-in shape) in the job's model frame; the assembly's
   footprint (XY bounding box of all parts) is placed on the platform as one part
   (:class:`~rotoprint.rotary.direct.PartPlacement`) and its height range is cut into layers
   (:func:`~rotoprint.slicing.layers.plan_layers`), so every material's layer ``i`` is the same
   slab.
2. Each head gets the direct rotary slicer's drop lattice for the assembly
   (:func:`~rotoprint.rotary.direct.slice_rotary` with the head's tilt; a head mounted at
   ``psi`` prints the part at ``angle - psi`` in its own frame, which is the same landing
   geometry). A material's image on a head is the direct slicer's print of each of its parts'
   exact cross-sections on that head's lattice.
3. Overlaps: a drop of a part is removed where its landing point is inside a part of another
   material with a higher priority (the same exact inside rule, on the same lattice, without
   density thinning), so every drop site belongs to at most one material.
4. Interlaced passes (``printer.passes``, default ``"auto"``): per head the pass planner
   (:func:`~rotoprint.rotary.interlace.plan_passes`) chooses radial pivot offsets whose union of
   live tracks leaves no gap the drops' footprints cannot close (dead nozzles' tracks covered by
   live ones), and the clock along the track (unless ``printer.clock.dpi_y`` is set); with
   ``printer.equalise`` (the default) every track keeps the share of its drops that evens the
   film of the **union** of the passes (:func:`~rotoprint.rotary.direct.union_pass_shares`: the
   transform path's ``track_fractions`` over the pass plan, the clock made
   ``EQUALISE_CLOCK_FACTOR`` times finer, dead tracks covered by the other passes), computed
   once per tilt and realised on each pass's images by ``thin_print``; ``equalise = false``
   prints every drop. The build's deposit figures (``coverage`` in ``plan.json``) measure the film that results. Every pass has its own
   lattice (the direct slicer with the pass's pivot offset), so its own exact images. Cycle
   ``c`` of a material is printed at pass ``c mod N`` of each ink's head.
5. Cycles: per material, one *cycle* is every ink in order, each ``repeats`` times; the
   cycles per layer are the fewest that make the thinnest 1 mm radial bin of the material
   reach the layer height, with the *true* volume per area of the planned drops: the drops
   of every pass of the material's first layer, counted per track radius, over the design
   area in that bin (:func:`measured_drop_density`). With interlace the computed cycles are
   rounded up to a multiple of the passes (every offset printed equally often). More passes
   than ``process.max_passes_per_layer`` give a warning and are capped.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from ..devices import InkjetDevice, load_device
from ..errors import ConfigError, RotoprintError
from ..mesh import Mesh
from ..rotary.direct import DirectSliceJob, PartPlacement, rasterize_section, slice_rotary
from ..rotary.edgecomp import EdgeRestore
from ..rotary.interlace import PassPlan
from ..rotary.placement import Placement
from ..rotary.printdata import RotaryPrint
from ..slicing import slice_mesh
from ..slicing._sections import Segments
from .estimates import cycle_thickness_um, cycles_for_height, track_density_per_mm2, wet_film_um
from .job import ResolvedJob
from .materials import Material

__all__ = ["HeadSetup", "PassStep", "MaterialBlock", "LayerSchedule", "MaterialEstimate", "BuildPlan", "plan_job",
           "load_part_mesh"]

log = logging.getLogger(__name__)

_EMPTY_SEGMENTS = Segments(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0, np.int64))

#: Radii sampled over a material's band for the thickness profile.
_PROFILE_SAMPLES = 64
#: Relative spread of a material's thickness over its band above which the plan warns.
THICKNESS_SPREAD_WARN = 0.10
#: A material whose planned thickness falls short of the layer height by more than this warns.
SHORTFALL_WARN = 0.05


@dataclass(frozen=True, eq=False)
class HeadSetup:
    """One head of the job with its drop lattice.

    Attributes
    ----------
    lattice : DirectSliceJob
        Direct slicer for the assembly in the head's frame (with the job's equalisation), of
        pass 0 (``pass_lattices[0]``).
    inside : DirectSliceJob
        The same lattice without thinning: "landing point inside" for priority masks.
    r_mm, density_per_mm2 : (M,) float64
        Track radii and drops per mm^2 of pass 0's lattice (after equalisation when on).
    revolution_s : tuple of float
        Time of one revolution per swathe at the clock frequency.
    pass_lattices, pass_inside : tuple of DirectSliceJob
        One per interlaced pass: the lattice with that pass's pivot offset (and without
        thinning).
    pass_offsets_mm : tuple of float
        Radial pivot offset of each pass (pass 0: 0).
    pass_plan : PassPlan or None
        The planner's result (None with ``printer.passes = 1``).
    interlace : dict
        How the clock was chosen (``clock``: ``"pass plan"`` or ``"job"``,
        ``dpi_y``, the gaps and dead-track cover in um), for ``plan.json``.
    """

    index: int
    name: str
    ink: str
    mount_angle_deg: float
    tilt_deg: float
    lattice: DirectSliceJob
    inside: DirectSliceJob
    r_mm: np.ndarray
    density_per_mm2: np.ndarray
    frequency_hz: float
    revolution_s: tuple[float, ...]
    pass_lattices: tuple[DirectSliceJob, ...] = ()
    pass_inside: tuple[DirectSliceJob, ...] = ()
    pass_offsets_mm: tuple[float, ...] = (0.0,)
    pass_plan: PassPlan | None = None
    interlace: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.pass_lattices:
            object.__setattr__(self, "pass_lattices", (self.lattice,))
            object.__setattr__(self, "pass_inside", (self.inside,))

    @property
    def passes(self) -> int:
        """Interlaced passes of this head."""
        return len(self.pass_lattices)

    def density_at(self, r_mm) -> np.ndarray:
        """Drops per mm^2 at radii ``r_mm`` (linear between tracks, held beyond them)."""
        return np.interp(np.asarray(r_mm, np.float64), self.r_mm, self.density_per_mm2)

    def to_json(self) -> dict:
        return {
            "index": self.index, "name": self.name, "ink": self.ink, "mount_angle_deg": self.mount_angle_deg,
            "tilt_deg": self.tilt_deg, "frequency_hz": self.frequency_hz,
            "revolution_s": list(self.revolution_s), "swathes": len(self.lattice.tracks),
            "passes": self.passes, "pass_offsets_mm": list(self.pass_offsets_mm),
            "pass_plan": self.pass_plan.to_json() if self.pass_plan is not None else None,
            "interlace": self.interlace,
            "pass_pivots_mm": [[float(t.pivot_radius_mm) for t in lat.tracks] for lat in self.pass_lattices],
            "density_per_mm2": {"min": float(self.density_per_mm2.min()), "max": float(self.density_per_mm2.max())},
            "lattice": self.lattice.to_json(),
        }


@dataclass(frozen=True)
class PassStep:
    """``repeats`` consecutive passes of one ink by one head, then ``wait_s``."""

    material: str
    ink: str
    head: str
    head_index: int
    repeats: int
    wait_s: float = 0.0

    def to_json(self) -> dict:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class MaterialEstimate:
    """Thickness figures of a material over its radial band (the same for every layer).

    ``per_pass_wet_um`` per ink: wet film of one pass at the band's lowest and highest
    density; ``per_cycle_um``: solid of one cycle (min, max over the band); ``cycles``: per
    layer; ``per_layer_um``: ``cycles * per_cycle`` (min, max). The densities are the true
    volume per area of the planned drops (``density_source``, :func:`measured_drop_density`):
    ``drops_per_mm2`` per ink, the mean over the interlaced passes, per profile bin."""

    material: str
    band_mm: tuple[float, float]
    per_pass_wet_um: dict[str, tuple[float, float]]
    per_cycle_um: tuple[float, float]
    cycles: int
    cycles_needed: int
    passes_per_layer: int
    per_layer_um: tuple[float, float]
    profile_r_mm: np.ndarray
    profile_per_layer_um: np.ndarray
    warnings: tuple[str, ...]
    interlace_passes: int = 1
    density_source: dict = field(default_factory=dict)
    drops_per_mm2: dict = field(default_factory=dict)

    def to_json(self) -> dict:
        d = {k: v for k, v in dataclasses.asdict(self).items() if not k.startswith("profile") and k != "drops_per_mm2"}
        d["profile"] = {"r_mm": self.profile_r_mm.round(4).tolist(), "per_layer_um": self.profile_per_layer_um.round(5).tolist(),
                        "drops_per_mm2": {k: np.asarray(v).round(4).tolist() for k, v in self.drops_per_mm2.items()}}
        return d


@dataclass(frozen=True)
class MaterialBlock:
    """One material in one layer: ``cycles`` times the ``passes`` in order, then the post-steps."""

    material: str
    cycles: int
    passes: tuple[PassStep, ...]
    post_steps: tuple[str, ...]
    drops: dict[str, int]
    thickness_um: tuple[float, float]
    interlace: dict[str, int] = field(default_factory=dict)
    drops_by_pass: dict[str, tuple[int, ...]] = field(default_factory=dict)

    @property
    def pass_count(self) -> int:
        return self.cycles * sum(p.repeats for p in self.passes)

    def interlace_of(self, ink: str, cycle: int) -> int:
        """The interlaced pass cycle ``cycle`` of ``ink`` is printed at: ``cycle mod N``."""
        return cycle % self.interlace.get(ink, 1)

    def to_json(self) -> dict:
        return {"material": self.material, "cycles": self.cycles, "passes_per_cycle": [p.to_json() for p in self.passes],
                "passes": self.pass_count, "post_steps": list(self.post_steps), "drops_per_pass": self.drops,
                "interlace_passes": dict(self.interlace), "drops_by_interlace_pass": {k: list(v) for k, v in self.drops_by_pass.items()},
                "thickness_um": list(self.thickness_um)}


@dataclass(frozen=True, eq=False)
class LayerSchedule:
    """Layer ``index``: the material blocks in print order and the print-ready images.

    ``images[(material, ink)]`` is the :class:`RotaryPrint` for that ink's head (one
    ``(F, N) uint8`` image per swathe) of interlaced pass 0, ``pass_images[(material, ink)]``
    those of every pass (``pass_images[k][0] is images[k]``); ``time_s`` the estimated
    printing time."""

    index: int
    z_bottom_mm: float
    z_top_mm: float
    blocks: tuple[MaterialBlock, ...]
    images: dict[tuple[str, str], RotaryPrint] = field(repr=False)
    time_s: float
    pass_images: dict[tuple[str, str], tuple[RotaryPrint, ...]] = field(default_factory=dict, repr=False)

    def sequence(self) -> list[dict]:
        """The layer's steps in order, cycles expanded: ``{"kind": "pass"|"post", ...}``."""
        out = []
        for b in self.blocks:
            for c in range(b.cycles):
                for p in b.passes:
                    out.append({"kind": "pass", "cycle": c, "interlace": b.interlace_of(p.ink, c), **p.to_json()})
            for s in b.post_steps:
                out.append({"kind": "post", "material": b.material, "step": s})
        return out


def load_part_mesh(job: ResolvedJob, part) -> Mesh:
    """A part's mesh in the job's model frame (mm).

    Parameters
    ----------
    job : ResolvedJob
        A relative mesh path is resolved against its ``base_dir``.
    part : PartSpec
        Its mesh file (read in its ``units``) or built-in shape, moved by its
        ``rotate_deg`` then ``translate_mm``.

    Returns
    -------
    Mesh

    Raises
    ------
    ConfigError
        ``rotate_deg`` or ``translate_mm`` is not three finite numbers, or unknown ``units``.
    InputFileError, MeshError
        The mesh file cannot be read or is not a usable mesh (see
        :func:`rotoprint.io.mesh.load_mesh`).
    """
    from ..io.mesh import load_mesh, make_transform

    T = make_transform(translate_mm=tuple(part.translate_mm), rotate_deg=tuple(part.rotate_deg), scale=1.0)
    if part.mesh is not None:
        from pathlib import Path

        p = Path(part.mesh)
        return load_mesh(p if p.is_absolute() else job.base_dir / p, units=part.units, transform=T)
    mesh = Mesh.from_triangles(part.shape.triangles(), source=f"shape {part.shape.kind} (part {part.name})")
    return mesh if np.array_equal(T, np.eye(4)) else mesh.transformed(T)


class BuildPlan:
    """A planned multi-material job. :meth:`layer` makes one layer's schedule and images."""

    def __init__(self, job: ResolvedJob, device: InkjetDevice, meshes: dict[str, Mesh], heads: tuple[HeadSetup, ...],
                 estimates: dict[str, MaterialEstimate], warnings: list[str], planar: dict | None = None) -> None:
        self.job = job
        #: layer parts (Gerber, Excellon, DXF, SVG): their exact polygons, sliced without a mesh
        self.planar = dict(planar or {})
        self._planar_segments = {n: pl.segments() for n, pl in self.planar.items()}
        self.device = device
        self.meshes = meshes
        self.heads = heads
        self.estimates = estimates
        self.warnings = warnings
        h0 = heads[0].lattice
        self.layers = h0.layers
        self.placement: PartPlacement = dataclasses.replace(h0.part, angle_deg=job.spec.placement.angle_deg)
        lh = job.spec.job.layer_height_mm
        self._slicers = {n: slice_mesh(m, device, layer_height_mm=lh) for n, m in meshes.items() if n not in self.planar}

    def __len__(self) -> int:
        return len(self.layers)

    @property
    def material_order(self) -> list[str]:
        return self.job.material_order

    def head(self, name_or_ink: str) -> HeadSetup:
        for h in self.heads:
            if name_or_ink in (h.name, h.ink):
                return h
        raise ConfigError(f"no head named or carrying {name_or_ink!r}")

    def design_grid(self, *, oversample: int = 1) -> Placement:
        """The assembly's Cartesian grid at the first head's pitch, in the job's placement."""
        d = self.heads[0].lattice.design
        return self.placement.design_placement(d.pitch_x_mm, d.pitch_y_mm, oversample=oversample)

    def sections(self, index: int) -> dict[str, Segments]:
        """Exact cross-sections (model XY) of every part in layer ``index``."""
        z = float(self.layers.z_slice_mm[index])
        out = {n: s.segments_at(z)[0] for n, s in self._slicers.items()}
        for n, pl in self.planar.items():
            out[n] = self._planar_segments[n] if pl.contains_z(z) else _EMPTY_SEGMENTS
        return out

    def part_terminals(self, name: str) -> dict:
        """Named terminals of a part: rectangles ``(x0, y0, x1, y1)`` (built-in shapes, the
        part's ``terminals``) or pad polygons (a layer part's file and points), model frame."""
        part = self.job.part(name)
        terms = dict(part.shape.terminals()) if part.shape is not None else {}
        if name in self.planar:
            terms.update(self.planar[name].layer.terminals)
        terms.update(part.terminals)
        return terms

    def _higher(self, part) -> list[str]:
        return [q.name for q in self.job.spec.parts if q.material != part.material and q.priority > part.priority]

    def material_print(self, material: str, head: HeadSetup, sections: dict[str, Segments], index: int, *,
                       thinned: bool = True, pass_index: int = 0) -> RotaryPrint:
        """The print of ``material`` on ``head`` in layer ``index``, overlaps resolved, of
        interlaced pass ``pass_index`` (its own lattice, the pivots moved by its offset).

        ``thinned=False`` gives every lattice site inside the region (no density
        equalisation)."""
        qp = int(pass_index)
        if not 0 <= qp < head.passes:
            raise IndexError(f"pass {qp} out of range 0..{head.passes - 1}")
        lat = head.pass_lattices[qp] if thinned else head.pass_inside[qp]
        inside = head.pass_inside[qp]
        A = self.job.spec.placement.angle_deg
        levels = None
        pr0 = None
        for part in self.job.spec.parts:
            if part.material != material:
                continue
            seg = sections[part.name]
            blocks = [sections[q] for q in self._higher(part) if len(sections[q])]
            # the edge restore's region is the part minus the higher-priority parts (their drops go below)
            pr = lat.print_from_segments(seg, layer_index=index, cut=blocks)
            lv = [s.levels for s in pr.swathes]  # pr is this call's own print: its images are edited in place, not copied
            for q in blocks:
                ins = inside.print_from_segments(q, layer_index=index)
                for j, s in enumerate(ins.swathes):
                    lv[j][s.levels > 0] = 0
            levels = lv if levels is None else [np.maximum(a, b) for a, b in zip(levels, lv)]
            pr0 = pr
        if pr0 is None:
            raise ConfigError(f"no part is made of {material!r}")
        extra = {} if head.passes == 1 else {"pass": qp, "passes": head.passes, "pass_offset_mm": head.pass_offsets_mm[qp]}
        sw = tuple(dataclasses.replace(s, levels=lv, extra={**s.extra, **extra}) for s, lv in zip(pr0.swathes, levels))
        return dataclasses.replace(pr0, swathes=sw, mount_angle_deg=head.mount_angle_deg,
                                   placement=dataclasses.replace(pr0.placement, angle_deg=A))

    def layer(self, index: int) -> LayerSchedule:
        """Schedule and print-ready images of layer ``index``."""
        if not 0 <= index < len(self):
            raise IndexError(f"layer {index} out of range 0..{len(self) - 1}")
        sections = self.sections(index)
        images: dict[tuple[str, str], RotaryPrint] = {}
        pass_images: dict[tuple[str, str], tuple[RotaryPrint, ...]] = {}
        blocks = []
        t = 0.0
        for mname in self.material_order:
            mat: Material = self.job.materials[mname]
            if not any(len(sections[p.name]) for p in self.job.spec.parts if p.material == mname):
                continue
            drops, by_pass, inter = {}, {}, {}
            for ink in mat.inks:
                h = self.head(ink.name)
                prs = tuple(self.material_print(mname, h, sections, index, pass_index=q) for q in range(h.passes))
                images[(mname, ink.name)] = prs[0]
                pass_images[(mname, ink.name)] = prs
                by_pass[ink.name] = tuple(int(sum(np.count_nonzero(s.levels) for s in pr.swathes)) for pr in prs)
                drops[ink.name] = by_pass[ink.name][0]
                inter[ink.name] = h.passes
            if not any(any(v) for v in by_pass.values()):
                for ink in mat.inks:
                    images.pop((mname, ink.name), None)
                    pass_images.pop((mname, ink.name), None)
                continue
            est = self.estimates[mname]
            passes = tuple(
                PassStep(material=mname, ink=ink.name, head=self.head(ink.name).name, head_index=self.head(ink.name).index,
                         repeats=ink.repeats, wait_s=ink.wait_after_s)
                for ink in mat.inks
            )
            blk = MaterialBlock(material=mname, cycles=est.cycles, passes=passes,
                                post_steps=tuple(s.describe() for s in mat.post_steps), drops=drops,
                                thickness_um=est.per_layer_um, interlace=inter,
                                drops_by_pass=by_pass if any(n > 1 for n in inter.values()) else {})
            blocks.append(blk)
            for p in passes:
                h = self.heads[p.head_index]
                t += est.cycles * p.repeats * (sum(h.revolution_s) + p.wait_s)
            t += sum(s.duration_s for s in mat.post_steps)
        return LayerSchedule(index=index, z_bottom_mm=float(self.layers.z_bottom_mm[index]),
                             z_top_mm=float(self.layers.z_top_mm[index]), blocks=tuple(blocks), images=images, time_s=t,
                             pass_images=pass_images)

    def __iter__(self) -> Iterator[LayerSchedule]:
        for i in range(len(self)):
            yield self.layer(i)

    def reference_image(self, material: str, sections: dict[str, Segments], *, oversample: int = 1,
                        grid: Placement | None = None) -> np.ndarray:
        """``(H, W) bool``: the material's region (overlaps resolved) at the pixel centres of the
        assembly's grid (``oversample`` divides its pitch), or of ``grid``, a grid over the same
        rectangle (e.g. the deposit model's film grid, :func:`rotoprint.rotary.deposit.film_grid`
        of :meth:`design_grid`)."""
        grid = self.design_grid(oversample=oversample) if grid is None else grid
        out = np.zeros((grid.height_px, grid.width_px), bool)
        for part in self.job.spec.parts:
            if part.material != material or not len(sections[part.name]):
                continue
            m = rasterize_section(sections[part.name], self.placement, grid) > 0
            for q in self._higher(part):
                if len(sections[q]):
                    m &= ~(rasterize_section(sections[q], self.placement, grid) > 0)
            out |= m
        return out

    def to_json(self) -> dict:
        sp = self.job.spec
        return {
            "job": sp.job.model_dump(mode="json"),
            "device": self.device.name,
            "head_model": self.device.head.model_dump(mode="json"),
            "placement": self.placement.to_json(),
            "layers": len(self),
            "layer_height_mm": sp.job.layer_height_mm,
            "material_order": self.material_order,
            "materials": {n: m.model_dump(mode="json") for n, m in self.job.materials.items()},
            "parts": [p.model_dump(mode="json", exclude_none=True) for p in sp.parts],
            "layer_parts": [pl.to_json(self.job.part(n).material) for n, pl in self.planar.items()],
            "heads": [h.to_json() for h in self.heads],
            "estimates": {n: e.to_json() for n, e in self.estimates.items()},
            "warnings": list(self.warnings),
        }


def _band(plan_part: PartPlacement, meshes: list[Mesh]) -> tuple[float, float]:
    lo = np.min([m.bounds[0][:2] for m in meshes], axis=0)
    hi = np.max([m.bounds[1][:2] for m in meshes], axis=0)
    xs = np.array([lo[0], hi[0]])
    ys = np.array([lo[1], hi[1]])
    xl, yl = plan_part.model_to_local(xs, ys)
    r_in = float(xl[0]) if yl[0] <= 0 <= yl[1] else float(min(np.hypot(xl[0], yl[0]), np.hypot(xl[0], yl[1])))
    r_out = float(max(np.hypot(xl[1], yl[0]), np.hypot(xl[1], yl[1])))
    return r_in, r_out


#: Width of the radial bins of the measured drop density, mm.
DENSITY_BIN_MM = 1.0
#: Smallest share of the median bin's design area for a bin to count (slivers at the ends).
DENSITY_BIN_MIN_SHARE = 0.1


def measured_drop_density(plan: BuildPlan, material: str, band: tuple[float, float]) -> tuple[np.ndarray, dict[str, np.ndarray], dict]:
    """The true drops per mm^2 of one pass of each of the material's inks, per radial bin.

    The material's first layer with a cross-section is printed on every interlaced pass of
    each ink's head (the planned, thinned images) and its drops landed
    (:func:`~rotoprint.rotary.simulate.place_drops`). Only the design's *interior* counts: the
    material's region rasterised on the deposit model's film grid
    (:func:`~rotoprint.rotary.deposit.film_grid` of the design grid) less the boundary band of
    the deposit figures (half a footprint plus half a cell), so tracks that graze an edge do
    not weigh in. Every drop landing in an interior cell (a level ``L`` of ``G`` counts ``L /
    G`` of a full drop) is counted at its landing radius, the interior's area (its cells, each
    at its centre's radius) in the same 1 mm radial bins; drops over area, divided by the
    passes, is one pass's density.

    Parameters
    ----------
    plan : BuildPlan
    material : str
    band : (float, float)
        The material's radial band, mm (the bins' range).

    Returns
    -------
    r_mm : (B,) float64
        Centres of the bins whose interior holds at least :data:`DENSITY_BIN_MIN_SHARE` of the
        median bin's.
    density : dict of str to (B,) float64
        Drops per mm^2 of one pass, per ink.
    source : dict
        ``layer``, ``bin_mm``, ``bins``, ``drops`` (per ink, all passes, in the interior),
        ``area_mm2`` (that layer's interior area), ``cell_um`` (the film grid's cells) and the
        ``rule``, for ``plan.json``.
    """
    from ..rotary.deposit import DepositOptions, film_grid, interior_mask, radial_area_mm2
    from ..rotary.simulate import place_drops

    parts = [p.name for p in plan.job.spec.parts if p.material == material]
    layer, secs = None, None
    for i in range(len(plan)):
        sc = plan.sections(i)
        if any(len(sc[n]) for n in parts):
            layer, secs = i, sc
            break
    lo, hi = band
    nb = max(1, math.ceil((hi - lo) / DENSITY_BIN_MM - 1e-9))
    edges = lo + DENSITY_BIN_MM * np.arange(nb + 1)
    if layer is None:
        return np.zeros(0), {ink.name: np.zeros(0) for ink in plan.job.materials[material].inks}, {"layer": None}
    head = plan.device.head
    grid = plan.design_grid()
    fine = film_grid(grid, head)
    nx, ny = fine.width_px // grid.width_px, fine.height_px // grid.height_px
    gx_um, gy_um = fine.pitch_x_mm * 1e3, fine.pitch_y_mm * 1e3
    inner = interior_mask(plan.reference_image(material, secs, grid=fine), gx_um, gy_um,
                          0.5 * DepositOptions().full_footprint_um(head) + 0.5 * min(gx_um, gy_um))
    area = radial_area_mm2(inner, fine, edges)
    keep = area > 0
    if keep.any():
        keep &= area >= DENSITY_BIN_MIN_SHARE * float(np.median(area[keep]))
    dens, drops = {}, {}
    g = head.grey_levels
    for ink in plan.job.materials[material].inks:
        h = plan.head(ink.name)
        counts = np.zeros(nb)
        total = 0.0
        for q in range(h.passes):
            d = place_drops(plan.material_print(material, h, secs, layer, pass_index=q))
            ci = np.floor(d.col * nx).astype(np.int64)
            ri = np.floor(d.row * ny).astype(np.int64)
            ok = (ci >= 0) & (ci < fine.width_px) & (ri >= 0) & (ri < fine.height_px)
            ok[ok] = inner[ri[ok], ci[ok]]
            w = np.asarray(d.level, np.float64)[ok] / g
            counts += np.histogram(np.hypot(d.x_mm[ok], d.y_mm[ok]), bins=edges, weights=w)[0]
            total += float(w.sum())
        with np.errstate(invalid="ignore", divide="ignore"):
            dens[ink.name] = (counts / h.passes / area)[keep]
        drops[ink.name] = total
    centres = 0.5 * (edges[:-1] + edges[1:])
    return centres[keep], dens, {"layer": layer, "bin_mm": DENSITY_BIN_MM, "bins": int(keep.sum()), "drops": drops,
                                 "area_mm2": float(area.sum()), "cell_um": [gx_um, gy_um],
                                 "rule": "drops of every interlaced pass of the material's first layer landing in its "
                                         "interior (the design on the film grid less half a footprint), per landing "
                                         "radius, over the interior's area per radial bin, divided by the passes"}


def _estimate(plan: BuildPlan, mat: Material, band: tuple[float, float], v_pl: float, layer_um: float) -> MaterialEstimate:
    job = plan.job
    sp = job.spec.process
    r, dens, source = measured_drop_density(plan, mat.name, band)
    if not r.size:  # no drop at all (a part thinner than the lattice): the lattice's nominal density
        r = np.linspace(band[0], band[1], _PROFILE_SAMPLES)
        dens = {ink.name: plan.head(ink.name).density_at(r) for ink in mat.inks}
        source = {**source, "rule": "no drop in the material's first layer: the lattice's nominal density"}
    t_cyc = np.asarray(cycle_thickness_um(mat, v_pl, dens), np.float64)
    t_min, t_max = float(t_cyc.min()), float(t_cyc.max())
    wet = {k: (float(wet_film_um(v_pl, d.min())), float(wet_film_um(v_pl, d.max()))) for k, d in dens.items()}
    n_inter = max(plan.head(ink.name).passes for ink in mat.inks)
    name = mat.name
    if not t_min > 0:
        raise ConfigError(f"{name}: its first layer gets no drop on some inks ({', '.join(k for k, d in dens.items() if not (d > 0).all())}); "
                          "a larger part, a finer clock or another placement", path=job.source)
    bare = cycles_for_height(layer_um, t_min)  # the fewest cycles that reach the layer
    needed = n_inter * math.ceil(bare / n_inter) if n_inter > 1 else bare  # every pass printed equally often
    ppc = mat.passes_per_cycle
    warn = []
    if name in sp.cycles_per_layer:
        cycles = sp.cycles_per_layer[name]
        if cycles * t_min < (1 - SHORTFALL_WARN) * layer_um:
            warn.append(f"{name}: {cycles} cycle(s) per layer (set in the job) make {cycles * t_min:.3g} um at the "
                        f"thinnest point, {100 * (1 - cycles * t_min / layer_um):.0f} % short of the {layer_um:g} um "
                        f"layer; {needed} cycles would reach it")
        if n_inter > 1 and cycles % n_inter:
            warn.append(f"{name}: {cycles} cycle(s) per layer (set in the job) are not a multiple of the {n_inter} "
                        f"interlaced passes: some passes print {cycles // n_inter + 1} times, others {cycles // n_inter}")
    elif needed * ppc > sp.max_passes_per_layer and bare * ppc <= sp.max_passes_per_layer:
        # the layer is reached within the limit, only not in a whole number of rounds of the passes
        cycles = bare
        if n_inter > 1 and cycles % n_inter:
            warn.append(f"{name}: {needed} cycles (a multiple of the {n_inter} interlaced passes) would exceed "
                        f"process.max_passes_per_layer = {sp.max_passes_per_layer}; planned {cycles}: some passes print "
                        f"{cycles // n_inter + 1} times, others {cycles // n_inter}")
    elif needed * ppc > sp.max_passes_per_layer:
        cycles = max(1, sp.max_passes_per_layer // ppc)
        warn.append(f"{name}: reaching the {layer_um:g} um layer needs {bare} cycles ({bare * ppc} passes) at "
                    f"{t_min * 1000:.3g} nm per cycle, more than process.max_passes_per_layer = "
                    f"{sp.max_passes_per_layer}; planned {cycles} cycles ({cycles * t_min:.3g} um, "
                    f"{100 * (1 - cycles * t_min / layer_um):.0f} % short): use a thinner layer, stronger inks or "
                    f"set process.cycles_per_layer.{name}")
    else:
        cycles = needed
    if n_inter > 1 and cycles < n_inter:
        warn.append(f"{name}: {cycles} cycle(s) per layer print only {cycles} of the {n_inter} interlaced passes: "
                    "the film has the gaps of fewer passes")
    if t_max > (1 + THICKNESS_SPREAD_WARN) * t_min:
        r_thin, r_thick = float(r[int(np.argmin(t_cyc))]), float(r[int(np.argmax(t_cyc))])
        todo = ("the equalised drops per area of its first layer's interior still vary: more interlaced passes "
                "(printer.passes) or a finer clock (printer.clock.dpi_y) average the thinning out"
                if job.spec.printer.equalise else "1/r drop density of one angular clock: set printer.equalise = true")
        warn.append(f"{name}: the thickness per cycle varies by {100 * (t_max / t_min - 1):.1f} % over radii "
                    f"{band[0]:.1f}-{band[1]:.1f} mm, thinnest in the 1 mm bin at {r_thin:.1f} mm, thickest at "
                    f"{r_thick:.1f} mm; the cycles are planned for the thinnest ({todo})")
    for ink in mat.inks:
        if ink.warning:
            warn.append(f"{name}: {ink.warning}")
    warn.extend(f"{name}: {w}" for w in mat.warnings)
    return MaterialEstimate(
        material=name, band_mm=band, per_pass_wet_um=wet, per_cycle_um=(t_min, t_max), cycles=cycles,
        cycles_needed=needed, passes_per_layer=cycles * ppc, per_layer_um=(cycles * t_min, cycles * t_max),
        profile_r_mm=np.asarray(r, np.float64), profile_per_layer_um=cycles * t_cyc, warnings=tuple(warn),
        interlace_passes=n_inter, density_source=source, drops_per_mm2=dens,
    )


def plan_job(job: ResolvedJob, *, backend: str = "jit") -> BuildPlan:
    """Plan a validated job: meshes, head lattices, estimates (images come per layer).

    Parameters
    ----------
    job : ResolvedJob
        From :func:`rotoprint.process.load_job` or :func:`~rotoprint.process.parse_job`.
    backend : {'jit', 'numpy'}
        Direct slicer kernel: compiled or the pure-numpy reference (identical output).

    Returns
    -------
    BuildPlan
    """
    sp = job.spec
    device = load_device(job.device_spec())
    if not isinstance(device, InkjetDevice):
        raise ConfigError(f"printer.device: {device.name!r} is not an inkjet head; a multi-material job needs print heads",
                          path=job.source)
    meshes = {}
    planar = {}
    for i, p in enumerate(sp.parts):
        try:
            if p.layer is not None:
                from .cadparts import default_tolerance, load_layer_part

                planar[p.name] = load_layer_part(job.base_dir, p, default_tolerance_mm=default_tolerance(device.head.pitch_mm))
                # the extruded polygon (vertical walls): only for the footprint and the printability check
                meshes[p.name] = planar[p.name].mesh()
            else:
                meshes[p.name] = load_part_mesh(job, p)
        except RotoprintError as exc:
            kind = 'mesh' if p.mesh else 'shape' if p.shape else 'layer'
            raise type(exc)(f"parts[{i}].{kind} (part {p.name!r}, referenced by {job.source or 'the job'}): "
                            f"{exc.problem}", path=exc.path) from None
    for i, r in enumerate(sp.resistance):
        if r.part in planar:
            avail = {**planar[r.part].layer.terminals, **job.part(r.part).terminals}
            for t in r.between:
                if t not in avail:
                    raise ConfigError(f"resistance[{i}].between: part {r.part!r} has no terminal {t!r}; its layer "
                                      f"{planar[r.part].file} has: {', '.join(sorted(avail)) or 'none'}", path=job.source)
    union = Mesh.from_triangles(np.concatenate([m.triangles for m in meshes.values()]), source="assembly")
    used_inks = {ink.name for m in job.materials.values() for ink in m.inks}
    clk = sp.printer.clock
    warnings: list[str] = []
    heads: list[HeadSetup] = []
    interlace_cache: dict[float, tuple] = {}
    for j, hs in enumerate(sp.printer.heads):
        if hs.ink not in used_inks:
            continue
        tilt = sp.printer.tilt_deg if hs.tilt_deg is None else hs.tilt_deg
        # the edge restore of the thinned tracks (printer.edge_restore: on where equalised on a binary head)
        edge = EdgeRestore() if sp.printer.edge_restore and sp.printer.equalise and device.head.grey_levels == 1 else None
        common = dict(layer_height_mm=sp.job.layer_height_mm, tilt_deg=tilt, inner_radius_mm=sp.placement.inner_radius_mm,
                      angle_deg=sp.placement.angle_deg - hs.mount_angle_deg, ref_radius_mm=clk.ref_radius_mm,
                      direction=sp.printer.direction, max_swathes=sp.printer.max_swathes, equalise=sp.printer.equalise,
                      backend=backend)
        try:
            lat = slice_rotary(union, device, dpi_y=clk.dpi_y, edge_restore=edge, **common)
            if sp.printer.passes == 1:
                lats, pp, offsets = [lat], None, (0.0,)
                info = {"passes": 1, "clock": "job" if clk.dpi_y is not None else "head", "dpi_y": lat.dpi_y,
                        "edge_restore": lat.edge_restore_record()}
            else:
                if tilt not in interlace_cache:
                    interlace_cache[tilt] = _interlace(union, device, lat, common, sp, warnings)
                pp, clock, info, shares = interlace_cache[tilt]
                offsets = pp.offsets_mm
                if shares is None:
                    lats = [slice_rotary(union, device, dpi_y=clock, pivot_offset_mm=o, edge_restore=edge, **common)
                            for o in offsets]
                    info = {**info, "edge_restore": lats[0].edge_restore_record()}
                else:  # the union's shares replace the per-pass equalisation
                    lats = [slice_rotary(union, device, dpi_y=clock, pivot_offset_mm=o, **{**common, "equalise": False},
                                         shares=shares[q], pass_index=q, edge_restore=edge) for q, o in enumerate(offsets)]
                    info = {**info, "edge_restore": lats[0].edge_restore_record()}
        except RotoprintError as exc:
            fld = "printer.tilt_deg" if hs.tilt_deg is None else f"printer.heads[{j}].tilt_deg"
            if "tilt" not in exc.problem:
                fld = f"printer.heads[{j}] ({hs.name})"
            if exc.problem.startswith("printer."):
                raise ConfigError(exc.problem, path=job.source) from None
            raise ConfigError(f"{fld}: {exc.problem}", path=job.source) from None
        lat = lats[0]
        insides = tuple(DirectSliceJob(la.slice_job, la.head, la.part, la.design, la.plan, la.tracks,
                                       options=dataclasses.replace(la.options, equalise=False), dpi_y=la.dpi_y) for la in lats)
        r, dens = track_density_per_mm2(lat.tracks, equalised=sp.printer.equalise, shares=lat.shares)
        f = device.head.max_frequency_hz if clk.frequency_hz is None else clk.frequency_hz
        if f > device.head.max_frequency_hz:
            raise ConfigError(f"printer.clock.frequency_hz: {f:g} Hz is above the head's maximum "
                              f"{device.head.max_frequency_hz:g} Hz", path=job.source)
        rev = tuple(2 * math.pi / t.dphi_rad / f for t in lat.tracks)
        heads.append(HeadSetup(index=j, name=hs.name, ink=hs.ink, mount_angle_deg=hs.mount_angle_deg, tilt_deg=tilt,
                               lattice=lat, inside=insides[0], r_mm=r, density_per_mm2=dens, frequency_hz=f, revolution_s=rev,
                               pass_lattices=tuple(lats), pass_inside=insides, pass_offsets_mm=tuple(offsets), pass_plan=pp,
                               interlace=info))
    part0 = heads[0].lattice.part
    v_pl = device.head.drop_volume_pl
    layer_um = sp.job.layer_height_mm * 1000
    plan = BuildPlan(job, device, meshes, tuple(heads), {}, warnings, planar=planar)
    for mname, mat in job.materials.items():
        band = _band(part0, [meshes[p.name] for p in sp.parts if p.material == mname])
        est = _estimate(plan, mat, band, v_pl, layer_um)
        plan.estimates[mname] = est
        warnings.extend(est.warnings)
    log.debug("planned %d layers, %d heads", len(heads[0].lattice), len(heads))
    return plan


def _interlace(union: Mesh, device, lat: DirectSliceJob, common: dict, sp, warnings: list[str]) -> tuple:
    """The pass plan of one tilt, its clock and the ``interlace`` record (see :func:`plan_job`)."""
    from ..errors import GeometryError
    from ..rotary.deposit import DepositOptions
    from ..rotary.interlace import plan_passes

    head = device.head
    n = None if sp.printer.passes == "auto" else int(sp.printer.passes)
    d_um = DepositOptions().full_footprint_um(head)
    try:
        pp = plan_passes(head, lat.plan, footprint_um=d_um, passes=n)
    except GeometryError as exc:
        raise ConfigError(f"printer.passes: {exc.problem}") from None
    clk = sp.printer.clock
    if clk.dpi_y is None:
        clock = pp.dpi_y
        src = "pass plan"
    else:
        clock = float(clk.dpi_y)
        src = "job"
        if 25.4 / clock > pp.along_track_mm * (1 + 1e-9):
            warnings.append(f"printer.clock.dpi_y: {clock:g} dpi spaces drops {25.4e3 / clock:.1f} um along the track, "
                            f"more than the {pp.along_track_mm * 1e3:.1f} um the {d_um:.1f} um footprints close with "
                            f"{pp.passes} interlaced pass(es): the film will have gaps (leave dpi_y out to use the plan's clock)")
    info = {"passes": pp.passes, "clock": src, "dpi_y": clock, "plan_dpi_y": pp.dpi_y,
            "footprint_um": d_um, "largest_gap_um": pp.largest_gap_mm * 1e3,
            "single_pass_largest_gap_um": pp.single_pass_largest_gap_mm * 1e3,
            "dead_nozzles": list(pp.dead_nozzles), "dead_track_cover_um": [c * 1e3 for c in pp.dead_track_cover_mm],
            "equalise": "union shares" if sp.printer.equalise and pp.passes > 1 else
            ("per track" if sp.printer.equalise else False)}
    shares = None
    if sp.printer.equalise and pp.passes > 1:
        # the shares of the union of the passes (as transform --passes --equalise), once per plan,
        # printed at EQUALISE_CLOCK_FACTOR x the clock; with dead nozzles their tracks covered
        from ..rotary.direct import union_pass_shares

        lat_c = slice_rotary(union, device, dpi_y=clock, **{**common, "equalise": False})
        shares, clock, eq = union_pass_shares(head, lat_c.plan, pp.offsets_mm, dpi_y=clock, ref_radius_mm=clk.ref_radius_mm,
                                              footprint_um=d_um)
        info.update(dpi_y=clock, union_shares={k: v for k, v in eq.items() if k != "dead_cover"}, dead_cover=eq["dead_cover"])
    return pp, clock, info, shares
