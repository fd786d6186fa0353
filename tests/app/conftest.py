"""A recordings root with one small synthetic drive for the inspector tests."""

from __future__ import annotations

import pytest
from app_fakes import Recordings

from core.engine import FusionEngine
from core.io.drive import Drive
from core.params import Params
from core.synth.generate import generate

SYNTH_SECONDS = 2.0


@pytest.fixture(scope="session")
def recordings(tmp_path_factory: pytest.TempPathFactory) -> Recordings:
    root = tmp_path_factory.mktemp("recordings")
    generate("highway", SYNTH_SECONDS, 1, root / "highway")
    # The first run after an install compiles the engine's numba code (README: about 15 s,
    # more on a busy machine): do it here, not inside a browser test's page timeout.
    with Drive(root / "highway") as drive:
        FusionEngine(Params(), drive.camera).seek(drive, 1)
    return Recordings(root, "highway")
