"""The 3D bird's-eye scene of a clip as one HTML page (`app.snapshot`, `fusionscope
export-scene`): the page inlines everything, its recording holds one frame of the clip per
frame interval on the inspector's fixed nodes, each frame is what the inspector shows, and
the page plays from file:// in headless Chromium.

The recording is read back as the page reads it: base64 in `window.__VISER_EMBED_DATA__`,
then viser's `StateSerializer.serialize` framing (uncompressed size, zstd of: msgpack
length, msgpack, 8-byte-aligned binary buffers).
"""

from __future__ import annotations

import base64
import dataclasses
import re
import socket
from pathlib import Path
from typing import Any

import cv2
import msgspec
import numpy as np
import pytest
import viser
import zstandard
from app_fakes import Recordings
from browser_page import SCREENSHOTS, TIMEOUT_MS
from playwright.sync_api import Page

from app import bird_eye, snapshot
from app.bird_eye import BirdEyeGeometry, top_down_pose
from app.snapshot import bird_eye_snapshot_html, clip_duration_s
from app.state import DEMO_LAYERS
from app.view import b_offset_y_m, bird_eye_view
from core.cli import main
from core.engine import FusionEngine
from core.io.drive import Drive
from core.io.errors import RecordingError
from core.io.frame import FrameInput
from core.params import Params

PARAMS = Params()
# B sees 10 m further: another texture, so B's ground is not A's
PARAMS_B = dataclasses.replace(
    PARAMS, motion_stereo=dataclasses.replace(PARAMS.motion_stereo, x_max_m=50.0)
)
# On the 2 s synthetic highway of conftest.py the first tracks are confirmed at frame 14: a
# clip from frame 15 shows them only when the frames before it were replayed.
FIRST, LAST = 15, 19
EMBED = re.compile(r'window\.__VISER_EMBED_DATA__="([A-Za-z0-9+/=]*)"')
SVG_NAMESPACE = "http://www.w3.org/2000/svg"  # an XML name in the page's icon, never loaded
TIME_TOLERANCE_S = 1e-6
FIXED_NODES = {
    "ground",
    "ego",
    "radar",
    "tracks",
    *(f"vehicles/{k}" for k in range(bird_eye.MAX_VEHICLE_BOXES)),
    *(f"labels/{k}" for k in range(bird_eye.MAX_TRACK_LABELS)),
}


# --- reading the page back ------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Recording:
    duration_s: float
    messages: list[tuple[float, dict[str, Any]]]
    buffers: list[bytes]

    def of(self, kind: str, name: str | None = None) -> list[tuple[float, dict[str, Any]]]:
        return [
            (t, m)
            for t, m in self.messages
            if m["type"] == kind and (name is None or m.get("name") == name)
        ]

    def ground_images(self, prefix: str) -> list[tuple[float, bytes]]:
        """(time, JPEG) of each picture the ground node of `prefix` gets: at its creation,
        then each update of its image."""
        name = f"{prefix}/ground"
        created = [(t, m["props"]["_data"]) for t, m in self.of("ImageMessage", name)]
        updated = [
            (t, m["updates"]["_data"])
            for t, m in self.of("SceneNodeUpdateMessage", name)
            if "_data" in m["updates"]
        ]
        return sorted(created + updated, key=lambda item: item[0])


def read_recording(html: str) -> Recording:
    (data,) = EMBED.findall(html)
    framed = base64.b64decode(data)
    inner_size = int.from_bytes(framed[:8], "little")
    inner = zstandard.ZstdDecompressor().decompress(framed[8:], max_output_size=inner_size)
    assert len(inner) == inner_size
    header = int.from_bytes(inner[:8], "little")
    payload = msgspec.msgpack.decode(inner[8 : 8 + header])
    buffers, offset = [], 8 + header
    for length in payload["binaryBufferLengths"]:
        offset += -offset % 8
        buffers.append(inner[offset : offset + length])
        offset += length
    assert offset == inner_size  # the buffers fill the payload to its end
    messages = [(float(t), m) for t, m in payload["messages"]]
    return Recording(float(payload["durationSeconds"]), messages, buffers)


@dataclasses.dataclass
class Node:
    props: dict[str, Any]
    position: list[float] | None = None
    visible: bool = True


def scene_at(recording: Recording, t_s: float) -> dict[str, Node]:
    """The scene nodes as the page has them at `t_s` seconds into the recording."""
    nodes: dict[str, Node] = {}
    for t, m in recording.messages:
        if t > t_s + TIME_TOLERANCE_S:
            break
        name, kind = m.get("name"), m["type"]
        if name is None:
            continue
        if "props" in m:
            nodes[name] = Node(dict(m["props"]))
        elif kind == "SceneNodeUpdateMessage":
            nodes[name].props.update(m["updates"])
        elif kind == "SetPositionMessage":
            nodes[name].position = m["position"]
        elif kind == "SetSceneNodeVisibilityMessage":
            nodes[name].visible = m["visible"]
        elif kind == "RemoveSceneNodeMessage":
            del nodes[name]
    return nodes


def jpeg_size(jpeg: bytes) -> tuple[int, ...]:
    """(rows, columns) of a JPEG picture."""
    image = cv2.imdecode(np.frombuffer(jpeg, np.uint8), cv2.IMREAD_GRAYSCALE)
    assert image is not None
    return tuple(image.shape)


def visible(nodes: dict[str, Node], group: str) -> list[Node]:
    return [n for name, n in nodes.items() if name.startswith(f"{group}/") and n.visible]


def stamps_s(drive_path: Path, first: int, last: int) -> list[float]:
    """The clip's frames' stamps, seconds from its first frame."""
    with Drive(drive_path) as drive:
        times = [int(t) for t in drive.times_ns[first : last + 1]]
    return [(t - times[0]) / 1e9 for t in times]


def engine_view(drive_path: Path, index: int, params: Params = PARAMS) -> BirdEyeGeometry:
    """What the inspector shows of frame `index` with a demo's layers (a snapshot's default):
    `FusionEngine.seek` to it."""
    with Drive(drive_path) as drive:
        result = FusionEngine(params, drive.camera).seek(drive, index)
    return bird_eye_view(result, params, DEMO_LAYERS)[0]


# --- fixtures -------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def drive_path(recordings: Recordings) -> Path:
    return recordings.root / recordings.name


@pytest.fixture(scope="module")
def page_html(drive_path: Path) -> str:
    with Drive(drive_path) as drive:
        return bird_eye_snapshot_html(drive, FIRST, LAST, PARAMS)


@pytest.fixture(scope="module")
def recording(page_html: str) -> Recording:
    return read_recording(page_html)


@pytest.fixture(scope="module")
def recording_ab(drive_path: Path) -> Recording:
    with Drive(drive_path) as drive:
        return read_recording(bird_eye_snapshot_html(drive, FIRST, LAST, PARAMS, PARAMS_B))


@pytest.fixture()
def servers(monkeypatch: pytest.MonkeyPatch) -> list[tuple[viser.ViserServer, dict[str, Any]]]:
    """Each viser server made from now on, with the arguments it was made with."""
    made: list[tuple[viser.ViserServer, dict[str, Any]]] = []
    real = viser.ViserServer

    def recorded(**kwargs: Any) -> viser.ViserServer:
        server = real(**kwargs)
        made.append((server, kwargs))
        return server

    monkeypatch.setattr(viser, "ViserServer", recorded)
    return made


def listening(port: int) -> bool:
    with socket.socket() as s:
        s.settimeout(1.0)
        return s.connect_ex(("127.0.0.1", port)) == 0


# --- the page -------------------------------------------------------------------------------


def test_page_is_viser_client_with_the_recording_inlined_and_no_address_to_load(
    page_html: str,
) -> None:
    assert page_html.lstrip().lower().startswith("<!doctype html>")
    assert len(EMBED.findall(page_html)) == 1
    # nothing fetched: no element names a file, every script and style is in the page
    assert not re.search(r"""\b(?:src|href)\s*=\s*["']?(?:https?:)?//""", page_html)
    assert not re.search(r"@import|url\(\s*[\"']?(?:https?:)?//", page_html)
    # the one web address in it is the XML namespace of the inline icon
    assert set(re.findall(r"(?:https?|wss?)://[^\s\"'<>)]*", page_html)) == {SVG_NAMESPACE}


def test_recording_holds_one_frame_per_clip_frame_at_its_stamp_and_lasts_the_clip(
    recording: Recording, drive_path: Path
) -> None:
    stamps = stamps_s(drive_path, FIRST, LAST)
    images = recording.ground_images(snapshot.PREFIX_A)
    assert [t for t, _ in images] == pytest.approx(stamps, abs=TIME_TOLERANCE_S)
    assert all(jpeg.startswith(b"\xff\xd8") for _, jpeg in images)
    # every message belongs to a frame: sent at a frame's stamp, nothing in between
    times = sorted({t for t, _ in recording.messages})
    assert times == pytest.approx(stamps, abs=TIME_TOLERANCE_S)
    with Drive(drive_path) as drive:
        expected_s = clip_duration_s(drive, FIRST, LAST)
        interval_s = 1 / drive.frame_rate_hz
    # the last frame stays one frame interval: five frames at 10 Hz play 0.5 s
    assert expected_s == pytest.approx(stamps[-1] + interval_s)
    assert recording.duration_s == pytest.approx(expected_s, abs=TIME_TOLERANCE_S)


def test_each_frame_is_drawn_on_the_fixed_nodes_created_once(recording: Recording) -> None:
    # viser makes the parent frames (prefix, prefix/vehicles, ...) itself, as virtual nodes
    created = [
        m["name"]
        for _, m in recording.messages
        if "props" in m and "name" in m and not m.get("virtual")
    ]
    prefix = snapshot.PREFIX_A + "/"
    ours = [name.removeprefix(prefix) for name in created if name.startswith(prefix)]
    assert sorted(ours) == sorted(FIXED_NODES)  # each once: none added for a later frame
    assert not [name for name in created if name.startswith(snapshot.PREFIX_B)]


def test_clip_frames_are_what_the_inspector_shows_after_the_frames_before_are_replayed(
    recording: Recording, drive_path: Path
) -> None:
    stamps = stamps_s(drive_path, FIRST, LAST)
    for k in (0, len(stamps) - 1):
        expected = engine_view(drive_path, FIRST + k)
        nodes = scene_at(recording, stamps[k])
        prefix = snapshot.PREFIX_A
        labels = [str(n.props["text"]) for n in visible(nodes, f"{prefix}/labels")]
        assert sorted(labels) == sorted(expected.label_texts)
        boxes = sorted(tuple(n.position or ()) for n in visible(nodes, f"{prefix}/vehicles"))
        assert np.allclose(boxes, sorted(map(tuple, expected.vehicle_centres_m)))
    # the first frame's tracks come from the replay: a fresh engine on it confirms none yet
    assert engine_view(drive_path, FIRST).label_texts
    with Drive(drive_path) as drive:
        cold = FusionEngine(PARAMS, drive.camera).process(drive.frame(FIRST))
    assert not bird_eye_view(cold, PARAMS, DEMO_LAYERS)[0].label_texts


def test_same_clip_gives_the_same_page(page_html: str, drive_path: Path) -> None:
    with Drive(drive_path) as drive:
        assert bird_eye_snapshot_html(drive, FIRST, LAST, PARAMS) == page_html


def test_page_opens_on_the_inspectors_top_down_view(recording: Recording) -> None:
    pose = top_down_pose(PARAMS, 0.0, 1)
    sent = {m["type"]: m for _, m in recording.messages if m.get("initial")}
    assert sent["SetCameraPositionMessage"]["position"] == pytest.approx(pose.position_m)
    assert sent["SetCameraLookAtMessage"]["look_at"] == pytest.approx(pose.look_at_m)
    assert sent["SetCameraUpDirectionMessage"]["position"] == pytest.approx(pose.up)


def test_ab_draws_b_beside_a_on_its_own_nodes_and_aims_between_them(
    recording_ab: Recording, drive_path: Path
) -> None:
    stamps = stamps_s(drive_path, FIRST, LAST)
    for prefix in (snapshot.PREFIX_A, snapshot.PREFIX_B):
        images = recording_ab.ground_images(prefix)
        assert [t for t, _ in images] == pytest.approx(stamps, abs=TIME_TOLERANCE_S)
    a_images = recording_ab.ground_images(snapshot.PREFIX_A)
    b_images = recording_ab.ground_images(snapshot.PREFIX_B)
    a_rows, b_rows = (jpeg_size(images[0][1])[0] for images in (a_images, b_images))
    assert b_rows > a_rows  # B's road reaches 10 m further

    nodes = scene_at(recording_ab, 0.0)
    a_ground = nodes[f"{snapshot.PREFIX_A}/ground"].position
    b_ground = nodes[f"{snapshot.PREFIX_B}/ground"].position
    assert a_ground is not None and b_ground is not None
    assert b_ground[1] == pytest.approx(a_ground[1] + b_offset_y_m(PARAMS))
    pose = top_down_pose(PARAMS, b_ground[1] / 2, 2)
    sent = {m["type"]: m for _, m in recording_ab.messages if m.get("initial")}
    assert sent["SetCameraLookAtMessage"]["look_at"] == pytest.approx(pose.look_at_m)
    assert sent["SetCameraPositionMessage"]["position"] == pytest.approx(pose.position_m)


# --- the private server ---------------------------------------------------------------------


class FailingDrive:
    """A drive whose frame `bad` cannot be read."""

    def __init__(self, drive: Drive, bad: int) -> None:
        self._drive = drive
        self._bad = bad

    def __getattr__(self, name: str) -> Any:
        return getattr(self._drive, name)

    def __len__(self) -> int:
        return len(self._drive)

    def frame(self, index: int) -> FrameInput:
        if index == self._bad:
            raise RecordingError(f"{self._drive.path}: frame {index} cannot be read (test)")
        return self._drive.frame(index)


def test_scene_is_recorded_on_a_private_server_on_a_free_port_stopped_after(
    servers: list[tuple[viser.ViserServer, dict[str, Any]]], drive_path: Path
) -> None:
    with Drive(drive_path) as drive:
        bird_eye_snapshot_html(drive, LAST, LAST, PARAMS)
    ((server, asked),) = servers
    assert asked["host"] == "127.0.0.1" and asked["port"] == 0  # loopback, any free port
    assert not listening(server.get_port())


def test_server_is_stopped_when_a_frame_of_the_clip_cannot_be_read(
    servers: list[tuple[viser.ViserServer, dict[str, Any]]], drive_path: Path
) -> None:
    with Drive(drive_path) as drive, pytest.raises(RecordingError, match="frame 17 cannot"):
        bird_eye_snapshot_html(FailingDrive(drive, 17), FIRST, LAST, PARAMS)
    ((server, _),) = servers
    assert not listening(server.get_port())


@pytest.mark.parametrize(
    ("first", "last", "message"),
    [
        (-1, 3, "first_frame: expected a frame of .* \\(0 .. 19\\), got -1"),
        (20, 20, "first_frame: expected a frame of .* \\(0 .. 19\\), got 20"),
        (5, 4, "last_frame: expected a frame of .* from first_frame 5 to 19, got 4"),
        (5, 20, "last_frame: expected a frame of .* from first_frame 5 to 19, got 20"),
    ],
)
def test_frames_that_are_not_a_clip_of_the_drive_are_refused_before_a_server_starts(
    servers: list[tuple[viser.ViserServer, dict[str, Any]]],
    drive_path: Path,
    first: int,
    last: int,
    message: str,
) -> None:
    with Drive(drive_path) as drive, pytest.raises(ValueError, match=message):
        bird_eye_snapshot_html(drive, first, last, PARAMS)
    assert not servers


# --- fusionscope export-scene ---------------------------------------------------------------


def test_export_scene_writes_the_page_of_the_clip_between_from_and_to(
    drive_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "scene.html"
    assert main(["export-scene", str(drive_path), str(out), "--from", "1.5", "--to", "1.9"]) == 0
    captured = capsys.readouterr()
    assert captured.out.strip().startswith(f"{out}: 5 frames, 1.50 to 1.90 s of {drive_path}")
    assert "viser" not in captured.out  # the private server's banner is not printed
    assert f"export-scene {drive_path.name} [" in captured.err and "5/5" in captured.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.html"]
    html = out.read_text(encoding="utf-8")
    images = read_recording(html).ground_images(snapshot.PREFIX_A)
    assert [t for t, _ in images] == pytest.approx(stamps_s(drive_path, FIRST, LAST))


def test_export_scene_with_ab_draws_set_b_beside_a(
    drive_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    b_file = tmp_path / "b.yaml"
    b_file.write_text("motion_stereo:\n  x_max_m: 50.0\n", encoding="utf-8")
    out = tmp_path / "ab.html"
    args = ["export-scene", str(drive_path), str(out), "--from", "1.8", "--ab", str(b_file)]
    assert main(args) == 0
    assert "(A and B beside it)" in capsys.readouterr().out
    recording_b = read_recording(out.read_text(encoding="utf-8"))
    assert len(recording_b.ground_images(snapshot.PREFIX_B)) == 2


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (
            ["--from", "5"],
            "--from 5: expected seconds from the first frame of {drive}, from 0 to 1.9",
        ),
        (
            ["--to", "2.5"],
            "--to 2.5: expected seconds from the first frame of {drive}, from 0 to 1.9",
        ),
        (["--from", "1.5", "--to", "0.5"], "--from 1.5, --to 0.5: expected --from before --to"),
        (["--from", "1.52", "--to", "1.58"], "--from 1.52, --to 1.58: no frame of {drive} between"),
        (["--params", "{tmp}/none.yaml"], "--params: {tmp}/none.yaml: cannot read parameter file"),
        (["--ab", "{tmp}/none.yaml"], "--ab: {tmp}/none.yaml: cannot read parameter file"),
    ],
)
def test_export_scene_refuses_a_clip_or_parameters_it_cannot_use_and_writes_nothing(
    drive_path: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    args: list[str],
    message: str,
) -> None:
    out = tmp_path / "scene.html"
    filled = [a.format(tmp=tmp_path) for a in args]
    assert main(["export-scene", str(drive_path), str(out), *filled]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fusionscope export-scene: ")
    assert message.format(drive=drive_path, tmp=tmp_path) in err
    assert list(tmp_path.iterdir()) == []


def test_export_scene_refuses_a_recording_or_page_it_cannot_use_and_writes_nothing(
    drive_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    cases = [
        (tmp_path / "nowhere", tmp_path / "a.html", "nowhere: expected a recording folder"),
        (drive_path, tmp_path / "a.htm", "a.htm: expected a file name ending in .html, got .htm"),
        (drive_path, tmp_path / "a", "expected a file name ending in .html, got no suffix"),
        (drive_path, tmp_path / "no" / "a.html", f"the folder {tmp_path / 'no'} does not exist"),
    ]
    for recording, out, message in cases:
        assert main(["export-scene", str(recording), str(out)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("fusionscope export-scene: ") and message in err
    assert list(tmp_path.iterdir()) == []


def test_export_scene_refuses_a_negative_time(
    drive_path: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit) as exit_:
        main(["export-scene", str(drive_path), str(tmp_path / "a.html"), "--from", "-1"])
    assert exit_.value.code == 2
    assert "--from: expected a number >= 0, got '-1'" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# --- in the browser -------------------------------------------------------------------------


SCENE_CENTRE_PX = (slice(300, 500), slice(600, 800))  # rows, columns: inside the road texture
GREY_TOLERANCE = 12  # grey levels between the channels of a grey texture's pixel
WHITE = 240  # the page's background, where nothing is drawn, and the scene fading in
TEXTURE_SHARE = 0.5  # of the centre's pixels, at least, once the scene is drawn
POLL_MS = 250


def centre(picture: bytes) -> np.ndarray:
    """The middle of a PNG screenshot, where the road texture is, as (H, W, 3) int16 BGR."""
    image = cv2.imdecode(np.frombuffer(picture, np.uint8), cv2.IMREAD_COLOR)
    assert image is not None
    return image[SCENE_CENTRE_PX].astype(np.int16)


def texture_share(region: np.ndarray) -> float:
    """The share of pixels that are grey (the bird's-eye texture), not the white page."""
    grey = (region.max(axis=2) - region.min(axis=2)) <= GREY_TOLERANCE
    return float(np.mean(grey & (region.max(axis=2) < WHITE)))


def changed(picture: bytes, before: bytes) -> bool:
    """The centre of `picture` is not that of `before`."""
    return bool(np.abs(centre(picture) - centre(before)).max() > GREY_TOLERANCE)


def settled(page: Page) -> bytes:
    """A screenshot of a page that shows the same on two screenshots POLL_MS apart."""
    last = page.screenshot()
    for _ in range(TIMEOUT_MS // POLL_MS):
        page.wait_for_timeout(POLL_MS)
        now = page.screenshot()
        if now == last:
            return now
        last = now
    raise AssertionError(f"the paused page still changed after {TIMEOUT_MS} ms")


def test_page_plays_the_clip_from_a_file_without_a_server(
    drive_path: Path, tmp_path: Path, page: Page
) -> None:
    with Drive(drive_path) as drive:
        last = len(drive) - 1
        html = bird_eye_snapshot_html(drive, 0, last, PARAMS)
        duration_s = clip_duration_s(drive, 0, last)
    path = tmp_path / "scene.html"
    path.write_text(html, encoding="utf-8")
    requested: list[str] = []
    page.on("request", lambda request: requested.append(request.url))

    page.goto(path.as_uri())
    slider = page.locator("[role=slider]")
    # the playback bar's thumb (drawn without a size): the recording is decoded
    slider.wait_for(state="attached", timeout=TIMEOUT_MS)
    assert float(slider.get_attribute("aria-valuemax") or 0) == pytest.approx(duration_s)
    # paused, the picture settles (the scene fades in when it first shows)
    page.keyboard.press("Space")
    paused = settled(page)
    held_at = slider.get_attribute("aria-valuenow")
    SCREENSHOTS.mkdir(parents=True, exist_ok=True)
    (SCREENSHOTS / "test_scene_snapshot_paused.png").write_bytes(paused)
    assert texture_share(centre(paused)) > TEXTURE_SHARE, "no road texture in the view's centre"

    page.keyboard.press("Space")  # playing on, another frame's texture comes
    later = paused
    for _ in range(TIMEOUT_MS // POLL_MS):
        page.wait_for_timeout(POLL_MS)
        later = page.screenshot()
        if changed(later, paused):
            break
    (SCREENSHOTS / "test_scene_snapshot_playing.png").write_bytes(later)
    assert changed(later, paused), f"the scene stood still for {TIMEOUT_MS} ms"
    assert slider.get_attribute("aria-valuenow") != held_at
    assert texture_share(centre(later)) > TEXTURE_SHARE

    remote = [u for u in requested if not u.startswith(("file:", "data:", "blob:"))]
    assert remote == []
