"""A folder of PNG masks (``mask_00000.png`` ..., white = expose) with ``manifest.json``; the
folder writer and reader the Perfactory-style job shares."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

from ..._hashing import sha256 as _sha256
from ..._version import __version__
from ...errors import ConfigError, InputFileError
from ..atomic import MANIFEST_NAME, OutputClaim
from ..inputs import MAX_IMAGE_BYTES, MAX_JSON_BYTES, parse_json, read_input_bytes
from ._common import ArchiveContents, ArchiveFormat, JobInfo, _Stats

__all__ = ["PNG", "write_folder", "read_folder"]


def write_folder(path, items, info: JobInfo, on_mask, claim: OutputClaim, *, fmt: ArchiveFormat,
                 extra: Callable[[Path, JobInfo, list, _Stats], None] | None = None) -> dict:
    """Write the masks, one PNG each, and ``manifest.json`` into the claimed folder; ``extra``
    adds the format's own files (given the folder, the job, the manifest entries and the
    statistics)."""
    stats = _Stats(info, info.layer_height_mm / info.copies)
    entries = []
    claim.part.mkdir()
    tmp = claim.part
    for m in items:
        name = fmt.mask_name(m.number)
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
                "sha256": _sha256(data).hexdigest(),
            }
        )
        if on_mask is not None:
            on_mask(m.number)
    if len(entries) != info.mask_count:
        raise ConfigError(f"expected {info.mask_count} masks, got {len(entries)}")
    inverted = bool(info.options.get("invert", False))
    manifest = {
        "rotoprint_version": __version__,
        "kind": fmt.kind,
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
    if extra is not None:
        extra(tmp, info, entries, stats)
    (tmp / MANIFEST_NAME).write_text(json.dumps(manifest, indent=1), encoding="utf-8")
    claim.install()
    return manifest


def read_folder(path: Path) -> tuple[dict, list[str]]:
    """The manifest of a mask folder and its mask names, each checked to exist."""
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
    return manifest, names


def _write(path, items, info: JobInfo, on_mask, claim: OutputClaim) -> dict:
    return write_folder(path, items, info, on_mask, claim, fmt=PNG)


def _open(path: Path, manifest: dict, names: list[str]) -> ArchiveContents:
    return ArchiveContents(path, "png", {}, {}, manifest, names, {}, mask_reader(path))


def mask_reader(path: Path):
    """Reads the mask file ``name`` of the folder ``path``, bounded in size."""
    return lambda n: read_input_bytes(path / n, what="mask image", limit_bytes=MAX_IMAGE_BYTES)


PNG = ArchiveFormat("png", is_dir=True, suffixes=(), kind="dlp-masks", write=_write, open=_open,
                    mask_name=lambda n: f"mask_{n:05d}.png")
