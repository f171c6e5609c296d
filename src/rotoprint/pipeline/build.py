"""``rotoprint build`` as named stages, run one by one: plan -> check -> layers -> simulate ->
resistance -> report. Each stage reports its progress (``on_step(stage, done, total)``) and
its time (``timings_s``).

Output folder (written under a temporary name and renamed when complete; nothing partial is
left on error; an existing folder is replaced only when it is provably an earlier rotoprint
output, see :mod:`rotoprint.io.ownership`, or with ``force``)::

    rotoprint-output.json          the ownership marker: every file written, with its SHA-256

    plan.json                      format "rotoprint-build-plan": heads, materials, estimates,
                                   warnings, printability, resistance, and per layer the
                                   ordered passes with their image files and SHA-256
    report.html                    self-contained report (no network)
    layers/layer_00000/MATERIAL-INK.png (+ .json sidecar; -s1, -s2 for several swathes;
                                   MATERIAL-INK-p1.png, -p2, ... per interlaced pass)
    machine/                       packed firing data, TIFF planes, program.json/.txt (docs/machine.md)
    overlays/layer_00000-MATERIAL.png   simulator overlays of a few layers
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from .._version import __version__
from ..errors import RotoprintError

__all__ = ["BuildResult", "run_build", "job_inputs", "STAGES", "PLAN_FORMAT", "stage_plan", "stage_check", "stage_layers",
           "stage_simulate", "stage_resistance", "stage_report"]

PLAN_FORMAT = "rotoprint-build-plan"
#: Oversampling of the design grid for the "design" resistance estimate.
RESISTANCE_OVERSAMPLE = 2
#: The stages, in the order they run.
STAGES = ("plan", "check", "layers", "simulate", "resistance", "report")

Step = Callable[[str, int, int], None]


@dataclass(frozen=True)
class BuildResult:
    out_dir: Path
    report_path: Path | None  # None: no report written (report=False)
    plan_path: Path
    summary: dict


@dataclass
class LayerOutputs:
    """What the layers stage hands on: per layer its JSON entry and composite PNG, the layers
    each material is present in, the masks of the resistance estimates, the print time."""

    layers_json: list[dict] = field(default_factory=list)
    composites: list[bytes] = field(default_factory=list)
    present: dict[str, list[int]] = field(default_factory=dict)
    design_masks: dict[str, list[np.ndarray]] = field(default_factory=dict)
    printed_thickness: dict[str, list[np.ndarray]] = field(default_factory=dict)
    total_time_s: float = 0.0


def _png_rgb(img: np.ndarray) -> bytes:
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(img).save(buf, format="PNG", compress_level=6)
    return buf.getvalue()


@contextlib.contextmanager
def _timed(timings: dict, key: str):
    t = time.perf_counter()
    try:
        yield
    finally:
        timings[key] = time.perf_counter() - t


# ---------------------------------------------------------------------- stages
def stage_plan(job, step: Step):
    """Plan the job: heads, passes, schedules (:func:`rotoprint.process.plan_job`)."""
    from ..process.plan import plan_job

    step("plan", 0, 1)
    plan = plan_job(job)
    step("plan", 1, 1)
    return plan


def stage_check(job, plan, tmp: Path, step: Step) -> list[dict]:
    """Printability of every part (exact cross-sections, Cartesian grid at the head's pitch);
    an overlay of each part's worst layer into ``tmp/overlays``. Returns the ``printability``
    entries of ``plan.json``."""
    from ..check import CheckOptions, check_layers, check_printability
    from ..check.overlay import overlay_image

    sp = job.spec
    checks = []
    for j, part in enumerate(sp.parts):
        step("check", j, len(sp.parts))
        opts = CheckOptions(tilt_deg=plan.heads[0].tilt_deg, radius_mm=sp.placement.inner_radius_mm)
        rep = check_printability(plan.meshes[part.name], plan.device, opts, layer_height_mm=sp.job.layer_height_mm)
        worst_layer = rep.findings[0].layer if rep.findings else None
        entry = {"part": part.name, "material": part.material, "ok": rep.ok, "counts": rep.counts(),
                 "lengths_mm": rep.lengths_mm(), "thinnest_wall": rep.thinnest_wall,
                 "narrowest_gap": rep.narrowest_gap, "limits": rep.limits,
                 "findings": [f.to_json() for f in rep.findings[:50]], "findings_total": len(rep.findings),
                 "overlay": None}
        if part.name in plan.planar:  # a CAD layer: its exact narrowest track and gap against the head
            entry["layer_exact"] = _layer_printability(plan.planar[part.name], rep.limits)
            entry["ok"] = entry["ok"] and entry["layer_exact"]["ok"]
        if worst_layer is not None:
            for lc in check_layers(plan.meshes[part.name], plan.device, layer_height_mm=sp.job.layer_height_mm):
                if lc.index == worst_layer:
                    name = f"overlays/check-{part.name}-layer_{worst_layer:05d}.png"
                    (tmp / name).write_bytes(_png_rgb(overlay_image(lc)))
                    entry["overlay"] = name
                    break
        checks.append(entry)
    step("check", len(sp.parts), len(sp.parts))
    return checks


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


def stage_layers(job, plan, tmp: Path, step: Step, mw=None) -> LayerOutputs:
    """Print-ready images of every layer into ``tmp/layers``, each layer's composite, and the
    design and printed masks of the materials with a resistance estimate; with ``mw`` (the
    machine writer of :func:`rotoprint.machine.program.machine_stage`) every layer is also
    streamed into ``machine/`` (progress as the ``machine`` step)."""
    from ..process.conductance import deposited_thickness_um
    from ..report.colours import composite_image
    from ..rotary.files import print_files

    sp = job.spec
    n = len(plan)
    order = plan.material_order
    grid1 = plan.design_grid()
    res_materials = {job.part(r.part).material for r in sp.resistance}
    out = LayerOutputs(present={m: [] for m in order}, design_masks={m: [] for m in res_materials},
                       printed_thickness={m: [] for m in res_materials})
    for i in range(n):
        step("layers", i, n)
        sched = plan.layer(i)
        out.total_time_s += sched.time_s
        ldir = tmp / "layers" / f"layer_{i:05d}"
        ldir.mkdir()
        images = []
        for (mname, ink), prs in sched.pass_images.items():
            h = plan.head(ink)
            passes = []
            for q, pr in enumerate(prs):
                stem = f"{mname}-{ink}" if len(prs) == 1 else f"{mname}-{ink}-p{q + 1}"
                blobs, side = print_files(pr, f"{stem}.png", device_name=plan.device.name,
                                          design={"source": f"{mname} in layer {i} (overlaps resolved by priority)", "layer": i})
                for name, data in blobs.items():
                    (ldir / name).write_bytes(data)
                passes.append({"pass": q, "pass_offset_mm": h.pass_offsets_mm[q], "sidecar": f"layers/layer_{i:05d}/{stem}.json",
                               "swathes": [{"file": f"layers/layer_{i:05d}/{s['file']}", "sha256": s["sha256"],
                                            "drops": s["drops"], "firings": s["firings"],
                                            "pivot_radius_mm": s["pivot_radius_mm"]} for s in side["swathes"]]})
            entry = {"material": mname, "ink": ink, "head": h.name, "head_index": h.index,
                     "mount_angle_deg": h.mount_angle_deg, "sidecar": passes[0]["sidecar"], "swathes": passes[0]["swathes"]}
            if len(prs) > 1:
                entry["passes"] = passes
            images.append(entry)
        sections = plan.sections(i)
        masks = {}
        for b in sched.blocks:
            out.present[b.material].append(i)
            masks[b.material] = plan.reference_image(b.material, sections)
        if masks:
            out.composites.append(_png_rgb(composite_image(masks, order)))
        else:
            out.composites.append(_png_rgb(np.full((grid1.height_px, grid1.width_px, 3), 255, np.uint8)))
        for m in res_materials:
            if m in masks:
                out.design_masks[m].append(plan.reference_image(m, sections, oversample=RESISTANCE_OVERSAMPLE))
                blk = next(b for b in sched.blocks if b.material == m)
                out.printed_thickness[m].append(
                    deposited_thickness_um(plan, m, _weighted_passes(job, m, sched.pass_images, blk.cycles), grid1))
        if mw is not None:
            step("machine", i, n)
            mw.add_layer(sched, masks)
        out.layers_json.append({
            "index": i, "z_bottom_mm": sched.z_bottom_mm, "z_top_mm": sched.z_top_mm, "time_s": sched.time_s,
            "blocks": [b.to_json() for b in sched.blocks], "images": images,
        })
    step("layers", n, n)
    return out


def _weighted_passes(job, material: str, prints: dict, cycles: int) -> dict[str, list[tuple[object, float]]]:
    """Per ink of ``material``: each interlaced pass's print (``prints[(material, ink)]``) and
    how often it prints in the layer (the cycles at that pass x the ink's repeats)."""
    out = {}
    for ink in job.materials[material].inks:
        prs = prints[(material, ink.name)]
        n = len(prs)
        out[ink.name] = [(pr, (cycles // n + (q < cycles % n)) * ink.repeats) for q, pr in enumerate(prs)]
    return out


def _simulate_layers(present: dict[str, list[int]], k: int) -> dict[str, list[int]]:
    """Up to ``k`` layers per material to simulate: first, last and evenly between."""
    out = {}
    for m, idx in present.items():
        if not idx or k <= 0:
            out[m] = []
            continue
        sel = np.unique(np.round(np.linspace(0, len(idx) - 1, min(k, len(idx)))).astype(int))
        out[m] = [idx[i] for i in sel]
    return out


def stage_simulate(job, plan, present: dict[str, list[int]], tmp: Path, step: Step) -> list[dict]:
    """The film of a few layers per material into ``tmp/overlays`` and their ``overlays``
    entries: the headline is the deposit model (:func:`rotoprint.rotary.deposit.deposit_film`)
    of the layer's planned drops, every interlaced pass of every ink weighted by how often it
    prints, measured on the film grid (the design grid divided into deposit cells) against the
    design rasterised at the cells' centres (``deposit``: the first ink's film, ``inks``: each
    ink's, ``reagent_pairs``), the
    secondary the simulator's cell model of the first ink's pass 0 (``iou``,
    ``uncovered_fraction``: pixels of the design whose nearest site of that pass's lattice
    fired; each pass's lattice tiles the design by itself)."""
    from ..rotary.deposit import DepositOptions, InkDrops, LevelOptions, deposit_film, film_grid, ink_drops
    from ..rotary.simulate import place_drops, render_overlay, simulate

    pick = _simulate_layers(present, job.spec.process.simulate_layers)
    total = sum(len(v) for v in pick.values())
    overlays = []
    head = plan.device.head
    for mname, idx in pick.items():
        inks = [ink.name for ink in job.materials[mname].inks]
        # each ink's film levels with its own figures where it gives them, else the head's
        levels = [LevelOptions.from_head(head, set_time_s=ink.set_time_s, viscosity_mpa_s=ink.viscosity_mpa_s,
                                         surface_tension_mn_m=ink.surface_tension_mn_m) for ink in job.materials[mname].inks]
        for i in idx:
            step("simulate", len(overlays), total)
            sections = plan.sections(i)
            ref = plan.reference_image(mname, sections)
            ref8 = ref.astype(np.uint8) * 255
            prints = {}
            for ink in inks:
                h = plan.head(ink)
                prints[(mname, ink)] = [plan.material_print(mname, h, sections, i, pass_index=q) for q in range(h.passes)]
            cycles = plan.estimates[mname].cycles
            weighted = _weighted_passes(job, mname, prints, cycles)
            sim = simulate(weighted[inks[0]][0][0], ref8)  # the cell model of pass 0 (each pass's lattice tiles the design)
            sets = []
            for ink in inks:
                parts = []
                for pr, w in weighted[ink]:
                    d = ink_drops(place_drops(pr), head)
                    parts.append(InkDrops(d.col, d.row, d.volume_pl * float(w)))
                sets.append(InkDrops.concat(parts))
            # each cycle's coat (one pass, repeats) sets before the next lands: h0 is one coat's
            coats = [max(1.0, float(sum(w for _, w in weighted[ink]))) for ink in inks]
            lv = tuple(replace(lev, coats=c) for lev, c in zip(levels, coats))
            opts = DepositOptions(level=lv)
            pl = weighted[inks[0]][0][0].placement
            # the design exact to a deposit cell: rasterised at the film grid's cell centres
            ref_cells = plan.reference_image(mname, sections, grid=film_grid(pl, head, opts))
            dep = deposit_film(ref_cells, pl, head, sets, pairs=[(0, 1)] if len(sets) == 2 else [], options=opts)
            films = {ink: {k: v for k, v in f.to_json().items() if k != "radial_bins"} for ink, f in zip(inks, dep.films)}
            name = f"overlays/layer_{i:05d}-{mname}.png"
            (tmp / name).write_bytes(_png_rgb(render_overlay(sim, scale=2)))
            overlays.append({"layer": i, "material": mname, "ink": inks[0], "head": plan.head(inks[0]).name, "file": name,
                             "interlace_passes": len(weighted[inks[0]]), "cycles": cycles,
                             "deposit": films[inks[0]], "inks": films, "reagent_pairs": list(dep.pairs),
                             "uncovered_fraction_worst_ink": max(f["uncovered_fraction"] for f in films.values()),
                             "cell_model": "pass 0", "iou": sim.report.iou, "uncovered_fraction": sim.report.uncovered_fraction,
                             "drops_outside": sim.report.drops_outside, "mean_error_um": sim.report.mean_error_um})
    step("simulate", total, total)
    return overlays


def coverage_summary(overlays: list[dict]) -> dict:
    """Per material, the headline coverage of ``plan.json`` and the report: the deposit
    model's worst uncovered fraction of the interior over the simulated layers and inks (as
    landed: levelling does not fill a dry cell), the thinnest-to-mean ratio (of the levelled
    film where every ink levels, ``set_time_s > 0``, else as landed; both are given, and
    ``thinnest_to_mean_basis`` says which is the headline), and the cell model's lowest IoU
    (secondary)."""
    out: dict[str, dict] = {}
    for o in overlays:
        m = out.setdefault(o["material"], {"model": "deposit", "layers": [], "uncovered_fraction": 0.0, "thinnest_to_mean": None,
                                            "band_uncovered_fraction": 0.0, "mean_um": [], "cell_model_iou": None,
                                            "thinnest_to_mean_as_landed": None, "thinnest_to_mean_levelled": None,
                                            "thinnest_to_mean_basis": "as landed", "levelling": []})
        m["layers"].append(o["layer"])
        m["uncovered_fraction"] = max(m["uncovered_fraction"], o["uncovered_fraction_worst_ink"])
        m["band_uncovered_fraction"] = max(m["band_uncovered_fraction"], max(f["band_uncovered_fraction"] for f in o["inks"].values()))
        ttm = min(f["thinnest_to_mean"] for f in o["inks"].values())
        m["thinnest_to_mean_as_landed"] = ttm if m["thinnest_to_mean_as_landed"] is None else min(m["thinnest_to_mean_as_landed"], ttm)
        levs = [f.get("levelled") for f in o["inks"].values()]
        if all(lv is not None for lv in levs):
            lt = min(lv["thinnest_to_mean"] for lv in levs)
            m["thinnest_to_mean_levelled"] = lt if m["thinnest_to_mean_levelled"] is None else min(m["thinnest_to_mean_levelled"], lt)
            for ink, lv in zip(o["inks"], levs):
                par = {"ink": ink, "set_time_s": lv["set_time_s"], "viscosity_mpa_s": lv["viscosity_mpa_s"],
                       "surface_tension_mn_m": lv["surface_tension_mn_m"], "h0_rule": lv["h0_rule"]}
                if par not in m["levelling"]:
                    m["levelling"].append(par)
        else:
            m["thinnest_to_mean_levelled"] = None
            m["levelling"] = []
        m["levelled_everywhere"] = m.get("levelled_everywhere", True) and all(lv is not None for lv in levs)
        m["mean_um"].append(o["deposit"]["mean_um"])
        m["cell_model_iou"] = o["iou"] if m["cell_model_iou"] is None else min(m["cell_model_iou"], o["iou"])
    for m in out.values():
        lev = m.pop("levelled_everywhere", False) and m["thinnest_to_mean_levelled"] is not None
        if not lev:
            m["thinnest_to_mean_levelled"], m["levelling"] = None, []
        m["thinnest_to_mean_basis"] = "levelled" if lev else "as landed"
        m["thinnest_to_mean"] = m["thinnest_to_mean_levelled"] if lev else m["thinnest_to_mean_as_landed"]
    return out


def stage_resistance(job, plan, layers: LayerOutputs, step: Step) -> list[dict]:
    """Resistance estimates (design and printed masks, and a hand check) of every
    ``[[resistance]]`` entry of the job."""
    from ..process.conductance import coil_hand_check, resistance_from_masks, resistance_from_thickness, thickness_map_um

    sp = job.spec
    grid1 = plan.design_grid()
    gridr = plan.design_grid(oversample=RESISTANCE_OVERSAMPLE)
    resistance = []
    for j, r in enumerate(sp.resistance):
        step("resistance", j, len(sp.resistance))
        m = job.part(r.part).material
        try:
            d, _ = resistance_from_masks(plan, r, layers.design_masks[m], gridr)
            films = layers.printed_thickness[m]
            total = np.sum(films, axis=0) if films else np.zeros((grid1.height_px, grid1.width_px))
            p, _ = resistance_from_thickness(plan, r, total, grid1, layers=len(films))
            p["model"] = "deposit: the film the planned drops of every pass deposit (process/conductance.py)"
        except RotoprintError as exc:
            resistance.append({"part": r.part, "between": list(r.between), "error": exc.problem})
            continue
        track_layers = len([mm for mm in layers.design_masks[m] if mm.any()])
        sh = job.part(r.part).shape
        if sh is not None and sh.kind == "square_coil":
            lh = sp.job.layer_height_mm
            track_layers = max(1, round(sh.height_mm / lh))
        region = np.logical_or.reduce(layers.design_masks[m]) if layers.design_masks[m] else None
        t_mean = float(thickness_map_um(plan, m, gridr)[region].mean()) if region is not None and region.any() else None
        hand = coil_hand_check(plan, r, track_layers=track_layers, per_layer_um=t_mean)
        resistance.append({"part": r.part, "material": m, "between": list(r.between),
                           "design": {**d, "oversample": RESISTANCE_OVERSAMPLE}, "printed": p, "hand_check": hand})
    step("resistance", len(sp.resistance), len(sp.resistance))
    return resistance


def stage_report(plan, plan_json: dict, composites: list[bytes], tmp: Path, step: Step, *, report: bool) -> str:
    """Write ``plan.json`` (and with ``report`` the self-contained ``report.html``) into
    ``tmp``; returns the text of ``plan.json``."""
    text = json.dumps(plan_json, indent=1, default=_json_default)
    (tmp / "plan.json").write_text(text, encoding="utf-8")
    if report:
        from ..report import render_report

        step("report", 0, 1)
        html = render_report(plan, plan_json, composites=composites, overlays_dir=tmp)
        (tmp / "report.html").write_text(html, encoding="utf-8")
        step("report", 1, 1)
    return text


def _interdigitated(job) -> dict:
    ide = {}
    for part in job.spec.parts:
        if part.shape is not None and part.shape.kind == "interdigitated":
            ide[part.name] = {"cell_constant_per_mm": part.shape.cell_constant_per_mm(),
                              "note": "film resistance between the combs = film sheet resistance x gap / (overlap x gaps)"}
    return ide


# ---------------------------------------------------------------------- the run
def job_inputs(job) -> list[Path]:
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


def run_build(job, out_dir: str | Path, *, on_step: Step | None = None, check: bool | None = None,
              report: bool = True, force: bool = False, inputs: Iterable[str | Path] = (), machine=None) -> BuildResult:
    """Run the stages of :data:`STAGES` for ``job`` and write ``out_dir``.

    Parameters
    ----------
    job : ResolvedJob
    out_dir : str or Path
    on_step : callable, optional
        ``on_step(stage, done, total)`` for progress display, for every stage in turn.
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
        ``summary["timings_s"]`` has every stage's time (``plan_s`` ... ``report_s``) and
        ``total_s``; ``plan.json`` records those of check, layers, simulate and resistance.
    """
    from ..io.atomic import atomic_dir

    t0 = time.perf_counter()
    step = on_step or (lambda *a: None)
    timings: dict[str, float] = {}
    stage_times: dict[str, float] = {}
    with _timed(stage_times, "plan_s"):
        plan = stage_plan(job, step)
    do_check = job.spec.process.check if check is None else bool(check)
    out = Path(out_dir)
    final = out.resolve()
    with atomic_dir(out, kind="build", inputs=[*inputs, *job_inputs(job)], force=force) as tmp:
        (tmp / "layers").mkdir()
        (tmp / "overlays").mkdir()
        from ..machine.program import machine_stage

        mw = machine_stage(plan, tmp / "machine", machine)  # the machine folder, streamed layer by layer
        with _timed(timings, "check_s"):
            checks = stage_check(job, plan, tmp, step) if do_check else []
        with _timed(timings, "layers_s"):
            layers = stage_layers(job, plan, tmp, step, mw)
            machine_totals = mw.close() if mw is not None else None
        with _timed(timings, "simulate_s"):
            overlays = stage_simulate(job, plan, layers.present, tmp, step)
        with _timed(timings, "resistance_s"):
            resistance = stage_resistance(job, plan, layers, step)
        plan_json = {
            "format": PLAN_FORMAT, "version": 1, "rotoprint": __version__,
            "source": job.source, **plan.to_json(),
            "grid": plan.design_grid().to_json(),
            "estimated_print_time_s": layers.total_time_s,
            "printability": checks,
            "resistance": resistance,
            "interdigitated": _interdigitated(job),
            "coverage": coverage_summary(overlays),
            "overlays": overlays,
            "timings_s": timings,
            "layers_detail": layers.layers_json,
        }
        with _timed(stage_times, "report_s"):
            text = stage_report(plan, plan_json, layers.composites, tmp, step, report=report)
    all_timings = {"plan_s": stage_times["plan_s"], **timings, "report_s": stage_times["report_s"],
                   "total_s": time.perf_counter() - t0}
    summary = {
        "layers": len(plan), "heads": len(plan.heads), "warnings": plan.warnings, "resistance": resistance,
        "printability_ok": all(c["ok"] for c in checks) if checks else None,
        "coverage": plan_json["coverage"],
        "estimated_print_time_s": layers.total_time_s,
        "timings_s": all_timings, "plan_sha256": hashlib.sha256(text.encode()).hexdigest(),
        "machine": machine_totals,
    }
    return BuildResult(out_dir=final, report_path=final / "report.html" if report else None, plan_path=final / "plan.json", summary=summary)


def _json_default(o):
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.integer | np.floating):
        v = o.item()
        return v if not (isinstance(v, float) and not math.isfinite(v)) else None
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")
