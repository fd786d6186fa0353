"""Reading the project's small YAML files with errors that name the file and the key."""

from __future__ import annotations

import math
from collections.abc import Mapping
from collections.abc import Set as AbstractSet
from pathlib import Path
from typing import Any

import yaml

from core.io.errors import RecordingError


def load_yaml_mapping(path: Path, what: str) -> dict[str, Any]:
    """The top-level mapping of a YAML file; RecordingError if missing, malformed, not a mapping."""
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError as err:
        raise RecordingError(f"{path}: {what} not found") from err
    except (OSError, UnicodeDecodeError) as err:
        raise RecordingError(f"{path}: cannot read {what}: {err}") from err
    try:
        raw = yaml.safe_load(text)
    except yaml.YAMLError as err:
        raise RecordingError(f"{path}: {what} is not valid YAML: {err}") from err
    if not isinstance(raw, dict):
        raise RecordingError(
            f"{path}: expected a mapping of keys ({what}), got {type(raw).__name__}"
        )
    return raw


class Fields:
    """Typed access to one YAML mapping; every error names the file and the dotted key."""

    def __init__(self, path: Path, raw: object, where: str = "") -> None:
        self.path = path
        self.where = where
        if not isinstance(raw, Mapping):
            raise RecordingError(f"{path}: {where or 'top level'}: expected a mapping, got {raw!r}")
        self.raw: Mapping[str, Any] = raw

    def key(self, name: str) -> str:
        return f"{self.where}.{name}" if self.where else name

    def fail(self, name: str, expected: str, got: object) -> RecordingError:
        return RecordingError(f"{self.path}: {self.key(name)}: expected {expected}, got {got!r}")

    def check_keys(
        self, required: AbstractSet[str], optional: AbstractSet[str] = frozenset()
    ) -> None:
        known = required | optional
        unknown = sorted(set(self.raw) - known)
        if unknown:
            raise RecordingError(
                f"{self.path}: {self.key(unknown[0])}: unknown key; "
                f"known keys here: {', '.join(sorted(known))}"
            )
        missing = sorted(required - set(self.raw))
        if missing:
            raise RecordingError(f"{self.path}: {self.key(missing[0])}: missing key")

    def has(self, name: str) -> bool:
        return self.raw.get(name) is not None

    def sub(self, name: str) -> Fields:
        return Fields(self.path, self.raw.get(name), self.key(name))

    def str_(self, name: str) -> str:
        value = self.raw.get(name)
        if not isinstance(value, str) or not value:
            raise self.fail(name, "a non-empty string", value)
        return value

    def int_(self, name: str) -> int:
        value = self.raw.get(name)
        if not isinstance(value, int) or isinstance(value, bool):
            raise self.fail(name, "an integer", value)
        return value

    def float_(self, name: str) -> float:
        value = self.raw.get(name)
        if (
            not isinstance(value, (int, float))
            or isinstance(value, bool)
            or not math.isfinite(value)
        ):
            raise self.fail(name, "a finite number", value)
        return float(value)

    def floats(self, name: str, n: int | None = None) -> tuple[float, ...]:
        value = self.raw.get(name)
        ok = isinstance(value, list) and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
        )
        if not ok or (n is not None and len(value) != n):  # type: ignore[arg-type]
            raise self.fail(
                name, f"a list of {n if n is not None else 'any number of'} numbers", value
            )
        return tuple(float(v) for v in value)  # type: ignore[union-attr]
