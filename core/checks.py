"""Checks at the engine's public boundary that several modules share (STYLE 10)."""

from __future__ import annotations

import math


def require_finite(name: str, value: float) -> None:
    """ValueError naming `name` unless `value` is a finite number."""
    if not math.isfinite(value):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")
