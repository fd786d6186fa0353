"""The inspector in headless Chromium: the camera image shows, stepping shows the next frame.

Needs Debian's chromium at /usr/bin/chromium (Playwright's own browser download is never
used). Without it the tests skip, except when CI or REQUIRE_BROWSER is set, where they fail.
"""

from __future__ import annotations

import os
import re
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest
from app_fakes import FakeDrive, Recordings
from playwright.sync_api import Browser, Page, sync_playwright

from app.server import DriveOpener, InspectorServer, open_drive
from core.io import Drive, FrameInput
from core.io.errors import RecordingError

CHROMIUM = Path("/usr/bin/chromium")
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
SCREENSHOT = Path("/tmp/inspector.png")
ERROR_SCREENSHOT = Path("/tmp/inspector-error.png")
TIMEOUT_MS = 30_000
SETTLE_MS = 1_000  # longer than a seek's replay and render

# The camera image: the one <img> viser fills from a blob with the rendered frame.
CAMERA_IMG = "img[src^='blob:']"


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
    context = browser.new_context(viewport={"width": 1400, "height": 800})  # fresh profile
    yield context.new_page()
    context.close()


def start(
    root: Path, recording: str | None = None, opener: DriveOpener = open_drive
) -> InspectorServer:
    presets = Path(tempfile.mkdtemp(prefix="fusionscope-presets-"))
    server = InspectorServer(root, recording, "127.0.0.1", 0, open_drive=opener, presets=presets)
    server.start()
    return server


def camera_src(page: Page) -> str:
    page.wait_for_function(
        f'() => {{ const i = document.querySelector("{CAMERA_IMG}");'
        " return i !== null && i.complete && i.naturalWidth > 0; }",
        timeout=TIMEOUT_MS,
    )
    return page.locator(CAMERA_IMG).get_attribute("src") or ""


def test_step_shows_the_next_frame(recordings: Recordings, page: Page) -> None:
    server = start(recordings.root, recordings.name)
    try:
        page.goto(f"http://127.0.0.1:{server.port}/")
        first = camera_src(page)
        size = page.locator(CAMERA_IMG).evaluate("i => [i.naturalWidth, i.naturalHeight]")
        assert size[0] == 640 and size[1] > 480  # the frame plus its caption strip
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        page.screenshot(path=str(SCREENSHOT))

        page.get_by_role("button", name="Step +1").click()
        page.get_by_text("frame 1 /").wait_for(timeout=TIMEOUT_MS)
        page.wait_for_function(
            f'src => document.querySelector("{CAMERA_IMG}")?.src !== src',
            arg=first,
            timeout=TIMEOUT_MS,
        )
        assert camera_src(page) != first
    finally:
        server.stop()


def test_play_runs_to_the_end_and_pause_stops(recordings: Recordings, page: Page) -> None:
    with Drive(recordings.root / recordings.name) as drive:
        last = len(drive) - 1
    server = start(recordings.root, recordings.name)
    try:
        page.goto(f"http://127.0.0.1:{server.port}/")
        camera_src(page)
        readout = page.get_by_text(re.compile(r"^frame \d+ / \d+ \|"))
        page.get_by_role("button", name="Play").click()
        page.get_by_text(f"frame {last} / {last}").wait_for(timeout=TIMEOUT_MS)
        page.get_by_role("button", name="Play").wait_for(timeout=TIMEOUT_MS)

        page.get_by_role("button", name="Play").click()  # from the end: starts over
        page.get_by_role("button", name="Pause").click()
        page.get_by_role("button", name="Play").wait_for(timeout=TIMEOUT_MS)
        # a frame stepped to just before the pause may still be rendering: let it arrive
        page.wait_for_timeout(SETTLE_MS)
        paused_at = readout.inner_text()
        page.wait_for_timeout(500)
        assert readout.inner_text() == paused_at
        assert not paused_at.startswith(f"frame {last} /")
    finally:
        server.stop()


def test_recording_that_cannot_open_shows_a_message(tmp_path: Path, page: Page) -> None:
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "recording.yaml").write_text("this: [is not a manifest\n")
    with pytest.raises(RecordingError) as err:
        Drive(tmp_path / "broken")
    server = start(tmp_path)
    try:
        page.goto(f"http://127.0.0.1:{server.port}/")
        page.get_by_text("Cannot show this recording").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text(str(err.value).splitlines()[0][-30:]).wait_for(timeout=TIMEOUT_MS)
        assert page.locator(CAMERA_IMG).count() == 0
        assert page.get_by_text("Traceback").count() == 0
        page.screenshot(path=str(ERROR_SCREENSHOT))
    finally:
        server.stop()


def test_frame_that_cannot_be_read_is_reported_in_the_readout(tmp_path: Path, page: Page) -> None:
    class DamagedDrive(FakeDrive):
        def frame(self, index: int) -> FrameInput:
            if index == 1:
                raise RecordingError("bag: frame 1 image is not a PNG")
            return super().frame(index)

    (tmp_path / "damaged").mkdir()
    (tmp_path / "damaged" / "recording.yaml").write_text("{}\n")
    server = start(tmp_path, None, lambda path: DamagedDrive(frames=5, name=path.name))
    try:
        page.goto(f"http://127.0.0.1:{server.port}/")
        camera_src(page)
        page.get_by_role("button", name="Step +1").click()
        page.get_by_text("frame 1 cannot be read").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("image is not a PNG").wait_for(timeout=TIMEOUT_MS)
        page.get_by_role("button", name="Step +1").click()
        page.get_by_text("frame 2 /").wait_for(timeout=TIMEOUT_MS)
    finally:
        server.stop()


def test_assumptions_and_reading_warnings_are_listed_under_the_name(
    tmp_path: Path, page: Page
) -> None:
    def noted(path: Path) -> FakeDrive:
        drive = FakeDrive(frames=3, name=path.name)
        drive.notes = (
            "speed 27 m/s is assumed, not measured",
            "can.log: skipped 3 lines that are not frames",
        )
        return drive

    (tmp_path / "noted").mkdir()
    (tmp_path / "noted" / "recording.yaml").write_text("{}\n")
    server = start(tmp_path, None, noted)
    try:
        page.goto(f"http://127.0.0.1:{server.port}/")
        camera_src(page)
        page.get_by_text("speed 27 m/s is assumed, not measured").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("skipped 3 lines that are not frames").wait_for(timeout=TIMEOUT_MS)
    finally:
        server.stop()


def test_keys_step_the_frame_and_the_keys_panel_lists_them(
    recordings: Recordings, page: Page
) -> None:
    server = start(recordings.root, recordings.name)
    try:
        page.goto(f"http://127.0.0.1:{server.port}/")
        camera_src(page)
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        page.locator("body").click(position={"x": 700, "y": 700})  # focus off the controls
        page.keyboard.press("ArrowRight")
        page.get_by_text("frame 1 /").wait_for(timeout=TIMEOUT_MS)
        page.keyboard.press("ArrowLeft")
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("Keys").click()
        page.get_by_text("Toggle layer: search areas").wait_for(timeout=TIMEOUT_MS)
    finally:
        server.stop()
