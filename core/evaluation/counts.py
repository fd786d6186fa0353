"""Figures of several frames or recordings added up, field by field."""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar

T = TypeVar("T")


def add_fields(a: T, b: T) -> T:
    """The field-by-field sum of two dataclass instances of one type: numbers add, tuples
    (listings) concatenate, nested dataclasses add the same way."""
    values: dict[str, Any] = {}
    for f in dataclasses.fields(a):  # type: ignore[arg-type]
        x, y = getattr(a, f.name), getattr(b, f.name)
        values[f.name] = add_fields(x, y) if dataclasses.is_dataclass(x) else x + y
    return type(a)(**values)
