"""DLP job outputs: masks encoded (in threads) and handed to their format's writer, and the
reader that reopens every format (used by the tests and by ``rotoprint`` itself to check what
it wrote). The formats live one module each in :mod:`rotoprint.io.formats` (SL1 / SL1S
archives, a PNG folder with a manifest, a Perfactory-style job folder), found through its
registry rather than by comparing names here.

Every output is written under a temporary name beside the target and renamed when complete.
ERM (two masks per slice): an SL1 archive holds ``2 N`` layers of half the layer height; the
folder formats keep both masks of a slice at one height.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from .._dataclass import dataclass
from ..errors import ConfigError, ImageError, InputFileError
from .atomic import OutputClaim
from .formats import FORMATS as _REGISTRY
from .formats import by_kind, by_suffix
from .formats._common import (  # noqa: F401 - the names this module has always offered
    CONFIG_KEYS,
    PERFACTORY_CFG,
    PERFACTORY_TXT,
    PRUSASLICER_KEYS,
    SL1_TILT_TIME_S,
    THUMBNAIL_SIZES,
    ArchiveContents,
    JobInfo,
    creation_time,
    job_dir_name,
    thumbnail_png,
)
from .formats.png import read_folder
from .images import png_bytes

__all__ = [
    "FORMATS",
    "JobInfo",
    "Encoded",
    "write_encoded",
    "write_job",
    "format_from_path",
    "read_job",
    "ArchiveContents",
    "CONFIG_KEYS",
    "PRUSASLICER_KEYS",
    "THUMBNAIL_SIZES",
    "SL1_TILT_TIME_S",
]


#: The format names, in the registry's order (one module each in :mod:`rotoprint.io.formats`).
FORMATS = tuple(_REGISTRY)


def mask_filename(number: int, fmt: str) -> str:
    """The file name of mask ``number`` in a ``fmt`` folder."""
    return _REGISTRY[fmt].mask_name(number)





def format_from_path(path: str | Path, fmt: str | None = None) -> str:
    """The output format: ``fmt`` if given, else from the suffix (.sl1, .sl1s), else 'png'.

    Parameters
    ----------
    path : str or Path
        The output; only its suffix is looked at, and only when ``fmt`` is None or ``'auto'``.
    fmt : {'auto', 'sl1', 'sl1s', 'png', 'perfactory'}, optional

    Returns
    -------
    {'sl1', 'sl1s', 'png', 'perfactory'}

    Raises
    ------
    ConfigError
        ``fmt`` is not one of the above, or it is not given and the suffix is one of
        ``.zip``, ``.png``, ``.cws``, ``.ctb``, ``.pwmx`` (a file format rotoprint does not write).
    """
    if fmt is not None and fmt != "auto":
        if fmt not in FORMATS:
            raise ConfigError(f"format must be one of auto, {', '.join(FORMATS)}, got {fmt!r}")
        return fmt
    suffix = Path(path).suffix.lower()
    form = by_suffix(suffix)
    if form is not None:
        return form.name
    if suffix in (".zip", ".png", ".cws", ".ctb", ".pwmx"):
        raise ConfigError(f"cannot tell the format from {Path(path).name!r}: use .sl1, .sl1s or a folder")
    return "png"












@dataclass(frozen=True)
class Encoded:
    """One mask ready to store: its PNG bytes, the sum of its plain (unmirrored, uninverted)
    grey levels, and a footprint crop ``(row0, col0, array)`` to merge (or None).
    ``whole_footprint``: the crop is already the merge of every mask's (the others carry
    None), so the thumbnails can be drawn from it while the masks are stored."""

    number: int
    layer: int
    copy: int
    z_mm: float
    png: bytes
    plain_sum: int
    footprint: tuple[int, int, np.ndarray] | None
    whole_footprint: bool = False






def _encoded(masks: Iterable, info: JobInfo, compress_level: int, workers: int):
    """Yield :class:`Encoded` masks in order; PNG encoding (zlib, which releases the GIL)
    runs in ``workers`` threads while the next masks are computed. At most
    ``2 * workers + 1`` masks are held at once."""
    from concurrent.futures import ThreadPoolExecutor

    from .._window import ordered

    def done(m, data: bytes) -> Encoded:
        return Encoded(m.number, m.layer, m.copy, m.z_mm, data, int(m.plain.sum(dtype=np.uint64)), (0, 0, m.plain))

    def checked():
        for m in masks:
            _check_mask(m.image, info, m.number)
            yield m

    def encode(m) -> Encoded:
        return done(m, png_bytes(m.image, compress_level=compress_level))

    if workers <= 0:
        yield from map(encode, checked())
        return
    with ThreadPoolExecutor(max_workers=workers, thread_name_prefix="rotoprint-png") as ex:
        yield from ordered(lambda m: ex.submit(encode, m), checked(), 2 * workers + 1)


def _default_workers() -> int:
    import os

    return 1 if (os.cpu_count() or 1) > 1 else 0


def _check_mask(img: np.ndarray, info: JobInfo, number: int) -> None:
    if img.dtype != np.uint8 or img.shape != (info.height_px, info.width_px):
        raise ImageError(
            f"mask {number} must be ({info.height_px}, {info.width_px}) uint8, got {img.shape} {img.dtype}"
        )


def write_job(
    path: str | Path,
    masks: Iterable,
    info: JobInfo,
    *,
    fmt: str | None = None,
    compress_level: int = 3,
    on_mask: Callable[[int], None] | None = None,
    encode_workers: int | None = None,
    force: bool = False,
) -> dict:
    """Write the masks of a job to ``path``; returns a summary (the manifest for folders).

    Parameters
    ----------
    path : path
        ``.sl1`` / ``.sl1s`` file, or a folder (``png`` or ``perfactory``).
    masks : iterable of :class:`rotoprint.masks.Mask`
        In projection order; each ``image`` is ``(info.height_px, info.width_px) uint8``.
    info : JobInfo
    fmt : {'auto', 'sl1', 'sl1s', 'png', 'perfactory'}, optional
        Default: from the suffix of ``path``.
    encode_workers : int, optional
        Threads encoding PNGs while the next masks are made (default: 1 on a multi-core
        machine, else 0 = encode inline). The output is the same either way.
    force : bool
        Replace an existing ``path`` even if it is not provably ours (see
        :mod:`rotoprint.io.ownership`: an archive of ours carries our marker in its comment).
    """
    fmt = format_from_path(path, fmt)
    workers = _default_workers() if encode_workers is None else int(encode_workers)
    items = _encoded(masks, info, compress_level, workers)
    return write_encoded(path, items, info, fmt=fmt, on_mask=on_mask, force=force)


def write_encoded(path: str | Path, items: Iterable[Encoded], info: JobInfo, *, fmt: str,
                  on_mask: Callable[[int], None] | None = None, claim: OutputClaim | None = None,
                  force: bool = False) -> dict:
    """Write already-encoded masks (in projection order) as ``fmt``; see :func:`write_job`.

    ``claim`` is the entered :class:`~rotoprint.io.atomic.OutputClaim` of ``path`` when the
    caller holds it already (else one is taken here, with ``force``).
    """
    form = _REGISTRY[fmt]
    ctx = contextlib.nullcontext(claim) if claim is not None else OutputClaim(path, is_dir=form.is_dir, kind=f"dlp-{fmt}", force=force)
    with ctx as c:
        return form.write(Path(path), items, info, on_mask, c)












# ---------------------------------------------------------------------------------- reading






def read_job(path: str | Path) -> ArchiveContents:
    """Reopen an SL1 / SL1S archive or a rotoprint mask folder and check its structure.

    Raises :class:`InputFileError` when a required key or file is missing, when the layer
    count in ``config.ini`` disagrees with the layers present, or when names are out of
    sequence.

    Parameters
    ----------
    path : str or Path
        An ``.sl1`` / ``.sl1s`` archive (any other file is opened as a zip and reported as
        ``sl1``), or a folder holding ``manifest.json``.

    Returns
    -------
    ArchiveContents
        Archives are read into memory whole; folders read each mask when it is asked for.
    """
    path = Path(path)
    if not path.exists():
        raise InputFileError("no such file or folder", path=path)
    if path.is_dir():
        manifest, names = read_folder(path)
        return by_kind(manifest.get("kind")).open(path, manifest, names)
    return _REGISTRY["sl1"].open(path, None, None)  # any file is opened as a zip

