"""Shared fixtures: the real recordings beside the project, and small synthetic drives."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
REALDATA_DIR = REPO_ROOT.parent / "shared" / "realdata"


@pytest.fixture(scope="session")
def realdata() -> Path:
    """The real recordings in ../shared/realdata (see its README).

    Skips when they are absent, except when REQUIRE_REAL_DATA=1 (as in CI), where it fails.
    """
    if REALDATA_DIR.is_dir():
        return REALDATA_DIR
    message = f"real data not found at {REALDATA_DIR}"
    if os.environ.get("REQUIRE_REAL_DATA") == "1":
        pytest.fail(message + " and REQUIRE_REAL_DATA=1 is set")
    pytest.skip(message)


@pytest.fixture(autouse=True, scope="session")
def _index_cache_in_a_temporary_folder(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Drive caches recording indexes; tests keep them out of the user's cache folder."""
    os.environ["FUSIONSCOPE_CACHE_DIR"] = str(tmp_path_factory.mktemp("fusionscope-cache"))
