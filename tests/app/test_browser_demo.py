"""Demo mode in headless Chromium: the presenter view has no controls and plays its clip over
and over beside a full inspector tab; a shared link opened in a new browser context shows the
same frame with the same layers and parameters; a tab presents its view and comes back to it;
the link is copied. Fixtures in conftest.py, helpers in browser_page.py."""

from __future__ import annotations

import contextlib
import re
from pathlib import Path

import cv2
from app_fakes import Recordings
from browser_page import (
    CAMERA_IMG,
    DIGEST_JS,
    SCREENSHOTS,
    SETTLE_MS,
    TIMEOUT_MS,
    camera_src,
    changed_pixels,
    field,
    pixels,
    serving,
    set_field,
)
from playwright.sync_api import Browser, Locator, Page, expect
from playwright.sync_api import Error as PlaywrightError
from test_browser_tuning import XI, open_folders

from app.draw import STRIP_HEIGHT_PX
from app.presenter import PICTURE_WIDTH_PX
from app.presenter_view import FIGURES_HEIGHT_PX
from core.io.drive import Drive

READOUT = re.compile(r"^frame \d+ / \d+ \|")
READ_INTERVALS_MS = (120, 170, 230)  # between reads of a playing picture: no common period


def presenter_camera(page: Page) -> Locator:
    """The presenter's camera picture: the widest picture (the legend is one too)."""
    page.wait_for_function(
        f'() => Array.from(document.querySelectorAll("{CAMERA_IMG}"))'
        ".filter(i => i.complete && i.naturalWidth > 640).length === 1",
        timeout=TIMEOUT_MS,
    )
    widths = page.locator(CAMERA_IMG).evaluate_all("images => images.map(i => i.naturalWidth)")
    return page.locator(CAMERA_IMG).nth(widths.index(max(widths)))


def playing_pixels(camera: Locator, wait_ms: int = 150) -> str:
    """A digest of the next picture that can be read whole, `wait_ms` from now (the page
    replaces the picture ten times a second, and a read can catch its blob being revoked),
    under the figures (the engine's time on a frame differs each time it is played)."""
    for _ in range(50):
        with contextlib.suppress(PlaywrightError):
            camera.page.wait_for_timeout(wait_ms)
            return str(camera.evaluate(DIGEST_JS, FIGURES_HEIGHT_PX))
    raise AssertionError(f"{camera}: no picture could be read in 50 tries")


def no_controls(page: Page) -> None:
    """The page shows no input of any kind (viser keeps hidden ones for its own settings)
    and has no parameter, layer, annotation or timeline folder."""
    visible = page.locator("input:visible")
    with contextlib.suppress(AssertionError):  # the inspector's page is emptied, then refilled
        expect(visible).to_have_count(0, timeout=TIMEOUT_MS)
    described = visible.evaluate_all(
        "inputs => inputs.map(i => [i.type, i.getAttribute('aria-label'), i.value])"
    )
    assert described == []
    for folder in ("Parameters", "Layers", "Annotation", "Timeline"):
        assert page.get_by_text(folder, exact=True).count() == 0, folder


def test_the_presenter_has_no_controls_and_plays_its_clip_over_and_over(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name, present=True, query="?clip=3-5"):
        page.get_by_text("frames 3–5 of 20").wait_for(timeout=TIMEOUT_MS)
        camera = presenter_camera(page)
        no_controls(page)
        # the clip's three frames, over and over: read at uneven intervals (reads 150 ms
        # apart can fall on the same two of the three 100 ms frames each loop), at least
        # twelve times and until all three were seen
        seen: set[str] = set()
        for k in range(40):
            seen.add(playing_pixels(camera, READ_INTERVALS_MS[k % len(READ_INTERVALS_MS)]))
            if k >= 11 and len(seen) >= 3:
                break
        assert len(seen) == 3
        assert "present=1" in page.url and "clip=3-5" in page.url
        # the figures are drawn over the camera picture, in the same image, not beside it
        assert page.get_by_text("to process this frame").count() == 0
        with Drive(recordings.root / recordings.name) as drive:
            size = drive.camera.intrinsics
        drawn_px = (size.width_px, size.height_px + STRIP_HEIGHT_PX)
        scaled_h = round(drawn_px[1] * PICTURE_WIDTH_PX / drawn_px[0])
        natural = camera.evaluate("i => [i.naturalWidth, i.naturalHeight]")
        assert natural == [PICTURE_WIDTH_PX, FIGURES_HEIGHT_PX + scaled_h]
        assert page.get_by_role("button", name="Back to the inspector").count() == 0


def test_a_full_inspector_tab_works_beside_a_presenter_tab(
    recordings: Recordings, page: Page, browser: Browser
) -> None:
    with serving(page, recordings.root, recordings.name, query="?present=1"):
        camera = presenter_camera(page)
        no_controls(page)
        other = page.context.new_page()
        other.goto(page.url.split("?")[0])
        camera_src(other)
        other.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        other.get_by_role("button", name="Step +1").click()
        other.get_by_text("frame 1 /").wait_for(timeout=TIMEOUT_MS)
        changed_pixels(page, camera, pixels(camera))  # the presenter still plays


def test_a_shared_link_shows_the_same_view_in_a_new_browser_context(
    recordings: Recordings, page: Page, browser: Browser
) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        set_field(page, "go to time s", "1.2")
        page.get_by_text("frame 12 /").wait_for(timeout=TIMEOUT_MS)
        page.get_by_label("radar", exact=True).click()
        open_folders(page, "Parameters", "motion_stereo")
        set_field(page, XI, "80")
        page.wait_for_url(re.compile(r"a\.motion_stereo\.threshold_xi=80"), timeout=TIMEOUT_MS)
        page.wait_for_timeout(SETTLE_MS)  # the exact picture after the preview
        shown = pixels(page.locator(CAMERA_IMG).first)  # the stage picture under the camera
        url = page.url
        assert "frame=12" in url and "layers=areas" not in url and "radar" not in url

        context = browser.new_context(viewport={"width": 1400, "height": 800})
        try:
            other = context.new_page()
            other.goto(url)
            camera_src(other)
            other.get_by_text("frame 12 /").wait_for(timeout=TIMEOUT_MS)
            other.wait_for_timeout(SETTLE_MS)
            again = pixels(other.locator(CAMERA_IMG).first)
            assert again == shown
            assert not other.get_by_label("radar", exact=True).is_checked()
            open_folders(other, "Parameters", "motion_stereo")
            assert field(other, XI).input_value() == "80"
            other.screenshot(path=str(SCREENSHOTS / "shared-link-opened.png"))
        finally:
            context.close()


def test_a_tab_presents_its_view_and_comes_back_to_it(recordings: Recordings, page: Page) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        page.get_by_label("radar", exact=True).click()
        open_folders(page, "Share and demo")
        set_field(page, "clip frames", "4-9")
        page.get_by_role("button", name="Present this view").click()
        page.get_by_role("button", name="Back to the inspector").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("frames 4–9 of 20").wait_for(timeout=TIMEOUT_MS)
        no_controls(page)
        page.wait_for_url(re.compile(r"present=1"), timeout=TIMEOUT_MS)

        page.get_by_role("button", name="Back to the inspector").click()
        page.get_by_text(READOUT).wait_for(timeout=TIMEOUT_MS)
        frame = int(page.get_by_text(READOUT).inner_text().split()[1])
        assert 4 <= frame <= 9  # where the presenter was, in the clip
        assert not page.get_by_label("radar", exact=True).is_checked()
        assert "present=1" not in page.url


def test_copy_link_puts_the_views_url_on_the_clipboard(recordings: Recordings, page: Page) -> None:
    page.context.grant_permissions(["clipboard-read", "clipboard-write"])
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        page.get_by_role("button", name="Step +1").click()
        page.get_by_text("frame 1 /").wait_for(timeout=TIMEOUT_MS)
        open_folders(page, "Share and demo")
        page.get_by_role("button", name="Copy link").click()
        page.get_by_text("Copied:").wait_for(timeout=TIMEOUT_MS)
        copied = page.evaluate("navigator.clipboard.readText()")
        assert copied == page.url and "frame=1" in copied


def test_a_link_with_parts_that_cannot_be_used_says_so_and_shows_the_rest(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name, query="?frame=5&layers=lasers"):
        page.get_by_text("frame 5 /").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("Parts of the link were left out").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text(re.compile("layers: expected layer names")).wait_for(timeout=TIMEOUT_MS)


def test_the_clip_is_exported_from_the_page_as_a_video_and_a_3d_scene(
    recordings: Recordings, page: Page, tmp_path: Path
) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        open_folders(page, "Share and demo")
        set_field(page, "clip frames", "2-5")
        with page.expect_download(timeout=TIMEOUT_MS) as video:
            page.get_by_role("button", name="Export video (MP4)").click()
        saved = tmp_path / video.value.suggested_filename
        video.value.save_as(saved)
        assert saved.name == f"{recordings.name}-2-5.mp4"
        capture = cv2.VideoCapture(str(saved))
        try:
            assert int(capture.get(cv2.CAP_PROP_FRAME_COUNT)) == 4
        finally:
            capture.release()
        with page.expect_download(timeout=TIMEOUT_MS) as scene:
            page.get_by_role("button", name="Export 3D scene (HTML)").click()
        html = Path(scene.value.path()).read_text(encoding="utf-8")
        assert scene.value.suggested_filename.endswith(".html")
        assert "window.__VISER_EMBED_DATA__" in html
