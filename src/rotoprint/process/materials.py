"""Materials made on the substrate from one or more inks, and the library of them.

A :class:`Material` is a solid formed on the substrate by inks printed in order (each ink
``repeats`` times per cycle), followed by post-steps (flash heating, cure). The paper's four
systems are built in (:data:`BUILTIN_MATERIALS`); users add or override materials in TOML with
the same fields (see ``docs/build.md``)::

    [materials.silver_hi]
    description = "silver from 2 M nitrate"
    product = { name = "silver", molar_mass_g_per_mol = 107.87, density_g_per_cm3 = 10.49 }
    conductivity_s_per_m = 1.42e5
    [[materials.silver_hi.inks]]
    name = "silver_nitrate_2M"
    concentration_mol_per_l = 2.0

Numbers that are not in the paper are marked ``nominal`` (typical values from the chemistry
of the system); measure your own and override them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Literal

from .. import ranges as R
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from ..errors import ConfigError, InputFileError
from ..io.records import field_problem

__all__ = [
    "Ink",
    "InkStep",
    "PostStep",
    "Product",
    "Material",
    "MaterialLibrary",
    "BUILTIN_MATERIALS",
    "builtin_library",
    "load_materials",
    "validation_message",
]


_DAY_S = 86_400.0  # waits and post steps: at most a day each
_SIGMA_MAX = 1e9  # S/m; silver, the best conductor, is 6.3e7


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


class Ink(_Strict):
    """One ink of a material: the reactant it carries and how much of the product it makes.

    ``stoichiometry`` is the moles of product formed per mole of this ink's reactant (silver
    nitrate 1, ascorbate 2: one ascorbate reduces two silver ions).
    """

    name: str = Field(min_length=1)
    reactant: str = ""
    concentration_mol_per_l: float = Field(gt=0, le=50)
    stoichiometry: float = Field(default=1.0, gt=0, le=1000)
    repeats: int = Field(default=1, ge=1, le=100)
    wait_after_s: float = Field(default=0.0, ge=0, le=_DAY_S)
    ph: tuple[Annotated[float, Field(ge=-2, le=16)], Annotated[float, Field(ge=-2, le=16)]] | None = None
    warning: str = ""
    #: film levelling (rotary/deposit.py LevelOptions): this ink's viscosity, surface tension
    #: and the time its wet film flows before it sets; None: the head's (nominal) figures
    viscosity_mpa_s: float | None = Field(default=None, ge=R.VISCOSITY_MPA_S.lo, le=R.VISCOSITY_MPA_S.hi)
    surface_tension_mn_m: float | None = Field(default=None, ge=R.SURFACE_TENSION_MN_M.lo, le=R.SURFACE_TENSION_MN_M.hi)
    set_time_s: float | None = Field(default=None, ge=R.SET_TIME_S.lo, le=R.SET_TIME_S.hi)

    @field_validator("name")
    @classmethod
    def _name(cls, v: str) -> str:
        if not v.replace("_", "").replace("-", "").isalnum():
            raise ValueError(f"ink names are letters, digits, '_' and '-', got {v!r}")
        return v


InkStep = Ink  # an ink in print order is the step itself (kept as an alias for readers)


class PostStep(_Strict):
    """A wait or treatment after a material's passes in a layer."""

    kind: Literal["flash_heat", "cure", "dry", "uv_cure", "wait"]
    temperature_c: float | None = Field(default=None, ge=-273.15, le=3000)
    duration_s: float = Field(default=0.0, ge=0, le=_DAY_S)
    note: str = ""

    def describe(self) -> str:
        t = f" at {self.temperature_c:g} C" if self.temperature_c is not None else ""
        d = f" for {self.duration_s:g} s" if self.duration_s else ""
        return f"{self.kind.replace('_', ' ')}{t}{d}" + (f" ({self.note})" if self.note else "")


class Product(_Strict):
    """The solid formed, for the thickness estimate ``t = n M / (rho (1 - porosity))``."""

    name: str
    molar_mass_g_per_mol: float = Field(gt=0, le=1e7)
    density_g_per_cm3: float = Field(gt=0, le=100)
    porosity: float = Field(default=0.0, ge=0, lt=1)


class Material(_Strict):
    """A material formed on the substrate from ``inks`` printed in order (one *cycle*)."""

    name: str = Field(min_length=1)
    description: str = ""
    inks: tuple[Ink, ...] = Field(min_length=1)
    product: Product
    post_steps: tuple[PostStep, ...] = ()
    conductivity_s_per_m: float | None = Field(default=None, gt=0, le=_SIGMA_MAX)
    bulk_conductivity_s_per_m: float | None = Field(default=None, gt=0, le=_SIGMA_MAX)
    warnings: tuple[str, ...] = ()
    figures: dict[str, str] = Field(default_factory=dict)
    nominal: tuple[str, ...] = ()
    source: str = ""

    @model_validator(mode="after")
    def _unique_inks(self) -> Material:
        names = [i.name for i in self.inks]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ValueError(f"ink {dup[0]!r} appears twice; use repeats instead")
        return self

    @property
    def conductive(self) -> bool:
        return self.conductivity_s_per_m is not None

    @property
    def passes_per_cycle(self) -> int:
        """Passes of one cycle: every ink, each ``repeats`` times."""
        return sum(i.repeats for i in self.inks)


_PAPER = "Rotational 3D printing of sensor devices using reactive ink chemistries (the founding paper)"

#: The paper's four material systems. Concentrations, products' densities and porosities are
#: nominal (not in the paper); the ink order, repeats, post-steps and figures are the paper's.
BUILTIN_MATERIALS: dict[str, dict] = {
    "plaster": {
        "name": "plaster",
        "description": "plaster of Paris (CaSO4 . 0.5 H2O) precipitated from ammonium sulphate and calcium chloride",
        "inks": [
            {"name": "ammonium_sulphate", "reactant": "(NH4)2SO4", "concentration_mol_per_l": 2.0, "stoichiometry": 1.0,
             "repeats": 3, "ph": [6.0, 7.0],
             "warning": "ammonium sulphate crystallises on the print head and blocks nozzles (paper, Fig. 7b): "
                        "use a reformulated ink, wipe or cap the head between layers, watch for dead nozzles"},
            {"name": "calcium_chloride", "reactant": "CaCl2", "concentration_mol_per_l": 5.0, "stoichiometry": 1.0,
             "repeats": 1, "ph": [6.0, 7.0]},
        ],
        "product": {"name": "CaSO4 . 0.5 H2O", "molar_mass_g_per_mol": 145.15, "density_g_per_cm3": 2.74, "porosity": 0.4},
        "post_steps": [],
        "figures": {"order": "ammonium sulphate printed 3 times, then calcium chloride once (paper, Fig. 7a)",
                    "pH": "both solutions adjusted to pH 6-7"},
        "nominal": ["concentration_mol_per_l", "density_g_per_cm3", "porosity"],
        "source": _PAPER,
    },
    "silver": {
        "name": "silver",
        "description": "conductive silver: silver nitrate reduced by over-printed ascorbate, then flash heated",
        "inks": [
            {"name": "silver_nitrate", "reactant": "AgNO3", "concentration_mol_per_l": 1.0, "stoichiometry": 1.0, "repeats": 1},
            {"name": "ascorbate", "reactant": "ascorbate (reducing agent)", "concentration_mol_per_l": 0.5,
             "stoichiometry": 2.0, "repeats": 1},
        ],
        "product": {"name": "Ag", "molar_mass_g_per_mol": 107.87, "density_g_per_cm3": 10.49, "porosity": 0.0},
        "post_steps": [{"kind": "flash_heat", "temperature_c": 150.0, "duration_s": 60.0,
                        "note": "after the silver passes of each layer"}],
        "conductivity_s_per_m": 1.42e5,
        "bulk_conductivity_s_per_m": 6.1e7,
        "warnings": ["printed silver conducts about 1/430 of bulk silver (1.42e5 S/m on paper against 6.1e7 S/m); "
                     "the paper calls this too low for sensor applications yet"],
        "figures": {"conductivity": "1.42e5 S/m printed on paper (bulk 6.1e7 S/m); 8.06e5 S/m reported for the same "
                                    "chemistry on an office thermal inkjet"},
        "nominal": ["concentration_mol_per_l", "porosity"],
        "source": _PAPER,
    },
    "epoxy": {
        "name": "epoxy",
        "description": "rigid epoxy: water-soluble poly-epoxide cured by a diamine",
        "inks": [
            {"name": "polyepoxide", "reactant": "water-soluble poly-epoxide (epoxide groups)", "concentration_mol_per_l": 2.0,
             "stoichiometry": 1.0, "repeats": 1},
            {"name": "diamine", "reactant": "diamine (4 N-H per molecule)", "concentration_mol_per_l": 0.5,
             "stoichiometry": 4.0, "repeats": 1},
        ],
        "product": {"name": "epoxy network (per epoxide-amine bond)", "molar_mass_g_per_mol": 200.0,
                    "density_g_per_cm3": 1.2, "porosity": 0.0},
        "post_steps": [{"kind": "cure", "duration_s": 0.0, "note": "cure before the next layer; time depends on the system"}],
        "warnings": ["epoxy ink stability is an open issue (paper): check viscosity and jetting before a long print"],
        "figures": {"system": "water-soluble poly-epoxide, self-curing or with a diamine"},
        "nominal": ["concentration_mol_per_l", "molar_mass_g_per_mol", "density_g_per_cm3"],
        "source": _PAPER,
    },
    "polyamide": {
        "name": "polyamide",
        "description": "polyamide from an acyl-thiol derivative of an acid chloride and a polyamine, at room temperature",
        "inks": [
            {"name": "acyl_thiol", "reactant": "acyl-thiol derivative of an acid chloride", "concentration_mol_per_l": 1.0,
             "stoichiometry": 1.0, "repeats": 1},
            {"name": "polyamine", "reactant": "polyamine (2 amines per molecule)", "concentration_mol_per_l": 0.5,
             "stoichiometry": 2.0, "repeats": 1},
        ],
        "product": {"name": "polyamide (per amide bond)", "molar_mass_g_per_mol": 150.0, "density_g_per_cm3": 1.14,
                    "porosity": 0.0},
        "post_steps": [],
        "figures": {"reaction": "reacts at room temperature"},
        "nominal": ["concentration_mol_per_l", "molar_mass_g_per_mol", "density_g_per_cm3"],
        "source": _PAPER,
    },
}


def validation_message(exc: ValidationError, prefix: str = "") -> str:
    """One line in words: the first error's field path and what it must be
    (``job.layer_height_mm must be at least 0.0001, got -1``), or the path and a check's own
    sentence (``parts[1].material: unknown material ...``).

    Parameters
    ----------
    exc : pydantic.ValidationError
    prefix : str
        Put before the field path (e.g. ``materials.silver``).

    Returns
    -------
    str
        ``PATH PROBLEM`` in words (:func:`rotoprint.io.records.field_problem`), with ``, got
        VALUE`` for a scalar input and a count of the other problems when there are more; the
        path is ``job`` when it is empty.
    """
    errs = exc.errors()
    e = errs[0]
    loc = prefix
    for part in e.get("loc", ()):
        if isinstance(part, int):
            loc += f"[{part}]"
        else:
            loc += ("." if loc else "") + str(part)
    problem = field_problem(e)
    more = f" (and {len(errs) - 1} more problem(s))" if len(errs) > 1 else ""
    sep = "" if problem.startswith(":") else " "
    return f"{loc or 'job'}{sep}{problem}{more}"


class MaterialLibrary:
    """Materials by name: the built-ins, then user materials (which may override them)."""

    def __init__(self, materials: dict[str, Material]) -> None:
        self._m = dict(materials)

    def __contains__(self, name: str) -> bool:
        return name in self._m

    def __getitem__(self, name: str) -> Material:
        try:
            return self._m[name]
        except KeyError:
            raise ConfigError(f"unknown material {name!r}; known: {', '.join(sorted(self._m))}") from None

    def names(self) -> list[str]:
        return sorted(self._m)

    def with_materials(self, extra: dict[str, Material]) -> MaterialLibrary:
        return MaterialLibrary({**self._m, **extra})


def _materials_from_dict(data: dict, origin: str | None) -> dict[str, Material]:
    if not isinstance(data, dict):
        raise ConfigError("materials must be a table of named materials", path=origin)
    out = {}
    for name, d in data.items():
        if not isinstance(d, dict):
            raise ConfigError(f"materials.{name}: expected a table", path=origin)
        try:
            out[name] = Material.model_validate({"name": name, **d})
        except ValidationError as exc:
            raise ConfigError(validation_message(exc, f"materials.{name}"), path=origin) from None
    return out


def builtin_library() -> MaterialLibrary:
    """The paper's four systems: plaster, silver, epoxy, polyamide.

    Returns
    -------
    MaterialLibrary
        A new library holding only the built-in materials.

    Examples
    --------
    >>> lib = builtin_library()
    >>> [(i.name, i.repeats) for i in lib["plaster"].inks]
    [('ammonium_sulphate', 3), ('calcium_chloride', 1)]
    >>> lib["silver"].conductivity_s_per_m, lib["silver"].post_steps[0].describe()
    (142000.0, 'flash heat at 150 C for 60 s (after the silver passes of each layer)')
    """
    return MaterialLibrary(_materials_from_dict(BUILTIN_MATERIALS, None))


def load_materials(source: str | Path | dict, *, base: MaterialLibrary | None = None) -> MaterialLibrary:
    """User materials from a TOML file (``[materials.NAME]`` tables) or a dict, on top of
    ``base`` (default: the built-ins).

    Parameters
    ----------
    source : str, Path or dict
        A TOML file holding only ``[materials.NAME]`` tables, or a dict of material name to
        its fields (the content of the ``materials`` table).
    base : MaterialLibrary, optional
        Materials to start from; default :func:`builtin_library`. Not modified.

    Returns
    -------
    MaterialLibrary
        ``base`` with the user materials added; a user material overrides one of the same name.

    Raises
    ------
    InputFileError
        The file is missing or is not a file.
    ConfigError
        Not UTF-8 TOML, a top-level table other than ``materials``, or a material that is not a
        table or has a missing or invalid field.
    """
    base = builtin_library() if base is None else base
    if isinstance(source, dict):
        return base.with_materials(_materials_from_dict(source, None))
    path = Path(source)
    if not path.exists():
        raise InputFileError("no such materials file", path=path)
    from ..io.inputs import MAX_TOML_BYTES, parse_toml, read_input_text

    text = read_input_text(path, what="materials file", limit_bytes=MAX_TOML_BYTES, error=ConfigError)
    data = parse_toml(text, path, what="materials file", error=ConfigError)
    if set(data) - {"materials"}:
        raise ConfigError(f"unexpected table(s) {sorted(set(data) - {'materials'})}; expected [materials.NAME]", path=path)
    return base.with_materials(_materials_from_dict(data.get("materials", {}), str(path)))

