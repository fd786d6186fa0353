"""Fixtures of the recording tests: one small known recording per session."""

from __future__ import annotations

from pathlib import Path

import pytest
from recording_fixture import write_recording


@pytest.fixture(scope="session")
def recording(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A five-frame recording written by RecordingWriter (read-only: copy it to change it)."""
    return write_recording(tmp_path_factory.mktemp("rec") / "tiny")
