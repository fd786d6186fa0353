"""The inspector in headless Chromium: the camera image shows, stepping shows the next frame,
play and pause, errors in the page, keys. Fixtures in conftest.py, helpers in browser_page.py.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from app_fakes import FakeDrive, Recordings
from browser_page import CAMERA_IMG, SETTLE_MS, TIMEOUT_MS, camera_src, field, serving
from playwright.sync_api import Page

from core.io import Drive, FrameInput
from core.io.errors import RecordingError


def test_step_shows_the_next_frame(recordings: Recordings, page: Page) -> None:
    with serving(page, recordings.root, recordings.name):
        first = camera_src(page)
        size = page.locator(CAMERA_IMG).first.evaluate("i => [i.naturalWidth, i.naturalHeight]")
        assert size[0] == 640 and size[1] > 480  # the frame plus its caption strip
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)

        page.get_by_role("button", name="Step +1").click()
        page.get_by_text("frame 1 /").wait_for(timeout=TIMEOUT_MS)
        page.wait_for_function(
            f'src => document.querySelector("{CAMERA_IMG}")?.src !== src',
            arg=first,
            timeout=TIMEOUT_MS,
        )
        assert camera_src(page) != first


def test_play_runs_to_the_end_and_pause_stops(recordings: Recordings, page: Page) -> None:
    with Drive(recordings.root / recordings.name) as drive:
        last = len(drive) - 1
    with serving(page, recordings.root, recordings.name):
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
        # while playing, the slider followed at most 5 times a second; paused, it is exact
        assert paused_at.startswith(f"frame {field(page, 'frame').input_value()} /")


def test_recording_that_cannot_open_shows_a_message(tmp_path: Path, page: Page) -> None:
    (tmp_path / "broken").mkdir()
    (tmp_path / "broken" / "recording.yaml").write_text("this: [is not a manifest\n")
    with pytest.raises(RecordingError) as err:
        Drive(tmp_path / "broken")
    with serving(page, tmp_path):
        page.get_by_text("Cannot show this recording").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text(str(err.value).splitlines()[0][-30:]).wait_for(timeout=TIMEOUT_MS)
        assert page.locator(CAMERA_IMG).count() == 0
        assert page.get_by_text("Traceback").count() == 0


def test_frame_that_cannot_be_read_is_reported_in_the_readout(tmp_path: Path, page: Page) -> None:
    class DamagedDrive(FakeDrive):
        def frame(self, index: int) -> FrameInput:
            if index == 1:
                raise RecordingError("bag: frame 1 image is not a PNG")
            return super().frame(index)

    (tmp_path / "damaged").mkdir()
    (tmp_path / "damaged" / "recording.yaml").write_text("{}\n")
    with serving(page, tmp_path, None, lambda path: DamagedDrive(frames=5, name=path.name)):
        camera_src(page)
        page.get_by_role("button", name="Step +1").click()
        page.get_by_text("frame 1 cannot be read").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("image is not a PNG").wait_for(timeout=TIMEOUT_MS)
        page.get_by_role("button", name="Step +1").click()
        page.get_by_text("frame 2 /").wait_for(timeout=TIMEOUT_MS)


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
    with serving(page, tmp_path, None, noted):
        camera_src(page)
        page.get_by_text("speed 27 m/s is assumed, not measured").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("skipped 3 lines that are not frames").wait_for(timeout=TIMEOUT_MS)


def test_keys_step_the_frame_and_the_keys_panel_lists_them(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        page.locator("body").click(position={"x": 700, "y": 700})  # focus off the controls
        page.keyboard.press("ArrowRight")
        page.get_by_text("frame 1 /").wait_for(timeout=TIMEOUT_MS)
        page.keyboard.press("ArrowLeft")
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("Keys").click()
        page.get_by_text("Toggle layer: search areas").wait_for(timeout=TIMEOUT_MS)
