from __future__ import annotations

from pathlib import Path

import pytest

from app.catalog import list_recordings, resolve_recording


def make_root(tmp_path: Path) -> Path:
    for name in ("b", "a"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "recording.yaml").write_text("{}\n")
    (tmp_path / "not-a-recording").mkdir()
    return tmp_path


def test_lists_only_folders_with_a_manifest(tmp_path: Path) -> None:
    assert list_recordings(make_root(tmp_path)) == ["a", "b"]


def test_resolves_a_listed_name_to_its_folder(tmp_path: Path) -> None:
    root = make_root(tmp_path)
    assert resolve_recording(root, "b") == root / "b"


@pytest.mark.parametrize("name", ["c", "not-a-recording", "../a", "/etc", "a/.."])
def test_refuses_names_outside_the_listing(tmp_path: Path, name: str) -> None:
    with pytest.raises(ValueError, match="recording: expected one of"):
        resolve_recording(make_root(tmp_path), name)


def test_root_must_be_a_folder(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="recordings root: expected a folder"):
        list_recordings(tmp_path / "missing")
