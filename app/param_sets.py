"""One tab's parameter sets: A, which the engine runs with, and B to compare with; which of
the two the fields edit; undo and redo of every change to them; presets.

Every change goes through `ParamSets`, which checks it (`core.params`), records it in the
tab's `History` and reports the new `Sets` to `on_change`; a value the parameters refuse
raises ParamsError and changes nothing. Undo and redo restore whole `Sets`.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Literal

from app.history import Change, History
from app.presets import PresetStore
from core.params import Params, ParamsError, to_dict

Which = Literal["A", "B"]


@dataclass(frozen=True)
class Sets:
    """Set A, set B (None: not comparing) and the one the fields edit."""

    a: Params = field(default_factory=Params)
    b: Params | None = None
    editing: Which = "A"

    def __post_init__(self) -> None:
        if self.editing == "B" and self.b is None:
            raise ValueError("editing: expected 'A' when there is no set B, got 'B'")

    @property
    def edited(self) -> Params:
        return self.b if self.editing == "B" and self.b is not None else self.a

    def with_edited(self, params: Params) -> Sets:
        return replace(self, b=params) if self.editing == "B" else replace(self, a=params)


def changed_names(params: Params) -> list[str]:
    """Dotted names of the parameters that differ from the defaults."""
    now, paper = to_dict(params), to_dict(Params())
    return [
        f"{stage}.{name}"
        for stage in now
        for name in now[stage]
        if now[stage][name] != paper[stage][name]
    ]


class ParamSets:
    """The parameter sets of one tab; `on_change(sets)` after every change (also undo/redo)."""

    def __init__(
        self, presets: PresetStore, history: History, on_change: Callable[[Sets], None]
    ) -> None:
        self.presets = presets
        self._history = history
        self._on_change = on_change
        self._sets = Sets()
        self._lock = threading.Lock()

    @property
    def sets(self) -> Sets:
        return self._sets

    # --- values of the edited set -----------------------------------------------------------
    def set_value(self, dotted: str, value: object) -> None:
        """One parameter of the edited set; ParamsError when the parameters refuse it."""
        edited = self._sets.edited
        was = edited.value_of(dotted)
        self._change(
            f"{self._sets.editing}: {dotted} {was} -> {value}",
            self._sets.with_edited(edited.with_value(dotted, value)),
        )

    def reset_value(self, dotted: str) -> None:
        """One parameter of the edited set back to its default."""
        default = Params().value_of(dotted)
        self._change(
            f"{self._sets.editing}: {dotted} back to the default {default}",
            self._sets.with_edited(self._sets.edited.with_value(dotted, default)),
        )

    def reset_all(self) -> None:
        """Every parameter of the edited set back to the defaults."""
        self._change(
            f"{self._sets.editing}: all back to the defaults", self._sets.with_edited(Params())
        )

    # --- presets ------------------------------------------------------------------------
    def save_preset(self, name: str) -> str:
        """Save the edited set as preset `name`; the file written. ParamsError on a bad name
        or a folder that cannot be written."""
        return str(self.presets.save(name, self._sets.edited))

    def load_preset(self, name: str) -> None:
        """Preset `name` into the edited set; ParamsError naming the file when it cannot."""
        params = self.presets.load(name)
        self._change(f"{self._sets.editing}: preset {name}", self._sets.with_edited(params))

    # --- A and B ------------------------------------------------------------------------
    def set_comparing(self, on: bool) -> None:
        """Start comparing (B starts as a copy of A) or stop (B is dropped, A edited)."""
        if on == (self._sets.b is not None):
            return
        new = replace(self._sets, b=self._sets.a) if on else Sets(self._sets.a)
        self._change("compare with B" if on else "stop comparing", new)

    def set_editing(self, which: Which) -> None:
        """Which set the fields edit (not an undoable change)."""
        if which == "B" and self._sets.b is None:
            raise ParamsError("editing: there is no set B; switch comparing on first")
        self._apply(replace(self._sets, editing=which))

    def swap(self) -> None:
        """A becomes B and B becomes A."""
        if self._sets.b is None:
            raise ParamsError("swap: there is no set B; switch comparing on first")
        self._change("swap A and B", replace(self._sets, a=self._sets.b, b=self._sets.a))

    def open_link(self, a: Params, b: Params | None) -> None:
        """The sets a view link carries (one undoable change), A edited."""
        self._change("the link's parameters", Sets(a, b))

    # --- history ------------------------------------------------------------------------
    def undo(self) -> str | None:
        return self._history.undo()

    def redo(self) -> str | None:
        return self._history.redo()

    def _change(self, label: str, new: Sets) -> None:
        old = self._sets
        if new == old:
            return
        self._apply(new)
        self._history.push(Change(label, lambda: self._apply(old), lambda: self._apply(new)))

    def _apply(self, sets: Sets) -> None:
        with self._lock:
            self._sets = sets
        self._on_change(sets)
