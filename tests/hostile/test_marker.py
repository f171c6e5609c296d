"""The ownership markers themselves: what counts as ours and what does not."""

from __future__ import annotations

import io
import os
import zipfile

import numpy as np

from rotoprint.io.images import png_bytes
from rotoprint.io.ownership import (
    MARKER_NAME,
    file_not_ours,
    folder_not_ours,
    mark_json,
    mark_png,
    remove_ours,
    write_folder_marker,
    zip_marker,
)


def _ours(tmp_path):
    d = tmp_path / "o"
    (d / "sub").mkdir(parents=True)
    (d / "a.png").write_bytes(b"a" * 10)
    (d / "sub" / "b.txt").write_text("b")
    write_folder_marker(d, "test")
    return d


def test_a_folder_with_our_marker_and_nothing_else_is_ours(tmp_path):
    d = _ours(tmp_path)
    assert folder_not_ours(d, complete=True) is None
    (d / "sub" / "b.txt").unlink()  # a file of ours missing: still ours (half-removed), not complete
    assert folder_not_ours(d) is None and folder_not_ours(d, complete=True) is not None


def test_extra_changed_linked_or_unlisted_entries_are_not_ours(tmp_path):
    d = _ours(tmp_path)
    (d / "extra.txt").write_text("x")
    assert "extra.txt" in folder_not_ours(d)
    (d / "extra.txt").unlink()
    (d / "a.png").write_bytes(b"b" * 10)  # same size, other bytes
    assert "a.png" in folder_not_ours(d) and "changed" in folder_not_ours(d)
    d2 = _ours(tmp_path / "2")
    os.symlink("/etc", d2 / "link")
    assert "link" in folder_not_ours(d2)
    d3 = _ours(tmp_path / "3")
    (d3 / "newdir").mkdir()
    (d3 / "a2").write_text("")
    assert folder_not_ours(d3) is not None


def test_removal_cut_short_leaves_a_folder_that_is_still_ours(tmp_path):
    d = _ours(tmp_path)
    (d / "a.png").unlink()  # as if remove_ours was killed after the first file
    assert folder_not_ours(d) is None
    remove_ours(d)
    assert not d.exists()


def test_png_zip_json_markers(tmp_path):
    png = png_bytes(np.zeros((4, 5), np.uint8))
    p = tmp_path / "x.png"
    p.write_bytes(png)
    assert file_not_ours(p) == "it carries no rotoprint marker"
    p.write_bytes(mark_png(png, "t"))
    assert file_not_ours(p) is None
    other = png_bytes(np.full((4, 5), 9, np.uint8))
    marked = mark_png(png, "t")
    i = marked.find(b"tEXt") - 4  # our chunk moved onto another image: not ours
    j = other.rfind(b"IEND") - 4
    p.write_bytes(other[:j] + marked[i : marked.rfind(b"IEND") - 4] + other[j:])
    assert "does not match" in file_not_ours(p)

    z = tmp_path / "x.sl1"
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("a.png", b"123")
        zip_marker(zf, "t")
    z.write_bytes(buf.getvalue())
    assert file_not_ours(z) is None
    with zipfile.ZipFile(z, "a") as zf:  # a member added afterwards: not ours
        zf.writestr("b.txt", b"mine")
    assert file_not_ours(z) is not None

    j = tmp_path / "x.json"
    import json

    j.write_text(json.dumps(mark_json({"a": 1})))
    assert file_not_ours(j) is None
    j.write_text(json.dumps({**mark_json({"a": 1}), "a": 2}))
    assert file_not_ours(j) is not None
    assert file_not_ours(tmp_path / "o") is not None  # a folder is not a file of ours
    assert MARKER_NAME == "rotoprint-output.json"
