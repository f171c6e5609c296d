"""rotoprint against PrusaSlicer on DLP archives: whole processes, same model, display and
layer height (issue 16).

For every case both programs run as whole processes from the shell's point of view:
``rotoprint dlp MESH --mode coverage --out JOB.sl1s`` against ``prusa-slicer --export-sla
--load PROFILE.ini MESH -o JOB.sl1s`` (a profile written here: supports, pad and elephant-foot
compensation off, hollowing off, its anti-aliasing on with ``gamma_correction = 1``). The two
alternate case by case over 3 rounds and each figure is the median of the 3 runs: wall time,
peak resident memory (GNU time's ``%M``), archive bytes.
The grey-sum area error is measured afterwards, outside the timing, on both archives: per
layer, ``sum(grey) / 255 * pixel area`` against the exact area of the mesh's cross-section
at the layer's slicing height (both slice at mid-layer), worst relative error over the layers
whose section is at least 1 mm^2, and at least 10 mm^2. The grey IoU of the two archives'
layers (sum of the pixelwise minimum over sum of the maximum) says they draw the same part.

The meshes are generated here (not committed): a 20 mm cube, a 640k-triangle torus, an
80k-triangle sphere of 60 mm, a 1M-triangle sphere of 19 mm and a 20 x 20 x 1 mm plate.

Without ``prusa-slicer`` on PATH the table says so and is skipped (``apt-get install
prusa-slicer``, Debian's package, installs it for the bench only).
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TITLE = "DLP archives: rotoprint dlp --mode coverage against PrusaSlicer --export-sla (whole processes, median of 3)"
ROUNDS = 3


@dataclass(frozen=True)
class Display:
    """What both programs are told about the projector."""

    preset: str  # rotoprint's device
    width_mm: float
    height_mm: float
    pixels_x: int
    pixels_y: int
    mirror_x: bool


SL1S = Display("prusa-sl1s", 81.0, 128.0, 1620, 2560, True)
SXGA = Display("perfactory-sxga", 27.77, 20.83, 1400, 1050, False)


@dataclass(frozen=True)
class Case:
    name: str
    display: Display
    layer_height_mm: float
    quick: bool  # part of --quick


CASES = (
    Case("20 mm cube, SL1S, 0.05 mm", SL1S, 0.05, True),
    Case("640k-triangle torus, SL1S, 0.1 mm", SL1S, 0.1, False),
    Case("80k-triangle sphere 60 mm, SL1S, 0.1 mm", SL1S, 0.1, False),
    Case("1M-triangle sphere 19 mm, perfactory-sxga 19.8 um, 0.019 mm", SXGA, 0.019, False),
    Case("10-layer part (20 x 20 x 1 mm plate), SL1S, 0.1 mm", SL1S, 0.1, True),
)


def _triangles(case: Case) -> np.ndarray:
    from rotoprint.testing import _grid_surface, box_triangles

    n = case.name
    if n.startswith("20 mm cube"):
        return box_triangles((20.0, 20.0, 20.0), (-10.0, -10.0, 0.0))
    if n.startswith("10-layer"):
        return box_triangles((20.0, 20.0, 1.0), (-10.0, -10.0, 0.0))
    if "torus" in n:  # R = 24, r = 8 mm: 16 mm high, 160 layers of 0.1 mm; 2 * 800 * 400 triangles
        nu, nv, R, r = 800, 400, 24.0, 8.0
        u = np.linspace(0, 2 * np.pi, nu, endpoint=False)
        v = np.linspace(0, 2 * np.pi, nv, endpoint=False)
        U, V = np.meshgrid(u, v, indexing="ij")
        P = np.stack([(R + r * np.cos(V)) * np.cos(U), (R + r * np.cos(V)) * np.sin(U), r * np.sin(V)], axis=-1)
        return _grid_surface(P, True, True) + [0.0, 0.0, r]
    if "80k" in n:
        return _sphere(30.0, 101, 400)  # 80,000 triangles
    if "1M" in n:
        return _sphere(9.5, 501, 1000)  # 1,000,000 triangles
    raise ValueError(n)


def _sphere(radius: float, n_lat: int, n_lon: int) -> np.ndarray:
    from rotoprint.testing import uv_sphere_mesh

    m = uv_sphere_mesh(radius, n_lat, n_lon)
    return m.vertices[m.faces] + [0.0, 0.0, radius]


def prusa_profile(d: Display, layer_height_mm: float) -> str:
    """A PrusaSlicer SLA config: the display, no supports, no pad, no elephant foot, AA on."""
    bed = f"0x0,{d.width_mm:g}x0,{d.width_mm:g}x{d.height_mm:g},0x{d.height_mm:g}"
    cfg = {
        "printer_technology": "SLA",
        "printer_model": "SL1S" if d is SL1S else "SL1",
        "bed_shape": bed,
        "display_width": f"{d.width_mm:g}",
        "display_height": f"{d.height_mm:g}",
        "display_pixels_x": d.pixels_x,
        "display_pixels_y": d.pixels_y,
        "display_orientation": "landscape",
        "display_mirror_x": int(d.mirror_x),
        "display_mirror_y": 0,
        "gamma_correction": 1,  # anti-aliasing on (0 would threshold)
        "absolute_correction": 0,
        "elefant_foot_compensation": 0,
        "relative_correction": "1,1",
        "supports_enable": 0,
        "pad_enable": 0,
        "hollowing_enable": 0,
        "layer_height": f"{layer_height_mm:g}",
        "initial_layer_height": f"{layer_height_mm:g}",
        "exposure_time": 2,
        "initial_exposure_time": 20,
        "faded_layers": 10,
        "max_print_height": 150,
        "material_correction": "1,1,1",
    }
    return "".join(f"{k} = {v}\n" for k, v in cfg.items())


def _rotoprint_cmd() -> list[str]:
    exe = Path(sys.executable).with_name("rotoprint")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rotoprint.cli.main"]


TIME = "/usr/bin/time"


def run_process(cmd: list[str], env: dict | None = None) -> tuple[float, float]:
    """Run ``cmd``; returns (wall seconds, peak RSS MiB of the process).

    The peak comes from GNU time (``%M``), which forks the command from its own small
    process: Linux keeps a process's peak RSS across fork and exec, so a command forked from
    this (large) bench process would report at least the bench's own peak."""
    t0 = time.perf_counter()
    p = subprocess.run([TIME, "-f", "MAXRSS_KB=%M", *cmd], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
    wall = time.perf_counter() - t0
    err = p.stderr.decode(errors="replace")
    if p.returncode:
        raise RuntimeError(f"{' '.join(cmd)} failed ({p.returncode}):\n{err[-2000:]}")
    kb = [int(line.split("=", 1)[1]) for line in err.splitlines() if line.startswith("MAXRSS_KB=")]
    return wall, kb[-1] / 1024.0


def layer_areas_mm2(path: Path) -> tuple[np.ndarray, float]:
    """Per-layer grey-sum area of an SL1/SL1S archive, and its pixel area (mm^2)."""
    import io
    import zipfile

    from PIL import Image

    with zipfile.ZipFile(path) as zf:
        ini = dict(
            (k.strip(), v.strip())
            for k, v in (line.split("=", 1) for line in zf.read("prusaslicer.ini").decode().splitlines() if "=" in line)
        )
        w_mm, h_mm = float(ini["display_width"]), float(ini["display_height"])
        px_x, px_y = int(ini["display_pixels_x"]), int(ini["display_pixels_y"])
        px_area = (w_mm / px_x) * (h_mm / px_y)
        names = sorted(n for n in zf.namelist() if n.endswith(".png") and "/" not in n)
        sums = []
        for n in names:
            with Image.open(io.BytesIO(zf.read(n))) as im:
                a = np.asarray(im.convert("L"))
            sums.append(int(a.sum(dtype=np.uint64)))
    return np.asarray(sums, np.float64) / 255.0 * px_area, px_area


def grey_iou(a: Path, b: Path) -> float:
    """Grey-level IoU of two archives' layers: sum(min(a, b)) / sum(max(a, b)) over every pixel
    of every layer (1 = the same masks)."""
    import io
    import zipfile

    from PIL import Image

    inter = union = 0
    with zipfile.ZipFile(a) as za, zipfile.ZipFile(b) as zb:
        na = sorted(n for n in za.namelist() if n.endswith(".png") and "/" not in n)
        nb = sorted(n for n in zb.namelist() if n.endswith(".png") and "/" not in n)
        for x, y in zip(na, nb):
            with Image.open(io.BytesIO(za.read(x))) as ia, Image.open(io.BytesIO(zb.read(y))) as ib:
                ga, gb = np.asarray(ia.convert("L")), np.asarray(ib.convert("L"))
            inter += int(np.minimum(ga, gb).sum(dtype=np.uint64))
            union += int(np.maximum(ga, gb).sum(dtype=np.uint64))
    return inter / union if union else 1.0


def exact_areas_mm2(mesh_path: Path, preset: str, layer_height_mm: float, n_layers: int) -> np.ndarray:
    """Exact area of the mesh's section at ``z_min + (i + 0.5) * layer_height`` (shoelace)."""
    from rotoprint import load_device, load_mesh, slice_mesh

    mesh = load_mesh(mesh_path)
    job = slice_mesh(mesh, load_device(preset), layer_height_mm=layer_height_mm)
    z0 = float(mesh.bounds[0][2])
    out = np.zeros(n_layers)
    for i in range(n_layers):
        seg, _ = job.segments_at(z0 + (i + 0.5) * layer_height_mm)
        s, e = seg.start, seg.end
        out[i] = 0.5 * float(np.sum(s[:, 0] * e[:, 1] - e[:, 0] * s[:, 1]))
    return out


def area_error(archive: Path, mesh_path: Path, preset: str, layer_height_mm: float) -> tuple[float, float, int]:
    """Worst per-layer relative grey-sum area error over the sections of at least 1 mm^2 and
    of at least 10 mm^2, and the layer count."""
    got, _ = layer_areas_mm2(archive)
    exact = exact_areas_mm2(mesh_path, preset, layer_height_mm, len(got))
    out = []
    for least in (1.0, 10.0):
        keep = exact >= least
        out.append(float(np.max(np.abs(got[keep] - exact[keep]) / exact[keep])) if keep.any() else float("nan"))
    return out[0], out[1], len(got)


def run(quick: bool) -> list[dict]:
    prusa = shutil.which("prusa-slicer")
    if prusa is None:
        print("PrusaSlicer table skipped: prusa-slicer is not installed (apt-get install prusa-slicer)", flush=True)
        return []
    if not os.access(TIME, os.X_OK):
        print(f"PrusaSlicer table skipped: {TIME} (GNU time, Debian package 'time') is needed for peak RSS", flush=True)
        return []
    from rotoprint.examples import write_binary_stl

    _compile_rotoprint()
    cases = [c for c in CASES if c.quick or not quick]
    rounds = 1 if quick else ROUNDS
    env = dict(os.environ)
    env.setdefault("SOURCE_DATE_EPOCH", "1700000000")
    results: dict[tuple[str, str], list[tuple[float, float]]] = {}
    sizes: dict[tuple[str, str], int] = {}
    with tempfile.TemporaryDirectory(prefix="rotoprint-vs-prusa-") as tmp:
        tmp = Path(tmp)
        files = {}
        for k, c in enumerate(cases):
            stl = tmp / f"case{k}.stl"
            write_binary_stl(stl, _triangles(c))
            ini = tmp / f"case{k}.ini"
            ini.write_text(prusa_profile(c.display, c.layer_height_mm))
            files[c.name] = (stl, ini)
        for _ in range(rounds):
            for c in cases:
                stl, ini = files[c.name]
                for tool in ("rotoprint", "prusaslicer"):
                    wall, rss, size = _one(c, tool, stl, ini, tmp, prusa, env)
                    results.setdefault((c.name, tool), []).append((wall, rss))
                    sizes[(c.name, tool)] = size
        import json

        print("timings (wall s, peak RSS MiB) per run:", json.dumps({f"{k[0]} | {k[1]}": v for k, v in results.items()}),
              "archive bytes:", json.dumps({f"{k[0]} | {k[1]}": v for k, v in sizes.items()}), flush=True)
        rows = []
        for c in cases:
            stl, _ = files[c.name]
            row = {"case": c.name}
            for tool in ("rotoprint", "prusaslicer"):
                runs = results[(c.name, tool)]
                row[f"{tool} wall s"] = statistics.median(r[0] for r in runs)
                row[f"{tool} peak RSS MiB"] = statistics.median(r[1] for r in runs)
                row[f"{tool} archive MB"] = sizes[(c.name, tool)] / 1e6
            for tool in ("rotoprint", "prusaslicer"):
                err1, err10, n = area_error(_out_path(tmp, c, tool), stl, c.display.preset, c.layer_height_mm)
                row[f"{tool} layers"] = n
                row[f"{tool} worst area err (>= 1 mm2)"] = err1
                row[f"{tool} worst area err (>= 10 mm2)"] = err10
            # as text: the table prints 4 significant digits, and these differ in the 5th
            row["grey IoU rotoprint / prusaslicer"] = f"{grey_iou(_out_path(tmp, c, 'rotoprint'), _out_path(tmp, c, 'prusaslicer')):.6f}"
            row["wall ratio"] = row["rotoprint wall s"] / row["prusaslicer wall s"]
            row["RSS ratio"] = row["rotoprint peak RSS MiB"] / row["prusaslicer peak RSS MiB"]
            row["bytes ratio"] = row["rotoprint archive MB"] / row["prusaslicer archive MB"]
            rows.append(row)
        return rows


def _compile_rotoprint() -> None:
    """Byte-compile rotoprint's modules before timing, as an installed wheel has them: an
    editable install run with ``PYTHONDONTWRITEBYTECODE=1`` (set in some environments, this
    machine's sessions among them) would otherwise compile its ~50 modules in every process,
    about 0.06 s of the 10-layer plate's 0.2 s of CPU."""
    import compileall

    import rotoprint

    compileall.compile_dir(str(Path(rotoprint.__file__).parent), quiet=1)


def _out_path(tmp: Path, c: Case, tool: str) -> Path:
    return tmp / f"{tool}-case{CASES.index(c)}.sl1s"


def _one(c: Case, tool: str, stl: Path, ini: Path, tmp: Path, prusa: str, env: dict) -> tuple[float, float, int]:
    out = _out_path(tmp, c, tool)
    if tool == "rotoprint":
        cmd = [*_rotoprint_cmd(), "dlp", str(stl), "--device", c.display.preset, "--layer-height",
               f"{c.layer_height_mm:g}", "--mode", "coverage", "--out", str(out), "--quiet"]
    else:
        cmd = [prusa, "--export-sla", "--loglevel", "1", "--load", str(ini), str(stl), "-o", str(out)]
    wall, rss = run_process(cmd, env)
    return wall, rss, out.stat().st_size


def plate_rounds(rounds: int = 15) -> dict:
    """The 10-layer plate alone, both programs alternating ``rounds`` times: min and median of
    the wall time and of the CPU time (user + sys of the process and its threads, from
    ``wait4``), seconds. The commands are the table's; the processes are spawned directly
    (peak RSS is not taken here, see :func:`run_process`)."""
    prusa = shutil.which("prusa-slicer")
    if prusa is None:
        raise SystemExit("prusa-slicer is not installed (apt-get install prusa-slicer)")
    from rotoprint.examples import write_binary_stl

    _compile_rotoprint()
    c = CASES[-1]
    env = dict(os.environ)
    env.setdefault("SOURCE_DATE_EPOCH", "1700000000")
    got: dict[str, list[tuple[float, float]]] = {"rotoprint": [], "prusaslicer": []}
    with tempfile.TemporaryDirectory(prefix="rotoprint-vs-prusa-plate-") as tmp:
        tmp = Path(tmp)
        stl, ini = tmp / "plate.stl", tmp / "plate.ini"
        write_binary_stl(stl, _triangles(c))
        ini.write_text(prusa_profile(c.display, c.layer_height_mm))
        cmds = {
            "rotoprint": [*_rotoprint_cmd(), "dlp", str(stl), "--device", c.display.preset, "--layer-height",
                          f"{c.layer_height_mm:g}", "--mode", "coverage", "--out", str(tmp / "r.sl1s"), "--quiet"],
            "prusaslicer": [prusa, "--export-sla", "--loglevel", "1", "--load", str(ini), str(stl), "-o", str(tmp / "p.sl1s")],
        }
        for _ in range(rounds):
            for tool, cmd in cmds.items():
                t0 = time.perf_counter()
                with open(os.devnull, "wb") as null:
                    pid = os.posix_spawn(cmd[0], cmd, env, file_actions=[(os.POSIX_SPAWN_DUP2, null.fileno(), 1)])
                    _, status, ru = os.wait4(pid, 0)
                wall = time.perf_counter() - t0
                if status != 0:
                    raise RuntimeError(f"{' '.join(cmd)} failed ({status})")
                got[tool].append((wall, ru.ru_utime + ru.ru_stime))
    out = {"rounds": rounds, "load average before / after": None}
    for tool, runs in got.items():
        walls, cpus = sorted(r[0] for r in runs), sorted(r[1] for r in runs)
        out[tool] = {"wall s min / median": (round(walls[0], 4), round(statistics.median(walls), 4)),
                     "CPU s min / median": (round(cpus[0], 4), round(statistics.median(cpus), 4))}
    ratio = statistics.median(r[0] for r in got["rotoprint"]) / statistics.median(r[0] for r in got["prusaslicer"])
    out["wall ratio (medians)"] = round(ratio, 3)
    return out


if __name__ == "__main__":  # python bench/bench_prusaslicer.py [ROUNDS]: the plate alone, alternating
    load0 = os.getloadavg()
    res = plate_rounds(int(sys.argv[1]) if len(sys.argv) > 1 else 15)
    res["load average before / after"] = (round(load0[0], 2), round(os.getloadavg()[0], 2))
    for k, v in res.items():
        print(f"{k}: {v}")
