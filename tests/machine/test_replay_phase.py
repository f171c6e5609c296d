"""Replay of a print made with an angular phase (``PassOptions(phases=True)``, Python API): the
print's mount angle is the head's turned by the phase, and the machine program folds that turn
into the image's index offset. The replay must count the phase once: at the machine clock's
angles the drops land where ``simulate`` puts the print's own drops (to what the ratio and the
whole counts move them), not a phase further along the track."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from rotoprint.machine.program import write_machine_folder
from rotoprint.machine.replay import load_program, replay_layers, replay_program
from rotoprint.process.plan import plan_job
from rotoprint.rotary.simulate import simulate

from test_machine_program import _same, _small_job
from test_replay_clock import _make_exact

#: the phase, in whole encoder counts (2**20 a turn): 1.5 mrad, about 90 um along the track at 60 mm
PHASE_COUNTS = 250


@pytest.fixture(scope="module")
def phased(tmp_path_factory):
    """A small job's machine folder whose every print has its mount turned by the phase, as
    ``pass_prints`` makes the prints of a phased pass (``mount_angle_deg + phase_angle``)."""
    root = tmp_path_factory.mktemp("phased")
    plan = plan_job(_small_job())
    n_counts = plan.job.spec.machine.encoder_counts_per_rev
    delta_deg = PHASE_COUNTS * 360.0 / n_counts
    layer = plan.layer
    prints = {}

    def shifted(i):
        s = layer(i)
        pi = {k: tuple(dataclasses.replace(pr, mount_angle_deg=pr.mount_angle_deg + delta_deg) for pr in prs)
              for k, prs in s.pass_images.items()}
        prints[i] = pi
        return dataclasses.replace(s, pass_images=pi, images={k: v[0] for k, v in pi.items()})

    plan.layer = shifted
    write_machine_folder(plan, root / "m")
    return root / "m" / "program.json", prints, plan


def test_the_program_folds_the_phase_into_the_index_offset(phased):
    path, prints, plan = phased
    prog = json.loads(path.read_text())
    heads = {h["name"]: h for h in prog["heads"]}
    recs = [r for L in prog["layers"] for r in L["images"]]
    assert recs
    for r in recs:
        assert r["mount_angle_deg"] - heads[r["head"]]["mount_angle_deg"] == pytest.approx(PHASE_COUNTS * 360.0 / 2**20)


def test_a_phased_print_replays_where_simulate_puts_its_drops(phased):
    path, prints, plan = phased
    machine = replay_program(path, layer=0)
    nominal = replay_program(path, layer=0, angles="nominal")
    assert machine["images"]
    for a, b in zip(machine["images"], nominal["images"], strict=True):
        # the phase (250 counts, about 90 um at 60 mm) counted twice would move every drop by it;
        # once, only the ratio x m/d and the whole-count index move them, by under a micrometre
        assert 0.0 < a["max_drop_displacement_um"] < 1.0
        assert a["drops"] == b["drops"]
        assert abs(a["mean_error_um"] - b["mean_error_um"]) <= a["max_drop_displacement_um"]
        assert abs(a["iou"] - b["iou"]) < 5e-3


def test_a_phased_print_with_an_exact_clock_gives_simulates_figures(phased):
    path, prints, plan = phased
    prog = json.loads(path.read_text())
    _make_exact(prog)
    n_counts = prog["machine"]["encoder_counts_per_rev"]
    for L in prog["layers"]:  # an exact clock keeps the program's phase: whole counts before the index
        for r in L["images"]:
            r["index_offset_counts"] = (r["index_offset_counts"] - r["direction"] * PHASE_COUNTS) % n_counts
        idx = {r["file"]: r["index_offset_counts"] for r in L["images"]}
        for s in L["steps"]:
            if s["kind"] == "revolution" and s["image"]:
                s["index_offset_counts"] = idx[s["image"]]
    p = path.with_name("exact.json")
    p.write_text(json.dumps(prog))
    machine = replay_program(p)
    assert machine["clock"]["max_drop_displacement_um"] == pytest.approx(0.0, abs=1e-6)
    loaded = load_program(p)
    n = 0
    for lay, imgs in replay_layers(loaded, p):
        for im in imgs:
            r = next(x for x in machine["images"]
                     if (x["layer"], x["material"], x["ink"], x["interlace"]) == (lay["index"], im.material, im.ink, im.interlace))
            pr = prints[lay["index"]][(im.material, im.ink)][im.interlace]
            assert im.print.mount_angle_deg == pytest.approx(pr.mount_angle_deg)
            _same(r, {k: v for k, v in simulate(im.print, im.design).report.to_json().items()})
            n += 1
    assert n >= 2
    assert math.isfinite(machine["iou"])
