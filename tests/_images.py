"""Photographs with a known room category, made on the spot: a procedural texture per
category (stripes one way or the other, a checkerboard), with noise and a random phase."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: Texture of each category the tests train on (categories of Places205 today).
TEXTURES = {"office": "horizontal", "kitchen": "vertical", "living_room": "checker"}


def texture(kind: str, rng: np.random.Generator, shape=(72, 96)) -> np.ndarray:
    """An (h, w) image in 30..220: stripes or a checkerboard of random period and phase."""
    y, x = np.mgrid[0 : shape[0], 0 : shape[1]].astype(float)
    period = rng.uniform(7.0, 11.0)
    phase = rng.uniform(0.0, 2 * np.pi)
    if kind == "horizontal":
        wave = np.sin(2 * np.pi * y / period + phase)
    elif kind == "vertical":
        wave = np.sin(2 * np.pi * x / period + phase)
    elif kind == "checker":
        wave = np.sign(np.sin(2 * np.pi * x / period + phase) * np.sin(2 * np.pi * y / period))
    else:
        raise ValueError(kind)
    img = 125.0 + 70.0 * wave + rng.normal(0.0, 12.0, shape)
    return np.clip(img, 30.0, 220.0)


def write_training_folder(root: Path, per_category: int, seed: int = 0, categories=None) -> Path:
    """``root/<category>/<k>.png`` for the categories of :data:`TEXTURES` (or those given)."""
    from PIL import Image

    rng = np.random.default_rng(seed)
    for name in categories or TEXTURES:
        folder = root / name
        folder.mkdir(parents=True, exist_ok=True)
        for k in range(per_category):
            img = texture(TEXTURES.get(name, "checker"), rng)
            Image.fromarray(img.astype(np.uint8)).save(folder / f"{k:02d}.png")
    return root
