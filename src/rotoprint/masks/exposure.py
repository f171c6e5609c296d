"""Exposure check: which thin walls and channels keep enough light to build.

A wall builds where, across it, some pixel reaches the cure threshold; a channel stays open
where, across it, some pixel stays below it. :func:`feature_exposure` measures that on one
mask for features of known position (:func:`rotoprint.pieces.feature_test_piece`), at every
pixel step along each feature. :func:`exposure_table` runs the modes over several sub-pixel
placements of the test piece (a 10 um wall on 19.8 um pixels lands differently on the grid
depending on where it falls) and summarises.

The model is deliberately simple: a pixel's dose is its grey level times the full dose, with
no optical blur and no resin spread (the paper's argument: smoothing lowers the peak across a
thin wall below what cures).
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from .._dataclass import dataclass
from ..errors import ConfigError

__all__ = ["FeatureExposure", "feature_exposure", "exposure_table", "format_exposure_table", "narrowest_kept_um"]


@dataclass(frozen=True)
class FeatureExposure:
    """Exposure of one feature in one mask.

    ``level`` is, for a wall, the lowest over its length of the peak grey level across it;
    for a channel, the highest over its length of the darkest level across it (fractions of
    full exposure). ``kept_fraction`` is the share of the feature's length where the wall
    reaches ``cure_threshold`` (channel: stays below it). ``kept`` means all of it.
    """

    kind: str
    width_mm: float
    level: float
    kept_fraction: float
    samples: int

    @property
    def kept(self) -> bool:
        return self.kept_fraction >= 1.0

    def to_json(self) -> dict:
        return {**asdict(self), "kept": self.kept}


def _feature_coords(feature, mx: np.ndarray, my: np.ndarray):
    """(across, along, half_width_lo, half_width_hi) of pixel centres in model mm / radians."""
    if feature.kind in ("wall", "channel"):
        return mx, my, feature.x0, feature.x1, feature.y0, feature.y1
    cx, cy = feature.centre
    dx, dy = mx - cx, my - cy
    return np.hypot(dx, dy), np.arctan2(dy, dx), feature.r_in, feature.r_out, -np.pi, np.pi


def feature_exposure(mask: np.ndarray, features, pixel_to_model: np.ndarray, *, pitch_mm: float, cure_threshold: float = 0.5) -> list[FeatureExposure]:
    """Measure every feature on one mask.

    Parameters
    ----------
    mask : (H, W) uint8
        White = expose (not inverted, not mirrored).
    features : sequence of :class:`rotoprint.pieces.Feature`
    pixel_to_model : (2, 3) float64
        Pixel ``(col, row)`` to model XY mm (``Grid.pixel_to_model``).
    pitch_mm : float
        Pixel size; pixels whose centre is within half a pixel of a feature (across it)
        count as on it, and the length is cut into steps of one pixel.
    cure_threshold : float
        Fraction of full exposure that cures, in ``[0, 1]``.

    Returns
    -------
    list of FeatureExposure
        In the order of ``features``. A feature with no pixel on it has ``samples == 0``
        (walls: level 0, not kept; channels: level 1, not kept).
    """
    if not 0.0 <= cure_threshold <= 1.0:
        raise ConfigError(f"cure threshold must be in [0, 1], got {cure_threshold}")
    m = np.asarray(mask)
    thr = cure_threshold * 255.0
    A = np.asarray(pixel_to_model, dtype=np.float64)
    inv = np.linalg.inv(A[:, :2])
    out = []
    for f in features:
        if f.kind in ("wall", "channel"):
            corners = np.array([[f.x0, f.y0], [f.x1, f.y0], [f.x0, f.y1], [f.x1, f.y1]])
        else:
            r = f.r_out
            corners = np.array([[f.centre[0] - r, f.centre[1] - r], [f.centre[0] + r, f.centre[1] + r],
                                [f.centre[0] - r, f.centre[1] + r], [f.centre[0] + r, f.centre[1] - r]])
        px = (corners - A[:, 2]) @ inv.T
        c0, r0 = np.floor(px.min(axis=0)).astype(int) - 2
        c1, r1 = np.ceil(px.max(axis=0)).astype(int) + 3
        c0, r0 = max(c0, 0), max(r0, 0)
        c1, r1 = min(c1, m.shape[1]), min(r1, m.shape[0])
        rr, cc = np.mgrid[r0:r1, c0:c1]
        mx = A[0, 0] * cc + A[0, 1] * rr + A[0, 2]
        my = A[1, 0] * cc + A[1, 1] * rr + A[1, 2]
        across, along, lo, hi, a0, a1 = _feature_coords(f, mx, my)
        half = 0.5 * pitch_mm
        if f.kind in ("wall", "channel"):
            on = (across >= lo - half) & (across <= hi + half) & (along >= a0 + pitch_mm) & (along <= a1 - pitch_mm)
            step = pitch_mm
            bins = np.floor((along - a0) / step).astype(np.int64)
        else:
            # a pixel square reaches up to half a diagonal across a ring at 45 degrees
            on = (across >= lo - half * np.sqrt(2)) & (across <= hi + half * np.sqrt(2))
            step = pitch_mm / max(0.5 * (lo + hi), pitch_mm)
            bins = np.floor((along - a0) / step).astype(np.int64)
        vals = m[r0:r1, c0:c1][on].astype(np.float64)
        b = bins[on]
        wall = f.kind in ("wall", "ring_wall")
        if vals.size == 0:
            out.append(FeatureExposure(f.kind, f.width_mm, 0.0 if wall else 1.0, 0.0, 0))
            continue
        ub, inverse = np.unique(b, return_inverse=True)
        if wall:
            per = np.full(len(ub), -np.inf)
            np.maximum.at(per, inverse, vals)
            ok = per >= thr
            level = per.min()
        else:
            per = np.full(len(ub), np.inf)
            np.minimum.at(per, inverse, vals)
            ok = per < thr
            level = per.max()
        out.append(FeatureExposure(f.kind, f.width_mm, float(level) / 255.0, float(ok.mean()), int(len(ub))))
    return out


def exposure_table(
    *,
    modes=("binary", "coverage", "smooth"),
    cure_threshold: float = 0.5,
    phases: int = 4,
    device: str = "perfactory-sxga",
    widths_mm=None,
    ring_segments: int = 720,
) -> list[dict]:
    """Run the exposure check on the generated test piece, one slice at mid-height (0.8 mm,
    through every feature).

    The piece is placed at ``phases x phases`` sub-pixel offsets (steps of ``1 / phases``
    pixel in x and y); for every feature and mode the rows give the worst ``level`` over
    the placements (walls: lowest peak; channels: highest trough), the mean
    ``kept_fraction``, and whether the feature was kept along all its length at every
    placement.

    Parameters
    ----------
    modes : sequence of {'binary', 'coverage', 'smooth'}
        Masks to compare: the binary slice, the exact-coverage mask, the binary slice after
        :func:`~rotoprint.masks.ops.smooth_mask`.
    cure_threshold : float
        Fraction of full exposure a pixel needs to cure, in [0, 1].
    phases : int
        Sub-pixel placements per axis (``phases ** 2`` slices per mode).
    device : str
        Name of the projector preset (see :func:`rotoprint.devices.load_device`).
    widths_mm : sequence of float, optional
        Feature widths of the test piece; default ``rotoprint.pieces.DEFAULT_WIDTHS_MM``.
    ring_segments : int
        Segments of each ring feature of the test piece.

    Returns
    -------
    list of dict
        Keys ``kind``, ``width_um``, and per mode ``<mode>_level``, ``<mode>_kept``,
        ``<mode>_kept_all``.

    Raises
    ------
    ConfigError
        A mode is not one of the three, or ``cure_threshold`` is outside [0, 1].
    DeviceError
        ``device`` is not a known preset.
    """
    from ..devices import load_device
    from ..mesh import Mesh
    from ..pieces import DEFAULT_WIDTHS_MM, feature_test_piece
    from ..slicing import slice_mesh
    from .coverage import coverage_mask
    from .ops import smooth_mask

    tris, feats = feature_test_piece(widths_mm or DEFAULT_WIDTHS_MM, ring_segments=ring_segments)
    mesh = Mesh.from_triangles(tris, source="feature test piece")
    dev = load_device(device)
    px = dev.pitch_x_mm
    acc: dict[tuple[str, int], list[FeatureExposure]] = {}
    for i in range(phases):
        for j in range(phases):
            off = (i / phases * dev.pitch_x_mm, j / phases * dev.pitch_y_mm)
            job = slice_mesh(mesh, dev, layer_height_mm=2.0, offset_mm=off)  # one layer, at 0.8 mm
            binary = job.layer(0).image
            for mode in modes:
                if mode == "binary":
                    img = binary
                elif mode == "smooth":
                    img = smooth_mask(binary)
                elif mode == "coverage":
                    s, e, _ = job.pixel_segments(0)
                    img = coverage_mask(s, e, job.grid.shape)
                else:
                    raise ConfigError(f"mode must be one of binary, coverage, smooth, got {mode!r}")
                res = feature_exposure(img, feats, job.grid.pixel_to_model, pitch_mm=px, cure_threshold=cure_threshold)
                for k, r in enumerate(res):
                    acc.setdefault((mode, k), []).append(r)
    rows = []
    for k, f in enumerate(feats):
        row = {"kind": f.kind, "width_um": round(f.width_mm * 1000, 1)}
        for mode in modes:
            rs = acc[(mode, k)]
            wall = f.kind in ("wall", "ring_wall")
            lev = min(r.level for r in rs) if wall else max(r.level for r in rs)
            row[f"{mode}_level"] = lev
            row[f"{mode}_kept"] = float(np.mean([r.kept_fraction for r in rs]))
            row[f"{mode}_kept_all"] = all(r.kept for r in rs)
        rows.append(row)
    return rows


def narrowest_kept_um(rows: list[dict], mode: str, kind: str, *, cure_threshold: float | None = None) -> float | None:
    """Smallest width (um) of ``kind`` from which every wider feature is kept at every
    placement; ``None`` if even the widest is not. With ``cure_threshold``, re-decide from
    the recorded levels (valid for rows whose features were kept along their whole length
    exactly when their level passes, which holds for the worst-placement ``level``).

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`exposure_table`.
    mode : str
        One of the modes the rows were made with.
    kind : str
        Feature kind (``'wall'``, ``'channel'``, ...); rows of other kinds are ignored.
    cure_threshold : float, optional
        Decide from ``<mode>_level`` (walls: ``>=``, channels: ``<``) instead of
        ``<mode>_kept_all``.

    Returns
    -------
    float or None
        ``width_um`` of that row.
    """
    rs = sorted((r for r in rows if r["kind"] == kind), key=lambda r: r["width_um"])
    wall = kind in ("wall", "ring_wall")

    def ok(r):
        if cure_threshold is None:
            return r[f"{mode}_kept_all"]
        lev = r[f"{mode}_level"]
        return lev >= cure_threshold if wall else lev < cure_threshold

    best = None
    for r in reversed(rs):
        if not ok(r):
            break
        best = r["width_um"]
    return best


def format_exposure_table(rows: list[dict], modes=("binary", "coverage", "smooth")) -> str:
    """A markdown table of :func:`exposure_table` rows: ``level / kept %`` per mode (the
    percentage is rounded down, so 100 % means all of it).

    Parameters
    ----------
    rows : list of dict
        Rows of :func:`exposure_table`.
    modes : sequence of str
        Columns, in order; each must be among the modes the rows were made with.

    Returns
    -------
    str
        The table's lines joined with newlines, no trailing newline.
    """
    head = "| feature | width (um) | " + " | ".join(modes) + " |"
    lines = [head, "|---|---:|" + "---:|" * len(modes)]
    for r in rows:
        cells = [f"{r[f'{m}_level']:.2f} / {np.floor(1000 * r[f'{m}_kept']) / 10:g}%" for m in modes]
        lines.append(f"| {r['kind']} | {r['width_um']:g} | " + " | ".join(cells) + " |")
    return "\n".join(lines)
