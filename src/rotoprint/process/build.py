"""The whole pipeline behind ``rotoprint build``: job -> plan -> print-ready images,
printability, estimates, simulator overlays, ``plan.json`` and ``report.html``.

Output folder (written under a temporary name and renamed when complete; nothing partial is
left on error; an existing folder is replaced only when it is provably an earlier rotoprint
output, see :mod:`rotoprint.io.ownership`, or with ``force``)::

    rotoprint-output.json          the ownership marker: every file written, with its SHA-256

    plan.json                      format "rotoprint-build-plan": heads, materials, estimates,
                                   warnings, printability, resistance, and per layer the
                                   ordered passes with their image files and SHA-256
    report.html                    self-contained report (no network)
    layers/layer_00000/MATERIAL-INK.png (+ .json sidecar; -s1, -s2 for several swathes)
    machine/                       packed firing data, TIFF planes, program.json/.txt (docs/machine.md)
    overlays/layer_00000-MATERIAL.png   simulator overlays of a few layers
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import __version__
from ..errors import RotoprintError
from .conductance import coil_hand_check, resistance_from_masks
from .job import ResolvedJob
from .plan import BuildPlan, plan_job

__all__ = ["BuildResult", "run_build", "PLAN_FORMAT", "MATERIAL_COLOURS", "composite_image"]

log = logging.getLogger(__name__)

PLAN_FORMAT = "rotoprint-build-plan"
#: Oversampling of the design grid for the "design" resistance estimate.
RESISTANCE_OVERSAMPLE = 2
#: RGB per material in composites (others get a colour from a fixed cycle).
MATERIAL_COLOURS = {"plaster": (214, 200, 170), "silver": (90, 96, 110), "epoxy": (230, 160, 40), "polyamide": (60, 160, 90)}
_CYCLE = [(200, 80, 80), (80, 120, 200), (150, 90, 180), (40, 170, 170)]


def material_colour(name: str, order: list[str]) -> tuple[int, int, int]:
    return MATERIAL_COLOURS.get(name, _CYCLE[order.index(name) % len(_CYCLE)] if name in order else (128, 128, 128))


def composite_image(masks: dict[str, np.ndarray], order: list[str]) -> np.ndarray:
    """``(H, W, 3) uint8``: each material's pixels in its colour on white (later on top).

    Parameters
    ----------
    masks : dict of str to (H, W) bool
        Each material's pixels; all of the same shape. Must not be empty.
    order : list of str
        Drawing order; materials not in it are not drawn.

    Returns
    -------
    (H, W, 3) uint8 ndarray
        RGB; colours from ``MATERIAL_COLOURS``, else from a fixed cycle by position in
        ``order``.
    """
    shape = next(iter(masks.values())).shape
    img = np.full(shape + (3,), 255, np.uint8)
    for m in order:
        if m in masks:
            img[masks[m]] = material_colour(m, order)
    return img


@dataclass(frozen=True)
class BuildResult:
    out_dir: Path
    report_path: Path
    plan_path: Path
    summary: dict


def _png_rgb(img: np.ndarray) -> bytes:
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG", compress_level=6)
    return buf.getvalue()


def _simulate_layers(n_layers: int, present: dict[str, list[int]], k: int) -> dict[str, list[int]]:
    """Up to ``k`` layers per material to simulate: first, last and evenly between."""
    out = {}
    for m, idx in present.items():
        if not idx or k <= 0:
            out[m] = []
            continue
        sel = np.unique(np.round(np.linspace(0, len(idx) - 1, min(k, len(idx)))).astype(int))
        out[m] = [idx[i] for i in sel]
    return out


def job_inputs(job: ResolvedJob) -> list[Path]:
    """The files a job reads (mesh files, its materials file, a device file), absolute.

    Parameters
    ----------
    job : ResolvedJob

    Returns
    -------
    list of Path
    """
    base = job.base_dir
    names = [p.mesh for p in job.spec.parts if p.mesh is not None]
    names += [n for n in (job.spec.job.materials_file, getattr(getattr(job.spec, "printer", None), "device", None)) if n]
    return [Path(n) if Path(n).is_absolute() else base / n for n in names]


def run_build(job: ResolvedJob, out_dir: str | Path, *, on_step: Callable[[str, int, int], None] | None = None,
              check: bool | None = None, report: bool = True, force: bool = False,
              inputs: Iterable[str | Path] = (), machine=None) -> BuildResult:
    """Run the whole pipeline for ``job`` and write ``out_dir``.

    Parameters
    ----------
    job : ResolvedJob
    out_dir : str or Path
    on_step : callable, optional
        ``on_step(stage, done, total)`` for progress display.
    check : bool, optional
        Run the printability check on every part (default: the job's ``process.check``).
    report : bool
        Write ``report.html``.
    force : bool
        Replace an existing ``out_dir`` even if it is not provably ours.
    inputs : iterable of path
        Files the run read besides the job's own (:func:`job_inputs`): ``out_dir`` must not be
        or hold one.
    machine : MachineOptions or False, optional
        How ``machine/`` is written (:class:`rotoprint.machine.program.MachineOptions`; default
        options when None); ``False``: no machine folder.

    Returns
    -------
    BuildResult
    """
    from ..check import CheckOptions, check_printability
    from ..check.overlay import overlay_image
    from ..io.atomic import atomic_dir
    from ..rotary.files import write_print
    from ..rotary.simulate import render_overlay, simulate

    t0 = time.perf_counter()
    step = on_step or (lambda *a: None)
    plan: BuildPlan = plan_job(job)
    sp = job.spec
    do_check = sp.process.check if check is None else bool(check)
    n = len(plan)
    order = plan.material_order
    grid1 = plan.design_grid()
    gridr = plan.design_grid(oversample=RESISTANCE_OVERSAMPLE)
    res_materials = {job.part(r.part).material for r in sp.resistance}
    design_masks: dict[str, list[np.ndarray]] = {m: [] for m in res_materials}
    printed_masks: dict[str, list[np.ndarray]] = {m: [] for m in res_materials}
    present: dict[str, list[int]] = {m: [] for m in order}
    composites: list[bytes] = []
    layers_json = []
    timings = {}
    out = Path(out_dir)
    final = out.resolve()
    with atomic_dir(out, kind="build", inputs=[*inputs, *job_inputs(job)], force=force) as tmp:
        (tmp / "layers").mkdir()
        (tmp / "overlays").mkdir()
        from ..machine.program import machine_stage

        mw = machine_stage(plan, tmp / "machine", machine)  # the machine folder, streamed layer by layer
        # printability of every part (exact cross-sections, Cartesian grid at the head's pitch)
        checks = []
        tc = time.perf_counter()
        if do_check:
            for j, part in enumerate(sp.parts):
                step("check", j, len(sp.parts))
                opts = CheckOptions(tilt_deg=plan.heads[0].tilt_deg, radius_mm=sp.placement.inner_radius_mm)
                rep = check_printability(plan.meshes[part.name], plan.device, opts, layer_height_mm=sp.job.layer_height_mm)
                worst_layer = None
                if rep.findings:
                    worst_layer = rep.findings[0].layer
                entry = {"part": part.name, "material": part.material, "ok": rep.ok, "counts": rep.counts(),
                         "lengths_mm": rep.lengths_mm(), "thinnest_wall": rep.thinnest_wall,
                         "narrowest_gap": rep.narrowest_gap, "limits": rep.limits,
                         "findings": [f.to_json() for f in rep.findings[:50]], "findings_total": len(rep.findings),
                         "overlay": None}
                if part.name in plan.planar:  # a CAD layer: its exact narrowest track and gap against the head
                    entry["layer_exact"] = _layer_printability(plan.planar[part.name], rep.limits)
                    entry["ok"] = entry["ok"] and entry["layer_exact"]["ok"]
                if worst_layer is not None:
                    from ..check import check_layers

                    for lc in check_layers(plan.meshes[part.name], plan.device, layer_height_mm=sp.job.layer_height_mm):
                        if lc.index == worst_layer:
                            name = f"overlays/check-{part.name}-layer_{worst_layer:05d}.png"
                            (tmp / name).write_bytes(_png_rgb(overlay_image(lc)))
                            entry["overlay"] = name
                            break
                checks.append(entry)
        timings["check_s"] = time.perf_counter() - tc
        # layers: print-ready images, composites, resistance masks
        tl = time.perf_counter()
        total_time_s = 0.0
        for i in range(n):
            step("layers", i, n)
            sched = plan.layer(i)
            total_time_s += sched.time_s
            ldir = tmp / "layers" / f"layer_{i:05d}"
            ldir.mkdir()
            images = []
            for (mname, ink), pr in sched.images.items():
                h = plan.head(ink)
                side = write_print(pr, ldir / f"{mname}-{ink}.png", device_name=plan.device.name,
                                   design={"source": f"{mname} in layer {i} (overlaps resolved by priority)", "layer": i})
                images.append({"material": mname, "ink": ink, "head": h.name, "head_index": h.index,
                               "mount_angle_deg": h.mount_angle_deg,
                               "sidecar": f"layers/layer_{i:05d}/{mname}-{ink}.json",
                               "swathes": [{"file": f"layers/layer_{i:05d}/{s['file']}", "sha256": s["sha256"],
                                            "drops": s["drops"], "firings": s["firings"]} for s in side["swathes"]]})
            sections = plan.sections(i)
            masks = {}
            for b in sched.blocks:
                present[b.material].append(i)
                masks[b.material] = plan.reference_image(b.material, sections)
            if masks:
                composites.append(_png_rgb(composite_image(masks, order)))
            else:
                composites.append(_png_rgb(np.full((grid1.height_px, grid1.width_px, 3), 255, np.uint8)))
            for m in res_materials:
                if m in masks:
                    design_masks[m].append(plan.reference_image(m, sections, oversample=RESISTANCE_OVERSAMPLE))
                    cov = None
                    for ink in job.materials[m].inks:
                        pr = plan.material_print(m, plan.head(ink.name), sections, i, thinned=False)
                        ref = masks[m].astype(np.uint8) * 255
                        p = simulate(pr, ref).printed
                        cov = p if cov is None else (cov & p)
                    printed_masks[m].append(cov)
            if mw is not None:
                step("machine", i, n)
                mw.add_layer(sched, masks)
            layers_json.append({
                "index": i, "z_bottom_mm": sched.z_bottom_mm, "z_top_mm": sched.z_top_mm, "time_s": sched.time_s,
                "blocks": [b.to_json() for b in sched.blocks], "images": images,
            })
        machine_totals = mw.close() if mw is not None else None
        timings["layers_s"] = time.perf_counter() - tl
        # simulator overlays of a few layers per material (coverage before density thinning)
        ts = time.perf_counter()
        overlays = []
        pick = _simulate_layers(n, present, sp.process.simulate_layers)
        for mname, idx in pick.items():
            ink0 = job.materials[mname].inks[0].name
            for i in idx:
                sections = plan.sections(i)
                pr = plan.material_print(mname, plan.head(ink0), sections, i, thinned=False)
                ref = plan.reference_image(mname, sections).astype(np.uint8) * 255
                sim = simulate(pr, ref)
                from ..rotary.deposit import deposit_film, ink_drops

                film = deposit_film(sim.inked, pr.placement, pr.head, [ink_drops(sim.drops, pr.head)]).films[0].to_json()
                name = f"overlays/layer_{i:05d}-{mname}.png"
                (tmp / name).write_bytes(_png_rgb(render_overlay(sim, scale=2)))
                overlays.append({"layer": i, "material": mname, "ink": ink0, "head": plan.head(ink0).name, "file": name,
                                 "deposit": {k: v for k, v in film.items() if k != "radial_bins"},
                                 "iou": sim.report.iou, "uncovered_fraction": sim.report.uncovered_fraction,
                                 "drops_outside": sim.report.drops_outside, "mean_error_um": sim.report.mean_error_um})
        timings["simulate_s"] = time.perf_counter() - ts
        # resistance estimates
        tr = time.perf_counter()
        resistance = []
        for r in sp.resistance:
            m = job.part(r.part).material
            try:
                d, _ = resistance_from_masks(plan, r, design_masks[m], gridr)
                p, _ = resistance_from_masks(plan, r, printed_masks[m], grid1)
            except RotoprintError as exc:
                resistance.append({"part": r.part, "between": list(r.between), "error": exc.problem})
                continue
            track_layers = len([mm for mm in design_masks[m] if mm.any()])
            sh = job.part(r.part).shape
            if sh is not None and sh.kind == "square_coil":
                lh = sp.job.layer_height_mm
                track_layers = max(1, round(sh.height_mm / lh))
            hand = coil_hand_check(plan, r, track_layers=track_layers)
            resistance.append({"part": r.part, "material": m, "between": list(r.between),
                               "design": {**d, "oversample": RESISTANCE_OVERSAMPLE}, "printed": p, "hand_check": hand})
        timings["resistance_s"] = time.perf_counter() - tr
        ide = {}
        for part in sp.parts:
            if part.shape is not None and part.shape.kind == "interdigitated":
                ide[part.name] = {"cell_constant_per_mm": part.shape.cell_constant_per_mm(),
                                  "note": "film resistance between the combs = film sheet resistance x gap / (overlap x gaps)"}
        plan_json = {
            "format": PLAN_FORMAT, "version": 1, "rotoprint": __version__,
            "source": job.source, **plan.to_json(),
            "grid": grid1.to_json(),
            "estimated_print_time_s": total_time_s,
            "printability": checks,
            "resistance": resistance,
            "interdigitated": ide,
            "overlays": overlays,
            "timings_s": timings,
            "layers_detail": layers_json,
        }
        text = json.dumps(plan_json, indent=1, default=_json_default)
        (tmp / "plan.json").write_text(text, encoding="utf-8")
        if report:
            from ..report import render_report

            step("report", 0, 1)
            html = render_report(plan, plan_json, composites=composites, overlays_dir=tmp)
            (tmp / "report.html").write_text(html, encoding="utf-8")
    timings["total_s"] = time.perf_counter() - t0
    summary = {
        "layers": n, "heads": len(plan.heads), "warnings": plan.warnings, "resistance": resistance,
        "printability_ok": all(c["ok"] for c in checks) if checks else None, "estimated_print_time_s": total_time_s,
        "timings_s": timings, "plan_sha256": hashlib.sha256(text.encode()).hexdigest(),
        "machine": machine_totals,
    }
    return BuildResult(out_dir=final, report_path=final / "report.html", plan_path=final / "plan.json", summary=summary)


def _layer_printability(placed, limits: dict) -> dict:
    """A layer part's narrowest track and gap (exact polygon, edge-normal rays) against the
    head's smallest wall and gap."""
    info = placed.layer.info()
    track, gap = info["narrowest_track_mm"], info["narrowest_gap_mm"]
    wall_min, gap_min = limits.get("min_wall_mm"), limits.get("min_gap_mm")
    track_ok = track is None or wall_min is None or track >= wall_min
    gap_ok = gap is None or gap_min is None or gap >= gap_min
    return {"narrowest_track_mm": track, "narrowest_track_at_mm": info["narrowest_track_at_mm"],
            "narrowest_gap_mm": gap, "narrowest_gap_at_mm": info["narrowest_gap_at_mm"],
            "min_wall_mm": wall_min, "min_gap_mm": gap_min, "track_ok": track_ok, "gap_ok": gap_ok,
            "ok": bool(track_ok and gap_ok)}


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.integer | np.floating):
        v = o.item()
        return v if not (isinstance(v, float) and not math.isfinite(v)) else None
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
