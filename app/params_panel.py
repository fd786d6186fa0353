"""The live parameter panel: a field for every parameter of `core.params.Params`, grouped by
stage, each with its unit, its default and, where the default departs from the papers, the
papers' value; undo and redo; compare with a set B; presets; reset one parameter or all to
the defaults.

The panel hands what the user did to `app.param_sets.ParamSets`, which checks and records
it; the session calls `show` with the outcome. Values set here by the server (`show`) do not
come back as changes (viser reports them with no client).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import fields
from pathlib import Path
from typing import Any, Literal

import viser

from app.param_sets import ParamSets, Sets, changed_names
from core.params import Params, ParamsError, params_from, to_dict

# a parameter's unit, from the end of its name (core/params.py names carry their units)
UNIT_SUFFIXES = (
    ("_mps2", "m/s²"),
    ("_mps", "m/s"),
    ("_radps", "rad/s"),
    ("_rad", "rad"),
    ("_deg", "deg"),
    ("_px", "px"),
    ("_ms", "ms"),
    ("_hz", "Hz"),
    ("_m", "m"),
    ("_s", "s"),
)


def unit_of(name: str) -> str:
    """The unit a parameter's name ends in ("" for counts, fractions and switches)."""
    return next((unit for suffix, unit in UNIT_SUFFIXES if name.endswith(suffix)), "")


def parameter_names(params: Params) -> list[tuple[str, str, Any]]:
    """(stage, name, value) of every parameter, in core/params.py's order."""
    data = to_dict(params)
    return [(stage, name, value) for stage in data for name, value in data[stage].items()]


def hint(name: str, default: object, papers: object) -> str:
    """A field's hint: its unit, its default and, where it departs, the papers' value."""
    unit = unit_of(name)
    departs = f" (papers: {papers})" if papers != default else ""
    return f"{unit + '; ' if unit else ''}default: {default}{departs}"


NO_CHOICE = "(none)"
NoticeColour = Literal["red", "green", "gray", "yellow"]


class ParamsPanel:
    """The "Parameters" folder of one client's page: undo and redo, A/B, presets, resets and
    a field per parameter. Every control calls `sets`; a refusal (ParamsError) goes to
    `notify(title, message, "red")` and the fields show the values in use again."""

    def __init__(
        self,
        gui: viser.GuiApi,
        sets: ParamSets,
        notify: Callable[[str, str, NoticeColour], None],
        order: int,
    ) -> None:
        self._sets = sets
        self._notify = notify
        self._handles: dict[str, Any] = {}
        with gui.add_folder("Parameters", order=order, expand_by_default=False):
            history = gui.add_button_group("history", ("Undo", "Redo"))
            self._compare = gui.add_checkbox(
                "compare with B", False, hint="run a second parameter set B beside A"
            )
            self._editing = gui.add_dropdown(
                "fields edit", ("A", "B"), initial_value="A", disabled=True
            )
            swap = gui.add_button("Swap A and B", icon=viser.Icon.ARROWS_EXCHANGE, disabled=True)
            self._swap = swap
            with gui.add_folder("Presets", expand_by_default=False):
                self._preset_name = gui.add_text("name", "", hint="letters, digits, - and _")
                save = gui.add_button("Save the edited set", icon=viser.Icon.DEVICE_FLOPPY)
                self._preset = gui.add_dropdown("preset", (NO_CHOICE,))
                load = gui.add_button("Load into the edited set", icon=viser.Icon.FOLDER_OPEN)
            self._changed = gui.add_dropdown("changed", (NO_CHOICE,), hint="from the defaults")
            reset_one = gui.add_button("Reset it to its default", icon=viser.Icon.RESTORE)
            reset = gui.add_button("Reset all to the defaults", icon=viser.Icon.RESTORE)
            rows = parameter_names(Params())
            papers = to_dict(params_from("papers"))
            for stage in (f.name for f in fields(Params)):
                with gui.add_folder(stage, expand_by_default=False):
                    for _, name, value in (r for r in rows if r[0] == stage):
                        paper = papers[stage][name]
                        self._handles[f"{stage}.{name}"] = self._field(gui, name, value, paper)
        history.on_click(lambda e: self._do(sets.undo if e.target.value == "Undo" else sets.redo))
        self._compare.on_update(
            lambda e: self._do(lambda: sets.set_comparing(e.target.value)) if e.client else None
        )
        self._editing.on_update(
            lambda e: (
                self._do(lambda: sets.set_editing("B" if e.target.value == "B" else "A"))
                if e.client
                else None
            )
        )
        swap.on_click(lambda _: self._do(sets.swap))
        save.on_click(lambda _: self._save_preset())
        load.on_click(lambda _: self._do(lambda: sets.load_preset(self._preset.value)))
        reset_one.on_click(lambda _: self._reset_one())
        reset.on_click(lambda _: self._do(sets.reset_all))
        for dotted, handle in self._handles.items():
            handle.on_update(
                lambda event, dotted=dotted: (
                    self._do(functools.partial(sets.set_value, dotted, event.target.value))
                    if event.client is not None
                    else None
                )
            )
        self.show(sets.sets)
        self._list_presets()

    @staticmethod
    def _field(gui: viser.GuiApi, name: str, default: object, papers: object) -> Any:
        label, tip = name, hint(name, default, papers)
        if isinstance(default, bool):
            return gui.add_checkbox(label, default, hint=tip)
        if isinstance(default, int):
            return gui.add_number(label, default, step=1, hint=tip)
        assert isinstance(default, float), f"{name}: a parameter of unexpected type"
        return gui.add_number(label, default, step=_step(default), hint=tip)

    def show(self, sets: Sets) -> None:
        """Put the edited set's values, what differs from the defaults and the A/B choice in
        the controls (after any change, an undo, a refusal)."""
        for stage, name, value in parameter_names(sets.edited):
            handle = self._handles[f"{stage}.{name}"]
            if handle.value != value:
                handle.value = value
        changed = changed_names(sets.edited)
        self._changed.options = tuple(changed) or (NO_CHOICE,)
        self._compare.value = sets.b is not None  # type: ignore[misc]  # asymmetric property
        self._editing.value = sets.editing  # type: ignore[misc]
        self._editing.disabled = self._swap.disabled = sets.b is None

    def _do(self, action: Callable[[], object]) -> None:
        try:
            action()
        except ParamsError as err:
            title, _, message = str(err).partition(": ")
            self._notify(f"{title}: refused", message or str(err), "red")
            self.show(self._sets.sets)

    def _save_preset(self) -> None:
        def save() -> None:
            path = self._sets.save_preset(self._preset_name.value)
            self._list_presets()
            self._preset.value = Path(path).stem  # type: ignore[misc]
            self._notify("Preset saved", path, "green")

        self._do(save)

    def _list_presets(self) -> None:
        """The preset dropdown's choices: the folder is listed when the panel is made and
        after a save, not on every parameter change."""
        self._preset.options = tuple(self._sets.presets.names()) or (NO_CHOICE,)

    def _reset_one(self) -> None:
        if self._changed.value != NO_CHOICE:
            self._do(functools.partial(self._sets.reset_value, self._changed.value))


def _step(value: float) -> float:
    """A field step: the power of ten at most a hundredth of the default (0.001 for 0)."""
    if value == 0.0:
        return 0.001
    return float(10.0 ** math.floor(math.log10(abs(value) / 100.0)))
