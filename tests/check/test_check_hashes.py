"""The check's outputs, byte for byte: the JSON report and every overlay of a few cases, hashed.

The hashes were recorded on main before the kernels were split by algorithm and the settings
became :class:`~rotoprint.check.CheckOptions` (issue 13): a refactor that changes any finding,
width, figure of the report or pixel of an overlay fails here. A change meant to alter the
check's results records new hashes, and says why, in the same commit.
"""

from __future__ import annotations

import hashlib
import json

import numpy as np
import pytest

from rotoprint.check import check_printability, mask_model, overlay_image
from rotoprint.devices import load_device
from rotoprint.mesh import Mesh
from rotoprint.testing import box_triangles


def _hollow_triangles() -> np.ndarray:
    """A 4 x 3 x 2 mm box with 0.5 mm walls shut on every side (one sealed cavity), and a
    0.05 mm fin on its lid (thin walls, vanished walls on the inkjet)."""
    X, Y, Z, t = 4.0, 3.0, 2.0, 0.5
    parts = [
        box_triangles((X, Y, t)),
        box_triangles((X, t, Z - t), (0, 0, t)),
        box_triangles((X, t, Z - t), (0, Y - t, t)),
        box_triangles((t, Y - 2 * t, Z - t), (0, t, t)),
        box_triangles((t, Y - 2 * t, Z - t), (X - t, t, t)),
        box_triangles((X, Y, t), (0, 0, Z)),
        box_triangles((2.0, 0.05, 0.3), (1.0, 1.5, Z + t)),
    ]
    return np.concatenate(parts)


def _hollow() -> Mesh:
    return Mesh.from_triangles(_hollow_triangles())


def _piece() -> Mesh:
    from rotoprint.pieces import feature_test_piece

    return Mesh.from_triangles(feature_test_piece()[0])


def _digest(mesh: Mesh, device: str, layer_height_mm: float, **kw) -> tuple[str, str, int]:
    """sha256 of the report's JSON (sorted keys), sha256 over every layer's overlay (layer
    index, shape, bytes), and the number of findings."""
    dev = load_device(device)
    h = hashlib.sha256()

    def on_layer(lc) -> None:
        img = overlay_image(lc)
        h.update(f"{lc.index}:{img.shape}".encode())
        h.update(img.tobytes())

    rep = check_printability(mesh, dev, layer_height_mm=layer_height_mm, on_layer=on_layer, **kw)
    text = json.dumps(rep.to_json(), sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest(), h.hexdigest(), len(rep.findings)


# (case, report sha256, overlays sha256, findings), recorded on main at 00263d0
RECORDED = {
    "piece-projector": (
        "91b520896b8ca6e5f668cb89c25e161b748405e0d0b383684d664f06f0981a65",
        "0514e593fc3f71668686707d1fd4c70d05f884afbd45d2aa56cec60cec195aa4",
        58,
    ),
    "piece-projector-smooth": (
        "4dade85852334137c9af9e16c93b5879697417c0bb21483a65eb7191bdc9f2d0",
        "97b82995fbb6c498a28ff9bb953a646d603d2f1426bc8554e71867eef72a40ac",
        274,
    ),
    "piece-inkjet": (
        "b6e80dac76c2191e28b5e44a9ed5fe6e8e00ae1507b28d4354172875c1a4c70e",
        "6d4c43441938ef0968266f901735cf6b53b25e227718005e205c676180d991ea",
        54,
    ),
    "half-donut": (
        "da15574f95aa60daba9111661330db2fcce1f0b3c1e9226624ae4bcf72780c17",
        "41487683d05c3bd2ec1a05687f30a79539775df9b35f5c692f4f8967cbf9e05f",
        12,
    ),
    "teapot-inkjet": (
        "fc372b46aee1186908326e78ec62a91791c6769c6ac6a0d80e51af7f45517e7c",
        "e02f79023015a566530194b6673243d0c6c666a9e2adfc5229810931b88b518e",
        5,
    ),
    "hollow-projector": (
        "f6cb41d2dd8eb94d0a868ed29de2268c96f905b30639b8158b32732824c56dc9",
        "ca412d0888b29ee5ef1910fb7cbbb99dd69279abc6f2194122e14c08024a5561",
        1,
    ),
    "hollow-inkjet": (
        "a2fa8487451a92accc2c5a365b86dd90ef1fb995d1799adbaf4e304e1b4e0902",
        "38bf989139ca10a300375cd9e17cb596538606648cf56fba8bc936bfce5bfc8a",
        5,
    ),
}


def _case(name: str, shared=None):
    if name == "piece-projector":
        return _piece(), "perfactory-sxga", 0.4, {}
    if name == "piece-projector-smooth":
        return _piece(), "perfactory-sxga", 0.5, {"mask_fn": mask_model("smooth"), "mask_name": "smooth", "fibre_angle_deg": 30.0}
    if name == "piece-inkjet":
        return _piece(), "omnidot760", 0.4, {"resolution_mm": 0.0}
    if name == "hollow-projector":
        return _hollow(), "perfactory-sxga", 0.25, {}
    if name == "hollow-inkjet":
        return _hollow(), "omnidot760", 0.25, {"min_wall_mm": 0.1, "min_gap_mm": 0.1}
    from rotoprint import load_mesh

    if name == "half-donut":
        return load_mesh(shared / "half_donut_ascii.stl"), "perfactory-sxga", 0.25, {}
    if name == "teapot-inkjet":
        return load_mesh(shared / "teapot_open.stl"), "omnidot760", 4.0, {}
    raise AssertionError(name)


@pytest.mark.parametrize("name", list(RECORDED))
def test_check_outputs_unchanged(name, request):
    shared = request.getfixturevalue("shared_meshes") if name in ("half-donut", "teapot-inkjet") else None
    mesh, device, lh, kw = _case(name, shared)
    got = _digest(mesh, device, lh, **kw)
    assert got[2] > 0 or name.startswith("teapot"), "each case is meant to find something"
    assert got == RECORDED[name]


def _write_stl(path, tris) -> None:
    import struct

    with open(path, "wb") as f:
        f.write(b"hash test".ljust(80, b" "))
        f.write(struct.pack("<I", len(tris)))
        for t in tris:
            f.write(struct.pack("<12fH", 0, 0, 0, *np.asarray(t, np.float32).ravel(), 0))


# `rotoprint check` with an exposure model, rotary limits and orientations (inkjet), recorded
# on main at 00263d0: report.json without the mesh's path (a temporary folder) and every overlay
CLI_RECORDED = {
    "projector": ("8e1a08b128a7dba5c072e4a948d08b5b19e2df23cc28a41b015f8eb33c2886ba", "8a6d93863430c53cfa30bcc84e96408ec10daef7ba324979919826d751f7009a", 3),
    "inkjet": (
        "0508f9b7db36f37c2a795dbbe801700a1ada06d131b4eb26de96f64d3b5c87c8",
        "37f549a2a6719cd8051c5090de20e6f864875ecfafb64448cd0b52468aeb6c23",
        3,
    ),
}


@pytest.mark.parametrize("name", list(CLI_RECORDED))
def test_check_cli_outputs_unchanged(name, run_cli, tmp_path):
    stl = tmp_path / "hollow.stl"
    _write_stl(stl, _hollow_triangles())
    out = tmp_path / "out"
    if name == "projector":
        args = ["--device", "perfactory-sxga", "--layer-height", "0.25", "--mask", "smooth", "--min-wall", "0.06", "--fibre-angle", "20"]
    else:
        args = ["--device", "omnidot760", "--layer-height", "0.5", "--rotary", "--tilt", "30", "--radius", "60", "--orientations", "0:90:45", "--no-islands"]
    code, _, err = run_cli("check", str(stl), *args, "--out", str(out), "--quiet")
    assert code == 3, err
    data = json.loads((out / "report.json").read_text())
    assert data.pop("mesh") == str(stl)
    rep = hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()
    h = hashlib.sha256()
    for p in sorted((out / "overlays").iterdir()):
        h.update(p.name.encode())
        h.update(p.read_bytes())
    assert (rep, h.hexdigest(), len(data["findings"])) == CLI_RECORDED[name]
