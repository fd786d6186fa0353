"""A recordings root with one small synthetic drive for the inspector tests, and headless
Chromium for the browser tests."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest
from app_fakes import Recordings
from browser_page import CHROMIUM, CHROMIUM_ARGS
from playwright.sync_api import Browser, Page, sync_playwright

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


@pytest.fixture(scope="module")
def browser(recordings: Recordings) -> Iterator[Browser]:
    """Headless Chromium; after `recordings`, which also compiles the engine first."""
    if not CHROMIUM.exists():
        message = f"headless browser tests need Debian chromium at {CHROMIUM}"
        if os.environ.get("CI") or os.environ.get("REQUIRE_BROWSER"):
            pytest.fail(message + " (CI / REQUIRE_BROWSER is set)")
        pytest.skip(message)
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield browser
        browser.close()


@pytest.fixture()
def page(browser: Browser) -> Iterator[Page]:
    """A page in a fresh profile (`browser_page.serving` saves its last picture)."""
    context = browser.new_context(viewport={"width": 1400, "height": 800})
    yield context.new_page()
    context.close()
