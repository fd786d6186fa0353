from __future__ import annotations

import pytest

from app.history import Change, History


def _change(log: list[str], value: int, before: int) -> Change:
    return Change(
        f"{before} -> {value}",
        lambda: log.append(f"undo {value}"),
        lambda: log.append(f"redo {value}"),
    )


def test_undo_and_redo_run_the_changes_in_reverse_and_forward_order() -> None:
    log: list[str] = []
    history = History()
    assert history.undo() is None and history.redo() is None
    history.push(_change(log, 1, 0))
    history.push(_change(log, 2, 1))
    assert history.undo() == "1 -> 2"
    assert history.undo() == "0 -> 1"
    assert history.undo() is None
    assert history.redo() == "0 -> 1"
    assert log == ["undo 2", "undo 1", "redo 1"]
    assert history.can_undo and history.can_redo


def test_a_new_change_drops_what_could_be_redone() -> None:
    log: list[str] = []
    history = History()
    history.push(_change(log, 1, 0))
    history.undo()
    history.push(_change(log, 5, 0))
    assert not history.can_redo
    assert history.redo() is None


def test_only_the_last_changes_are_kept() -> None:
    log: list[str] = []
    history = History(max_changes=2)
    for v in range(1, 5):
        history.push(_change(log, v, v - 1))
    assert [history.undo(), history.undo(), history.undo()] == ["3 -> 4", "2 -> 3", None]


def test_a_history_without_room_is_refused() -> None:
    with pytest.raises(ValueError, match="max_changes: expected at least 1, got 0"):
        History(0)
