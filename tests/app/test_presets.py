from __future__ import annotations

import os
from pathlib import Path

import pytest

from app.presets import PresetStore, check_name
from core.params import Params, ParamsError, load_params, params_from


def test_a_saved_preset_loads_back_equal_and_is_listed(tmp_path: Path) -> None:
    store = PresetStore(tmp_path / "presets")
    assert store.names() == ["papers"]  # built in, listed first
    params = Params().with_value("motion_stereo.threshold_xi", 31.5)
    path = store.save("tight-xi", params)
    assert path == tmp_path / "presets" / "tight-xi.yaml"
    assert store.load("tight-xi") == params
    assert load_params(path) == params  # the command line's --params reads it too
    assert store.names() == ["papers", "tight-xi"]


def test_the_papers_preset_is_built_in_loads_as_the_command_line_does_and_cannot_be_saved(
    tmp_path: Path,
) -> None:
    store = PresetStore(tmp_path / "presets")
    assert store.load("papers") == params_from("papers")
    with pytest.raises(ParamsError, match="preset name: 'papers' is built in"):
        store.save("papers", Params())
    assert not (tmp_path / "presets").exists()


def test_saving_again_replaces_the_preset_and_leaves_no_temporary_file(tmp_path: Path) -> None:
    store = PresetStore(tmp_path)
    store.save("a", Params())
    changed = Params().with_value("motion_stereo.threshold_xi", 12.0)
    store.save("a", changed)
    assert store.load("a") == changed
    assert sorted(os.listdir(tmp_path)) == ["a.yaml"]


@pytest.mark.parametrize(
    "name", ["", " ", "../evil", "a/b", "a.b", ".hidden", "-x", "x" * 65, "a b", "ä"]
)
def test_names_that_could_leave_the_folder_or_hide_are_refused(tmp_path: Path, name: str) -> None:
    store = PresetStore(tmp_path / "presets")
    with pytest.raises(ParamsError, match="preset name: expected letters, digits"):
        store.save(name, Params())
    assert not (tmp_path / "presets").exists()  # nothing written anywhere
    assert list(tmp_path.iterdir()) == []


def test_surrounding_spaces_are_dropped_from_a_name() -> None:
    assert check_name("  highway-1 ") == "highway-1"


def test_a_missing_preset_names_its_file_and_what_exists(tmp_path: Path) -> None:
    store = PresetStore(tmp_path)
    store.save("kept", Params())
    with pytest.raises(ParamsError, match=r"nope\.yaml: no such preset; saved here: \['kept'\]"):
        store.load("nope")


def test_a_broken_preset_file_is_reported_with_its_path_and_left_alone(tmp_path: Path) -> None:
    (tmp_path / "bad.yaml").write_text("pitch: {max_lines: many}\n")
    store = PresetStore(tmp_path)
    with pytest.raises(ParamsError, match=r"bad\.yaml: pitch"):
        store.load("bad")
    assert (tmp_path / "bad.yaml").read_text() == "pitch: {max_lines: many}\n"


def test_a_folder_that_cannot_be_created_is_named(tmp_path: Path) -> None:
    (tmp_path / "file").write_text("")
    store = PresetStore(tmp_path / "file" / "presets")
    with pytest.raises(ParamsError, match="cannot write presets here"):
        store.save("a", Params())
