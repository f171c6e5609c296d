"""The fibre slicer: a mesh sliced at constant Z by parallel fibres at the device's pitch.

Every image is made at its final size on the device grid, never scaled. See
``docs/slicing.md`` for the rules (vertex on a plane or a fibre, fill rules, open meshes).
"""

from __future__ import annotations

import copy

import logging
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .._dataclass import dataclass
from .._resources import check_raster_fits
from ..mesh import Mesh
from ._fill import FILL_RULES, fill_numpy
from ._gaps import GapReport, close_gaps
from ._sections import FaceSweep, Segments, section
from .grid import Grid, make_grid
from .layers import LayerPlan, plan_layers
from .options import BACKENDS, SliceOptions, slice_options_from

__all__ = ["Layer", "SliceJob", "SliceOptions", "slice_mesh", "FILL_RULES", "BACKENDS"]

log = logging.getLogger(__name__)

_NO_GAPS = GapReport()


@dataclass(frozen=True)
class Layer:
    """One sliced layer.

    Attributes
    ----------
    index : int
    z_mm : float
        Height of the slicing plane (the middle of the layer).
    z_bottom_mm, z_top_mm : float
    image : (H, W) uint8
        255 where there is material, 0 elsewhere.
    gaps : GapReport
        What gap closing did (open meshes only).
    """

    index: int
    z_mm: float
    z_bottom_mm: float
    z_top_mm: float
    image: np.ndarray
    gaps: GapReport
    n_segments: int


class SliceJob:
    """A planned slicing run. Iterating yields :class:`Layer` objects one at a time.

    Memory does not grow with the layer count: each image is made when it is asked for.
    Build one with :func:`slice_mesh`; ``device`` and ``options`` are what it was made for.
    """

    def __init__(self, mesh: Mesh, grid: Grid, plan: LayerPlan, *, device, options: SliceOptions) -> None:
        self.mesh = mesh
        self.grid = grid
        self.plan = plan
        self.device = device
        self.options = options
        self.fill = options.fill
        self.gap_radius_mm = options.gap_radius_mm
        self.backend = options.backend
        self._sweep = FaceSweep(mesh)
        suspect = mesh.topology.suspect_edges
        self._suspect = suspect
        self._any_suspect = bool(suspect.any())
        # Pixel-centre sampling does not depend on the scan direction, so image rows are
        # always scanned (contiguous writes); ``grid.fibre_axis`` records the device's own
        # fibre direction (nozzle tracks) for the rotary stages and the manifest.
        self._to_uv = grid.model_to_pixel  # u = col (along the scanned row), v = row
        self._n_fib, self._n_samp = grid.height, grid.width

    def __len__(self) -> int:
        return len(self.plan)

    def for_another_thread(self) -> SliceJob:
        """The same job for another thread: everything shared (read only) but the face
        sweep's position, which each thread keeps for its own increasing heights."""
        other = copy.copy(self)
        other._sweep = self._sweep.fork()
        return other

    @property
    def slice_options(self) -> dict:
        """The options as :func:`slice_mesh` keywords (what the layer manifest records)."""
        return self.options.as_dict()

    @property
    def fill_affine(self) -> np.ndarray:
        """``(2, 3) float64``: model XY (mm) to the fill's ``(u, v)`` (u: column along a scanned row, v: row)."""
        return self._to_uv

    def segments(self, index: int) -> tuple[Segments, GapReport]:
        """The closed cross-section of layer ``index`` in model XY (mm), and its gap report."""
        return self.segments_at(float(self.plan.z_slice_mm[index]))

    def segments_at(self, z_mm: float) -> tuple[Segments, GapReport]:
        """The closed cross-section at any height ``z_mm`` (vertex rule: see ``_sections``)."""
        z = float(z_mm)
        faces = self._sweep.faces_at(z)
        seg = section(self.mesh, faces, z)
        if self._any_suspect and len(seg) and (self._suspect[seg.start_edge].any() or self._suspect[seg.end_edge].any()):
            return close_gaps(seg, self._suspect, self.gap_radius_mm)
        return seg, _NO_GAPS

    def pixel_segments(self, index: int) -> tuple[np.ndarray, np.ndarray, GapReport]:
        """Layer ``index``'s segments as ``(S, 2)`` start and end in pixel ``(col, row)``."""
        seg, rep = self.segments(index)
        m = self._to_uv  # (grid.model_to_pixel, computed once: not two inverses per layer)
        return _affine(m, seg.start), _affine(m, seg.end), rep

    def image_at(self, z_mm: float) -> tuple[np.ndarray, GapReport]:
        """``(H, W) uint8`` image of the cross-section at any height, and its gap report."""
        seg, rep = self.segments_at(z_mm)
        return self._fill(seg), rep

    def _fill(self, seg: Segments) -> np.ndarray:
        t = self._to_uv
        a = _affine(t, seg.start)
        b = _affine(t, seg.end)
        args = (a[:, 0], a[:, 1], b[:, 0], b[:, 1], self._n_fib, self._n_samp, self.fill)
        if self.backend == "numpy":
            return fill_numpy(*args)
        from ._fill import fill_fast

        return fill_fast(*args)

    def layer(self, index: int) -> Layer:
        """Slice one layer."""
        return self.layer_and_segments(index)[0]

    def layer_and_segments(self, index: int) -> tuple[Layer, Segments]:
        """Slice one layer and return it with its closed cross-section (model XY mm), computing
        the section once (for checks that need both the image and the exact outline)."""
        if not 0 <= index < len(self):
            raise IndexError(f"layer {index} out of range 0..{len(self) - 1}")
        seg, rep = self.segments(index)
        layer = Layer(
            index=index,
            z_mm=float(self.plan.z_slice_mm[index]),
            z_bottom_mm=float(self.plan.z_bottom_mm[index]),
            z_top_mm=float(self.plan.z_top_mm[index]),
            image=self._fill(seg),
            gaps=rep,
            n_segments=len(seg),
        )
        return layer, seg

    def __iter__(self) -> Iterator[Layer]:
        for i in range(len(self)):
            yield self.layer(i)


def _affine(m: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Apply a ``(2, 3)`` affine to ``(N, 2)`` points with elementwise arithmetic only.

    Not ``xy @ m.T``: a BLAS product may fuse multiply-adds in some lanes and not in others,
    and then a point shared by two segments could map to two different values; the
    half-open fibre rule needs bit-identical copies.
    """
    x, y = xy[:, 0], xy[:, 1]
    out = np.empty_like(xy)
    out[:, 0] = (m[0, 0] * x + m[0, 1] * y) + m[0, 2]
    out[:, 1] = (m[1, 0] * x + m[1, 1] * y) + m[1, 2]
    return out


def slice_mesh(mesh: Mesh, device, options: SliceOptions | None = None, **keywords) -> SliceJob:
    """Plan the slicing of ``mesh`` for ``device``; iterate the result for the layers.

    Parameters
    ----------
    mesh : Mesh
    device : InkjetDevice or ProjectorDevice or str
        Gives the pitch, the field and the fibre direction (see :mod:`rotoprint.devices`); a
        preset name or a device .toml file is loaded.
    options : SliceOptions, optional
        Layer height, fibre angle, fill rule, offset, gap radius, backend.
    **keywords
        Fields of :class:`~rotoprint.slicing.options.SliceOptions` by name
        (``layer_height_mm=0.1``, ``fill="evenodd"``, ...), replacing those of ``options``.

    Examples
    --------
    >>> from rotoprint.testing import box_mesh
    >>> from rotoprint.devices import load_device
    >>> job = slice_mesh(box_mesh((2, 1, 1)), load_device("perfactory-sxga"), layer_height_mm=0.5)
    >>> len(job), job.grid.shape
    (2, (1050, 1400))
    >>> int((next(iter(job)).image > 0).sum())  # 2 mm / 19.836 um -> 100 columns, 1 mm / 19.838 um -> 50 rows
    5000
    """
    opts = slice_options_from(options, keywords)
    if isinstance(device, (str, Path)):  # a name or file; a device model is used as it is
        from ..devices import as_device

        device = as_device(device)
    lo, hi = mesh.bounds
    plan = plan_layers(float(lo[2]), float(hi[2]), opts.layer_height_mm)
    grid = make_grid(
        mesh.vertices[:, :2],
        pitch_mm=(device.pitch_x_mm, device.pitch_y_mm),
        fibre_axis=device.fibre_axis,
        field_px=device.field_px,
        fibre_angle_deg=opts.fibre_angle_deg,
        offset_mm=opts.offset_mm,
        centre=opts.centre,
    )
    check_raster_fits(grid.width, grid.height, 5, what="layer image")
    return SliceJob(mesh, grid, plan, device=device, options=opts)
