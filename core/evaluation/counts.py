"""Figures of several frames or recordings added up, field by field."""

from __future__ import annotations

import dataclasses
import itertools
from collections.abc import Sequence
from typing import Any, TypeVar

T = TypeVar("T")


def sum_fields(items: Sequence[T]) -> T:
    """The field-by-field sum of dataclass instances of one type: numbers add, tuples
    (listings) concatenate, nested dataclasses add the same way. In one pass, so that
    summing a long drive's frames costs as much as the frames."""
    if not items:
        raise ValueError("items: expected at least one figure to sum, got none")
    values: dict[str, Any] = {}
    for f in dataclasses.fields(items[0]):  # type: ignore[arg-type]
        column = [getattr(item, f.name) for item in items]
        if dataclasses.is_dataclass(column[0]):
            values[f.name] = sum_fields(column)
        elif isinstance(column[0], tuple):
            values[f.name] = tuple(itertools.chain.from_iterable(column))
        else:
            values[f.name] = sum(column)
    return type(items[0])(**values)


def add_fields(a: T, b: T) -> T:
    """`sum_fields` of two."""
    return sum_fields([a, b])
