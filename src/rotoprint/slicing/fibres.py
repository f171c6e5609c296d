"""The fibre slicer: a mesh sliced at constant Z by parallel fibres at the device's pitch.

Every image is made at its final size on the device grid, never scaled. See
``docs/slicing.md`` for the rules (vertex on a plane or a fibre, fill rules, open meshes).
"""

from __future__ import annotations

import logging
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from .._resources import check_raster_fits
from ..constants import DEFAULT_GAP_RADIUS_MM
from ..errors import ConfigError
from ..mesh import Mesh
from ._fill import FILL_RULES, fill_numpy
from ._gaps import GapReport, close_gaps
from ._sections import FaceSweep, Segments, section
from .grid import Grid, make_grid
from .layers import LayerPlan, plan_layers

__all__ = ["Layer", "SliceJob", "slice_mesh", "FILL_RULES", "BACKENDS"]

log = logging.getLogger(__name__)

BACKENDS = ("jit", "numpy")


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
    Build one with :func:`slice_mesh`.
    """

    def __init__(
        self,
        mesh: Mesh,
        grid: Grid,
        plan: LayerPlan,
        *,
        fill: str,
        gap_radius_mm: float,
        backend: str,
    ) -> None:
        self.mesh = mesh
        self.grid = grid
        self.plan = plan
        self.fill = fill
        self.gap_radius_mm = gap_radius_mm
        self.backend = backend
        self._sweep = FaceSweep(mesh)
        topo = mesh.topology
        suspect = topo.edge_face_count != 2
        if topo.orientation_conflicts:
            conflict_pairs = topo.pair_same_direction
            fe = topo.face_edges
            # Edges shared by two faces wound the same way: their chains do not link.
            pf = topo.pair_faces[conflict_pairs]
            for a, b in pf:
                suspect[np.intersect1d(fe[a], fe[b])] = True
        self._suspect = suspect
        m = grid.model_to_pixel
        if grid.fibre_axis == "x":  # rows are fibres: v = row, u = col
            self._to_uv = np.array([m[0], m[1]])
            self._n_fib, self._n_samp = grid.height, grid.width
        else:  # columns are fibres: v = col, u = row
            self._to_uv = np.array([m[1], m[0]])
            self._n_fib, self._n_samp = grid.width, grid.height

    def __len__(self) -> int:
        return len(self.plan)

    def segments(self, index: int) -> tuple[Segments, GapReport]:
        """The closed cross-section of layer ``index`` in model XY (mm), and its gap report."""
        z = float(self.plan.z_slice_mm[index])
        faces = self._sweep.faces_at(z)
        seg = section(self.mesh, faces, z)
        if len(seg) and self._suspect.any():
            return close_gaps(seg, self._suspect, self.gap_radius_mm)
        return seg, GapReport()

    def pixel_segments(self, index: int) -> tuple[np.ndarray, np.ndarray, GapReport]:
        """Layer ``index``'s segments as ``(S, 2)`` start and end in pixel ``(col, row)``."""
        seg, rep = self.segments(index)
        m = self.grid.model_to_pixel
        return seg.start @ m[:, :2].T + m[:, 2], seg.end @ m[:, :2].T + m[:, 2], rep

    def layer(self, index: int) -> Layer:
        """Slice one layer."""
        return self.layer_and_segments(index)[0]

    def layer_and_segments(self, index: int) -> tuple[Layer, Segments]:
        """Slice one layer and return it with its closed cross-section (model XY mm), computing
        the section once (for checks that need both the image and the exact outline)."""
        if not 0 <= index < len(self):
            raise IndexError(f"layer {index} out of range 0..{len(self) - 1}")
        seg, rep = self.segments(index)
        t = self._to_uv
        a = seg.start @ t[:, :2].T + t[:, 2]
        b = seg.end @ t[:, :2].T + t[:, 2]
        fill_fn = _fill_function(self.backend)
        img = fill_fn(a[:, 0], a[:, 1], b[:, 0], b[:, 1], self._n_fib, self._n_samp, self.fill)
        if self.grid.fibre_axis == "y":
            img = np.ascontiguousarray(img.T)
        layer = Layer(
            index=index,
            z_mm=float(self.plan.z_slice_mm[index]),
            z_bottom_mm=float(self.plan.z_bottom_mm[index]),
            z_top_mm=float(self.plan.z_top_mm[index]),
            image=img,
            gaps=rep,
            n_segments=len(seg),
        )
        return layer, seg

    def __iter__(self) -> Iterator[Layer]:
        for i in range(len(self)):
            yield self.layer(i)


def _fill_function(backend: str):
    if backend == "numpy":
        return fill_numpy
    from ._kernels import fill_jit

    return fill_jit


def slice_mesh(
    mesh: Mesh,
    device,
    *,
    layer_height_mm: float,
    fibre_angle_deg: float | None = None,
    fill: str = "nonzero",
    offset_mm: tuple[float, float] = (0.0, 0.0),
    centre: bool = True,
    gap_radius_mm: float = DEFAULT_GAP_RADIUS_MM,
    backend: str = "jit",
) -> SliceJob:
    """Plan the slicing of ``mesh`` for ``device``; iterate the result for the layers.

    Parameters
    ----------
    mesh : Mesh
    device : InkjetDevice or ProjectorDevice
        Gives the pitch, the field and the fibre direction (see :mod:`rotoprint.devices`).
    layer_height_mm : float
    fibre_angle_deg : float, optional
        Direction of the fibres in the model's XY plane, degrees counter-clockwise from +X.
        Default: the device's own fibre direction with the model unrotated.
    fill : {'nonzero', 'evenodd'}
    offset_mm : (2,) float
        Where the part's footprint centre goes, relative to the field centre (``centre=True``),
        or the translation of the model's origin (``centre=False``).
    gap_radius_mm : float
        Open ends of a cross-section closer than this are joined (open meshes).
    backend : {'jit', 'numpy'}
        The compiled kernel or the pure-numpy reference; their output is identical.

    Examples
    --------
    >>> from rotoprint.testing import box_mesh
    >>> from rotoprint.devices import load_device
    >>> job = slice_mesh(box_mesh((2, 1, 1)), load_device("perfactory-sxga"), layer_height_mm=0.5)
    >>> len(job), job.grid.shape
    (2, (1050, 1400))
    >>> int((next(iter(job)).image > 0).sum())  # 2 x 1 mm at 19.84 um pixels
    5082
    """
    if fill not in FILL_RULES:
        raise ConfigError(f"fill must be one of {', '.join(FILL_RULES)}, got {fill!r}")
    if backend not in BACKENDS:
        raise ConfigError(f"backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if not gap_radius_mm >= 0:
        raise ConfigError(f"gap radius must be >= 0 mm, got {gap_radius_mm}")
    if fibre_angle_deg is not None and not np.isfinite(fibre_angle_deg):
        raise ConfigError(f"fibre angle must be finite, got {fibre_angle_deg}")
    lo, hi = mesh.bounds
    plan = plan_layers(float(lo[2]), float(hi[2]), float(layer_height_mm))
    grid = make_grid(
        mesh.vertices[:, :2],
        pitch_x_mm=device.pitch_x_mm,
        pitch_y_mm=device.pitch_y_mm,
        fibre_axis=device.fibre_axis,
        field_px=device.field_px,
        fibre_angle_deg=fibre_angle_deg,
        offset_mm=offset_mm,
        centre=centre,
    )
    check_raster_fits(grid.width, grid.height, 5, what="layer image")
    return SliceJob(mesh, grid, plan, fill=fill, gap_radius_mm=float(gap_radius_mm), backend=backend)
