"""The fast entry of `rotoprint dlp` (rotoprint.cli._fast) held to the typer command: the same
options with the same meaning (the check is built from the typer command's own parameters, so
an option added there and not in the fast table fails here), the same outputs and messages,
and no typer, rich, pydantic or numba imported on the way."""

from __future__ import annotations

import json
import subprocess
import sys
import typing
from pathlib import Path

import pytest
import typer.main

from rotoprint import ranges as R
from rotoprint._plain_device import PROJECTOR_FIELDS, _plain_device, load_projector
from rotoprint.cli import _fast
from rotoprint.cli.dlp import dlp_command
from rotoprint.cli.main import app
from rotoprint.io.stl import write_binary_stl
from rotoprint.testing import box_triangles

BASE = ["mesh.stl", "--device", "perfactory-sxga", "--layer-height", "0.5", "--out", "job.sl1"]


def _command():
    return typer.main.get_command(app).commands["dlp"]


def _typer_params(args: list[str]) -> dict:
    """The typer command's parsed keyword arguments for ``args`` (parsed, not run)."""
    with _command().make_context("dlp", list(args)) as ctx:
        return dict(ctx.params)


def _hints() -> dict:
    return typing.get_type_hints(dlp_command, include_extras=True)


def _base_type(name: str):
    hint = _hints()[name]
    t = typing.get_args(hint)[0] if typing.get_origin(hint) is typing.Annotated else hint
    args = [a for a in typing.get_args(t) if a is not type(None)]
    return args[0] if args else t


def _sample(name: str, kind) -> str:
    """A value of the option's type inside its range, other than the default."""
    return {int: "3", float: "0.5", str: "abc", Path: "other.sl1"}[kind]


OPTIONS = {o.name: o for o in _command().params if o.name != "mesh"}
FAST = {row[0]: row for row in _fast.DLP_OPTIONS}


def test_fast_table_is_the_typer_command():
    assert list(FAST) == list(OPTIONS), "the fast table lists the typer command's options, in its order"
    assert [p.name for p in _command().params if p.param_type_name == "argument"] == [_fast.DLP_ARGUMENT[0]]
    for name, opt in OPTIONS.items():
        _, strings, kind, default, check = FAST[name]
        if opt.is_flag:
            assert kind == "flag", name
            on, off = (strings if isinstance(strings[0], tuple) else (strings, ()))
            assert list(on) == opt.opts and list(off) == opt.secondary_opts, name
        else:
            assert kind is _base_type(name), name
            assert list(strings) == opt.opts and not opt.secondary_opts, name
        assert (default is _fast._REQUIRED) == opt.required, name
        if not opt.required:
            assert default == opt.default and type(default) is type(opt.default), name
        cb = opt.callback
        if cb is None:
            assert check is None, name
        elif getattr(cb, "range", None) is not None:
            assert check is not None and check.startswith("range:") and getattr(R, check[6:]) == cb.range, name
        else:
            assert cb.__name__ == "scale_cb" and check == "scale", name


@pytest.mark.parametrize("name", list(OPTIONS))
def test_every_option_means_the_same(name):
    opt = OPTIONS[name]
    forms = []
    if opt.is_flag:
        forms = [[s] for s in opt.opts + opt.secondary_opts]
    else:
        v = _sample(name, _base_type(name))
        for s in opt.opts:
            forms.append([s, v])
            forms.append([f"{s}={v}"] if s.startswith("--") else [f"{s}{v}"])
    for form in forms:
        args = BASE + form  # device, layer height, out: repeated, the last one counts in both
        want = _typer_params(args)
        got = _fast.parse_dlp(args)
        assert got == want, form
        assert {k: type(v) for k, v in got.items()} == {k: type(v) for k, v in want.items()}, form


def test_all_options_together_and_interspersed():
    args = ["-q", "--mode", "binary", "--erm", "--invert", "--mirror-x", "--mirror-y", "mesh.stl", "--first-layers", "2",
            "--first-layer-offset", "10", "--format", "sl1", "--exposure", "3", "--first-exposure", "30", "--fibre-angle", "15",
            "--offset", "1,2", "--units", "cm", "--scale", "-2", "--rotate", "0,0,90", "--translate", "1,1,0",
            "--no-fill-holes", "-j2", "--scheduler", "tcp://h:1", "--resume", "-v", "--force",
            "-dperfactory-sxga", "--layer-height=0.25", "-o", "-odd.sl1"]
    assert _fast.parse_dlp(args) == _typer_params(args)
    after_dashes = [*BASE[1:], "--", "-mesh.stl"]  # after '--' a word is the mesh even with a '-'
    assert _fast.parse_dlp(after_dashes) == _typer_params(after_dashes)


@pytest.mark.parametrize("args", [
    [*BASE, "--help"], [*BASE, "--bogus"], [*BASE, "--erm=1"], BASE[:-2], [*BASE, "second.stl"], [*BASE, "-qv"],
    [*BASE, "--workers", "two"], [*BASE, "--workers", "0"], [*BASE, "--scale", "0"], [*BASE, "--layer-height", "1e9"],
    [*BASE, "--out"], [*BASE, "--mode"], BASE[1:],
])
def test_what_the_fast_parser_does_not_read_goes_to_typer(args):
    with pytest.raises(_fast._NotPlain):
        _fast.parse_dlp(args)
    assert _fast.try_dlp(["dlp", *args]) is None


def test_not_dlp_or_turned_off_goes_to_typer(monkeypatch):
    assert _fast.try_dlp(["slice", *BASE]) is None
    assert _fast.try_dlp(["--version"]) is None
    monkeypatch.setenv("ROTOPRINT_FAST_CLI", "0")
    assert _fast.try_dlp(["dlp", *BASE]) is None


# ----------------------------------------------------------------- whole runs, both paths
@pytest.fixture
def part(tmp_path):
    p = tmp_path / "block.stl"
    write_binary_stl(p, box_triangles((3.0, 2.0, 1.0)))
    return p


def _both(run_cli, monkeypatch, tmp_path, *args):
    """(code, stderr, output bytes or None) of the fast path and the typer path, each writing
    into its own folder under the same name."""
    monkeypatch.setenv("SOURCE_DATE_EPOCH", "1700000000")
    res = []
    for way in ("fast", "typer"):
        monkeypatch.setenv("ROTOPRINT_FAST_CLI", "1" if way == "fast" else "0")
        d = tmp_path / ("fast" if way == "fast" else "slow")  # same length: a tab stop falls alike
        d.mkdir(exist_ok=True)
        argv = [str(a).replace("OUT", str(d)) for a in args]
        code, out, err = run_cli(*argv)
        files = sorted(p for p in d.rglob("*") if p.is_file())
        res.append((code, out, err.replace(str(d), "OUT"), [(p.relative_to(d).as_posix(), p.read_bytes()) for p in files]))
    return res


@pytest.mark.parametrize("extra", [
    ["-o", "OUT/job.sl1s", "-d", "prusa-sl1s"],
    ["-o", "OUT/masks", "-d", "perfactory-sxga", "--mode", "smooth", "--erm", "--first-layers", "1", "--first-layer-offset", "20"],
    ["-o", "OUT/pjob", "-d", "perfactory-sxga", "--format", "perfactory", "--mode", "binary", "--invert", "--exposure", "3"],
])
def test_same_outputs_and_summary(run_cli, monkeypatch, tmp_path, part, extra):
    fast, slow = _both(run_cli, monkeypatch, tmp_path, "dlp", part, "--layer-height", "0.5", *extra)
    assert fast[0] == slow[0] == 0, (fast[2], slow[2])
    assert fast[1:] == slow[1:]
    assert fast[3] and fast[2].count("\n") == 1  # the summary: one line


@pytest.mark.parametrize("case", ["no-mesh", "bad-device", "inkjet", "device-file-lax", "device-file-bad", "offset", "bad-out"])
def test_same_errors(run_cli, monkeypatch, tmp_path, part, case):
    dev = tmp_path / "dev.toml"
    text = Path(__file__).resolve().parents[2].joinpath("src/rotoprint/devices/presets/perfactory-sxga.toml").read_text()
    args = ["dlp", part, "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", "OUT/j.sl1"]
    if case == "no-mesh":
        args[1] = tmp_path / "none.stl"
    elif case == "bad-device":
        args[3] = "no-such-printer"
    elif case == "inkjet":
        args[3] = "omnidot760"
    elif case in ("device-file-lax", "device-file-bad"):  # lax: a pydantic conversion the plain reader leaves to pydantic
        dev.write_text(text.replace("pixels_x = 1400", 'pixels_x = "1400"' if case == "device-file-lax" else "pixels_x = 0"))
        args[3] = dev
    elif case == "offset":
        args += ["--offset", "1,x"]
    elif case == "bad-out":
        args += ["--format", "zip"]
    fast, slow = _both(run_cli, monkeypatch, tmp_path, *args)
    assert fast[:3] == slow[:3]
    if case == "device-file-lax":
        assert fast[0] == 0 and fast[3] == slow[3]
    else:
        assert fast[0] == 2 and fast[2].startswith("rotoprint: error: ") and fast[2].count("\n") == 1, fast[2]
        assert fast[3] == slow[3] == []


def test_help_is_typers(run_cli):
    code, out, err = run_cli("dlp", "--help")
    assert code == 0
    for opt in OPTIONS.values():
        for s in opt.opts + opt.secondary_opts:
            assert s in out, s


# ----------------------------------------------------------------------- no heavy imports
def _assert_dlp_imports_none_of(part, out, args, modules):
    """``rotoprint dlp PART -d prusa-sl1s --layer-height 0.5 -o OUT ARGS`` in a fresh interpreter
    (the C extension on): it exits 0 and has imported no top-level package of ``modules``."""
    code = (
        "import sys\n"
        "from rotoprint.cli.entry import main\n"
        f"rc = main(['dlp', {str(part)!r}, '-d', 'prusa-sl1s', '--layer-height', '0.5', '-o', {str(out)!r}] + {list(args)!r})\n"
        f"print(rc, sorted({{m.split('.')[0] for m in sys.modules}} & {set(modules)!r}))\n"
    )
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       env={"PATH": "/usr/bin:/bin", "ROTOPRINT_NATIVE": "1"})
    assert p.returncode == 0, p.stderr
    assert p.stdout.split("\n")[0] == "0 []", p.stdout + p.stderr


@pytest.mark.parametrize("quiet,mode", [(True, "coverage"), (False, "coverage"), (True, "binary"), (True, "smooth")])
def test_fast_path_imports_no_typer_rich_pydantic_numba(tmp_path, part, quiet, mode):
    from rotoprint._accel import native

    if native is None:
        pytest.skip("rotoprint._native is not built: the masks' kernels are numba's")
    args = ["--mode", mode] + (["--quiet"] if quiet else [])
    _assert_dlp_imports_none_of(part, tmp_path / "j.sl1s", args, {"typer", "click", "rich", "pydantic", "pydantic_core", "numba"})
    assert (tmp_path / "j.sl1s").is_file()


# ------------------------------------------------------------------- devices without pydantic
def test_short_coverage_job_skips_openssl_tempfile_and_thread_pools(tmp_path, part):
    """A 10-layer-like coverage job needs neither OpenSSL's hashlib (``rotoprint._hashing``),
    tempfile (with random) nor concurrent.futures (no render threads for so little work): each
    was a few ms of its start-up."""
    from rotoprint._accel import native
    from rotoprint._hashing import _builtin_sha256

    if native is None or _builtin_sha256 is None:
        pytest.skip("needs rotoprint._native and Python's built-in SHA-256")
    _assert_dlp_imports_none_of(part, tmp_path / "j.sl1s", ["--mode", "coverage", "--quiet"],
                                {"_hashlib", "hashlib", "tempfile", "random", "concurrent"})


def test_numpy_core_preloaded_off_the_main_thread():
    """``rotoprint dlp`` loads numpy's core extension in a thread (dlopen without the GIL)
    before numpy is imported; numpy then imports and works as ever, with one BLAS thread."""
    from rotoprint._accel import native

    if native is None:
        pytest.skip("rotoprint._native is not built")
    code = (
        "import os, sys, threading\n"
        "from rotoprint.cli import entry\n"
        "assert entry._looks_like_dlp(['-q', 'dlp', 'x.stl']) and not entry._looks_like_dlp(['check', 'dlp'])\n"
        "entry._preload_numpy()\n"
        "for t in threading.enumerate():\n"
        "    if t.name == 'rotoprint-preload':\n"
        "        t.join()\n"
        "maps = open('/proc/self/maps').read()\n"
        "print('numpy' in sys.modules, '_multiarray_umath' in maps, os.environ['OPENBLAS_NUM_THREADS'])\n"
        "import numpy as np\n"
        "print(float(np.linalg.inv(np.eye(3) * 2)[0, 0]), len(os.listdir('/proc/self/task')))\n"
    )
    env = {"PATH": "/usr/bin:/bin"}
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split("\n")[:2] == ["False True 1", "0.5 1"], p.stdout
    # turned off with the C extension: nothing loaded ahead
    off = code.replace("print('numpy' in sys.modules", "print('numpy' in sys.modules or 'x'")
    p = subprocess.run([sys.executable, "-c", off], capture_output=True, text=True, timeout=120,
                       env={**env, "ROTOPRINT_NATIVE": "0", "OPENBLAS_NUM_THREADS": "2"})
    assert p.returncode == 0, p.stderr
    assert p.stdout.split("\n")[0] == "x False 2", p.stdout
    assert native.preload("/nonexistent/lib.so") is False


def test_plain_projector_fields_are_the_models():
    from rotoprint.devices import Projector

    fields = Projector.model_fields
    assert list(PROJECTOR_FIELDS) == list(fields)
    for name, (kind, default, lo, lo_open, hi) in PROJECTOR_FIELDS.items():
        f = fields[name]
        assert (default is ...) == f.is_required(), name
        if default is not ...:
            assert default == f.default and type(default) is type(f.default), name
        ann = f.annotation
        if kind is str and lo is not None:
            assert typing.get_origin(ann) is typing.Literal and set(typing.get_args(ann)) == set(lo), name
            continue
        assert ann is kind, name
        bounds = {type(m).__name__: m for m in f.metadata}
        if kind is bool or kind is str:
            assert not bounds, name
            continue
        low = bounds.get("Gt") if lo_open else bounds.get("Ge")
        assert low is not None and (low.gt if lo_open else low.ge) == lo, name
        assert bounds["Le"].le == hi, name
        assert set(bounds) == {"Gt" if lo_open else "Ge", "Le"}, name


def test_plain_presets_dump_as_the_models():
    from rotoprint.devices import ProjectorDevice, load_device, preset_names

    projectors = [n for n in preset_names() if isinstance(load_device(n), ProjectorDevice)]
    assert projectors
    for n in projectors:
        for over in ({}, {"exposure_s": 2.5, "first_exposure_s": 7}):
            want = load_device(n, **over)
            got = load_projector(n, **over)
            assert got is not None, n
            assert json.dumps(got.model_dump(mode="json")) == json.dumps(want.model_dump(mode="json")), n
            for prop in ("pitch_x_mm", "pitch_y_mm", "field_px", "fibre_axis", "name", "kind"):
                assert getattr(got, prop) == getattr(want, prop), (n, prop)
            assert _plain_device(want.model_dump(mode="json")) == got  # a worker's task rebuilds it
    assert load_projector("omnidot760") is None  # an inkjet: load_device's
    assert load_projector("no-such") is None


@pytest.mark.parametrize("edit", [
    ("pixels_x = 1400", "pixels_x = 1400.0"), ("pixels_x = 1400", "pixels_x = true"), ("pixels_x = 1400", "pixels_x = 0"),
    ("mirror_x = false", "mirror_x = 0"), ('orientation = "landscape"', 'orientation = "sideways"'),
    ("pixels_x = 1400", "pixels_x = 1400\nextra = 1"), ("cure_threshold = 0.5", "cure_threshold = nan"),
])
def test_plain_reader_leaves_anything_else_to_pydantic(tmp_path, edit):
    from rotoprint.devices import load_device

    text = Path(__file__).resolve().parents[2].joinpath("src/rotoprint/devices/presets/perfactory-sxga.toml").read_text()
    assert edit[0] in text
    p = tmp_path / "d.toml"
    p.write_text(text.replace(edit[0], edit[1], 1))
    assert load_projector(p) is None
    try:  # pydantic takes it (lax) or refuses it: either way it is the one that decides
        load_device(p)
    except Exception as exc:  # noqa: BLE001
        assert type(exc).__name__ in ("DeviceError", "InputFileError"), exc


def test_same_summary_and_error_for_names_with_tabs_and_wide_characters(run_cli, monkeypatch, tmp_path, part):
    fast, slow = _both(run_cli, monkeypatch, tmp_path, "dlp", part, "--layer-height", "0.5", "-d", "perfactory-sxga",
                       "-o", "OUT/j\tob 部品.sl1")
    assert fast[0] == slow[0] == 0 and fast[1:] == slow[1:]
    fast, slow = _both(run_cli, monkeypatch, tmp_path, "dlp", tmp_path / "no\tsuch 部品.stl", "--layer-height", "0.5",
                       "-d", "perfactory-sxga", "-o", "OUT/j.sl1")
    assert fast[0] == slow[0] == 2 and fast[1:] == slow[1:]
