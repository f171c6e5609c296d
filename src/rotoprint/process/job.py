"""The job file: one TOML file describes a multi-material print (see ``docs/build.md``).

::

    [job]
    name = "coil sensor"
    layer_height_mm = 0.02

    [printer]
    device = "omnidot760"      # preset or device .toml (relative: from the job file's folder)
    tilt_deg = 20.0
    equalise = true            # the same volume per area at every radius (with passes: over their union)
    passes = "auto"            # interlaced passes per layer (1..64 or "auto", the default)
    [printer.clock]
    dpi_y = 360.0              # drops per inch along the track at the reference radius
    [[printer.heads]]
    name = "H1"
    ink = "ammonium_sulphate"
    mount_angle_deg = 0.0

    [placement]
    inner_radius_mm = 60.0
    angle_deg = 0.0

    [[parts]]
    name = "body"
    material = "plaster"
    priority = 1
    mesh = "body.stl"          # or: shape = { kind = "box", size_mm = [20, 20, 0.2] }
                               # or: layer = { file = "coil-F_Cu.gbr", z_mm = [0.2, 0.24] } (docs/cad.md)

    [[resistance]]
    part = "coil"
    between = ["outer", "inner"]

Validation errors are one line in words naming the field (``job.layer_height_mm must be a number,
got 'thin'``, ``parts[1].material: unknown material 'silvr' ...``) and the file, and are
:class:`~rotoprint.errors.ConfigError` (exit code 2 on the command line).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .. import ranges as R
from ..errors import ConfigError, InputFileError
from ..machine.spec import MachineSpec
from .materials import Material, MaterialLibrary, builtin_library, load_materials, validation_message
from .cadparts import LayerFile
from .shapes import Shape

__all__ = ["JobSpec", "JobInfo", "PrinterSpec", "HeadSpec", "ClockSpec", "PlacementSpec", "PartSpec", "ResistanceSpec",
           "ProcessSpec", "load_job", "parse_job", "ResolvedJob"]


class _Strict(BaseModel):
    # allow_inf_nan=False: a NaN or infinite number is refused by the field that holds it
    # ("placement.inner_radius_mm must be a finite number, got inf"), not later by whatever uses it.
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


# The range of the angular clock (drops per inch along the track at the reference radius): from a
# drop every 1.016 mm (coarser than any drop can bridge) to one every 0.254 um.
DPI_Y_RANGE = (25.0, 100_000.0)
FREQUENCY_HZ_MAX = 1_000_000.0


_Angle = Annotated[float, R.field(R.ANGLE_DEG)]
_Coord = Annotated[float, R.field(R.COORD_MM)]
_PRIORITY = R.Range(-1_000_000, 1_000_000, integer=True)
_CYCLES = R.Range(1, 10_000, integer=True)  # cycles (passes) per layer


class JobInfo(_Strict):
    name: str = "job"
    layer_height_mm: float = Field(ge=R.LAYER_HEIGHT_MM.lo, le=10)
    materials_file: str | None = None
    description: str = ""


class ClockSpec(_Strict):
    """The angular clock: ``dpi_y`` drops per inch along the track at the reference radius
    (default: each swathe's outermost track), fired at most at ``frequency_hz`` (default: the
    head's maximum)."""

    dpi_y: float | None = None
    ref_radius_mm: float | None = Field(default=None, gt=0, le=10_000)
    frequency_hz: float | None = Field(default=None, gt=0, le=FREQUENCY_HZ_MAX)

    @field_validator("dpi_y")
    @classmethod
    def _dpi_range(cls, v: float | None) -> float | None:
        lo, hi = DPI_Y_RANGE
        if v is not None and not lo <= v <= hi:
            raise ValueError(f"must be {lo:g} to {hi:g} drops per inch (a drop pitch along the track of "
                             f"{25.4 / lo:g} mm to {25.4e3 / hi:g} um)")
        return v


class HeadSpec(_Strict):
    """One head on the machine, carrying one ink."""

    name: str = Field(min_length=1)
    ink: str = Field(min_length=1)
    mount_angle_deg: Annotated[float, R.field(R.ANGLE_DEG)] = 0.0
    tilt_deg: Annotated[float, R.field(R.TILT_DEG)] | None = None

    @field_validator("mount_angle_deg")
    @classmethod
    def _finite(cls, v: float) -> float:
        if not math.isfinite(v):
            raise ValueError("must be a finite number of degrees")
        return v


class PrinterSpec(_Strict):
    """The printer. ``passes``: interlaced passes per layer (docs/build.md): each layer's
    cycles of a material are printed in turn at the pass plan's radial offsets
    (:func:`rotoprint.rotary.interlace.plan_passes`); ``"auto"`` (the default) lets the planner
    choose up to :data:`~rotoprint.rotary.interlace.MAX_PASSES` so that the drops' footprints
    close the film, and then the clock follows from the plan unless ``clock.dpi_y`` is set;
    ``1`` prints every cycle at the planned pivots with the job's clock (no interlace).
    ``equalise`` (default true): with more than one pass every track keeps its share of the
    union-equalised film (:func:`rotoprint.rotary.direct.union_pass_shares`, the clock made
    2 x the plan's); with one pass the tracks are thinned to the lowest drops per mm^2; false:
    every drop. ``edge_restore`` (default false; with ``equalise`` on a binary head): of the
    drops the equalisation thins out, those inside a material's region within 50 um of an edge
    met along the platform radius come back at 1.3 x the track's share
    (:class:`rotoprint.rotary.edgecomp.EdgeRestore`, as ``transform --passes`` does), so the
    levelled film's 1 mm bins beside the edges keep their ink. Opt-in: on the coil demo it did
    not even the levelled bins (silver layer 8 1.17 -> 3.21 %, ``docs/benchmarks.md``)."""

    device: str = "omnidot760"
    tilt_deg: Annotated[float, R.field(R.TILT_DEG)] = 0.0
    direction: int = 1
    equalise: bool = True
    edge_restore: bool = False
    passes: int | Literal["auto"] = "auto"
    max_swathes: Annotated[int, R.field(R.SWATHES)] | None = None
    clock: ClockSpec = ClockSpec()
    heads: tuple[HeadSpec, ...] = Field(min_length=1)

    @field_validator("passes", mode="before")
    @classmethod
    def _passes(cls, v):
        if v == "auto" and isinstance(v, str):
            return v
        if isinstance(v, bool) or not isinstance(v, int) or v not in R.PASSES:
            raise ValueError(f"must be a whole number {R.PASSES.lo}..{R.PASSES.hi} or 'auto'")
        return v

    @field_validator("direction")
    @classmethod
    def _dir(cls, v: int) -> int:
        if v not in (1, -1):
            raise ValueError("must be 1 (counter-clockwise) or -1 (clockwise)")
        return v

    @model_validator(mode="after")
    def _unique(self) -> PrinterSpec:
        for attr in ("name", "ink"):
            vals = [getattr(h, attr) for h in self.heads]
            dup = sorted({v for v in vals if vals.count(v) > 1})
            if dup:
                raise ValueError(f"two heads have the {attr} {dup[0]!r}; each head carries one ink and each ink one head")
        return self


class PlacementSpec(_Strict):
    """Where the assembly's footprint sits: its inner edge (smallest model X) at
    ``inner_radius_mm`` on the centre line at ``angle_deg`` (see ``docs/rotary.md``)."""

    inner_radius_mm: Annotated[float, R.field(R.RADIUS_MM)]
    angle_deg: Annotated[float, R.field(R.ANGLE_DEG)] = 0.0


class PartSpec(_Strict):
    """A part: a mesh file, a built-in shape or a CAD layer (:mod:`.cadparts`), of one material.

    Where parts of different materials overlap, the pixel (drop) belongs to the part with the
    highest ``priority``. ``cycles_per_layer`` overrides the planner's number of cycles."""

    name: str = Field(min_length=1)
    material: str = Field(min_length=1)
    priority: Annotated[int, R.field(_PRIORITY)] = 0
    mesh: str | None = None
    shape: Shape | None = None
    layer: LayerFile | None = None  # a Gerber/Excellon/DXF/SVG region between two heights (cadparts)
    units: str = "mm"
    rotate_deg: tuple[_Angle, _Angle, _Angle] = (0.0, 0.0, 0.0)
    translate_mm: tuple[_Coord, _Coord, _Coord] = (0.0, 0.0, 0.0)
    terminals: dict[str, tuple[_Coord, _Coord, _Coord, _Coord]] = Field(default_factory=dict, max_length=10_000)

    @model_validator(mode="after")
    def _one_source(self) -> PartSpec:
        if sum(v is not None for v in (self.mesh, self.shape, self.layer)) != 1:
            raise ValueError("give exactly one of 'mesh' (a file), 'shape' (a built-in shape) or 'layer' "
                             "(a Gerber, Excellon, DXF or SVG layer)")
        if self.layer is not None and "units" in self.model_fields_set:
            raise ValueError("a layer part takes its units inside layer = { ..., units = ... }")
        for k, (x0, y0, x1, y1) in self.terminals.items():
            if not (x1 > x0 and y1 > y0):
                raise ValueError(f"terminal {k!r} must be [x0, y0, x1, y1] with x1 > x0 and y1 > y0")
        return self


class ResistanceSpec(_Strict):
    part: str
    between: tuple[str, str]


class ProcessSpec(_Strict):
    """Planner settings: material order in a layer, the most passes per layer before a
    warning, and per-material overrides of the cycles per layer."""

    order: tuple[str, ...] | None = None
    max_passes_per_layer: int = Field(default=200, ge=1, le=_CYCLES.hi)
    cycles_per_layer: dict[str, Annotated[int, R.field(_CYCLES)]] = Field(default_factory=dict)
    check: bool = True
    simulate_layers: int = Field(default=4, ge=0, le=1000)

    @field_validator("cycles_per_layer")
    @classmethod
    def _pos(cls, v: dict[str, int]) -> dict[str, int]:
        bad = {k: n for k, n in v.items() if n < 1}
        if bad:
            raise ValueError(f"cycles must be >= 1, got {bad}")
        return v


class JobSpec(_Strict):
    job: JobInfo
    printer: PrinterSpec
    placement: PlacementSpec
    parts: tuple[PartSpec, ...] = Field(min_length=1)
    resistance: tuple[ResistanceSpec, ...] = ()
    process: ProcessSpec = ProcessSpec()
    materials: dict[str, dict] = Field(default_factory=dict)
    machine: MachineSpec = MachineSpec()  # the [machine] section: encoder, radial stage, speeds (docs/machine.md)

    @model_validator(mode="after")
    def _names(self) -> JobSpec:
        names = [p.name for p in self.parts]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"two parts are named {dup[0]!r}")
        return self


class ResolvedJob:
    """A validated job with its materials resolved and paths made absolute.

    Attributes
    ----------
    spec : JobSpec
    materials : dict[str, Material]
        The materials the parts use, in print order within a layer.
    base_dir : Path
        Folder of the job file (mesh paths are relative to it).
    """

    def __init__(self, spec: JobSpec, library: MaterialLibrary, base_dir: Path, source: str | None) -> None:
        self.spec = spec
        self.library = library
        self.base_dir = base_dir
        self.source = source
        used = []
        for p in spec.parts:
            if p.material not in used:
                used.append(p.material)
        order = list(spec.process.order) if spec.process.order is not None else used
        self.material_order: list[str] = order
        self.materials: dict[str, Material] = {n: library[n] for n in order}

    def part(self, name: str) -> PartSpec:
        for p in self.spec.parts:
            if p.name == name:
                return p
        raise ConfigError(f"no part named {name!r}", path=self.source)

    def resolve(self, path: str | Path) -> Path:
        """A path named in the job: relative paths are taken from the job file's folder."""
        p = Path(path)
        return p if p.is_absolute() else self.base_dir / p

    def device_spec(self) -> str:
        """``printer.device`` for :func:`~rotoprint.devices.load_device`: a preset name as it
        is, a device file resolved against the job file's folder (like meshes)."""
        from ..devices import preset_names

        dev = self.spec.printer.device
        if dev in preset_names() or (Path(dev).suffix.lower() != ".toml" and "/" not in dev):
            return dev  # a preset, or an unknown name load_device explains
        return str(self.resolve(dev))


def _check_refs(spec: JobSpec, lib: MaterialLibrary, src: str | None) -> None:
    def err(msg: str):
        raise ConfigError(msg, path=src)

    for i, p in enumerate(spec.parts):
        if p.material not in lib:
            err(f"parts[{i}].material: unknown material {p.material!r}; known: {', '.join(lib.names())}")
    used = {p.material for p in spec.parts}
    if spec.process.order is not None:
        order = list(spec.process.order)
        for j, m in enumerate(order):
            if m not in used:
                err(f"process.order[{j}]: {m!r} is not the material of any part")
        missing = sorted(used - set(order))
        if missing:
            err(f"process.order: the material {missing[0]!r} of a part is missing from the order")
        if len(set(order)) != len(order):
            err("process.order: a material is listed twice")
    for m in spec.process.cycles_per_layer:
        if m not in used:
            err(f"process.cycles_per_layer.{m}: not the material of any part")
    inks = {h.ink: j for j, h in enumerate(spec.printer.heads)}
    for m in sorted(used):
        for ink in lib[m].inks:
            if ink.name not in inks:
                err(f"printer.heads: no head carries the ink {ink.name!r} that material {m!r} needs "
                    f"(inks: {', '.join(i.name for i in lib[m].inks)})")
    # parts of different materials with the same priority could overlap ambiguously
    seen: dict[int, str] = {}
    for i, p in enumerate(spec.parts):
        other = seen.get(p.priority)
        if other is not None and other != p.material:
            err(f"parts[{i}].priority: {p.priority} is also the priority of a {other!r} part; parts of different "
                "materials need different priorities (the higher one wins where they overlap)")
        seen[p.priority] = p.material
    names = {p.name: p for p in spec.parts}
    for i, r in enumerate(spec.resistance):
        if r.part not in names:
            err(f"resistance[{i}].part: no part named {r.part!r}")
        p = names[r.part]
        if not lib[p.material].conductive:
            err(f"resistance[{i}].part: {r.part!r} is {p.material}, which has no conductivity")
        avail = dict(p.terminals)
        if p.shape is not None:
            avail = {**p.shape.terminals(), **avail}
        for t in r.between:
            if p.layer is not None:
                break  # a layer's pads are named in its file: checked when the plan reads it
            if t not in avail:
                err(f"resistance[{i}].between: part {r.part!r} has no terminal {t!r}; it has: {', '.join(sorted(avail)) or 'none'}")
        if r.between[0] == r.between[1]:
            err(f"resistance[{i}].between: the two terminals must differ")


def parse_job(data: dict, *, base_dir: str | Path = ".", source: str | None = None) -> ResolvedJob:
    """Validate a job given as a dict (the parsed TOML).

    Parameters
    ----------
    data : dict
        The job's tables, as :func:`tomllib.loads` gives them.
    base_dir : str or Path
        Folder that relative paths (``materials_file``, mesh files) are resolved against.
    source : str, optional
        Name of the job file, for error messages.

    Returns
    -------
    ResolvedJob
        With its materials taken from the built-ins, then ``materials_file``, then the job's
        own ``[materials]`` tables (later ones override earlier ones).

    Raises
    ------
    ConfigError
        A field is missing or invalid, a reference (material, part, ink, terminal) does not
        resolve, or ``materials_file`` is not valid TOML or holds an invalid material; the
        message names the field.
    InputFileError
        ``materials_file`` is missing or is not a file.
    """
    try:
        spec = JobSpec.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(validation_message(exc), path=source) from None
    base = Path(base_dir)
    lib = builtin_library()
    if spec.job.materials_file:
        mp = Path(spec.job.materials_file)
        lib = load_materials(mp if mp.is_absolute() else base / mp, base=lib)
    if spec.materials:
        lib = load_materials(spec.materials, base=lib)
    _check_refs(spec, lib, source)
    return ResolvedJob(spec, lib, base, source)


def load_job(path: str | Path) -> ResolvedJob:
    """Read and validate a job file.

    Parameters
    ----------
    path : str or Path
        A UTF-8 TOML job file; relative paths in it are resolved against its folder.

    Returns
    -------
    ResolvedJob
        See :func:`parse_job`.

    Raises
    ------
    InputFileError
        Missing or unreadable file.
    ConfigError
        Not TOML, or a field is missing or invalid (the message names the field).
    """
    p = Path(path)
    if not p.exists():
        raise InputFileError("no such job file", path=p)
    if p.is_dir():
        raise InputFileError("is a directory, expected a job .toml file", path=p)
    from ..io.inputs import MAX_TOML_BYTES, parse_toml, read_input_text

    text = read_input_text(p, what="job file", limit_bytes=MAX_TOML_BYTES, error=ConfigError)
    data = parse_toml(text, p, what="job file", error=ConfigError)
    return parse_job(data, base_dir=p.resolve().parent, source=str(p))
