"""write_example (used by `rotoprint demo`): atomic, and never replaces what it did not write."""

from __future__ import annotations

import pytest

from rotoprint.errors import InputFileError
from rotoprint.pipeline.examples import write_example
from rotoprint.process.examples import EXAMPLES, example_files


def _snapshot(folder):
    return {p.name: p.read_bytes() for p in folder.iterdir()}


def test_writes_the_example_and_rewrites_its_own_copy(tmp_path):
    folder = tmp_path / "job"
    job = write_example("coil-sensor", folder)
    assert job == folder / EXAMPLES["coil-sensor"][0]
    assert _snapshot(folder) == example_files("coil-sensor")  # no temporary left beside them
    assert write_example("coil-sensor", folder) == job  # an unchanged earlier copy is ours: rewritten
    assert _snapshot(folder) == example_files("coil-sensor")


def test_refuses_an_edited_job_file(tmp_path):
    folder = tmp_path / "job"
    job = write_example("coil-sensor", folder)
    job.write_text(job.read_text() + "\n# my change\n")
    before = _snapshot(folder)
    with pytest.raises(InputFileError) as ei:
        write_example("coil-sensor", folder)
    assert str(ei.value) == f"{job}: differs from the coil-sensor example (edited?); refusing to overwrite it"
    assert _snapshot(folder) == before


def test_refuses_a_folder_with_other_files(tmp_path):
    folder = tmp_path / "job"
    folder.mkdir()
    (folder / "mine.toml").write_text("keep me")
    with pytest.raises(InputFileError, match=r"holds files that are not the gas-sensor example \(mine.toml\)"):
        write_example("gas-sensor", folder)
    assert _snapshot(folder) == {"mine.toml": b"keep me"}


def test_refuses_a_file_in_place_of_the_folder(tmp_path):
    f = tmp_path / "job"
    f.write_text("x")
    with pytest.raises(InputFileError, match="exists and is not a folder"):
        write_example("coil-sensor", f)
    assert f.read_text() == "x"


def test_a_failed_write_leaves_no_job_file_and_no_temporaries(tmp_path, monkeypatch):
    import rotoprint.io.atomic as atomic

    calls = []
    real = atomic.os.replace

    def failing_replace(src, dst):
        calls.append(dst)
        if len(calls) == 2:
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(atomic.os, "replace", failing_replace)
    folder = tmp_path / "job"
    with pytest.raises(OSError):
        write_example("coil-sensor", folder)
    assert len(calls) == 2 and calls[-1] == folder / "coil-sensor.toml"  # the job file is renamed last
    # no job file without its meshes, no temporary left; what is there is the example's own
    assert _snapshot(folder) == {"coil-body.stl": example_files("coil-sensor")["coil-body.stl"]}
    monkeypatch.undo()
    assert write_example("coil-sensor", folder).exists()  # and a rerun completes it


def test_demo_refuses_an_edited_job_without_a_traceback(run_cli, tmp_path):
    job_dir = tmp_path / "d" / "job"
    job = write_example("coil-sensor", job_dir)
    job.write_text("# mine\n")
    code, _, err = run_cli("demo", "--out", tmp_path / "d")
    assert code == 2
    assert err.strip() == f"rotoprint: error: {job}: differs from the coil-sensor example (edited?); refusing to overwrite it"
    assert job.read_text() == "# mine\n" and not (tmp_path / "d" / "build").exists()


#: SHA-256 of each bundled job file. The texts are put together from shared pieces
#: (process/_job_pieces.py); a change to a piece must not
#: change a job by accident. When a job changes on purpose, update its digest here and add the
#: old one to pipeline/examples._EARLIER_SHA256, so a user's earlier copy is not refused as
#: "edited" by the next `rotoprint demo` (test below).
JOB_SHA256 = {
    "coil-sensor": "aab679f231df7a4e268824b319cee919bcd91635ad6bb423ebc72e63e679bee9",
    "gas-sensor": "eef40ecbf0764936217a4af07aa6c4a437696d2431563c68d37164ae6a788db0",
    "cad-coil": "5e06ad979524a15be1d3b09add05096961afb28d06068dfb1511c0b6fd1c465e",
}


def test_the_bundled_job_files_are_the_ones_users_have():
    import hashlib
    import tomllib

    assert set(JOB_SHA256) == set(EXAMPLES)
    heads = {}
    for name, (job, _, _) in EXAMPLES.items():
        data = example_files(name)[job]
        assert hashlib.sha256(data).hexdigest() == JOB_SHA256[name], name
        heads[name] = tomllib.loads(data.decode("utf-8"))["printer"]["heads"]
    assert heads["cad-coil"] == heads["coil-sensor"][:4] == heads["gas-sensor"][:4]  # the shared H1-H4


def test_an_earlier_releases_job_file_is_replaced_not_refused(tmp_path):
    import hashlib

    from rotoprint.pipeline.examples import _EARLIER_SHA256

    new = example_files("coil-sensor")["coil-sensor.toml"]
    # the job as releases before the equalise comment's change wrote it (its digest pinned there)
    old = new.replace(b"# the same ink per mm2 at every radius: the passes print their shares of the union-equalised film",
                      b"# the same drops per mm2 at every radius (inner tracks thinned)")
    assert old != new and hashlib.sha256(old).hexdigest() == "35bfeb1c5eb65af2d6552941a28471818ba3c22b7d3b132f2a42ea1d32e7475e"
    assert hashlib.sha256(old).hexdigest() in _EARLIER_SHA256
    assert not ({hashlib.sha256(example_files(n)[j]).hexdigest() for n, (j, _, _) in EXAMPLES.items()} - _EARLIER_SHA256
                - set(JOB_SHA256.values()))
    folder = tmp_path / "job"
    write_example("coil-sensor", folder)
    (folder / "coil-sensor.toml").write_bytes(old)
    write_example("coil-sensor", folder)  # our own earlier copy: replaced
    assert (folder / "coil-sensor.toml").read_bytes() == new
    (folder / "coil-sensor.toml").write_bytes(old + b"# mine\n")  # an edit of it is still refused
    with pytest.raises(InputFileError, match="edited"):
        write_example("coil-sensor", folder)
