"""SL1 and SL1S archives (what PrusaSlicer and UVtools read): a zip with ``config.ini``
(``key = value``), ``prusaslicer.ini`` (the ``display_*`` keys PrusaSlicer requires), layers
``<jobDir>00000.png`` ... (8-bit grey, from 0, five digits) and the thumbnails
``thumbnail/thumbnail400x400.png`` and ``thumbnail/thumbnail800x480.png``. UVtools counts
layers as ``numSlow + numFast``; every layer is written as a fast-tilt layer.

ERM (two masks per slice): the printer takes one mask per height step, so the ``2 N`` masks
are written as ``2 N`` layers of half the layer height (the same total height; each slice's
second, shifted copy is the layer above it)."""

from __future__ import annotations

import functools
import io
import re
import zipfile
from pathlib import Path


from ..._version import __version__
from ...errors import ConfigError, InputFileError
from ..atomic import OutputClaim, kill_point
from ..images import open_image
from ..inputs import MAX_ARCHIVE_BYTES, read_input_bytes, read_zip_members
from ..ownership import zip_marker
from ._common import (
    CONFIG_KEYS,
    PRUSASLICER_KEYS,
    THUMBNAIL_SIZES,
    ArchiveContents,
    ArchiveFormat,
    JobInfo,
    _fmt,
    _ini,
    _parse_ini,
    _print_time_s,
    _Stats,
    _zinfo,
    creation_time,
    job_dir_name,
    thumbnail_png,
)

__all__ = ["SL1", "SL1S"]


def _write_sl1(path, items, info: JobInfo, on_mask, claim: OutputClaim, *, fmt: str) -> dict:
    job_dir = job_dir_name(path)
    n_out = info.mask_count
    thickness = info.layer_height_mm / info.copies
    stats = _Stats(info, thickness)
    names: list[str] = []
    thumbs: _Background | None = None
    try:
        with open(claim.part, "wb") as fh, zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            for m in items:
                if thumbs is None and not names and m.whole_footprint and m.footprint is not None:
                    # the job's whole footprint comes first: the thumbnails (mostly zlib and C,
                    # without the GIL) are drawn on another core while the masks are stored
                    thumbs = _Background(lambda crop=m.footprint[2]: [thumbnail_png(crop, size) for size in THUMBNAIL_SIZES])
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
            pngs = thumbs.result() if thumbs is not None else [thumbnail_png(stats.footprint_crop, size) for size in THUMBNAIL_SIZES]
            for size, png in zip(THUMBNAIL_SIZES, pngs, strict=True):
                # deflated too: a thumbnail of flat colour (a prism's footprint) shrinks 8x (1417 to
                # 175 bytes); the fixed part of the archive is most of a small job's bytes
                zf.writestr(_zinfo(f"thumbnail/thumbnail{size[0]}x{size[1]}.png"), png,
                            compress_type=zipfile.ZIP_DEFLATED, compresslevel=9)
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
            zf.writestr(_zinfo("config.ini"), _ini(config), compress_type=zipfile.ZIP_DEFLATED, compresslevel=9)
            zf.writestr(_zinfo("prusaslicer.ini"), _ini(prusa), compress_type=zipfile.ZIP_DEFLATED, compresslevel=9)
            zip_marker(zf, f"dlp-{fmt}")
    finally:
        if thumbs is not None:  # (also when storing the masks failed: nothing outlives the writer)
            thumbs.join()
    claim.install()
    return {"format": fmt, "path": str(path), "masks": n_out, "config": config, "prusaslicer": prusa, "volume_mm3": stats.volume_mm3}


class _Background:
    """``fn()`` run in a thread; :meth:`result` waits for it and returns its value or raises
    its exception."""

    def __init__(self, fn) -> None:
        import threading

        self._fn, self._value, self._exc = fn, None, None
        self._thread = threading.Thread(target=self._run, name="rotoprint-thumbnails", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            self._value = self._fn()
        except BaseException as exc:  # noqa: BLE001 - handed to the caller in result()
            self._exc = exc

    def join(self) -> None:
        self._thread.join()

    def result(self):
        self._thread.join()
        if self._exc is not None:
            raise self._exc
        return self._value


def _open(path: Path, manifest=None, names=None) -> ArchiveContents:
    """Reopen an archive (any file that is not a folder is opened as a zip)."""
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


SL1 = ArchiveFormat("sl1", is_dir=False, suffixes=(".sl1",), kind="", write=functools.partial(_write_sl1, fmt="sl1"), open=_open)
SL1S = ArchiveFormat("sl1s", is_dir=False, suffixes=(".sl1s",), kind="", write=functools.partial(_write_sl1, fmt="sl1s"), open=_open)
