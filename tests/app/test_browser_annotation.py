"""Annotating in headless Chromium, on the Udacity vehicles video as `fusionscope import`
makes it: draw a box by dragging on the frame, change its class, leave the frame and come
back, undo and redo, reload the page; two tabs editing one box, the second is refused.
Fixtures in conftest.py, helpers in browser_page.py."""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from app_fakes import Recordings
from browser_page import TIMEOUT_MS, camera_src, serving, set_field
from playwright.sync_api import Browser, Page

from core.annotation.formats import import_annotations
from core.cli import DEFAULT_RECORDINGS, main

NAME = "cars"
FOLDER_OPEN_MS = 600  # longer than a folder's unfolding animation
SETTLE_MS = 1_500  # a drag's edit saved and the plane's picture replaced
YELLOW_MIN = 180  # a selected box is drawn yellow: R and G at least this, B below BLUE_MAX
BLUE_MAX = 110
DRAG_PX = (-60, -20, 40, 30)  # from (x0, y0) to (x1, y1), relative to the 3D view's centre
# a drag from well inside the box DRAG_PX draws (from its corner, a pixel's difference in how
# a tab's camera is aimed decides between moving that box and drawing a new one)
MOVE_PX = (-10, 5, 10, 15)


@pytest.fixture(scope="module")
def cars(realdata: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A recordings root holding the Udacity vehicles video imported at 25 frames/s."""
    root = tmp_path_factory.mktemp("annotate")
    video = realdata / "udacity-highway" / "vehicles_1280x720.mp4"
    args = ["import", "video", str(video), str(root / NAME), "--fps", "25"]
    args += ["--fx", "579", "--cx", "320", "--cy", "180", "--camera-height-m", "1.3"]
    args += ["--assume-speed-mps", "26"]
    assert main(args) == 0
    return root


def saved(root: Path) -> dict:  # type: ignore[type-arg]
    return json.loads((root / NAME / "groundtruth.json").read_text())


def annotate(page: Page) -> None:
    """Open the Annotation folder and switch annotation mode on."""
    camera_src(page)
    page.get_by_text("Annotation", exact=True).click()
    page.wait_for_timeout(FOLDER_OPEN_MS)
    page.get_by_label("annotate", exact=True).check()
    page.get_by_text("tracks, revision").wait_for(timeout=TIMEOUT_MS)
    page.wait_for_timeout(SETTLE_MS)


def view_centre(page: Page) -> tuple[float, float]:
    box = page.locator("canvas").nth(1).bounding_box()
    assert box is not None
    return box["x"] + box["width"] / 2, box["y"] + box["height"] / 2


def drag(page: Page, drag_px: tuple[int, int, int, int] = DRAG_PX) -> None:
    x, y = view_centre(page)
    dx0, dy0, dx1, dy1 = drag_px
    page.mouse.move(x + dx0, y + dy0)
    page.mouse.down()
    page.mouse.move(x + (dx0 + dx1) / 2, y + (dy0 + dy1) / 2, steps=5)
    page.mouse.move(x + dx1, y + dy1, steps=5)
    page.mouse.up()
    page.wait_for_timeout(SETTLE_MS)


def yellow_outline_seen(page: Page) -> bool:
    """Does the 3D view show yellow (the selected box) along the dragged rectangle's top?"""
    x, y = view_centre(page)
    dx0, dy0, dx1, _ = DRAG_PX
    shot = page.screenshot(clip={"x": x + dx0, "y": y + dy0 - 4, "width": dx1 - dx0, "height": 8})
    import cv2  # decoding the screenshot

    bgr = cv2.imdecode(np.frombuffer(shot, np.uint8), cv2.IMREAD_COLOR)
    b, g, r = bgr[..., 0], bgr[..., 1], bgr[..., 2]
    yellow = (r >= YELLOW_MIN) & (g >= YELLOW_MIN) & (b < BLUE_MAX)
    return bool(yellow.sum() >= (dx1 - dx0) // 2)


def test_draw_a_box_change_it_leave_and_come_back_undo_redo_reload(cars: Path, page: Page) -> None:
    with serving(page, cars, NAME):
        annotate(page)
        drag(page)
        (track,) = saved(cars)["tracks"]
        assert track["class"] == "car" and [k["frame"] for k in track["keyframes"]] == [0]
        u0, v0, u1, v1 = track["keyframes"][0]["box_px"]
        assert 0 < u0 < u1 < 640 and 0 < v0 < v1 < 360  # about 100 x 50 px in the frame
        assert yellow_outline_seen(page)

        choice = page.get_by_label("class", exact=True)
        choice.click()
        page.get_by_role("option", name="truck", exact=True).click()
        page.wait_for_timeout(SETTLE_MS)
        assert saved(cars)["tracks"][0]["class"] == "truck"

        set_field(page, "go to time s", "0.2")  # 25 frames/s
        page.get_by_text("frame 5 /").wait_for(timeout=TIMEOUT_MS)
        set_field(page, "go to time s", "0")
        page.get_by_text("frame 0 /").wait_for(timeout=TIMEOUT_MS)
        page.wait_for_timeout(SETTLE_MS)
        assert yellow_outline_seen(page)  # the box is there again

        page.get_by_text("38 frames at").click()  # the keys go to the page, not a field
        page.keyboard.press("Control+z")  # the class back to car
        page.wait_for_timeout(SETTLE_MS)
        assert saved(cars)["tracks"][0]["class"] == "car"
        page.keyboard.press("Control+z")  # the box gone
        page.wait_for_timeout(SETTLE_MS)
        assert saved(cars)["tracks"] == []
        page.keyboard.press("Control+Shift+z")  # and back
        page.wait_for_timeout(SETTLE_MS)
        assert len(saved(cars)["tracks"]) == 1

        page.reload()
        annotate(page)
        page.get_by_text("1 tracks, revision").wait_for(timeout=TIMEOUT_MS)


def test_two_tabs_editing_one_box_the_second_is_refused(cars: Path, browser: Browser) -> None:
    first = browser.new_context(viewport={"width": 1400, "height": 800}).new_page()
    second = browser.new_context(viewport={"width": 1400, "height": 800}).new_page()
    with serving(first, cars, NAME) as server:
        second.goto(f"http://127.0.0.1:{server.port}/")
        annotate(first)
        annotate(second)
        # the second tab's frame rendered for annotation has reached it: a render arriving
        # after the first tab's edit would show the second tab that edit, and its drag would
        # rightly not be refused (a seek away and back renders the frame again)
        for seconds, frame in (("0.04", 1), ("0", 0)):  # 25 frames/s
            set_field(second, "go to time s", seconds)
            second.get_by_text(f"frame {frame} /").wait_for(timeout=TIMEOUT_MS)
        second.wait_for_timeout(SETTLE_MS)
        drag(first, MOVE_PX)  # moves the box the test before left there
        after_first = saved(cars)
        # the second tab still shows the box as it was: its drag moves that, and is refused
        drag(second, MOVE_PX)
        second.get_by_text("Not saved: another tab changed this").wait_for(timeout=TIMEOUT_MS)
        assert saved(cars) == after_first
    first.context.close()
    second.context.close()


@pytest.fixture(scope="module")
def unannotated(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A recordings root with the bundled exurban drive (radar, tracked cars) without its
    generated truth, so that it can be annotated."""
    root = tmp_path_factory.mktemp("unannotated")
    shutil.copytree(DEFAULT_RECORDINGS / "exurban", root / "exurban")
    (root / "exurban" / "groundtruth.json").unlink()
    manifest = root / "exurban" / "recording.yaml"
    lines = manifest.read_text().splitlines()
    manifest.write_text("\n".join(x for x in lines if not x.startswith("groundtruth:")) + "\n")
    return root


def test_accept_an_engine_track_download_and_import_a_file(
    unannotated: Path, page: Page, tmp_path: Path
) -> None:
    recording = unannotated / "exurban"
    with serving(page, unannotated, "exurban"):
        annotate(page)
        set_field(page, "go to time s", "5.5")  # frame 55: a car tracked since frame 42
        page.get_by_text("frame 55 /").wait_for(timeout=TIMEOUT_MS)
        page.wait_for_timeout(SETTLE_MS)
        choice = page.get_by_label("engine track", exact=True)
        choice.click()
        page.get_by_role("option", name=re.compile(r"^vehicle #\d+$")).first.click()
        set_field(page, "frames", "45-75")
        page.get_by_role("button", name="Accept it over the frames").click()
        page.get_by_text("Track accepted").wait_for(timeout=TIMEOUT_MS)
        (track,) = json.loads((recording / "groundtruth.json").read_text())["tracks"]
        assert track["class"] == "car" and 2 <= len(track["keyframes"]) < 31

        with page.expect_download(timeout=TIMEOUT_MS) as download:
            page.get_by_role("button", name="Download the annotations").click()
        exported = tmp_path / download.value.suggested_filename
        download.value.save_as(exported)
        assert exported.name == "exurban-annotations.xml"  # cvat, the default format
        assert (
            import_annotations(exported, "cvat").tracks[0].keyframes[0].frame
            == (track["keyframes"][0]["frame"])
        )

        bad = tmp_path / "broken.xml"
        bad.write_text("<annotations><track")
        page.locator("input[type=file]").set_input_files(str(bad))
        page.get_by_text("broken.xml not imported").wait_for(timeout=TIMEOUT_MS)
        page.locator("input[type=file]").set_input_files(str(exported))
        page.get_by_text("exurban-annotations.xml imported").wait_for(timeout=TIMEOUT_MS)
        assert len(json.loads((recording / "groundtruth.json").read_text())["tracks"]) == 1
        page.get_by_label("detection", exact=True).click()
        page.get_by_role("option", name=re.compile(r"^vehicle 1 at u \d+$")).click()
        page.get_by_role("button", name="This detection").click()
        page.wait_for_timeout(SETTLE_MS)
        tracks = json.loads((recording / "groundtruth.json").read_text())["tracks"]
        assert len(tracks) == 2 and [k["frame"] for k in tracks[1]["keyframes"]] == [55]


def test_a_file_over_the_upload_limit_is_refused_and_the_annotations_stay(
    unannotated: Path, page: Page
) -> None:
    limit_bytes = 2_000
    truth = unannotated / "exurban" / "groundtruth.json"
    before = truth.read_bytes() if truth.exists() else None  # earlier tests may annotate
    with serving(page, unannotated, "exurban", max_upload_bytes=limit_bytes):
        annotate(page)
        big = {"name": "big.xml", "mimeType": "text/xml", "buffer": b"<annotations/>" * 300}
        page.locator("input[type=file]").set_input_files(big)  # type: ignore[arg-type]
        page.get_by_text("Upload refused").wait_for(timeout=TIMEOUT_MS)
        assert page.get_by_text(
            "big.xml: 4,200 bytes is over the 2,000 bytes a file uploaded to the inspector may have"
        ).is_visible()
        page.wait_for_timeout(SETTLE_MS)
        assert page.get_by_text("big.xml not imported").count() == 0  # never reached the import
        assert (truth.read_bytes() if truth.exists() else None) == before


def test_a_generated_truth_opens_read_only_with_its_reason(
    recordings: Recordings, page: Page
) -> None:
    truth = recordings.root / recordings.name / "groundtruth.json"
    before = truth.read_bytes()
    with serving(page, recordings.root, recordings.name):
        camera_src(page)
        page.get_by_text("Annotation", exact=True).click()
        page.wait_for_timeout(FOLDER_OPEN_MS)
        page.get_by_label("annotate", exact=True).check()
        page.get_by_text("Read-only:").wait_for(timeout=TIMEOUT_MS)
        page.get_by_text("format_version 1").first.wait_for(timeout=TIMEOUT_MS)
        assert page.get_by_role("button", name="Accept it over the frames").is_disabled()
        assert page.get_by_role("button", name="Download the annotations").is_enabled()
    assert truth.read_bytes() == before
