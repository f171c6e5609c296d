"""From a slicing job to the sequence of masks a DLP printer projects.

Per layer, in this order: raster (``binary`` pixel-centre sampling, ``coverage`` exact area
fraction, or ``smooth`` = binary then the paper's PIL SMOOTH); first-layer inset (layers
``i < first_layers``); ERM copy (shifted one pixel right and down); mirroring; inversion.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import asdict

import numpy as np

from .._dataclass import dataclass
from ..errors import ConfigError
from .coverage import coverage_mask
from .ops import erm_shift, first_layer_offsets_um, inset_mask, invert_mask, mirror_mask, smooth_mask

__all__ = ["MODES", "FIRST_LAYER_OFFSET_MAX_UM", "MaskOptions", "check_first_layer_offset", "Mask", "iter_masks", "layer_masks", "plain_from_image", "render_layer"]

MODES = ("binary", "coverage", "smooth")

# The largest first-layer (elephant-foot) inset accepted, um: well above any real compensation
# (tens to a few hundred um) and below what would blank a layer of any printable part.
FIRST_LAYER_OFFSET_MAX_UM = 2000.0


@dataclass(frozen=True)
class MaskOptions:
    """How masks are made (see module doc). ``mirror_x``/``mirror_y`` are the final flips."""

    mode: str = "coverage"
    erm: bool = False
    invert: bool = False
    mirror_x: bool = False
    mirror_y: bool = False
    first_layers: int = 0
    first_layer_offset_um: float = 0.0

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ConfigError(f"mode must be one of {', '.join(MODES)}, got {self.mode!r}")
        first_layer_offsets_um(0, first_layers=self.first_layers, first_layer_offset_um=self.first_layer_offset_um)
        if self.first_layer_offset_um > FIRST_LAYER_OFFSET_MAX_UM:
            raise ConfigError(f"--first-layer-offset must be at most {FIRST_LAYER_OFFSET_MAX_UM:g} um, got "
                              f"{self.first_layer_offset_um:g} um")
        if self.first_layer_offset_um > 0 and self.first_layers == 0:
            raise ConfigError("a first-layer offset needs --first-layers N > 0 (the layers it fades over)")

    @property
    def copies(self) -> int:
        return 2 if self.erm else 1

    def to_json(self) -> dict:
        return asdict(self)


def check_first_layer_offset(options: MaskOptions, footprint_mm: tuple[float, float]) -> None:
    """Refuse a first-layer inset that would blank the first layers.

    Parameters
    ----------
    options : MaskOptions
        Its ``first_layer_offset_um`` is checked.
    footprint_mm : (2,) float
        Width and depth of the part's XY bounding box, mm.

    Raises
    ------
    ConfigError
        The inset is more than half the smaller side of the footprint (the inset would meet
        itself in the middle and leave nothing of the part).

    Examples
    --------
    >>> check_first_layer_offset(MaskOptions(first_layers=2, first_layer_offset_um=900), (3.0, 2.0))
    >>> check_first_layer_offset(MaskOptions(first_layers=2, first_layer_offset_um=1100), (3.0, 2.0))
    Traceback (most recent call last):
    ...
    rotoprint.errors.ConfigError: --first-layer-offset of 1100 um is more than half the part's smallest footprint dimension (2 mm): it would blank the first layers
    """
    smallest_mm = float(min(footprint_mm))
    if options.first_layer_offset_um > 0 and options.first_layer_offset_um > smallest_mm / 2 * 1000:
        raise ConfigError(f"--first-layer-offset of {options.first_layer_offset_um:g} um is more than half the part's "
                          f"smallest footprint dimension ({smallest_mm:g} mm): it would blank the first layers")


@dataclass(frozen=True)
class Mask:
    """One projected mask: slice ``layer`` (its ``copy``-th exposure, 1 = the ERM copy).

    ``image`` is what is projected; ``plain`` the same mask before mirroring and inversion
    (white = expose, as the part is seen from above), for previews and statistics.
    """

    number: int
    layer: int
    copy: int
    z_mm: float
    image: np.ndarray
    plain: np.ndarray


def render_layer(job, index: int, options: MaskOptions, *, backend: str = "jit") -> np.ndarray:
    """``(H, W) uint8`` mask of layer ``index`` before ERM, mirroring and inversion.

    Parameters
    ----------
    job : SliceJob
    index : int
        0-based layer index.
    options : MaskOptions
        ``mode`` chooses the raster; layers ``index < first_layers`` are inset by
        :func:`~rotoprint.masks.ops.first_layer_offsets_um`.
    backend : {'jit', 'numpy'}
        Coverage kernel (``mode='coverage'`` only; see
        :func:`~rotoprint.masks.coverage.coverage_mask`).

    Returns
    -------
    (H, W) uint8 ndarray
        ``(H, W)`` is ``job.grid.shape``; white = expose.

    Raises
    ------
    ConfigError
        ``mode='coverage'`` on a job sliced with a fill rule other than ``'nonzero'``.
    """
    if options.mode == "coverage":
        if job.fill != "nonzero":
            raise ConfigError(f"coverage masks use the nonzero rule; the job was sliced with {job.fill!r}")
        s, e, _ = job.pixel_segments(index)
        img = coverage_mask(s, e, job.grid.shape, backend=backend)
    else:
        img = job.layer(index).image
    inset_um = 0.0
    if index < options.first_layers:
        inset_um = float(
            first_layer_offsets_um(index + 1, first_layers=options.first_layers, first_layer_offset_um=options.first_layer_offset_um)[index]
        )
    if inset_um > 0:
        img = inset_mask(img, inset_mm=inset_um / 1000.0, pitch_x_mm=job.grid.pitch_x_mm, pitch_y_mm=job.grid.pitch_y_mm)
    if options.mode == "smooth":
        img = smooth_mask(img)
    return img


def layer_masks(job, index: int, options: MaskOptions, *, backend: str = "jit") -> list[Mask]:
    """The ``options.copies`` masks of layer ``index``, numbered in projection order.

    Parameters
    ----------
    job : SliceJob
    index : int
        0-based layer index.
    options : MaskOptions
    backend : {'jit', 'numpy'}
        See :func:`render_layer`.

    Returns
    -------
    list of Mask
        One, or two with ``erm`` (the second shifted by :func:`~rotoprint.masks.ops.erm_shift`);
        mask ``c`` has ``number = index * options.copies + c``.

    Raises
    ------
    ConfigError
        See :func:`render_layer`.
    """
    base = render_layer(job, index, options, backend=backend)
    z = float(job.plan.z_slice_mm[index])
    out = []
    for c in range(options.copies):
        img = plain = base if c == 0 else erm_shift(base)
        if options.mirror_x or options.mirror_y:
            img = mirror_mask(img, mirror_x=options.mirror_x, mirror_y=options.mirror_y)
        if options.invert:
            img = invert_mask(img)
        out.append(Mask(number=index * options.copies + c, layer=index, copy=c, z_mm=z, image=img, plain=plain))
    return out


def plain_from_image(image: np.ndarray, options: MaskOptions) -> np.ndarray:
    """Undo inversion and mirroring: the mask as seen from above, white = expose.

    Parameters
    ----------
    image : (H, W) uint8
        A projected mask (:attr:`Mask.image`) made with ``options``.
    options : MaskOptions
        Only ``invert``, ``mirror_x`` and ``mirror_y`` are used.

    Returns
    -------
    (H, W) uint8 ndarray
        ``image`` itself when ``options`` neither inverts nor mirrors.

    Raises
    ------
    ImageError
        ``image`` is not a 2-D uint8 array (checked only when it is inverted or mirrored).
    """
    img = invert_mask(image) if options.invert else image
    if options.mirror_x or options.mirror_y:
        img = mirror_mask(img, mirror_x=options.mirror_x, mirror_y=options.mirror_y)
    return img


def iter_masks(job, options: MaskOptions, *, backend: str = "jit") -> Iterator[Mask]:
    """Yield every mask of ``job`` in projection order (``len(job) * options.copies`` masks).

    Parameters
    ----------
    job : SliceJob
    options : MaskOptions
    backend : {'jit', 'numpy'}
        See :func:`render_layer`.

    Yields
    ------
    Mask
        Layer by layer, made one layer at a time.

    Raises
    ------
    ConfigError
        See :func:`render_layer`.
    """
    for i in range(len(job)):
        yield from layer_masks(job, i, options, backend=backend)
