"""Hostile print sidecars: a wrong field is one line in words naming the file and the field.

A sidecar (the JSON beside a rotary print's images, read by :func:`rotoprint.rotary.files.read_print`)
whose head held a wrong type or an out-of-range number was refused with pydantic's own text
("sidecar field head.nozzles: Input should be greater than 0"), and a missing key as
"sidecar is incomplete or invalid: KeyError: 'dphi_rad'". Each now names the field by its path
and says what it must be (:mod:`rotoprint.io.records`), exit 2, nothing written.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from _bounds_helpers import assert_refused, run_cli_bounded, tree
from rotoprint.io.images import write_png
from rotoprint.rotary.testimage import test_design as make_design


@pytest.fixture(scope="module")
def printed(tmp_path_factory) -> Path:
    """A folder holding a one-swathe rotary print p.png and its sidecar p.json."""
    root = tmp_path_factory.mktemp("print")
    write_png(root / "d.png", make_design(120))
    run = run_cli_bounded("transform", "d.png", "--device", "omnidot760", "--tilt", "20", "--radius", "60",
                          "--out", "p.png", cwd=root)
    assert run.code == 0, run.err
    (root / "d.png").unlink()
    return root


def _pop(key: str):
    return lambda t: t.pop(key)


#: (the field's place in the sidecar, its edit, what the message says)
CASES = [
    (("head",), lambda t: t.update(nozzles="many"), "sidecar field 'head.nozzles' must be a whole number, got 'many'"),
    (("head",), lambda t: t.update(swathe_mm=-2.5), "sidecar field 'head.swathe_mm' must be greater than 0.0, got -2.5"),
    (("head",), _pop("row_separation_mm"), "sidecar field 'head.row_separation_mm' is missing (it is required)"),
    # was "tilt 20 deg is at or beyond the maximum tilt 85.50 deg of this head": the head, not the tilt, is wrong
    (("head",), lambda t: t.update(nozzles=1), "sidecar field swathes[0].nozzles is 764, more than the head has (head.nozzles 1)"),
    ((), lambda t: t.update(head=[1, 2]), "sidecar field 'head' must be a table, got a list"),
    (("swathes", 0), _pop("dphi_rad"), "swathes[0] has no key 'dphi_rad': the sidecar is incomplete"),
    (("swathes", 0), lambda t: t.update(pivot_radius_mm=-60), "sidecar field swathes[0].pivot_radius_mm must be > 0, got -60"),
]


@pytest.mark.parametrize(("at", "edit", "said"), CASES, ids=[c[2].split(" must")[0].split(" is ")[0] for c in CASES])
def test_a_bad_sidecar_field_is_one_line_in_words(printed, tmp_path, at, edit, said):
    shutil.copytree(printed, tmp_path / "w")
    w = tmp_path / "w"
    side = json.loads((w / "p.json").read_text())
    table = side
    for k in at:
        table = table[k]
    edit(table)
    (w / "p.json").write_text(json.dumps(side))
    before = tree(w)
    run = run_cli_bounded("simulate", "p.png", "--out", "ov.png", cwd=w)
    line = assert_refused(run, "p.json:", said)
    for raw in ("Input should", "Field required", "KeyError", "TypeError", "incomplete or invalid"):
        assert raw not in line, line
    assert tree(w) == before


def test_a_passes_manifest_listing_one_print_twice_is_refused(printed, tmp_path):
    """Two entries of one file would deposit one print twice and call it two passes."""
    from rotoprint.rotary.interlace import PASSES_FORMAT

    shutil.copytree(printed, tmp_path / "w")
    w = tmp_path / "w"
    (w / "m-passes.json").write_text(json.dumps({"format": PASSES_FORMAT, "files": ["p.json", "p.json"]}))
    before = tree(w)
    run = run_cli_bounded("simulate", "m-passes.json", "--out", "ov.png", cwd=w)
    assert_refused(run, "m-passes.json:", "passes manifest field files lists p.json twice")
    assert tree(w) == before
    from rotoprint.rotary.interlace import read_passes

    (w / "m-passes.json").write_text(json.dumps({"format": PASSES_FORMAT, "files": ["p.json", "q.json"]}))
    assert read_passes(w / "m-passes.json") == [w / "p.json", w / "q.json"]
