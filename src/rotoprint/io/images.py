"""PNG writing and reading for layer images (8-bit greyscale)."""

from __future__ import annotations

import hashlib
import io
from pathlib import Path

import numpy as np
from PIL import Image

from ..errors import ImageError, InputFileError

__all__ = ["png_bytes", "write_png", "read_grey_image"]


def png_bytes(image: np.ndarray, *, compress_level: int = 3) -> bytes:
    """Encode a ``(H, W) uint8`` image as an 8-bit greyscale PNG."""
    if image.dtype != np.uint8 or image.ndim != 2:
        raise ImageError(f"layer images must be 2-D uint8, got {image.ndim}-D {image.dtype}")
    buf = io.BytesIO()
    Image.fromarray(image, mode=None).save(buf, format="PNG", compress_level=compress_level)
    return buf.getvalue()


def write_png(path: str | Path, image: np.ndarray, *, compress_level: int = 3) -> str:
    """Write ``image`` as PNG; returns the SHA-256 of the bytes written."""
    data = png_bytes(image, compress_level=compress_level)
    Path(path).write_bytes(data)
    return hashlib.sha256(data).hexdigest()


def read_grey_image(path: str | Path) -> np.ndarray:
    """Read an image as ``(H, W) uint8``; colour and 16-bit images are refused."""
    path = Path(path)
    if not path.exists():
        raise InputFileError("no such image file", path=path)
    try:
        with Image.open(path) as im:
            im.load()
            mode = im.mode
            if mode in ("1", "L", "P") and not (mode == "P" and "transparency" in im.info):
                arr = np.asarray(im.convert("L"))
            else:
                raise ImageError(f"expected an 8-bit greyscale or monochrome image, got mode {mode!r}", path=path)
    except (OSError, SyntaxError) as exc:
        raise ImageError(f"not a readable image: {exc}", path=path) from None
    return np.ascontiguousarray(arr, dtype=np.uint8)
