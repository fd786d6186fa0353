"""The recordings the inspector may serve: folders with a manifest directly under one root."""

from __future__ import annotations

from pathlib import Path

from core.io.manifest import MANIFEST_NAME


def list_recordings(root: Path) -> list[str]:
    """Sorted names of the folders directly under `root` that hold a `recording.yaml`."""
    if not root.is_dir():
        raise ValueError(f"recordings root: expected a folder, got {root}")
    return sorted(p.name for p in root.iterdir() if (p / MANIFEST_NAME).is_file())


def resolve_recording(root: Path, name: str) -> Path:
    """The folder of recording `name` under `root`; only names `list_recordings` gives."""
    names = list_recordings(root)
    if name not in names:
        raise ValueError(f"recording: expected one of {names} under {root}, got {name!r}")
    return root / name
