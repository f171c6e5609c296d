"""Writing a rotary print (:func:`rotoprint.rotary.files.print_files`: swathe PNGs and the
sidecar) to ``PRINT.png``: every file atomic and marked as ours, nothing replaced that is not
provably ours (``rotoprint transform``)."""

from __future__ import annotations

from pathlib import Path

from ..errors import InputFileError
from ..io.atomic import check_output_path, write_owned_file
from ..rotary.files import print_files, print_paths
from ..rotary.printdata import RotaryPrint

__all__ = ["write_print", "transform_passes"]


def _check_then_write(first: Path, files: dict[Path, bytes], also: list[Path], *, inputs, force: bool) -> None:
    """Check ``first`` and every path of ``also`` (:func:`rotoprint.io.atomic.check_output_path`:
    none an input, none there and not provably ours) before the first file is written, then
    write ``files`` (path -> bytes), each atomically and marked as ours."""
    check_output_path(first, is_dir=False, inputs=inputs, force=force, also=also)
    for path, data in files.items():
        write_owned_file(path, data, kind="rotary-print", inputs=inputs, force=force, marked=True)


def write_print(pr: RotaryPrint, out_png: str | Path, *, device_name: str = "", design: dict | None = None,
                force: bool = False, inputs=()) -> dict:
    """Write the swathe images and the sidecar; returns the sidecar dict.

    Parameters
    ----------
    pr : RotaryPrint
    out_png : str or Path
        ``PRINT.png``; the swathe images are named by :func:`rotoprint.rotary.files.swathe_filenames` and the sidecar
        ``PRINT.json``, all in the same folder. Each file is written atomically.
    device_name : str
        Recorded in the sidecar as ``device``.
    design : dict, optional
        Extra fields for the sidecar's ``design`` table (beside ``kind``).
    force : bool
        Replace existing files even if they are not provably ours (each file we write carries
        our marker, see :mod:`rotoprint.io.ownership`).
    inputs : iterable of path
        Files the run read (the design, a device file): no output may be one.

    Returns
    -------
    dict
        The sidecar as written, with the SHA-256 of every swathe image.

    Raises
    ------
    InputFileError
        ``out_png`` does not end in ``.png``, its folder does not exist, an output file is an
        input, or one exists and is not provably ours (without ``force``).
    """
    out_png = Path(out_png)
    if out_png.suffix.lower() != ".png":
        raise InputFileError("output must be a .png file", path=out_png)
    blobs, side = print_files(pr, out_png.name, device_name=device_name, design=design)
    files = {out_png.parent / name: data for name, data in blobs.items()}
    _check_then_write(out_png, files, [*print_paths(out_png)[1:], *files], inputs=inputs, force=force)
    return side


def transform_passes(design, device, placement, out_png: str | Path, options, *, design_info: dict | None = None,
                     force: bool = False, inputs=()) -> dict:
    """Plan interlaced passes for ``design`` (:func:`rotoprint.rotary.interlace.pass_prints`)
    and write each pass as its own exact print, then the passes manifest.

    Parameters
    ----------
    design : (H, W) uint8
    device : InkjetDevice, InkjetHead or str
    placement : Placement
    out_png : str or Path
        ``PRINT.png``: pass ``q`` is written as ``PRINT-p{q+1}.png`` (swathes ``-p{q+1}-s1.png``,
        ...) with its own sidecar; ``PRINT-passes.json`` (format
        :data:`rotoprint.rotary.interlace.PASSES_FORMAT`) lists the plan and the files. Nothing
        is written before every pass is made.
    options : PassOptions
    design_info : dict, optional
        Recorded in the sidecars (path, digest, ...).
    force, inputs
        As for :func:`write_print`.

    Returns
    -------
    dict
        The passes manifest as written.
    """
    import json

    from ..rotary.interlace import pass_files, pass_prints

    device_name, prints, manifest = pass_prints(design, device, placement, options)
    files = pass_files(out_png, len(prints))
    mp = Path(out_png).with_name(Path(out_png).stem + "-passes.json")
    made = []  # every pass's files as bytes first: every path is checked before the first is written
    for pr, f in zip(prints, files, strict=True):
        blobs, _ = print_files(pr, f.name, device_name=device_name, design=design_info)
        made.append({f.parent / name: data for name, data in blobs.items()})
    also = [mp] + [q for f, m in zip(files, made) for q in (*print_paths(f), *m)]
    _check_then_write(files[0], {p: d for m in made for p, d in m.items()}, also, inputs=inputs, force=force)
    manifest = {**manifest, "files": [f.with_suffix(".json").name for f in files]}
    write_owned_file(mp, (json.dumps(manifest, indent=2) + "\n").encode("utf-8"), kind="passes", inputs=inputs, force=force)
    return manifest
