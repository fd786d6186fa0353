"""Undo and redo for one browser tab: a stack of changes, each able to undo and redo itself.

    history.push(Change("pitch.max_lines 6 -> 8", undo=put_back_old, redo=put_new))
    history.undo()   # runs put_back_old, returns the change's label
    history.redo()   # runs put_new

A change is recorded after it was made; pushing a new change drops what could be redone.
The stack keeps the last MAX_CHANGES changes. Parameter changes use it now; annotation
edits are meant to join the same stack.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

MAX_CHANGES = 500


@dataclass(frozen=True)
class Change:
    """A change already made: `label` says what it did, `undo` and `redo` apply it again."""

    label: str
    undo: Callable[[], None]
    redo: Callable[[], None]


class History:
    """Undo and redo stacks of `Change`s (thread-safe: controls call in from several threads)."""

    def __init__(self, max_changes: int = MAX_CHANGES) -> None:
        if max_changes < 1:
            raise ValueError(f"max_changes: expected at least 1, got {max_changes}")
        self._max = max_changes
        self._done: list[Change] = []
        self._undone: list[Change] = []
        self._lock = threading.Lock()

    def push(self, change: Change) -> None:
        with self._lock:
            self._done.append(change)
            del self._done[: -self._max]
            self._undone.clear()

    def undo(self) -> str | None:
        """Undo the last change; its label, or None when there is nothing to undo."""
        with self._lock:
            if not self._done:
                return None
            change = self._done.pop()
            self._undone.append(change)
        change.undo()
        return change.label

    def redo(self) -> str | None:
        """Redo the last undone change; its label, or None when there is nothing to redo."""
        with self._lock:
            if not self._undone:
                return None
            change = self._undone.pop()
            self._done.append(change)
        change.redo()
        return change.label

    @property
    def can_undo(self) -> bool:
        return bool(self._done)

    @property
    def can_redo(self) -> bool:
        return bool(self._undone)
