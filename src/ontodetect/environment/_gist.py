"""The GIST descriptor of a scene (Oliva & Torralba 2001), as the thesis uses it (§4, [34]).

The steps follow the authors' reference implementation (``LMgist``):

1. grey levels, resized so that the shorter side is :attr:`GistParams.image_size` and
   cropped to a centred square, then stretched to 0..255;
2. prefiltering: ``log(1 + I)``, whitening (the image minus its Gaussian low-pass,
   cut-off ``fc = 4`` cycles per image) and local contrast normalisation (division by
   ``0.2 +`` the local standard deviation, seen through the same Gaussian);
3. a bank of Gabor filters in the frequency domain, 4 scales x 8 orientations, applied
   to the image padded by mirroring (32 pixels) to avoid wrap-around at the borders;
4. each filter's response magnitude averaged over a 4 x 4 grid of blocks.

4 x 8 filters x 16 blocks = 512 values. Step 1's stretch to 0..255 makes the descriptor
the same for any global change of brightness and contrast (``a * I + b``, ``a > 0``),
which is what the thesis's photographs under varying light need.
"""

from __future__ import annotations

import functools
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import fft, ndimage

from .._rules import POSITIVE, Interval, check_param
from ..errors import InvalidParameterError

__all__ = ["GistParams", "gist"]

#: Mirror padding (pixels) of the prefilter: keeps the whitening from wrapping around.
PREFILTER_PAD = 5
#: Constant added to the local standard deviation before dividing by it (reference value):
#: flat regions are not amplified into noise.
CONTRAST_FLOOR = 0.2
#: Radial bandwidth, peak frequency falloff and angular bandwidth of the Gabor bank
#: (reference values: peak at 0.3 cycles/pixel for the finest scale, each scale 1.85
#: times coarser).
GABOR_RADIAL = 0.35
GABOR_PEAK = 0.3
GABOR_SCALE_STEP = 1.85
#: Filters applied per FFT batch: bounds memory (8 x 320 x 320 complex = 13 MB).
FILTER_BATCH = 8

_SIZE = Interval(16, 4096, "both", integer=True)
_BLOCKS = Interval(1, 64, "both", integer=True)
_ORIENTATIONS = Interval(1, 64, "both", integer=True)
_PAD = Interval(0, 1024, "both", integer=True)


@dataclass(frozen=True)
class GistParams:
    """Settings of the GIST descriptor; the defaults are the reference implementation's.

    Parameters
    ----------
    image_size : int
        Side of the square the image is resized and cropped to (256).
    orientations : tuple of int
        Orientations per scale, finest scale first (``(8, 8, 8, 8)``: 4 scales x 8).
    blocks : int
        The response magnitudes are averaged over a ``blocks x blocks`` grid (4).
    prefilter_fc : float
        Cut-off of the whitening and contrast normalisation, cycles per image (4).
    boundary : int
        Mirror padding before the Gabor filters, pixels (32).
    """

    image_size: int = 256
    orientations: tuple[int, ...] = (8, 8, 8, 8)
    blocks: int = 4
    prefilter_fc: float = 4.0
    boundary: int = 32

    def __post_init__(self) -> None:
        check_param("image_size", _SIZE, self.image_size)
        check_param("blocks", _BLOCKS, self.blocks)
        check_param("prefilter_fc", POSITIVE, self.prefilter_fc)
        check_param("boundary", _PAD, self.boundary)
        orientations = tuple(self.orientations)
        if not orientations:
            raise InvalidParameterError("orientations", "one count per scale", self.orientations)
        for k in orientations:
            check_param("orientations", _ORIENTATIONS, k)
        object.__setattr__(self, "orientations", tuple(int(k) for k in orientations))
        if self.blocks > self.image_size:
            raise InvalidParameterError(
                "blocks", f"at most image_size ({self.image_size})", self.blocks
            )

    @property
    def length(self) -> int:
        """Values in a descriptor: filters x blocks² (512 by default)."""
        return sum(self.orientations) * self.blocks**2

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON values (a model file records the settings it was trained with)."""
        d = asdict(self)
        d["orientations"] = list(self.orientations)
        return d

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> GistParams:
        """The inverse of :meth:`to_dict`; unknown keys are an error."""
        unknown = set(data) - {"image_size", "orientations", "blocks", "prefilter_fc", "boundary"}
        if unknown:
            raise InvalidParameterError("gist", "keys of GistParams", sorted(unknown))
        data = dict(data)
        if "orientations" in data:
            if not isinstance(data["orientations"], (list, tuple)):
                raise InvalidParameterError(
                    "orientations", "a list of counts", data["orientations"]
                )
            data["orientations"] = tuple(data["orientations"])
        return cls(**data)


def gist(image: ArrayLike, params: GistParams | None = None) -> NDArray[np.float64]:
    """The GIST descriptor of an image: ``(params.length,) float64``, 512 values by default.

    Parameters
    ----------
    image : (h, w) or (h, w, c) array_like
        Grey levels or colour channels (any range; only the first three channels are
        used and averaged). At least 2 x 2 pixels.
    params : GistParams, optional
        The descriptor's settings; the reference implementation's by default.

    Returns
    -------
    (n,) float64
        Per Gabor filter (scale-major, then orientation), the mean response magnitude in
        each block of the grid (blocks down the rows first).

    Examples
    --------
    >>> import numpy as np
    >>> stripes = np.tile([0.0, 0.0, 255.0, 255.0], (64, 16))
    >>> g = gist(stripes)
    >>> g.shape
    (512,)
    >>> bool(np.allclose(g, gist(0.5 * stripes)))
    True
    """
    params = params or GistParams()
    grey = _grey(image)
    square = _resize_crop(grey, params.image_size)
    low, high = float(square.min()), float(square.max())
    square = (square - low) * (255.0 / (high - low)) if high > low else np.zeros_like(square)
    whitened = _prefilter(square, params.prefilter_fc)
    return _gabor_energy(whitened, params)


def _grey(image: ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(image, dtype=np.float64)
    if arr.ndim == 3:
        arr = arr[:, :, :3].mean(axis=2)
    if arr.ndim != 2:
        raise InvalidParameterError("image", "an (h, w) or (h, w, c) array", f"shape {arr.shape}")
    if min(arr.shape) < 2:
        raise InvalidParameterError("image", "at least 2 x 2 pixels", f"shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InvalidParameterError("image", "finite values", "NaN or infinity")
    return arr


def _resize_crop(img: NDArray[np.float64], size: int) -> NDArray[np.float64]:
    """Bilinear resize so that the shorter side is ``size``, then the centred square.

    Shrinking first blurs with a Gaussian of ``(1/scale - 1) / 2`` pixels so that fine
    texture does not alias into coarse (as MATLAB's ``imresize`` antialiasing does).
    """
    h, w = img.shape
    scale = max(size / h, size / w)
    if scale < 1.0:
        img = ndimage.gaussian_filter(img, sigma=(1.0 / scale - 1.0) / 2.0, mode="reflect")
    new_h, new_w = max(size, round(h * scale)), max(size, round(w * scale))
    top, left = (new_h - size) // 2, (new_w - size) // 2
    # Output pixel centres mapped onto input pixel centres (align by centres, not corners).
    rows = (np.arange(top, top + size) + 0.5) * (h / new_h) - 0.5
    cols = (np.arange(left, left + size) + 0.5) * (w / new_w) - 0.5
    rr, cc = np.meshgrid(rows, cols, indexing="ij")
    return ndimage.map_coordinates(img, [rr, cc], order=1, mode="nearest")


def _gaussian_transfer(n: int, fc: float) -> NDArray[np.float64]:
    """The prefilter's Gaussian in the frequency domain, DC at index 0 (value 1)."""
    s1 = fc / np.sqrt(np.log(2.0))
    f = np.fft.fftfreq(n) * n
    return np.exp(-(f[:, None] ** 2 + f[None, :] ** 2) / s1**2)


def _prefilter(img: NDArray[np.float64], fc: float) -> NDArray[np.float64]:
    """Whitening and local contrast normalisation (reference ``prefilt``)."""
    img = np.log1p(img)
    padded = np.pad(img, PREFILTER_PAD, mode="symmetric")
    sn, sm = padded.shape
    n = max(sn, sm)
    n += n % 2
    padded = np.pad(padded, ((0, n - sn), (0, n - sm)), mode="symmetric")
    gf = _gaussian_transfer(n, fc)
    # The Gaussian is 1 at zero frequency, so the whitening removes any constant exactly.
    out = padded - fft.ifft2(fft.fft2(padded) * gf).real
    local_std = np.sqrt(np.abs(fft.ifft2(fft.fft2(out**2) * gf)))
    out = out / (CONTRAST_FLOOR + local_std)
    return out[PREFILTER_PAD : sn - PREFILTER_PAD, PREFILTER_PAD : sm - PREFILTER_PAD]


@functools.lru_cache(maxsize=4)
def _gabor_bank(n: int, orientations: tuple[int, ...]) -> NDArray[np.float64]:
    """Transfer functions ``(filters, n, n)`` of the Gabor bank (reference ``createGabor``),
    laid out for an unshifted FFT."""
    half = np.arange(-(n // 2), n - n // 2, dtype=np.float64)
    fx, fy = np.meshgrid(half, half)
    fr = np.fft.ifftshift(np.hypot(fx, fy))
    theta = np.fft.ifftshift(np.arctan2(fy, fx))
    bank = []
    for scale, count in enumerate(orientations):
        peak = GABOR_PEAK / GABOR_SCALE_STEP**scale
        angular = 16.0 * count**2 / 32.0**2
        for j in range(count):
            tr = theta + np.pi / count * j
            tr = tr + 2 * np.pi * (tr < -np.pi) - 2 * np.pi * (tr > np.pi)
            bank.append(
                np.exp(
                    -10.0 * GABOR_RADIAL * (fr / n / peak - 1.0) ** 2
                    - 2.0 * angular * np.pi * tr**2
                )
            )
    out = np.stack(bank)
    out.setflags(write=False)
    return out


def _gabor_energy(img: NDArray[np.float64], params: GistParams) -> NDArray[np.float64]:
    """Mean magnitude of every Gabor response over the block grid (reference ``gistGabor``)."""
    b = params.boundary
    size = img.shape[0]
    padded = np.pad(img, b, mode="symmetric") if b else img
    bank = _gabor_bank(padded.shape[0], params.orientations)
    spectrum = fft.fft2(padded)
    edges = np.fix(np.linspace(0, size, params.blocks + 1)).astype(int)
    counts = np.diff(edges)
    out = np.empty((len(bank), params.blocks, params.blocks))
    for start in range(0, len(bank), FILTER_BATCH):
        chunk = bank[start : start + FILTER_BATCH]
        response = np.abs(fft.ifft2(spectrum[None] * chunk, axes=(-2, -1)))
        response = response[:, b : b + size, b : b + size]
        # Block sums by cumulative sums at the block edges, then divided by block areas.
        rows = np.add.reduceat(response, edges[:-1], axis=1)
        sums = np.add.reduceat(rows, edges[:-1], axis=2)
        out[start : start + len(chunk)] = sums / np.outer(counts, counts)
    # Blocks down the rows first, as the reference implementation orders them.
    return out.transpose(0, 2, 1).reshape(-1)
