"""Hostile device files and machine programs: one line in words naming the file and the field.

A device TOML that is empty or holds a wrong type was refused with pydantic's own text
("Unable to extract tag using discriminator 'kind'", "Input should be a valid integer, unable
to parse string as an integer"); a machine program missing a key was refused as
"KeyError: 'clock'", or (a key of its totals) ended in a traceback. Each now names the field
by its path and says what it must be, exit 2, nothing written.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from _bounds_helpers import assert_refused, run_cli_bounded, tree
from rotoprint.examples import write_binary_stl
from rotoprint.testing import box_triangles

HEAD = 'kind = "inkjet"\nname = "h"\n[head]\nnozzles = 100\nswathe_mm = 10\nrow_separation_mm = 1\n'


@pytest.mark.parametrize(("text", "said"), [
    ("", "dev.toml: no device kind (the file is empty): a device file says kind = \"inkjet\" or kind = \"projector\""),
    ('name = "x"\n', "no device kind: a device file says kind"),
    ('kind = "laser"\nname = "x"\n', "kind must be \"inkjet\" or \"projector\", got 'laser'"),
    (HEAD.replace("nozzles = 100", 'nozzles = "many"'), "device field 'head.nozzles' must be a whole number, got 'many'"),
    (HEAD.replace("nozzles = 100", "nozzles = 0"), "device field 'head.nozzles' must be greater than 0, got 0"),
    (HEAD.replace("nozzles = 100", "nozzles = inf"), "device field 'head.nozzles' must be a finite number, got inf"),
    (HEAD.replace("swathe_mm = 10", 'swathe_mm = "wide"'), "device field 'head.swathe_mm' must be a number, got 'wide'"),
    (HEAD.replace("row_separation_mm = 1\n", ""), "device field 'head.row_separation_mm' is missing (it is required)"),
    (HEAD + "nozzle_count = 3\n", "device field 'head.nozzle_count' is not a known field"),
    (HEAD + "dead_nozzles = [1, \"a\"]\n", "device field 'head.dead_nozzles[1]' must be a whole number, got 'a'"),
    (HEAD + "dead_nozzles = 7\n", "device field 'head.dead_nozzles' must be a list, got a whole number"),
    ('kind = "inkjet"\nname = "x"\nhead = 5\n', "device field 'head' must be a table, got a whole number"),
    ('kind = "projector"\nname = "p"\n[projector]\npixels_x = 10\npixels_y = 10\nwidth_mm = 10\nheight_mm = 10\n'
     'orientation = "diagonal"\n', "device field 'projector.orientation' must be one of 'landscape' or 'portrait', got 'diagonal'"),
])
def test_a_bad_device_file_is_one_line_in_words(tmp_path, text, said):
    write_binary_stl(tmp_path / "box.stl", box_triangles((2, 2, 1)))
    (tmp_path / "dev.toml").write_text(text)
    before = tree(tmp_path)
    run = run_cli_bounded("slice", "box.stl", "-d", "dev.toml", "--layer-height", "0.5", "-o", "out", cwd=tmp_path)
    line = assert_refused(run, "dev.toml:", said)
    for raw in ("Input should", "Field required", "Extra inputs", "discriminator", "Unable to extract"):
        assert raw not in line, line
    assert tree(tmp_path) == before


def _job() -> dict:
    return {
        "job": {"name": "tiny", "layer_height_mm": 0.05},
        "printer": {"device": "omnidot760", "tilt_deg": 10.0, "heads": [{"name": "A", "ink": "ammonium_sulphate"},
                                                                      {"name": "B", "ink": "calcium_chloride"}]},
        "placement": {"inner_radius_mm": 50.0},
        "parts": [{"name": "p", "material": "plaster", "shape": {"kind": "box", "size_mm": [2, 2, 0.05], "origin_mm": [0, 0, 0]}}],
        "process": {"cycles_per_layer": {"plaster": 1}},
    }


@pytest.fixture(scope="module")
def program(tmp_path_factory) -> Path:
    """A machine folder (program.json and its packed files) of a one-layer job."""
    from rotoprint.machine.program import write_machine_folder
    from rotoprint.process.job import parse_job
    from rotoprint.process.plan import plan_job

    root = tmp_path_factory.mktemp("prog") / "m"
    write_machine_folder(plan_job(parse_job(_job(), base_dir=".", source="tiny.toml")), root)
    return root


#: (path of the key removed, what the message says)
MISSING = [
    (["heads"], "the program has no key 'heads': the program is incomplete"),
    (["machine"], "the program has no key 'machine'"),
    (["heads", 0, "swathes"], "heads[0] has no key 'swathes'"),
    (["heads", 0, "swathes", 0, "clock"], "heads[0].swathes[0] has no key 'clock'"),
    (["packing", "bits_per_nozzle"], "packing has no key 'bits_per_nozzle'"),
    (["layers", 0, "images", 0, "file"], "layers[0].images[0] has no key 'file'"),
    (["layers", 0, "images", 0, "band_mm"], "layer 0: a record has no key 'band_mm'"),
    (["layers", 0, "steps", 0, "kind"], "layers[0].steps[0] has no key 'kind'"),
    (["totals", "time_s"], "totals has no key 'time_s'"),  # was a traceback
    (["totals", "flagged_clocks"], "totals has no key 'flagged_clocks'"),  # was a traceback
]


def _replay_edited(tmp_path, program: Path, edit) -> str:
    """``replay`` of a copy of the machine folder with ``edit`` applied to its program."""
    m = tmp_path / "m"
    shutil.copytree(program, m)
    prog = json.loads((m / "program.json").read_text())
    edit(prog)
    (m / "program.json").write_text(json.dumps(prog))
    before = tree(tmp_path)
    run = run_cli_bounded("replay", "m/program.json", "--out", "o.png", cwd=tmp_path)
    line = assert_refused(run, "m/program.json:")
    assert "KeyError" not in line and "TypeError" not in line
    assert tree(tmp_path) == before
    return line


@pytest.mark.parametrize(("path", "said"), MISSING, ids=[".".join(map(str, p)) for p, _ in MISSING])
def test_a_program_missing_a_key_names_where(tmp_path, program, path, said):
    def edit(prog):
        o = prog
        for k in path[:-1]:
            o = o[k]
        del o[path[-1]]

    line = _replay_edited(tmp_path, program, edit)
    assert said in line, line


@pytest.mark.parametrize(("path", "value", "said"), [
    (["heads"], 5, "heads must be a list, got 5"),
    (["totals"], [1], "totals must be a table"),
    (["machine", "encoder_counts_per_rev"], "lots", "field 'machine.encoder_counts_per_rev' must be a whole number, got 'lots'"),
    (["machine", "bogus"], 1, "field 'machine.bogus' is not a known field"),
    (["heads", 0, "model", "nozzles"], "many", "field 'heads[0].model.nozzles' must be a whole number, got 'many'"),
])
def test_a_program_with_a_wrong_type_names_the_field(tmp_path, program, path, value, said):
    def edit(prog):
        o = prog
        for k in path[:-1]:
            o = o[k]
        o[path[-1]] = value

    line = _replay_edited(tmp_path, program, edit)
    assert said in line, line
