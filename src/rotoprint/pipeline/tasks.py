"""The three kinds of layer work handed to the producer, as picklable "make the job" and
"render layer i" callables: plain layer images, DLP masks, direct rotary slices.

:class:`MeshJob` rebuilds the slicing job (or the direct rotary job) from the mesh arrays in
a worker; :class:`PlainLayer`, :class:`MaskLayer` and :class:`RotaryLayer` turn a layer index
into its files as bytes (:class:`~rotoprint.pipeline.producer.Rendered`). The producer sees
only these two callables and their key.
"""

from __future__ import annotations

import json
import weakref

import numpy as np

from .._hashing import sha256 as _sha256
from .._dataclass import dataclass, field
from .._version import __version__
from .producer import LayerSource, Rendered

__all__ = ["MeshJob", "PlainLayer", "MaskLayer", "RotaryLayer", "layer_source", "mask_name"]


@dataclass(frozen=True)
class MeshJob:
    """Everything a worker needs to rebuild a job, and nothing that is not picklable.

    ``vertices`` ``(V, 3) float64``, ``faces`` ``(F, 3) int64``: the repaired mesh (the worker
    does not repair it again); ``device`` the device model's JSON; ``slice_options`` the
    keyword arguments of :func:`rotoprint.slice_mesh`, or ``rotary_options`` those of
    :func:`rotoprint.rotary.slice_rotary` for a direct rotary job.
    """

    vertices: np.ndarray
    faces: np.ndarray
    source: str | None
    device: dict
    slice_options: dict
    rotary_options: dict | None = None
    face_edges: np.ndarray | None = field(default=None, compare=False)
    suspect_edges: np.ndarray | None = field(default=None, compare=False)

    @classmethod
    def of(cls, job, *, rotary_options: dict | None = None) -> MeshJob:
        """The picklable description of a :class:`~rotoprint.slicing.SliceJob` (with
        ``rotary_options``: of the direct rotary job made on it)."""
        mesh = job.mesh
        return cls(vertices=mesh.vertices, faces=mesh.faces, source=mesh.source, device=job.device.model_dump(mode="json"),
                   slice_options={} if rotary_options is not None else dict(job.slice_options),
                   rotary_options=rotary_options, face_edges=mesh.topology.face_edges,
                   suspect_edges=mesh.topology.suspect_edges)

    def __call__(self):
        if self.rotary_options is None:
            built = _BUILT.get(id(self))
            if built is not None and built[0]() is self:
                # another thread of this process built it: share its arrays (the mesh, the
                # sorted face bounds), not its sweep's position
                return built[1].for_another_thread()
        from .._resources import release_free_memory
        from .._plain_device import device_from_dump
        from ..mesh import Mesh, PrebuiltTopology
        from ..slicing import slice_mesh

        mesh = Mesh(vertices=self.vertices, faces=self.faces, source=self.source)  # already repaired
        if self.face_edges is not None and self.suspect_edges is not None:
            object.__setattr__(mesh, "_topology", PrebuiltTopology(self.face_edges, self.suspect_edges))
        device = device_from_dump(self.device, "task device")  # a projector without pydantic
        if self.rotary_options is not None:
            from ..rotary.direct import slice_rotary

            job = slice_rotary(mesh, device, **self.rotary_options)
        else:
            job = slice_mesh(mesh, device, **self.slice_options)
            key = id(self)
            _BUILT[key] = (weakref.ref(self, lambda _, key=key: _BUILT.pop(key, None)), job)
        release_free_memory()
        return job

    @property
    def nbytes(self) -> int:
        """Memory of the rebuilt job beyond its rasters: the mesh and its face sweep."""
        return self.vertices.nbytes + self.faces.nbytes * 6

    def fingerprint_meta(self) -> dict:
        return {"device": self.device, "options": self.slice_options, "rotary": self.rotary_options}


#: id(MeshJob) -> (weak reference to it, the SliceJob a thread of this process built from it)
_BUILT: dict[int, tuple] = {}


@dataclass(frozen=True)
class PlainLayer:
    """Layer ``i`` of a slicing job as ``layer_NNNNN.png`` (255 = material), with its
    ``pixels_on`` and ``gaps`` in the journal."""

    compress_level: int = 3

    def __call__(self, job, index: int) -> Rendered:
        from ..io.images import png_bytes
        from ..io.layers import layer_filename

        layer = job.layer(index)
        data = png_bytes(layer.image, compress_level=self.compress_level)
        return Rendered(index, {layer_filename(index): data},
                        {"pixels_on": int(np.count_nonzero(layer.image)), "gaps": layer.gaps.to_json()})


def mask_name(number: int) -> str:
    """File name of mask ``number`` in a DLP job's work folder."""
    return f"mask_{number:05d}.png"


@dataclass(frozen=True)
class MaskLayer:
    """The DLP masks of layer ``i``: one PNG per copy (ERM makes two), the sum of each copy's
    plain mask (for the resin volume) in the journal, and in ``extra`` the layer's footprint
    (max over its copies) cropped to its bounding box as ``(row0, col0, (h, w) uint8)`` or
    None when empty. ``options`` is :meth:`MaskOptions.to_json`."""

    options: dict
    compress_level: int = 3

    def __call__(self, job, index: int) -> Rendered:
        from ..io.images import png_bytes
        from ..masks.pipeline import MaskOptions, layer_masks

        options = MaskOptions(**self.options)
        fast = _coverage_window(job, index, options)
        if fast is not None:
            return fast
        masks = layer_masks(job, index, options)
        copies = len(masks)
        files = {mask_name(index * copies + c): png_bytes(m.image, compress_level=self.compress_level)
                 for c, m in enumerate(masks)}
        fp = masks[0].plain
        for m in masks[1:]:
            fp = np.maximum(fp, m.plain)
        rows = np.flatnonzero(fp.any(axis=1))
        crop = None
        if rows.size:
            cols = np.flatnonzero(fp.any(axis=0))
            crop = (int(rows[0]), int(cols[0]), np.ascontiguousarray(fp[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]))
        return Rendered(index, files, {"plain_sums": [int(m.plain.sum(dtype=np.uint64)) for m in masks]}, crop)


def _coverage_window(job, index: int, options) -> Rendered | None:
    """Coverage masks without inset, smoothing, ERM or inversion, made and encoded from the
    part's window only (the rest of the mask is black): the same pixels as
    :func:`~rotoprint.masks.pipeline.layer_masks`, without whole-image passes. None when
    the options or the layer need the general path."""
    if (options.mode != "coverage" or options.erm or options.invert or index < options.first_layers
            or job.fill != "nonzero"):
        return None
    from ..io.images import png_bytes_window
    from ..masks.coverage import coverage_window

    s, e, _ = job.pixel_segments(index)
    shape = job.grid.shape
    r0, c0, win, tail = coverage_window(s, e, shape)
    if tail is not None:  # the rows right of the window are not black: general path
        return None
    key = (r0, c0, win.shape, tuple(shape), options.mirror_x, options.mirror_y)
    last = _LAST_WINDOW[0]  # (one read: another thread may replace it meanwhile)
    if last is not None and last[0] == key and np.array_equal(last[1], win):
        # the same pixels as the last layer made (a prism's walls): the PNG depends on the
        # pixels, the image size and the mirroring only, so it is the same bytes
        png, sums, crop = last[2]
        return Rendered(index, {mask_name(index): png}, {"plain_sums": list(sums)}, crop)
    total, (a, b, c, d) = _window_stats(win)
    crop = None
    if b > a:
        crop = (r0 + a, c0 + c, np.ascontiguousarray(win[a:b, c:d]))
    png = png_bytes_window(win, shape, r0, c0, mirror_x=options.mirror_x, mirror_y=options.mirror_y)
    sums = (total,)
    # kept for the next layer (the window is compared whole: equal arrays, equal pixels)
    _LAST_WINDOW[0] = (key, win, (png, sums, crop))
    return Rendered(index, {mask_name(index): png}, {"plain_sums": list(sums)}, crop)


#: the last coverage window made in this process (by any thread), with its PNG, plain sum and
#: footprint crop; replaced whole (one slot), emptied when a DLP job is written
_LAST_WINDOW: list = [None]


def forget_last_window() -> None:
    """Drop the kept window (:func:`rotoprint.pipeline.outputs.write_dlp_job` calls this when done)."""
    _LAST_WINDOW[0] = None


def _window_stats(win: np.ndarray) -> tuple[int, tuple[int, int, int, int]]:
    """The grey sum of ``win`` ``(hh, ww) uint8`` and the rows ``a:b`` and columns ``c:d``
    holding its non-zero pixels (``b == a`` when there are none); one pass in C."""
    from .._accel import native

    if native is not None:
        total, a, b, c, d = native.window_stats(np.ascontiguousarray(win), *win.shape)
        return int(total), (a, b, c, d)
    rows = np.flatnonzero(win.any(axis=1))
    if not rows.size:
        return 0, (0, 0, 0, 0)
    cols = np.flatnonzero(win.any(axis=0))
    return int(win.sum(dtype=np.uint64)), (int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1)


@dataclass(frozen=True)
class RotaryLayer:
    """Layer ``i`` of a direct rotary job: swathe PNGs, the sidecar, optionally the reference
    image (:func:`rotoprint.rotary.direct.rotary_layer_files`); its manifest entry in the
    journal as ``entry``."""

    device_name: str
    reference_images: bool = False

    def __call__(self, job, index: int) -> Rendered:
        from ..rotary.direct import rotary_layer_files

        files, record = rotary_layer_files(job, index, device_name=self.device_name, reference_images=self.reference_images)
        return Rendered(index, files, {"entry": record})


def layer_source(make_job: MeshJob, render, extra: dict | None = None) -> LayerSource:
    """The :class:`LayerSource` of ``make_job`` and ``render``, keyed by a SHA-256 over the
    mesh, the device, the options, what is rendered, the rotoprint version and ``extra``.

    Parameters
    ----------
    make_job : MeshJob
    render : PlainLayer, MaskLayer or RotaryLayer
    extra : dict, optional
        More JSON values the key must depend on.

    Returns
    -------
    LayerSource
    """
    h = _sha256(expect_bytes=make_job.vertices.nbytes + make_job.faces.nbytes)
    h.update(np.ascontiguousarray(make_job.vertices, dtype="<f8").tobytes())
    h.update(np.ascontiguousarray(make_job.faces, dtype="<i8").tobytes())
    meta = {**make_job.fingerprint_meta(), "render": type(render).__name__, "render_options": render.__dict__,
            "version": __version__, "extra": extra or {}}
    h.update(json.dumps(meta, sort_keys=True, default=str).encode())
    return LayerSource(make_job, render, h.hexdigest())
