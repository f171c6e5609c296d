"""Sweep every subcommand's numeric options with extreme values (run as a script, not collected).

    .venv/bin/python tests/hostile/sweep_options.py [--only SUBSTR] [--jobs 2]

Each case runs in a forked child (rotoprint imported once in the parent) with a 1 GiB address
space limit on top of what the parent has mapped and a time limit; the outcome is classified as
ok (exit 0/3), refused (exit 2, one line, no traceback), multi (exit 2 but several lines),
traceback, crash (signal), hang (timeout) or memory (MemoryError / address space exhausted).
"""

from __future__ import annotations

import argparse
import collections
import os
import resource
import shutil
import signal
import sys
import tempfile
import time
from pathlib import Path

EXTREMES = ["0", "-1", "nan", "inf", "1e300", "1e-300", str(2**63)]
INT_EXTREMES = ["0", "-1", str(2**31), str(2**63 - 1), str(2**63)]
TIMEOUT_S = 30.0
MEM_LIMIT = 1 << 30


def make_inputs(base: Path) -> None:
    import numpy as np
    from PIL import Image

    from rotoprint.testing import box_triangles

    tri = box_triangles((4.0, 4.0, 2.0)).astype(np.float32)
    rec = np.zeros(len(tri), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["v"] = tri
    (base / "box.stl").write_bytes(b"\0" * 80 + np.uint32(len(tri)).tobytes() + rec.tobytes())
    d = np.zeros((40, 60), np.uint8)
    d[5:35, 10:50] = 255
    Image.fromarray(d).save(base / "d.png")


def cases() -> list[tuple[str, list[str], list[str]]]:
    """(label, argv before the swept option, swept options with value kinds)."""
    slice_b = ["slice", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", "out", "-q"]
    rot_b = ["slice", "box.stl", "-d", "omnidot760", "--layer-height", "0.5", "-o", "out", "-q", "--rotary", "--tilt", "30", "--radius", "50"]
    dlp_b = ["dlp", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.5", "-o", "out", "-q"]
    chk_b = ["check", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.5", "-q"]
    chk_r = ["check", "-d", "omnidot760", "--rotary", "--tilt", "30", "--radius", "50", "-q"]
    chk_m = ["check", "box.stl", "-d", "perfactory-sxga", "--layer-height", "0.5", "-q", "--mask", "smooth"]
    head_b = ["head", "-d", "omnidot760"]
    tr_b = ["transform", "d.png", "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", "p.png", "-q"]
    sim_b = ["simulate", "pr/p.png", "-o", "ov.png"]
    info_b = ["info", "box.stl"]
    mesh = ["--scale:f", "--rotate:t", "--translate:t"]
    return [
        ("info", info_b, mesh),
        ("slice", slice_b, ["--layer-height:f", "--fibre-angle:f", "--offset:p", "--gap-radius:f", "--workers:i"] + mesh),
        ("slice-ink", ["slice", "box.stl", "-d", "omnidot760", "--layer-height", "0.5", "-o", "out", "-q"], ["--dpi-y:f"]),
        ("slice-rot", rot_b, ["--tilt:f", "--radius:f", "--angle:f", "--direction:i", "--ref-radius:f", "--max-swathes:i", "--dpi-y:f", "--layer-height:f", "--translate:t"]),
        ("dlp", dlp_b, ["--layer-height:f", "--first-layers:i", "--first-layer-offset:f", "--exposure:f", "--first-exposure:f",
                        "--fibre-angle:f", "--offset:p", "--gap-radius:f", "--workers:i"] + mesh),
        ("check", chk_b, ["--layer-height:f", "--min-wall:f", "--min-gap:f", "--fibre-angle:f", "--orientations:r", "--resolution:f",
                          "--max-overlays:i", "--offset:p", "--gap-radius:f"] + mesh),
        ("check-ink", ["check", "box.stl", "-d", "omnidot760", "--layer-height", "0.5", "-q"], ["--dpi-y:f", "--min-wall:f"]),
        ("check-rot", chk_r, ["--tilt:f", "--radius:f", "--dpi-y:f"]),
        ("check-mask", chk_m, ["--cure-threshold:f"]),
        ("head", head_b, ["--tilt:f", "--tilt-range:r", "--radius:f"]),
        ("transform", tr_b, ["--tilt:f", "--radius:f", "--dpi-y:f", "--ref-radius:f", "--design-dpi:f", "--max-swathes:i", "--angle:f", "--direction:i"]),
        ("transform-paper", tr_b + ["--method", "paper"], ["--tilt:f", "--dpi-y:f", "--design-dpi:f", "--angle:f"]),
        ("simulate", sim_b, ["--drop-diameter:f", "--jitter:f", "--dead:d", "--seed:i", "--scale:i"]),
    ]


def values(kind: str) -> list[str]:
    if kind == "f":
        return EXTREMES
    if kind == "i":
        return INT_EXTREMES
    if kind == "t":
        return [f"{v},0,0" for v in EXTREMES] + ["0,0,1e300"]
    if kind == "p":
        return [f"{v},0" for v in EXTREMES]
    if kind == "r":
        return ["nan:80:10", "0:inf:10", "0:80:1e-300", "-1e300:1e300:1", "0:80:0", "1e300:1e300:1", "0:1e300:1e290"]
    if kind == "d":
        return ["-1", str(2**63), "1e300", "99999999"]
    raise ValueError(kind)


def run_case(base: Path, argv: list[str]) -> tuple[str, int, str, float]:
    from rotoprint.cli.main import main

    work = Path(tempfile.mkdtemp(prefix="sw", dir=base.parent))
    for name in ("box.stl", "d.png"):
        os.symlink(base / name, work / name)
    shutil.copytree(base / "pr", work / "pr")
    t0 = time.monotonic()
    pid = os.fork()
    if pid == 0:  # child
        try:
            os.chdir(work)
            soft = MEM_LIMIT + _mapped_bytes()
            resource.setrlimit(resource.RLIMIT_AS, (soft, soft))
            fd = os.open("stderr.txt", os.O_WRONLY | os.O_CREAT)
            os.dup2(fd, 2)
            fo = os.open("stdout.txt", os.O_WRONLY | os.O_CREAT)
            os.dup2(fo, 1)
            sys.stdout = open(1, "w", closefd=False)
            sys.stderr = open(2, "w", closefd=False)
            from rotoprint.cli import _common

            _common.console.file = sys.stderr
            _common.out_console.file = sys.stdout
            code = main(argv)
        except BaseException:
            import traceback

            traceback.print_exc()
            code = 99
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code if isinstance(code, int) else 98)
    status = None
    while time.monotonic() - t0 < TIMEOUT_S:
        done, st = os.waitpid(pid, os.WNOHANG)
        if done:
            status = st
            break
        time.sleep(0.05)
    dt = time.monotonic() - t0
    if status is None:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        err = (work / "stderr.txt").read_text(errors="replace")
        shutil.rmtree(work, ignore_errors=True)
        return "hang", -1, err, dt
    err = (work / "stderr.txt").read_text(errors="replace")
    shutil.rmtree(work, ignore_errors=True)
    if os.WIFSIGNALED(status):
        return "crash", -os.WTERMSIG(status), err, dt
    code = os.WEXITSTATUS(status)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    if "Traceback" in err or code in (98, 99):
        kind = "memory" if "MemoryError" in err else "traceback"
    elif code in (0, 3):
        kind = "ok"
    elif code == 2 and len(lines) == 1:
        kind = "refused"
    else:
        kind = "multi"
    return kind, code, err, dt


def _mapped_bytes() -> int:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[0]) * os.sysconf("SC_PAGE_SIZE")


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", default="")
    ap.add_argument("--show", default="traceback,crash,hang,memory,multi,ok")
    args = ap.parse_args()
    import rotoprint.cli.main  # noqa: F401  (imported once, before the forks)

    base = Path(tempfile.mkdtemp(prefix="rotoprint-sweep-"))
    make_inputs(base)
    from rotoprint.cli.main import main as cli

    os.chdir(base)
    (base / "pr").mkdir()
    assert cli(["transform", "d.png", "-d", "omnidot760", "--tilt", "30", "--radius", "50", "-o", "pr/p.png", "-q"]) == 0
    tally: collections.Counter = collections.Counter()
    show = set(args.show.split(","))
    for label, argv, opts in cases():
        for spec in opts:
            opt, kind = spec.split(":")
            for v in values(kind):
                full = [*argv, opt, v] if opt not in argv else _replace(argv, opt, v)
                name = f"{label} {opt} {v}"
                if args.only and args.only not in name:
                    continue
                outcome, code, err, dt = run_case(base, full)
                tally[outcome] += 1
                if outcome in show:
                    last = err.strip().splitlines()[-1] if err.strip() else ""
                    print(f"{outcome:9s} {code:4d} {dt:5.1f}s  {name}  | {last[:160]}", flush=True)
    print("TALLY", dict(tally), "total", sum(tally.values()))
    shutil.rmtree(base, ignore_errors=True)
    return 0


def _replace(argv: list[str], opt: str, v: str) -> list[str]:
    out = list(argv)
    out[out.index(opt) + 1] = v
    return out


if __name__ == "__main__":
    sys.exit(main())
