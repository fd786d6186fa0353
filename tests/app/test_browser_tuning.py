"""Tuning in headless Chromium: a threshold changes the binarised image, a layer toggles,
presets and undo bring values back, A/B shows both sides and what differs, a recording that
cannot be opened leaves the page working. Fixtures in conftest.py, helpers in browser_page.py.
"""

from __future__ import annotations

from pathlib import Path

from app_fakes import Recordings
from browser_page import (
    CAMERA_IMG,
    TIMEOUT_MS,
    camera_src,
    changed_pixels,
    field,
    pixels,
    serving,
    set_field,
    shows_pixels,
    stage_top_px,
)
from playwright.sync_api import Page, expect

from app.metrics import error_marks
from app.view import AB_GAP_PX
from core.evaluation.evaluate import evaluate_recording
from core.params import Params

FOLDER_OPEN_MS = 600  # longer than a folder's unfolding animation
XI = "threshold_xi"  # motion stereo's binarisation threshold (grey levels)


def open_folders(page: Page, *names: str) -> None:
    """Open GUI folders in turn, each after the one before has finished unfolding (a click
    on a title that is still moving can miss it)."""
    for name in names:
        page.get_by_text(name, exact=True).first.click()
        page.wait_for_timeout(FOLDER_OPEN_MS)


def test_a_threshold_changes_the_binarised_image(recordings: Recordings, page: Page) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        picture, top_px = (
            page.locator(CAMERA_IMG).first,
            stage_top_px(recordings.root / recordings.name),
        )
        first = pixels(picture, top_px)
        set_field(page, "go to time s", "1.0")  # motion stereo needs frames before it
        page.get_by_text("frame 10 /").wait_for(timeout=TIMEOUT_MS)
        # the read-out can name the frame before its picture is shown (a loaded machine)
        before = changed_pixels(page, picture, first, top_px)
        open_folders(page, "Parameters", "motion_stereo")
        set_field(page, XI, "80")
        changed_pixels(page, picture, before, top_px)  # the threshold changes the picture
        set_field(page, XI, "20")  # the paper's value again: the first picture again
        assert shows_pixels(page, picture, before, top_px)


def test_a_layer_toggled_off_and_on_changes_the_picture_and_back(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        camera = page.locator(CAMERA_IMG).first
        before = pixels(camera)
        page.get_by_label("radar", exact=True).click()
        without_radar = changed_pixels(page, camera, before)
        page.get_by_label("radar", exact=True).click()
        assert changed_pixels(page, camera, without_radar) == before


def test_a_saved_preset_brings_a_value_back_and_undo_too(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name) as server:
        camera_src(page)
        open_folders(page, "Parameters", "Presets", "motion_stereo")
        set_field(page, XI, "33")
        set_field(page, "name", "my-preset")
        page.get_by_role("button", name="Save the edited set").click()
        page.get_by_text("Preset saved").wait_for(timeout=TIMEOUT_MS)
        assert (server.presets.folder / "my-preset.yaml").is_file()
        set_field(page, XI, "44")
        expect(field(page, XI)).to_have_value("44")
        page.get_by_role("button", name="Load into the edited set").click()
        expect(field(page, XI)).to_have_value("33", timeout=TIMEOUT_MS)
        page.get_by_role("button", name="Undo").click()  # undoes the load
        expect(field(page, XI)).to_have_value("44", timeout=TIMEOUT_MS)
        page.get_by_role("button", name="Redo").click()
        expect(field(page, XI)).to_have_value("33", timeout=TIMEOUT_MS)
        set_field(page, "name", "../outside")
        page.get_by_role("button", name="Save the edited set").click()
        page.get_by_text("preset name: refused").wait_for(timeout=TIMEOUT_MS)
        assert sorted(p.name for p in server.presets.folder.iterdir()) == ["my-preset.yaml"]


def test_a_refused_value_is_said_in_the_page_and_the_field_goes_back(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        open_folders(page, "Parameters", "motion_stereo")
        set_field(page, XI, "-5")
        page.get_by_text("motion_stereo.threshold_xi: refused").wait_for(timeout=TIMEOUT_MS)
        expect(field(page, XI)).to_have_value("20", timeout=TIMEOUT_MS)


def test_comparing_shows_a_and_b_side_by_side_and_what_differs(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        width = page.locator(CAMERA_IMG).first.evaluate("i => i.naturalWidth")
        open_folders(page, "Parameters")
        page.get_by_label("compare with B", exact=True).click()
        page.wait_for_function(
            f'w => document.querySelector("{CAMERA_IMG}").naturalWidth === w',
            arg=2 * width + AB_GAP_PX,
            timeout=TIMEOUT_MS,
        )
        page.get_by_text("A has, B lacks").wait_for(timeout=TIMEOUT_MS)
        # B keeps no vehicle narrower than 2.9 m: A's vehicles are listed as A's alone
        page.get_by_label("fields edit", exact=True).click()
        page.get_by_role("option", name="B").click()
        open_folders(page, "vehicle")
        set_field(page, "min_width_m", "2.9")
        page.get_by_text("vehicle at").first.wait_for(timeout=TIMEOUT_MS)
        assert page.get_by_text("B has, A lacks").is_visible()


def test_a_recording_that_cannot_open_leaves_the_page_working(
    recordings: Recordings, tmp_path: Path, page: Page
) -> None:
    root = tmp_path / "root"
    root.mkdir()
    (root / "aa-broken").mkdir()
    (root / "aa-broken" / "recording.yaml").write_text("this: [is not a manifest\n")
    (root / "highway").symlink_to(recordings.root / recordings.name)
    with serving(page, root):  # the first by name: the broken one
        page.get_by_text("Cannot show this recording: aa-broken").wait_for(timeout=TIMEOUT_MS)
        page.get_by_label("recording", exact=True).click()
        page.get_by_role("option", name="highway").click()
        camera_src(page)
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        assert page.get_by_text("Traceback").count() == 0


def test_the_metrics_mark_errors_on_the_timeline_and_jump_there(
    recordings: Recordings, page: Page
) -> None:
    with serving(page, recordings.root, recordings.name) as server:
        camera_src(page)
        open_folders(page, "Metrics")
        page.get_by_role("button", name="Evaluate the drive under A").click()
        page.get_by_text("Vehicles, frame by frame").wait_for(timeout=TIMEOUT_MS)
        report = evaluate_recording(
            server.recordings_root / recordings.name, Params(), timing=False
        )
        marks = error_marks(report, ("vehicle FN",))
        later = [m.frame for m in marks if m.frame > 0]
        assert later, "the synthetic drive should have a vehicle FN after frame 0 to jump to"
        page.get_by_role("button", name="Next").click()
        page.get_by_text(f"frame {later[0]} /").wait_for(timeout=TIMEOUT_MS)
        page.get_by_label("jump to", exact=True).click()
        page.get_by_role("option", name=marks[-1].text).click()
        page.get_by_text(f"frame {marks[-1].frame} /").wait_for(timeout=TIMEOUT_MS)
