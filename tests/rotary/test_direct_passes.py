"""The direct slicer's interlaced passes (``slice --rotary --passes``, issue 14): the union of
the passes equalised with the transform path's shares (``track_fractions``, the dead-track
cover), realised by ``thin_print``; ``--no-equalise`` keeps every drop."""

from __future__ import annotations

import json
import struct

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import ConfigError
from rotoprint.testing import box_mesh, box_triangles


def _stl(path, size_mm):
    tri = box_triangles(size_mm)
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + struct.pack("<I", len(tri)))
        for t in tri:
            fh.write(struct.pack("<12fH", 0, 0, 0, *t.ravel().tolist(), 0))
    return path


def _slice_and_simulate(run_cli, tmp_path, name, *extra):
    mesh = _stl(tmp_path / "band.stl", (16.0, 0.6, 0.2))  # a band 16 mm wide radially: 1/r is 27 % over it
    out = tmp_path / name
    code, _, err = run_cli("slice", mesh, "--device", "omnidot760", "--rotary", "--tilt", "20", "--radius", "60",
                           "--layer-height", "0.2", "--out", out, "--passes", "auto", "--reference-images", *extra)
    assert code == 0, err
    man = json.loads((tmp_path / f"{name}-passes.json").read_text())
    code, o, err = run_cli("simulate", *[tmp_path / f / "layer_00000.json" for f in man["folders"]], "--out",
                           tmp_path / f"{name}.png", "--json")
    assert code == 0, err
    return man, json.loads(o)["deposit"]


def test_union_equalised_passes_flatten_the_bins_and_conserve_the_volume(run_cli, tmp_path):
    eq_man, eq = _slice_and_simulate(run_cli, tmp_path, "eq")  # the default: the union's shares
    pl_man, pl = _slice_and_simulate(run_cli, tmp_path, "plain", "--no-equalise")
    assert eq_man["equalise"] == "thinning" and pl_man["equalise"] is None and pl_man["union_shares"] is None
    us = eq_man["union_shares"]
    assert eq_man["dpi_y"] == us["dpi_y"] == us["clock_factor"] * pl_man["dpi_y"] and 0.5 < us["mean_share"] < 1.0
    side = json.loads((tmp_path / "eq-p2" / "manifest.json").read_text())
    assert side["options"]["equalise"] == "union shares" and side["options"]["pass"] == 1
    # plain passes: 1/r of one angular clock per swathe; the union's shares: even 1 mm bins
    assert pl["radial_spread"] > 0.08, pl["radial_spread"]
    assert eq["radial_spread"] <= 0.03, eq["radial_spread"]
    for d in (eq, pl):
        assert abs(d["volume_error_fraction"]) < 1e-9 and d["uncovered_fraction"] <= 0.005
    assert eq["levelled"]["thinnest_to_mean"] > pl["levelled"]["thinnest_to_mean"]


def test_the_shares_are_the_transform_paths_realised_by_thin_print():
    from rotoprint.rotary.direct import slice_rotary, union_pass_shares
    from rotoprint.rotary.equalise import EQUALISE_CLOCK_FACTOR, thin_print, track_fractions, ReachFloor
    from rotoprint.rotary.interlace import COVER_SHARE, plan_passes
    from rotoprint.rotary.deposit import DepositOptions
    from rotoprint.rotary.options import RotarySetup

    dev = load_device("omnidot760")
    head = dev.head
    mesh = box_mesh((6.0, 1.0, 0.4))
    base = slice_rotary(mesh, dev, layer_height_mm=0.2, tilt_deg=20.0, inner_radius_mm=60.0)
    d_um = DepositOptions().full_footprint_um(head)
    pp = plan_passes(head, base.plan, footprint_um=d_um)
    shares, clock, rec = union_pass_shares(head, base.plan, pp.offsets_mm, dpi_y=pp.dpi_y)
    want = track_fractions(head, base.plan, pp.offsets_mm, RotarySetup(tilt_deg=20.0, dpi_y=pp.dpi_y), footprint_um=d_um,
                           reach=ReachFloor(COVER_SHARE * d_um, EQUALISE_CLOCK_FACTOR))
    assert clock == EQUALISE_CLOCK_FACTOR * pp.dpi_y and rec["dead_cover"] is None
    assert all(np.array_equal(a, b) for pa, pb in zip(shares, want) for a, b in zip(pa, pb))
    for q in (0, 2):
        plain = slice_rotary(mesh, dev, layer_height_mm=0.2, tilt_deg=20.0, inner_radius_mm=60.0, dpi_y=clock,
                             pivot_offset_mm=pp.offsets_mm[q])
        job = plain.with_shares(shares[q], pass_index=q)
        for layer in (0, 1):  # the pattern moves from layer to layer
            got = job.layer(layer)
            ref = thin_print(plain.layer(layer), shares[q], pass_index=q + 64 * layer)
            assert all(np.array_equal(a.levels, b.levels) for a, b in zip(got.swathes, ref.swathes))
        # the numpy reference kernel thins the same way
        ref_np = slice_rotary(mesh, dev, layer_height_mm=0.2, tilt_deg=20.0, inner_radius_mm=60.0, dpi_y=clock,
                              pivot_offset_mm=pp.offsets_mm[q], backend="numpy", shares=shares[q], pass_index=q).layer(1)
        assert all(np.array_equal(a.levels, b.levels) for a, b in zip(ref_np.swathes, job.layer(1).swathes))
        # a worker rebuilds the same pass from the JSON options
        again = slice_rotary(mesh, dev, **json.loads(json.dumps(job.rotary_options)))
        assert np.array_equal(again.layer(0).swathes[0].levels, job.layer(0).swathes[0].levels)
    with pytest.raises(ConfigError, match="one \\(764,\\) array per swathe"):
        plain.with_shares([np.ones(3)])
    for bad in (np.nan, np.inf, -0.5):  # a NaN share would have the fill write events it made no room for
        broken = [f.copy() for f in shares[0]]
        broken[0][100] = bad
        with pytest.raises(ConfigError, match="shares must be finite and >= 0"):
            plain.with_shares(broken)
    eq = slice_rotary(mesh, dev, layer_height_mm=0.2, tilt_deg=20.0, inner_radius_mm=60.0, equalise=True)
    with pytest.raises(ConfigError, match="options.equalise must be False"):
        eq.with_shares(shares[0])


def test_dead_nozzles_are_covered_by_the_other_passes():
    from rotoprint.rotary.direct import slice_rotary, union_pass_shares
    from rotoprint.rotary.interlace import plan_passes
    from rotoprint.rotary.deposit import DepositOptions

    dev = load_device("omnidot760")
    base = slice_rotary(box_mesh((6.0, 1.0, 0.2)), dev, layer_height_mm=0.2, tilt_deg=20.0, inner_radius_mm=60.0)
    k = base.tracks[0].nozzle
    dead = tuple(sorted(int(x) for x in k[[10, k.size // 2, k.size - 11]]))
    head = dev.head.model_copy(update={"dead_nozzles": dead})
    pp = plan_passes(head, base.plan, footprint_um=DepositOptions().full_footprint_um(head))
    shares, _, rec = union_pass_shares(head, base.plan, pp.offsets_mm, dpi_y=pp.dpi_y)
    cov = rec["dead_cover"]
    assert cov is not None and cov["dead_tracks"] >= len(dead) and cov["moved"] > 0
    assert cov["moved"] + cov["lost"] == pytest.approx(cov["demand"])
    assert all(not f[list(dead)].any() for per in shares for f in per)
    # the cover only adds drops to live tracks: the shares equalised with the dead nozzles as live ones, times the
    # common scale the cover reports where its window had no room (DeadCoverOptions.scale_shares), or more
    from rotoprint.rotary.equalise import EQUALISE_CLOCK_FACTOR, ReachFloor, track_fractions
    from rotoprint.rotary.interlace import COVER_SHARE
    from rotoprint.rotary.options import RotarySetup

    d_um = DepositOptions().full_footprint_um(head)
    as_live = track_fractions(head, base.plan, pp.offsets_mm, RotarySetup(tilt_deg=20.0, dpi_y=pp.dpi_y), footprint_um=d_um,
                              reach=ReachFloor(COVER_SHARE * d_um, EQUALISE_CLOCK_FACTOR), dead_nozzles=())
    live = np.ones(head.nozzles, bool)
    live[list(dead)] = False
    s = float(cov["scale"])
    assert 0.85 <= s <= 1.0
    gain = [(f - s * g)[live] for pf, pg in zip(shares, as_live) for f, g in zip(pf, pg)]
    assert min(float(x.min()) for x in gain) >= -1e-12 and max(float(x.max()) for x in gain) > 0
