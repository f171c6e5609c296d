"""A :class:`RotaryPrint` as the bytes of its PNG images plus a JSON sidecar, and reading it back.

``PRINT.png`` for one swathe; ``PRINT-s1.png``, ``PRINT-s2.png``, ... for several; always the
sidecar ``PRINT.json`` listing them. :func:`print_files` makes the bytes;
:func:`rotoprint.pipeline.prints.write_print` writes them (atomically, after all images are
encoded, so an error leaves nothing behind).
"""

from __future__ import annotations

import glob
import hashlib
import json
import math
import re
from pathlib import Path

import numpy as np

from .. import ranges as R
from .._resources import check_raster_fits
from ..ranges import check_range

from ..devices.models import InkjetHead
from pydantic import ValidationError

from ..errors import ImageError, InputFileError, RotoprintError
from ..io.ownership import mark_json, mark_png
from ..io.records import MissingKeyError, as_record, missing_key_message, validation_line
from ..io.images import png_bytes
from ..io.images import open_image
from ..io.inputs import MAX_IMAGE_BYTES, read_input_bytes, read_json_file
from .head import check_tilt
from .placement import Placement
from .printdata import SIDECAR_FORMAT, RotaryPrint, SwatheImage, levels_to_png, png_to_levels, runs_to_mask

__all__ = ["check_print_fields", "print_files", "print_paths", "read_print", "swathe_filenames", "sidecar_path"]


def swathe_filenames(out_png: Path, n: int) -> list[Path]:
    """File names of the swathe images of a print written as ``out_png``.

    Parameters
    ----------
    out_png : Path
    n : int
        Number of swathes.

    Returns
    -------
    list of Path
        ``[out_png]`` for one swathe, else ``PRINT-s1.png`` ... ``PRINT-sN.png`` beside it.
    """
    out_png = Path(out_png)
    if n == 1:
        return [out_png]
    return [out_png.with_name(f"{out_png.stem}-s{j + 1}{out_png.suffix}") for j in range(n)]


def print_files(pr: RotaryPrint, png_name: str, *, device_name: str = "", design: dict | None = None) -> tuple[dict[str, bytes], dict]:
    """The files of a print as bytes, ``{name: bytes}`` (swathe PNGs, then the sidecar JSON
    named like ``png_name`` with ``.json``), and the sidecar dict."""
    files = swathe_filenames(Path(png_name), len(pr.swathes))
    blobs = [mark_png(png_bytes(levels_to_png(s.levels, pr.head.grey_levels)), "rotary-print") for s in pr.swathes]
    side = pr.to_json(files=[f.name for f in files], device_name=device_name, design=design)
    for d, b in zip(side["swathes"], blobs):
        d["sha256"] = hashlib.sha256(b).hexdigest()
    out = {f.name: b for f, b in zip(files, blobs)}
    side = mark_json(side)
    out[Path(png_name).with_suffix(".json").name] = (json.dumps(side, indent=2) + "\n").encode("utf-8")
    return out, side


def print_paths(out_png: str | Path) -> list[Path]:
    """Every file a print written to ``out_png`` may take: the PNG, its sidecar, and any
    existing swathe images ``STEM-sN.png`` beside it (all are checked before a write).

    Parameters
    ----------
    out_png : str or Path

    Returns
    -------
    list of Path
    """
    out_png = Path(out_png)
    parent = out_png.parent if str(out_png.parent) else Path(".")
    found = sorted(p for p in parent.glob(f"{glob.escape(out_png.stem)}-s*.png") if re.fullmatch(r"-s[0-9]+", p.stem[len(out_png.stem):]))
    return [out_png, out_png.with_suffix(".json"), *found]


def sidecar_path(path: str | Path) -> Path:
    """The sidecar of a print: ``X.json`` itself, ``X.png`` -> ``X.json``, ``X-s2.png`` -> ``X.json``.

    Parameters
    ----------
    path : str or Path
        The sidecar or one of the print's images.

    Returns
    -------
    Path
        ``path`` with the suffix ``.json`` when that file exists or the stem has no ``-sN``
        ending; else the name with ``-sN`` dropped (``X-s2.png`` -> ``X.json``). The returned
        file need not exist.
    """
    p = Path(path)
    if p.suffix.lower() == ".json":
        return p
    cand = p.with_suffix(".json")
    if cand.exists():
        return cand
    m = re.fullmatch(r"(.*)-s\d+", p.stem)
    if m:
        return p.with_name(m.group(1) + ".json")
    return cand


_FINITE = R.Range(-math.inf, math.inf)


def _number(d: dict, key: str, where: str, sp: Path, *, positive: bool = False, rng: R.Range | None = None,
            what: str = "sidecar field") -> float:
    """``d[key]`` as a finite float (``> 0`` if ``positive``; in ``rng`` if given; an int if
    ``rng.integer``), or an InputFileError naming the field (``what`` before its name)."""
    v = d[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or v not in _FINITE:  # an int past floats too
        raise InputFileError(f"{what} {where}{key} must be a finite number, got {R.show_value(v)}", path=sp)
    if positive and not v > 0:
        raise InputFileError(f"{what} {where}{key} must be > 0, got {v!r}", path=sp)
    if rng is not None:
        return check_range(v, rng, f"{what} {where}{key}", error=InputFileError, path=sp)
    return float(v)


_FIRING_INDEX = R.Range(-R.MAX_COUNT, R.MAX_COUNT, integer=True)
_DPHI_RAD = R.Range(0.0, 2 * math.pi, "rad", lo_open=True)


def _check_placement(pl: dict, sp: Path) -> None:
    """The sidecar's ``placement`` table: whole positive pixel counts, positive pitches and inner
    radius, a finite angle (InputFileError naming ``sp`` and the field; KeyError if one is missing)."""
    if not isinstance(pl, dict):
        raise InputFileError(f"sidecar field placement must be a table, got {R.show_value(pl)}", path=sp)
    for key in ("width_px", "height_px"):
        _number(pl, key, "placement.", sp, rng=R.Range(1, R.MAX_COUNT, integer=True))
    for key in ("pitch_x_mm", "pitch_y_mm", "inner_radius_mm"):
        _number(pl, key, "placement.", sp, positive=True)
    if "angle_deg" in pl:
        _number(pl, "angle_deg", "placement.", sp, rng=R.ANGLE_DEG)


def check_print_fields(side: dict, head: InkjetHead, sp: Path, *, what: str = "sidecar field", flat: bool = False) -> None:
    """Range checks on the numbers of a sidecar (:mod:`rotoprint.ranges`): tilt within the
    head's limit, angles, densities and radii in range, integer counts and nozzle runs within
    the head, and every swathe image sized before it is read.

    Also for the image records of a machine program (:mod:`rotoprint.machine.replay`), which
    carry the same fields: ``what`` starts each message (``"sidecar field"``, or the record's
    place and ``"field"``), and ``flat`` names a swathe's fields without their ``swathes[j].``
    (a record of one swathe). Raises InputFileError naming ``sp``; KeyError if a field is missing."""
    tilt = _number(side, "tilt_deg", "", sp, what=what)
    _number(side, "mount_angle_deg", "", sp, rng=R.ANGLE_DEG, what=what)
    _number(side, "dpi_y", "", sp, positive=True, rng=R.DPI, what=what)
    if side["direction"] not in (1, -1) or isinstance(side["direction"], bool):
        raise InputFileError(f"{what} direction must be 1 or -1, got {R.show_value(side['direction'])}", path=sp)
    if not isinstance(side["swathes"], list) or not 1 <= len(side["swathes"]) <= R.SWATHES.hi:
        raise InputFileError(f"{what} swathes must be a list of 1 to {R.SWATHES.hi:g} swathes", path=sp)
    pixels = 0
    for j, d in enumerate(side["swathes"]):
        where = "" if flat else f"swathes[{j}]."
        if not isinstance(d, dict):
            raise InputFileError(f"{what} swathes[{j}] must be a table, got {R.show_value(d)}", path=sp)
        dphi = _number(d, "dphi_rad", where, sp, positive=True, rng=_DPHI_RAD, what=what)
        if "angle_per_firing_deg" in d:
            deg = _number(d, "angle_per_firing_deg", where, sp, positive=True, what=what)
            if not math.isclose(deg, math.degrees(dphi), rel_tol=1e-9):
                raise InputFileError(f"{what} {where}angle_per_firing_deg is {deg!r}, but dphi_rad "
                                     f"{dphi!r} is {math.degrees(dphi)!r} deg", path=sp)
        _number(d, "pivot_radius_mm", where, sp, positive=True, rng=R.RADIUS_MM, what=what)
        _number(d, "ref_radius_mm", where, sp, positive=True, rng=R.RADIUS_MM, what=what)
        _number(d, "index", where, sp, rng=R.COUNT, what=what)
        _number(d, "first_firing_index", where, sp, rng=_FIRING_INDEX, what=what)
        firings = _number(d, "firings", where, sp, rng=R.Range(1, R.MAX_COUNT, integer=True), what=what)
        n = d.get("nozzles")
        if isinstance(n, int) and not isinstance(n, bool) and n > head.nozzles:
            raise InputFileError(f"{what} {where}nozzles is {n}, more than the head has (head.nozzles {head.nozzles}): "
                                 "the head does not match its images", path=sp)
        nozzles = _number(d, "nozzles", where, sp, rng=R.Range(1, head.nozzles, integer=True), what=what)
        _number(d, "enabled_nozzles", where, sp, rng=R.Range(0, head.nozzles, integer=True), what=what)
        runs = d.get("enabled_nozzle_runs")
        if runs is not None:
            ok = isinstance(runs, list) and len(runs) <= head.nozzles and all(
                isinstance(r, list) and len(r) == 2 and all(isinstance(k, int) and not isinstance(k, bool) for k in r)
                and 0 <= r[0] < r[1] <= head.nozzles for r in runs)
            if not ok:
                raise InputFileError(f"{what} {where}enabled_nozzle_runs must be [start, end) nozzle runs "
                                     f"within the head's {head.nozzles} nozzles", path=sp)
        if not isinstance(d["band_mm"], list) or len(d["band_mm"]) != 2:
            raise InputFileError(f"{what} {where}band_mm must be [low, high], got {R.show_value(d['band_mm'])}", path=sp)
        lo, hi = (_number({"band_mm": v}, "band_mm", where, sp, rng=R.COORD_MM, what=what) for v in d["band_mm"])
        if not hi >= lo:
            raise InputFileError(f"{what} {where}band_mm must be [low, high] with high >= low, got {R.show_value(d['band_mm'])}", path=sp)
        pixels += firings * nozzles
    check_raster_fits(1, pixels, 2, what=f"{sp.name}: the swathe images")
    try:  # after the swathes: a head that does not match its images (head.nozzles 1) is named as such first
        check_tilt(head, tilt)
    except RotoprintError as exc:
        raise InputFileError(f"{what} tilt_deg: {exc.problem}", path=sp) from None


def read_print(path: str | Path) -> tuple[RotaryPrint, dict, Path]:
    """Read a print written by :func:`rotoprint.pipeline.prints.write_print` from its PNG or its sidecar.

    Parameters
    ----------
    path : str or Path
        A swathe PNG (``X.png``, ``X-s2.png``), the sidecar ``X.json``, or ``X.png`` (the name
        given to ``rotoprint transform -o``) when the swathes were written as ``X-s1.png`` ...

    Returns
    -------
    print : RotaryPrint
        The swathe images (``(firings, nozzles) uint8`` levels each) and their setting.
    sidecar : dict
        The parsed sidecar JSON.
    sidecar_path : Path

    Raises
    ------
    InputFileError
        Missing files, a sidecar that is not ours, or a sidecar field that is missing, of the
        wrong type, or out of range (a tilt at or beyond the head's limit, ``dphi_rad <= 0``,
        ``head.nozzles`` not a whole number > 0); one line in words naming the sidecar and the
        field by its path (:mod:`rotoprint.io.records`), never pydantic's own text.
    ImageError
        A swathe image that is not 8-bit greyscale or not the size the sidecar says.
    """
    p = Path(path)
    sp = sidecar_path(p)
    if not p.exists() and not (p.suffix.lower() == ".png" and sp.is_file()):
        # PRINT.png is the name given to 'transform -o' even when the swathes were written
        # as PRINT-s1.png ...: its sidecar PRINT.json names them
        raise InputFileError("no such file", path=p)
    if not sp.exists():
        raise InputFileError(f"no sidecar {sp.name} beside it (written by 'rotoprint transform')", path=p)
    side = read_json_file(sp, what="sidecar")
    if not isinstance(side, dict) or side.get("format") != SIDECAR_FORMAT:
        raise InputFileError(f"not a rotoprint rotary-print sidecar (format {SIDECAR_FORMAT!r} expected)", path=sp)
    side = as_record(side)
    try:
        try:
            head = InkjetHead.model_validate(side["head"])
        except ValidationError as exc:
            raise InputFileError(validation_line(exc, "head", record="the sidecar", field="sidecar field"),
                                 path=sp) from None
        check_print_fields(side, head, sp)
        _check_placement(side["placement"], sp)
        if not isinstance(side["method"], str):
            raise InputFileError(f"sidecar field method must be a text string, got {R.show_value(side['method'])}", path=sp)
        design = side.get("design", {})
        if not isinstance(design, dict) or not isinstance(design.get("kind", "binary"), str):
            raise InputFileError("sidecar field design must be a table whose kind is a text string, got "
                                 f"{R.show_value(design)}", path=sp)
        for j, d in enumerate(side["swathes"]):
            if not isinstance(d["file"], str):
                raise InputFileError(f"sidecar field swathes[{j}].file must be a file name, got {R.show_value(d['file'])}",
                                     path=sp)
        placement = Placement.from_json(side["placement"])
        swathes = []
        for d in side["swathes"]:
            f = sp.parent / d["file"]
            if not f.exists():
                raise InputFileError(f"swathe image {d['file']} listed in the sidecar is missing", path=sp)
            if not (sp.parent / d["file"]).resolve().is_relative_to(sp.parent.resolve()):
                raise InputFileError(f"swathe image {d['file']!r} listed in the sidecar is outside its folder", path=sp)
            data = read_input_bytes(f, what="print image", limit_bytes=MAX_IMAGE_BYTES)
            try:
                with open_image(data, f, "print image") as im:
                    im.load()
                    if im.mode != "L":
                        raise ImageError(f"print image must be 8-bit greyscale, got mode {im.mode!r}", path=f)
                    png = np.asarray(im)
            except OSError as exc:
                raise ImageError(f"not a readable image: {exc}", path=f) from None
            if png.shape != (d["firings"], d["nozzles"]):
                raise ImageError(
                    f"image is {png.shape[1]} x {png.shape[0]} px, the sidecar says {d['nozzles']} x {d['firings']}", path=f
                )
            runs = d.get("enabled_nozzle_runs")
            swathes.append(
                SwatheImage(
                    index=int(d["index"]),
                    levels=png_to_levels(png, head.grey_levels),
                    pivot_radius_mm=float(d["pivot_radius_mm"]),
                    first_firing=int(d["first_firing_index"]),
                    dphi_rad=float(d["dphi_rad"]),
                    ref_radius_mm=float(d["ref_radius_mm"]),
                    band_mm=(float(d["band_mm"][0]), float(d["band_mm"][1])),
                    enabled_nozzles=int(d["enabled_nozzles"]),
                    enabled=None if runs is None else runs_to_mask(runs, head.nozzles),
                )
            )
        pr = RotaryPrint(
            method=str(side["method"]),
            head=head,
            tilt_deg=float(side["tilt_deg"]),
            mount_angle_deg=float(side["mount_angle_deg"]),
            direction=int(side["direction"]),
            dpi_y=float(side["dpi_y"]),
            placement=placement,
            swathes=tuple(swathes),
            design_kind=design.get("kind", "binary"),
        )
    except MissingKeyError as exc:
        raise InputFileError(missing_key_message(exc, "the sidecar"), path=sp) from None
    except (KeyError, TypeError, ValueError) as exc:
        if isinstance(exc, RotoprintError):
            raise
        raise InputFileError(f"sidecar is incomplete or invalid: {type(exc).__name__}: {exc}", path=sp) from None
    return pr, side, sp
