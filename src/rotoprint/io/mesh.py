"""Loading meshes from files: STL natively, OBJ / PLY / 3MF / OFF / GLB through trimesh."""

from __future__ import annotations

import io
import logging
from pathlib import Path

import numpy as np

from .._resources import release_free_memory
from ..constants import UNITS_TO_MM
from ..errors import ConfigError, MeshError, RotoprintError
from ..ranges import COORD_MM
from .inputs import MAX_MESH_BYTES, check_input_file, read_input_bytes, read_zip_members
from ..mesh import Mesh
from .stl import read_stl_bytes

__all__ = ["load_mesh", "load_triangles", "make_transform", "SUPPORTED_SUFFIXES"]

log = logging.getLogger(__name__)

SUPPORTED_SUFFIXES = (".stl", ".obj", ".ply", ".3mf", ".off", ".glb", ".gltf")


def make_transform(
    *,
    translate_mm: tuple[float, float, float] = (0.0, 0.0, 0.0),
    rotate_deg: tuple[float, float, float] = (0.0, 0.0, 0.0),
    scale: float | tuple[float, float, float] = 1.0,
) -> np.ndarray:
    """A ``(4, 4) float64`` affine: scale, then rotate about X, Y, Z (degrees), then translate.

    Parameters
    ----------
    translate_mm : (3,) float
        Translation along X, Y, Z, applied last.
    rotate_deg : (3,) float
        Rotations about X, then Y, then Z, in degrees.
    scale : float or (3,) float
        One factor for all axes, or one per axis; applied first. Must be finite and non-zero.

    Returns
    -------
    (4, 4) float64 ndarray
        The affine for column vectors ``[x, y, z, 1]``.

    Raises
    ------
    ConfigError
        ``scale`` is zero or not finite, or ``rotate_deg`` / ``translate_mm`` is not three
        finite numbers.

    Examples
    --------
    >>> T = make_transform(translate_mm=(1, 2, 3), rotate_deg=(0, 0, 90))
    >>> np.round(T @ [1, 0, 0, 1], 12).tolist()
    [1.0, 3.0, 3.0, 1.0]
    """
    s = np.broadcast_to(np.asarray(scale, dtype=np.float64), (3,))
    if not np.all(np.isfinite(s)) or np.any(s == 0):
        raise ConfigError(f"scale (--scale) must be finite and non-zero, got {tuple(s.tolist())}")
    for name, option, value in (("rotate_deg", "--rotate", rotate_deg), ("translate_mm", "--translate", translate_mm)):
        v = np.asarray(value, dtype=np.float64)
        if v.shape != (3,) or not np.isfinite(v).all():
            raise ConfigError(f"{name} ({option}) must be three finite numbers, got {tuple(np.ravel(v).tolist())}")
    rx, ry, rz = np.deg2rad(np.asarray(rotate_deg, dtype=np.float64))
    cx, sx, cy, sy, cz, sz = np.cos(rx), np.sin(rx), np.cos(ry), np.sin(ry), np.cos(rz), np.sin(rz)
    Rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    T = np.eye(4)
    T[:3, :3] = Rz @ Ry @ Rx @ np.diag(s)
    T[:3, 3] = np.asarray(translate_mm, dtype=np.float64)
    return T


def load_triangles(path: str | Path) -> np.ndarray:
    """Read a mesh file into ``(N, 3, 3) float64`` triangles in the file's own units.

    Parameters
    ----------
    path : str or Path
        A ``.stl`` file (read natively) or one of the other :data:`SUPPORTED_SUFFIXES`
        (read through trimesh, without processing).

    Returns
    -------
    (N, 3, 3) float64 ndarray
        Triangles, then corners, then X, Y, Z; no units conversion or transform.

    Raises
    ------
    InputFileError
        The file is missing, is not a regular file (directory, FIFO, device), is larger than
        :data:`~rotoprint.io.inputs.MAX_MESH_BYTES`, or cannot be read (permission denied).
    MeshError
        Unsupported suffix, an empty non-STL file, a file trimesh cannot read or that holds
        no triangles, or an invalid STL.
    """
    path = Path(path)
    check_input_file(path, what="mesh file", limit_bytes=MAX_MESH_BYTES)
    suffix = path.suffix.lower()
    if suffix not in SUPPORTED_SUFFIXES:
        raise MeshError(
            f"unsupported mesh format {suffix or '(no suffix)'!r}; expected one of {', '.join(SUPPORTED_SUFFIXES)}",
            path=path,
        )
    data = read_input_bytes(path, what="mesh file", limit_bytes=MAX_MESH_BYTES)
    if suffix == ".stl":
        return read_stl_bytes(data, str(path))
    if len(data) == 0:
        raise MeshError("file is empty", path=path)
    if suffix == ".ply":
        check_ply_counts(data, path)
    elif suffix == ".off":
        check_off_counts(data, path)
    return _load_with_trimesh(path, data)


#: Formats trimesh parses as text; their bytes are decoded here (see :func:`_text_for_trimesh`).
_TEXT_SUFFIXES = (".obj", ".off", ".gltf")
_PRINTABLE = bytes(b"\t\n\r\f\v" + bytes(range(32, 127)))


def _text_for_trimesh(data: bytes, path: Path) -> bytes:
    """A text mesh's bytes as UTF-8, or a MeshError for content that is not text.

    UTF-8 is taken as it is. Other bytes are read as Latin-1 (every byte a character; the
    numbers and keywords of OBJ / OFF are ASCII, so only comments and names can differ) when
    the file is text: no NUL byte and at least 95 % printable ASCII or whitespace. Anything else
    (binary garbage) is refused here rather than handed to trimesh's encoding guesser.
    """
    try:
        data.decode("utf-8")
        return data
    except UnicodeDecodeError:
        pass
    kind = path.suffix.lower()[1:].upper()
    sample = data[: 1 << 20]
    printable = len(sample) - len(sample.translate(None, _PRINTABLE))
    if b"\0" in sample or printable < 0.95 * len(sample):
        raise MeshError(f"could not read as {kind}: binary data, not text "
                        f"({100 * printable / len(sample):.0f} % printable characters)", path=path)
    return data.decode("latin-1").encode("utf-8")


_PLY_SIZES = {"char": 1, "int8": 1, "uchar": 1, "uint8": 1, "short": 2, "int16": 2, "ushort": 2, "uint16": 2,
              "int": 4, "int32": 4, "uint": 4, "uint32": 4, "float": 4, "float32": 4, "double": 8, "float64": 8}
_PLY_MAX_HEADER = 64 * 1024


def check_ply_counts(data: bytes, path: Path) -> None:
    """Refuse a PLY whose header declares more elements than the file holds (a lying header).

    ASCII: every element is one line, so the data lines must number at least the declared
    total. Binary: each element takes at least its fixed-size properties plus, per list, the
    count and three entries (a face has three corners or more), so the file must be at least
    that long. Only the header is parsed here; trimesh reads the data.

    Raises
    ------
    MeshError
        No complete header, or a declared count the file cannot hold.
    """
    head = data[:_PLY_MAX_HEADER]
    end = head.find(b"end_header")
    if not head.startswith(b"ply") or end < 0:
        return  # not a header we can read: trimesh says what is wrong
    nl = head.find(b"\n", end)
    body_at = (nl + 1) if nl >= 0 else len(head)
    fmt, elements = "", []  # [name, count, min bytes per element]
    for raw in head[:end].decode("ascii", "replace").splitlines():
        w = raw.split()
        if len(w) >= 2 and w[0] == "format":
            fmt = w[1]
        elif len(w) >= 3 and w[0] == "element":
            try:
                elements.append([w[1], int(w[2]), 0])
            except ValueError:
                raise MeshError(f"PLY header: element {w[1]} has count {w[2]!r}, not an integer", path=path) from None
        elif len(w) >= 3 and w[0] == "property" and elements:
            if w[1] == "list" and len(w) >= 5:
                elements[-1][2] += _PLY_SIZES.get(w[2], 1) + 3 * _PLY_SIZES.get(w[3], 1)
            else:
                elements[-1][2] += _PLY_SIZES.get(w[1], 1)
    for name, n, _ in elements:
        if n < 0:
            raise MeshError(f"PLY header declares {n} {name} elements", path=path)
    total = sum(n for _, n, _ in elements)
    if fmt == "ascii":
        lines = sum(1 for ln in data[body_at:].splitlines() if ln.strip())
        if lines < total:
            desc = ", ".join(f"{n} {name}" for name, n, _ in elements)
            raise MeshError(f"PLY header declares {desc} ({total} lines) but the file holds {lines} data lines", path=path)
    elif fmt.startswith("binary"):
        need = sum(n * b for _, n, b in elements)
        have = len(data) - body_at
        if have < need:
            desc = ", ".join(f"{n} {name}" for name, n, _ in elements)
            raise MeshError(f"PLY header declares {desc}, at least {need} bytes, but the file holds {have}", path=path)


def check_off_counts(data: bytes, path: Path) -> None:
    """Refuse an OFF file whose header declares more vertices and faces than it holds.

    The counts line (``NV NF NE``, after the ``OFF`` keyword and any ``#`` comments) must be
    followed by at least ``NV + NF`` data lines; trimesh would otherwise read what is there and
    keep quiet about the rest.

    Raises
    ------
    MeshError
        A count that is not a non-negative integer, or fewer data lines than declared.
    """
    lines = (ln.split(b"#", 1)[0].strip() for ln in data.splitlines())
    lines = [ln for ln in lines if ln]
    if not lines or not lines[0].upper().endswith(b"OFF") and not lines[0].upper().startswith(b"OFF"):
        return  # not a header we can read: trimesh says what is wrong
    head = lines[0].split()
    rest = 1
    counts = head[1:]  # "OFF NV NF NE" on one line
    if not counts:
        if len(lines) < 2:
            return
        counts, rest = lines[1].split(), 2
    try:
        nv, nf = int(counts[0]), int(counts[1])
    except (ValueError, IndexError):
        raise MeshError(f"OFF header: counts line {b' '.join(counts).decode('ascii', 'replace')!r} is not 'NV NF NE'",
                        path=path) from None
    if nv < 0 or nf < 0:
        raise MeshError(f"OFF header declares {nv} vertices and {nf} faces", path=path)
    have = len(lines) - rest
    if have < nv + nf:
        raise MeshError(f"OFF header declares {nv} vertices and {nf} faces ({nv + nf} lines) "
                        f"but the file holds {have} data lines", path=path)


def _load_with_trimesh(path: Path, data: bytes) -> np.ndarray:
    import trimesh

    suffix = path.suffix.lower()
    kind = suffix[1:].upper()
    if suffix in _TEXT_SUFFIXES:
        data = _text_for_trimesh(data, path)
    if suffix == ".3mf":
        # trimesh inflates every member in memory: check each inflates within a bound first
        read_zip_members(data, path, what="3MF file")
    try:
        # From memory, with a resolver that reads referenced files (textures, .bin buffers,
        # .mtl) through the same bounded reader and only from the mesh's own folder.
        loaded = trimesh.load(file_obj=io.BytesIO(data), file_type=suffix[1:], force="mesh", process=False,
                              resolver=_BoundedResolver(path))
    except RotoprintError:
        raise
    except Exception as exc:  # trimesh raises many kinds for bad files
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise MeshError(f"could not read as {kind}: {first}", path=path) from exc
    faces = getattr(loaded, "faces", None)
    vertices = getattr(loaded, "vertices", None)
    if faces is None or vertices is None or len(faces) == 0:
        raise MeshError("file holds no triangles", path=path)
    try:
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise MeshError(f"vertices or faces are not numbers: {exc}", path=path) from exc
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
        raise MeshError(f"expected (V, 3) vertices and (F, 3) faces, got {v.shape} and {f.shape}", path=path)
    # trimesh does not check the indices (process=False); a negative one would wrap around
    bad = (f < 0) | (f >= len(v))
    if bad.any():
        i = int(np.flatnonzero(bad.any(axis=1))[0])
        raise MeshError(
            f"{int(bad.any(axis=1).sum())} face(s) refer to vertices that do not exist (first: face {i} "
            f"uses vertex {int(f[i][bad[i]][0])}, the file has {len(v)} vertices)",
            path=path,
        )
    return v[f]


class _BoundedResolver:
    """A trimesh resolver: files a mesh refers to, read bounded, from its folder only."""

    def __init__(self, mesh: Path, folder: Path | None = None) -> None:
        self.mesh = mesh
        self.parent = (folder or mesh.parent).resolve()

    def get(self, name: str) -> bytes:
        p = (self.parent / name).resolve()
        if not p.is_relative_to(self.mesh.parent.resolve()):
            raise MeshError(f"refers to {name!r}, which leads outside the mesh's folder (to {p})", path=self.mesh)
        return read_input_bytes(p, what="file a mesh refers to", limit_bytes=MAX_MESH_BYTES)

    __getitem__ = get

    def namespaced(self, namespace: str) -> _BoundedResolver:
        return _BoundedResolver(self.mesh, self.parent / namespace)

    def keys(self):
        return iter(())

    def write(self, name, data):  # pragma: no cover - trimesh only writes when exporting
        raise MeshError("refusing to write beside a mesh while reading it", path=self.mesh)


def load_mesh(
    path: str | Path,
    *,
    units: str = "mm",
    transform: np.ndarray | None = None,
    fill_holes: bool = True,
) -> Mesh:
    """Load a mesh file into a validated :class:`~rotoprint.mesh.Mesh` in millimetres.

    Parameters
    ----------
    path : str or Path
        STL (binary or ASCII, several ``solid`` blocks allowed), or OBJ, PLY, 3MF, OFF, GLB.
    units : {'mm', 'cm', 'm', 'um', 'inch'}
        Units of the file's coordinates; the mesh is converted to millimetres.
    transform : (4, 4) float array, optional
        Applied after the unit conversion (see :func:`make_transform`).
    fill_holes : bool
        Fill the mesh's holes (closed loops of open edges) before anything else sees it
        (see :mod:`rotoprint._holes`); reported in ``mesh.info()['holes']``.

    Raises
    ------
    InputFileError
        Missing file, a directory, unreadable.
    MeshError
        Empty, truncated, lying header, garbage, broken facet, no triangles, NaN / inf.
    """
    if units not in UNITS_TO_MM:
        raise ConfigError(f"units must be one of {', '.join(UNITS_TO_MM)}, got {units!r}")
    tri = load_triangles(path)
    if tri.shape[0] == 0:
        raise MeshError("file holds no triangles", path=path)
    bad = ~np.isfinite(tri).all(axis=(1, 2))
    if bad.any():
        first = int(np.flatnonzero(bad)[0])
        raise MeshError(
            f"{int(bad.sum())} triangle(s) have NaN or infinite coordinates (first: triangle {first})",
            path=path,
        )
    if UNITS_TO_MM[units] != 1.0:
        tri *= UNITS_TO_MM[units]  # tri is our own array: scaled in place
    if transform is not None:
        T = np.asarray(transform, dtype=np.float64)
        if T.shape != (4, 4):
            raise ConfigError(f"transform must be a (4, 4) matrix, got shape {T.shape}")
        if not np.isfinite(T).all():
            raise ConfigError("transform has NaN or infinite entries (check --rotate, --translate and --scale)")
        if not np.array_equal(T, np.eye(4)):
            tri = tri @ T[:3, :3].T + T[:3, 3]
            if np.linalg.det(T[:3, :3]) < 0:  # a mirroring transform reverses every face
                tri = tri[:, ::-1, :]
    lo, hi = float(tri.min()), float(tri.max())
    if not (lo >= COORD_MM.lo and hi <= COORD_MM.hi):
        far = lo if -lo > hi else hi
        raise MeshError(
            f"a coordinate reaches {far:.3g} mm after units, scale and transform; parts must lie "
            f"{COORD_MM.text()} (check --units, --scale and --translate)",
            path=path,
        )
    box = [tri]  # handed over: freed inside once the vertices are merged (less peak memory)
    del tri
    mesh = Mesh.from_triangles(box, source=str(path), fill_holes=fill_holes, _owned=True)
    release_free_memory()
    return mesh
