"""Write the DLP feature test piece (like the paper's: 10 mm square, 1.6 mm high, walls,
channels, ring walls and ring gaps 10-200 um wide) as ``examples/test_piece.stl``, and its
feature list as ``examples/test_piece_features.json``.

    python examples/make_test_piece.py [OUT.stl]
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from rotoprint.examples import write_binary_stl
from rotoprint.pieces import feature_test_piece


def main(argv: list[str]) -> int:
    out = Path(argv[0]) if argv else Path(__file__).resolve().parent / "test_piece.stl"
    tris, features = feature_test_piece()
    write_binary_stl(out, tris)
    out.with_name(out.stem + "_features.json").write_text(
        json.dumps([f.to_json() for f in features], indent=1), encoding="utf-8"
    )
    print(f"{out}: {len(tris)} triangles, {len(features)} features")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
