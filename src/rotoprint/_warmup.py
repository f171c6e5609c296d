"""Compile and cache the jit kernels at install time: ``python -m rotoprint._warmup``.

numba keeps its cache in ``__pycache__`` next to the sources, so an editable install in a
fresh clone starts cold, and the first ``rotoprint demo`` / ``check`` / ``slice --rotary``
would spend a minute compiling. ``make`` runs this once after installing: the demo, checks
(a feature piece with overlays and the exposure model, an open mesh), slices of a small part,
exact transforms and a simulation, and the DLP modes run in two processes at once (the
machine's cores), each compile shown as a line, and each kernel compiled by one of the two
only (:func:`share_compiles`). Later runs load the kernels from the cache. :data:`WARMED`
lists the kernels this compiles, :data:`NOT_WARMED` the others and why.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path


#: The cached jit kernels (``@njit(cache=True)``, not inlined) that the commands of
#: :func:`_commands` compile, by module; a kernel called by another is compiled with it. Measured:
#: the cache index files a cold warm-up writes (``python bench/warmup_cover.py``, which also
#: fails when this list and a cold warm-up disagree); ``tests/test_warmup.py`` fails when a
#: kernel in the sources is in neither this list nor :data:`NOT_WARMED`.
WARMED: dict[str, tuple[str, ...]] = {
    "rotoprint.check._cavities": ("empty_runs", "cavity_step"),
    "rotoprint.check._kernels.chains": ("chain_components", "chain_successors", "_chain_runs"),
    "rotoprint.check._kernels.classify": ("_bands", "_winding", "classify_segments"),
    "rotoprint.check._kernels.crossings": ("_split_cell_size", "_pt_seg_d2", "_isolate", "_near", "split_at_crossings", "_rects_apart", "_run_pairs", "_split_cells", "_grid_pairs", "_split"),
    "rotoprint.check._kernels.grid": ("_cell_size",),
    "rotoprint.check._kernels.groups": ("_sort_pixels", "group_chords_in", "group_stats", "emit_groups"),
    "rotoprint.check._kernels.layer": ("_below", "_argmin_finite", "_check_layer"),
    "rotoprint.check._kernels.pointhash": ("_keys", "_key_table"),
    "rotoprint.check._kernels.raster": ("paint_chords", "_runs_at", "chord_presence_runs", "chord_extreme", "_absent_runs"),
    "rotoprint.check._kernels.runs": ("fill_runs", "island_runs", "section_runs", "_island_stats"),
    "rotoprint.check._kernels.simplify": ("_greedy_emit", "simplify_section"),
    "rotoprint.check._kernels.unionfind": ("_find", "_union", "_relabel"),
    "rotoprint.check._kernels.widths": ("_run_clear", "sample_widths", "_seg_cells", "sample_widths_chained", "measure_widths"),
    "rotoprint.rotary._deposit_kernels": ("deposit_strip_jit", "interior_rows_jit", "strip_stats_jit", "pair_counts_jit", "radial_cell_counts_jit"),
    "rotoprint.rotary._direct_kernels": ("_scanline_fill", "_direct_fill"),
    "rotoprint.rotary._edgecomp_kernels": ("restore_candidates_jit", "radial_near_jit"),
    "rotoprint.rotary._exact_kernels": ("_coords_nb", "_bilinear_nb", "_track_windows_nb", "_window_bounds_nb", "_windows_fill_nb", "_windows_fill_gather_nb", "_ink_blocks_nb", "_windows_sample_thin_nb", "_binary_levels_nb"),
    "rotoprint.rotary._equalise_kernels": ("profile_jit", "level_at_jit", "settle_jit", "drop_round_jit"),
    "rotoprint.rotary._halftone_kernels": ("diffuse_jit",),
    "rotoprint.rotary._interlace_kernels": ("max_gaps_jit", "profile_add_jit", "profile_base_jit", "shortfall_terms_jit", "candidate_gaps_jit", "candidate_radii_jit", "sorted_gaps_jit"),
    "rotoprint.rotary._levelling_kernels": ("restrict_wet_jit", "prolong_combine_jit", "film_stats_jit"),
    "rotoprint.slicing._kernels": ("bucket_crossings", "union_labels"),
}

_C_FALLBACK = ("the C extension's kernel runs instead (rotoprint._native); where it is not built, the warm-up's "
               "dlp, slice and check commands take this fallback (that path's warm-up is not measured)")
#: The cached kernels no command reaches on a first run with the C extension built, and why.
NOT_WARMED: dict[str, str] = {
    "rotoprint.masks._coverage_kernels.accumulate_jit": _C_FALLBACK,
    "rotoprint.masks._coverage_kernels.resolve_jit": (
        "library API only (rotoprint.masks.coverage_fraction, backend='jit'); no command calls it"),
    "rotoprint.masks._coverage_kernels.resolve_grey_jit": _C_FALLBACK,
    "rotoprint.masks._coverage_kernels.resolve_nearest_jit": _C_FALLBACK,
    "rotoprint.slicing._kernels._fill_spans": _C_FALLBACK,
    "rotoprint.slicing._kernels._crossing": _C_FALLBACK,
    "rotoprint.slicing._kernels.section_kernel": _C_FALLBACK,
    "rotoprint.rotary._exact_kernels._windows_gather_nb": (
        "the second gather through exact maps already filled (the library's ExactMaps reused for another "
        "design on the same lattice); no command reuses maps, the first gather is _windows_fill_gather_nb"),
    "rotoprint.rotary._thin_kernels.thin_levels_jit": (
        "library API (rotoprint.rotary.equalise.thin_print) and the thinning of grey designs sampled with ThinShares; "
        "the commands' equalised binary passes thin while sampling (_windows_sample_thin_nb), grey heads halftone"),
}


def _grey_device(tmp: Path) -> Path:
    """A copy of the omnidot760 preset with 4 drop sizes: an equalised grey-level head reaches
    the halftone kernel."""
    from importlib import resources

    text = (resources.files("rotoprint.devices") / "presets" / "omnidot760.toml").read_text(encoding="utf-8")
    text = text.replace('name = "omnidot760"', 'name = "warmup-grey"').replace("grey_levels = 1", "grey_levels = 4")
    path = tmp / "grey-head.toml"
    path.write_text(text, encoding="utf-8")
    return path


def _inputs(tmp: Path) -> dict[str, Path]:
    """The small inputs the warm-up's commands read (written into ``tmp``)."""
    import numpy as np
    from PIL import Image

    from .examples import write_binary_stl
    from .pieces import feature_test_piece
    from .testing import box_triangles, torus_mesh

    paths = {k: tmp / v for k, v in (("part", "part.stl"), ("box", "box.stl"), ("piece", "piece.stl"),
                                      ("open", "open.stl"), ("design", "design.png"), ("grey", "grey.png"))}
    torus = torus_mesh(4.0, 1.5, 48, 24).triangles
    write_binary_stl(paths["part"], torus)
    write_binary_stl(paths["box"], box_triangles((3.0, 2.0, 0.4)))
    # walls and channels of 10-200 um: a check finds some (the grouping and overlay kernels)
    write_binary_stl(paths["piece"], feature_test_piece(height_mm=0.9, base_mm=0.3, ring_segments=90)[0])
    write_binary_stl(paths["open"], torus[: len(torus) - 48])  # a ring of faces missing: open sections
    design = np.zeros((60, 90), np.uint8)
    design[10:50, 15:75] = 255
    Image.fromarray(design).save(paths["design"])
    Image.fromarray(np.tile(np.linspace(0, 255, 90).astype(np.uint8), (60, 1))).save(paths["grey"])
    paths["grey_head"] = _grey_device(tmp)
    return paths


def _commands(tmp: Path) -> list[list[list[str]]]:
    """Two groups of rotoprint commands (one per process), together touching every kernel a
    user's first command can reach with the C extension built (the jit fallbacks of the C
    kernels compile here too when it is not: the commands are the same)."""
    p = _inputs(tmp)
    rot = ["--tilt", "20", "--radius", "60"]
    for name in ("tr", "tr-grey", "tr-passes", "tr-steep"):
        (tmp / name).mkdir()
    a = [
        # the exact transform, binary and grey designs; the halftone of a grey-level head
        ["transform", str(p["design"]), "--device", "omnidot760", *rot, "--out", str(tmp / "tr" / "PRINT.png"), "-q"],
        ["transform", str(p["grey"]), "--device", str(p["grey_head"]), *rot, "--passes", "auto", "--equalise",
         "--out", str(tmp / "tr-grey" / "PRINT.png"), "-q"],
        ["transform", str(p["design"]), "--device", "omnidot760", *rot, "--passes", "auto", "--equalise",
         "--out", str(tmp / "tr-passes" / "PRINT.png"), "-q"],
        # a steep tilt: the equalisation leaves whole tracks out where they crowd (drop_round_jit)
        ["transform", str(p["design"]), "--device", "omnidot760", "--tilt", "70", "--radius", "60", "--passes", "auto",
         "--equalise", "--out", str(tmp / "tr-steep" / "PRINT.png"), "-q"],
        # the deposit model and the coarse-grid film levelling
        ["simulate", str(tmp / "tr-passes" / "PRINT-passes.json"), "--out", str(tmp / "sim.png"), "--json"],
        ["demo", "--out", str(tmp / "demo")],
    ]
    b = [
        # findings grouped, overlays painted, the exposure model's extremes
        ["check", str(p["piece"]), "--device", "perfactory-sxga", "--layer-height", "0.3", "--mask", "binary",
         "--out", str(tmp / "chk"), "--json"],
        ["check", str(p["part"]), "--device", "omnidot760", "--layer-height", "0.5", "--json"],
        # open sections joined across their gaps
        ["check", str(p["open"]), "--device", "omnidot760", "--layer-height", "0.5", "--no-fill-holes", "--json"],
        ["slice", str(p["part"]), "--device", "omnidot760", "--rotary", *rot, "--angle", "0",
         "--layer-height", "0.5", "--out", str(tmp / "rot"), "--reference-images", "-q"],
        ["slice", str(p["part"]), "--device", "perfactory-sxga", "--layer-height", "0.5", "--out", str(tmp / "cart"), "-q"],
    ]
    for mode in ("binary", "smooth", "coverage"):
        b.append(["dlp", str(p["box"]), "--device", "perfactory-sxga", "--layer-height", "0.2", "--mode", mode,
                  "--first-layers", "1", "--first-layer-offset", "20", "--out", str(tmp / f"dlp-{mode}"), "-q"])
    return [a, b]


def share_compiles(lock_dir: str) -> None:
    """Let the warm-up processes compile each kernel once between them.

    Both processes run commands that touch some of the same kernels (the demo checks its
    parts, as ``rotoprint check`` does). Each kernel's compile is made to take an exclusive
    lock on ``lock_dir/<module>.<name>.lock`` first: the process that comes second waits, and
    numba's ``Dispatcher.compile`` then finds the kernel in the disk cache the first one
    wrote, and loads it instead of compiling it again. Kernels calling kernels take their
    locks in call order (callers before callees, and a call graph has no cycles), so two
    processes cannot wait on each other; a kernel already locked by this process (its own
    nested compiles) is not locked again.
    """
    import fcntl

    from numba.core.dispatcher import Dispatcher

    original = Dispatcher.compile
    held: set[str] = set()
    one_thread = threading.RLock()  # numba compiles one kernel at a time per process anyway

    def compile_once(self, sig):
        fn = self.py_func
        key = f"{fn.__module__}.{fn.__qualname__}"
        with one_thread:
            if key in held:
                return original(self, sig)
            with open(os.path.join(lock_dir, key + ".lock"), "w") as fh:
                fcntl.flock(fh, fcntl.LOCK_EX)
                held.add(key)
                try:
                    return original(self, sig)
                finally:
                    held.discard(key)
                    fcntl.flock(fh, fcntl.LOCK_UN)

    Dispatcher.compile = compile_once


def run_commands(cmds: list[list[str]]) -> int:
    """Run the rotoprint commands ``cmds`` in this process; 0, or the first failure's exit code
    (named on stderr). ``check`` may exit 3: the part has features below the device's minimum
    (the feature piece has, on purpose)."""
    from .cli.main import main

    for c in cmds:
        rc = main(c)
        if rc not in ((0, 3) if c[0] == "check" else (0,)):
            print(f"warm-up: 'rotoprint {' '.join(c)}' exited {rc}", file=sys.stderr, flush=True)
            return int(rc or 1)
    return 0


#: Seconds without a compile line after which the warm-up says it is still at work (one kernel
#: can compile for a minute on a loaded 2-core machine, and its line is printed when it starts).
HEARTBEAT_S = 30.0
_last_line = [time.perf_counter()]


def _run_group(cmds: list[list[str]], env: dict, lock_dir: str) -> tuple[subprocess.Popen, threading.Thread]:
    """Run ``cmds`` in one process; pass on only its compile lines (and, on failure, the rest)."""
    code = (f"import sys; from rotoprint._warmup import share_compiles, run_commands; share_compiles({lock_dir!r}); "
            f"sys.exit(run_commands({cmds!r}))")
    proc = subprocess.Popen([sys.executable, "-c", code], env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True, errors="replace")
    other: list[str] = []

    def relay() -> None:
        for line in proc.stderr:
            if line.startswith(("compiling jit kernel", "compiled ")):
                print("  " + line.rstrip(), flush=True)
                _last_line[0] = time.perf_counter()
            else:
                other.append(line)

    t = threading.Thread(target=relay, daemon=True)
    t.start()
    t.other = other  # type: ignore[attr-defined]
    return proc, t


def main() -> int:
    env = {**os.environ, "ROTOPRINT_COMPILE_NOTICE": "1"}
    t0 = time.perf_counter()
    print("rotoprint: compiling the jit kernels once (cached for every later run)...", flush=True)
    with tempfile.TemporaryDirectory(prefix="rotoprint-warmup-") as tmp:
        locks = Path(tmp) / "locks"
        locks.mkdir()
        runs = [_run_group(g, env, str(locks)) for g in _commands(Path(tmp))]
        _last_line[0] = time.perf_counter()
        while any(p.poll() is None for p, _ in runs):
            time.sleep(0.5)
            if time.perf_counter() - _last_line[0] >= HEARTBEAT_S:
                print(f"  ... still compiling and running the warm-up's commands ({time.perf_counter() - t0:.0f} s so far)", flush=True)
                _last_line[0] = time.perf_counter()
        codes = [p.wait() for p, _ in runs]
        for _, t in runs:
            t.join()
    if any(codes):
        for (_, t), c in zip(runs, codes):
            if c:
                sys.stderr.write("".join(t.other[-20:]))
        print(f"rotoprint: warm-up failed (exit codes {codes}); kernels will compile on first use", file=sys.stderr)
        return 1
    print(f"rotoprint: kernels ready in {time.perf_counter() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
