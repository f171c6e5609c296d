"""Replaying a machine program: read only ``program.json`` and the packed files, decode them,
land every drop as the machine would and compare with the layer's design region.

The drops are placed by :func:`rotoprint.rotary.simulate.simulate` from the decoded images
and the program's geometry (head model, tilt, mount, direction, stage position, first
firing) at the angles the machine fires them (``angles="machine"``, the default): an
image's first firing when the encoder has counted ``index_offset_counts`` after the index
pulse, each next one ``divider / multiplier`` counts later (:func:`machine_clock`). The
integer ratio and the whole counts move each drop off its nominal site (``i * dphi_rad``);
the largest such displacement is reported per image, swathe and revolution step. With an
exact clock the figures are those ``simulate`` gives for the build's images;
``angles="nominal"`` places the drops at the nominal angles (the figures of ``simulate``).

Refused, with one line naming the step: a file that is missing or whose SHA-256 differs, a
radial stage position outside the machine's stage, a clock the head or the controller cannot
make (firing frequency above the head's or machine's maximum, a platform speed above the
machine's, a multiplier or divider beyond the controller's limits, a ratio that does not make
the image's firings per revolution).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from pydantic import ValidationError

from .. import ranges as R
from ..devices.models import InkjetHead
from ..errors import ConfigError, InputFileError, RotoprintError
from ..io.inputs import parse_json, read_input_bytes
from ..io.machine import nozzle_order, read_packed, unpack_levels, words_per_row
from ..io.records import MissingKeyError, as_record, missing_key_message, validation_line
from ..rotary.files import check_print_fields
from ..rotary.placement import Placement
from ..rotary.printdata import RotaryPrint, SwatheImage, runs_to_mask
from ..rotary.simulate import FiringClock
from .program import PROGRAM_FORMAT, PROGRAM_VERSION, unshift_rows
from .spec import MachineSpec

__all__ = ["load_program", "ReplayImage", "replay_layers", "replay_program", "machine_clock", "MAX_PROGRAM_BYTES",
           "MAX_IMAGE_BYTES", "ANGLES", "EXACT_RAD", "clock_is_exact"]

#: Where a replay places the firings: the machine's clock, or the nominal ``i * dphi``.
ANGLES = ("machine", "nominal")

#: Largest program.json read (a 1,000-layer coil program is about 200 MB).
MAX_PROGRAM_BYTES = 2 * 2**30
#: Largest packed file read.
MAX_IMAGE_BYTES = 1 * 2**30


def _read_bounded(path: Path, limit: int, what: str, where: str, program: Path) -> bytes:
    """A regular file of at most ``limit`` bytes (:func:`rotoprint.io.inputs.read_input_bytes`),
    its refusals as one line naming ``where`` in ``program``."""
    if not path.exists() and not path.is_symlink():
        raise InputFileError(f"{where}: {what} {path.name} is missing", path=program)
    try:
        return read_input_bytes(path, what=what, limit_bytes=limit)
    except InputFileError as exc:
        raise InputFileError(f"{where}: {what} {path.name} {exc.problem}", path=program) from None


def load_program(path: str | Path) -> dict:
    """Read and check the header of a machine program.

    Parameters
    ----------
    path : str or Path
        ``machine/program.json``.

    Returns
    -------
    dict
        The parsed program.

    Raises
    ------
    InputFileError
        Missing, too big, not JSON, not a rotoprint machine program or of a newer version, a
        ``machine`` section that does not validate, or a head whose clock, stage position or
        speed the machine cannot make (the message names the head and swathe).
    """
    p = Path(path)
    prog = parse_json(read_input_bytes(p, what="machine program", limit_bytes=MAX_PROGRAM_BYTES), p, what="program")
    try:
        return _checked_program(as_record(prog), p)
    except MissingKeyError as exc:
        raise InputFileError(missing_key_message(exc), path=p) from None


def _checked_program(prog: dict, p: Path) -> dict:
    """:func:`load_program`'s checks of the parsed ``prog`` (a :class:`~rotoprint.io.records.Record`)."""
    if not isinstance(prog, dict) or prog.get("format") != PROGRAM_FORMAT:
        raise InputFileError(f"not a rotoprint machine program (format {PROGRAM_FORMAT!r} expected)", path=p)
    if not isinstance(prog.get("version"), int) or prog["version"] > PROGRAM_VERSION:
        raise InputFileError(f"program version {prog.get('version')!r}; this rotoprint reads up to {PROGRAM_VERSION}", path=p)
    if not isinstance(prog["machine"], dict):
        raise InputFileError(f"program has no valid machine section (a table), got {R.show_value(prog['machine'])}",
                             path=p)
    try:
        spec = MachineSpec(**prog["machine"])
    except ValidationError as exc:
        raise InputFileError(validation_line(exc, "machine"), path=p) from None
    prog["_spec"] = spec
    _check_design_grid(prog.get("design_grid"), p)
    for k in ("heads", "layers"):
        if not isinstance(prog[k], list):
            raise InputFileError(f"{k} must be a list, got {R.show_value(prog[k])}", path=p)
    if not isinstance(prog["totals"], dict):
        raise InputFileError(f"totals must be a table, got {R.show_value(prog['totals'])}", path=p)
    for j, h in enumerate(prog["heads"]):
        if not isinstance(h, dict) or not isinstance(h["model"], dict) or not isinstance(h["swathes"], list):
            raise InputFileError(f"heads[{j}] must be a table with a table model and a list swathes", path=p)
        try:
            h["_model"] = InkjetHead(**h["model"])
        except ValidationError as exc:
            raise InputFileError(validation_line(exc, f"heads[{j}].model"), path=p) from None
        for s in h["swathes"]:
            if not (isinstance(s, dict) and isinstance(s["clock"], dict)):
                raise InputFileError(f"heads[{j}]: a swathe and its clock must be tables", path=p)
            _check_swathe(spec, h, s, {**s, **s["clock"]}, f"head {h['name']} swathe {s['swathe']}", p)
    return prog


def _check_design_grid(g: object, p: Path) -> None:
    """The program's ``design_grid`` (the placement every design region is drawn on): whole
    pixel counts and finite positive pitches (a machine places the regions by it)."""
    if not isinstance(g, dict):
        raise InputFileError("program has no valid design_grid", path=p)
    for k in ("width_px", "height_px"):
        v = g.get(k)
        if not (isinstance(v, int) and not isinstance(v, bool) and 1 <= v <= R.MAX_COUNT):
            raise InputFileError(f"design_grid.{k} must be a whole number 1..{R.MAX_COUNT:g}, got {R.show_value(v)}", path=p)
    for k in ("pitch_x_mm", "pitch_y_mm"):
        v = g.get(k)
        if not (_finite(v) and v > 0):
            raise InputFileError(f"design_grid.{k} must be a finite length > 0 mm, got {R.show_value(v)}", path=p)


def _finite(v: object) -> bool:
    """A JSON number that is finite as a float (not a bool, not an int past the float range)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return False
    try:
        return math.isfinite(v)
    except OverflowError:
        return False


def _shown(v: object) -> str:
    """A program's value in a message: a float as written, anything else short (an integer of
    thousands of digits by its size, :func:`rotoprint.ranges.show_value`)."""
    return repr(v) if isinstance(v, float) else R.show_value(v)


def _check_swathe(spec: MachineSpec, head: dict, sw: dict, step: dict, where: str, p: Path) -> None:
    """A stage position and a clock the machine can make, else one line naming ``where``."""
    lo, hi = spec.radial_stage_mm
    pos = step["radial_stage_mm"]
    if not (_finite(pos) and lo <= pos <= hi):
        raise InputFileError(f"{where}: radial stage position {_shown(pos)} mm is outside the machine's stage [{lo:g}, {hi:g}] mm", path=p)
    f = step["frequency_hz"]
    fmax = min(head["_model"].max_frequency_hz, spec.head_frequency_hz or math.inf)
    if not (_finite(f) and 0 < f <= fmax):
        raise InputFileError(f"{where}: firing clock {_shown(f)} Hz is beyond what the head can reach ({fmax:g} Hz)", path=p)
    m, d = step["multiplier"], step["divider"]
    if not (isinstance(m, int) and isinstance(d, int) and 1 <= m <= spec.clock_max_multiplier and 1 <= d <= spec.clock_max_divider):
        raise InputFileError(f"{where}: encoder ratio x{_shown(m)}/{_shown(d)} is beyond the controller's limits "
                             f"(multiplier <= {spec.clock_max_multiplier}, divider <= {spec.clock_max_divider})", path=p)
    dphi = sw["dphi_rad"]
    want = 2 * math.pi / dphi
    got = spec.encoder_counts_per_rev * m / d
    if abs(got / want - 1) > 0.01:
        raise InputFileError(f"{where}: encoder ratio x{m}/{d} makes {got:.6g} firings per revolution, the image needs "
                             f"{want:.6g}: the clock cannot be reached", path=p)
    rpm = 60.0 * f / got
    if rpm > spec.max_platform_rpm:
        raise InputFileError(f"{where}: {f:g} Hz needs the platform at {rpm:.2f} rpm, above the machine's "
                             f"{spec.max_platform_rpm:g} rpm", path=p)


def machine_clock(counts_per_rev: int, multiplier: int, divider: int, index_offset_counts: int, first_firing: int,
                  mount_turn_rad: float = 0.0) -> FiringClock:
    """The angles an image's firings fire at on the machine.

    The controller fires the image's first firing ``index_offset_counts`` encoder counts after
    the index pulse and every ``divider / multiplier`` counts after that: firing ``i`` at
    ``2 pi (index_offset_counts + (i - first_firing) * divider / multiplier) / counts_per_rev``.

    ``mount_turn_rad``: for a print made for a mount turned from the head's by ``delta`` (an
    interlaced pass's angular phase), ``direction * delta``. The program folds that turn into
    the index offset (the head's data delayed by it); the print keeps its own mount angle, so
    the turn is added back here and the phase is counted once.

    Examples
    --------
    >>> c = machine_clock(4000, 1, 4, 8, 2)  # 1000 firings per revolution, exact
    >>> float(c.turn_rad(np.array([3]))[0]) == 2 * math.pi * 12 / 4000
    True
    """
    step = 2 * math.pi / counts_per_rev
    return FiringClock(ref_firing=int(first_firing), turn_at_ref_rad=index_offset_counts * step + mount_turn_rad,
                       dphi_rad=step * divider / multiplier)


#: A machine angle within this of the nominal one over a whole image (rad; a picometre at
#: 100 mm) is float rounding of an exact clock: the drops stay on their nominal sites.
EXACT_RAD = 1e-12


def clock_is_exact(clock: FiringClock, sw: SwatheImage) -> bool:
    """Whether ``clock`` fires every firing of ``sw`` at its nominal angle ``i * dphi_rad``
    (within :data:`EXACT_RAD`, modulo a turn): an exact ratio and a whole index offset."""
    f = sw.levels.shape[0]
    lo, hi = sw.first_firing, sw.first_firing + max(f - 1, 0)
    worst = 0.0
    for i in (lo, hi):
        d = float(clock.turn_rad(np.array([i]))[0]) - i * sw.dphi_rad
        worst = max(worst, abs(math.remainder(d, 2 * math.pi)))
    return worst < EXACT_RAD


@dataclass(frozen=True, eq=False)
class ReplayImage:
    """One head's image of one material in one layer, decoded: the print and the design.

    ``clocks``: per swathe index, the machine's firing angles (:func:`machine_clock`);
    ``files``: per swathe index, the packed file; ``steps``: the numbers of the revolution
    steps that print it.
    """

    layer: int
    material: str
    ink: str
    head: str
    print: RotaryPrint
    design: np.ndarray  # (H, W) uint8, 0 / 255
    clocks: dict
    files: dict
    steps: dict
    interlace: int = 0


def _check_image_counts(rec: dict, counts_per_rev: int, where: str, p: Path) -> None:
    """An image record's index offset (a whole count within one revolution) and first firing
    (a whole number in the sidecar range), or one line naming the image."""
    off, first = rec.get("index_offset_counts"), rec.get("first_firing_index")
    if isinstance(off, bool) or not isinstance(off, int) or not 0 <= off < counts_per_rev:
        raise InputFileError(f"{where}: index_offset_counts must be a whole count in 0..{counts_per_rev - 1}, "
                             f"got {str(off)[:40]!r}", path=p)
    if isinstance(first, bool) or not isinstance(first, int) or not -R.MAX_COUNT <= first <= R.MAX_COUNT:
        raise InputFileError(f"{where}: first_firing_index must be a whole number within +-{R.MAX_COUNT:g}, "
                             f"got {str(first)[:40]!r}", path=p)


def _check_image_record(rec: dict, head: dict, where: str, p: Path) -> None:
    """An image record's setting and swathe numbers, checked as a sidecar's are
    (:func:`rotoprint.rotary.files.check_print_fields`), its swathe one of its head's, its
    interlaced pass a whole number and its row offsets those of its swathe; one line naming
    the image and the field."""
    model: InkjetHead = head["_model"]
    sw = rec["swathe"]
    if isinstance(sw, bool) or not isinstance(sw, int) or not 0 <= sw < len(head["swathes"]):
        raise InputFileError(f"{where}: field swathe must be one of head {head['name']}'s swathes "
                             f"0..{len(head['swathes']) - 1}, got {R.show_value(sw)}", path=p)
    q = rec.get("interlace", 0)
    if isinstance(q, bool) or not isinstance(q, int) or not 0 <= q < R.PASSES.hi:
        raise InputFileError(f"{where}: field interlace must be a pass number 0..{R.PASSES.hi - 1:g}, got {R.show_value(q)}",
                             path=p)
    check_print_fields({**rec, "swathes": [{**rec, "index": sw}]}, model, p, what=f"{where}: field", flat=True)
    offs = rec.get("row_offsets_firings")
    if offs != head["swathes"][sw].get("row_offsets_firings"):
        raise InputFileError(f"{where}: field row_offsets_firings {R.show_value(offs)} is not its swathe's "
                             f"{R.show_value(head['swathes'][sw].get('row_offsets_firings'))}", path=p)


class _Files:
    """Packed files read and checked once each."""

    def __init__(self, root: Path, program: Path) -> None:
        self.root = root
        self.program = program

    def read(self, rel: str, sha: str, where: str) -> bytes:
        f = self.root / rel
        if not (f.resolve().is_relative_to(self.root.resolve())):
            raise InputFileError(f"{where}: file {rel!r} is outside the machine folder", path=self.program)
        data = _read_bounded(f, MAX_IMAGE_BYTES, "file", where, self.program)
        if hashlib.sha256(data).hexdigest() != sha:
            raise InputFileError(f"{where}: file {rel} was altered (its SHA-256 differs from the program's)", path=self.program)
        return data


def _layer_images(lay: dict, prog: dict, p: Path, files: _Files, want: set[int] | None) -> list[ReplayImage] | None:
    """Check one layer's steps; decode its images if ``want`` has it (else None). KeyError,
    TypeError, ValueError or IndexError on a malformed record (the caller names the layer)."""
    spec: MachineSpec = prog["_spec"]
    heads = {h["name"]: h for h in prog["heads"]}
    pk = prog["packing"]
    bits = pk["bits_per_nozzle"]
    nn = pk["nozzle_order"]
    i = lay["index"]
    recs = {}
    for r in lay["images"]:
        recs[r["file"]] = r
    printed_by: dict[str, list[int]] = {}
    for st in lay["steps"]:
        where = f"layer {i} step {st['n']} ({st['kind']}" + (f" of {st['head']} swathe {st['swathe']})" if st["kind"] == "revolution" else ")")
        t = st.get("time_s")
        if not (_finite(t) and t >= 0):
            raise InputFileError(f"{where}: time_s {_shown(t)} is not a duration", path=p)
        if st["kind"] != "revolution":
            continue
        h = heads.get(st["head"])
        if h is None or not 0 <= st["swathe"] < len(h["swathes"]):
            raise InputFileError(f"{where}: no such head or swathe in the program's heads", path=p)
        _check_swathe(spec, h, h["swathes"][st["swathe"]], st, where, p)
        if st["image"] is not None and st["image"] not in recs:
            raise InputFileError(f"{where}: image {st['image']} is not listed in layer {i}'s images", path=p)
        if st["image"] is not None:
            c = h["swathes"][st["swathe"]]["clock"]
            r = recs[st["image"]]
            if (st["multiplier"], st["divider"], st["index_offset_counts"]) != (c["multiplier"], c["divider"],
                                                                                  r["index_offset_counts"]):
                raise InputFileError(f"{where}: clock x{st['multiplier']}/{st['divider']} index {st['index_offset_counts']} "
                                     f"is not the one of its swathe and image (x{c['multiplier']}/{c['divider']} index "
                                     f"{r['index_offset_counts']})", path=p)
            printed_by.setdefault(st["image"], []).append(st["n"])
    if want is not None and i not in want:
        return None
    for r in lay["images"]:
        if r["head"] not in heads:
            raise InputFileError(f"layer {i} image {r['file']}: no head {R.show_value(r['head'])} in the program's heads", path=p)
        _check_image_counts(r, spec.encoder_counts_per_rev, f"layer {i} image {r['file']}", p)
        _check_image_record(r, heads[r["head"]], f"layer {i} image {r['file']}", p)
    designs = {}
    for d in lay["designs"]:
        where = f"layer {i} design of {d['material']}"
        data = files.read(d["file"], d["sha256"], where)
        try:
            w = read_packed(data, d["height_px"], d["width_px"], 1)
            designs[d["material"]] = unpack_levels(w, 1, np.arange(d["width_px"])) * np.uint8(255)
        except RotoprintError as exc:
            raise InputFileError(f"{where}: {exc.problem}", path=p) from None
    groups: dict[tuple[str, str, int], list[dict]] = {}
    for r in lay["images"]:  # one print per interlaced pass
        groups.setdefault((r["material"], r["ink"], int(r.get("interlace", 0))), []).append(r)
    out = []
    for (mname, ink, q), rs in groups.items():
        h = heads[rs[0]["head"]]
        model: InkjetHead = h["_model"]
        order = nozzle_order(model.nozzles, model.rows, odd_row=nn["odd_row"], descending=nn["direction"] == "descending")
        rows_of = np.arange(model.nozzles) % model.rows
        sws = []
        clocks, files_of, steps = {}, {}, {}
        for r in sorted(rs, key=lambda r: r["swathe"]):
            where = f"layer {i} image {r['file']}"
            c = h["swathes"][r["swathe"]]["clock"]
            # a phased pass's mount turn is in its index offset and in its mount angle: once
            turn = int(r["direction"]) * math.radians(float(r["mount_angle_deg"]) - float(h["mount_angle_deg"]))
            clocks[r["swathe"]] = machine_clock(spec.encoder_counts_per_rev, c["multiplier"], c["divider"],
                                                r["index_offset_counts"], r["first_firing_index"], turn)
            steps[r["swathe"]] = printed_by.get(r["file"], [])
            files_of[r["swathe"]] = r["file"]
            words = words_per_row(r["nozzles"], bits)
            if r.get("words_per_row") != words:  # what a machine reading the program takes as the row length
                raise InputFileError(f"{where}: field words_per_row must be {words} ({r['nozzles']} nozzles of {bits} "
                                     f"bit(s) in 32-bit words), got {R.show_value(r.get('words_per_row'))}", path=p)
            data = files.read(r["file"], r["sha256"], where)
            try:
                lv = unpack_levels(read_packed(data, r["firings"], r["nozzles"], bits), bits, order)
            except RotoprintError as exc:
                raise InputFileError(f"{where}: {exc.problem}", path=p) from None
            first = r["first_firing_index"]
            if r.get("row_offsets_firings"):
                lv, dfirst = unshift_rows(lv, rows_of, r["row_offsets_firings"])
                first += dfirst
            runs = r.get("enabled_nozzle_runs")
            sws.append(SwatheImage(index=r["swathe"], levels=lv, pivot_radius_mm=float(r["pivot_radius_mm"]),
                                   first_firing=int(first), dphi_rad=float(r["dphi_rad"]),
                                   ref_radius_mm=float(r["ref_radius_mm"]),
                                   band_mm=(float(r["band_mm"][0]), float(r["band_mm"][1])),
                                   enabled_nozzles=int(r["enabled_nozzles"]),
                                   enabled=None if runs is None else runs_to_mask(runs, model.nozzles)))
        r0 = rs[0]
        where = f"layer {i} image {r0['file']}"
        if not isinstance(r0["placement"], dict):
            raise InputFileError(f"{where}: field placement must be a table, got {R.show_value(r0['placement'])}", path=p)
        try:
            placement = Placement.from_json(r0["placement"])
        except RotoprintError as exc:
            raise InputFileError(f"{where}: field placement: {exc.problem}", path=p) from None
        pr = RotaryPrint(method=r0["method"], head=model, tilt_deg=float(r0["tilt_deg"]),
                         mount_angle_deg=float(r0["mount_angle_deg"]), direction=int(r0["direction"]),
                         dpi_y=float(r0["dpi_y"]), placement=placement, swathes=tuple(sws))
        if mname not in designs:
            raise InputFileError(f"layer {i}: no design region of {mname} for its images", path=p)
        if designs[mname].shape != (placement.height_px, placement.width_px):
            dh, dw = designs[mname].shape
            raise InputFileError(f"{where}: field placement is {placement.width_px} x {placement.height_px} px, "
                                 f"the layer's design of {mname} {dw} x {dh} px", path=p)
        out.append(ReplayImage(layer=i, material=mname, ink=ink, head=h["name"], print=pr, design=designs[mname],
                               clocks=clocks, files=files_of, steps=steps, interlace=q))
    return out


def replay_layers(prog: dict, program_path: str | Path, *, layers: list[int] | None = None) -> Iterator[tuple[dict, list[ReplayImage]]]:
    """Check every step of the chosen layers and decode their images, layer by layer.

    Parameters
    ----------
    prog : dict
        From :func:`load_program`.
    program_path : str or Path
    layers : list of int, optional
        Layer indices to decode (default all); the steps of every layer are checked.

    Yields
    ------
    layer : dict
        The program's layer record.
    images : list of ReplayImage
        One per (material, ink) of the layer, swathes together.
    """
    p = Path(program_path)
    prog = as_record(prog)
    root = p.parent
    files = _Files(root, p)
    want = None if layers is None else set(layers)
    for lay in prog["layers"]:
        try:
            out = _layer_images(lay, prog, p, files, want)
        except MissingKeyError as exc:
            raise InputFileError(missing_key_message(exc), path=p) from None
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            if isinstance(exc, RotoprintError):
                raise
            where = f"layer {R.show_value(lay.get('index'))}" if isinstance(lay, dict) else "a layer"
            if type(exc) is KeyError:  # a record copied out of the program (no path kept)
                raise InputFileError(f"{where}: a record has no key {exc}: the program is incomplete", path=p) from None
            raise InputFileError(f"{where}: a program record holds a value of the wrong type or size "
                                 f"({type(exc).__name__}: {str(exc)[:80]})", path=p) from None
        if out is not None:
            yield lay, out


def replay_program(path: str | Path, *, layer: int | None = None, on_step: Callable[[str, int, int], None] | None = None,
                   keep_layer: int | None = None, overlay_scale: int | None = None, deposit: bool = False,
                   angles: str = "machine") -> dict:
    """Replay a program: the simulator's figures for every image of every (or one) layer.

    Parameters
    ----------
    path : str or Path
        ``machine/program.json``.
    layer : int, optional
        Only this layer (its steps and every other layer's steps are still checked).
    on_step : callable, optional
        ``on_step("replay", done, total)``.
    keep_layer : int, optional
        Keep the :class:`~rotoprint.rotary.simulate.Simulation` objects of this layer (for
        the overlay), under ``"_sims"``.
    overlay_scale : int, optional
        The overlay's scale, checked against memory before anything is simulated.
    deposit : bool
        Also run the deposit model (:func:`rotoprint.rotary.deposit.deposit_film`, the film
        figures a build gives for its overlays) on every image: ``deposit`` per image, without
        the radial bins. About a second per image.
    angles : {'machine', 'nominal'}
        Place the firings at the machine clock's angles (:func:`machine_clock`) or at the
        nominal ``i * dphi_rad``.

    Returns
    -------
    dict
        ``images``: per image ``layer, material, ink, head, swathes``, the keys of
        ``simulate``'s report (``iou``, ``uncovered_fraction``, ``drops``, ...),
        ``max_drop_displacement_um`` (the largest distance of a drop from its nominal site)
        and ``swathe_clocks`` (per swathe: ``swathe, image, steps`` (the revolution steps
        printing it), ``max_drop_displacement_um``); ``iou`` the lowest and
        ``uncovered_fraction`` the highest over them; ``drops`` and ``drops_outside`` summed;
        ``time_s``, ``steps``, the program's totals; ``clock``: the largest angle error per
        revolution, the flagged swathes, ``angles`` and the largest drop displacement.
    """
    if angles not in ANGLES:
        raise ConfigError(f"angles must be one of {', '.join(ANGLES)}, got {angles!r}")
    p = Path(path)
    prog = load_program(p)
    try:
        return _replay(prog, p, layer, on_step, keep_layer, overlay_scale, deposit, angles)
    except MissingKeyError as exc:
        raise InputFileError(missing_key_message(exc), path=p) from None


def _replay(prog: dict, p: Path, layer, on_step, keep_layer, overlay_scale, deposit: bool, angles: str) -> dict:
    """:func:`replay_program` of the loaded ``prog``."""
    from ..rotary.simulate import check_overlay_fits, place_drops, simulate

    if overlay_scale is not None:
        try:
            g = prog["design_grid"]
            shape = (int(g["height_px"]), int(g["width_px"]))
        except (KeyError, TypeError, ValueError):
            raise InputFileError("program has no valid design_grid", path=p) from None
        check_overlay_fits(shape, overlay_scale)
    nl = len(prog["layers"])
    if layer is not None and not 0 <= layer < nl:
        raise InputFileError(f"--layer {layer}: the program has layers 0..{nl - 1}", path=p)
    step = on_step or (lambda *a: None)
    results = []
    sims = []
    for k, (lay, imgs) in enumerate(replay_layers(prog, p, layers=None if layer is None else [layer])):
        step("replay", k, nl)
        for im in imgs:
            clocks = None
            if angles == "machine":  # exact clocks leave their swathes' drops on the nominal sites, bit for bit
                clocks = {sw.index: im.clocks[sw.index] for sw in im.print.swathes
                          if not clock_is_exact(im.clocks[sw.index], sw)} or None
            sim = simulate(im.print, im.design, clocks=clocks)
            nominal = place_drops(im.print) if clocks else sim.drops
            moved_um = 1e3 * np.hypot(sim.drops.x_mm - nominal.x_mm, sim.drops.y_mm - nominal.y_mm)
            per_sw = []
            for sw in im.print.swathes:
                sel = sim.drops.swathe == sw.index
                per_sw.append({"swathe": sw.index, "image": im.files[sw.index], "steps": im.steps[sw.index],
                               "max_drop_displacement_um": float(moved_um[sel].max()) if sel.any() else 0.0})
            if keep_layer is not None and im.layer == keep_layer:
                sims.append((im, sim))
            r = {"layer": im.layer, "material": im.material, "ink": im.ink, "head": im.head, "interlace": im.interlace,
                 "method": im.print.method, "tilt_deg": im.print.tilt_deg, "swathes": len(im.print.swathes),
                 **sim.report.to_json(),
                 "max_drop_displacement_um": max(s_["max_drop_displacement_um"] for s_ in per_sw), "swathe_clocks": per_sw}
            if deposit:
                from ..rotary.deposit import deposit_film, ink_drops

                film = deposit_film(sim.inked, im.print.placement, im.print.head, [ink_drops(sim.drops, im.print.head)])
                r["deposit"] = {k: v for k, v in film.films[0].to_json().items() if k != "radial_bins"}
            results.append(r)
    step("replay", nl, nl)
    tot = prog["totals"]
    errs = [s["clock"]["angle_error_per_rev_deg"] for h in prog["heads"] for s in h["swathes"]]
    out = {
        "program": str(p), "layers": nl, "replayed_layers": sorted({r["layer"] for r in results}) if layer is None else [layer],
        "images": results,
        "iou": min((r["iou"] for r in results), default=float("nan")),
        "uncovered_fraction": max((r["uncovered_fraction"] for r in results), default=float("nan")),
        "drops": sum(r["drops"] for r in results),
        "drops_outside": sum(r["drops_outside"] for r in results),
        "time_s": tot["time_s"], "steps": tot["steps"], "revolutions": tot["revolutions"],
        "clock": {"max_angle_error_per_rev_deg": max(errs, default=0.0), "flagged": tot["flagged_clocks"], "angles": angles,
                  "max_drop_displacement_um": max((r["max_drop_displacement_um"] for r in results), default=0.0)},
    }
    if keep_layer is not None:
        out["_sims"] = sims
    return out
