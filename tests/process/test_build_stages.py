"""``run_build`` runs named stages in order, each with its progress and its time (issue 13)."""

from __future__ import annotations

import json

from _build_helpers import box_part, job_dict

from rotoprint.pipeline import run_build
from rotoprint.pipeline.build import STAGES
from rotoprint.process import parse_job


def test_every_stage_reports_progress_in_order_and_its_time(tmp_path):
    job = parse_job(job_dict([box_part("body", "plaster", 1, (4, 3, 0.1)), box_part("pad", "silver", 2, (1.5, 1.5, 0.05))],
                             process={"check": True}))
    seen: list[tuple[str, int, int]] = []
    res = run_build(job, tmp_path / "out", on_step=lambda stage, done, total: seen.append((stage, done, total)))
    order = list(dict.fromkeys(s for s, _, _ in seen if s != "machine"))  # machine/ is streamed within layers
    assert order == list(STAGES)
    for stage in STAGES:
        steps = [(d, t) for s, d, t in seen if s == stage]
        assert steps[-1][0] == steps[-1][1]  # every stage ends at done == total
        assert all(d <= t for d, t in steps)
    assert [d for s, d, _ in seen if s == "layers"] == list(range(res.summary["layers"] + 1))
    t = res.summary["timings_s"]
    assert list(t) == [f"{s}_s" for s in STAGES] + ["total_s"]
    assert all(v >= 0 for v in t.values()) and t["total_s"] >= sum(t[f"{s}_s"] for s in STAGES) * 0.99
    plan = json.loads(res.plan_path.read_text())
    assert list(plan["timings_s"]) == ["check_s", "layers_s", "simulate_s", "resistance_s"]  # as before the stages


def test_without_check_and_report_those_stages_report_nothing(tmp_path):
    job = parse_job(job_dict([box_part("body", "plaster", 1, (3, 2, 0.1))]))
    seen = []
    res = run_build(job, tmp_path / "out", on_step=lambda *a: seen.append(a[0]), check=False, report=False)
    assert "check" not in seen and "report" not in seen
    assert res.report_path is None and not (res.out_dir / "report.html").exists() and res.plan_path.exists()
