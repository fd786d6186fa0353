"""Checks at the engine's public boundary that several modules share (STYLE 10)."""

from __future__ import annotations

import math

import numpy as np


def require_finite(name: str, value: float) -> None:
    """ValueError naming `name` unless `value` is a finite number."""
    if not math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")


def require_grey_image(name: str, image: object) -> None:
    """ValueError naming `name` unless `image` is an (H, W) uint8 numpy array."""
    if not isinstance(image, np.ndarray):
        raise ValueError(f"{name}: expected an (H, W) uint8 grey image, got {type(image).__name__}")
    if image.dtype != np.uint8 or image.ndim != 2:
        raise ValueError(
            f"{name}: expected an (H, W) uint8 grey image, got {image.dtype} {image.shape}"
        )
