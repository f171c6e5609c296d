"""Run every benchmark in bench/ and print one table per benchmark.

Each module ``bench/bench_*.py`` defines ``run(quick: bool) -> list[dict]`` returning rows
(one dict per measurement, same keys) and a ``TITLE`` string. Peers are measured in the
same run and compared as ratios, because these machines are noisy.

    python bench/run.py            # everything
    python bench/run.py slicing    # modules whose name contains 'slicing'
    python bench/run.py --quick    # smaller sizes, for a smoke run
"""

from __future__ import annotations

import datetime
import importlib.util
import platform
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def _table(title: str, rows: list[dict]) -> str:
    if not rows:
        return f"## {title}\n\n(no rows)\n"
    keys = list(rows[0].keys())
    fmt = lambda v: f"{v:.4g}" if isinstance(v, float) else str(v)  # noqa: E731
    lines = [f"## {title}", "", "| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    for r in rows:
        lines.append("| " + " | ".join(fmt(r.get(k, "")) for k in keys) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str]) -> int:
    quick = "--quick" in argv
    names = [a for a in argv if not a.startswith("--")]
    sys.path.insert(0, str(HERE))
    import os

    print(f"# rotoprint benchmarks, {datetime.date.today()}, {platform.node()}, "
          f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}\n")
    for path in sorted(HERE.glob("bench_*.py")):
        if names and not any(n in path.stem for n in names):
            continue
        spec = importlib.util.spec_from_file_location(path.stem, path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[path.stem] = mod  # dataclasses look their module up
        spec.loader.exec_module(mod)
        rows = mod.run(quick=quick)
        print(_table(getattr(mod, "TITLE", path.stem), rows), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
