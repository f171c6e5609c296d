"""Shared fixtures. Real meshes are read from ../shared/data/meshes (never copied here).

The bundled examples' builds take 10-30 s each, so the tests that only read a build share
one per session (:func:`coil_build`, :func:`gas_build`, :func:`coil_demo`); their files are
made read-only so that a test that would change them fails instead (copy what you change).

Under pytest-xdist (``make test`` runs ``pytest -n 2 --dist loadgroup``) a shared build is
still made once per run: the first worker that needs it builds it under a file lock in the
run's common temporary folder, the others wait and read it (:func:`_once_per_run`). With
``--dist loadgroup`` the tests that use a shared build are one unit of work, scheduled first,
so that one worker makes and reads them while the other runs the rest
(:func:`pytest_xdist_make_scheduler`).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
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


#: the session fixtures whose tests form one unit of work under xdist (one worker makes and reads them)
SHARED_BUILDS = ("coil_build", "gas_build", "coil_demo")


def _uses_shared_build(item) -> bool:
    return any(f in SHARED_BUILDS for f in getattr(item, "fixturenames", ()))


def _group_file(config) -> Path:
    """(controller) where the workers list the tests that read a shared build."""
    if not hasattr(config, "_rotoprint_group_dir"):
        import tempfile

        config._rotoprint_group_dir = Path(tempfile.mkdtemp(prefix="rotoprint-xdist-"))
    return config._rotoprint_group_dir / "shared-build-tests.json"


def pytest_unconfigure(config):
    d = getattr(config, "_rotoprint_group_dir", None)
    if d is not None:
        shutil.rmtree(d, ignore_errors=True)


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node):
    """(xdist controller) each worker is told where to list the tests of the group, and where
    the workers' jit compile locks are."""
    listed = _group_file(node.config)
    (listed.parent / "jit-locks").mkdir(exist_ok=True)
    node.workerinput["rotoprint_group_file"] = str(listed)
    node.workerinput["rotoprint_jit_locks"] = str(listed.parent / "jit-locks")


def pytest_configure(config):
    """(xdist worker) a jit kernel that is not in the disk cache yet (the tests' own reference
    kernels in a fresh clone, a signature the warm-up did not touch) is compiled by one worker
    while the other waits and then loads it from the cache (rotoprint._warmup.share_compiles)."""
    locks = getattr(config, "workerinput", {}).get("rotoprint_jit_locks")
    if locks:
        from rotoprint._warmup import share_compiles

        share_compiles(locks)


def pytest_collection_modifyitems(config, items):
    """(xdist worker) list the node ids of the tests that use a shared build, for the
    controller's scheduler (every worker collects the same tests and writes the same list)."""
    where = getattr(config, "workerinput", {}).get("rotoprint_group_file")
    if where:
        tmp = Path(f"{where}.{os.getpid()}")
        tmp.write_text(json.dumps([it.nodeid for it in items if _uses_shared_build(it)]))
        os.replace(tmp, where)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """``--dist loadgroup``: the tests that use a shared build are one unit of work, sent to
    one worker first (the largest unit goes first), every other test its own unit. (xdist's
    own ``xdist_group`` marks rename node ids, which pytest 9.2 no longer allows.)"""
    if config.getvalue("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadScopeScheduling

    listed = _group_file(config)

    class SharedBuildsTogether(LoadScopeScheduling):
        _group: set[str] | None = None

        def _split_scope(self, nodeid: str) -> str:
            if self._group is None:
                self._group = set(json.loads(listed.read_text())) if listed.exists() else set()
            return "shared builds" if nodeid in self._group else nodeid

    return SharedBuildsTogether(config, log)


def _once_per_run(tmp_path_factory, name: str, make) -> CliBuild:
    """``make(root)`` -> CliBuild, once per run even across pytest-xdist workers.

    Without xdist: in a fresh ``tmp_path_factory`` folder. Under xdist: in ``name`` of the
    run's common temporary folder (the workers' basetemp's parent), under an exclusive
    ``fcntl`` lock; the first worker builds and writes ``name.json`` (the CliBuild's fields),
    the others wait on the lock and read it. The folder is made read-only once built."""
    if os.environ.get("PYTEST_XDIST_WORKER") is None:
        root = tmp_path_factory.mktemp(name)
        b = make(root)
        _set_writable(root, False)
        return b
    import fcntl

    common = tmp_path_factory.getbasetemp().parent
    root, record = common / name, common / f"{name}.json"
    with open(common / f"{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if record.exists():
            d = json.loads(record.read_text())
            return CliBuild(**{k: Path(v) if k in ("root", "job", "out") else tuple(v) if k == "args" else v
                               for k, v in d.items()})
        if root.exists():  # a worker that failed to build before: build again from scratch
            _set_writable(root, True)
            shutil.rmtree(root)
        root.mkdir()
        b = make(root)
        _set_writable(root, False)
        record.write_text(json.dumps({k: str(v) if isinstance(v, Path) else v for k, v in b.__dict__.items()}))
        return b


def _example_build(tmp_path_factory, example: str, *args: str):
    """``rotoprint build job/EXAMPLE.toml --out build ARGS`` in a fresh working folder, with
    SOURCE_DATE_EPOCH set; the folder is read-only while the tests read it."""
    from rotoprint.pipeline.examples import write_example

    def make(root: Path) -> CliBuild:
        with _in_folder(root, SOURCE_DATE_EPOCH=SOURCE_DATE_EPOCH):
            job = write_example(example, Path("job"))
            argv = ("build", str(job), "--out", "build", *args)
            code, out, err = call_cli(*argv)
        return CliBuild(root=root, job=root / job, out=root / "build", code=code, stdout=out, stderr=err, args=argv)

    b = _once_per_run(tmp_path_factory, example, make)
    try:
        yield b
    finally:
        _set_writable(b.root, True)


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
    def make(root: Path) -> CliBuild:
        argv = ("demo", "--out", str(root / "d"))
        code, out, err = call_cli(*argv)
        return CliBuild(root=root, job=root / "d" / "job" / "coil-sensor.toml", out=root / "d" / "build", code=code,
                        stdout=out, stderr=err, args=argv)

    b = _once_per_run(tmp_path_factory, "demo", make)
    try:
        yield b
    finally:
        _set_writable(b.root, True)


__all__ = ["CliRunner", "ROOT", "SHARED_MESHES", "CliBuild", "call_cli"]
