"""The bundled example jobs say what they print: examples/ holds the job files
:mod:`rotoprint.process.examples` writes (``rotoprint demo`` writes the same), each job reads,
and an ``equalise = true`` line's comment describes the default print (the interlaced
passes print their shares of the union-equalised film), not the single-pass thinning that
came before it ("inner tracks thinned")."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from rotoprint.process.examples import EXAMPLES, example_files
from rotoprint.process.job import parse_job

EXAMPLES_DIR = Path(__file__).resolve().parents[2] / "examples"
#: Words of the print before passes were union-equalised (a track thinned on its own).
STALE = re.compile(r"tracks? (are )?thinned|thinned to the lowest", re.IGNORECASE)


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_the_examples_folder_holds_the_packages_job(name):
    """The job file byte for byte (the meshes and CAD files are not compared: ezdxf writes a
    DXF's CLASSES in an order that changes with the interpreter's hash seed)."""
    job_name = EXAMPLES[name][0]
    on_disk = EXAMPLES_DIR / name / job_name
    assert on_disk.is_file(), f"examples/{name}/{job_name} missing: run examples/make_sensors.py"
    assert on_disk.read_bytes() == example_files(name)[job_name], \
        f"examples/{name}/{job_name} differs from rotoprint.process.examples: run examples/make_sensors.py"


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_an_example_job_describes_the_print_it_makes(name):
    import tomllib

    job_name = EXAMPLES[name][0]
    text = example_files(name)[job_name].decode()
    d = tomllib.loads(text)
    spec = parse_job(d, base_dir=EXAMPLES_DIR / name, source=job_name).spec
    for line in text.splitlines():
        if line.split("#")[0].strip().startswith("equalise"):
            comment = line.partition("#")[2]
            assert not STALE.search(comment), f"{job_name}: {line.strip()!r}"
            if comment and spec.printer.equalise and spec.printer.passes != 1:
                assert "union" in comment, f"{job_name}: {line.strip()!r} does not say the passes are union-equalised"
