"""DLP job outputs: SL1 / SL1S archives, a Perfactory-style job folder, a PNG folder with a
manifest, and a reader that reopens all three (used by the tests and by ``rotoprint``
itself to check what it wrote).

Every output is written under a temporary name beside the target and renamed when complete.

SL1 / SL1S (what PrusaSlicer and UVtools read): a zip with ``config.ini`` (``key = value``),
``prusaslicer.ini`` (the ``display_*`` keys PrusaSlicer requires), layers
``<jobDir>00000.png`` ... (8-bit grey, from 0, five digits) and the thumbnails
``thumbnail/thumbnail400x400.png`` and ``thumbnail/thumbnail800x480.png``. UVtools counts
layers as ``numSlow + numFast``; every layer is written as a fast-tilt layer.

ERM (two masks per slice) in an SL1 archive: the printer takes one mask per height step, so
the ``2 N`` masks are written as ``2 N`` layers of half the layer height (the same total
height; each slice's second, shifted copy is the layer above it, the staggered-brick
structure ERM aims at). The folder formats keep both masks of a slice at one height.
"""

from __future__ import annotations

import contextlib

import datetime
import hashlib
import io
import json
import re
import zipfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from PIL import Image

from .. import __version__
from ..ranges import Range, check_range
from ..errors import ConfigError, ImageError, InputFileError
from .atomic import MANIFEST_NAME, OutputClaim, kill_point
from .ownership import zip_marker
from .images import png_bytes
from .images import open_image
from .inputs import (MAX_ARCHIVE_BYTES, MAX_IMAGE_BYTES, MAX_JSON_BYTES, parse_json, read_input_bytes,
                     read_input_text, read_zip_members)

__all__ = [
    "FORMATS",
    "JobInfo",
    "write_job",
    "format_from_path",
    "read_job",
    "ArchiveContents",
    "CONFIG_KEYS",
    "PRUSASLICER_KEYS",
    "THUMBNAIL_SIZES",
    "SL1_TILT_TIME_S",
]

FORMATS = ("sl1", "sl1s", "png", "perfactory")

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
    if suffix in (".sl1", ".sl1s"):
        return suffix[1:]
    if suffix in (".zip", ".png", ".cws", ".ctb", ".pwmx"):
        raise ConfigError(f"cannot tell the format from {Path(path).name!r}: use .sl1, .sl1s or a folder")
    return "png"


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
        self.footprint = np.zeros((info.height_px, info.width_px), np.uint8)

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


@dataclass(frozen=True)
class _Encoded:
    """One mask ready to store: its PNG bytes, the sum of its plain (unmirrored, uninverted)
    grey levels, and a footprint crop ``(row0, col0, array)`` to merge (or None)."""

    number: int
    layer: int
    copy: int
    z_mm: float
    png: bytes
    plain_sum: int
    footprint: tuple[int, int, np.ndarray] | None


def thumbnail_png(footprint: np.ndarray | None, size: tuple[int, int]) -> bytes:
    """An RGB PNG of ``size`` (w, h) showing the part's footprint (max over the masks)."""
    w, h = size
    canvas = Image.new("RGB", (w, h), (24, 24, 24))
    if footprint is not None and footprint.any():
        rows = np.flatnonzero(footprint.any(axis=1))
        cols = np.flatnonzero(footprint.any(axis=0))
        crop = footprint[rows[0] : rows[-1] + 1, cols[0] : cols[-1] + 1]
        ch, cw = crop.shape
        scale = min((w - 8) / cw, (h - 8) / ch)
        nw, nh = max(1, round(cw * scale)), max(1, round(ch * scale))
        img = Image.fromarray(crop).resize((nw, nh), Image.Resampling.BOX if scale < 1 else Image.Resampling.NEAREST)
        g = np.asarray(img, dtype=np.float64) / 255.0
        rgb = np.empty((nh, nw, 3), np.uint8)
        for k, (c0, c1) in enumerate(((24, 250), (24, 140), (24, 30))):
            rgb[..., k] = np.round(c0 + (c1 - c0) * g).astype(np.uint8)
        canvas.paste(Image.fromarray(rgb), ((w - nw) // 2, (h - nh) // 2))
    buf = io.BytesIO()
    canvas.save(buf, format="PNG")
    return buf.getvalue()


def _print_time_s(info: JobInfo, n_layers: int) -> float:
    nf = min(info.first_exposure_layers, n_layers)
    return nf * info.first_exposure_s + (n_layers - nf) * info.exposure_s + n_layers * SL1_TILT_TIME_S


def _encoded(masks: Iterable, info: JobInfo, compress_level: int, workers: int):
    """Yield :class:`_Encoded` masks in order; PNG encoding (zlib, which releases the GIL)
    runs in ``workers`` threads while the next masks are computed. At most
    ``2 * workers + 1`` masks are held at once."""
    from concurrent.futures import ThreadPoolExecutor

    from .._window import ordered

    def done(m, data: bytes) -> _Encoded:
        return _Encoded(m.number, m.layer, m.copy, m.z_mm, data, int(m.plain.sum(dtype=np.uint64)), (0, 0, m.plain))

    def checked():
        for m in masks:
            _check_mask(m.image, info, m.number)
            yield m

    def encode(m) -> _Encoded:
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


def write_encoded(path: str | Path, items: Iterable[_Encoded], info: JobInfo, *, fmt: str,
                  on_mask: Callable[[int], None] | None = None, claim: OutputClaim | None = None,
                  force: bool = False) -> dict:
    """Write already-encoded masks (in projection order) as ``fmt``; see :func:`write_job`.

    ``claim`` is the entered :class:`~rotoprint.io.atomic.OutputClaim` of ``path`` when the
    caller holds it already (else one is taken here, with ``force``).
    """
    is_dir = fmt not in ("sl1", "sl1s")
    ctx = contextlib.nullcontext(claim) if claim is not None else OutputClaim(path, is_dir=is_dir, kind=f"dlp-{fmt}", force=force)
    with ctx as c:
        if not is_dir:
            return _write_sl1(Path(path), items, info, fmt, on_mask, c)
        return _write_folder(Path(path), items, info, fmt, on_mask, c)


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


def _write_sl1(path, items, info: JobInfo, fmt, on_mask, claim: OutputClaim) -> dict:
    job_dir = job_dir_name(path)
    n_out = info.mask_count
    thickness = info.layer_height_mm / info.copies
    stats = _Stats(info, thickness)
    names: list[str] = []
    with open(claim.part, "wb") as fh, zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for m in items:
            name = f"{job_dir}{m.number:05d}.png"
            # deflated again, as PrusaSlicer does: the layer PNGs of a mostly empty field
            # shrink 3-30x more (repeated deflate codes of empty rows)
            zf.writestr(_zinfo(name), m.png, compress_type=zipfile.ZIP_DEFLATED, compresslevel=9)
            names.append(name)
            kill_point(f"archive-{len(names)}")
            stats.add_sum(m.plain_sum)
            stats.add_footprint(m.footprint)
            if on_mask is not None:
                on_mask(m.number)
        if len(names) != n_out:
            raise ConfigError(f"expected {n_out} masks, got {len(names)}")
        for size in THUMBNAIL_SIZES:
            zf.writestr(_zinfo(f"thumbnail/thumbnail{size[0]}x{size[1]}.png"), thumbnail_png(stats.footprint, size),
                        compress_type=zipfile.ZIP_STORED)
        model = info.printer_model if info.printer_model != "rotoprint" else ("SL1S" if fmt == "sl1s" else "SL1")
        nfade = min(info.first_exposure_layers, n_out)
        config = {
            "action": "print",
            "jobDir": job_dir,
            "layerHeight": _fmt(thickness),
            "expTime": _fmt(info.exposure_s),
            "expTimeFirst": _fmt(info.first_exposure_s),
            "expUserProfile": 0,
            "fileCreationTimestamp": creation_time().strftime("%Y-%m-%d at %H:%M:%S UTC"),
            "hollow": 0,
            "materialName": info.material_name,
            "numFade": nfade,
            "numFast": n_out,
            "numSlow": 0,
            "printProfile": f"{_fmt(thickness)}mm rotoprint",
            "printTime": _fmt(round(_print_time_s(info, n_out), 1)),
            "printerModel": model,
            "printerProfile": f"rotoprint {info.device_name or model}",
            "printerVariant": "default",
            "prusaSlicerVersion": f"rotoprint {__version__}",
            "usedMaterial": _fmt(stats.volume_mm3 / 1000.0),
        }
        prusa = {
            "display_width": _fmt(info.width_px * info.pixel_x_mm),
            "display_height": _fmt(info.height_px * info.pixel_y_mm),
            "display_pixels_x": info.width_px,
            "display_pixels_y": info.height_px,
            "display_mirror_x": int(info.mirror_x),
            "display_mirror_y": int(info.mirror_y),
            "display_orientation": info.orientation,
            "layer_height": _fmt(thickness),
            "exposure_time": _fmt(info.exposure_s),
            "initial_exposure_time": _fmt(info.first_exposure_s),
            "gamma_correction": 1,
            "printer_model": model,
            "printer_technology": "SLA",
            "faded_layers": nfade,
        }
        zf.writestr(_zinfo("config.ini"), _ini(config), compress_type=zipfile.ZIP_DEFLATED)
        zf.writestr(_zinfo("prusaslicer.ini"), _ini(prusa), compress_type=zipfile.ZIP_DEFLATED)
        zip_marker(zf, f"dlp-{fmt}")
    claim.install()
    return {"format": fmt, "path": str(path), "masks": n_out, "config": config, "prusaslicer": prusa, "volume_mm3": stats.volume_mm3}


def mask_filename(number: int, fmt: str) -> str:
    return f"{number:05d}.png" if fmt == "perfactory" else f"mask_{number:05d}.png"


def _write_folder(path, items, info: JobInfo, fmt, on_mask, claim: OutputClaim) -> dict:
    stats = _Stats(info, info.layer_height_mm / info.copies)
    entries = []
    claim.part.mkdir()
    tmp = claim.part
    for m in items:
        name = mask_filename(m.number, fmt)
        data = m.png
        (tmp / name).write_bytes(data)
        area = stats.add_sum(m.plain_sum)
        stats.add_footprint(m.footprint)
        entries.append(
            {
                "index": m.number,
                "file": name,
                "layer": m.layer,
                "copy": m.copy,
                "z_mm": m.z_mm,
                "exposed_area_mm2": area,
                "sha256": hashlib.sha256(data).hexdigest(),
            }
        )
        if on_mask is not None:
            on_mask(m.number)
    if len(entries) != info.mask_count:
        raise ConfigError(f"expected {info.mask_count} masks, got {len(entries)}")
    inverted = bool(info.options.get("invert", False))
    manifest = {
        "rotoprint_version": __version__,
        "kind": "dlp-masks" if fmt == "png" else "perfactory-job",
        "source": info.source,
        "mesh": info.mesh,
        "device_name": info.device_name,
        "device": info.device,
        "options": info.options,
        "layer_height_mm": info.layer_height_mm,
        "masks_per_layer": info.copies,
        "grid": info.grid,
        "image": {
            "format": "png",
            "mode": "L",
            "expose": 0 if inverted else 255,
            "masked": 255 if inverted else 0,
            "grey": info.options.get("mode", "binary") != "binary" or bool(info.options.get("first_layers", 0)),
            "mirror_x": info.mirror_x,
            "mirror_y": info.mirror_y,
        },
        "exposure_s": info.exposure_s,
        "first_exposure_s": info.first_exposure_s,
        "first_exposure_layers": info.first_exposure_layers,
        "volume_mm3": stats.volume_mm3,
        "layer_count": info.layer_count,
        "mask_count": len(entries),
        "masks": entries,
    }
    if fmt == "perfactory":
        cfg = {
            "job": info.job_name,
            "masks": len(entries),
            "layers": info.layer_count,
            "masks_per_layer": info.copies,
            "erm": int(info.copies == 2),
            "layer_thickness_mm": _fmt(info.layer_height_mm),
            "pixels_x": info.width_px,
            "pixels_y": info.height_px,
            "pixel_size_x_mm": _fmt(info.pixel_x_mm),
            "pixel_size_y_mm": _fmt(info.pixel_y_mm),
            "exposure_s": _fmt(info.exposure_s),
            "first_exposure_s": _fmt(info.first_exposure_s),
            "first_exposure_layers": info.first_exposure_layers,
            "mask_files": "00000.png ... in projection order",
        }
        (tmp / PERFACTORY_CFG).write_bytes(b"[build]\n" + _ini(cfg))
        opts = ", ".join(f"{k}={v}" for k, v in info.options.items())
        (tmp / PERFACTORY_TXT).write_text(
            f"rotoprint {__version__} Perfactory-style job '{info.job_name}'\n"
            f"source: {info.source}\ndevice: {info.device_name}\noptions: {opts}\n"
            f"{info.layer_count} layers x {info.copies} mask(s), {info.width_px} x {info.height_px} px\n"
            f"material volume: {stats.volume_mm3:.3f} mm^3\n",
            encoding="utf-8",
        )
    (tmp / MANIFEST_NAME).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    claim.install()
    return manifest


# ---------------------------------------------------------------------------------- reading


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
        mpath = path / MANIFEST_NAME
        if not mpath.exists():
            raise InputFileError(f"folder holds no {MANIFEST_NAME}", path=path)
        try:
            manifest = parse_json(read_input_bytes(mpath, what=MANIFEST_NAME, limit_bytes=MAX_JSON_BYTES),
                                  mpath, what=MANIFEST_NAME)
            names = [str(m["file"]) for m in manifest["masks"]]
        except (ValueError, KeyError, TypeError, RecursionError) as exc:  # JSONDecodeError is a ValueError
            raise InputFileError(f"{MANIFEST_NAME} is not a mask list ({type(exc).__name__}: {exc})", path=path) from None
        except InputFileError as exc:
            raise InputFileError(f"{MANIFEST_NAME} is not a mask list ({exc.problem})", path=path) from None
        root = path.resolve()
        for n in names:
            if not (path / n).resolve().is_relative_to(root):
                raise InputFileError(f"mask {n!r} listed in the manifest is outside the folder", path=path)
            if not (path / n).is_file():
                raise InputFileError(f"mask {n} listed in the manifest is missing", path=path)
        fmt = "perfactory" if manifest.get("kind") == "perfactory-job" else "png"
        cfg = {}
        if fmt == "perfactory":
            cfg = _parse_ini(read_input_text(path / PERFACTORY_CFG, what=PERFACTORY_CFG, limit_bytes=MAX_JSON_BYTES),
                             PERFACTORY_CFG, path)
        return ArchiveContents(path, fmt, cfg, {}, manifest, names, {},
                               lambda n: read_input_bytes(path / n, what="mask image", limit_bytes=MAX_IMAGE_BYTES))
    data = read_input_bytes(path, what="SL1 archive", limit_bytes=MAX_ARCHIVE_BYTES)
    if not zipfile.is_zipfile(io.BytesIO(data)):
        raise InputFileError("not a zip archive (SL1 / SL1S expected)", path=path)
    members = read_zip_members(data, path, what="SL1 archive")
    del data
    for req in ("config.ini", "prusaslicer.ini"):
        if req not in members:
            raise InputFileError(f"archive has no {req}", path=path)
    try:
        config = _parse_ini(members["config.ini"].decode("utf-8"), "config.ini", path)
        prusa = _parse_ini(members["prusaslicer.ini"].decode("utf-8"), "prusaslicer.ini", path)
    except UnicodeDecodeError as exc:
        raise InputFileError(f"archive ini member is not UTF-8 text (byte {exc.start})", path=path) from None
    missing = [k for k in CONFIG_KEYS if k not in config] + [k for k in PRUSASLICER_KEYS if k not in prusa]
    if missing:
        raise InputFileError(f"archive lacks keys: {', '.join(missing)}", path=path)
    job_dir = config["jobDir"]
    layer_re = re.compile(re.escape(job_dir) + r"(\d{5})\.png$")
    layers = sorted(n for n in members if layer_re.fullmatch(n))
    expect = [f"{job_dir}{i:05d}.png" for i in range(len(layers))]
    if layers != expect:
        raise InputFileError("layer names are not <jobDir>00000.png ... in sequence", path=path)
    try:
        n_cfg = int(config["numFast"]) + int(config["numSlow"])
    except ValueError:
        raise InputFileError(f"config.ini numFast / numSlow are not whole numbers: {config['numFast']!r}, "
                             f"{config['numSlow']!r}", path=path) from None
    if n_cfg != len(layers):
        raise InputFileError(f"config.ini counts {n_cfg} layers (numFast + numSlow), the archive holds {len(layers)}", path=path)
    thumbs = {}
    for n, data in members.items():
        if n.startswith("thumbnail/") and n.endswith(".png"):
            with open_image(data, path, f"thumbnail {n}") as im:
                thumbs[n] = im.size
    fmt = path.suffix.lower().lstrip(".") if path.suffix.lower() in (".sl1", ".sl1s") else "sl1"
    return ArchiveContents(path, fmt, config, prusa, {}, layers, thumbs, members.__getitem__)
