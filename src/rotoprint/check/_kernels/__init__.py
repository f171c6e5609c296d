"""Jit kernels of the printability check (numba), one module per algorithm. Inputs are
validated by the callers in :mod:`rotoprint.check.core`; everything here takes contiguous
float64 / int64 / uint8 arrays. Geometry is in model millimetres on the exact cross-section
(the slicer's segments); raster work in pixel indices ``(col, row)``.

What the checker calls, per layer:

- :func:`~.simplify.simplify_section` (:mod:`.simplify`): the section with its chains
  simplified to the resolution, on which widths are measured;
- :func:`~.layer.check_layer` (:mod:`.layer`), the rest of the layer in one call, returning a
  :class:`~.layer.LayerResult`:

  - :func:`~.runs.section_runs` (:mod:`.runs`): the layer's material as runs of pixels per
    row by the slicer's own fill (equal to its image, which the check does not need);
  - :func:`~.widths.measure_widths` (:mod:`.widths`): the crossing search
    (:func:`~.crossings.split_at_crossings`, :mod:`.crossings`), the chains
    (:func:`~.chains.chain_components`, :func:`~.chains.chain_successors`, :mod:`.chains`),
    the boundary by the fill rule (:func:`~.classify.classify_segments`, :mod:`.classify`),
    then the wall and gap widths from samples along the boundary
    (:func:`~.widths.sample_widths_chained`), measured only as far as the findings need;
  - the selections against the thresholds and the raster tests on the runs
    (:func:`~.raster.chord_presence_runs`, :mod:`.raster`);
  - the islands over the layer below (:func:`~.runs.island_runs`);
- :func:`~.groups.emit_groups` (:mod:`.groups`): the chords of one kind grouped into findings;
- with an exposure model, :func:`~.raster.chord_extreme`: the peak or lowest grey along chords.

The overlays paint chords with :func:`~.raster.paint_chords`; the cavities
(:mod:`rotoprint.check._cavities`) use the union-find of :mod:`.unionfind`. Shared by the
modules: :mod:`.grid` (cell grids, ray set-up and hit test), :mod:`.pointhash` (points keyed by
their bits and the hash table of chain starts), :mod:`.unionfind` (find, union, relabelling).

Every kernel is compiled with ``cache=True``. Numba keys a cached function on its own file
only: a kernel calling one of another module keeps the callee it was compiled with. After
editing a module here, remove the package's cache (``find src/rotoprint/check -name
'*.nb[ic]' -delete``) before measuring or testing.

The plain references the tests compare these with (every width by casting every ray, the
image instead of runs, labelling a painted canvas, ...) are in the tests
(``tests/check/_reference_kernels.py``).
"""

from .chains import _chain_runs, chain_components, chain_successors  # noqa: F401 - _chain_runs: tests
from .classify import classify_segments
from .crossings import _split_cell_size, split_at_crossings  # noqa: F401 - _split_cell_size: tests
from .groups import emit_groups, group_chords_in, group_stats
from .layer import LayerParams, LayerResult, check_layer
from .pointhash import _keys  # noqa: F401 - tests
from .raster import chord_extreme, chord_presence_runs, paint_chords
from .runs import fill_runs, island_runs, section_runs
from .simplify import simplify_section
from .widths import measure_widths, sample_widths, sample_widths_chained

__all__ = [
    "LayerParams",
    "LayerResult",
    "chain_components",
    "chain_successors",
    "check_layer",
    "chord_extreme",
    "chord_presence_runs",
    "classify_segments",
    "emit_groups",
    "fill_runs",
    "group_chords_in",
    "group_stats",
    "island_runs",
    "measure_widths",
    "paint_chords",
    "sample_widths",
    "sample_widths_chained",
    "section_runs",
    "simplify_section",
    "split_at_crossings",
]
