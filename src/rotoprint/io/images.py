"""PNG writing and reading for layer images (8-bit greyscale)."""

from __future__ import annotations

import contextlib
import hashlib
import io
import re
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np
from PIL import Image

from ..errors import ImageError, InputFileError

__all__ = ["png_bytes", "write_png", "read_grey_image", "open_image"]


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
    limit = Image.MAX_IMAGE_PIXELS
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            im = Image.open(io.BytesIO(data))
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        m = re.search(r"(\d+) pixels", str(exc))
        size = m.group(1) if m else "too many"
        raise ImageError(f"{what} has {size} pixels, more than the {limit} pixel limit against decompression bombs "
                         f"(PIL.Image.MAX_IMAGE_PIXELS)", path=path) from None
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
        zlib level passed to Pillow (0 none ... 9 smallest); the pixels are the same for any.

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
    buf = io.BytesIO()
    Image.fromarray(image, mode=None).save(buf, format="PNG", compress_level=compress_level)
    return buf.getvalue()


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
    return hashlib.sha256(data).hexdigest()


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
