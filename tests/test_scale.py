"""Scale and faults: identical bytes with any number of workers or Dask, resume after a kill,
refusal before a run that cannot fit."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from rotoprint.devices import load_device
from rotoprint.examples import write_binary_stl
from rotoprint.io.layers import partial_path
from rotoprint.pipeline import RunOptions, write_layer_folder
from rotoprint.slicing import slice_mesh
from rotoprint.testing import torus_mesh, uv_sphere_mesh


def folder_bytes(path: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(path.iterdir())}


def _write(job, out, **kw):
    dev = job.device
    return write_layer_folder(job, out, device_name=dev.name, device=dev.model_dump(mode="json"), options={},
                              run=RunOptions(**kw))


@pytest.fixture(scope="module")
def job():
    mesh = torus_mesh(6.0, 2.0, 48, 24)
    return slice_mesh(mesh, load_device("perfactory-sxga"), layer_height_mm=0.4)


def test_identical_bytes_1_and_2_workers(job, tmp_path):
    a, b = tmp_path / "one", tmp_path / "two"
    _write(job, a, workers=1)
    _write(job, b, workers=2)
    fa, fb = folder_bytes(a), folder_bytes(b)
    assert len(fa) == len(job) + 2 and fa == fb


def test_identical_bytes_on_a_dask_local_cluster(job, tmp_path):
    import distributed  # a test dependency: a broken install must fail, not skip
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=":0") as cluster:  # any free port: two workers start clusters at once
        d = tmp_path / "dask"
        _write(job, d, scheduler=cluster.scheduler_address)
    a = tmp_path / "one"
    _write(job, a, workers=1)
    assert folder_bytes(a) == folder_bytes(d)


def test_unreachable_scheduler_is_a_clear_error(job, tmp_path, monkeypatch):
    from rotoprint import ConfigError
    from rotoprint.pipeline import producer

    monkeypatch.setattr(producer, "DASK_CONNECT_TIMEOUT_S", 1.0)
    with pytest.raises(ConfigError, match="cannot reach the Dask scheduler|did not answer within"):
        _write(job, tmp_path / "x", scheduler="tcp://127.0.0.1:9")


def test_resume_after_a_kill(tmp_path):
    mesh_path = tmp_path / "sphere.stl"
    write_binary_stl(mesh_path, uv_sphere_mesh(9.0, 48, 96).triangles)
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "rotoprint.cli.main", "slice", str(mesh_path), "-d", "perfactory-sxga",
           "--layer-height", "0.03", "-o", str(out), "-q"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    journal = partial_path(out) / "journal.jsonl"
    deadline = time.time() + 60
    while time.time() < deadline:
        if journal.exists() and len(journal.read_text().splitlines()) > 40:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_journal = len(journal.read_text().splitlines()) - 1
    assert 40 <= n_journal < 600, "the run was not killed mid-way"
    assert not out.exists()  # never half-written under its final name
    # damage one finished layer: resume must notice it and make it again
    victim = sorted(partial_path(out).glob("layer_*.png"))[3]
    victim.write_bytes(b"garbage")
    resumed = subprocess.run(cmd[:-1] + ["--resume", "-v"], capture_output=True, text=True, env=os.environ)
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming:" in resumed.stderr
    kept = int(resumed.stderr.split("resuming:")[1].split("of")[0])
    assert kept == n_journal - 1
    clean = tmp_path / "clean"
    subprocess.run(cmd[:-2] + [str(clean), "-q"], check=True)
    assert folder_bytes(out) == folder_bytes(clean)
    assert not partial_path(out).exists()


def test_refused_up_front_when_the_disk_is_too_small(job, tmp_path, monkeypatch, run_cli):
    import shutil

    from rotoprint.io import resumable as layers_mod

    real = shutil.disk_usage

    def tiny(path):
        u = real(path)
        return type(u)(u.total, u.used, 1000)

    monkeypatch.setattr(layers_mod.shutil, "disk_usage", tiny)
    mesh_path = tmp_path / "t.stl"
    write_binary_stl(mesh_path, torus_mesh(6.0, 2.0, 24, 12).triangles)
    code, _, err = run_cli("slice", mesh_path, "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", tmp_path / "o")
    assert code == 2 and "only 1000 B is free" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists() and not partial_path(tmp_path / "o").exists()


def test_refused_up_front_when_memory_is_too_small(job, tmp_path, monkeypatch):
    from rotoprint import ResourceError
    from rotoprint.io import resumable as layers_mod

    monkeypatch.setattr(layers_mod, "available_memory_bytes", lambda: 10 * 2**20)
    with pytest.raises(ResourceError, match="use fewer --workers"):
        _write(job, tmp_path / "m", workers=4)
    assert not (tmp_path / "m").exists()


def test_manifest_records_checksums(job, tmp_path):
    import hashlib

    out = tmp_path / "o"
    man = _write(job, out)
    for rec in man["layers"]:
        assert hashlib.sha256((out / rec["file"]).read_bytes()).hexdigest() == rec["sha256"]
    assert json.loads((out / "manifest.json").read_text())["layer_count"] == len(job)


# ---------------------------------------------------------------- DLP archives
@pytest.fixture
def torus_stl(tmp_path):
    p = tmp_path / "torus.stl"
    write_binary_stl(p, torus_mesh(6.0, 2.0, 48, 24).triangles)
    return p


@pytest.mark.parametrize("mode,erm", [("coverage", False), ("smooth", True)])
def test_sl1_identical_bytes_1_2_workers_and_dask(run_cli, torus_stl, tmp_path, monkeypatch, mode, erm):
    import distributed  # a test dependency: a broken install must fail, not skip
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    base = ["dlp", torus_stl, "-d", "perfactory-sxga", "--layer-height", "0.5", "--mode", mode, "-q"] + (["--erm"] if erm else [])
    outs = {}
    for name, extra in (("w1", []), ("w2", ["--workers", "2"])):
        (tmp_path / name).mkdir()
        outs[name] = tmp_path / name / "job.sl1"  # same name: jobDir comes from it
        code, _, err = run_cli(*base, "-o", outs[name], *extra)
        assert code == 0, err
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=":0") as cluster:  # any free port: two workers start clusters at once
        (tmp_path / "dask").mkdir()
        outs["dask"] = tmp_path / "dask" / "job.sl1"
        code, _, err = run_cli(*base, "-o", outs["dask"], "--scheduler", cluster.scheduler_address)
        assert code == 0, err
    data = {k: v.read_bytes() for k, v in outs.items()}
    assert data["w1"] == data["w2"] == data["dask"]
    from rotoprint.io.archives import read_job

    job = read_job(outs["w1"])
    assert len(job) == 8 * (2 if erm else 1)


def test_sl1_resume_after_a_kill(tmp_path):
    mesh_path = tmp_path / "sphere.stl"
    write_binary_stl(mesh_path, uv_sphere_mesh(9.0, 48, 96).triangles)
    out = tmp_path / "job.sl1"
    cmd = [sys.executable, "-m", "rotoprint.cli.main", "dlp", str(mesh_path), "-d", "perfactory-sxga",
           "--layer-height", "0.05", "--mode", "coverage", "-o", str(out), "-q"]
    env = {**os.environ, "SOURCE_DATE_EPOCH": "1700000000"}
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    journal = partial_path(out) / "journal.jsonl"
    deadline = time.time() + 60
    while time.time() < deadline:
        if journal.exists() and len(journal.read_text().splitlines()) > 30:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    n_journal = len(journal.read_text().splitlines()) - 1
    assert 30 <= n_journal < 360, "the run was not killed mid-way"
    assert not out.exists()
    resumed = subprocess.run(cmd[:-1] + ["--resume", "-v"], capture_output=True, text=True, env=env)
    assert resumed.returncode == 0, resumed.stderr
    assert f"resuming: {n_journal} of 360" in resumed.stderr
    (tmp_path / "clean").mkdir()
    clean = tmp_path / "clean" / "job.sl1"
    subprocess.run(cmd[:-2] + [str(clean), "-q"], check=True, env=env)
    assert out.read_bytes() == clean.read_bytes()
    assert not partial_path(out).exists()


def test_a_new_task_never_gets_an_old_tasks_job():
    """Regression: the worker-side job cache once keyed tasks by id(), which Python reuses."""
    from rotoprint.pipeline.producer import LayerSource, render_one
    from rotoprint.pipeline.tasks import MeshJob, PlainLayer, layer_source

    mesh = torus_mesh(6.0, 2.0, 24, 12)
    dev = load_device("perfactory-sxga")
    for lh, n in ((1.0, 4), (0.5, 8), (0.25, 16)):
        mj = MeshJob.of(slice_mesh(mesh, dev, layer_height_mm=lh))
        task = layer_source(mj, PlainLayer())
        bare = LayerSource(MeshJob(mj.vertices, mj.faces, None, mj.device, mj.slice_options), PlainLayer())  # no key
        for t in (task, bare):
            assert render_one(t, n - 1).index == n - 1  # the last layer exists for this job
        del task, bare


# ---------------------------------------------------------------- direct rotary slicing
def test_rotary_slices_identical_bytes_with_workers_and_resumable(run_cli, torus_stl, tmp_path, monkeypatch):
    base = ["slice", torus_stl, "-d", "omnidot760", "--rotary", "--tilt", "20", "--radius", "40",
            "--layer-height", "0.5", "--reference-images", "-q"]
    outs = {}
    for name, extra in (("w1", []), ("w2", ["--workers", "2"])):
        (tmp_path / name).mkdir()
        outs[name] = tmp_path / name / "rot"  # same folder name: sidecars name the reference image's path
        code, _, err = run_cli(*base, "-o", outs[name], *extra)
        assert code == 0, err
    a, b = folder_bytes(outs["w1"]), folder_bytes(outs["w2"])
    assert len(a) == 8 * 3 + 2  # per layer: print image, sidecar, reference image; the manifest and our marker
    assert a == b
    # interrupt a run after a few layers, then resume it
    from rotoprint.io import resumable

    real_record = resumable.PartialOutput.record
    calls = {"n": 0}

    def record_then_crash(self, index, files, **payload):
        rec = real_record(self, index, files, **payload)
        calls["n"] += 1
        if calls["n"] == 3:
            raise KeyboardInterrupt  # stands for a kill: nothing is cleaned up
        return rec

    (tmp_path / "r").mkdir()
    out = tmp_path / "r" / "rot"
    monkeypatch.setattr(resumable.PartialOutput, "record", record_then_crash)
    code, _, _ = run_cli(*base, "-o", out)
    assert code == 130  # interrupted: the CLI aborts and leaves the journal for --resume
    monkeypatch.setattr(resumable.PartialOutput, "record", real_record)
    assert not out.exists() and partial_path(out).exists()
    code, _, err = run_cli(*base, "-o", out, "--resume")
    assert code == 0, err
    assert folder_bytes(out) == a
    assert not partial_path(out).exists()
    # the folder can be moved: simulate finds the reference image next to the sidecar
    moved = tmp_path / "moved"
    out.rename(moved)
    code, stdout, err = run_cli("simulate", moved / "layer_00003.png", "-o", tmp_path / "ov.png", "--json")
    assert code == 0, err
    assert json.loads(stdout)["iou"] > 0.9
