"""Photographs of a scene: read as grey-level arrays, and found in folders.

Images feed the environment prior (a scene classifier on the GIST descriptor); only
their grey levels matter. Pillow is imported when an image is first read, so the
command line starts without it.
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ..errors import CorruptFileError, ReadError
from ._textfile import regular_file

__all__ = ["IMAGE_EXTENSIONS", "MAX_IMAGE_PIXELS", "image_files", "read_image"]

#: File name endings taken as images when a folder is listed (lower case).
IMAGE_EXTENSIONS = (
    ".jpg",
    ".jpeg",
    ".png",
    ".bmp",
    ".gif",
    ".tif",
    ".tiff",
    ".webp",
    ".ppm",
    ".pgm",
)
#: Largest image read (pixels): 100 megapixels, well above any camera frame; a header
#: declaring more is refused before its pixels are decoded.
MAX_IMAGE_PIXELS = 100_000_000


def read_image(path: str | os.PathLike[str]) -> NDArray[np.float64]:
    """The grey levels of an image file, ``(h, w) float64`` in 0..255.

    Colour images become the mean of their red, green and blue channels (as the GIST
    reference implementation does); transparency is ignored.

    Raises
    ------
    ReadError
        The file is missing, a folder, or cannot be read.
    CorruptFileError
        The file is not an image Pillow can decode (damaged, truncated, another format).

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from PIL import Image
    >>> f = pathlib.Path(tempfile.mkdtemp()) / "grey.png"
    >>> Image.new("L", (4, 3), 200).save(f)
    >>> read_image(f).shape, float(read_image(f).max())
    ((3, 4), 200.0)
    """
    p = Path(path)
    regular_file(p, "image")
    from PIL import Image  # heavy: Pillow only when an image is read

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(p) as img:
                w, h = img.size
                if w * h > MAX_IMAGE_PIXELS:
                    raise CorruptFileError(
                        p, f"{w} x {h} pixels is more than an image may hold ({MAX_IMAGE_PIXELS:,})"
                    )
                img.load()
                mode = img.mode
                if mode in ("I", "I;16", "I;16B", "I;16L", "F"):
                    grey = np.asarray(img, dtype=np.float64)
                    top = float(grey.max()) if grey.size else 0.0
                    grey = grey * (255.0 / top) if top > 255.0 else grey
                else:
                    rgb = np.asarray(img.convert("RGB"), dtype=np.float64)
                    grey = rgb.mean(axis=2)
    except CorruptFileError:
        raise
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        raise CorruptFileError(p, f"too many pixels to be a photograph ({exc})") from None
    except FileNotFoundError:
        raise ReadError(p, "no such image") from None
    except PermissionError:
        raise ReadError(p, "permission denied (the image cannot be read)") from None
    except (OSError, ValueError, SyntaxError, EOFError, TypeError, IndexError) as exc:
        # Pillow reports unknown formats as UnidentifiedImageError (an OSError), truncated
        # data as OSError, and some damaged headers as SyntaxError or ValueError.
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CorruptFileError(p, f"not a readable image ({reason})") from None
    if grey.ndim != 2 or min(grey.shape) < 1:
        raise CorruptFileError(p, f"not a two-dimensional image (shape {grey.shape})")
    if not np.all(np.isfinite(grey)):
        raise CorruptFileError(p, "the image holds values that are not finite numbers")
    return grey


def image_files(path: str | os.PathLike[str]) -> list[Path]:
    """The image files a path names: itself if it is a file, else the images of the
    folder (by extension, :data:`IMAGE_EXTENSIONS`; hidden files left out), sorted by name.

    Raises
    ------
    ReadError
        The path does not exist, or the folder holds no image.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> for name in ("b.png", "a.JPG", "notes.txt", ".hidden.png"):
    ...     _ = (d / name).write_bytes(b"")
    >>> [p.name for p in image_files(d)]
    ['a.JPG', 'b.png']
    """
    p = Path(path)
    if not p.exists():
        raise ReadError(p, "no such image or folder of images")
    if not p.is_dir():
        return [p]
    try:
        entries = sorted(p.iterdir())
    except OSError as exc:
        raise ReadError(p, f"cannot list the folder ({exc.strerror or exc})") from None
    found = [
        e
        for e in entries
        if not e.name.startswith(".") and e.suffix.lower() in IMAGE_EXTENSIONS and not e.is_dir()
    ]
    if not found:
        raise ReadError(p, f"holds no image (looked for {', '.join(IMAGE_EXTENSIONS)})")
    return found
