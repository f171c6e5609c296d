"""What the DLP output formats share: the job description (:class:`JobInfo`), the running
statistics, ini tables, thumbnails, reproducible zip entries and dates, the reopened job
(:class:`ArchiveContents`), and :class:`ArchiveFormat`, the entry every format module gives
the registry in :mod:`rotoprint.io.formats`."""

from __future__ import annotations

import datetime
import re
import struct
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..._dataclass import dataclass, field
from ...errors import ConfigError, ImageError, InputFileError
from ...ranges import Range, check_range
from ..images import open_image

#: Keys of ``config.ini`` written in every SL1 / SL1S archive.
CONFIG_KEYS = (
    "action", "jobDir", "layerHeight", "expTime", "expTimeFirst", "expUserProfile",
    "fileCreationTimestamp", "hollow", "materialName", "numFade", "numFast", "numSlow",
    "printProfile", "printTime", "printerModel", "printerProfile", "printerVariant",
    "prusaSlicerVersion", "usedMaterial",
)
#: Keys of ``prusaslicer.ini`` (the seven ``display_*`` keys are required by PrusaSlicer).
PRUSASLICER_KEYS = (
    "display_width", "display_height", "display_pixels_x", "display_pixels_y",
    "display_mirror_x", "display_mirror_y", "display_orientation", "layer_height",
    "exposure_time", "initial_exposure_time", "gamma_correction", "printer_model",
    "printer_technology", "faded_layers",
)
THUMBNAIL_SIZES = ((400, 400), (800, 480))
#: Seconds per layer added to the exposure for the print-time estimate (tilt, settle).
SL1_TILT_TIME_S = 5.0
PERFACTORY_CFG = "build.cfg"
PERFACTORY_TXT = "job.txt"


@dataclass(frozen=True)
class JobInfo:
    """What an output says about the job besides the masks.

    ``mesh`` and ``device`` are JSON-ready dicts (``Mesh.info()``, ``device.model_dump()``).
    """

    job_name: str
    layer_height_mm: float
    layer_count: int
    copies: int
    width_px: int
    height_px: int
    pixel_x_mm: float
    pixel_y_mm: float
    mirror_x: bool
    mirror_y: bool
    orientation: str
    exposure_s: float
    first_exposure_s: float
    first_exposure_layers: int
    printer_model: str
    material_name: str = "rotoprint resin"
    device_name: str = ""
    device: dict = field(default_factory=dict)
    mesh: dict = field(default_factory=dict)
    source: str = ""
    options: dict = field(default_factory=dict)
    grid: dict = field(default_factory=dict)

    @property
    def mask_count(self) -> int:
        return self.layer_count * self.copies


_JOB_NAME = re.compile(r"[^A-Za-z0-9_-]+")


def job_dir_name(path: str | Path) -> str:
    """``jobDir`` of an archive: the file stem with anything but ``[A-Za-z0-9_-]`` as '_'."""
    name = _JOB_NAME.sub("_", Path(path).stem) or "job"
    return name


def _ini(d: dict) -> bytes:
    return "".join(f"{k} = {v}\n" for k, v in d.items()).encode("utf-8")


def _fmt(x: float) -> str:
    return f"{x:.6g}"


class _Stats:
    """Running statistics over the masks: material volume and the footprint for thumbnails."""

    def __init__(self, info: JobInfo, thickness_mm: float) -> None:
        self.px_area = info.pixel_x_mm * info.pixel_y_mm
        self.thickness = thickness_mm
        self.volume_mm3 = 0.0
        self.footprint = np.zeros((info.height_px, info.width_px), np.uint8)  # (pages untouched stay unmapped)
        self._box: tuple[int, int, int, int] | None = None  # rows r0:r1, columns c0:c1 merged so far

    def add_sum(self, plain_sum: int) -> float:
        """Count one mask whose plain grey levels add up to ``plain_sum``; returns its area."""
        area = float(plain_sum) / 255.0 * self.px_area
        self.volume_mm3 += area * self.thickness
        return area

    def add_footprint(self, crop: tuple[int, int, np.ndarray] | None) -> None:
        if crop is not None:
            r0, c0, a = crop
            view = self.footprint[r0 : r0 + a.shape[0], c0 : c0 + a.shape[1]]
            np.maximum(view, a, out=view)
            r1, c1 = r0 + view.shape[0], c0 + view.shape[1]
            b = self._box
            self._box = (r0, c0, r1, c1) if b is None else (min(b[0], r0), min(b[1], c0), max(b[2], r1), max(b[3], c1))

    @property
    def footprint_crop(self) -> np.ndarray | None:
        """The footprint within the rows and columns merged so far (a view; None before any):
        all of its non-zero pixels, without a pass over the whole field."""
        b = self._box
        return None if b is None else self.footprint[b[0] : b[2], b[1] : b[3]]


def _area_resize(a: np.ndarray, nh: int, nw: int) -> np.ndarray:
    """``(nh, nw) float64`` of ``a`` ``(H, W)`` resized: a box (area) average over each output
    pixel's span of input rows and columns (boundaries rounded to whole pixels) when
    shrinking, the nearest input pixel when growing."""

    def axis(x: np.ndarray, n_out: int, ax: int) -> np.ndarray:
        n = x.shape[ax]
        if n_out >= n:  # growing (or the same): nearest
            return np.take(x, np.minimum((np.arange(n_out) * n) // n_out, n - 1), axis=ax)
        edges = (np.arange(n_out + 1) * n + n_out // 2) // n_out
        sums = np.add.reduceat(x, edges[:-1], axis=ax, dtype=np.float64)  # no uint8 wrap
        shape = [1, 1]
        shape[ax] = n_out
        return sums / np.diff(edges).reshape(shape)

    # rows first, on the uint8 footprint; columns on the few rows left (contiguous)
    return np.ascontiguousarray(axis(np.ascontiguousarray(axis(a, nh, 0).T), nw, 0).T)


def _png_chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def _deflate_rle(data) -> bytes:
    z = zlib.compressobj(9, zlib.DEFLATED, 15, 9, zlib.Z_RLE)
    return z.compress(data) + z.flush()


def rgb_png(rgb: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of ``rgb`` ``(H, W, 3) uint8``: every row filtered "Up" (a flat
    background is all zero bytes), one zlib stream, run-length strategy (a third of level 9's
    time on such rows, about as small)."""
    h, w, _ = rgb.shape
    rows = rgb.reshape(h, w * 3)
    up = np.empty((h, w * 3 + 1), np.uint8)
    up[:, 0] = 2  # filter type Up
    up[0, 1:] = rows[0]
    np.subtract(rows[1:], rows[:-1], out=up[1:, 1:])  # modulo 256, as the filter is defined
    ihdr = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + _png_chunk(b"IHDR", ihdr) + _png_chunk(b"IDAT", _deflate_rle(up)) + \
        _png_chunk(b"IEND", b"")


#: (background, part) level of each of R, G, B in the thumbnails: orange on dark grey
_THUMB_COLOURS = ((24, 250), (24, 140), (24, 30))


def thumbnail_png(footprint: np.ndarray | None, size: tuple[int, int]) -> bytes:
    """An RGB PNG of ``size`` (w, h) showing the part's footprint (max over the masks): the
    footprint's bounding box scaled to fit with a 4-pixel margin (area average), orange on
    dark grey. numpy and zlib only (no Pillow at a job's start-up)."""
    w, h = size
    canvas = np.full((h, w, 3), 24, np.uint8)
    if footprint is not None and footprint.any():
        rows = np.flatnonzero(footprint.any(axis=1))
        cols = np.flatnonzero(footprint.any(axis=0))
        crop = footprint[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
        ch, cw = crop.shape
        scale = min((w - 8) / cw, (h - 8) / ch)
        nw, nh = max(1, round(cw * scale)), max(1, round(ch * scale))
        y0, x0 = (h - nh) // 2, (w - nw) // 2
        from ..._accel import native

        if native is not None:  # the same operations in C, in one pass (no float temporaries)
            rgb = np.empty((nh, nw, 3), np.uint8)
            native.thumb_rgb(np.ascontiguousarray(crop), ch, cw, nh, nw, rgb, *(c for pair in _THUMB_COLOURS for c in pair))
            canvas[y0 : y0 + nh, x0 : x0 + nw] = rgb
        else:
            g = _area_resize(crop, nh, nw) / 255.0
            level = np.empty_like(g)
            for k, (c0, c1) in enumerate(_THUMB_COLOURS):
                np.multiply(g, float(c1 - c0), out=level)  # round(c0 + (c1 - c0) * g), in place
                level += float(c0)
                np.rint(level, out=level)  # (what round() does with no decimals: half to even)
                canvas[y0 : y0 + nh, x0 : x0 + nw, k] = level  # whole values in 24..250: exact
    return rgb_png(canvas)


def _print_time_s(info: JobInfo, n_layers: int) -> float:
    nf = min(info.first_exposure_layers, n_layers)
    return nf * info.first_exposure_s + (n_layers - nf) * info.exposure_s + n_layers * SL1_TILT_TIME_S


def _zinfo(name: str) -> zipfile.ZipInfo:
    """A zip entry with a fixed date, so that archives of the same job are the same bytes."""
    return zipfile.ZipInfo(name, date_time=(2020, 1, 1, 0, 0, 0))


_EPOCH_S = Range(0, 253_402_300_799, integer=True)  # 1970 to the end of year 9999


def creation_time() -> datetime.datetime:
    """Now, or ``SOURCE_DATE_EPOCH`` when set (reproducible outputs)."""
    import os

    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    if epoch is not None:
        try:
            secs = int(epoch)
        except ValueError:
            raise ConfigError(f"SOURCE_DATE_EPOCH must be whole seconds, got {epoch!r}") from None
        secs = check_range(secs, _EPOCH_S, "SOURCE_DATE_EPOCH")
        return datetime.datetime.fromtimestamp(secs, datetime.timezone.utc)
    return datetime.datetime.now(datetime.timezone.utc)


@dataclass
class ArchiveContents:
    """A DLP job reopened: format, its ini tables (SL1) or manifest (folders), mask names.

    ``mask(i)`` decodes mask ``i`` as ``(H, W) uint8``; ``thumbnails`` maps names to
    ``(width, height)``.
    """

    path: Path
    format: str
    config: dict[str, str]
    prusaslicer: dict[str, str]
    manifest: dict
    mask_names: list[str]
    thumbnails: dict[str, tuple[int, int]]
    _reader: Callable[[str], bytes]

    def __len__(self) -> int:
        return len(self.mask_names)

    def mask(self, i: int) -> np.ndarray:
        data = self._reader(self.mask_names[i])
        with open_image(data, self.path, f"mask {self.mask_names[i]}") as im:
            if im.mode != "L":
                raise ImageError(f"mask {self.mask_names[i]} is mode {im.mode!r}, expected 'L' (8-bit grey)", path=self.path)
            return np.asarray(im).copy()


def _parse_ini(text: str, where: str, path: Path) -> dict[str, str]:
    out: dict[str, str] = {}
    for n, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s or s.startswith(("#", ";", "[")):
            continue
        if "=" not in s:
            raise InputFileError(f"{where} line {n} is not 'key = value': {s[:60]!r}", path=path)
        k, v = s.split("=", 1)
        out[k.strip()] = v.strip()
    return out


@dataclass(frozen=True)
class ArchiveFormat:
    """One output format in the registry.

    Attributes
    ----------
    name : str
        As given to ``--format`` and recorded in the output.
    is_dir : bool
        A folder (else one file).
    suffixes : tuple of str
        Output suffixes that select it when no format is given (``.sl1``).
    kind : str
        Folders: the manifest's ``kind`` (how a folder is told apart when reopened); files: "".
    write : callable
        ``(path, items, info, on_mask, claim) -> dict``: write the encoded masks into the
        claimed temporary path and install it; returns the summary.
    open : callable
        ``(path, manifest, names) -> ArchiveContents``: reopen an output (folders: with their
        checked manifest and mask names; files: both None).
    mask_name : callable
        ``number -> str``: the file name of mask ``number`` (folders).
    """

    name: str
    is_dir: bool
    suffixes: tuple[str, ...]
    kind: str
    write: Callable
    open: Callable
    mask_name: Callable[[int], str] = field(default=lambda n: f"{n:05d}.png")
