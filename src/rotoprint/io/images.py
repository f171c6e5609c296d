"""PNG writing and reading for layer images (8-bit greyscale). Pillow is imported where it
is used (reading; writing without the C extension)."""

from __future__ import annotations

import contextlib
import io
import re
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np

from .._hashing import sha256 as _sha256
from ..errors import ImageError, InputFileError

__all__ = ["png_bytes", "png_bytes_window", "write_png", "read_grey_image", "open_image"]


@contextlib.contextmanager
def open_image(data: bytes, path: str | Path, what: str = "image") -> Iterator[Image.Image]:
    """Pillow's ``Image.open`` on bytes already read, with its decompression-bomb guard made an
    :class:`ImageError` that names the file and the pixel count.

    An image over ``PIL.Image.MAX_IMAGE_PIXELS`` (Pillow warns) or twice that (Pillow refuses)
    is refused, before its pixels are decoded. Other failures to parse are an ImageError too.

    Parameters
    ----------
    data : bytes
    path : str or Path
        For messages.
    what : str
        ``"design image"``, ``"mask"``, ...
    """
    from PIL import Image  # Pillow is imported by the readers, not by a job's start-up

    limit = Image.MAX_IMAGE_PIXELS
    if not data:
        raise ImageError(f"{what} file is empty", path=path)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            im = Image.open(io.BytesIO(data))
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        m = re.search(r"(\d+) pixels", str(exc))
        size = m.group(1) if m else "too many"
        raise ImageError(f"{what} has {size} pixels, more than the {limit} pixel limit against decompression bombs "
                         f"(PIL.Image.MAX_IMAGE_PIXELS)", path=path) from None
    except Image.UnidentifiedImageError:  # its text names the BytesIO object, not the file
        raise ImageError(f"not a readable {what}: not in an image format Pillow reads (PNG, TIFF, BMP, ...), "
                         "or truncated", path=path) from None
    except (OSError, SyntaxError, ValueError) as exc:
        raise ImageError(f"not a readable {what}: {exc}", path=path) from None
    with im:
        yield im


def png_bytes(image: np.ndarray, *, compress_level: int = 3) -> bytes:
    """Encode a ``(H, W) uint8`` image as an 8-bit greyscale PNG.

    Parameters
    ----------
    image : (H, W) uint8
    compress_level : int
        zlib level (0 stores, 1 ... 9 deflate); the pixels are the same for any. With the C
        extension the encoder is the one of :func:`png_bytes_window` (whole image as the
        window; zlib's run-length strategy, for which levels 1 to 9 are the same), else Pillow.

    Returns
    -------
    bytes
        The PNG file's content.

    Raises
    ------
    ImageError
        ``image`` is not 2-D or not ``uint8``.
    """
    if image.dtype != np.uint8 or image.ndim != 2:
        raise ImageError(f"layer images must be 2-D uint8, got {image.ndim}-D {image.dtype}")
    from .._accel import native

    if native is not None and image.size and 0 <= compress_level <= 9:
        h, w = image.shape
        return native.png_grey(np.ascontiguousarray(image), w, h, 0, 0, h, w, False, False, int(compress_level))
    buf = io.BytesIO()
    from PIL import Image

    Image.fromarray(image, mode=None).save(buf, format="PNG", compress_level=compress_level)
    return buf.getvalue()


def png_bytes_window(window: np.ndarray, shape: tuple[int, int], r0: int, c0: int, *, mirror_x: bool = False,
                     mirror_y: bool = False) -> bytes:
    """An 8-bit greyscale PNG of a ``shape`` image that is black except for ``window`` at
    ``(r0, c0)``, flipped left-right and/or top-bottom: the DLP masks' encoder.

    Rows equal to the row above are filtered "Up" and runs of them are copied from deflate
    chunks made once per process; the other rows are deflated with zlib's run-length strategy
    (see ``rotoprint/_native.c``). Without the C extension: the same pixels through
    :func:`png_bytes` (other bytes). The bytes depend on the pixels only.

    Parameters
    ----------
    window : (hh, ww) uint8
    shape : (int, int)
        ``(H, W)`` of the whole image.
    r0, c0 : int
        Where the window's first pixel lies in the image before flipping.
    mirror_x, mirror_y : bool
        Reverse the column / row order of the whole image.

    Returns
    -------
    bytes

    Raises
    ------
    ImageError
        ``window`` is not 2-D uint8 or does not fit in ``shape`` at ``(r0, c0)``.
    """
    from .._accel import native

    h, w = (int(v) for v in shape)
    if window.dtype != np.uint8 or window.ndim != 2:
        raise ImageError(f"layer images must be 2-D uint8, got {window.ndim}-D {window.dtype}")
    hh, ww = window.shape
    if r0 < 0 or c0 < 0 or r0 + hh > h or c0 + ww > w or h <= 0 or w <= 0:
        raise ImageError(f"a {hh} x {ww} window at ({r0}, {c0}) does not fit a {h} x {w} image")
    if native is not None:
        return native.png_grey(np.ascontiguousarray(window), w, h, int(r0), int(c0), hh, ww, bool(mirror_x),
                               bool(mirror_y), 6)
    img = np.zeros((h, w), np.uint8)
    img[r0 : r0 + hh, c0 : c0 + ww] = window
    if mirror_x:
        img = img[:, ::-1]
    if mirror_y:
        img = img[::-1]
    return png_bytes(np.ascontiguousarray(img))


def write_png(path: str | Path, image: np.ndarray, *, compress_level: int = 3) -> str:
    """Write ``image`` as PNG; returns the SHA-256 of the bytes written.

    Parameters
    ----------
    path : str or Path
        Written directly (not atomically), replacing an existing file.
    image : (H, W) uint8
    compress_level : int
        See :func:`png_bytes`.

    Returns
    -------
    str
        Hex SHA-256 digest of the PNG bytes.

    Raises
    ------
    ImageError
        ``image`` is not 2-D or not ``uint8``.
    """
    data = png_bytes(image, compress_level=compress_level)
    Path(path).write_bytes(data)
    return _sha256(data).hexdigest()


def read_grey_image(path: str | Path) -> np.ndarray:
    """Read an image as ``(H, W) uint8``; colour and 16-bit images are refused.

    Parameters
    ----------
    path : str or Path
        A greyscale (``L``), 1-bit (``1``, read as 0 / 255) or palette (``P``, without
        transparency) image in any format Pillow reads.

    Returns
    -------
    (H, W) uint8 ndarray
        C-contiguous; palette images converted to their grey values.

    Raises
    ------
    InputFileError
        The file does not exist.
    ImageError
        Pillow cannot read it, or its mode is another (colour, 16-bit, with alpha, ...).
    """
    from .inputs import MAX_IMAGE_BYTES, read_input_bytes

    path = Path(path)
    if not path.exists():
        raise InputFileError("no such image file", path=path)
    data = read_input_bytes(path, what="image file", limit_bytes=MAX_IMAGE_BYTES)
    try:
        with open_image(data, path) as im:
            im.load()
            mode = im.mode
            if mode in ("1", "L", "P") and not (mode == "P" and "transparency" in im.info):
                arr = np.asarray(im.convert("L"))
            else:
                raise ImageError(f"expected an 8-bit greyscale or monochrome image, got mode {mode!r}", path=path)
    except (OSError, SyntaxError) as exc:
        raise ImageError(f"not a readable image: {exc}", path=path) from None
    return np.ascontiguousarray(arr, dtype=np.uint8)
