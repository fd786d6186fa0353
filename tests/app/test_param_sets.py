from __future__ import annotations

from pathlib import Path

import pytest

from app.history import History
from app.param_sets import ParamSets, Sets, changed_names
from app.presets import PresetStore
from core.params import Params, ParamsError

XI = "motion_stereo.threshold_xi"


@pytest.fixture()
def seen() -> list[Sets]:
    return []


@pytest.fixture()
def sets(tmp_path: Path, seen: list[Sets]) -> ParamSets:
    return ParamSets(PresetStore(tmp_path / "presets"), History(), seen.append)


def test_a_value_changes_set_a_and_is_reported(sets: ParamSets, seen: list[Sets]) -> None:
    sets.set_value(XI, 25.0)
    assert sets.sets.a.motion_stereo.threshold_xi == 25.0 and sets.sets.b is None
    assert seen == [sets.sets]
    assert changed_names(sets.sets.a) == [XI]


def test_a_refused_value_changes_nothing(sets: ParamSets, seen: list[Sets]) -> None:
    with pytest.raises(ParamsError):
        sets.set_value(XI, -5.0)
    assert sets.sets == Sets() and seen == []
    assert sets.undo() is None


def test_undo_and_redo_walk_back_and_forth_over_changes(sets: ParamSets) -> None:
    sets.set_value(XI, 25.0)
    sets.set_value(XI, 30.0)
    sets.reset_value(XI)
    assert sets.sets.a == Params()
    assert sets.undo() == f"A: {XI} back to the default 20.0"
    assert sets.sets.a.motion_stereo.threshold_xi == 30.0
    sets.undo()
    assert sets.sets.a.motion_stereo.threshold_xi == 25.0
    sets.redo()
    assert sets.sets.a.motion_stereo.threshold_xi == 30.0


def test_comparing_copies_a_into_b_and_edits_b_alone(sets: ParamSets) -> None:
    sets.set_value(XI, 25.0)
    sets.set_comparing(True)
    assert sets.sets.b == sets.sets.a
    sets.set_editing("B")
    sets.set_value(XI, 40.0)
    assert (
        sets.sets.a.motion_stereo.threshold_xi,
        sets.sets.edited.motion_stereo.threshold_xi,
    ) == (
        25.0,
        40.0,
    )
    sets.swap()
    assert sets.sets.a.motion_stereo.threshold_xi == 40.0
    assert sets.sets.b is not None and sets.sets.b.motion_stereo.threshold_xi == 25.0
    sets.set_comparing(False)
    assert sets.sets == Sets(sets.sets.a)
    sets.undo()  # comparing again, as before
    assert sets.sets.b is not None and sets.sets.editing == "B"


def test_b_cannot_be_edited_or_swapped_without_comparing(sets: ParamSets) -> None:
    with pytest.raises(ParamsError, match="editing: there is no set B"):
        sets.set_editing("B")
    with pytest.raises(ParamsError, match="swap: there is no set B"):
        sets.swap()
    with pytest.raises(ValueError, match="editing: expected 'A'"):
        Sets(editing="B")


def test_a_preset_saves_the_edited_set_and_loads_back_undoably(sets: ParamSets) -> None:
    sets.set_value(XI, 33.0)
    path = sets.save_preset("mine")
    assert path.endswith("mine.yaml")
    sets.reset_all()
    assert sets.sets.a == Params()
    sets.load_preset("mine")
    assert sets.sets.a.motion_stereo.threshold_xi == 33.0
    sets.undo()
    assert sets.sets.a == Params()


def test_a_missing_preset_changes_nothing(sets: ParamSets, seen: list[Sets]) -> None:
    with pytest.raises(ParamsError, match="no such preset"):
        sets.load_preset("absent")
    assert seen == []
