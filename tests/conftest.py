"""Shared fixtures. Real meshes are read from ../shared/data/meshes (never copied here).

The bundled examples' builds take 10-30 s each, so the tests that only read a build share
one per session (:func:`coil_build`, :func:`gas_build`, :func:`coil_demo`); their files are
made read-only so that a test that would change them fails instead (copy what you change).
"""

from __future__ import annotations

import contextlib
import io
import os
import stat
from dataclasses import dataclass
from pathlib import Path

import pytest
from typer.testing import CliRunner

ROOT = Path(__file__).resolve().parents[1]
SHARED_MESHES = ROOT.parent / "shared" / "data" / "meshes"
#: the builds' timestamp (SOURCE_DATE_EPOCH) in the shared builds and the golden digests
SOURCE_DATE_EPOCH = "1700000000"


@pytest.fixture(scope="session")
def shared_meshes() -> Path:
    if not SHARED_MESHES.is_dir():
        msg = f"real meshes not found at {SHARED_MESHES} (the shared/ folder beside the repo)"
        if os.environ.get("CI"):
            pytest.fail(msg + "; CI must have them")
        pytest.skip(msg)
    return SHARED_MESHES


def call_cli(*args) -> tuple[int, str, str]:
    """Call the CLI in-process: (exit code, stdout, stderr)."""
    from rotoprint.cli import _common
    from rotoprint.cli.main import main

    out, err = io.StringIO(), io.StringIO()
    old_c, old_o = _common.console.file, _common.out_console.file
    _common.console.file, _common.out_console.file = err, out
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            code = main([str(a) for a in args])
    finally:
        _common.console.file, _common.out_console.file = old_c, old_o
    return code, out.getvalue(), err.getvalue()


@pytest.fixture
def run_cli():
    """Call the CLI in-process: returns (exit_code, stdout, stderr)."""
    return call_cli


@dataclass(frozen=True)
class CliBuild:
    """A build made once per session by the CLI, from the working folder ``root``.

    ``job`` and ``out`` are absolute; the CLI was given them relative to ``root`` (so no
    absolute path is in the outputs: tests/test_golden_outputs.py hashes them)."""

    root: Path
    job: Path
    out: Path
    code: int
    stdout: str
    stderr: str
    #: the command line the CLI was given
    args: tuple[str, ...] = ()


@contextlib.contextmanager
def _in_folder(folder: Path, **env: str):
    old_cwd, old_env = Path.cwd(), {k: os.environ.get(k) for k in env}
    os.chdir(folder)
    os.environ.update(env)
    try:
        yield
    finally:
        os.chdir(old_cwd)
        for k, v in old_env.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def _set_writable(top: Path, writable: bool) -> None:
    w = stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH
    for p in [top, *top.rglob("*")]:
        if p.is_symlink():
            continue
        mode = p.stat().st_mode
        p.chmod((mode | stat.S_IWUSR) if writable else (mode & ~w))


def _example_build(tmp_path_factory, example: str, *args: str):
    """``rotoprint build job/EXAMPLE.toml --out build ARGS`` in a fresh working folder, with
    SOURCE_DATE_EPOCH set; the folder is read-only while the tests read it."""
    from rotoprint.pipeline.examples import write_example

    root = tmp_path_factory.mktemp(example)
    with _in_folder(root, SOURCE_DATE_EPOCH=SOURCE_DATE_EPOCH):
        job = write_example(example, Path("job"))
        argv = ("build", str(job), "--out", "build", *args)
        code, out, err = call_cli(*argv)
    _set_writable(root, False)
    try:
        yield CliBuild(root=root, job=root / job, out=root / "build", code=code, stdout=out, stderr=err, args=argv)
    finally:
        _set_writable(root, True)


@pytest.fixture(scope="session")
def coil_build(tmp_path_factory):
    """The coil sensor (the demo's job) as ``rotoprint build ... --no-check``: plan.json,
    report.html, layers/, overlays/, machine/ (tests/test_golden_outputs.py pins its digest)."""
    yield from _example_build(tmp_path_factory, "coil-sensor", "--no-check")


@pytest.fixture(scope="session")
def gas_build(tmp_path_factory):
    """The gas sensor as ``rotoprint build`` with its printability check (digest pinned too)."""
    yield from _example_build(tmp_path_factory, "gas-sensor")


@pytest.fixture(scope="session")
def coil_demo(tmp_path_factory):
    """``rotoprint demo --out DIR`` (the coil sensor with its check): a CliBuild whose ``out``
    is DIR/build."""
    root = tmp_path_factory.mktemp("demo")
    argv = ("demo", "--out", str(root / "d"))
    code, out, err = call_cli(*argv)
    _set_writable(root, False)
    try:
        yield CliBuild(root=root, job=root / "d" / "job" / "coil-sensor.toml", out=root / "d" / "build", code=code,
                       stdout=out, stderr=err, args=argv)
    finally:
        _set_writable(root, True)


__all__ = ["CliRunner", "ROOT", "SHARED_MESHES", "CliBuild", "call_cli"]
