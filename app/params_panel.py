"""The live parameter panel: a field for every parameter of `core.params.Params`, grouped by
stage, each with its unit and the paper's value, and a reset to the papers' values.

The panel only reports what the user typed (`on_change(dotted_name, value)`); the session
checks it with `Params.with_value` and shows the outcome with `show`. Values set here by the
server (`show`) do not come back as changes.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import fields
from typing import Any

import viser

from core.params import Params, to_dict

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


def hint(name: str, paper_value: object) -> str:
    unit = unit_of(name)
    return f"{unit + '; ' if unit else ''}paper: {paper_value}"


class ParamsPanel:
    """The "Parameters" folder of one client's page."""

    def __init__(
        self,
        gui: viser.GuiApi,
        on_change: Callable[[str, object], None],
        on_reset: Callable[[], None],
        order: int,
    ) -> None:
        self._handles: dict[str, Any] = {}
        with gui.add_folder("Parameters", order=order, expand_by_default=False):
            reset = gui.add_button("Reset all to the papers' values", icon=viser.Icon.RESTORE)
            reset.on_click(lambda _: on_reset())
            stage_names = [f.name for f in fields(Params)]
            rows = parameter_names(Params())
            for stage in stage_names:
                with gui.add_folder(stage, expand_by_default=False):
                    for _, name, value in (r for r in rows if r[0] == stage):
                        self._handles[f"{stage}.{name}"] = self._field(gui, name, value)
        for dotted, handle in self._handles.items():
            handle.on_update(
                lambda event, dotted=dotted: (
                    on_change(dotted, event.target.value) if event.client is not None else None
                )
            )

    @staticmethod
    def _field(gui: viser.GuiApi, name: str, paper_value: object) -> Any:
        label, tip = name, hint(name, paper_value)
        if isinstance(paper_value, bool):
            return gui.add_checkbox(label, paper_value, hint=tip)
        if isinstance(paper_value, int):
            return gui.add_number(label, paper_value, step=1, hint=tip)
        assert isinstance(paper_value, float), f"{name}: a parameter of unexpected type"
        return gui.add_number(label, paper_value, step=_step(paper_value), hint=tip)

    def show(self, params: Params) -> None:
        """Put `params`' values in the fields (a reset, a refused value, a loaded preset)."""
        for stage, name, value in parameter_names(params):
            handle = self._handles[f"{stage}.{name}"]
            if handle.value != value:
                handle.value = value


def _step(value: float) -> float:
    """A field step: the power of ten at most a hundredth of the paper's value (0.001 for 0)."""
    if value == 0.0:
        return 0.001
    return float(10.0 ** math.floor(math.log10(abs(value) / 100.0)))
