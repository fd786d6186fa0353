"""Checks at the engine's public boundary that several modules share (STYLE 10)."""

from __future__ import annotations

import math
from collections.abc import Collection
from pathlib import Path

import numpy as np


def require_finite(name: str, value: float) -> None:
    """ValueError naming `name` unless `value` is a finite number."""
    if not math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")


def require_grey_image(name: str, image: object) -> None:
    """ValueError naming `name` unless `image` is an (H, W) uint8 numpy array."""
    require_2d_array(name, image, np.uint8, "uint8 grey image")


def require_2d_array(name: str, array: object, dtype: type[np.generic], what: str) -> None:
    """ValueError naming `name` unless `array` is an (H, W) numpy array of `dtype`; `what`
    names the expected kind in the message ("int8 edge image")."""
    if not isinstance(array, np.ndarray):
        raise ValueError(f"{name}: expected an (H, W) {what}, got {type(array).__name__}")
    if array.dtype != dtype or array.ndim != 2:
        raise ValueError(f"{name}: expected an (H, W) {what}, got {array.dtype} {array.shape}")


def output_suffix(name: str, path: Path, suffixes: Collection[str]) -> str:
    """The suffix of `path` (lower case), a file to be written; ValueError naming `name` when
    the suffix is not one of `suffixes`, `path` is a folder, or its folder does not exist."""
    suffix = path.suffix.lower()
    if suffix not in suffixes:
        raise ValueError(
            f"{name} {path}: expected a file name ending in {' or '.join(suffixes)}, "
            f"got {path.suffix or 'no suffix'}"
        )
    if path.is_dir():
        raise ValueError(f"{name} {path}: expected a file to write, got a folder")
    if not path.parent.is_dir():
        raise ValueError(f"{name} {path}: the folder {path.parent} does not exist")
    return suffix
