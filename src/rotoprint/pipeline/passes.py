"""Direct rotary slicing in interlaced passes: one journalled rotary slice folder per pass
(the plan from :func:`rotoprint.rotary.interlace.plan_passes`) and the passes manifest."""

from __future__ import annotations

__all__ = ["slice_rotary_passes"]


def slice_rotary_passes(mesh, device, out_dir, options, *, passes: str | int = "auto", reference_images: bool = False,
                        record: dict | None = None, run=None) -> dict:
    """Direct rotary slicing in interlaced passes: ``DIR-p1/``, ``DIR-p2/``, ... (each a complete
    rotary slice folder of :func:`~rotoprint.pipeline.write_rotary_slices`, its swathes'
    pivots moved by the pass's offset, at the plan's clock) and ``DIR-passes.json`` listing the
    plan and the folders.

    Parameters
    ----------
    mesh : Mesh
        Its ``source`` is recorded as the mesh's path.
    device : InkjetDevice
    out_dir : str or Path
        ``DIR``: the folders are made beside it.
    options : RotarySliceOptions
        Layer height, tilt, placement, clock, direction, swathe limit, fill, gap radius; its
        ``pivot_offset_mm`` is replaced by each pass's offset and its ``dpi_y``, when None, by
        the plan's clock. ``equalise``: the shares of the **union** of the passes
        (:func:`~rotoprint.rotary.direct.union_pass_shares`: the transform path's
        ``track_fractions``, with the dead-track cover where the head has dead nozzles),
        computed once and printed by each pass at the clock made ``EQUALISE_CLOCK_FACTOR``
        times finer (without the edge restore of :class:`~rotoprint.rotary.edgecomp.EdgeRestore`,
        which ``transform --passes`` applies by default: on the direct route it is opt-in,
        :meth:`~rotoprint.rotary.direct.DirectSliceJob.with_shares` and the build's
        ``printer.edge_restore``); False: every track keeps every drop (plain passes).
    passes : int or 'auto'
    reference_images : bool
        Also write each layer's Cartesian design image.
    record : dict, optional
        More options to record in every folder's manifest (JSON values).
    run : RunOptions, optional
        ``force`` and ``inputs`` (and the workers) of the writes.

    Returns
    -------
    dict
        The passes manifest as written.
    """
    import dataclasses
    import json
    from pathlib import Path

    from ..errors import GeometryError
    from ..io.atomic import write_owned_file
    from ..rotary.deposit import DepositOptions
    from ..rotary.direct import PartPlacement, slice_rotary, union_pass_shares
    from ..rotary.interlace import PASSES_FORMAT, parse_passes, plan_passes
    from ..rotary.options import RotarySliceOptions, options_from
    from ..rotary.swathes import plan_swathes
    from .outputs import write_rotary_slices
    from .producer import RunOptions

    opts = options_from(RotarySliceOptions, options, {}, what="slice_rotary_passes")
    run = run or RunOptions()
    head = device.head
    n = parse_passes(passes)
    part = PartPlacement.for_mesh(mesh, inner_radius_mm=opts.inner_radius_mm, angle_deg=opts.angle_deg)
    design = part.design_placement(head.pitch_mm, 25.4 / head.dpi_y)
    r_in, r_out = design.radial_range_mm()
    sp = plan_swathes(head, tilt_deg=float(opts.tilt_deg), inner_radius_mm=r_in, outer_radius_mm=r_out,
                      mount_angle_deg=0.0, direction=int(opts.direction), max_swathes=opts.max_swathes)
    pp = plan_passes(head, sp, footprint_um=DepositOptions().full_footprint_um(head), passes=n)
    clock = pp.dpi_y if opts.dpi_y is None else float(opts.dpi_y)
    shares, eq, edge = None, None, None
    if opts.equalise:  # the union's shares, once for the plan (on the slicer's own swathes)
        job0 = slice_rotary(mesh, device, dataclasses.replace(opts, dpi_y=clock, equalise=False))
        shares, clock, eq = union_pass_shares(head, job0.plan, pp.offsets_mm, dpi_y=clock, ref_radius_mm=opts.ref_radius_mm)
        # the edge restore is not the default here: on the coil demo's build it did not even the levelled
        # bins (docs/benchmarks.md, branch edged13); slice_rotary / with_shares and printer.edge_restore give it
        edge = None
    out = Path(out_dir)
    folders = [out.with_name(f"{out.name}-p{q + 1}") for q in range(pp.passes)]
    for q, (off, folder) in enumerate(zip(pp.offsets_mm, folders)):
        job = slice_rotary(mesh, device, dataclasses.replace(opts, dpi_y=clock, pivot_offset_mm=off, equalise=False))
        if shares is not None:
            if len(job.plan.swathes) != len(shares[q]):
                raise GeometryError(f"pass {q + 1} plans {len(job.plan.swathes)} swathes, its shares {len(shares[q])}")
            job = job.with_shares(shares[q], pass_index=q, edge_restore=edge)
        rec = {"layer_height_mm": opts.layer_height_mm, "tilt_deg": opts.tilt_deg, "radius_mm": opts.inner_radius_mm,
               "angle_deg": opts.angle_deg, "direction": opts.direction, "ref_radius_mm": opts.ref_radius_mm,
               "max_swathes": opts.max_swathes, "fill": opts.fill, "gap_radius_mm": opts.gap_radius_mm,
               "reference_images": reference_images, "pass": q, "passes": pp.passes, "pass_offset_mm": off, "dpi_y": clock,
               **(record or {}), "equalise": "union shares" if shares is not None else False,
               "edge_restore": job.edge_restore_record()}
        mesh_info = {"path": str(getattr(mesh, "source", None) or ""), "triangles": int(mesh.faces.shape[0])}
        write_rotary_slices(job, folder, device_name=device.name, options=rec, mesh_info=mesh_info,
                            reference_images=reference_images, run=run)
    manifest = {"format": PASSES_FORMAT, "version": 1, "device": device.name, "tilt_deg": float(opts.tilt_deg), "dpi_y": clock,
                "equalise": "thinning" if shares is not None else None,
                "union_shares": {k: v for k, v in eq.items() if k != "dead_cover"} if eq is not None else None,
                "edge_restore": job.edge_restore_record(),
                "pass_plan": pp.to_json(), "folders": [f.name for f in folders],
                "files": [], "layer_sidecars": "FOLDER/layer_NNNNN.json in each folder: the passes of layer NNNNN"}
    if eq is not None and eq["dead_cover"] is not None:
        manifest["dead_cover"] = eq["dead_cover"]
    mp = out.with_name(out.name + "-passes.json")
    write_owned_file(mp, (json.dumps(manifest, indent=2) + "\n").encode("utf-8"), kind="passes", inputs=run.inputs,
                     force=run.force)
    return manifest
