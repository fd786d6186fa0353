"""The inspector's latency in a real browser, timed inside the page; prints the figures.

    python scripts/bench_inspector.py                 # the issue's counts: 2,000 + 2,000
    python scripts/bench_inspector.py --quick --json  # small counts, also as JSON

Starts `fusionscope serve` on a bundled recording (a free port, its own process), drives
Debian's Chromium (/usr/bin/chromium, never Playwright's download) with Playwright and
measures, against the targets of the issue:

With the "Motion stereo" stage picture under the camera and the bird's-eye view on:

- parameter change: `motion_stereo.threshold_xi` typed into its field of the Parameters
  folder, alternating between the paper's value and half of it; p95 <= 100 ms until every
  visible picture shows the new frame.
- seek: a random frame typed into the number box of the Timeline's "frame" slider;
  p95 <= 150 ms.
- playback at rate 4x (40 frames/s asked of a 10 Hz drive): frames/s shown, >= 25, in one tab,
  then in one of `--tabs` tabs while the others are idle and while they all play; then all
  the tabs playing at 1x, the drive's own rate: frames/s shown in the measured tab, at least
  REAL_TIME_SHARE of the drive's rate (the issue: "10 tabs connected keep playback
  real-time"). Frames/s
  shown: frames whose pictures were decoded in the measured page over the seconds played,
  counted in the rendered picture updated least often (the camera panel's picture, the
  stage picture under the camera in it, `app.view.stage_under`; a page with several pictures
  shows every frame in each, so one frame is counted once); at the end of the drive
  Play is pressed again (it starts over) and the restart counts as playing time.
- server memory: VmRSS of the server (children included) after warm-up, after each quarter
  of the seeks and of the parameter changes; growth from after the first quarter of the
  seeks to after the parameter changes <= 5 %. By then the server's two bounded caches have
  filled (the drive's decoded frames, 64 MiB, a whole bundled drive; each engine's kept
  states, 256 of about 86 KB), which a few dozen random seeks with their replays do; the
  growth from after warm-up, which includes that, is printed too.

Timing: a capture-phase listener on the page's window takes the action's first keydown /
input / change / pointerdown event as t0 (its `event.timeStamp`, the time the browser
created the event); a MutationObserver sees each <img> get a new src (viser shows each
rendered picture as a blob: URL) and calls `img.decode()` on it. The action is done at t1,
when every visible rendered image (blob: src, laid out, non-zero size) has a src set after t0
whose decode resolved, and, for a seek, the read-out names the target frame; t1 is the last of
those decodes: the camera panel's picture, the camera and the stage picture in one (the
bird's-eye view is drawn by WebGL, not an <img>, and is not timed). An action not done
within `--timeout-ms` is a miss; a miss counts as slower than any finished action in the
percentiles. Each finished action is also split at the moment viser's websocket worker
handed the page the message batch with its pictures: before it, the server and the socket;
after it, the page (React, blob URL, decode).

The page is driven as a person would, with two departures: a value is put in a number field
in one edit (Playwright's fill), since viser sends a number field's value on every change and
typing "10" key by key would also ask for 1; and Play is pressed from inside the page, so
that the count can press it again at the end of the drive without a round trip.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import json
import math
import os
import platform
import random
import re
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from playwright.sync_api import Browser, Locator, Page, ViewportSize, sync_playwright

from app.session import PANEL_LABELS
from app.view import PREVIEW_NOTE
from core.cli import DEFAULT_RECORDING, DEFAULT_RECORDINGS, ProgressBar
from core.params import Params

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
VIEWPORT: ViewportSize = {"width": 1400, "height": 800}

# the targets
MOVE_P95_TARGET_MS = 100.0
SEEK_P95_TARGET_MS = 150.0
PLAYBACK_TARGET_FPS = 25.0
MEMORY_GROWTH_TARGET_PCT = 5.0

PLAY_RATE = "4x"
REAL_TIME_RATE = "1x"  # the drive's own rate, every tab playing
REAL_TIME_SHARE = 0.9  # of the drive's frames a tab playing in real time shows, at least
MOVE_PARAMETER = ("motion_stereo", "threshold_xi")  # binarises motion stereo's difference C
STAGE = "Motion stereo"  # the stage picture under the camera while measuring

SERVER_START_S = 60.0  # until the server answers HTTP
SERVER_STOP_S = 10.0  # after SIGINT, before SIGKILL
FIRST_IMAGE_MS = 240_000  # a fresh install compiles the engine's numba code on the first render
UI_TIMEOUT_MS = 30_000  # a control to appear, a tab to show its image
SETTLE_S = 1.0  # after a miss: let a late picture land before the next action
WARMUP_SEEKS = 5  # default of --warmup
WARMUP_MOVES = 2
OTHERS_HEAD_START_S = 1.0  # the other tabs play this long before, and after, the measured one

QUICK = {"seeks": 50, "moves": 50, "play_s": 4.0, "tabs": 4}
FULL = {"seeks": 2000, "moves": 2000, "play_s": 10.0, "tabs": 10}

# Installed in every page before viser's client runs: window.__bench.
HARNESS_JS = r"""
(() => {
  if (window.__bench) return;
  const tracked = new WeakMap(); // <img> -> {src, tSet, tDecoded}
  let armed = false, t0 = null, expect = null, absent = null, done = null, waiter = null;
  // ms from t0 until every visible picture was first replaced and decoded, and until the
  // batch with those pictures reached the page
  let first = null, firstArrived = null;
  let play = null; // the playback being counted: {decodes: Map <img> -> count, restarts}
  const batches = []; // when viser's websocket worker handed the page a batch with an image

  // viser runs its websocket in a worker, which posts the decoded batches to the page
  const NativeWorker = window.Worker;
  window.Worker = class extends NativeWorker {
    constructor(...args) {
      super(...args);
      this.addEventListener("message", (ev) => { // before viser's own onmessage
        const d = ev.data;
        if (d && d.type === "message_batch" && d.messages.some(
          (m) => m.type === "GuiUpdateMessage" && m.updates && "_data" in m.updates)) {
          batches.push(performance.now());
          if (batches.length > 1000) batches.splice(0, 500);
        }
      });
    }
  };

  const shown = () => [...document.querySelectorAll("img")].filter(
    (i) => i.src.startsWith("blob:") && i.offsetParent !== null
      && i.offsetWidth > 0 && i.offsetHeight > 0);
  const readoutShows = (text) => [...document.querySelectorAll("code")].some(
    (c) => c.textContent.includes(text));

  function finish() {
    if (waiter === null || done === null) return;
    const [resolve, timer] = waiter;
    waiter = null;
    clearTimeout(timer);
    resolve(done);
  }
  function check() {
    if (!armed || t0 === null || done !== null) return;
    const imgs = shown();
    if (imgs.length === 0) return;
    let t1 = -Infinity;
    for (const img of imgs) {
      const e = tracked.get(img);
      if (!e || e.src !== img.src || e.tSet < t0 || e.tDecoded === null) return;
      t1 = Math.max(t1, e.tDecoded);
    }
    const arrived = batches.filter((t) => t >= t0 && t <= t1).at(-1) ?? NaN;
    if (first === null) [first, firstArrived] = [t1 - t0, arrived - t0];
    if (expect !== null && !readoutShows(expect)) return;
    if (absent !== null && readoutShows(absent)) return;
    armed = false;
    done = {ok: true, ms: t1 - t0, arrived_ms: arrived - t0, first_ms: first,
            first_arrived_ms: firstArrived, images: imgs.length, reason: ""};
    finish();
  }
  function track(img) {
    if (!img.src.startsWith("blob:")) return;
    const e = {src: img.src, tSet: performance.now(), tDecoded: null};
    tracked.set(img, e);
    img.decode().then(() => {
      if (tracked.get(img) !== e) return; // replaced before it was decoded
      e.tDecoded = performance.now();
      if (play !== null && shown().includes(img)) {
        play.decodes.set(img, (play.decodes.get(img) ?? 0) + 1);
      }
      check();
    }, () => {}); // a src replaced while decoding rejects: its successor counts
  }
  new MutationObserver((records) => {
    for (const r of records) {
      if (r.type === "attributes") {
        if (r.target instanceof HTMLImageElement) track(r.target);
        continue;
      }
      for (const n of r.addedNodes) {
        if (n instanceof HTMLImageElement) track(n);
        else if (n instanceof Element) n.querySelectorAll("img").forEach(track);
      }
    }
  }).observe(document, {subtree: true, childList: true, attributes: true,
                        attributeFilter: ["src"]});
  for (const type of ["keydown", "input", "change", "pointerdown"]) {
    window.addEventListener(type, (ev) => {
      if (!armed || t0 !== null) return;
      const now = performance.now();
      // the event's own time when it is in this clock (it is in Chromium), else now
      t0 = ev.timeStamp > 0 && ev.timeStamp <= now && now - ev.timeStamp < 1000
        ? ev.timeStamp : now;
    }, {capture: true});
  }

  const button = (label) => [...document.querySelectorAll("button")].find(
    (b) => b.textContent.trim() === label && b.offsetParent !== null);

  window.__bench = {
    // Before an action: the next input event starts it; `text` (or null): the read-out
    // must show it too; `without` (or null): the read-out must no longer show it.
    arm(text, without) {
      armed = true; t0 = null; done = null; first = firstArrived = null;
      expect = text; absent = without;
    },
    // After an action: {ok, ms, images, reason}, a miss after timeoutMs.
    wait(timeoutMs) {
      return new Promise((resolve) => {
        const timer = setTimeout(() => {
          waiter = null;
          armed = false;
          const why = t0 === null ? "no input event seen"
            : expect !== null && !readoutShows(expect) ? "read-out never showed " + expect
            : absent !== null && readoutShows(absent) ? "read-out still showed " + absent
            : "not every visible image was replaced and decoded";
          resolve({ok: false, ms: NaN, first_ms: first ?? NaN,
                   first_arrived_ms: firstArrived ?? NaN, arrived_ms: NaN,
                   images: shown().length, reason: why});
        }, timeoutMs);
        waiter = [resolve, timer];
        check();
        finish();
      });
    },
    // A shown image is decoded (the page is ready for an action).
    ready() {
      const imgs = shown();
      return imgs.length > 0 && imgs.every((i) => i.complete && i.naturalWidth > 0);
    },
    // Press Play and count the frames shown in the next `seconds`, pressing Play again when
    // the drive ends (it then starts over): {decodes, seconds, restarts}. Frames shown: the
    // fewest new pictures decoded in any one shown <img> (camera, stage picture), so a
    // frame counts once, and only as often as every picture was updated.
    playback(seconds) {
      return new Promise((resolve) => {
        const start = performance.now();
        const deadline = start + seconds * 1000;
        play = {decodes: new Map(), restarts: 0};
        let started = false;
        button("Play")?.click();
        const tick = setInterval(() => {
          const now = performance.now();
          if (now >= deadline) {
            clearInterval(tick);
            const result = play;
            play = null;
            button("Pause")?.click();
            const counts = shown().map((i) => result.decodes.get(i) ?? 0);
            resolve({decodes: counts.length > 0 ? Math.min(...counts) : 0,
                     seconds: (now - start) / 1000,
                     restarts: result.restarts});
            return;
          }
          if (button("Pause")) started = true;
          else if (started && button("Play")) { // at the end of the drive
            started = false;
            play.restarts += 1;
            button("Play").click();
          }
        }, 20);
      });
    },
  };
})();
"""


# --- the server -----------------------------------------------------------------------------
def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def _children(pid: int) -> list[int]:
    """Every descendant of `pid`, from /proc."""
    parents: dict[int, list[int]] = {}
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue  # ended meanwhile
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        parents.setdefault(ppid, []).append(int(entry.name))
    found, todo = [], [pid]
    while todo:
        kids = parents.get(todo.pop(), [])
        found += kids
        todo += kids
    return found


def rss_kib(pid: int) -> int:
    """VmRSS of `pid` and its descendants, KiB."""
    total = 0
    for p in (pid, *_children(pid)):
        try:
            status = Path(f"/proc/{p}/status").read_text()
        except OSError:
            continue
        match = re.search(r"^VmRSS:\s+(\d+) kB", status, re.MULTILINE)
        total += int(match.group(1)) if match else 0
    return total


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


class Server:
    """`fusionscope serve` in its own process (and session), stopped by `stop`."""

    def __init__(self, recordings: Path, recording: str, port: int) -> None:
        self.port = port
        self.url = ""  # the address `serve` prints (with its token), read by wait_until_answering
        self._log: IO[bytes] = tempfile.TemporaryFile()
        args = ["serve", "--recordings", str(recordings), "--recording", recording]
        self.process = subprocess.Popen(
            [sys.executable, "-m", "core.cli", *args, "--port", str(port)],
            stdin=subprocess.DEVNULL,
            stdout=self._log,
            stderr=subprocess.STDOUT,
            start_new_session=True,  # a Ctrl-C reaches this script, which stops the server
            # SIGINT is the server's clean stop; a shell starting this script in the background
            # leaves SIGINT ignored, and Python then installs no handler for it
            preexec_fn=_default_sigint,
        )

    @property
    def pid(self) -> int:
        return self.process.pid

    def log_tail(self, lines: int = 20) -> str:
        self._log.seek(0)
        return "\n".join(self._log.read().decode(errors="replace").splitlines()[-lines:])

    def wait_until_answering(self, timeout_s: float = SERVER_START_S) -> None:
        deadline = time.monotonic() + timeout_s
        while True:
            if self.process.poll() is not None:
                raise RuntimeError(
                    f"fusionscope serve ended with code {self.process.returncode}:\n"
                    + self.log_tail()
                )
            self.url = self.url or self._printed_url()
            try:
                if self.url:
                    with urllib.request.urlopen(self.url, timeout=1.0) as reply:
                        if reply.status == 200:
                            return
            except (urllib.error.URLError, OSError):
                pass
            if time.monotonic() > deadline:
                raise RuntimeError(
                    f"fusionscope serve did not answer on port {self.port} within "
                    f"{timeout_s:.0f} s:\n" + self.log_tail()
                )
            time.sleep(0.2)

    def _printed_url(self) -> str:
        """The address in the line `fusionscope serve` prints when it is up; "" before."""
        self._log.seek(0)
        found = re.search(rb"fusionscope inspector: (\S+)", self._log.read())
        return found.group(1).decode() if found else ""

    def stop(self) -> None:
        """SIGINT (the server's own clean stop), SIGKILL if it lingers; then SIGKILL to any
        process it started that outlived it."""
        started = _children(self.pid) if self.process.poll() is None else []
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.wait(SERVER_STOP_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        for pid in started:
            with contextlib.suppress(ProcessLookupError, PermissionError):
                os.kill(pid, signal.SIGKILL)
        self._log.close()


@contextlib.contextmanager
def running_server(recordings: Path, recording: str) -> Iterator[Server]:
    server = Server(recordings, recording, free_port())
    try:
        server.wait_until_answering()
        yield server
    finally:
        server.stop()


# --- figures --------------------------------------------------------------------------------
def percentile(values: Sequence[float], q: float) -> float:
    """Nearest-rank percentile (q in 0..100); a miss is +inf; NaN for no values."""
    if not values:
        return math.nan
    ranked = sorted(values)
    return ranked[max(math.ceil(q / 100.0 * len(ranked)) - 1, 0)]


@dataclass
class Latencies:
    """One kind of action: its latencies (ms, a miss is +inf), why each miss missed, and for
    the finished ones when the batch with the last pictures reached the page (ms after t0;
    NaN when not seen). A figure without a target (None) is for information."""

    name: str
    target_p95_ms: float | None
    ms: list[float] = field(default_factory=list)
    miss_reasons: dict[str, int] = field(default_factory=dict)
    arrived_ms: list[float] = field(default_factory=list)

    def add(self, outcome: dict[str, Any]) -> bool:
        if outcome["ok"]:
            self.ms.append(float(outcome["ms"]))
            arrived = outcome.get("arrived_ms")
            self.arrived_ms.append(math.nan if arrived is None else float(arrived))
            return True
        self.ms.append(math.inf)
        reason = str(outcome["reason"])
        self.miss_reasons[reason] = self.miss_reasons.get(reason, 0) + 1
        return False

    @property
    def misses(self) -> int:
        return sum(self.miss_reasons.values())

    def summary(self) -> dict[str, Any]:
        p95 = percentile(self.ms, 95)
        finished = [t for t in self.ms if math.isfinite(t)]
        split = [(a, t - a) for a, t in zip(self.arrived_ms, finished, strict=True) if a == a]
        return {
            "name": self.name,
            "count": len(self.ms),
            "misses": self.misses,
            "miss_reasons": dict(self.miss_reasons),
            "p50_ms": percentile(self.ms, 50),
            "p95_ms": p95,
            "max_ms": max(self.ms, default=math.nan),
            "target_p95_ms": self.target_p95_ms,
            "passed": None if self.target_p95_ms is None else p95 <= self.target_p95_ms,
            # where the time of a finished action went (medians): until the pictures reached
            # the page (server, socket, viser's worker), then until they were decoded
            "to_page_p50_ms": percentile([a for a, _ in split], 50),
            "in_page_p50_ms": percentile([b for _, b in split], 50),
        }


@dataclass
class Playback:
    """Frames/s shown while playing: frames whose pictures were decoded in the page (counted
    in the picture updated least often) over the time played (from Play to the end of the
    window, restarts at the end of the drive included)."""

    name: str
    fps: float
    frames: int
    seconds: float
    restarts: int
    target_fps: float | None = PLAYBACK_TARGET_FPS  # None: for information

    @staticmethod
    def of(
        name: str, counted: dict[str, Any], target_fps: float | None = PLAYBACK_TARGET_FPS
    ) -> Playback:
        """From the page's count: {decodes, seconds, restarts}."""
        frames, seconds = int(counted["decodes"]), float(counted["seconds"])
        fps = frames / seconds if seconds > 0 else math.nan
        return Playback(name, fps, frames, seconds, int(counted["restarts"]), target_fps)

    def summary(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "fps": self.fps,
            "frames": self.frames,
            "seconds": self.seconds,
            "restarts": self.restarts,
            "target_fps": self.target_fps,
            "passed": None if self.target_fps is None else self.fps >= self.target_fps,
        }


@dataclass
class Report:
    machine: dict[str, Any]
    recording: str
    frames: int
    frame_rate_hz: float
    latencies: list[Latencies]
    playback: list[Playback]
    rss_kib: dict[str, int]
    server_pid: int

    def memory_growth_pct(self, since: str) -> float:
        """RSS growth from sample `since` to after the parameter changes, %."""
        before, after = self.rss_kib[since], self.rss_kib["after moves"]
        return 100.0 * (after - before) / before if before > 0 else math.nan

    def summary(self) -> dict[str, Any]:
        # judged from the sample after the first quarter of the seeks: the bounded caches
        # (decoded frames, kept engine states) are full by then, so growth after it is what
        # would keep growing
        later = list(self.rss_kib)[1]
        growth = self.memory_growth_pct(later)
        return {
            "machine": self.machine,
            "recording": self.recording,
            "frames": self.frames,
            "frame_rate_hz": self.frame_rate_hz,
            "latency": [lat.summary() for lat in self.latencies],
            "playback": [p.summary() for p in self.playback],
            "memory": {
                "rss_kib": dict(self.rss_kib),
                "judged_from": later,
                "growth_pct": growth,
                "target_growth_pct": MEMORY_GROWTH_TARGET_PCT,
                "passed": growth <= MEMORY_GROWTH_TARGET_PCT,
                "growth_after_warm_up_pct": self.memory_growth_pct("after warm-up"),
            },
            "server_pid": self.server_pid,
        }


# --- the page -------------------------------------------------------------------------------
def open_tab(browser: Browser, url: str, bird_eye: bool = True) -> Page:
    """A fresh browser context on the inspector, its first picture shown; the 3D
    bird's-eye view switched off in the Panels folder unless `bird_eye`."""
    context = browser.new_context(viewport=VIEWPORT)
    context.add_init_script(HARNESS_JS)
    page = context.new_page()
    page.goto(url)
    page.wait_for_function("() => window.__bench.ready()", timeout=FIRST_IMAGE_MS)
    if not bird_eye:
        page.get_by_text("Panels", exact=True).click()
        switch = page.get_by_label(PANEL_LABELS["bird_eye"], exact=True)
        switch.click()
        if switch.is_checked():
            raise RuntimeError("the bird's-eye view switch did not turn off")
        page.get_by_text("Panels", exact=True).click()
        page.wait_for_function("() => window.__bench.ready()", timeout=UI_TIMEOUT_MS)
    return page


def select_stage(page: Page, title: str) -> None:
    """Show the stage picture `title` under the camera (the "stage" dropdown)."""
    choice = page.locator("label").filter(has_text="stage").filter(visible=True).first
    box = choice.locator("xpath=ancestor::div[.//input][1]//input").first
    if box.input_value() != title:
        box.click()
        page.get_by_role("option", name=title, exact=True).click()
    page.wait_for_function("() => window.__bench.ready()", timeout=UI_TIMEOUT_MS)


def set_rate(page: Page, rate: str) -> None:
    field_ = page.get_by_label("rate", exact=True)
    field_.click()
    page.get_by_role("option", name=rate, exact=True).click()
    page.wait_for_function(
        f"() => [...document.querySelectorAll('input')].some(i => i.value === {json.dumps(rate)}"
        " && i.type !== 'hidden')",
        timeout=UI_TIMEOUT_MS,
    )


def drive_size(page: Page) -> tuple[int, float]:
    """Frames and frame rate (Hz) of the drive shown, from the headline above the Timeline."""
    headline = page.get_by_text(re.compile(r"\d+ frames at [\d.]+ Hz")).first.inner_text()
    match = re.search(r"(\d+) frames at ([\d.]+) Hz", headline)
    if match is None:
        raise RuntimeError(f"the page's headline has no frame count: {headline!r}")
    return int(match.group(1)), float(match.group(2))


def frame_box(page: Page) -> Locator:
    """The number box beside the Timeline's "frame" slider."""
    label = page.locator("label[for]").filter(has_text=re.compile(r"^frame$")).first
    slider_id = label.get_attribute("for")
    return page.locator(f"[id='{slider_id}']").locator("xpath=..//input[@type='text']")


def parameter_field(page: Page, stage: str, name: str) -> Locator:
    """The number field of parameter `stage.name`, its folders opened."""
    field_ = page.get_by_label(name, exact=True)
    if not field_.is_visible():
        page.get_by_text("Parameters", exact=True).click()
        page.get_by_text(stage, exact=True).click()
    field_.wait_for(state="visible", timeout=UI_TIMEOUT_MS)
    return field_


def timed(
    page: Page,
    act: Callable[[], None],
    timeout_ms: float,
    readout: str | None,
    without: str | None = None,
) -> dict[str, Any]:
    """Arm the harness, act, and wait for the page's verdict on the action: every visible
    picture replaced and decoded, the read-out showing `readout` and not `without` (each
    when given). The outcome's `first_ms` is when the pictures were first all replaced."""
    page.evaluate("([text, without]) => window.__bench.arm(text, without)", [readout, without])
    act()
    outcome: dict[str, Any] = page.evaluate("ms => window.__bench.wait(ms)", timeout_ms)
    if not outcome["ok"]:
        page.wait_for_timeout(SETTLE_S * 1000)
    return outcome


def type_value(box: Locator, text: str) -> None:
    """Put `text` in a number field as one edit, then Enter. viser sends a number field's
    value on every change: typing "30" key by key would also ask for 3. Enter is pressed on
    the keyboard, not on the field's locator: a locator's press first checks in the page
    that the field is the hit target, which kept the page's main thread busy for 20-40 ms
    just when the server's answer came (seen in a Chromium trace: Playwright's DevTools
    message before every answer), a delay no person's key press makes."""
    box.fill(text)
    box.page.keyboard.press("Enter")


def seek(page: Page, box: Locator, frame: int, timeout_ms: float) -> dict[str, Any]:
    """Type `frame` in the frame box (another frame than the one shown: the same would not
    change the box, and nothing would happen)."""
    return timed(page, lambda: type_value(box, str(frame)), timeout_ms, f"frame {frame} /")


def show_frame(page: Page, box: Locator, frame: int) -> None:
    """Show `frame`, untimed (nothing to do when it is shown)."""
    if int(box.input_value() or -1) != frame:
        _needed(seek(page, box, frame, FIRST_IMAGE_MS), f"showing frame {frame}")


def _needed(outcome: dict[str, Any], what: str) -> None:
    """An untimed step the measurements build on: it must finish."""
    if not outcome["ok"]:
        raise RuntimeError(f"{what}: {outcome['reason']} within {FIRST_IMAGE_MS / 1000:g} s")


def seeks(
    page: Page,
    count: int,
    frames: int,
    rng: random.Random,
    timeout_ms: float,
    after_each: Callable[[int, int], None],
) -> Latencies:
    result = Latencies("seek to a random frame", SEEK_P95_TARGET_MS)
    select_stage(page, STAGE)
    box = frame_box(page)
    current = int(box.input_value() or 0)
    for i in range(count):
        target = rng.choice([f for f in range(frames) if f != current])
        if result.add(seek(page, box, target, timeout_ms)):
            current = target
        else:
            current = int(box.input_value() or current)
        after_each(i + 1, count)
    return result


def move_values() -> tuple[str, str]:
    """The parameter's paper value and half of it, both accepted by `Params`."""
    stage, name = MOVE_PARAMETER
    paper = float(getattr(getattr(Params(), stage), name))
    other = paper / 2.0
    Params().with_value(f"{stage}.{name}", other)  # a value the server will accept
    return f"{paper:g}", f"{other:g}"


def moves(
    page: Page, count: int, timeout_ms: float, after_each: Callable[[int, int], None]
) -> tuple[Latencies, Latencies]:
    """Parameter changes, each to the other of two values; then back to the paper's value.

    Two figures: until every visible picture first shows the new value (the server's
    preview of the frame when it has one, `FusionEngine.preview`), and until they show the
    exact result (the read-out no longer says preview)."""
    first = Latencies("parameter change -> panels", MOVE_P95_TARGET_MS)
    exact = Latencies("  ... -> exact (replayed)", None)  # after the 0.15 s rest: no target
    select_stage(page, STAGE)
    box = parameter_field(page, *MOVE_PARAMETER)
    paper, other = move_values()
    for i in range(count):
        text = paper if float(box.input_value()) == float(other) else other
        act = functools.partial(type_value, box, text)
        outcome = timed(page, act, timeout_ms, None, PREVIEW_NOTE)
        exact.add(outcome)
        first_ms = outcome["first_ms"]
        if first_ms is None or not math.isfinite(first_ms):
            first.add({"ok": False, "reason": outcome["reason"]})
        else:
            first.add({"ok": True, "ms": first_ms, "arrived_ms": outcome["first_arrived_ms"]})
        after_each(i + 1, count)
    if float(box.input_value()) != float(paper):  # untimed
        timed(page, functools.partial(type_value, box, paper), timeout_ms, None, PREVIEW_NOTE)
    return first, exact


def play(page: Page, seconds: float) -> dict[str, Any]:
    counted: dict[str, Any] = page.evaluate("s => window.__bench.playback(s)", seconds)
    page.get_by_role("button", name="Play").wait_for(timeout=UI_TIMEOUT_MS)
    return counted


def play_in_all(
    measured: Page, others: list[Page], seconds: float, rate: str, target_fps: float
) -> list[Playback]:
    """Every tab plays at `rate`: `measured` for `seconds`, the others from a little before
    to a little after. The measured tab's figure (against `target_fps`), and the mean of
    every tab's (for information)."""
    for page in (measured, *others):
        set_rate(page, rate)
    for page in others:
        page.evaluate(
            "s => { window.__benchPlay = window.__bench.playback(s); }",
            seconds + 2 * OTHERS_HEAD_START_S,
        )
    measured.wait_for_timeout(OTHERS_HEAD_START_S * 1000)
    tabs = len(others) + 1
    name = f"{tabs} tabs, all playing at {rate}"
    figure = Playback.of(f"{name}: the measured tab", play(measured, seconds), target_fps)
    each = [figure]
    for page in others:
        each.append(Playback.of("", page.evaluate("() => window.__benchPlay")))
        page.get_by_role("button", name="Play").wait_for(timeout=UI_TIMEOUT_MS)
    mean = Playback(
        f"{name}: mean of the tabs",
        sum(p.fps for p in each) / len(each),
        sum(p.frames for p in each),
        sum(p.seconds for p in each),
        sum(p.restarts for p in each),
        None,
    )
    return [figure, mean]


# --- the run --------------------------------------------------------------------------------
def machine_info(browser_version: str, load_at_start: tuple[float, float, float]) -> dict[str, Any]:
    """What the figures depend on; the load averages (1, 5, 15 min) say how busy the CPUs
    were with other work."""
    return {
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "chromium": browser_version,
        "platform": platform.platform(),
        "load_average_at_start": [round(x, 2) for x in load_at_start],
        "load_average_at_end": [round(x, 2) for x in os.getloadavg()],
    }


def warm_up(page: Page, box: Locator, frames: int, rng: random.Random, count: int) -> None:
    """Seeks and parameter changes not measured: the engine's first runs, the page's first
    pictures of each kind."""
    for _ in range(count):
        current = int(box.input_value() or 0)
        target = rng.choice([f for f in range(frames) if f != current])
        _needed(seek(page, box, target, FIRST_IMAGE_MS), f"warm-up: seeking to frame {target}")
    show_frame(page, box, frames // 2)
    _, changes = moves(page, WARMUP_MOVES, FIRST_IMAGE_MS, lambda done, total: None)
    if changes.misses:
        raise RuntimeError(f"warm-up: parameter changes: {changes.miss_reasons}")
    select_stage(page, STAGE)


def playbacks(
    browser: Browser,
    page: Page,
    url: str,
    seconds: float,
    tabs: int,
    bird_eye: bool,
    frame_rate_hz: float,
    say: Callable[[str], None],
) -> list[Playback]:
    """Frames/s shown in `page` (camera, stage picture and, if `bird_eye`, the bird's-eye
    view) at PLAY_RATE: alone, then with `tabs - 1` more tabs, idle, then all playing; then
    all playing at REAL_TIME_RATE, against REAL_TIME_SHARE of the drive's `frame_rate_hz`."""
    say(f"playback at {PLAY_RATE}, {seconds:g} s per figure")
    set_rate(page, PLAY_RATE)
    shown: list[Playback] = []
    select_stage(page, STAGE)
    alone = f"1 tab at {PLAY_RATE}, camera + {STAGE.lower()}"
    shown.append(Playback.of(alone, play(page, seconds)))
    if tabs < 2:
        return shown
    say(f"opening {tabs - 1} more tabs")
    others = [open_tab(browser, url, bird_eye) for _ in range(tabs - 1)]
    page.bring_to_front()
    say(f"playback in 1 of {tabs} tabs, then in all, at {PLAY_RATE} and {REAL_TIME_RATE}")
    shown.append(Playback.of(f"{tabs} tabs at {PLAY_RATE}, {tabs - 1} idle", play(page, seconds)))
    shown += play_in_all(page, others, seconds, PLAY_RATE, PLAYBACK_TARGET_FPS)
    real_time_fps = REAL_TIME_SHARE * frame_rate_hz * float(REAL_TIME_RATE.rstrip("x"))
    return shown + play_in_all(page, others, seconds, REAL_TIME_RATE, real_time_fps)


def _sampling(
    label: str, pid: int, rss: dict[str, int], progress: bool
) -> Callable[[int, int], None]:
    """After each action: the progress bar, and the server's RSS after each quarter."""
    bar = ProgressBar(label) if progress else None

    def after(done: int, total: int) -> None:
        if bar is not None:
            bar(done, total)
        if done < total and done in {total // 4, total // 2, 3 * total // 4}:
            rss[f"after {done} {label}"] = rss_kib(pid)

    return after


def run(options: argparse.Namespace) -> Report:
    """Start the server and the browser, measure, stop both (also on errors and Ctrl-C)."""
    if not options.chromium.exists():
        raise FileNotFoundError(
            f"{options.chromium}: no Chromium there; install Debian's (apt-get install chromium) "
            "or give --chromium"
        )
    rng = random.Random(options.seed)
    progress = not options.no_progress
    load_at_start = os.getloadavg()
    started = time.monotonic()

    def say(text: str) -> None:
        if progress:
            print(f"[{time.monotonic() - started:5.1f} s] {text}", file=sys.stderr, flush=True)

    with running_server(options.recordings, options.recording) as server, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=str(options.chromium), args=CHROMIUM_ARGS)
        try:
            say(f"server pid {server.pid} on {server.url}; waiting for the first picture")
            page = open_tab(browser, server.url, not options.no_bird_eye)
            frames, frame_rate_hz = drive_size(page)
            if frames < 2:
                raise RuntimeError(f"{options.recording}: {frames} frame(s), nothing to seek to")
            say("warming up")
            box = frame_box(page)
            warm_up(page, box, frames, rng, options.warmup)
            rss = {"after warm-up": rss_kib(server.pid)}

            say(f"{options.seeks} seeks")
            each = _sampling("seeks", server.pid, rss, progress)
            seek_figures = seeks(page, options.seeks, frames, rng, options.timeout_ms, each)
            rss["after seeks"] = rss_kib(server.pid)
            show_frame(page, box, frames // 2)  # a frame with motion to binarise
            say(f"{options.moves} parameter changes")
            each = _sampling("parameter changes", server.pid, rss, progress)
            move_figures = moves(page, options.moves, options.timeout_ms, each)
            rss["after moves"] = rss_kib(server.pid)

            shown = playbacks(
                browser,
                page,
                server.url,
                options.play_s,
                options.tabs,
                not options.no_bird_eye,
                frame_rate_hz,
                say,
            )
            rss["at the end"] = rss_kib(server.pid)
            machine = machine_info(browser.version, load_at_start)
        finally:
            browser.close()
        say("done; stopping the server")
    return Report(
        machine,
        options.recording,
        frames,
        frame_rate_hz,
        [*move_figures, seek_figures],
        shown,
        rss,
        server.pid,
    )


# --- output ---------------------------------------------------------------------------------
def _ms(value: float) -> str:
    return "miss" if math.isinf(value) else "-" if math.isnan(value) else f"{value:.1f}"


def _loads(values: list[float]) -> str:
    return " ".join(f"{x:.2f}" for x in values)


def _verdict(passed: bool | None) -> str:
    return "" if passed is None else "PASS" if passed else "MISS"


def format_report(summary: dict[str, Any], options: argparse.Namespace) -> str:
    m = summary["machine"]
    asked_fps = summary["frame_rate_hz"] * float(PLAY_RATE.rstrip("x"))
    lines = [
        f"fusionscope inspector in a browser — {summary['recording']} ({summary['frames']} "
        f"frames at {summary['frame_rate_hz']:g} Hz); {options.seeks} seeks, "
        f"{options.moves} parameter changes, {options.play_s:g} s per playback, "
        f"{options.tabs} tab{'' if options.tabs == 1 else 's'}",
        f"machine: {m['cpus']} CPUs, Python {m['python']}, Chromium {m['chromium']}; "
        f"load average (1, 5, 15 min) {_loads(m['load_average_at_start'])} at the start, "
        f"{_loads(m['load_average_at_end'])} at the end",
        "panels: camera, motion stereo picture, "
        + ("no bird's-eye view (--no-bird-eye)" if options.no_bird_eye else "3D bird's-eye view"),
        "",
        "latency, input event -> every visible picture replaced and decoded (ms; a miss is "
        f"no picture within {options.timeout_ms:g} ms)",
        f"{'action':<30} {'n':>5} {'misses':>6} {'p50':>7} {'p95':>7} {'max':>7}  "
        f"{'target':<13} verdict",
    ]
    for lat in summary["latency"]:
        target = "" if lat["target_p95_ms"] is None else f"p95 <= {lat['target_p95_ms']:g}"
        lines.append(
            f"{lat['name']:<30} {lat['count']:>5} {lat['misses']:>6} {_ms(lat['p50_ms']):>7} "
            f"{_ms(lat['p95_ms']):>7} {_ms(lat['max_ms']):>7}  "
            f"{target:<13} {_verdict(lat['passed'])}"
        )
        for reason, n in lat["miss_reasons"].items():
            lines.append(f"    {n} missed: {reason}")
    lines.append("  median split: input -> pictures reach the page | -> decoded and shown")
    for lat in summary["latency"]:
        lines.append(
            f"  {lat['name']:<28} {_ms(lat['to_page_p50_ms']):>7} | "
            f"{_ms(lat['in_page_p50_ms']):>7} ms"
        )
    lines += [
        "",
        f"playback, frames/s shown (rate {PLAY_RATE} asks {asked_fps:g} frames/s, "
        f"{REAL_TIME_RATE} the drive's {summary['frame_rate_hz']:g})",
        f"{'':<50} {'fps':>6}  {'target':<8} verdict",
    ]
    for p in summary["playback"]:
        target = "" if p["target_fps"] is None else f">= {p['target_fps']:g}"
        lines.append(f"{p['name']:<50} {p['fps']:>6.1f}  {target:<8} {_verdict(p['passed'])}")
    mem = summary["memory"]
    lines += ["", "server memory (VmRSS of the server process and its children)"]
    lines += [f"  {k:<34} {v / 1024:7.1f} MiB" for k, v in mem["rss_kib"].items()]
    lines.append(
        f"growth from {mem['judged_from']} to after the parameter changes: "
        f"{mem['growth_pct']:+.1f} % (target <= {mem['target_growth_pct']:g} %) "
        f"{_verdict(mem['passed'])}"
    )
    lines.append(
        "growth from after warm-up to after the parameter changes: "
        f"{mem['growth_after_warm_up_pct']:+.1f} % (the server's bounded caches of decoded "
        "frames and engine states filling)"
    )
    return "\n".join(lines)


def _json_safe(value: Any) -> Any:
    """inf / NaN as null: JSON has neither."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_json_safe(v) for v in value]
    return value


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return value


def _seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of seconds, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a number of seconds > 0, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bench_inspector.py",
        description=(__doc__ or "").split("\n\n")[0],
    )
    parser.add_argument(
        "--recordings",
        type=Path,
        default=DEFAULT_RECORDINGS,
        help="folder of recordings (default: the bundled ones)",
    )
    parser.add_argument(
        "--recording",
        default=DEFAULT_RECORDING,
        help=f"recording measured on (default: {DEFAULT_RECORDING})",
    )
    parser.add_argument("--seeks", type=_count, help=f"seeks (default: {FULL['seeks']})")
    parser.add_argument(
        "--moves", type=_count, help=f"parameter changes (default: {FULL['moves']})"
    )
    parser.add_argument(
        "--play-s", type=_seconds, help=f"seconds per playback figure (default: {FULL['play_s']})"
    )
    parser.add_argument(
        "--tabs",
        type=_count,
        help=f"tabs for the many-tabs playback, 1 for none (default: {FULL['tabs']})",
    )
    parser.add_argument(
        "--quick",
        action="store_true",
        help="small counts: " + ", ".join(f"{k} {v:g}" for k, v in QUICK.items()),
    )
    parser.add_argument(
        "--timeout-ms",
        type=_seconds,
        default=5000.0,
        help="an action not done after this is a miss (default: 5000)",
    )
    parser.add_argument(
        "--warmup",
        type=_count,
        default=WARMUP_SEEKS,
        help=f"random seeks before measuring (default: {WARMUP_SEEKS})",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the seek targets")
    parser.add_argument("--chromium", type=Path, default=CHROMIUM, help=f"default: {CHROMIUM}")
    parser.add_argument(
        "--no-bird-eye",
        action="store_true",
        help="measure with the 3D bird's-eye view switched off (Panels folder) in every tab",
    )
    parser.add_argument("--json", action="store_true", help="also print the figures as JSON")
    parser.add_argument("--no-progress", action="store_true", help="no progress on stderr")
    return parser


def parse_args(argv: Sequence[str] | None = None) -> argparse.Namespace:
    options = build_parser().parse_args(argv)
    counts = QUICK if options.quick else FULL
    for key, value in counts.items():
        if getattr(options, key) is None:
            setattr(options, key, value)
    return options


def main(argv: Sequence[str] | None = None) -> int:
    options = parse_args(argv)
    try:
        report = run(options)
    except (RuntimeError, FileNotFoundError) as err:
        print(f"bench_inspector: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("\nbench_inspector: interrupted; server and browser stopped", file=sys.stderr)
        return 130
    summary = report.summary()
    print(format_report(summary, options))
    if options.json:
        print(json.dumps(_json_safe(summary), indent=2))
    return 0


def _stop_on_sigterm(signum: int, frame: object) -> None:
    raise SystemExit(128 + signum)  # unwinds through run(): the server is stopped


if __name__ == "__main__":
    signal.signal(signal.SIGTERM, _stop_on_sigterm)
    raise SystemExit(main())
