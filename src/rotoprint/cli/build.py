"""`rotoprint build JOB.toml --out DIR`: the whole multi-material pipeline for one job.

Exit codes: 0 built; 3 built, but the printability check found features that fall short
(everything is written first); 2 bad input (one line on stderr naming the file and the
problem, nothing written).
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer

from .. import ranges as R
from ._base import is_quiet
from ._common import ForceOpt, JsonOpt, console, in_range, out_console, print_json, print_table, progress, styled

EXIT_SHORT = 3


def _fmt_time(s: float) -> str:
    h, rem = divmod(int(round(s)), 3600)
    return f"{h} h {rem // 60:02d} min" if h else f"{rem // 60} min {rem % 60:02d} s"


def report_summary(res, *, label: str = "") -> None:
    """Print a build's summary on the terminal (stderr) and where the report is (stdout)."""
    from rich.table import Table

    s = res.summary
    console.print(f"{label}{s['layers']} layers, {s['heads']} heads, estimated printing time {_fmt_time(s['estimated_print_time_s'])}")
    for w in s["warnings"]:
        console.print(styled(("warning:", "yellow"), f" {w}"), soft_wrap=True)
    if s["resistance"]:
        t = Table(title="Resistance estimates", title_justify="left")
        for c in ("part", "terminals", "exact region", "deposited film", "hand check"):
            t.add_column(c)
        for r in s["resistance"]:
            if "error" in r:
                t.add_row(r["part"], " - ".join(r["between"]), r["error"], "", "")
                continue

            def ohm(v):
                return "open" if v is None else f"{v:.4g} ohm"

            hc = r.get("hand_check")
            t.add_row(r["part"], " - ".join(r["between"]), ohm(r["design"]["resistance_ohm"]), ohm(r["printed"]["resistance_ohm"]),
                      ohm(hc["resistance_ohm"]) if hc else "-")
        print_table(t, console)
    if s["printability_ok"] is False:
        console.print(styled(("printability: some features fall short", "red"), " (see the report)"))
    if res.report_path is not None:  # not with --no-report
        out_console.print(f"report: {res.report_path}")
    out_console.print(f"plan:   {res.plan_path}")
    m = s.get("machine")
    if m:
        flag = f", FLAGGED clocks: {', '.join(m['flagged_clocks'])}" if m["flagged_clocks"] else ""
        out_console.print(f"machine: {res.out_dir / 'machine' / 'program.json'} ({m['steps']} steps, {m['revolutions']} revolutions, "
                          f"{_fmt_time(m['time_s'])}{flag})")


@contextmanager
def stage_progress():
    """``on_step(stage, done, total)`` for :func:`~rotoprint.pipeline.run_build`: a rich bar per
    stage on a terminal; elsewhere (a pipe, a CI log) one line as each stage ends, with its time,
    so a long build never sits silent (a job refused before its plan is done prints only its error line)."""
    tasks: dict[str, int] = {}
    started: dict[str, float] = {}
    with progress() as bar:
        def on_step(stage: str, done: int, total: int) -> None:
            if stage not in tasks:
                tasks[stage] = bar.add_task(stage, total=total)
                started[stage] = time.perf_counter()
            bar.update(tasks[stage], completed=done)
            if bar.disable and done >= total and stage in started and not is_quiet():
                dt_s = time.perf_counter() - started.pop(stage)
                console.print(f"  {stage}: {total} step{'s' if total != 1 else ''} in {dt_s:.1f} s", highlight=False, markup=False)

        yield on_step


def build_command(
    job: Annotated[Path, typer.Argument(help="Job file (.toml): parts, materials, printer, placement.")],
    out: Annotated[Path, typer.Option("--out", "-o", help="Output folder (replaced only if provably an earlier rotoprint output, or with --force).")],
    no_check: Annotated[bool, typer.Option("--no-check", help="Skip the printability check.")] = False,
    no_report: Annotated[bool, typer.Option("--no-report", help="Do not write report.html.")] = False,
    json_out: JsonOpt = False,
    force: ForceOpt = False,
    bits: Annotated[int | None, typer.Option("--bits", help="Bits per nozzle in machine/ (1, 2 or 4; default: from the head's grey levels).", callback=in_range(R.MACHINE_BITS))] = None,
    row_delays: Annotated[str, typer.Option("--row-delays", help="machine/: 'baked' into the images (exact at every radius) or as per-row offsets in the 'program'.")] = "baked",
    no_machine: Annotated[bool, typer.Option("--no-machine", help="Do not write machine/.")] = False,
) -> int:
    """Plan a multi-material job: print-ready images per layer, head and ink, the ordered passes,
    thickness and resistance estimates, printability, and a self-contained report.html."""
    from ..process import load_job
    from ..io.atomic import check_output_path
    from ..pipeline import run_build
    from ..pipeline.build import job_inputs

    from ..machine.program import MachineOptions

    mopts = False if no_machine else MachineOptions(bits=bits, row_delays=row_delays)  # checked before any work
    check_output_path(out, is_dir=True, inputs=[job], force=force)  # before the job is read
    spec = load_job(job)
    with stage_progress() as on_step:
        res = run_build(spec, out, on_step=on_step, check=False if no_check else None, report=not no_report, force=force,
                        inputs=[job, *job_inputs(spec)], machine=mopts)
    if json_out:
        print_json({"out": str(res.out_dir), "report": None if res.report_path is None else str(res.report_path),
                    "plan": str(res.plan_path), **res.summary})
    else:
        report_summary(res)
    if res.summary["printability_ok"] is False:
        raise typer.Exit(EXIT_SHORT)
    return 0
