"""A/B of the equalised shares against another checkout (e.g. main): identical arrays and CPU time.

    PYTHONPATH=src python bench/shares_ab.py OTHER_SRC [REPEATS]

Each tree runs in its own process (``PYTHONPATH`` = its ``src``): the shares as ``pass_prints``
computes them (``track_fractions`` with the lattice-reach floors, then with dead nozzles the dead
cover) for the acceptance bench's setup (1200 x 1200 test design at 360 dpi from 60 mm, tilts
0/20/45/70, without and with 5 seeded dead nozzles), pickled; the two are compared with
``np.array_equal`` per pass and swathe, and the best of REPEATS (default 3) CPU seconds printed.
"""

from __future__ import annotations

import os
import pickle
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _cases():
    import dataclasses

    import numpy as np

    from rotoprint import load_device
    from rotoprint.rotary import Placement, plan_swathes
    from rotoprint.rotary.interlace import COVER_SHARE, EQUALISE_CLOCK_FACTOR, ReachFloor, plan_passes, track_fractions
    from rotoprint.rotary.options import RotarySetup

    head0 = load_device("omnidot760").head
    px = 25.4 / 360
    r_in, r_out = Placement(1200, 1200, px, px, inner_radius_mm=60.0).radial_range_mm()
    for tilt in (0.0, 20.0, 45.0, 70.0):
        sp = plan_swathes(head0, tilt_deg=tilt, inner_radius_mm=r_in, outer_radius_mm=r_out)
        rng = np.random.default_rng(14)
        dead = tuple(sorted(int(k) for k in rng.choice(np.flatnonzero(sp.swathes[0].enabled), 5, replace=False)))
        pp = plan_passes(head0, sp, footprint_um=49.6)
        for h in (head0, head0.model_copy(update={"dead_nozzles": dead})):
            st = RotarySetup(tilt_deg=tilt, dpi_y=pp.dpi_y)
            cover = bool(h.dead_nozzles and pp.passes > 1)

            def shares(h=h, sp=sp, pp=pp, st=st, cover=cover):
                fr = track_fractions(h, sp, pp.offsets_mm, st, footprint_um=49.6,
                                     reach=ReachFloor(COVER_SHARE * 49.6, EQUALISE_CLOCK_FACTOR), dead_nozzles=() if cover else None)
                if cover:
                    from rotoprint.rotary.deadcover import cover_dead_tracks

                    fr, _ = cover_dead_tracks(h, sp, pp.offsets_mm, dataclasses.replace(st, dpi_y=pp.dpi_y * EQUALISE_CLOCK_FACTOR),
                                              shares=fr, footprint_um=49.6)
                return fr

            yield f"tilt {tilt:g}{', 5 dead' if h.dead_nozzles else ''}", shares


def _child(out: str, repeats: int) -> None:
    res = {}
    for name, fn in _cases():
        fr = fn()
        best = float("inf")
        for _ in range(repeats):
            t = time.process_time()
            fn()
            best = min(best, time.process_time() - t)
        res[name] = (fr, best)
    Path(out).write_bytes(pickle.dumps(res))


def main() -> None:
    if sys.argv[1] == "--child":
        _child(sys.argv[2], int(sys.argv[3]))
        return
    other = Path(sys.argv[1]).resolve()
    repeats = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    here = Path(__file__).resolve().parents[1] / "src"
    import numpy as np

    got = {}
    with tempfile.TemporaryDirectory() as td:
        for label, src in (("other", other), ("this", here)):
            p = Path(td) / f"{label}.pkl"
            subprocess.run([sys.executable, __file__, "--child", str(p), str(repeats)], check=True,
                           env={**os.environ, "PYTHONPATH": str(src)})
            got[label] = pickle.loads(p.read_bytes())
    print("| case | other ms | this ms | ratio | shares identical |")
    print("|---|---|---|---|---|")
    for name, (fa, ta) in got["other"].items():
        fb, tb = got["this"][name]
        same = len(fa) == len(fb) and all(np.array_equal(x, y) for p, q in zip(fa, fb) for x, y in zip(p, q))
        print(f"| {name} | {1e3 * ta:.0f} | {1e3 * tb:.0f} | {ta / tb:.2f} | {same} |")


if __name__ == "__main__":
    main()
