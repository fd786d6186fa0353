"""A recordings root with one small synthetic drive for the inspector tests."""

from __future__ import annotations

import pytest
from app_fakes import Recordings

from core.synth.generate import generate

SYNTH_SECONDS = 2.0


@pytest.fixture(scope="session")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> Recordings:
    root = tmp_path_factory.mktemp("recordings")
    generate("highway", SYNTH_SECONDS, 1, root / "highway")
    return Recordings(root, "highway")
