"""`fusionscope export-video` and `app.video_export`: a short clip of a bundled drive decodes
with the frame count, size and rate expected, its boxes lie where the engine's result puts
them, its first frame is what the inspector shows, and bad arguments leave no file."""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt
import pytest
from engine_frames import FRAME, engine_result
from PIL import Image, ImageSequence

from app import overlays
from app.state import DEMO_LAYERS, Layers
from app.video_export import (
    GIF_PICTURE_WIDTH_PX,
    ExportSummary,
    export_video,
    layers_named,
    partial_path,
)
from app.video_frame import video_frame
from app.view import AB_GAP_PX
from core.cli import DEFAULT_RECORDINGS, main
from core.io.drive import Drive
from core.params import Params, params_hash, save_params
from core.search_area import box_pixels

HIGHWAY = DEFAULT_RECORDINGS / "highway"
CLIP = (FRAME, FRAME + 2)  # frame 90 of the highway first: vehicles on it
CHANNEL_TOLERANCE = 40  # H.264 at 4:2:0 blurs a 2 px coloured line with its neighbours
LUMA_BLOCK_TOLERANCE = 16  # mean |difference| of brightness over any 8x8 block
BLOCK_PX = 8
RgbImage = npt.NDArray[np.uint8]


@pytest.fixture(scope="module")
def drive() -> Iterator[Drive]:
    with Drive(HIGHWAY) as d:
        yield d


@pytest.fixture(scope="module")
def mp4(drive: Drive, tmp_path_factory: pytest.TempPathFactory) -> ExportSummary:
    out = tmp_path_factory.mktemp("mp4") / "clip.mp4"
    return export_video(drive, out, *CLIP)


def _decode(path: Path) -> tuple[list[RgbImage], float]:
    """Every frame of a video as RGB, and its frame rate, by OpenCV."""
    capture = cv2.VideoCapture(str(path))
    try:
        fps = capture.get(cv2.CAP_PROP_FPS)
        frames = []
        while True:
            ok, bgr = capture.read()
            if not ok:
                return frames, fps
            frames.append(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
    finally:
        capture.release()


def _outline(rgb: RgbImage, box_px: tuple[int, int, int, int]) -> RgbImage:
    """(N, 3): the pixels of a box's outline `overlays.BOX_THICKNESS_PX` deep, as drawn."""
    c0, r0, c1, r1 = box_px
    rings = []
    for k in range(overlays.BOX_THICKNESS_PX):
        top, bottom = rgb[r0 + k, c0 + k : c1 - k + 1], rgb[r1 - k, c0 + k : c1 - k + 1]
        left, right = rgb[r0 + k : r1 - k + 1, c0 + k], rgb[r0 + k : r1 - k + 1, c1 - k]
        rings += [top, bottom, left, right]
    return np.concatenate(rings)


def _worst_luma_block(a: RgbImage, b: RgbImage) -> float:
    """The largest mean |brightness difference| over the 8x8 blocks of two pictures."""
    grey = [cv2.cvtColor(x, cv2.COLOR_RGB2GRAY).astype(np.float64) for x in (a, b)]
    diff = np.abs(grey[0] - grey[1])
    h, w = (s // BLOCK_PX * BLOCK_PX for s in diff.shape)
    blocks = diff[:h, :w].reshape(h // BLOCK_PX, BLOCK_PX, w // BLOCK_PX, BLOCK_PX)
    return float(blocks.mean(axis=(1, 3)).max())


def test_mp4_decodes_with_the_clips_frames_size_and_the_drives_rate(
    mp4: ExportSummary, drive: Drive
) -> None:
    frames, fps = _decode(mp4.path)
    assert len(frames) == mp4.frames == CLIP[1] - CLIP[0] + 1
    assert frames[0].shape == (mp4.size_px[1], mp4.size_px[0], 3)
    assert mp4.size_px[0] == drive.camera.intrinsics.width_px
    assert mp4.size_px[1] > drive.camera.intrinsics.height_px  # the banner under it
    assert all(s % 2 == 0 for s in mp4.size_px)
    assert fps == pytest.approx(drive.frame_rate_hz)
    assert mp4.file_bytes == mp4.path.stat().st_size
    assert not partial_path(mp4.path).exists()


def _top_level_boxes(path: Path) -> list[bytes]:
    """The types of an MP4 file's top-level boxes, in file order (ISO 14496-12: a 32-bit
    big-endian size, then the type; size 1: a 64-bit size follows)."""
    data = path.read_bytes()
    types, at = [], 0
    while at + 8 <= len(data):
        size = int.from_bytes(data[at : at + 4], "big")
        if size == 1:
            size = int.from_bytes(data[at + 8 : at + 16], "big")
        types.append(data[at + 4 : at + 8])
        if size < 8:
            break
        at += size
    return types


def test_mp4_plays_while_it_loads_its_index_comes_first(mp4: ExportSummary) -> None:
    boxes = _top_level_boxes(mp4.path)
    assert boxes.index(b"moov") < boxes.index(b"mdat"), boxes


def test_vehicle_boxes_are_drawn_where_the_engines_result_puts_them(
    mp4: ExportSummary,
) -> None:
    frames, _ = _decode(mp4.path)
    result = engine_result("highway", FRAME)  # what the inspector shows
    # the demo draws the confirmed vehicle tracks measured on the frame, with their bodies
    shown = overlays.measured_shown(result.tracked_vehicles)
    assert shown, "frame 90 of the highway has confirmed vehicles"
    for track in shown:
        box = box_pixels(track.outline_px)
        on = np.median(_outline(frames[0], box), axis=0)
        assert np.abs(on - overlays.VEHICLE_COLOUR).max() <= CHANNEL_TOLERANCE, (box, on)
        c0, r0, c1, r1 = box
        beside = (c0 - 12, r0 - 12, c1 - 12, r1 - 12)  # the same outline moved off the box
        off = np.median(_outline(frames[0], beside), axis=0)
        assert np.abs(off - overlays.VEHICLE_COLOUR).max() > CHANNEL_TOLERANCE, (beside, off)


def test_first_frame_is_what_the_inspector_shows_for_it(mp4: ExportSummary, drive: Drive) -> None:
    frames, _ = _decode(mp4.path)
    composed = video_frame(
        drive,
        DEMO_LAYERS,
        drive.frame(FRAME),
        [engine_result("highway", FRAME)],
        [params_hash(Params())],
    )
    assert _worst_luma_block(frames[0], composed) <= LUMA_BLOCK_TOLERANCE
    other = video_frame(
        drive,
        DEMO_LAYERS,
        drive.frame(FRAME + 1),
        [engine_result("highway", FRAME + 1)],
        [params_hash(Params())],
    )
    assert _worst_luma_block(frames[0], other) > LUMA_BLOCK_TOLERANCE  # the check sees


def test_ab_export_is_twice_as_wide_plus_the_gap(
    mp4: ExportSummary, drive: Drive, tmp_path: Path
) -> None:
    b = dataclasses.replace(
        Params(), tracking=dataclasses.replace(Params().tracking, confirm_frames=1)
    )
    out = export_video(drive, tmp_path / "ab.mp4", FRAME, FRAME + 1, params_b=b)
    frames, _ = _decode(out.path)
    assert len(frames) == 2
    assert out.size_px[0] == 2 * mp4.size_px[0] + AB_GAP_PX
    assert frames[0].shape[1] == out.size_px[0]


def test_gif_decodes_with_the_clips_frames_scaled_and_timed(drive: Drive, tmp_path: Path) -> None:
    out = export_video(drive, tmp_path / "clip.gif", *CLIP)
    with Image.open(out.path) as gif:
        frames = [f.convert("RGB") for f in ImageSequence.Iterator(gif)]
        assert gif.info["loop"] == 0
        assert gif.info["duration"] == pytest.approx(1000 / drive.frame_rate_hz)
    assert len(frames) == CLIP[1] - CLIP[0] + 1
    assert frames[0].size == out.size_px
    assert out.size_px[0] == GIF_PICTURE_WIDTH_PX
    narrow = export_video(drive, tmp_path / "narrow.gif", FRAME, FRAME, gif_width_px=320)
    with Image.open(narrow.path) as gif:
        assert gif.size[0] == 320 and gif.n_frames == 1


def test_failed_export_leaves_the_old_file_and_no_partial(drive: Drive, tmp_path: Path) -> None:
    out = tmp_path / "clip.mp4"
    out.write_bytes(b"the old video")

    def interrupt(done: int, total: int) -> None:
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        export_video(drive, out, *CLIP, progress=interrupt)
    assert out.read_bytes() == b"the old video"
    assert list(tmp_path.iterdir()) == [out]


def test_export_refuses_a_clip_outside_the_drive(drive: Drive, tmp_path: Path) -> None:
    with pytest.raises(ValueError, match=r"first_frame: expected a frame of .*, got 150"):
        export_video(drive, tmp_path / "x.mp4", 150, 150)
    with pytest.raises(ValueError, match=r"last_frame: expected .* first_frame 5 to 149, got 4"):
        export_video(drive, tmp_path / "x.mp4", 5, 4)
    with pytest.raises(ValueError, match=r"gif_width_px: only for a \.gif"):
        export_video(drive, tmp_path / "x.mp4", 5, 5, gif_width_px=100)
    assert list(tmp_path.iterdir()) == []


def test_layers_by_name_switch_on_those_only() -> None:
    chosen = layers_named("radar, vehicles")
    assert [n for n in Layers.names() if getattr(chosen, n)] == ["radar", "vehicles"]
    assert not any(getattr(layers_named(""), n) for n in Layers.names())


def test_cli_exports_a_clip_and_reports_its_speed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "clip.mp4"
    args = ["export-video", str(HIGHWAY), str(out), "--from", "9", "--to", "9.2"]
    assert main([*args, "--layers", "vehicles,radar"]) == 0
    captured = capsys.readouterr()
    frames, _ = _decode(out)
    assert len(frames) == 3
    assert "3 frames (90-92" in captured.out and "x real time" in captured.out
    assert "frames/s" in captured.out
    assert "export-video highway [" in captured.err  # the progress bar


@pytest.fixture()
def bad_params(tmp_path: Path) -> Path:
    path = tmp_path / "bad.yaml"
    save_params(Params(), path)
    path.write_text(path.read_text().replace("confirm_frames:", "confirm_frame:"))
    return path


@pytest.mark.parametrize(
    ("extra", "out_name", "expected"),
    [
        (["--layers", "radar,cars"], "x.mp4", "--layers radar,cars: expected comma-separated"),
        (["--from", "20"], "x.mp4", "--from 20: expected"),
        (["--from", "5", "--to", "2"], "x.mp4", "--from 5, --to 2: expected --from before --to"),
        ([], "x.avi", "expected a file name ending in .mp4 or .gif, got .avi"),
        ([], "missing/x.mp4", "the folder"),
        (["--params", "BAD"], "x.mp4", "--params: "),
        (["--ab", "BAD"], "x.gif", "--ab: "),
        (["--gif-width", "200"], "x.mp4", "--gif-width: only for a .gif"),
    ],
)
def test_cli_refuses_bad_arguments_by_name_and_writes_nothing(
    extra: list[str],
    out_name: str,
    expected: str,
    bad_params: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    out = out_dir / out_name
    extra = [str(bad_params) if a == "BAD" else a for a in extra]
    assert main(["export-video", str(HIGHWAY), str(out), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fusionscope export-video: ") and expected in err, err
    if out_name.startswith("missing"):
        assert str(out.parent) in err
    assert list(out_dir.iterdir()) == []


def test_cli_never_writes_over_a_folder(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = tmp_path / "clip.mp4"
    folder.mkdir()
    assert main(["export-video", str(HIGHWAY), str(folder), "--to", "0.1"]) == 2
    assert "expected a file to write, got a folder" in capsys.readouterr().err
    assert folder.is_dir() and list(folder.iterdir()) == []
    assert list(tmp_path.iterdir()) == [folder]


def test_the_speed_after_the_first_frame_leaves_out_its_warm_up() -> None:
    summary = ExportSummary(Path("x.mp4"), 0, 100, (640, 570), 10.0, 1, 3.0, 3.0, 1.0)
    assert summary.real_time_multiple == pytest.approx(101 / 10 / 3.0)
    assert summary.steady_real_time_multiple == pytest.approx(100 / 10 / 2.0)
