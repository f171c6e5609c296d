"""Print devices: presets shipped with the package, and user device files (TOML)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import TypeAdapter, ValidationError

import math

from ..errors import ConfigError, DeviceError, InputFileError
from .models import Device, InkjetDevice, InkjetHead, Projector, ProjectorDevice

__all__ = ["load_device", "as_device", "preset_names", "Device", "InkjetDevice", "InkjetHead", "Projector", "ProjectorDevice"]

_ADAPTER: TypeAdapter = TypeAdapter(Device)


def preset_names() -> list[str]:
    """Names of the presets shipped with rotoprint."""
    root = resources.files(__package__) / "presets"
    return sorted(p.name[: -len(".toml")] for p in root.iterdir() if p.name.endswith(".toml"))


# Command-line options that override a device field: (option, the devices it applies to, unit).
_OVERRIDE_OPTIONS: dict[str, tuple[str, str, str]] = {
    "dpi_y": ("--dpi-y", "inkjet heads", "dpi"),
    "exposure_s": ("--exposure", "projectors", "seconds"),
    "first_exposure_s": ("--first-exposure", "projectors", "seconds"),
}


def _override_name(key: str) -> str:
    return _OVERRIDE_OPTIONS[key][0] if key in _OVERRIDE_OPTIONS else f"override {key!r}"


def _check_overrides(data: dict[str, Any], overrides: dict[str, Any], origin: str) -> str:
    """The table the overrides go into; a ConfigError naming the option if one cannot apply."""
    kind = data.get("kind")
    table = "head" if kind == "inkjet" else "projector"
    model = InkjetHead if kind == "inkjet" else Projector
    for key, value in overrides.items():
        name = _override_name(key)
        if key not in model.model_fields:
            applies = _OVERRIDE_OPTIONS[key][1] if key in _OVERRIDE_OPTIONS else f"devices with a {key!r} field"
            raise ConfigError(f"{name} applies to {applies} only; {origin} is a {kind} device")
        if isinstance(value, float) and not math.isfinite(value):
            unit = _OVERRIDE_OPTIONS[key][2] if key in _OVERRIDE_OPTIONS else "units"
            raise ConfigError(f"{name} must be a finite number of {unit}, got {value}")
    return table


def _validate(data: dict[str, Any], origin: str, overridden: tuple[str, ...] = ()) -> InkjetDevice | ProjectorDevice:
    from ..io.records import field_problem, validation_line

    try:
        return _ADAPTER.validate_python(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        raw = [str(p) for p in err["loc"]]
        if len(raw) >= 2 and raw[-2] in ("head", "projector") and raw[-1] in overridden:
            raise ConfigError(f"{_override_name(raw[-1])} {field_problem(err).lstrip(': ')} (device {origin})") from None
        if err["type"] == "union_tag_not_found":
            empty = " (the file is empty)" if not data else ""
            raise DeviceError(f"no device kind{empty}: a device file says kind = \"inkjet\" or kind = \"projector\"",
                              path=origin) from None
        if err["type"] == "union_tag_invalid":
            raise DeviceError(f"kind must be \"inkjet\" or \"projector\", got {err['ctx'].get('tag')!r}",
                              path=origin) from None
        # the tagged union puts the kind first in the path (inkjet.head.nozzles): left out
        raise DeviceError(validation_line(exc, skip=("inkjet", "projector"), record="the device",
                                          field="device field"), path=origin) from None


def load_device(spec: str | Path, **overrides: Any) -> InkjetDevice | ProjectorDevice:
    """A device from a preset name (see :func:`preset_names`) or a TOML device file.

    ``overrides`` replace fields of the device's ``head`` or ``projector`` table, e.g.
    ``load_device("omnidot760", dpi_y=720)``.
    """
    spec_s = str(spec)
    if spec_s in preset_names():
        text = (resources.files(__package__) / "presets" / f"{spec_s}.toml").read_text(encoding="utf-8")
        origin = f"preset {spec_s}"
    else:
        path = Path(spec_s)
        if not path.exists():
            if path.suffix.lower() != ".toml" and "/" not in spec_s:
                raise DeviceError(f"unknown device {spec_s!r}; presets: {', '.join(preset_names())}, or a .toml file")
            raise InputFileError("no such device file", path=path)
        if path.is_dir():
            raise InputFileError("is a directory, expected a device .toml file", path=path)
        from ..io.inputs import MAX_TOML_BYTES, read_input_text

        text = read_input_text(path, what="device file", limit_bytes=MAX_TOML_BYTES, error=DeviceError)
        origin = str(path)
    from ..io.inputs import parse_toml

    data = parse_toml(text, origin, what="device file", error=DeviceError)
    overrides = {k: v for k, v in overrides.items() if v is not None}
    if overrides and isinstance(data, dict):
        table = _check_overrides(data, overrides, origin)
        if not isinstance(data.get(table, {}), dict):
            raise DeviceError(f"invalid device field '{table}': expected a table", path=origin)
        data[table] = {**data.get(table, {}), **overrides}
    return _validate(data, origin, tuple(overrides))


def as_device(device: Any) -> Any:
    """:func:`load_device` of ``device`` when it is a preset name (such as
    ``"perfactory-sxga"``) or the path of a TOML device file, else ``device`` itself (a device
    model). Every public function that takes a device takes either.

    Raises
    ------
    DeviceError, InputFileError
        As :func:`load_device`.
    """
    if isinstance(device, (str, Path)):
        return load_device(device)
    return device
