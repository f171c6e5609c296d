"""Every archive written is reopened: keys, layer count, names, sizes, pixel values."""

from __future__ import annotations

import zipfile

import numpy as np
import pytest

from rotoprint import load_device, slice_mesh
from rotoprint.errors import ConfigError, ImageError, InputFileError
from rotoprint.io.archives import (
    CONFIG_KEYS,
    PRUSASLICER_KEYS,
    JobInfo,
    format_from_path,
    read_job,
    write_job,
)
from rotoprint.masks import MaskOptions, iter_masks
from rotoprint.testing import box_mesh, cylinder_mesh


def _job(device="perfactory-sxga", mesh=None, lh=0.5):
    dev = load_device(device)
    m = mesh if mesh is not None else cylinder_mesh(2.0, 1.5, 64)
    return dev, slice_mesh(m, dev, layer_height_mm=lh)


def _info(job, dev, options: MaskOptions, name="part"):
    p = dev.projector
    return JobInfo(
        job_name=name, layer_height_mm=job.plan.layer_height_mm, layer_count=len(job), copies=options.copies,
        width_px=job.grid.width, height_px=job.grid.height, pixel_x_mm=job.grid.pitch_x_mm, pixel_y_mm=job.grid.pitch_y_mm,
        mirror_x=options.mirror_x, mirror_y=options.mirror_y, orientation=p.orientation, exposure_s=p.exposure_s,
        first_exposure_s=p.first_exposure_s, first_exposure_layers=p.first_exposure_layers, printer_model=p.printer_model,
        device_name=dev.name, options=options.to_json(), grid=job.grid.to_json(),
    )


@pytest.mark.parametrize("suffix,device", [(".sl1", "perfactory-sxga"), (".sl1s", "prusa-sl1s")])
@pytest.mark.parametrize("erm", [False, True])
def test_sl1_roundtrip(tmp_path, suffix, device, erm):
    dev, job = _job(device)
    opts = MaskOptions(mode="coverage", erm=erm, mirror_x=dev.projector.mirror_x)
    info = _info(job, dev, opts)
    out = tmp_path / f"my part{suffix}"
    write_job(out, iter_masks(job, opts), info)
    want = [m.image for m in iter_masks(job, opts)]
    a = read_job(out)
    assert a.format == suffix[1:]
    assert set(CONFIG_KEYS) <= set(a.config) and set(PRUSASLICER_KEYS) <= set(a.prusaslicer)
    n = len(job) * (2 if erm else 1)
    assert len(a) == n == int(a.config["numFast"]) + int(a.config["numSlow"])
    assert a.config["jobDir"] == "my_part"
    assert a.mask_names == [f"my_part{i:05d}.png" for i in range(n)]
    assert a.thumbnails == {"thumbnail/thumbnail400x400.png": (400, 400), "thumbnail/thumbnail800x480.png": (800, 480)}
    p = a.prusaslicer
    assert (int(p["display_pixels_x"]), int(p["display_pixels_y"])) == (dev.projector.pixels_x, dev.projector.pixels_y)
    assert float(p["display_width"]) == pytest.approx(dev.projector.width_mm)
    assert float(p["display_height"]) == pytest.approx(dev.projector.height_mm)
    assert p["display_mirror_x"] == str(int(dev.projector.mirror_x)) and p["display_orientation"] == "landscape"
    assert float(a.config["layerHeight"]) == pytest.approx(0.5 / (2 if erm else 1))
    assert a.config["printerModel"] == ("SL1S" if suffix == ".sl1s" else "SL1")
    for i in range(n):
        img = a.mask(i)
        assert img.shape == (dev.projector.pixels_y, dev.projector.pixels_x) and img.dtype == np.uint8
        np.testing.assert_array_equal(img, want[i])
    # the resin volume is the coverage integral: pi r^2 h of the 64-gon prism, within a pixel row
    vol_ml = float(a.config["usedMaterial"])
    prism = 0.5 * 64 * 4.0 * np.sin(2 * np.pi / 64) * 1.5
    assert vol_ml * 1000 == pytest.approx(prism, rel=2e-3)
    import os

    umask = os.umask(0)
    os.umask(umask)
    assert out.stat().st_mode & 0o777 == 0o666 & ~umask  # not the temporary file's 0600


@pytest.mark.parametrize("fmt", ["png", "perfactory"])
def test_folders_roundtrip(tmp_path, fmt):
    dev, job = _job()
    opts = MaskOptions(mode="smooth", erm=True, invert=True, mirror_y=True)
    info = _info(job, dev, opts, name="pj")
    out = tmp_path / "job"
    manifest = write_job(out, iter_masks(job, opts), info, fmt=fmt)
    a = read_job(out)
    assert a.format == fmt and len(a) == 2 * len(job) == manifest["mask_count"]
    names = [f"{i:05d}.png" if fmt == "perfactory" else f"mask_{i:05d}.png" for i in range(len(a))]
    assert a.mask_names == names
    assert sorted(p.name for p in out.iterdir()) == sorted(
        names + ["manifest.json", "rotoprint-output.json"] + (["build.cfg", "job.txt"] if fmt == "perfactory" else [])
    )
    assert [m["layer"] for m in a.manifest["masks"]] == [i // 2 for i in range(len(a))]
    assert [m["copy"] for m in a.manifest["masks"]] == [i % 2 for i in range(len(a))]
    assert a.manifest["image"]["expose"] == 0  # inverted
    if fmt == "perfactory":
        assert a.config["erm"] == "1" and int(a.config["masks"]) == len(a)
        assert float(a.config["layer_thickness_mm"]) == 0.5
    for m, img_want in zip(iter_masks(job, opts), range(len(a))):
        got = a.mask(img_want)
        np.testing.assert_array_equal(got, m.image)
        assert got.shape == (1050, 1400)
    # inverted background is white; the ERM copy is the first one moved right and down
    first, second = a.mask(0), a.mask(1)
    assert first[0, 0] == 255
    plain0, plain1 = (255 - first)[::-1], (255 - second)[::-1]  # undo inversion and mirror_y
    np.testing.assert_array_equal(plain1[1:, 1:], plain0[:-1, :-1])
    assert plain0.any()


def test_erm_copy_is_shifted_and_mirror_applied():
    dev, job = _job()
    plain = list(iter_masks(job, MaskOptions(mode="binary", erm=True)))
    np.testing.assert_array_equal(plain[1].image[1:, 1:], plain[0].image[:-1, :-1])
    mir = list(iter_masks(job, MaskOptions(mode="binary", mirror_x=True)))
    np.testing.assert_array_equal(mir[0].image, plain[0].image[:, ::-1])
    np.testing.assert_array_equal(mir[0].plain, plain[0].image)


def test_first_layers_are_inset():
    dev, job = _job(mesh=box_mesh((4, 4, 2)), lh=0.25)
    opts = MaskOptions(mode="coverage", first_layers=4, first_layer_offset_um=100)
    areas = [m.image.sum(dtype=np.int64) / 255 * job.grid.pitch_x_mm * job.grid.pitch_y_mm for m in iter_masks(job, opts)]
    # a 4 x 4 mm square inset by d has area (4 - 2d)^2
    for i, d in enumerate([0.1, 0.075, 0.05, 0.025, 0, 0, 0, 0]):
        assert areas[i] == pytest.approx((4 - 2 * d) ** 2, rel=2e-3)


def test_nothing_partial_on_failure(tmp_path):
    dev, job = _job()
    opts = MaskOptions(mode="binary")
    info = _info(job, dev, opts)

    def broken():
        for m in iter_masks(job, opts):
            yield m
            raise RuntimeError("disk on fire")

    for name in ("x.sl1", "folder"):
        with pytest.raises(RuntimeError):
            write_job(tmp_path / name, broken(), info)
        assert list(tmp_path.iterdir()) == []
    with pytest.raises(ConfigError, match="expected 3 masks, got 1"):
        write_job(tmp_path / "y.sl1", (m for m in list(iter_masks(job, opts))[:1]), info)
    with pytest.raises(ImageError, match=r"must be \(1050, 1400\) uint8"):
        bad = next(iter_masks(job, opts))
        write_job(tmp_path / "z.sl1", [type(bad)(0, 0, 0, 0.0, bad.image[:5], bad.plain)], info)
    assert list(tmp_path.iterdir()) == []


def test_reader_rejects_bad_archives(tmp_path):
    p = tmp_path / "bad.sl1"
    p.write_bytes(b"not a zip")
    with pytest.raises(InputFileError, match="not a zip"):
        read_job(p)
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("config.ini", "jobDir = a\nnumFast = 1\n")
        zf.writestr("prusaslicer.ini", "display_width = 1\n")
    with pytest.raises(InputFileError, match="lacks keys: action"):
        read_job(p)
    with pytest.raises(InputFileError, match="no such"):
        read_job(tmp_path / "missing.sl1")
    # a layer folder whose manifest is not JSON, or not a mask list
    d = tmp_path / "layers"
    d.mkdir()
    for text in ("{not json", '{"masks": [{"name": "x"}]}', '["a"]'):
        (d / "manifest.json").write_text(text)
        with pytest.raises(InputFileError, match="not a mask list"):
            read_job(d)


def test_format_from_path():
    assert format_from_path("a.SL1") == "sl1" and format_from_path("a.sl1s") == "sl1s"
    assert format_from_path("out") == "png" and format_from_path("out", "perfactory") == "perfactory"
    with pytest.raises(ConfigError, match="cannot tell the format"):
        format_from_path("a.zip")
    with pytest.raises(ConfigError, match="format must be one of"):
        format_from_path("a", "ctb")
