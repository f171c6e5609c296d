"""Acceptance round trip of issue 3 as a markdown table (docs/rotary.md): 1200 x 1200 test
design at 360 dpi, first column at 60 mm, tilts 0/20/45/70, exact and paper methods.

    PYTHONPATH=src python bench/rotary_acceptance.py
"""

from __future__ import annotations

from rotoprint import load_device
from rotoprint.rotary import Placement, simulate, transform_exact
from rotoprint.rotary.paper import transform_paper
from rotoprint.rotary.testimage import test_design


def main() -> None:
    head = load_device("omnidot760").head
    d = test_design(1200)
    px = 25.4 / 360
    pl = Placement(1200, 1200, px, px, inner_radius_mm=60.0)
    print("| tilt deg | method | swathes | IoU | area ratio | mean err px | max err px | uncovered % | drops outside % | IoU, 60 um discs |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for tilt in (0.0, 20.0, 45.0, 70.0):
        for name, fn in (("exact", transform_exact), ("paper", transform_paper)):
            pr = fn(d, head, pl, tilt_deg=tilt)
            r = simulate(pr, d).report
            print(f"| {tilt:g} | {name} | {len(pr.swathes)} | {r.iou:.4f} | {r.area_ratio:.4f} | {r.mean_error_px:.3f} | "
                  f"{r.max_error_px:.3f} | {100 * r.uncovered_fraction:.2f} | {100 * r.drops_outside_fraction:.2f} | {r.disc_iou:.4f} |")


if __name__ == "__main__":
    main()
