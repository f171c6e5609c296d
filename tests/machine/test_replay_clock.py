"""Replay at the machine clock's angles: the first firing a whole number of encoder counts after
the index pulse, the next ones every divider / multiplier counts. An exact clock gives the
figures of the nominal placement (``simulate``) to 1e-9; an inexact one moves every drop by at
most what the ratio and the rounded index offset say, and the replay reports it."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rotoprint.machine.program import write_machine_folder
from rotoprint.machine.replay import machine_clock, replay_layers, replay_program, load_program
from rotoprint.process.plan import plan_job
from rotoprint.rotary.simulate import FiringClock, place_drops

from test_machine_program import _same, _small_job


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    root = tmp_path_factory.mktemp("small")
    write_machine_folder(plan_job(_small_job()), root / "m")
    return root / "m" / "program.json"


def _expected_displacement_um(prog: dict, im, rec_of) -> float:
    """Largest drop displacement of one replayed image, from the program's numbers alone:
    a drop of firing i at radius r moves along its circle by the chord 2 r sin(|dev| / 2),
    dev = (index counts + (i - first) d / m) 2 pi / N - i dphi."""
    n_counts = prog["machine"]["encoder_counts_per_rev"]
    nominal = place_drops(im.print)
    worst = 0.0
    for sw in im.print.swathes:
        rec = rec_of[(im.material, im.ink, im.interlace, sw.index)]
        c = next(h for h in prog["heads"] if h["name"] == im.head)["swathes"][sw.index]["clock"]
        sel = nominal.swathe == sw.index
        i = nominal.firing[sel]
        turn = (rec["index_offset_counts"] + (i - rec["first_firing_index"]) * c["divider"] / c["multiplier"]) * 2 * math.pi / n_counts
        dev = np.remainder(turn - i * sw.dphi_rad + math.pi, 2 * math.pi) - math.pi
        r = np.hypot(nominal.x_mm[sel], nominal.y_mm[sel])
        if i.size:
            worst = max(worst, float((2e3 * r * np.abs(np.sin(dev / 2))).max()))
    return worst


def test_an_inexact_clock_moves_the_drops_by_what_the_program_says(small):
    prog = load_program(small)
    rec_of = {(r["material"], r["ink"], int(r.get("interlace", 0)), r["swathe"]): r for L in prog["layers"] for r in L["images"] if L["index"] == 0}
    machine = replay_program(small, layer=0)
    nominal = replay_program(small, layer=0, angles="nominal")
    (_, imgs), = list(replay_layers(prog, small, layers=[0]))[:1]
    by = {(r["material"], r["ink"], r["interlace"]): r for r in machine["images"]}
    for im in imgs:
        r = by[(im.material, im.ink, im.interlace)]
        want = _expected_displacement_um(prog, im, rec_of)
        # sub-micrometre, but not nothing (float noise at 60 mm is ~1e-8 um): the clock's ratio and whole
        # counts; 0.004 um since the build's passes print at the equalised clock (2 x the plan's)
        assert 1e-3 < want < 1.0
        assert r["max_drop_displacement_um"] == pytest.approx(want, rel=1e-6)
        assert r["swathe_clocks"][0]["max_drop_displacement_um"] == pytest.approx(want, rel=1e-6)
    assert machine["clock"]["angles"] == "machine" and nominal["clock"]["angles"] == "nominal"
    assert machine["clock"]["max_drop_displacement_um"] == max(r["max_drop_displacement_um"] for r in machine["images"])
    assert nominal["clock"]["max_drop_displacement_um"] == 0.0
    for a, b in zip(machine["images"], nominal["images"], strict=True):
        # same drops; the figures move by no more than sub-micrometre shifts can: mean error by at
        # most the largest displacement, IoU and coverage by the pixels whose nearest site changes
        assert a["drops"] == b["drops"] and a["design_pixels"] == b["design_pixels"]
        d_um = a["max_drop_displacement_um"]
        assert abs(a["mean_error_um"] - b["mean_error_um"]) <= d_um
        assert abs(a["max_error_um"] - b["max_error_um"]) <= d_um
        assert abs(a["iou"] - b["iou"]) < 5e-3 and abs(a["uncovered_fraction"] - b["uncovered_fraction"]) < 5e-3
        assert abs(a["drops_outside"] - b["drops_outside"]) <= 0.01 * a["drops"]


def test_every_revolution_step_is_reported_with_its_swathe(small):
    rep = replay_program(small)
    prog = json.loads(small.read_text())
    steps = {s["n"]: s for L in prog["layers"] for s in L["steps"] if s["kind"] == "revolution" and s["image"]}
    seen = [n for r in rep["images"] for sw in r["swathe_clocks"] for n in sw["steps"]]
    assert sorted(seen) == sorted(steps)
    for r in rep["images"]:
        for sw in r["swathe_clocks"]:
            assert all(steps[n]["image"] == sw["image"] for n in sw["steps"])


def _make_exact(prog: dict, divider: int = 150) -> None:
    """Turn every swathe's clock exact: multiplier 1, angle per firing 2 pi * divider / N, index
    offsets in whole counts (the first firing * divider)."""
    n_counts = prog["machine"]["encoder_counts_per_rev"]
    dphi = 2 * math.pi / n_counts * divider / 1  # as machine_clock makes it
    for h in prog["heads"]:
        for s in h["swathes"]:
            s["dphi_rad"] = dphi
            s["clock"].update(multiplier=1, divider=divider)
    for L in prog["layers"]:
        for r in L["images"]:
            r["dphi_rad"] = dphi
            r["index_offset_counts"] = (r["first_firing_index"] * divider) % n_counts
        idx = {r["file"]: r["index_offset_counts"] for r in L["images"]}
        for s in L["steps"]:
            if s["kind"] == "revolution":
                s.update(multiplier=1, divider=divider)
                if s["image"]:
                    s["index_offset_counts"] = idx[s["image"]]


def test_an_exact_clock_gives_the_nominal_figures(small):
    prog = json.loads(small.read_text())
    _make_exact(prog)
    small.with_name("exact.json").write_text(json.dumps(prog))
    p = small.with_name("exact.json")
    machine = replay_program(p)
    nominal = replay_program(p, angles="nominal")
    assert machine["clock"]["max_drop_displacement_um"] == 0.0
    for a, b in zip(machine["images"], nominal["images"], strict=True):
        _same(a, {k: v for k, v in b.items() if k != "swathe_clocks"})
    # and the nominal figures are those of simulate for the decoded prints (bit for bit placement)
    from rotoprint.rotary.simulate import simulate

    loaded = load_program(p)
    for (_, imgs) in replay_layers(loaded, p, layers=[1]):
        for im in imgs:
            r = next(x for x in machine["images"] if (x["layer"], x["material"], x["ink"], x["interlace"]) == (1, im.material, im.ink, im.interlace))
            _same(r, simulate(im.print, im.design).report.to_json())


def test_firing_clock_places_drops_at_its_angles(small):
    prog = load_program(small)
    (_, imgs), = list(replay_layers(prog, small, layers=[0]))[:1]
    pr = imgs[0].print
    sw = pr.swathes[0]
    nominal = place_drops(pr)
    same = place_drops(pr, clocks={sw.index: FiringClock(sw.first_firing, sw.first_firing * sw.dphi_rad, sw.dphi_rad)})
    assert np.allclose(same.x_mm, nominal.x_mm, atol=1e-12) and np.allclose(same.y_mm, nominal.y_mm, atol=1e-12)
    turned = place_drops(pr, clocks={sw.index: FiringClock(sw.first_firing, sw.first_firing * sw.dphi_rad + 1e-3, sw.dphi_rad)})
    # 1 mrad more turned: every drop lands rotated by -direction * 1 mrad about the platform axis
    a = -pr.direction * 1e-3
    x = nominal.x_mm * math.cos(a) - nominal.y_mm * math.sin(a)
    y = nominal.x_mm * math.sin(a) + nominal.y_mm * math.cos(a)
    assert np.allclose(turned.x_mm, x, atol=1e-9) and np.allclose(turned.y_mm, y, atol=1e-9)
    c = machine_clock(4000, 1, 4, 8, 2)
    assert c.turn_rad(np.array([2, 3])).tolist() == pytest.approx([2 * math.pi * 8 / 4000, 2 * math.pi * 12 / 4000])


def test_a_step_whose_clock_is_not_its_swathes_is_refused(small, run_cli, tmp_path):
    prog = json.loads(small.read_text())
    st = next(s for s in prog["layers"][0]["steps"] if s["kind"] == "revolution" and s["image"])
    st["index_offset_counts"] += 1
    p = small.with_name("edited.json")
    p.write_text(json.dumps(prog))
    code, out, err = run_cli("replay", p, "--out", tmp_path / "o.png")
    assert code == 2 and err.strip().count("\n") == 0 and f"layer 0 step {st['n']}" in err
    assert "is not the one of its swathe and image" in err and not (tmp_path / "o.png").exists()
    code, out, err = run_cli("replay", small, "--angles", "sideways", "--out", tmp_path / "o.png")
    assert code == 2 and "--angles must be one of machine, nominal" in err


@pytest.mark.parametrize("field, bad", [("index_offset_counts", "x"), ("index_offset_counts", -5), ("index_offset_counts", 1.5),
                                        ("index_offset_counts", 2 ** 70), ("first_firing_index", 2.5), ("first_firing_index", None)])
def test_an_image_with_impossible_counts_is_refused_naming_it(small, field, bad):
    from rotoprint.errors import InputFileError

    prog = json.loads(small.read_text())
    rec = prog["layers"][0]["images"][0]
    rec[field] = bad
    for st in prog["layers"][0]["steps"]:  # the steps that print it say the same (their own check passes)
        if st.get("image") == rec["file"] and field == "index_offset_counts":
            st["index_offset_counts"] = bad
    p = small.with_name(f"bad-{field}.json")
    p.write_text(json.dumps(prog))
    with pytest.raises(InputFileError, match=f"image {rec['file']}: {field} must be a whole"):
        replay_program(p, layer=0)
