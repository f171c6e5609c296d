"""A Perfactory-style job folder: masks ``00000.png`` ... in projection order, ``manifest.json``,
``build.cfg`` (an ini ``[build]`` table) and a readable ``job.txt``."""

from __future__ import annotations

from pathlib import Path

from ..._version import __version__
from ..atomic import OutputClaim
from ..inputs import MAX_JSON_BYTES, read_input_text
from ._common import PERFACTORY_CFG, PERFACTORY_TXT, ArchiveContents, ArchiveFormat, JobInfo, _fmt, _ini, _parse_ini, _Stats
from .png import mask_reader, write_folder

__all__ = ["PERFACTORY"]


def _extra(tmp: Path, info: JobInfo, entries: list, stats: _Stats) -> None:
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


def _write(path, items, info: JobInfo, on_mask, claim: OutputClaim) -> dict:
    return write_folder(path, items, info, on_mask, claim, fmt=PERFACTORY, extra=_extra)


def _open(path: Path, manifest: dict, names: list[str]) -> ArchiveContents:
    cfg = _parse_ini(read_input_text(path / PERFACTORY_CFG, what=PERFACTORY_CFG, limit_bytes=MAX_JSON_BYTES),
                     PERFACTORY_CFG, path)
    return ArchiveContents(path, "perfactory", cfg, {}, manifest, names, {}, mask_reader(path))


PERFACTORY = ArchiveFormat("perfactory", is_dir=True, suffixes=(), kind="perfactory-job", write=_write, open=_open,
                           mask_name=lambda n: f"{n:05d}.png")
