"""Shared fixtures. Real meshes are read from ../shared/data/meshes (never copied here)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

ROOT = Path(__file__).resolve().parents[1]
SHARED_MESHES = ROOT.parent / "shared" / "data" / "meshes"


@pytest.fixture(scope="session")
def shared_meshes() -> Path:
    if not SHARED_MESHES.is_dir():
        msg = f"real meshes not found at {SHARED_MESHES} (the shared/ folder beside the repo)"
        if os.environ.get("CI"):
            pytest.fail(msg + "; CI must have them")
        pytest.skip(msg)
    return SHARED_MESHES


@pytest.fixture
def run_cli():
    """Call the CLI in-process: returns (exit_code, stdout, stderr)."""
    from rotoprint.cli.main import main

    def _run(*args: str):
        import contextlib
        import io

        out, err = io.StringIO(), io.StringIO()
        from rotoprint.cli import _common

        old_c, old_o = _common.console.file, _common.out_console.file
        _common.console.file, _common.out_console.file = err, out
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                code = main([str(a) for a in args])
        finally:
            _common.console.file, _common.out_console.file = old_c, old_o
        return code, out.getvalue(), err.getvalue()

    return _run


__all__ = ["CliRunner", "ROOT", "SHARED_MESHES"]
