"""Printability: what a part loses on a device, layer by layer.

Widths are measured on the cross-section (the slicer's segments, their chains simplified to
``resolution_mm``, 1/100 pixel by default: widths within twice that of the exact section's; 0
measures on the section as sliced), not on the image: from sample points at most half a pixel
apart along the boundary, a ray along the inward normal
meets the other side of the wall after exactly the wall's width, and one along the outward
normal crosses the gap to the next material. A wall narrower than the minimum is what an
opening by a disc of that diameter removes, a gap narrower than the minimum what a closing
fills; the rays find both without the opening's artefacts (an opening also shaves every convex
corner, a closing fills every concave one) and find walls too thin to hold a single pixel.

Against the image (the device raster at the given fibre angle):

- ``vanished_wall``: a wall with no material pixel centre in it (over two pixels of its length);
- ``closed_gap``: a gap with no empty pixel centre in it (the two sides merge);
- ``island``: a connected region (8-neighbours) with no material pixel directly below it;
- with an exposure model (DLP masks): ``underexposed`` walls whose peak grey along their width
  stays below the cure threshold, and ``cured_gap`` gaps whose darkest pixel across is above it;
- ``cavity``: empty space the part shuts in on every side (a resin trap), found on the layers'
  runs of empty pixels joined through the layers (:mod:`._cavities`).

See ``docs/check.md``.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np

from ..errors import ConfigError
from ..mesh import Mesh
from . import _kernels as K
from ._cavities import CavityTracker
from .limits import device_limits
from .options import EXPOSURE_TEST_PX, RASTER_TEST_PX, CheckOptions, CheckSettings, resolution_for

__all__ = [
    "KINDS", "Finding", "LayerCheck", "CheckReport", "CheckOptions", "check_layers", "check_printability", "compare_orientations", "join_regions",
    "resolution_for",
]

log = logging.getLogger(__name__)

#: Problem kinds, in the order they are reported.
KINDS: tuple[str, ...] = ("thin_wall", "narrow_gap", "vanished_wall", "closed_gap", "island", "underexposed", "cured_gap", "cavity")

#: Side offset (mm) at which the fill rule is evaluated to tell boundary from inner segments.
_SIDE_EPS_MM = 1e-7
#: Segments of different chains closer than this (mm) without meeting are classified one by one.
_NEAR_MM = 1e-5
#: Rays ignore hits nearer than this (mm): the segment a sample lies on, and touching ends.
_RAY_TMIN_MM = 1e-9
#: Smallest side of the cells (in pixels) in which rays look for the other side of a wall or gap
#: (cells grow where segments are sparse, see ``_kernels.grid._cell_size``).
_CELL_PX = 0.5
#: Samples along the boundary at most this many pixels apart.
_SPACING_PX = 0.5
#: Chords of one kind closer than this many pixels are reported as one finding.
_GROUP_PX = 1
#: Walls and gaps narrower than these many pixels are tested against the raster and the
#: exposure (:mod:`.options`).
_RASTER_TEST_PX = RASTER_TEST_PX
_EXPOSURE_TEST_PX = EXPOSURE_TEST_PX


@dataclass(frozen=True)
class Finding:
    """One problem region in one layer.

    ``x_mm, y_mm`` (model frame) and ``col, row`` (device pixel) locate its worst point: the
    middle of its narrowest chord, or an island's centroid. ``width_mm`` is that narrowest
    width (``None`` for islands); ``length_mm`` the boundary length it spans (half of it is
    each side of a wall); ``area_mm2`` an island's area; ``value`` the peak (underexposed) or
    lowest (cured gap) exposure as a fraction of full.

    A ``cavity`` (empty space the part shuts in on every side: resin that cannot drain) is
    reported at the layer that closes it over (its roof), with ``first_layer`` and
    ``first_z_mm`` the first layer it is in, ``volume_mm3`` its volume (pixels times pixel
    area times layer height), its centroid and its box over all its layers.
    """

    kind: str
    layer: int
    z_mm: float
    x_mm: float
    y_mm: float
    col: float
    row: float
    width_mm: float | None = None
    length_mm: float | None = None
    area_mm2: float | None = None
    value: float | None = None
    bbox_mm: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    volume_mm3: float | None = None
    first_layer: int | None = None
    first_z_mm: float | None = None

    def to_json(self) -> dict:
        d = asdict(self)
        d["bbox_mm"] = list(self.bbox_mm)
        return d


class LayerCheck:
    """What one layer's check found, with what an overlay needs.

    ``image`` is the layer's ``(H, W) uint8`` device image (the slicer's), ``chords[kind]``
    ``(n, 4) float64`` pixel-index chords ``(col0, row0, col1, row1)`` across each problem
    wall or gap (for a cavity, the four sides of its box); ``islands`` the ``(H, W) bool`` unsupported pixels (``None``: no island).
    The check itself works on the exact section and the layer's runs of material; the two
    images are made when they are first read.
    """

    __slots__ = ("index", "z_mm", "_image", "findings", "chords", "_islands", "thinnest_wall", "narrowest_gap")

    def __init__(self, index, z_mm, image, findings, chords, islands, thinnest_wall, narrowest_gap) -> None:
        self.index = index
        self.z_mm = z_mm
        self._image = image  # an array, or a function making it
        self.findings = findings
        self.chords = chords
        self._islands = islands  # None, an array, or a function making it
        self.thinnest_wall = thinnest_wall
        self.narrowest_gap = narrowest_gap

    @property
    def image(self) -> np.ndarray:
        if callable(self._image):
            self._image = self._image()
        return self._image

    @image.setter
    def image(self, value) -> None:
        self._image = value

    @property
    def islands(self) -> np.ndarray | None:
        if callable(self._islands):
            self._islands = self._islands()
        return self._islands

    @islands.setter
    def islands(self, value) -> None:
        self._islands = value

    def __repr__(self) -> str:
        return (
            f"LayerCheck(index={self.index}, z_mm={self.z_mm}, findings={len(self.findings)}, "
            f"thinnest_wall={self.thinnest_wall}, narrowest_gap={self.narrowest_gap})"
        )


def join_regions(findings: Sequence[Finding], grow_mm: float = 0.0) -> list[dict]:
    """Findings of one kind in consecutive layers whose bounding boxes (grown by ``grow_mm``)
    overlap, joined into regions through the part: one thin fin is one region, not one
    finding per layer. A cavity is one region as it is (its finding is the whole body).

    Returns one dict per region, in order of kind (:data:`KINDS`), first layer and position:
    ``kind``, ``first_layer``, ``last_layer``, ``z_mm`` ``[lo, hi]``, ``findings`` (how many),
    ``width_mm`` (narrowest; ``None`` for islands), ``area_mm2`` (islands: summed over the
    layers), ``layer``, ``x_mm``, ``y_mm`` (the worst finding: narrowest, or largest island)
    and ``bbox_mm`` (x0, y0, x1, y1 over the layers).
    """
    out: list[dict] = []
    for kind in KINDS:
        fs = [f for f in findings if f.kind == kind]
        if not fs:
            continue
        if kind == "cavity":  # each is one body through its layers already: never joined
            out.extend(_cavity_region(f) for f in sorted(fs, key=lambda f: (f.first_layer, f.bbox_mm[1], f.bbox_mm[0])))
            continue
        n = len(fs)
        parent = list(range(n))

        def find(i: int) -> int:
            while parent[i] != i:
                parent[i] = parent[parent[i]]
                i = parent[i]
            return i

        box = np.array([f.bbox_mm for f in fs], dtype=np.float64).reshape(n, 4)
        box[:, :2] -= grow_mm
        box[:, 2:] += grow_mm
        layer = np.array([f.layer for f in fs])
        by_layer: dict[int, np.ndarray] = {}
        for L in np.unique(layer):
            by_layer[int(L)] = np.flatnonzero(layer == L)
        for L, a in by_layer.items():
            b = by_layer.get(L + 1)
            if b is None:
                continue
            for k in range(0, a.size, 1024):  # bounded memory for many findings per layer
                ak = a[k : k + 1024]
                A, B = box[ak][:, None, :], box[b][None, :, :]
                hit = (A[..., 0] <= B[..., 2]) & (B[..., 0] <= A[..., 2]) & (A[..., 1] <= B[..., 3]) & (B[..., 1] <= A[..., 3])
                for i, j in zip(*np.nonzero(hit)):
                    ri, rj = find(int(ak[i])), find(int(b[j]))
                    if ri != rj:
                        parent[ri] = rj
        groups: dict[int, list[int]] = {}
        for i in range(n):
            groups.setdefault(find(i), []).append(i)
        regs = []
        for members in groups.values():
            g = [fs[i] for i in members]
            if kind == "island":
                worst = max(g, key=lambda f: f.area_mm2 or 0.0)
            else:
                worst = min(g, key=lambda f: f.width_mm)
            regs.append(
                {
                    "kind": kind,
                    "first_layer": min(f.layer for f in g),
                    "last_layer": max(f.layer for f in g),
                    "z_mm": [min(f.z_mm for f in g), max(f.z_mm for f in g)],
                    "findings": len(g),
                    "width_mm": worst.width_mm,
                    "area_mm2": sum(f.area_mm2 or 0.0 for f in g) if kind == "island" else None,
                    "volume_mm3": None,
                    "layer": worst.layer,
                    "x_mm": worst.x_mm,
                    "y_mm": worst.y_mm,
                    "bbox_mm": [min(f.bbox_mm[0] for f in g), min(f.bbox_mm[1] for f in g), max(f.bbox_mm[2] for f in g), max(f.bbox_mm[3] for f in g)],
                }
            )
        regs.sort(key=lambda r: (r["first_layer"], r["bbox_mm"][1], r["bbox_mm"][0]))
        out.extend(regs)
    return out


def _cavity_region(f: Finding) -> dict:
    first = f.layer if f.first_layer is None else f.first_layer
    return {
        "kind": f.kind,
        "first_layer": first,
        "last_layer": f.layer,
        "z_mm": [f.z_mm if f.first_z_mm is None else f.first_z_mm, f.z_mm],
        "findings": 1,
        "width_mm": None,
        "area_mm2": None,
        "volume_mm3": f.volume_mm3,
        "layer": f.layer,
        "x_mm": f.x_mm,
        "y_mm": f.y_mm,
        "bbox_mm": list(f.bbox_mm),
    }


@dataclass
class CheckReport:
    """The result of :func:`check_printability`; ``to_json()`` gives the JSON report."""

    device: str
    settings: dict
    grid: dict
    n_layers: int
    limits: dict
    findings: list[Finding] = field(default_factory=list)
    thinnest_wall: dict | None = None
    narrowest_gap: dict | None = None
    layers_with_findings: list[int] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.findings

    def counts(self) -> dict[str, int]:
        return {k: sum(1 for f in self.findings if f.kind == k) for k in KINDS}

    def regions(self) -> list[dict]:
        """The findings joined through the layers (:func:`join_regions`, boxes grown by one
        pixel): what a user fixes, one entry per feature."""
        pitch = max(self.grid.get("pitch_x_mm", 0.0), self.grid.get("pitch_y_mm", 0.0)) if isinstance(self.grid, dict) else 0.0
        return join_regions(self.findings, pitch)

    def lengths_mm(self) -> dict[str, float]:
        out = {k: 0.0 for k in KINDS}
        for f in self.findings:
            out[f.kind] += f.length_mm or 0.0
        return out

    def loss_mm(self) -> float:
        """Boundary length (mm) that the raster or the exposure loses: vanished walls, closed
        gaps, underexposed walls and cured gaps (the orientation-dependent problems)."""
        L = self.lengths_mm()
        return L["vanished_wall"] + L["closed_gap"] + L["underexposed"] + L["cured_gap"]

    def to_json(self) -> dict:
        return {
            "ok": self.ok,
            "device": self.device,
            "settings": self.settings,
            "limits": self.limits,
            "n_layers": self.n_layers,
            "thinnest_wall": self.thinnest_wall,
            "narrowest_gap": self.narrowest_gap,
            "counts": self.counts(),
            "lengths_mm": self.lengths_mm(),
            "island_area_mm2": sum(f.area_mm2 or 0.0 for f in self.findings if f.kind == "island"),
            "cavity_volume_mm3": sum(f.volume_mm3 or 0.0 for f in self.findings if f.kind == "cavity"),
            "layers_with_findings": self.layers_with_findings,
            "regions": self.regions(),
            "grid": self.grid,
            "findings": [f.to_json() for f in self.findings],
        }


# ----------------------------------------------------------------------------- helpers


def _affine_apply(m: np.ndarray, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return m[0, 0] * x + m[0, 1] * y + m[0, 2], m[1, 0] * x + m[1, 1] * y + m[1, 2]


# ----------------------------------------------------------------------------- one layer


class _LayerChecker:
    """Everything fixed for a job: thresholds (the :class:`~.options.CheckSettings` ``st``),
    affines, sampling."""

    def __init__(self, job, st: CheckSettings, grey_fn) -> None:
        g = job.grid
        min_wall_mm, min_gap_mm = st.min_wall_mm, st.min_gap_mm
        self.job = job
        self.grid = g
        self.m2p = np.ascontiguousarray(g.model_to_pixel)
        self.p2m = np.ascontiguousarray(g.pixel_to_model)
        self.pmax = max(g.pitch_x_mm, g.pitch_y_mm)
        self.spacing = _SPACING_PX * min(g.pitch_x_mm, g.pitch_y_mm)
        self.min_wall = min_wall_mm
        self.min_gap = min_gap_mm
        self.cap = st.measured_up_to_mm
        self.grey_fn = grey_fn
        self.thr = st.cure_threshold
        self.islands = st.islands
        self.cavities = CavityTracker(g.width, g.height) if st.cavities else None
        self.evenodd = job.fill == "evenodd"
        # widths the findings need exactly (the smallest one is measured up to the cap)
        lim = _RASTER_TEST_PX * self.pmax
        if grey_fn is not None:
            lim = max(lim, _EXPOSURE_TEST_PX * self.pmax)
        self.need_wall = max(min_wall_mm, lim)
        self.need_gap = max(min_gap_mm, lim)
        self.cell = _CELL_PX * min(g.pitch_x_mm, g.pitch_y_mm)
        # the slicer's own model-to-pixel affine (its fill's crossings are recomputed as runs)
        uv = np.ascontiguousarray(job.fill_affine, dtype=np.float64)
        self.params = K.LayerParams(
            uv, g.height, g.width, self.evenodd, self.cell, _NEAR_MM, _SIDE_EPS_MM, self.spacing, self.cap, _RAY_TMIN_MM,
            self.need_wall, self.need_gap, self.min_wall, self.min_gap, _RASTER_TEST_PX * self.pmax, self.p2m, self.m2p, self.pmax,
        )
        self._no_runs = (np.zeros(g.height + 1, np.int64), np.zeros(0, np.int64), np.zeros(0, np.int64))
        self.prev_runs: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
        self.resolution = float(st.resolution_mm)
        self._pos = np.full(0, -1, np.int32)  # edge -> segment buffer of simplify_section
        # canvas of emit_groups (all zeros between calls): the grid with a margin for chords
        # that reach past it
        self._canvas = np.zeros((g.height + 8) * (g.width + 8), np.int32)

    def _simplified(self, seg) -> tuple[np.ndarray, np.ndarray]:
        """The section on which widths are measured: as sliced, or simplified to the resolution."""
        if self.resolution <= 0.0 or len(seg) == 0:
            return seg.start, seg.end
        s, e, need = K.simplify_section(seg.start, seg.end, seg.start_edge, seg.end_edge, self.resolution, self._pos)
        if need:  # the edge buffer grows (once or twice per job)
            self._pos = np.full(max(need, 2 * self._pos.shape[0]), -1, np.int32)
            s, e, _ = K.simplify_section(seg.start, seg.end, seg.start_edge, seg.end_edge, self.resolution, self._pos)
        return s, e

    def run(self, index: int) -> LayerCheck:
        job = self.job
        seg, _ = job.segments(index)
        z = float(job.plan.z_slice_mm[index])
        findings: list[Finding] = []
        chords: dict[str, np.ndarray] = {}
        prev = self.prev_runs
        below = self.islands and prev is not None  # the first layer stands on the platform
        if prev is None:
            prev = self._no_runs
        # one call: the layer's runs of material (equal to the slicer's image, which the
        # check does not need), widths and selections, raster tests on the runs, islands
        ws, we = self._simplified(seg)
        res = K.check_layer((seg.start, seg.end), (ws, we), prev, below, self.params)
        rs, r0, r1 = res.rs, res.r0, res.r1
        if self.islands:
            self.prev_runs = (rs, r0, r1)
        image = lambda: job._fill(seg)  # noqa: E731 - the slicer's image, made when read
        thin_w = narrow_g = None
        if len(seg):
            bx, by, ux, uy, ln, wall, gap = res.samples
            thin_w = self._extreme(res.thinnest, wall, bx, by, ux, uy, +1.0, index, z)
            narrow_g = self._extreme(res.narrowest, gap, bx, by, ux, uy, -1.0, index, z)
            # widths against the thresholds, then against the raster
            for kind, idx, width, sgn in (
                ("thin_wall", res.thin, wall, 1.0), ("narrow_gap", res.narrow, gap, -1.0), ("vanished_wall", res.vanished, wall, 1.0), ("closed_gap", res.closed, gap, -1.0)
            ):
                if idx.size:
                    self._emit(kind, idx, width, sgn, bx, by, ux, uy, ln, index, z, findings, chords)
            # widths against the exposure
            if self.grey_fn is not None:
                img = image = image()
                grey = np.asarray(self.grey_fn(index, img))
                if grey.shape != img.shape or grey.dtype != np.uint8:
                    raise ConfigError(f"the mask function must return {img.shape} uint8, got {grey.shape} {grey.dtype}")
                lim = _EXPOSURE_TEST_PX * self.pmax
                level = self.thr * 255.0
                for kind, width, sgn, take_max in (("underexposed", wall, 1.0, True), ("cured_gap", gap, -1.0, False)):
                    cand = np.flatnonzero(width < lim)
                    if not cand.size:
                        continue
                    ac, ar, bc, br = self._chord_px(bx[cand], by[cand], sgn * ux[cand], sgn * uy[cand], width[cand])
                    ext = K.chord_extreme(ac, ar, bc, br, grey, take_max)
                    bad = ext < level if take_max else ext >= level
                    vals = np.full(width.shape, np.nan)
                    vals[cand] = ext / 255.0
                    self._emit(kind, cand[bad], width, sgn, bx, by, ux, uy, ln, index, z, findings, chords, values=vals)
        if self.cavities is not None:
            boxes = []
            for rec in self.cavities.step(rs, r0, r1, index):
                findings.append(self._cavity(rec, index, z))
                a, b, c, d = rec["col0"] - 0.5, rec["row0"] - 0.5, rec["col1"] + 0.5, rec["row1"] + 0.5
                boxes += [(a, b, c, b), (c, b, c, d), (c, d, a, d), (a, d, a, b)]  # its box, on the overlay
            if boxes:
                chords["cavity"] = np.array(boxes, np.float64)
        island_mask = None
        if self.islands and res.islands.shape[1]:
            island_mask = self._islands(res.islands, res.island_of_run, rs, r0, r1, index, z, findings)
        return LayerCheck(index, z, image, findings, chords, island_mask, thin_w, narrow_g)

    # -- helpers

    def _chord_px(self, bx, by, ux, uy, w):
        ac, ar = _affine_apply(self.m2p, bx, by)
        bc, br = _affine_apply(self.m2p, bx + w * ux, by + w * uy)
        return (np.ascontiguousarray(a) for a in (ac, ar, bc, br))

    def _cavity(self, rec: dict, index: int, z: float) -> Finding:
        g = self.grid
        x, y = _affine_apply(self.p2m, np.array([rec["col"]]), np.array([rec["row"]]))
        cc = np.array([rec["col0"] - 0.5, rec["col1"] + 0.5])
        rr = np.array([rec["row0"] - 0.5, rec["row1"] + 0.5])
        X, Y = _affine_apply(self.p2m, np.repeat(cc, 2), np.tile(rr, 2))
        return Finding(
            kind="cavity",
            layer=index,
            z_mm=z,
            x_mm=float(x[0]),
            y_mm=float(y[0]),
            col=float(rec["col"]),
            row=float(rec["row"]),
            bbox_mm=(float(X.min()), float(Y.min()), float(X.max()), float(Y.max())),
            volume_mm3=float(rec["pixels"] * g.pitch_x_mm * g.pitch_y_mm * float(self.job.plan.layer_height_mm)),
            first_layer=int(rec["first_layer"]),
            first_z_mm=float(self.job.plan.z_slice_mm[int(rec["first_layer"])]),
        )

    def _extreme(self, i, width, bx, by, ux, uy, sgn, index, z) -> dict | None:
        if i < 0:
            return None
        w = float(width[i])
        mx = bx[i] + 0.5 * w * sgn * ux[i]
        my = by[i] + 0.5 * w * sgn * uy[i]
        c, r = _affine_apply(self.m2p, mx, my)
        return {"width_mm": w, "layer": index, "z_mm": z, "x_mm": float(mx), "y_mm": float(my), "col": float(c), "row": float(r)}

    def _emit(self, kind, idx, width, sgn, bx, by, ux, uy, ln, index, z, findings, chords, values=None) -> None:
        """Group the chords of the samples ``idx`` (increasing) into pixel regions (chords
        closer than ``_GROUP_PX`` pixels join), one finding per region."""
        if not idx.size:
            return
        ch, g, st = K.emit_groups(idx, width, sgn, bx, by, ux, uy, ln, self.m2p, _GROUP_PX, self._canvas)
        chords[kind] = ch
        ng = st.shape[1]
        val = None
        if values is not None:
            v = values[idx]
            val = [v[g == k].max() if kind == "underexposed" else v[g == k].min() for k in range(ng)]
        for k, (w, x, y, c, r, length, x0, y0, x1, y1) in enumerate(st.T.tolist()):
            findings.append(
                Finding(
                    kind=kind,
                    layer=index,
                    z_mm=z,
                    x_mm=x,
                    y_mm=y,
                    col=c,
                    row=r,
                    width_mm=w,
                    length_mm=length,
                    value=None if val is None else float(val[k]),
                    bbox_mm=(x0, y0, x1, y1),
                )
            )

    def _islands(self, st, isl, rs, r0, r1, index: int, z: float, findings: list[Finding]):
        """Findings for the regions (8-connected) of this layer with no material pixel of the
        layer below, and a function making their ``(H, W) bool`` mask.

        Found on the runs of material of each image row (from the section by the slicer's own
        fill: same pixel coordinates, crossings and rule, equal to the image), by union-find
        over the runs of neighbouring rows: the work follows the outline, not the image size.
        """
        g = self.grid
        px_area = g.pitch_x_mm * g.pitch_y_mm
        cnt, cr, cc, rlo, rhi, clo, chi = st
        x, y = _affine_apply(self.p2m, cc, cr)
        for i in range(cnt.size):
            corners_c = np.array([clo[i] - 0.5, chi[i] + 0.5])
            corners_r = np.array([rlo[i] - 0.5, rhi[i] + 0.5])
            X, Y = _affine_apply(self.p2m, np.repeat(corners_c, 2), np.tile(corners_r, 2))
            findings.append(
                Finding(
                    kind="island",
                    layer=index,
                    z_mm=z,
                    x_mm=float(x[i]),
                    y_mm=float(y[i]),
                    col=float(cc[i]),
                    row=float(cr[i]),
                    area_mm2=float(cnt[i] * px_area),
                    bbox_mm=(float(X.min()), float(Y.min()), float(X.max()), float(Y.max())),
                )
            )
        shape = (g.height, g.width)

        def mask() -> np.ndarray:
            out = np.zeros(shape, bool)
            row = np.repeat(np.arange(shape[0]), np.diff(rs))
            for k in np.flatnonzero(isl >= 0):
                out[row[k], r0[k] : r1[k]] = True
            return out

        return mask


# ----------------------------------------------------------------------------- public API


def _as_job(job_or_mesh, device, *, layer_height_mm, fibre_angle_deg, slice_options):
    from ..slicing import SliceJob, slice_mesh

    if isinstance(job_or_mesh, SliceJob):
        if layer_height_mm is not None or fibre_angle_deg is not None or slice_options:
            raise ConfigError("layer_height_mm, fibre_angle_deg and slicing options apply to a mesh; this is a sliced job already")
        return job_or_mesh
    if isinstance(job_or_mesh, Mesh):
        if layer_height_mm is None:
            raise ConfigError("layer_height_mm is needed to check a mesh")
        return slice_mesh(job_or_mesh, device, layer_height_mm=layer_height_mm, fibre_angle_deg=fibre_angle_deg, **slice_options)
    raise ConfigError(f"expected a Mesh or a SliceJob, got {type(job_or_mesh).__name__}")


def check_layers(
    job_or_mesh,
    device,
    options: CheckOptions | None = None,
    *,
    layer_height_mm: float | None = None,
    fibre_angle_deg: float | None = None,
    slice_options: dict | None = None,
    **settings,
) -> Iterator[LayerCheck]:
    """Check layer after layer; yields one :class:`LayerCheck` each (see
    :func:`check_printability` for the parameters). Memory does not grow with the layers."""
    from ..devices import as_device

    device = as_device(device)
    opts = CheckOptions.of(options, settings)
    job = _as_job(job_or_mesh, device, layer_height_mm=layer_height_mm, fibre_angle_deg=fibre_angle_deg, slice_options=slice_options or {})
    yield from _iter(job, opts.resolve(device), opts.mask_fn)


def _iter(job, st: CheckSettings, mask_fn) -> Iterator[LayerCheck]:
    grey_fn = None if mask_fn is None else (lambda i, img: mask_fn(img))
    checker = _LayerChecker(job, st, grey_fn)
    for i in range(len(job)):
        yield checker.run(i)


def check_printability(
    job_or_mesh,
    device,
    options: CheckOptions | None = None,
    *,
    layer_height_mm: float | None = None,
    fibre_angle_deg: float | None = None,
    slice_options: dict | None = None,
    on_layer: Callable[[LayerCheck], None] | None = None,
    **settings,
) -> CheckReport:
    """Check a part for walls and gaps below the device's minimum, features the raster loses,
    unsupported islands and (with an exposure model) features that do not cure.

    Parameters
    ----------
    job_or_mesh : SliceJob or Mesh
        A sliced job, or a mesh to slice for ``device`` at ``layer_height_mm``.
    device : InkjetDevice or ProjectorDevice
    options : CheckOptions, optional
        What to check (thresholds, exposure model, islands, cavities, resolution, rotary
        limits); default :class:`~rotoprint.check.options.CheckOptions` ``()``.
    layer_height_mm, fibre_angle_deg : float, optional
        Slicing of a mesh (see :func:`rotoprint.slicing.slice_mesh`); ``slice_options`` passes
        the others (``fill``, ``offset_mm``, ``gap_radius_mm``, ...).
    on_layer : callable, optional
        Called with every :class:`LayerCheck` (e.g. to write overlays).
    **settings
        Fields of :class:`~rotoprint.check.options.CheckOptions` by name (``min_wall_mm=...``,
        ``islands=False``, ...), replacing those of ``options``.

    Returns
    -------
    CheckReport

    Examples
    --------
    >>> from rotoprint.testing import box_mesh
    >>> from rotoprint.devices import load_device
    >>> part = box_mesh((2.0, 0.05, 0.2))                  # a 50 um wall
    >>> rep = check_printability(part, load_device("omnidot760"), layer_height_mm=0.1)
    >>> rep.counts()["thin_wall"], round(rep.thinnest_wall["width_mm"], 3)
    (2, 0.05)
    """
    from ..devices import as_device

    device = as_device(device)
    if on_layer is not None and not callable(on_layer):
        raise ConfigError("on_layer must be callable")
    opts = CheckOptions.of(options, settings)
    job = _as_job(job_or_mesh, device, layer_height_mm=layer_height_mm, fibre_angle_deg=fibre_angle_deg, slice_options=slice_options or {})
    st = opts.resolve(device)
    report_settings = st.to_json()
    report_settings["layer_height_mm"] = float(job.plan.layer_height_mm)
    report_settings["fibre_angle_deg"] = fibre_angle_deg
    report_settings["fill"] = job.fill
    limits = device_limits(
        device,
        mask_fn=opts.mask_fn if device.kind == "projector" else None,
        cure_threshold=st.cure_threshold,
        tilt_deg=opts.tilt_deg,
        radius_mm=opts.radius_mm,
    )
    rep = CheckReport(device=device.name, settings=report_settings, grid=job.grid.to_json(), n_layers=len(job), limits=limits)
    for lc in _iter(job, st, opts.mask_fn):
        if lc.findings:
            rep.findings.extend(lc.findings)
            rep.layers_with_findings.append(lc.index)
        for attr in ("thinnest_wall", "narrowest_gap"):
            cur, new = getattr(rep, attr), getattr(lc, attr)
            if new is not None and (cur is None or new["width_mm"] < cur["width_mm"]):
                setattr(rep, attr, new)
        if on_layer is not None:
            on_layer(lc)
        del lc  # the layer's image goes now, not when the next layer is done
    return rep


def compare_orientations(
    mesh: Mesh,
    device,
    options: CheckOptions | None = None,
    *,
    angles_deg: Sequence[float],
    layer_height_mm: float,
    slice_options: dict | None = None,
    **settings,
) -> dict:
    """Check ``mesh`` at every fibre angle (the part rotated in the device plane) and say which
    loses least (``options``, ``slice_options`` and ``settings`` as for
    :func:`check_printability`).

    The loss is the boundary length (mm) of walls that vanish, gaps that close and (with an
    exposure model) walls that do not cure and gaps that do: the problems the raster's
    direction decides. Widths measured on the exact section do not depend on the angle.

    Returns
    -------
    dict
        ``rows`` (one per angle: ``angle_deg``, ``loss_mm``, ``counts``, ``island_area_mm2``)
        and ``best_angle_deg`` (least loss, then least island area, then the first given).
    """
    from ..devices import as_device

    device = as_device(device)
    angles = [float(a) for a in angles_deg]
    if not angles or not all(math.isfinite(a) for a in angles):
        raise ConfigError(f"angles must be finite numbers of degrees, got {list(angles_deg)!r}")
    opts = CheckOptions.of(options, settings)
    rows = []
    for a in angles:
        rep = check_printability(mesh, device, opts, layer_height_mm=layer_height_mm, fibre_angle_deg=a, slice_options=slice_options)
        j = rep.to_json()
        rows.append(
            {
                "angle_deg": a,
                "loss_mm": rep.loss_mm(),
                "island_area_mm2": j["island_area_mm2"],
                "counts": j["counts"],
                "lengths_mm": j["lengths_mm"],
            }
        )
    best = min(range(len(rows)), key=lambda i: (round(rows[i]["loss_mm"], 9), round(rows[i]["island_area_mm2"], 12), i))
    return {"rows": rows, "best_angle_deg": rows[best]["angle_deg"]}
