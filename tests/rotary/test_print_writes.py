"""``write_print`` and ``transform_passes`` (pipeline/prints) share one check-then-write: every
path is checked (not an input, not a file that is not provably ours) before the first file
is written; with ``force`` the user's file is replaced, and our own files are replaced
without it."""

from __future__ import annotations

import numpy as np
import pytest

from rotoprint import load_device
from rotoprint.errors import InputFileError
from rotoprint.io.ownership import file_not_ours
from rotoprint.pipeline.prints import transform_passes, write_print
from rotoprint.rotary import Placement, transform_exact
from rotoprint.rotary.files import print_files
from rotoprint.rotary.interlace import PassOptions
from rotoprint.rotary.options import RotarySetup

PX = 25.4 / 360


def _folder(p):
    return {q.name: q.read_bytes() for q in p.iterdir()}


def test_write_print_checks_every_file_before_the_first_and_force_replaces(tmp_path):
    head = load_device("omnidot760").head
    d = np.full((30, 30), 255, np.uint8)
    pr = transform_exact(d, head, Placement(30, 30, PX, PX, inner_radius_mm=60.0), tilt_deg=20.0)
    names = list(print_files(pr, "o.png")[0])
    assert len(names) >= 2 and names[0] == "o.png"
    (tmp_path / names[-1]).write_bytes(b"the user's\n")  # where the last file would go
    before = _folder(tmp_path)
    with pytest.raises(InputFileError, match=names[-1]):
        write_print(pr, tmp_path / "o.png")
    assert _folder(tmp_path) == before  # not even the first file
    side = write_print(pr, tmp_path / "o.png", force=True)
    assert sorted(_folder(tmp_path)) == sorted(names) and side["swathes"]
    assert all(file_not_ours(tmp_path / n) is None for n in names)
    write_print(pr, tmp_path / "o.png")  # our own now: replaced without force


def test_transform_passes_checks_every_pass_before_the_first_and_force_replaces(tmp_path):
    d = np.full((20, 20), 255, np.uint8)
    pl = Placement(20, 20, PX, PX, inner_radius_mm=60.0)
    opts = PassOptions(RotarySetup(tilt_deg=0.0), passes=2)
    user = tmp_path / "o-p2.png"  # pass 2's image
    user.write_bytes(b"the user's\n")
    before = _folder(tmp_path)
    with pytest.raises(InputFileError, match="o-p2.png"):
        transform_passes(d, "omnidot760", pl, tmp_path / "o.png", opts)
    assert _folder(tmp_path) == before
    m = transform_passes(d, "omnidot760", pl, tmp_path / "o.png", opts, force=True)
    assert m["files"] == ["o-p1.json", "o-p2.json"] and file_not_ours(user) is None
    assert (tmp_path / "o-passes.json").exists() and (tmp_path / "o-p1.png").exists()
    transform_passes(d, "omnidot760", pl, tmp_path / "o.png", opts)  # our own now
