"""Driving the inspector in headless Debian Chromium: the browser and page fixtures live in
conftest.py; these are the helpers the browser tests share.

Needs Debian's chromium at /usr/bin/chromium (Playwright's own browser download is never
used). Without it the tests skip, except when CI or REQUIRE_BROWSER is set, where they fail.
"""

from __future__ import annotations

import contextlib
import importlib.util
import os
import shutil
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

from playwright.sync_api import Error as PlaywrightError
from playwright.sync_api import Locator, Page

from app.draw import STRIP_HEIGHT_PX
from app.server import DriveOpener, InspectorServer, open_drive
from app.upload_limit import DEFAULT_MAX_UPLOAD_BYTES
from app.view import PREVIEW_NOTE, SETTLING_NOTE, STAGE_GAP_PX
from core.io.drive import Drive

SCRIPTS = Path(__file__).resolve().parents[2] / "scripts"


def load_script(name: str) -> ModuleType:
    """scripts/NAME.py as a module (a script, not a package module)."""
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


# Chromium as the benchmark runs it: Debian's, headless, without a GPU or background traffic
_BENCH = load_script("bench_inspector")
CHROMIUM: Path = _BENCH.CHROMIUM
CHROMIUM_ARGS: list[str] = _BENCH.CHROMIUM_ARGS
SCREENSHOTS = Path(tempfile.gettempdir()) / "fusionscope-browser-tests"
TIMEOUT_MS = 30_000
PIXEL_READS = 5  # tries to read a picture the page may be replacing
SETTLE_MS = 1_000  # longer than a seek's replay and render

# The camera image: the first <img> viser fills from a blob with a rendered picture.
CAMERA_IMG = "img[src^='blob:']"
# The rendered pictures on screen: the camera, then the stage picture under it.
VISIBLE_IMG = "img[src^='blob:']:visible"


def start(
    root: Path,
    recording: str | None = None,
    opener: DriveOpener = open_drive,
    present: bool = False,
    max_upload_bytes: int = DEFAULT_MAX_UPLOAD_BYTES,
) -> InspectorServer:
    presets = Path(tempfile.mkdtemp(prefix="fusionscope-presets-"))
    server = InspectorServer(
        root,
        recording,
        "127.0.0.1",
        0,
        open_drive=opener,
        presets=presets,
        present=present,
        max_upload_bytes=max_upload_bytes,
    )
    server.start()
    return server


@contextlib.contextmanager
def serving(
    page: Page,
    root: Path,
    recording: str | None = None,
    opener: DriveOpener = open_drive,
    *,
    present: bool = False,
    query: str = "",
    max_upload_bytes: int = DEFAULT_MAX_UPLOAD_BYTES,
) -> Iterator[InspectorServer]:
    """An inspector on `root` (`present`: a presenter-only one), opened in `page` at the URL
    query `query`; on leaving, the page is saved to SCREENSHOTS/<test>.png while the server
    still runs, then the server stops."""
    server = start(root, recording, opener, present, max_upload_bytes)
    try:
        page.goto(f"http://127.0.0.1:{server.port}/{query}")
        yield server
    finally:
        test = os.environ.get("PYTEST_CURRENT_TEST", "page").split("::")[-1].split(" ")[0]
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        with contextlib.suppress(Exception):  # a page that is gone must not hide the failure
            page.screenshot(path=str(SCREENSHOTS / f"{test}.png"))
        server.stop()
        shutil.rmtree(server.presets.folder, ignore_errors=True)


def camera_src(page: Page) -> str:
    page.wait_for_function(
        f'() => {{ const i = document.querySelector("{CAMERA_IMG}");'
        " return i !== null && i.complete && i.naturalWidth > 0; }",
        timeout=TIMEOUT_MS,
    )
    return page.locator(CAMERA_IMG).first.get_attribute("src") or ""


def pixels(image: Locator, top_px: int = 0) -> str:
    """A digest of the decoded pixels of an <img> from row `top_px` down, to tell pictures
    apart (not their URLs). A picture the page replaces while it is read (its blob URL
    revoked mid-decode) is read again."""
    for _ in range(PIXEL_READS - 1):
        with contextlib.suppress(PlaywrightError):
            return _digest(image, top_px)
        image.page.wait_for_timeout(100)
    return _digest(image, top_px)


DIGEST_JS = """async (i, top) => { await i.decode(); const c = document.createElement('canvas');
    c.width = i.naturalWidth; c.height = i.naturalHeight;
    const g = c.getContext('2d'); g.drawImage(i, 0, 0);
    const d = g.getImageData(0, top, c.width, c.height - top).data;
    let h = 0; for (let k = 0; k < d.length; k += 7) h = (h * 31 + d[k]) >>> 0;
    return `${c.width}x${c.height}:${h}`; }"""


def _digest(image: Locator, top_px: int) -> str:
    return str(image.evaluate(DIGEST_JS, top_px))


def stage_top_px(drive_path: Path) -> int:
    """The first row of the stage picture in the camera panel's picture (`pixels`' top_px):
    under the camera picture of the drive at `drive_path`, its caption and the gap
    (`app.view.stage_under`)."""
    with Drive(drive_path) as drive:
        height_px = drive.camera.intrinsics.height_px
    return height_px + STRIP_HEIGHT_PX + STAGE_GAP_PX


def _provisional(page: Page) -> Locator:
    """The read-out's note that the picture shown is a preview or a settling replay."""
    return (
        page.locator("code")
        .filter(has_text=PREVIEW_NOTE)
        .or_(page.locator("code").filter(has_text=SETTLING_NOTE))
    )


def changed_pixels(page: Page, image: Locator, before: str, top_px: int = 0) -> str:
    """Wait until `image` shows other pixels than `before` (from row `top_px` down), the
    same on two reads 100 ms apart (a read while the page swaps pictures can catch one half
    drawn), and the read-out does not call it a preview or settling (after a parameter
    change the exact picture replaces the preview once the value has rested, which can be
    well over 100 ms later, and the from-start one replaces a settling replay); its digest."""
    provisional = _provisional(page)
    last = before
    for _ in range(TIMEOUT_MS // 100):
        now = pixels(image, top_px)
        if now != before and now == last and provisional.count() == 0:
            return now
        last = now
        page.wait_for_timeout(100)
    raise AssertionError(f"{image}: the picture did not change in {TIMEOUT_MS} ms")


def shows_pixels(page: Page, image: Locator, expected: str, top_px: int = 0) -> bool:
    """Whether `image` comes to show the pixels `expected` (from row `top_px` down; a digest
    of `pixels`) within TIMEOUT_MS with the read-out calling it neither a preview nor
    settling: on a loaded machine a picture from another state can show for a while before
    the exact one replaces it."""
    provisional = _provisional(page)
    for _ in range(TIMEOUT_MS // 100):
        if pixels(image, top_px) == expected and provisional.count() == 0:
            return True
        page.wait_for_timeout(100)
    return False


def field(page: Page, label: str) -> Locator:
    """The visible input of the control labelled `label` (a parameter's field once its
    folder is open). viser's text fields do not tie their label to the input, so the input
    is found beside the label rather than by `get_by_label`."""
    row = page.locator("label").filter(has_text=label).filter(visible=True)
    exact = row.locator(f"xpath=self::*[normalize-space(.)='{label}']")
    return exact.locator("xpath=ancestor::div[.//input][1]//input").first


def set_field(page: Page, label: str, value: str) -> None:
    box = field(page, label)
    box.fill(value)
    box.press("Enter")
