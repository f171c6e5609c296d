"""STL reading: binary by exact length, ASCII by structure; never by the word "solid".

A binary STL is an 80-byte header, a little-endian uint32 triangle count ``n`` and ``n``
records of 50 bytes. A file is read as binary exactly when its length is ``84 + 50 n``;
otherwise it must parse as ASCII STL (one or more ``solid ... endsolid`` blocks). Anything
else is refused with a message that says which of the two it resembled and why it failed.
"""

from __future__ import annotations

import functools
import re

import numpy as np

from ..errors import MeshError

#: One binary record: normal, three vertices, attribute byte count; little-endian.
BINARY_RECORD = np.dtype(
    [("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attr", "<u2")]
)
assert BINARY_RECORD.itemsize == 50  # noqa: S101 - a dtype invariant, not input validation

_NUM = r"([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf|infinity))"


@functools.cache
def _facet_patterns() -> tuple[re.Pattern, re.Pattern]:
    """A whole ASCII facet, and its keyword; compiled when an ASCII file is read (about 1 ms
    that a binary STL's job need not pay at start-up)."""
    facet = re.compile(
        rb"facet\s+normal\s+\S+\s+\S+\s+\S+\s+outer\s+loop\s+"
        + rb"\s+".join([rb"vertex\s+" + _NUM.encode() + rb"\s+" + _NUM.encode() + rb"\s+" + _NUM.encode()] * 3)
        + rb"\s+endloop\s+endfacet",
        re.IGNORECASE,
    )
    return facet, re.compile(rb"(?<![a-z])facet\s+normal", re.IGNORECASE)


def _looks_like_text(data: bytes) -> bool:
    sample = data[:4096]
    return all(b in b"\t\n\r\f\v" or 32 <= b < 127 for b in sample)


def read_stl_bytes(data: bytes, path: str) -> np.ndarray:
    """Parse STL content; returns ``(N, 3, 3) float64`` triangles in file units."""
    size = len(data)
    if size == 0:
        raise MeshError("file is empty", path=path)
    if size >= 84:
        (count,) = np.frombuffer(data, dtype="<u4", count=1, offset=80)
        count = int(count)
        if size == 84 + 50 * count:
            if count == 0:
                raise MeshError("binary STL holds zero triangles", path=path)
            rec = np.frombuffer(data, dtype=BINARY_RECORD, count=count, offset=84)
            return rec["vertices"].astype(np.float64)
    if _looks_like_text(data):
        return _read_ascii(data, path)
    # Not text, and the length does not match the header's count: a binary file that is
    # truncated, padded, or whose count lies.
    if size < 84:
        raise MeshError(f"not an STL file: {size} bytes, shorter than a binary STL header (84 bytes)", path=path)
    (count,) = np.frombuffer(data, dtype="<u4", count=1, offset=80)
    expected = 84 + 50 * int(count)
    if (size - 84) % 50 == 0:
        raise MeshError(
            f"binary STL header declares {int(count)} triangles ({expected} bytes) but the file "
            f"has {size} bytes, room for {(size - 84) // 50}: the header count is wrong",
            path=path,
        )
    raise MeshError(
        f"not a valid STL: as binary, the header declares {int(count)} triangles ({expected} bytes) "
        f"but the file has {size} bytes (truncated or not an STL), and it is not ASCII text",
        path=path,
    )


def _read_ascii(data: bytes, path: str) -> np.ndarray:
    if not re.match(rb"\s*solid\b", data, re.IGNORECASE):
        raise MeshError("not an STL file: text that does not start with 'solid'", path=path)
    facet, keyword = _facet_patterns()
    matches = list(facet.finditer(data))
    n_keywords = len(keyword.findall(data))
    if n_keywords == 0:
        raise MeshError("ASCII STL holds zero facets", path=path)
    if len(matches) != n_keywords:
        # Locate the first facet keyword not covered by a well-formed facet.
        covered = {m.start() for m in matches}
        for m in keyword.finditer(data):
            if m.start() not in covered:
                line = data.count(b"\n", 0, m.start()) + 1
                raise MeshError(f"ASCII STL has a broken facet at line {line}", path=path)
    # Every block must be closed by endsolid; a file cut short is refused.
    n_solid = len(re.findall(rb"(?m)^\s*solid\b", data, re.IGNORECASE))
    n_end = len(re.findall(rb"(?m)^\s*endsolid\b", data, re.IGNORECASE))
    if n_end < n_solid:
        raise MeshError(f"ASCII STL is cut short: {n_solid} 'solid' blocks but {n_end} 'endsolid'", path=path)
    tokens = b" ".join(b" ".join(m.groups()) for m in matches).split()
    return np.array(tokens, dtype=np.float64).reshape(-1, 3, 3)


def binary_stl_bytes(triangles: np.ndarray) -> bytes:
    """``(N, 3, 3)`` triangles (any float dtype, mm) as the bytes of a binary STL (normals from the winding)."""
    tri = np.asarray(triangles, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        ln = np.linalg.norm(n, axis=1, keepdims=True)
    rec = np.zeros(len(tri), dtype=BINARY_RECORD)
    rec["normal"] = np.divide(n, ln, out=np.zeros_like(n), where=np.isfinite(ln) & (ln > 0))
    rec["vertices"] = tri
    header = b"rotoprint binary STL".ljust(80, b" ")
    return header + np.uint32(len(tri)).tobytes() + rec.tobytes()


def write_binary_stl(path, triangles: np.ndarray) -> None:
    """Write ``(N, 3, 3)`` triangles as a binary STL (normals from the winding)."""
    with open(path, "wb") as fh:
        fh.write(binary_stl_bytes(triangles))
