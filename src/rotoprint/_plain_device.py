"""Projector devices (:mod:`rotoprint.devices`) read without pydantic, for the start-up of ``rotoprint dlp``.

Importing pydantic and building the device models costs a short command (a 10-layer DLP job)
about a tenth of its time. :func:`load_projector` reads a preset or device file whose fields
are plainly valid -- every value of exactly the type the model declares (an int for an int
field, an int or a float for a float field, a bool, a string), inside the model's bounds, no
unknown key -- into a :class:`PlainProjectorDevice` that gives what the pydantic model gives
(the same attributes and properties, the same ``model_dump(mode="json")``). Anything else
returns None and the caller uses :func:`rotoprint.devices.load_device`, whose messages and
lax conversions stay the one reference: this module only ever accepts a subset of what the
model accepts, with the same result. ``tests/test_fast_dlp.py`` holds :data:`PROJECTOR_FIELDS`
to the model's fields, defaults and bounds, and the presets' dumps to the model's.
"""

from __future__ import annotations

import math
from dataclasses import fields
from pathlib import Path
from typing import Any

from ._dataclass import dataclass
from ._projector import ProjectorGeometry

__all__ = ["PlainProjector", "PlainProjectorDevice", "PROJECTOR_FIELDS", "load_projector", "device_from_dump"]

#: field: (type, default, lower bound, lower bound open, upper bound); default ... = required;
#: for str fields the bounds are the allowed values (None: any string). The order is the
#: model's (it is the order of ``model_dump``).
PROJECTOR_FIELDS: dict[str, tuple[type, Any, Any, bool, Any]] = {
    "pixels_x": (int, ..., 0, True, 100_000),
    "pixels_y": (int, ..., 0, True, 100_000),
    "width_mm": (float, ..., 0.0, True, 10_000.0),
    "height_mm": (float, ..., 0.0, True, 10_000.0),
    "mirror_x": (bool, False, None, False, None),
    "mirror_y": (bool, False, None, False, None),
    "orientation": (str, "landscape", ("landscape", "portrait"), False, None),
    "cure_threshold": (float, 0.5, 0.0, False, 1.0),
    "exposure_s": (float, 8.0, 1e-3, False, 3600.0),
    "first_exposure_s": (float, 35.0, 1e-3, False, 3600.0),
    "first_exposure_layers": (int, 10, 0, False, 10_000),
    "printer_model": (str, "rotoprint", None, False, None),
}
_DEVICE_KEYS = ("kind", "name", "description", "source", "nominal", "projector")


@dataclass(frozen=True)
class PlainProjector:
    """The fields of :class:`rotoprint.devices.Projector` (see there)."""

    pixels_x: int
    pixels_y: int
    width_mm: float
    height_mm: float
    mirror_x: bool
    mirror_y: bool
    orientation: str
    cure_threshold: float
    exposure_s: float
    first_exposure_s: float
    first_exposure_layers: int
    printer_model: str


@dataclass(frozen=True)
class PlainProjectorDevice(ProjectorGeometry):
    """The fields and properties of :class:`rotoprint.devices.ProjectorDevice` (see there)."""

    kind: str
    name: str
    description: str
    source: str
    nominal: tuple[str, ...]
    projector: PlainProjector

    def model_dump(self, mode: str = "json") -> dict[str, Any]:
        """The pydantic model's ``model_dump(mode="json")``: a dict of JSON values, fields in order."""
        if mode != "json":
            raise ValueError("only mode='json' is offered")
        return {"kind": self.kind, "name": self.name, "description": self.description, "source": self.source,
                "nominal": list(self.nominal), "projector": {f.name: getattr(self.projector, f.name) for f in fields(PlainProjector)}}


def _plain_value(value: Any, spec: tuple[type, Any, Any, bool, Any]) -> Any:
    """``value`` as the model would store it, or ``...`` when this is not plainly valid."""
    kind, _, lo, lo_open, hi = spec
    if kind is bool:
        return value if type(value) is bool else ...
    if kind is str:
        return value if type(value) is str and (lo is None or value in lo) else ...
    if kind is int:
        if type(value) is not int:
            return ...
    elif type(value) in (int, float):
        value = float(value)
        if not math.isfinite(value):
            return ...
    else:
        return ...
    if (value <= lo if lo_open else value < lo) or value > hi:
        return ...
    return value


def _plain_device(data: Any) -> PlainProjectorDevice | None:
    if not isinstance(data, dict) or not set(data) <= set(_DEVICE_KEYS) or data.get("kind") != "projector":
        return None
    name, desc, src, nominal, proj = (data.get("name"), data.get("description", ""), data.get("source", ""),
                                      data.get("nominal", []), data.get("projector"))
    if type(name) is not str or type(desc) is not str or type(src) is not str:
        return None
    if type(nominal) is not list or not all(type(s) is str for s in nominal) or len(nominal) > 10_000:
        return None
    if not isinstance(proj, dict) or not set(proj) <= set(PROJECTOR_FIELDS):
        return None
    values = {}
    for key, spec in PROJECTOR_FIELDS.items():
        if key not in proj:
            if spec[1] is ...:
                return None
            values[key] = spec[1]
            continue
        v = _plain_value(proj[key], spec)
        if v is ...:
            return None
        values[key] = v
    return PlainProjectorDevice("projector", name, desc, src, tuple(nominal), PlainProjector(**values))


def load_projector(spec: str | Path, **overrides: Any) -> PlainProjectorDevice | None:
    """:func:`rotoprint.devices.load_device` of a plainly valid projector preset or device
    file (see the module's text), or None: then the caller asks :func:`load_device`, for the
    device or for its error.

    Parameters
    ----------
    spec : str or Path
        A preset name or a device .toml file.
    **overrides
        ``exposure_s``, ``first_exposure_s`` (None: the device's).
    """
    from .io.inputs import MAX_TOML_BYTES

    overrides = {k: v for k, v in overrides.items() if v is not None}
    if not set(overrides) <= {"exposure_s", "first_exposure_s"}:
        return None
    spec_s = str(spec)
    root = Path(__file__).parent / "devices" / "presets"  # not through the package: that imports pydantic
    try:
        preset = root / f"{spec_s}.toml"
        if "/" not in spec_s and spec_s and not spec_s.startswith(".") and preset.is_file():
            text = preset.read_text(encoding="utf-8")
        else:
            path = Path(spec_s)
            if path.suffix.lower() != ".toml" or not path.is_file() or path.stat().st_size > MAX_TOML_BYTES:
                return None
            text = path.read_text(encoding="utf-8")
        import tomllib

        data = tomllib.loads(text)
    except (OSError, ValueError, RecursionError):
        return None  # load_device says what is wrong
    if overrides and isinstance(data, dict) and isinstance(data.get("projector"), dict):
        data["projector"] = {**data["projector"], **overrides}
    return _plain_device(data)


def device_from_dump(data: dict, origin: str):
    """The device of a ``model_dump(mode="json")`` (a worker's task): a
    :class:`PlainProjectorDevice` when it is plainly one, else the pydantic model
    (``rotoprint.devices._validate``, with its errors)."""
    dev = _plain_device(data)
    if dev is not None:
        return dev
    from .devices import _validate

    return _validate(data, origin)
