"""Direct rotary slicing in interlaced passes: one journalled rotary slice folder per pass
(the plan from :func:`rotoprint.rotary.interlace.plan_passes`) and the passes manifest."""

from __future__ import annotations

__all__ = ["slice_rotary_passes"]


def slice_rotary_passes(mesh, device, out_dir, *, passes: str | int = "auto", layer_height_mm: float, tilt_deg: float,
                        inner_radius_mm: float, angle_deg: float = 0.0, direction: int = 1, ref_radius_mm: float | None = None,
                        max_swathes: int | None = None, fill: str = "nonzero", gap_radius_mm: float | None = None,
                        reference_images: bool = False, options: dict | None = None, mesh_path=None,
                        equalise: bool = False, force: bool = False, inputs=()) -> dict:
    """Direct rotary slicing in interlaced passes: ``DIR-p1/``, ``DIR-p2/``, ... (each a complete
    rotary slice folder of :func:`~rotoprint.pipeline.write_rotary_slices`, its swathes'
    pivots moved by the pass's offset, at the plan's clock) and ``DIR-passes.json`` listing the
    plan and the folders. ``equalise`` thins each pass's tracks as the direct slicer does.

    Returns
    -------
    dict
        The passes manifest as written.
    """
    import json
    from pathlib import Path

    from ..io.atomic import write_owned_file
    from ..rotary.deposit import DepositOptions
    from ..constants import DEFAULT_GAP_RADIUS_MM
    from ..rotary.direct import PartPlacement, slice_rotary
    from ..rotary.interlace import PASSES_FORMAT, parse_passes, plan_passes
    from ..rotary.swathes import plan_swathes
    from .outputs import write_rotary_slices
    from .producer import RunOptions

    head = device.head
    n = parse_passes(passes)
    part = PartPlacement.for_mesh(mesh, inner_radius_mm=inner_radius_mm, angle_deg=angle_deg)
    design = part.design_placement(head.pitch_mm, 25.4 / head.dpi_y)
    r_in, r_out = design.radial_range_mm()
    sp = plan_swathes(head, tilt_deg=float(tilt_deg), inner_radius_mm=r_in, outer_radius_mm=r_out,
                      mount_angle_deg=0.0, direction=int(direction), max_swathes=max_swathes)
    pp = plan_passes(head, sp, footprint_um=DepositOptions().full_footprint_um(head), passes=n)
    out = Path(out_dir)
    folders = [out.with_name(f"{out.name}-p{q + 1}") for q in range(pp.passes)]
    gap = DEFAULT_GAP_RADIUS_MM if gap_radius_mm is None else gap_radius_mm
    for q, (off, folder) in enumerate(zip(pp.offsets_mm, folders)):
        job = slice_rotary(mesh, device, layer_height_mm=layer_height_mm, tilt_deg=tilt_deg, inner_radius_mm=inner_radius_mm,
                           angle_deg=angle_deg, dpi_y=pp.dpi_y, ref_radius_mm=ref_radius_mm, direction=direction,
                           max_swathes=max_swathes, equalise=equalise, fill=fill, gap_radius_mm=gap, pivot_offset_mm=off)
        opts = {"layer_height_mm": layer_height_mm, "tilt_deg": tilt_deg, "radius_mm": inner_radius_mm, "angle_deg": angle_deg,
                "direction": direction, "ref_radius_mm": ref_radius_mm, "max_swathes": max_swathes, "fill": fill,
                "gap_radius_mm": gap, "reference_images": reference_images, "pass": q, "passes": pp.passes,
                "pass_offset_mm": off, "dpi_y": pp.dpi_y, **(options or {})}
        mesh_info = {"path": str(mesh_path or ""), "triangles": int(mesh.faces.shape[0])}
        write_rotary_slices(job, folder, device_name=device.name, options=opts, mesh_info=mesh_info,
                            reference_images=reference_images, run=RunOptions(force=force, inputs=tuple(inputs)))
    manifest = {"format": PASSES_FORMAT, "version": 1, "device": device.name, "tilt_deg": float(tilt_deg), "dpi_y": pp.dpi_y,
                "pass_plan": pp.to_json(), "folders": [f.name for f in folders],
                "files": [], "layer_sidecars": "FOLDER/layer_NNNNN.json in each folder: the passes of layer NNNNN"}
    mp = out.with_name(out.name + "-passes.json")
    write_owned_file(mp, (json.dumps(manifest, indent=2) + "\n").encode("utf-8"), kind="passes", inputs=inputs, force=force)
    return manifest
