"""Shared fixtures: the real recordings beside the project, and small synthetic drives."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import pytest

REPO_ROOT = Path(__file__).resolve().parents[1]
REALDATA_DIR = REPO_ROOT.parent / "shared" / "realdata"
REPORT = pytest.StashKey[list[str]]()


def pytest_configure(config: pytest.Config) -> None:
    config.stash[REPORT] = []


def pytest_terminal_summary(
    terminalreporter: pytest.TerminalReporter, config: pytest.Config
) -> None:
    """Figures the tests measured (accuracy on the bundled drives), after the results."""
    lines = config.stash.get(REPORT, [])
    if lines:
        terminalreporter.section("figures measured by the tests")
        for line in lines:
            terminalreporter.write_line(line)


@pytest.fixture
def report(request: pytest.FixtureRequest) -> Callable[[str], None]:
    """Adds a line to the figures printed at the end of the test run."""
    return request.config.stash[REPORT].append


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
