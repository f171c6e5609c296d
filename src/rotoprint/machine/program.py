"""Writing ``machine/``: packed firing data, TIFF planes and the machine program of a build.

Layout (``docs/machine.md``)::

    machine/program.json                 format "rotoprint-machine-program", version 1
    machine/program.txt                  the same steps, one line each
    machine/layers/layer_NNNNN/MATERIAL-INK-sJ.bin   packed words (see rotoprint.io.machine)
    machine/layers/layer_NNNNN/MATERIAL-INK-sJ.tif   the same image as a TIFF plane
    machine/layers/layer_NNNNN/design-MATERIAL.bin   the layer's design region, 1 bit per pixel

The writer streams: each layer's files and its part of the program are written when the
layer is added and nothing of it is kept, so memory does not grow with the layer count. It
writes into a folder that the caller installs atomically (the build's temporary folder, or
:func:`write_machine_folder`'s).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from .. import __version__
from ..errors import ConfigError
from ..io.machine import bits_for_levels, nozzle_order, pack_levels, packed_bytes, tiff_bytes
from ..io.machine.packing import WORD_BYTE_ORDER, max_level
from ..io.ownership import open_tracked, write_tracked
from ..rotary.head import Mount, nozzle_layout
from ..rotary.printdata import _runs
from .clock import FLAG_FRACTION, clock_ratio
from .spec import MachineSpec

__all__ = ["MachineOptions", "MachineWriter", "machine_stage", "PROGRAM_FORMAT", "PROGRAM_VERSION", "row_offsets_firings",
           "write_machine_folder", "shift_rows", "unshift_rows"]

PROGRAM_FORMAT = "rotoprint-machine-program"
PROGRAM_VERSION = 1


@dataclass(frozen=True)
class MachineOptions:
    """How the machine folder is written.

    Attributes
    ----------
    bits : {1, 2, 4} or None
        Bits per nozzle; ``None``: the fewest that hold the head's grey levels.
    row_delays : {'baked', 'program'}
        ``baked``: every nozzle's true firing delay is in the image (exact at every radius);
        ``program``: each row's delay, rounded to whole firings at the swathe, is taken out of
        the image and listed per swathe as ``row_offsets_firings`` for the controller.
    tiff : bool
        Also write each image as a TIFF plane.
    """

    bits: int | None = None
    row_delays: Literal["baked", "program"] = "baked"
    tiff: bool = True

    def __post_init__(self) -> None:
        if self.bits is not None and self.bits not in (1, 2, 4):
            raise ConfigError(f"--bits must be 1, 2 or 4, got {self.bits!r}")
        if self.row_delays not in ("baked", "program"):
            raise ConfigError(f"--row-delays must be 'baked' or 'program', got {self.row_delays!r}")


def row_offsets_firings(head, *, pivot_radius_mm: float, tilt_deg: float, mount_angle_deg: float, direction: int,
                        dphi_rad: float) -> list[int]:
    """Each row's firing delay relative to row 0, whole firings, for a head at one swathe.

    Row ``q``'s nozzles sit ``Delta phi_q`` (their mean angle minus row 0's) ahead of row 0; a
    drop for the same target fires ``Delta phi_q / (direction * dphi)`` firings later. On a
    rotary platform this is right at one radius only, which is why ``baked`` is the default.

    Returns
    -------
    list of int
        ``head.rows`` entries, the first 0.
    """
    lay = nozzle_layout(head, Mount(pivot_radius_mm, tilt_deg=tilt_deg, mount_angle_deg=mount_angle_deg, direction=direction))
    ref = lay.phi_rad[lay.row == 0]
    out = []
    for q in range(head.rows):
        ph = lay.phi_rad[lay.row == q]
        if not ph.size:
            out.append(0)
            continue
        d = np.angle(np.exp(1j * (ph.mean() - ref.mean())))
        out.append(int(round(float(d) / (direction * dphi_rad))))
    return out


def shift_rows(levels: np.ndarray, rows_of: np.ndarray, offsets: list[int]) -> tuple[np.ndarray, int]:
    """Take each row's delay out of a firing image: ``(F', N)`` and the first-firing shift.

    Nozzles of row ``q`` move ``max(offsets) - offsets[q]`` image rows down; the image grows by
    ``max - min`` rows and its first firing moves by ``-max(offsets)``. The controller firing
    image row ``b'`` of row ``q`` at firing ``first' + b' + offsets[q]`` reproduces the
    baked image exactly.
    """
    f, n = levels.shape
    dmax, dmin = max(offsets), min(offsets)
    out = np.zeros((f + dmax - dmin, n), levels.dtype)
    for q, d in enumerate(offsets):
        cols = np.flatnonzero(rows_of == q)
        out[dmax - d: dmax - d + f, cols] = levels[:, cols]
    return out, -dmax


def unshift_rows(levels: np.ndarray, rows_of: np.ndarray, offsets: list[int]) -> tuple[np.ndarray, int]:
    """Inverse of :func:`shift_rows`: the baked ``(F, N)`` image and the first-firing shift back."""
    dmax, dmin = max(offsets), min(offsets)
    f = levels.shape[0] - (dmax - dmin)
    out = np.zeros((f, levels.shape[1]), levels.dtype)
    for q, d in enumerate(offsets):
        cols = np.flatnonzero(rows_of == q)
        out[:, cols] = levels[dmax - d: dmax - d + f, cols]
    return out, dmax


def _fmt_s(t: float) -> str:
    return f"{t:.3f} s"


class MachineWriter:
    """Writes ``folder`` (``machine/``) layer by layer for a :class:`~rotoprint.process.plan.BuildPlan`.

    The heads' clocks, stage positions and speeds are checked against ``spec`` when the
    writer is made (one line naming the field, the head and the swathe). Call
    :meth:`add_layer` for every layer in order, then :meth:`close`.
    """

    def __init__(self, plan, folder: str | Path, spec: MachineSpec | None = None, options: MachineOptions | None = None,
                 *, source: str | None = None) -> None:
        self.plan = plan
        self.spec = spec or MachineSpec()
        self.opts = options or MachineOptions()
        self.folder = Path(folder)
        head = plan.device.head
        need = bits_for_levels(head.grey_levels)
        self.bits = need if self.opts.bits is None else self.opts.bits
        if self.bits < need:
            raise ConfigError(f"--bits {self.bits}: the head has {head.grey_levels} drop levels, which need {need} bits per nozzle")
        nn = self.spec.nozzle_numbering
        if nn.odd_row >= head.rows:
            raise ConfigError(f"machine.nozzle_numbering.odd_row: {nn.odd_row} is not a row of a {head.rows}-row head")
        self.order = nozzle_order(head.nozzles, head.rows, odd_row=nn.odd_row, descending=nn.direction == "descending")
        self.rows_of = np.arange(head.nozzles) % head.rows
        self._heads = [self._head_record(h) for h in plan.heads]
        self._index = {h.index: r for h, r in zip(plan.heads, self._heads)}
        self.folder.mkdir(parents=True, exist_ok=True)
        (self.folder / "layers").mkdir(exist_ok=True)
        # hashed as they are written (the output's ownership marker does not read them again)
        self._json = open_tracked(self.folder / "program.json")
        self._txt = open_tracked(self.folder / "program.txt")
        self._n_step = 0
        self._layers = 0
        self._total = 0.0
        self._printing = 0.0
        self._motion = 0.0
        self._idle = 0.0
        self._revs = 0
        self._flagged: set[tuple[str, int]] = set()
        self._stage: dict[str, float] = {}
        self._z_prev: float | None = None
        header = {
            "format": PROGRAM_FORMAT, "version": PROGRAM_VERSION, "rotoprint": __version__, "job": source,
            "device": plan.device.name,
            "machine": self.spec.model_dump(mode="json"),
            "packing": {"bits_per_nozzle": self.bits, "max_level": max_level(self.bits), "word_bits": 32,
                        "bit_order": "msb-first", "word_byte_order": WORD_BYTE_ORDER,
                        "row_padding": "zero bits to a whole word", "nozzle_order": nn.model_dump(mode="json"),
                        "tiff": bool(self.opts.tiff)},
            "row_delays": self.opts.row_delays,
            "design_grid": plan.design_grid().to_json(),
            "heads": self._heads,
        }
        text = json.dumps(header, indent=1)
        self._json.write(text[:-2] + ',\n "layers": [\n')
        self._line(f"rotoprint machine program v{PROGRAM_VERSION} - {source or 'job'} - device {plan.device.name}")
        self._line(f"packing: {self.bits} bit(s) per nozzle, 32-bit words MSB first ({WORD_BYTE_ORDER}-endian), "
                   f"nozzle order: odd numbers in row {nn.odd_row}, {nn.direction}; row delays {self.opts.row_delays}")
        m = self.spec
        self._line(f"machine: encoder {m.encoder_counts_per_rev} counts/rev, radial stage {m.radial_stage_mm[0]:g}-"
                   f"{m.radial_stage_mm[1]:g} mm, max {m.max_platform_rpm:g} rpm; idle: {m.idle.mode}")
        for r in self._heads:
            for s in r["swathes"]:
                c = s["clock"]
                stage = (f"stage {s['radial_stage_mm']:.4f} mm" if len(s["pass_stage_mm"]) == 1 else
                         "stage " + " / ".join(f"{v:.4f}" for v in s["pass_stage_mm"]) + " mm (interlaced passes)")
                self._line(f"head {r['name']} ({r['ink']}) swathe {s['swathe']}: {stage}, "
                           f"clock x{c['multiplier']}/{c['divider']}, angle error {c['angle_error_per_rev_deg']:.3g} deg/rev "
                           f"({c['angle_error_per_rev_steps']:.3g} firing steps){'  FLAGGED' if c['flagged'] else ''}, "
                           f"{s['platform_rpm']:.2f} rpm, {s['revolution_s']:.4f} s/rev"
                           + (f", row offsets {s['row_offsets_firings']} firings" if s["row_offsets_firings"] else ""))

    # -- validation of the heads against the machine ---------------------------------------
    def _head_record(self, h) -> dict:
        m = self.spec
        dev = self.plan.device.head
        fmax = min(dev.max_frequency_hz, m.head_frequency_hz or math.inf)
        if h.frequency_hz > fmax:
            which = "machine.head_frequency_hz" if m.head_frequency_hz and m.head_frequency_hz < dev.max_frequency_hz else "head max_frequency_hz"
            raise ConfigError(f"{which}: head {h.name} fires at {h.frequency_hz:g} Hz, above the {fmax:g} Hz it can reach")
        sws = []
        for j, t in enumerate(h.lattice.tracks):
            where = f"head {h.name} swathe {j}"
            pivot = float(t.pivot_radius_mm)
            stages = [float(la.tracks[j].pivot_radius_mm) for la in h.pass_lattices]  # pass q: pivot + its offset
            lo, hi = m.radial_stage_mm
            for q, st in enumerate(stages):
                if not lo <= st <= hi:
                    raise ConfigError(f"machine.radial_stage_mm: {where}" + (f" pass {q}" if len(stages) > 1 else "")
                                      + f" needs the radial stage at {st:.4f} mm, outside [{lo:g}, {hi:g}] mm")
            rev_s = 2 * math.pi / t.dphi_rad / h.frequency_hz
            rpm = 60.0 / rev_s
            if rpm > m.max_platform_rpm:
                raise ConfigError(f"machine.max_platform_rpm: {where} turns the platform at {rpm:.2f} rpm to fire at "
                                  f"{h.frequency_hz:g} Hz, above {m.max_platform_rpm:g} rpm (lower printer.clock.frequency_hz)")
            try:
                c = clock_ratio(t.dphi_rad, m.encoder_counts_per_rev, max_multiplier=m.clock_max_multiplier,
                                max_divider=m.clock_max_divider)
            except ConfigError as exc:
                raise ConfigError(f"machine.encoder_counts_per_rev: {where}: {exc.problem}") from None
            sws.append({"swathe": j, "radial_stage_mm": pivot, "pass_stage_mm": stages,
                        "pass_offsets_mm": [float(o) for o in h.pass_offsets_mm], "dphi_rad": float(t.dphi_rad),
                        "frequency_hz": h.frequency_hz, "revolution_s": rev_s, "platform_rpm": rpm,
                        "clock": c.to_json(), "clocked_dphi_rad": c.clocked_dphi_rad,
                        "row_offsets_firings": row_offsets_firings(
                            dev, pivot_radius_mm=pivot, tilt_deg=h.tilt_deg, mount_angle_deg=h.mount_angle_deg,
                            direction=self.plan.job.spec.printer.direction, dphi_rad=t.dphi_rad)
                        if self.opts.row_delays == "program" else None})
        return {"index": h.index, "name": h.name, "ink": h.ink, "tilt_deg": h.tilt_deg, "mount_angle_deg": h.mount_angle_deg,
                "passes": h.passes, "pass_offsets_mm": [float(o) for o in h.pass_offsets_mm],
                "direction": self.plan.job.spec.printer.direction, "frequency_hz": h.frequency_hz,
                "model": self.plan.device.head.model_dump(mode="json"), "swathes": sws}

    # -- streaming -------------------------------------------------------------------------
    def _line(self, s: str) -> None:
        self._txt.write(s + "\n")

    def _write(self, rel: str, data: bytes) -> str:
        return write_tracked(self.folder / rel, data)

    def _step(self, steps: list, d: dict) -> dict:
        d = {"n": self._n_step, **d}
        self._n_step += 1
        self._total += d["time_s"]
        steps.append(d)
        return d

    def _idle_note(self, t: float) -> dict | None:
        idle = self.spec.idle
        if t <= idle.after_s or idle.mode == "none":
            return None
        if idle.mode == "spit":
            n = int(t // idle.spit_interval_s)
            return {"mode": "spit", "spits": n, "drops_per_nozzle": n * idle.spit_drops}
        return {"mode": "wet"}

    def add_layer(self, sched, designs: dict[str, np.ndarray]) -> None:
        """Write layer ``sched.index``: its images, design regions and steps.

        Parameters
        ----------
        sched : LayerSchedule
            From ``plan.layer(i)``, layers in order.
        designs : dict of str to (H, W) bool
            Each printed material's region on the design grid (``plan.reference_image``).
        """
        i = sched.index
        if i != self._layers:
            raise ConfigError(f"machine program: layer {i} added after {self._layers - 1}")
        rel_dir = f"layers/layer_{i:05d}"
        (self.folder / rel_dir).mkdir()
        images = []
        by_key = {}
        every = [(mname, ink, q, pr, len(prs)) for (mname, ink), prs in sched.pass_images.items() for q, pr in enumerate(prs)]
        for mname, ink, q, pr, n_pass in every:
            hrec = self._index[self.plan.head(ink).index]
            for j, sw in enumerate(pr.swathes):
                lv = sw.levels
                first = sw.first_firing
                offs = None
                if self.opts.row_delays == "program":
                    offs = hrec["swathes"][j]["row_offsets_firings"]
                    lv, dfirst = shift_rows(lv, self.rows_of, offs)
                    first += dfirst
                words = pack_levels(lv, self.bits, self.order)
                key = f"{mname}-{ink}-s{j}" if n_pass == 1 else f"{mname}-{ink}-p{q + 1}-s{j}"
                name = f"{rel_dir}/{key}"
                sha = self._write(name + ".bin", packed_bytes(words))
                rec = {"key": key, "material": mname, "ink": ink, "head": hrec["name"], "head_index": hrec["index"],
                       "swathe": j, "interlace": q, "pass_offset_mm": hrec["pass_offsets_mm"][q],
                       "file": name + ".bin", "sha256": sha, "firings": int(lv.shape[0]),
                       "nozzles": int(lv.shape[1]), "words_per_row": int(words.shape[1]), "first_firing_index": int(first),
                       "row_offsets_firings": offs, "drops": int(np.count_nonzero(lv)),
                       "enabled_nozzles": sw.enabled_nozzles,
                       "enabled_nozzle_runs": _runs(sw.enabled) if sw.enabled is not None else None,
                       "pivot_radius_mm": sw.pivot_radius_mm, "ref_radius_mm": sw.ref_radius_mm, "band_mm": list(sw.band_mm),
                       "dphi_rad": sw.dphi_rad, "method": pr.method, "tilt_deg": pr.tilt_deg,
                       "mount_angle_deg": pr.mount_angle_deg, "direction": pr.direction, "dpi_y": pr.dpi_y,
                       "placement": pr.placement.to_json()}
                n_counts = self.spec.encoder_counts_per_rev
                # a print made for a mount turned by delta from the head's (an interlaced pass's
                # angular phase) is the head's firing data delayed by direction * delta
                delta = math.radians(pr.mount_angle_deg - hrec["mount_angle_deg"])
                exact = (first * sw.dphi_rad - pr.direction * delta) / (2 * math.pi) * n_counts
                rec["index_offset_counts"] = int(round(exact)) % n_counts
                rec["index_error_deg"] = (round(exact) - exact) * 360.0 / n_counts
                if self.opts.tiff:
                    desc = json.dumps({"rotoprint": "machine", "layer": i, "material": mname, "ink": ink, "swathe": j,
                                       **({"pass": q} if n_pass > 1 else {}),
                                       "bits": self.bits, "rows": "firings", "columns": "nozzles in the head's order"})
                    rec["tiff"] = name + ".tif"
                    rec["tiff_sha256"] = self._write(name + ".tif", tiff_bytes(lv, self.bits, self.order, description=desc))
                images.append(rec)
                by_key[(mname, ink, q, j)] = rec
        design_recs = []
        for mname in sorted(designs):
            d = np.asarray(designs[mname], bool)
            words = pack_levels(d.astype(np.uint8), 1, np.arange(d.shape[1]))
            name = f"{rel_dir}/design-{mname}.bin"
            design_recs.append({"material": mname, "file": name, "sha256": self._write(name, packed_bytes(words)),
                                "height_px": int(d.shape[0]), "width_px": int(d.shape[1]), "bits": 1})
        steps: list[dict] = []
        self._line("")
        self._line(f"layer {i}: z {sched.z_bottom_mm:.4f}-{sched.z_top_mm:.4f} mm")
        t_layer0 = self._total
        p = 0
        m = self.spec
        for b in sched.blocks:
            for c in range(b.cycles):
                for ps in b.passes:
                    hrec = self._index[ps.head_index]
                    q = b.interlace_of(ps.ink, c)  # the interlaced pass of this cycle
                    for rep in range(ps.repeats):
                        for s in hrec["swathes"]:
                            j = s["swathe"]
                            rec = by_key.get((b.material, ps.ink, q, j))
                            stage = s["pass_stage_mm"][q]
                            if self._stage.get(hrec["name"]) != stage:
                                prev = self._stage.get(hrec["name"])
                                if prev is not None or m.radial_move_s:
                                    st = self._step(steps, {"kind": "radial_move", "layer": i, "head": hrec["name"],
                                                            "from_mm": prev, "to_mm": stage, "time_s": m.radial_move_s})
                                    self._motion += st["time_s"]
                                    self._line(f"  {st['n']:7d} move   {hrec['name']} radial stage -> {stage:.4f} mm  {_fmt_s(st['time_s'])}")
                                self._stage[hrec["name"]] = stage
                            c_ = s["clock"]
                            st = self._step(steps, {
                                "kind": "revolution", "layer": i, "pass": p, "cycle": c, "repeat": rep, "interlace": q,
                                "pass_offset_mm": hrec["pass_offsets_mm"][q],
                                "material": b.material, "ink": ps.ink, "head": hrec["name"], "swathe": j,
                                "radial_stage_mm": stage, "frequency_hz": s["frequency_hz"],
                                "multiplier": c_["multiplier"], "divider": c_["divider"],
                                "angle_error_per_rev_deg": c_["angle_error_per_rev_deg"], "clock_flagged": c_["flagged"],
                                "index_offset_counts": rec["index_offset_counts"] if rec else None,
                                "firings": rec["firings"] if rec else 0,
                                "image": rec["file"] if rec else None, "sha256": rec["sha256"] if rec else None,
                                "time_s": s["revolution_s"]})
                            self._revs += 1
                            self._printing += st["time_s"]
                            if c_["flagged"]:
                                self._flagged.add((hrec["name"], j))
                            self._line(f"  {st['n']:7d} rev    pass {p} cycle {c}" + (f" interlace {q}" if hrec["passes"] > 1 else "")
                                       + f" {b.material}/{ps.ink} on {hrec['name']} "
                                       f"swathe {j}  stage {stage:.4f} mm  clock x{c_['multiplier']}/{c_['divider']} "
                                       f"(err {c_['angle_error_per_rev_deg']:.2g} deg/rev{' FLAGGED' if c_['flagged'] else ''})  "
                                       + (f"index {rec['index_offset_counts']}  {rec['firings']} firings  {rec['file']} "
                                          f"{rec['sha256'][:12]}" if rec else "no drops")
                                       + f"  {_fmt_s(st['time_s'])}")
                        if ps.wait_s:
                            st = self._step(steps, {"kind": "wait", "layer": i, "material": b.material, "ink": ps.ink,
                                                    "time_s": ps.wait_s, "idle": self._idle_note(ps.wait_s)})
                            self._idle += st["time_s"]
                            self._line(f"  {st['n']:7d} wait   after {ps.ink}  {_fmt_s(st['time_s'])}")
                    p += 1
            mat = self.plan.job.materials[b.material]
            for ps_ in mat.post_steps:
                st = self._step(steps, {"kind": "post", "layer": i, "material": b.material, "post": ps_.kind,
                                        "temperature_c": ps_.temperature_c, "time_s": ps_.duration_s,
                                        "describe": ps_.describe(), "idle": self._idle_note(ps_.duration_s)})
                self._idle += st["time_s"]
                self._line(f"  {st['n']:7d} post   {b.material}: {ps_.describe()}  {_fmt_s(st['time_s'])}")
        dz = sched.z_top_mm - sched.z_bottom_mm
        st = self._step(steps, {"kind": "z_step", "layer": i, "z_step_mm": dz, "to_z_mm": sched.z_top_mm,
                                "time_s": m.z_step_s, "idle": self._idle_note(m.z_step_s)})
        self._motion += st["time_s"]
        self._line(f"  {st['n']:7d} z      platform down {dz:.4f} mm  {_fmt_s(st['time_s'])}")
        layer = {"index": i, "z_bottom_mm": sched.z_bottom_mm, "z_top_mm": sched.z_top_mm, "z_step_mm": dz,
                 "plan_time_s": sched.time_s, "time_s": self._total - t_layer0, "passes": p,
                 "images": images, "designs": design_recs, "steps": steps}
        self._json.write((",\n" if self._layers else "") + json.dumps(layer, separators=(",", ":")))
        self._layers += 1

    def close(self) -> dict:
        """Finish ``program.json`` and ``program.txt``; returns the totals."""
        totals = {"layers": self._layers, "steps": self._n_step, "revolutions": self._revs, "time_s": self._total,
                  "printing_s": self._printing, "idle_s": self._idle, "motion_s": self._motion,
                  "flagged_clocks": [f"head {h} swathe {j}" for h, j in sorted(self._flagged)],
                  "flag_rule": f"angle error per revolution >= {FLAG_FRACTION} firing step"}
        self._json.write("\n ],\n \"totals\": " + json.dumps(totals) + "\n}\n")
        self._json.close()
        self._line("")
        self._line(f"total: {self._n_step} steps, {self._revs} revolutions, {self._total:.3f} s "
                   f"(printing {self._printing:.3f} s, waits and post-steps {self._idle:.3f} s, motion {self._motion:.3f} s)")
        if self._flagged:
            self._line("FLAGGED clocks: " + ", ".join(totals["flagged_clocks"]))
        self._txt.close()
        return totals

    def abort(self) -> None:
        for f in (self._json, self._txt):
            if not f.closed:
                f.close()


def machine_stage(plan, folder: Path, options=None):
    """The build's machine stage: a :class:`MachineWriter` on ``folder`` with the job's
    ``[machine]`` section, or None when ``options`` is False."""
    if options is False:
        return None
    try:
        return MachineWriter(plan, folder, plan.job.spec.machine, options if isinstance(options, MachineOptions) else None,
                             source=Path(plan.job.source).name if plan.job.source else None)
    except ConfigError as exc:
        raise ConfigError(exc.problem, path=plan.job.source) from None


def write_machine_folder(plan, out: str | Path, spec: MachineSpec | None = None, options: MachineOptions | None = None, *,
                         on_step=None, force: bool = False, inputs=(), layers=None) -> dict:
    """Write a plan's machine folder at ``out`` atomically (without the rest of a build).

    Parameters
    ----------
    plan : BuildPlan
    out : str or Path
        The folder to write (replaced only when provably ours, or with ``force``).
    spec, options : MachineSpec, MachineOptions
    on_step : callable, optional
        ``on_step("machine", done, total)``.
    layers : int, optional
        Only the first ``layers`` layers.

    Returns
    -------
    dict
        The program's totals.
    """
    from ..io.atomic import atomic_dir

    n = len(plan) if layers is None else min(int(layers), len(plan))
    step = on_step or (lambda *a: None)
    with atomic_dir(out, kind="machine", inputs=inputs, force=force) as tmp:
        w = MachineWriter(plan, tmp, plan.job.spec.machine if spec is None else spec, options,
                          source=Path(plan.job.source).name if plan.job.source else None)
        try:
            for i in range(n):
                step("machine", i, n)
                sched = plan.layer(i)
                secs = plan.sections(i)
                w.add_layer(sched, {b.material: plan.reference_image(b.material, secs) for b in sched.blocks})
            step("machine", n, n)
            return w.close()
        except BaseException:
            w.abort()
            raise
