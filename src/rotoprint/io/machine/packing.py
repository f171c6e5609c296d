"""Firing images packed as print controllers take them (``film-and-machine.md`` s. 5).

A firing image ``levels[i, k]`` (row = firing, column = rotoprint nozzle ``k``) becomes, per
row, the head's nozzles in *the head's own numbering* (:func:`nozzle_order`), ``bits`` bits per
nozzle, packed into 32-bit words most significant bit first: nozzle ``c`` of the head's order
is in word ``c // (32 / bits)`` at bits ``31 - (c % (32 / bits)) * bits`` down to
``32 - (c % (32 / bits) + 1) * bits``. The last word of a row is padded with zeros. Raw files
store the words as unsigned 32-bit integers in :data:`WORD_BYTE_ORDER` byte order, row after
row, no header (the shape is in the program).

Bit depths: 1 bit (binary heads, level 0/1), 2 bits (4 levels, 0..3), 4 bits (8-level heads:
only the low 3 bits print, levels 0..7).
"""

from __future__ import annotations

import io

import numpy as np

from ...errors import ConfigError, ImageError

__all__ = ["BITS_CHOICES", "WORD_BYTE_ORDER", "bits_for_levels", "nozzle_order", "pack_levels", "unpack_levels",
           "packed_bytes", "read_packed", "tiff_bytes", "words_per_row", "max_level"]

BITS_CHOICES = (1, 2, 4)
#: Byte order of the 32-bit words in the raw files.
WORD_BYTE_ORDER = "little"
_DTYPE = np.dtype("<u4")


def max_level(bits: int) -> int:
    """Largest drop level a ``bits``-bit field prints: 1, 3, or 7 (4 bits: the low 3 print)."""
    _check_bits(bits)
    return {1: 1, 2: 3, 4: 7}[bits]


def _check_bits(bits: int) -> None:
    if bits not in BITS_CHOICES:
        raise ConfigError(f"bits per nozzle must be 1, 2 or 4, got {bits!r}")


def bits_for_levels(grey_levels: int) -> int:
    """The smallest bit depth that holds a head's drop levels.

    Parameters
    ----------
    grey_levels : int
        Largest drop level of the head (1 for a binary head).

    Returns
    -------
    int
        1 for 1 level, 2 for up to 3, 4 for up to 7.

    Raises
    ------
    ConfigError
        More than 7 levels (no controller field of this family holds them).

    Examples
    --------
    >>> bits_for_levels(1), bits_for_levels(3), bits_for_levels(7)
    (1, 2, 4)
    """
    for b in BITS_CHOICES:
        if grey_levels <= max_level(b):
            return b
    raise ConfigError(f"a head with {grey_levels} grey levels needs more than the 3 printing bits of a 4-bit field")


def words_per_row(nozzles: int, bits: int) -> int:
    """32-bit words per packed row: ``ceil(nozzles * bits / 32)``."""
    _check_bits(bits)
    return -(-nozzles * bits // 32)


def nozzle_order(nozzles: int, rows: int, *, odd_row: int = 0, descending: bool = False) -> np.ndarray:
    """The head's nozzle numbering as rotoprint nozzle indices.

    rotoprint numbers nozzles by their position along the head (``k * pitch``, row ``k % rows``).
    A head numbers them from one end (``descending``: from the far end, rotoprint nozzle
    ``N - 1``) in groups of ``rows`` neighbours; within a group its first (odd) number is the
    nozzle in row ``odd_row``, then the following rows in turn. A last group with fewer than
    ``rows`` nozzles keeps that order among the nozzles it has.

    Parameters
    ----------
    nozzles : int
        ``N > 0``.
    rows : int
        Rows of the head, ``>= 1``.
    odd_row : int
        rotoprint row (``0 .. rows - 1``) that holds the head's nozzles 1, 1 + rows, ...
    descending : bool
        The head counts from rotoprint nozzle ``N - 1`` towards 0.

    Returns
    -------
    (N,) int64 ndarray
        A permutation: column ``c`` of a packed row is rotoprint nozzle ``order[c]``.

    Examples
    --------
    >>> nozzle_order(5, 2, odd_row=1).tolist()
    [1, 0, 3, 2, 4]
    >>> nozzle_order(4, 2, odd_row=1, descending=True).tolist()
    [3, 2, 1, 0]
    """
    if nozzles < 1 or rows < 1:
        raise ConfigError(f"a head needs nozzles >= 1 and rows >= 1, got {nozzles} and {rows}")
    if not 0 <= odd_row < rows:
        raise ConfigError(f"odd_row must be 0..{rows - 1} for a head of {rows} rows, got {odd_row}")
    pos = np.arange(nozzles, dtype=np.int64)
    if descending:
        pos = pos[::-1]
    # position along the head's own count: p = 0 .. N-1 from its first end; group g = p // rows
    # holds the count positions g*rows .. g*rows + rows - 1; rows come as odd_row, odd_row+1, ...
    k = pos  # rotoprint index at count position p
    row = k % rows
    group = np.arange(nozzles) // rows
    rank = (row - odd_row) % rows
    order = np.lexsort((rank, group))
    return k[order].astype(np.int64)


def pack_levels(levels: np.ndarray, bits: int, order: np.ndarray) -> np.ndarray:
    """Pack a firing image into 32-bit words, MSB first, in the head's nozzle order.

    Parameters
    ----------
    levels : (F, N) uint8
        Drop levels, 0 = no drop, at most :func:`max_level` (``bits``).
    bits : {1, 2, 4}
    order : (N,) int64
        From :func:`nozzle_order`.

    Returns
    -------
    (F, W) uint32 ndarray
        ``W = words_per_row(N, bits)``.

    Raises
    ------
    ImageError
        A level above what ``bits`` prints, or ``order`` not of length ``N``.
    """
    _check_bits(bits)
    lv = np.asarray(levels)
    if lv.ndim != 2 or lv.dtype != np.uint8:
        raise ImageError(f"a firing image must be a 2-D uint8 array, got {lv.ndim}-D {lv.dtype}")
    f, n = lv.shape
    if order.shape != (n,):
        raise ImageError(f"nozzle order has {order.size} entries, the image {n} columns")
    top = int(lv.max()) if lv.size else 0
    if top > max_level(bits):
        raise ImageError(f"drop level {top} does not fit {bits} bit(s) per nozzle (at most {max_level(bits)})")
    per = 32 // bits
    w = words_per_row(n, bits)
    v = np.zeros((f, w * per), np.uint32)
    v[:, :n] = lv[:, order]
    shifts = (32 - bits * (np.arange(per, dtype=np.uint32) + 1)).astype(np.uint32)
    v = v.reshape(f, w, per) << shifts
    return np.bitwise_or.reduce(v, axis=2).astype(np.uint32) if per > 1 else v[:, :, 0]


def unpack_levels(words: np.ndarray, bits: int, order: np.ndarray) -> np.ndarray:
    """Inverse of :func:`pack_levels`.

    Parameters
    ----------
    words : (F, W) uint32
    bits : {1, 2, 4}
    order : (N,) int64
        The head's nozzle order used when packing.

    Returns
    -------
    (F, N) uint8 ndarray
        Levels in rotoprint nozzle order (4 bits: the low 3 bits of each field).

    Raises
    ------
    ImageError
        ``W`` is not ``words_per_row(N, bits)``, or padding bits are set.
    """
    _check_bits(bits)
    words = np.asarray(words, np.uint32)
    n = order.size
    w = words_per_row(n, bits)
    if words.ndim != 2 or words.shape[1] != w:
        raise ImageError(f"packed rows must be {w} words for {n} nozzles at {bits} bit(s), got shape {words.shape}")
    per = 32 // bits
    shifts = (32 - bits * (np.arange(per, dtype=np.uint32) + 1)).astype(np.uint32)
    mask = np.uint32((1 << bits) - 1)
    v = ((words[:, :, None] >> shifts) & mask).reshape(words.shape[0], w * per)
    if np.any(v[:, n:]):
        raise ImageError("packed rows have bits set in the padding after the last nozzle")
    if bits == 4 and np.any(v[:, :n] & 8):
        raise ImageError("a 4-bit field has its high (non-printing) bit set")
    out = np.empty((words.shape[0], n), np.uint8)
    out[:, order] = v[:, :n]
    return out


def packed_bytes(words: np.ndarray) -> bytes:
    """The raw file's bytes: ``(F, W) uint32`` words, row after row, in :data:`WORD_BYTE_ORDER`."""
    return np.ascontiguousarray(words, dtype=_DTYPE).tobytes()


def read_packed(data: bytes, firings: int, nozzles: int, bits: int) -> np.ndarray:
    """``(F, W) uint32`` words from a raw file's bytes, checking its size first.

    Raises
    ------
    ImageError
        The byte count is not ``F * W * 4``.
    """
    w = words_per_row(nozzles, bits)
    want = firings * w * 4
    if len(data) != want:
        raise ImageError(f"packed file has {len(data)} bytes, {firings} rows of {w} words need {want}")
    return np.frombuffer(data, dtype=_DTYPE).reshape(firings, w).astype(np.uint32)


def tiff_bytes(levels: np.ndarray, bits: int, order: np.ndarray, *, description: str = "") -> bytes:
    """One TIFF plane (greyscale, ``bits`` bits per sample, uncompressed) of a firing image.

    Rows are firings, columns the head's nozzles in its own order; a sample is the drop level
    (0 = no drop; PhotometricInterpretation MinIsBlack). Rows are packed MSB first and padded
    to whole bytes, as TIFF stores samples of fewer than 8 bits. The samples are packed here
    and handed to tifffile as one strip (tifffile needs imagecodecs to pack them itself).

    Parameters
    ----------
    levels : (F, N) uint8
    bits : {1, 2, 4}
    order : (N,) int64
    description : str
        The TIFF ImageDescription tag.

    Returns
    -------
    bytes
    """
    import tifffile

    _check_bits(bits)
    lv = np.asarray(levels, np.uint8)
    f, n = lv.shape
    if int(lv.max(initial=0)) > max_level(bits):
        raise ImageError(f"drop level {int(lv.max())} does not fit {bits} bit(s) per nozzle")
    per = 8 // bits
    nb = -(-n // per)
    v = np.zeros((f, nb * per), np.uint8)
    v[:, :n] = lv[:, order]
    shifts = (8 - bits * (np.arange(per) + 1)).astype(np.uint8)
    packed = np.bitwise_or.reduce(v.reshape(f, nb, per) << shifts, axis=2).astype(np.uint8)
    buf = io.BytesIO()
    with tifffile.TiffWriter(buf) as tw:
        tw.write(data=iter([packed.tobytes()]), shape=(f, n), dtype=np.uint8, bitspersample=bits, photometric="minisblack",
                 compression=None, rowsperstrip=max(f, 1), description=description or None, software="rotoprint")
    return buf.getvalue()
