"""The shared CLI options: defined once, on the app for every command, plain help, tables
that do not lose figures in a pipe, and the name given to 'transform -o' read by simulate."""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

import pytest

from rotoprint.cli.main import app

SRC = Path(__file__).resolve().parents[1] / "src" / "rotoprint" / "cli"
SHARED = ("--quiet", "--verbose", "--workers", "--scheduler", "--resume", "--fill", "--gap-radius", "--offset",
          "--dpi-y", "--fibre-angle")
SUBCOMMANDS = sorted(c.name for c in app.registered_commands)
# rich markup tags ([bold], [/red], [link=...]) and emoji the console would draw
MARKUP = re.compile(r"\[/?(bold|italic|dim|red|green|yellow|blue|cyan|magenta|link|b|i|u)\b[^\]]*\]")
NON_ASCII_SYMBOL = re.compile(r"[\U0001F000-\U0001FAFF\u2600-\u27BF\u2B00-\u2BFF]")


def test_every_subcommand_is_checked():
    assert {"slice", "dlp", "check", "head", "transform", "simulate", "info", "build", "demo"} <= set(SUBCOMMANDS)


@pytest.mark.parametrize("sub", SUBCOMMANDS)
def test_help_has_no_emoji_and_no_markup(run_cli, sub):
    code, out, err = run_cli(sub, "--help")
    assert code == 0, err
    assert "Usage: rotoprint " + sub in out
    assert not NON_ASCII_SYMBOL.search(out), NON_ASCII_SYMBOL.findall(out)
    assert not MARKUP.search(out), MARKUP.findall(out)


def test_tilt_range_help_prints_its_text(run_cli):
    code, out, _ = run_cli("head", "--help")
    assert code == 0 and "'A:B:STEP'" in out and "\U0001F171" not in out
    code, out, _ = run_cli("check", "--help")
    assert code == 0 and "'A:B:STEP'" in out


def test_shared_options_are_declared_once():
    """No subcommand module spells a shared option itself: they come from cli/options.py."""
    for path in sorted(SRC.glob("*.py")):
        if path.name == "options.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "Option":
                names = {a.value for a in node.args if isinstance(a, ast.Constant)}
                assert not names & set(SHARED), f"{path.name}:{node.lineno} redeclares {names & set(SHARED)}"


def test_shared_help_is_the_same_everywhere(run_cli):
    seen: dict[str, set[str]] = {}
    for sub in SUBCOMMANDS:
        _, out, _ = run_cli(sub, "--help")
        flat = " ".join(out.split())
        for opt in SHARED:
            m = re.search(re.escape(opt) + r"(?: \S+)? ((?:(?! -[-a-z]).)*)", flat)
            if m and f" {opt}" in f" {flat}":
                seen.setdefault(opt, set()).add(m.group(1).split("[default")[0].strip())
    for opt, texts in seen.items():
        assert len(texts) == 1, (opt, texts)


def test_app_quiet_and_verbose_work_for_every_command(run_cli, tmp_path):
    code, out, err = run_cli("--help")
    assert code == 0 and "--verbose" in out and "--quiet" in out
    design = tmp_path / "d.png"
    from rotoprint.io.images import write_png
    from rotoprint.rotary.testimage import test_design

    write_png(design, test_design(60))
    args = ("transform", design, "--device", "omnidot760", "--tilt", "20", "--radius", "60", "--out", tmp_path / "p.png")
    code, _, err = run_cli(*args)
    assert code == 0 and "swathe(s)" in err  # the summary
    code, _, err2 = run_cli("-q", *args)
    assert code == 0 and not err2.strip(), err2
    code, _, err3 = run_cli(*args, "-q")  # the per-command spelling still works
    assert code == 0 and not err3.strip(), err3
    code, _, err4 = run_cli(*args)  # the app's flag does not stick to the next run
    assert code == 0 and "swathe(s)" in err4
    code, out4, err = run_cli("-v", "head", "--tilt", "10")  # a command without its own --verbose
    assert code == 0, err


def test_wide_table_keeps_every_figure_in_a_pipe(run_cli):
    """'rotoprint head' in a pipe (80 columns): no figure is cut to an ellipsis."""
    from rotoprint import load_device
    from rotoprint.rotary.head import head_figures

    code, out, err = run_cli("head", "--tilt-range", "10:20:10")
    assert code == 0, err
    assert "\u2026" not in out and "..." not in out
    assert max(len(line) for line in out.splitlines()) <= 80
    head = load_device("omnidot760").head
    for t in (10.0, 20.0):
        f = head_figures(head, tilt_deg=t, pivot_radius_mm=60.0)
        lo, hi = f.overlap_band_mm
        for text in (f"{lo:.3f}-{hi:.3f} ({hi - lo:.3f})", f"{f.pitch_radial_min_mm * 1000:.1f}-{f.pitch_radial_max_mm * 1000:.1f}",
                     f"{f.inner_single_row_band_mm[0]:.2f}-{f.inner_single_row_band_mm[1]:.2f}"):
            assert text in out, text


def test_narrow_table_stays_a_table(run_cli, tmp_path):
    from rotoprint.cli._common import print_table
    import io

    from rich.console import Console
    from rich.table import Table

    buf = io.StringIO()
    con = Console(file=buf, width=80, markup=False, emoji=False)
    t = Table(title="t")
    t.add_column("a")
    t.add_column("b")
    t.add_row("1", "2")
    print_table(t, con)
    assert "┃" in buf.getvalue() or "│" in buf.getvalue()
    buf2 = io.StringIO()
    con2 = Console(file=buf2, width=36, markup=False, emoji=False)
    w = Table(title="wide")
    for c in ("first column", "second column", "third"):
        w.add_column(c)
    w.add_row("12345.678", "abcdefgh-ijkl", "x")
    print_table(w, con2)
    text = buf2.getvalue()
    assert "first column: 12345.678" in text and "second column: abcdefgh-ijkl" in text and "\u2026" not in text


def test_simulate_takes_the_name_given_to_transform(run_cli, tmp_path):
    """transform -o PRINT.png splits into PRINT-s1.png ...; simulate PRINT.png reads them."""
    from rotoprint.io.images import write_png
    from rotoprint.rotary.testimage import test_design

    design = tmp_path / "d.png"
    write_png(design, test_design(100))  # 42 mm at 60 dpi: two swathes at tilt 45 (150 px: 2.3x the time)
    out = tmp_path / "p.png"
    code, _, err = run_cli("transform", design, "--device", "omnidot760", "--tilt", "45", "--radius", "40",
                           "--design-dpi", "60", "--out", out)
    assert code == 0, err
    side = json.loads(out.with_suffix(".json").read_text())
    assert len(side["swathes"]) >= 2 and not out.exists()
    code, o1, err = run_cli("simulate", out, "--out", tmp_path / "ov.png", "--json")
    assert code == 0, err
    code, o2, err = run_cli("simulate", tmp_path / side["swathes"][0]["file"], "--out", tmp_path / "ov2.png", "--json")
    assert code == 0, err
    a, b = json.loads(o1), json.loads(o2)
    a.pop("overlay"), b.pop("overlay")
    assert a == b and a["swathes"] == len(side["swathes"])
    code, _, err = run_cli("simulate", tmp_path / "missing.png", "--out", tmp_path / "ov3.png")
    assert code == 2 and "no such file" in err
