"""Print devices: presets shipped with the package, and user device files (TOML)."""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import TypeAdapter, ValidationError

from ..errors import DeviceError, InputFileError
from .models import Device, InkjetDevice, InkjetHead, Projector, ProjectorDevice

__all__ = ["load_device", "preset_names", "Device", "InkjetDevice", "InkjetHead", "Projector", "ProjectorDevice"]

_ADAPTER: TypeAdapter = TypeAdapter(Device)


def preset_names() -> list[str]:
    """Names of the presets shipped with rotoprint."""
    root = resources.files(__package__) / "presets"
    return sorted(p.name[: -len(".toml")] for p in root.iterdir() if p.name.endswith(".toml"))


def _validate(data: dict[str, Any], origin: str) -> InkjetDevice | ProjectorDevice:
    try:
        return _ADAPTER.validate_python(data)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err["loc"] if p not in ("inkjet", "projector")) or "(top level)"
        raise DeviceError(f"invalid device field '{where}': {err['msg']}", path=origin) from None


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
        try:
            text = path.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            raise DeviceError("device file is not UTF-8 text", path=path) from None
        origin = str(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise DeviceError(f"not valid TOML: {exc}", path=origin) from None
    if overrides:
        table = "head" if data.get("kind") == "inkjet" else "projector"
        data.setdefault(table, {})
        data[table] = {**data[table], **{k: v for k, v in overrides.items() if v is not None}}
    return _validate(data, origin)
