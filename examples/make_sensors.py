"""Write the two sensor examples (job files and meshes) into examples/.

    python examples/make_sensors.py            # then: rotoprint build examples/coil-sensor/coil-sensor.toml --out coil-build

The text and geometry live in rotoprint.process.examples, so that `rotoprint demo` can write
the same files after a plain `pip install`.
"""

from __future__ import annotations

from pathlib import Path

from rotoprint.pipeline.examples import write_example
from rotoprint.process.examples import EXAMPLES

if __name__ == "__main__":
    here = Path(__file__).resolve().parent
    for name in EXAMPLES:
        print(write_example(name, here / name, overwrite=True))  # these folders are ours
