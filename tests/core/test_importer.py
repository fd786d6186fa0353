"""`fusionscope import`: recordings from videos, a still with CAN, and ROS bags, opened with
Drive; the resampling, the stamps, the calibration scaling, and bad input through the CLI."""

from __future__ import annotations

import filecmp
import math
import struct
from pathlib import Path
from typing import Any

import cantools
import cv2
import numpy as np
import numpy.typing as npt
import pytest
import yaml
from rosbags import rosbag1, rosbag2
from rosbags.rosbag2 import StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from core.camera import Intrinsics
from core.cli import main
from core.io import Drive, load_calibration, load_manifest, radar_msgs
from core.io.calibration import save_camera_info
from core.io.errors import RecordingError
from core.io.importers.calibration_spec import scale_intrinsics
from core.io.importers.can_mapping import MAPPING_EXAMPLE
from core.io.importers.finish import read_grey
from core.io.manifest import BagStream, RadarCanSource
from core.io.writer import png_image_message, vehicle_dbc_path

NS = 1_000_000_000

RAV4_MAPPING = MAPPING_EXAMPLE  # the documented example is the RAV4's
RAV4_TIME_S = 46408.547  # realdata README: the camera frame's time on the CAN clock
RAV4_RADAR_X_M = 2.7
# The first SPEED frame (0xB4 at 46408.585 s, after the image) carries 0x0B7A in bytes 5-6:
# 2938 * 0.01 km/h = 29.38 km/h; speed before the first sample is held from it.
RAV4_SPEED_MPS = 29.38 / 3.6

SYNTH_SPEED_MAPPING = """\
can:
  speed: {message: SPEED, signal: SPEED, unit: km/h}
  yaw_rate: {message: KINEMATICS, signal: YAW_RATE, unit: deg/s}
"""


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def write_ramp_video(path: Path, frames: int, fps: float, size: tuple[int, int]) -> None:
    """A lossless (FFV1) video whose frame k is uniformly grey 8 * k: its index, readable back."""
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"FFV1"), fps, size)
    assert writer.isOpened()
    for k in range(frames):
        writer.write(np.full((size[1], size[0], 3), 8 * k, dtype=np.uint8))
    writer.release()


# --- videos ------------------------------------------------------------------------------


def test_each_output_time_takes_the_nearest_source_frame(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=30, fps=20.0, size=(320, 240))  # 0 .. 1.45 s
    out = tmp_path / "rec"
    code, _, err = run(capsys, "import", "video", video, out, "--fps", "3", "--hfov-deg", "60")
    assert code == 0, err
    with Drive(out) as drive:
        # Output times k/3 s up to the last source frame (1.45 s); source frame j at j/20 s.
        times_s = [k / 3 for k in range(5)]
        nearest = [round(t * 20.0) for t in times_s]  # 0, 7, 13, 20, 27
        assert len(drive) == 5
        assert drive.times_ns.tolist() == [round(t * NS) for t in times_s]
        assert [int(drive.frame(k).image[0, 0]) for k in range(5)] == [8 * j for j in nearest]
        assert drive.frame(0).image.shape == (480, 640)  # enlarged to the default width


def test_a_clip_on_the_video_clock_with_a_start_stamp(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=30, fps=20.0, size=(320, 240))
    out = tmp_path / "clip"
    start_ns = 5 * NS
    code, _, err = run(
        capsys,
        *("import", "video", video, out, "--from-s", "0.5", "--to-s", "1.0"),
        *("--start-ns", start_ns, "--width", "160", "--hfov-deg", "60"),
    )
    assert code == 0, err
    with Drive(out) as drive:
        # 0.5, 0.6, ..., 1.0 s on the video clock: source frames 10, 12, ..., 20.
        assert drive.times_ns.tolist() == [start_ns + (5 + k) * NS // 10 for k in range(6)]
        assert [int(drive.frame(k).image[0, 0]) for k in range(6)] == [
            8 * j for j in range(10, 21, 2)
        ]
        assert drive.frame(0).image.shape == (120, 160)


def test_udacity_guardrail_video(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "guardrail"
    video = realdata / "udacity-highway" / "guardrail_960x540.mp4"
    code, printed, err = run(
        capsys,
        *("import", "video", video, out, "--assume-speed-mps", "27"),
        *("--fx", "1000", "--cx", "470", "--cy", "275", "--pitch-rad", "0.02"),
    )
    assert code == 0, err
    assert f"{out}: 89 frames, 640x360" in printed
    with Drive(out) as drive:
        # 221 frames at 25 fps last 8.8 s: output times 0, 0.1, ..., 8.8 s.
        assert len(drive) == 89
        assert np.all(np.diff(drive.times_ns) == 100_000_000) and drive.times_ns[0] == 0
        assert drive.frame(88).image.shape == (360, 640)
        assert drive.name == "guardrail_960x540"
        assert drive.manifest.assumptions.speed_mps == 27.0
        assert drive.manifest.assumptions.yaw_rate_radps == 0.0
        assert drive.manifest.can is None and drive.manifest.radar is None
        i = drive.camera.intrinsics
        s = 640 / 960  # the resize; pixel centres map as (u + 0.5) * s - 0.5
        assert (i.fx_px, i.fy_px) == pytest.approx((1000 * s, 1000 * s))
        assert (i.cx_px, i.cy_px) == pytest.approx((470.5 * s - 0.5, 275.5 * s - 0.5))
        assert drive.camera.rows_used_px is None
        e = drive.camera.extrinsics
        assert (e.height_m, e.x_m, e.pitch_rad) == (1.2, 1.5, 0.02)
        description = drive.manifest.description
        assert "guardrail_960x540.mp4" in description and "assumed 27 m/s" in description


def test_drive_gives_the_assumed_speed(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "guardrail"
    video = realdata / "udacity-highway" / "guardrail_960x540.mp4"
    code, _, err = run(
        capsys,
        *("import", "video", video, out, "--to-s", "0.3", "--assume-speed-mps", "27"),
        *("--hfov-deg", "60"),
    )
    assert code == 0, err
    with Drive(out) as drive:
        assert drive.frame(1).speed_mps == 27.0 and drive.frame(1).yaw_rate_radps == 0.0


def test_udacity_vehicles_video_with_the_chessboard_calibration(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    camera_info = tmp_path / "camera_info.yaml"
    chessboard = realdata / "udacity-highway" / "chessboard"
    assert run(capsys, "calibrate", chessboard, "--board", "9x6", "--out", camera_info)[0] == 0
    out = tmp_path / "vehicles"
    video = realdata / "udacity-highway" / "vehicles_1280x720.mp4"
    code, printed, err = run(
        capsys,
        *("import", "video", video, out, "--camera-info", camera_info, "--name", "cars"),
        *("--assume-speed-mps", "26", "--assume-yaw-rate-radps", "0.01"),
    )
    assert code == 0, err
    assert "note:" not in printed
    with Drive(out) as drive:
        assert len(drive) == 15  # 38 frames at 25 fps: 0 .. 1.48 s -> 0, 0.1, .., 1.4 s
        assert np.all(np.diff(drive.times_ns) == 100_000_000)
        assert drive.frame(14).image.shape == (360, 640)
        assert drive.name == "cars"
        assert drive.manifest.assumptions.yaw_rate_radps == 0.01
        i = drive.camera.intrinsics
    cal = yaml.safe_load(camera_info.read_text())
    fx, _, cx, _, fy, cy = cal["camera_matrix"]["data"][:6]
    assert i.fx_px == pytest.approx(fx / 2) and i.fy_px == pytest.approx(fy / 2)
    assert i.cx_px == pytest.approx((cx + 0.5) / 2 - 0.5)
    assert i.cy_px == pytest.approx((cy + 0.5) / 2 - 0.5)
    assert list(i.distortion) == pytest.approx(cal["distortion_coefficients"]["data"])


def test_a_video_without_speed_gets_a_note(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=4, fps=10.0, size=(64, 48))
    code, printed, _ = run(capsys, "import", "video", video, tmp_path / "r", "--hfov-deg", "50")
    assert code == 0
    assert "note: no speed" in printed and "motion stereo cannot work" in printed
    assert load_manifest(tmp_path / "r").assumptions.speed_mps is None


def test_scaling_keeps_the_image_centre_and_the_field_of_view() -> None:
    i = Intrinsics.from_fov(960, 540, math.radians(70))
    scaled = scale_intrinsics(i, 640, 360)
    centred = Intrinsics.from_fov(640, 360, math.radians(70))
    assert (scaled.fx_px, scaled.cx_px, scaled.cy_px) == pytest.approx(
        (centred.fx_px, centred.cx_px, centred.cy_px)
    )
    assert scaled.horizontal_fov_rad == pytest.approx(math.radians(70))


# --- video with CAN, the RAV4 still ------------------------------------------------------


def rav4_flags(realdata: Path, mapping: Path) -> list[str | Path]:
    d = realdata / "comma2k19-rav4"
    return [
        *("--can", d / "rav4_seg40.log.gz", "--mapping", mapping),
        *("--dbc", d / "toyota_rav4_powertrain.dbc", "--dbc", d / "toyota_adas_radar.dbc"),
    ]


def test_a_video_on_the_can_clock_gets_speed_from_can(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=20, fps=10.0, size=(64, 48))
    mapping = tmp_path / "speed.yaml"
    mapping.write_text(RAV4_MAPPING.split("radar:")[0])
    out = tmp_path / "rav4_video"
    code, _, err = run(
        capsys,
        *("import", "video", video, out, "--video-start-s", "46420", "--hfov-deg", "50"),
        *rav4_flags(realdata, mapping),
    )
    assert code == 0, err
    m = load_manifest(out)
    assert m.can is not None and m.can.bus.dbc == ("toyota_rav4_powertrain.dbc",)
    assert m.radar is None
    with Drive(out) as drive:
        assert drive.times_ns[0] == 46420 * NS and len(drive) == 20
        # The CAN-tests' range for this drive (tests/core/io/test_canlog.py).
        assert all(7.0 < drive.frame(k).speed_mps < 23.0 for k in (0, 19))


def import_rav4(realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> Path:
    mapping = tmp_path / "rav4_mapping.yaml"
    mapping.write_text(RAV4_MAPPING)
    out = tmp_path / "rav4"
    code, printed, err = run(
        capsys,
        *("import", "still", realdata / "comma2k19-rav4" / "first_frame.png", out),
        *("--time-s", str(RAV4_TIME_S), *rav4_flags(realdata, mapping)),
        *("--fx", "910", "--fy", "910", "--cx", "582", "--cy", "437"),
        *("--camera-height-m", "1.2", "--radar-x-m", str(RAV4_RADAR_X_M)),
        *("--max-radar-skew-ms", "50"),
    )
    assert code == 0, err
    assert "1 frames, 640x481" in printed
    # The image is 38 ms before the log's first frame: accepted, with a note.
    assert "outside the CAN log's span 46408.585-46468.578 s" in printed
    return out


def test_rav4_still_with_can_writes_manifest_and_calibration_and_opens(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = import_rav4(realdata, tmp_path, capsys)
    m = load_manifest(out)
    assert m.name == "first_frame"
    assert m.can is not None
    assert m.can.bus.log == "rav4_seg40.log.gz" and m.can.bus.channel == "can0"
    assert m.can.bus.dbc == ("toyota_rav4_powertrain.dbc",)
    assert (m.can.speed.message, m.can.speed.signal, m.can.speed.unit) == ("SPEED", "SPEED", "km/h")
    assert (m.can.yaw_rate.message, m.can.yaw_rate.unit) == ("KINEMATICS", "deg/s")
    assert isinstance(m.radar, RadarCanSource)
    assert m.radar.bus.dbc == ("toyota_adas_radar.dbc",) and m.radar.bus.channel == "can1"
    assert m.radar.messages == "TRACK_A_*"
    assert (m.radar.lateral.signal, m.radar.lateral.sign) == ("LAT_DIST", -1)
    assert m.radar.valid is not None and m.radar.range_rate is not None
    assert m.assumptions.speed_mps is None and m.max_radar_skew_ms == 50.0
    source = realdata / "comma2k19-rav4"
    for name in ("rav4_seg40.log.gz", "toyota_rav4_powertrain.dbc", "toyota_adas_radar.dbc"):
        assert filecmp.cmp(out / name, source / name, shallow=False)
    cal = load_calibration(out / "calibration.yaml")
    i = cal.camera.intrinsics
    assert (i.width_px, i.height_px) == (640, 481)  # 874 * 640 / 1164 = 480.5
    sx, sy = 640 / 1164, 481 / 874
    assert (i.fx_px, i.fy_px) == pytest.approx((910 * sx, 910 * sy))
    assert (i.cx_px, i.cy_px) == pytest.approx((582.5 * sx - 0.5, 437.5 * sy - 0.5))
    assert cal.radar_mount.x_m == RAV4_RADAR_X_M and cal.camera.extrinsics.height_m == 1.2
    # and it opens, with speed and radar tracks
    with Drive(out) as drive:
        assert len(drive) == 1 and drive.times_ns[0] == round(RAV4_TIME_S * NS)
        frame = drive.frame(0)
        assert frame.image.shape == (481, 640)
        assert frame.speed_mps == pytest.approx(RAV4_SPEED_MPS, abs=0.01)
        # README: tracks at 29.3 m straight ahead and at 18.3 m, 2.9 m to the right -- in the
        # vehicle frame: the first scan's LONG_DIST is 26.6 m and 15.56 m, plus the 2.7 m mount.
        ahead = [t for t in frame.radar if abs(t.x_m - 29.3) < 0.2 and abs(t.y_m) < 0.2]
        right = [t for t in frame.radar if abs(t.x_m - 18.3) < 0.2 and abs(t.y_m + 2.9) < 0.2]
        assert ahead and right


def test_rav4_still_a_time_outside_the_can_log_is_refused(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mapping = tmp_path / "m.yaml"
    mapping.write_text(RAV4_MAPPING)
    image = realdata / "comma2k19-rav4" / "first_frame.png"
    out = tmp_path / "rav4"
    code, _, err = run(
        capsys,
        *("import", "still", image, out, "--time-s", "46500.0", "--hfov-deg", "60"),
        *("--radar-x-m", "2.7", *rav4_flags(realdata, mapping)),
    )
    assert code == 2
    assert err.startswith("fusionscope import still: --time-s 46500.000: ")
    assert "outside the CAN log's span 46408.585-46468.578 s" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.yaml"]


def test_rav4_radar_without_a_mount_is_refused(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mapping = tmp_path / "m.yaml"
    mapping.write_text(RAV4_MAPPING)
    image = realdata / "comma2k19-rav4" / "first_frame.png"
    code, _, err = run(
        capsys,
        *("import", "still", image, tmp_path / "r", "--time-s", str(RAV4_TIME_S)),
        *("--hfov-deg", "60", *rav4_flags(realdata, mapping)),
    )
    assert code == 2 and "--radar-x-m: the recording has radar" in err


@pytest.mark.parametrize(
    ("mapping", "message"),
    [
        (
            RAV4_MAPPING.replace("speed:", "speeed:"),
            "can.speeed: unknown key; known keys here:",
        ),
        ("can:\n  log: x.log\n", "can.log: not allowed in a mapping file"),
        ("cans: {}\n", "cans: unknown key; known keys here: can, radar"),
        ("{}\n", "expected a `can:` section"),
        (
            "radar:\n  messages: TRACK_A_*\n",
            "radar: expected one key `can:` holding the radar's CAN fields",
        ),
        (
            RAV4_MAPPING.replace("unit: km/h", "unit: knots"),
            "can.speed.unit: expected one of m/s, km/h, mph, got 'knots'",
        ),
        (
            RAV4_MAPPING.replace("message: SPEED,", "message: SPEEDO,"),
            "message 'SPEEDO' is in none of the DBC files",
        ),
        (
            RAV4_MAPPING.replace("TRACK_A_*", "TRACK_Z_*"),
            "radar.can.messages: the pattern 'TRACK_Z_*' matches no message",
        ),
        (
            RAV4_MAPPING.replace("LONG_DIST", "LONG_DISTANCE"),
            "has no signal 'LONG_DISTANCE'",
        ),
        (
            RAV4_MAPPING.replace("channel: can0", "channel: can3"),
            "on channel can3, no frames of SPEED (0x0B4; channels with it: can0)",
        ),
    ],
)
def test_a_bad_mapping_is_refused_naming_the_file_and_key(
    realdata: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    mapping: str,
    message: str,
) -> None:
    path = tmp_path / "mapping.yaml"
    path.write_text(mapping)
    image = realdata / "comma2k19-rav4" / "first_frame.png"
    code, _, err = run(
        capsys,
        *("import", "still", image, tmp_path / "r", "--time-s", str(RAV4_TIME_S)),
        *("--hfov-deg", "60", "--radar-x-m", "2.7", *rav4_flags(realdata, path)),
    )
    assert code == 2
    assert err.startswith("fusionscope import still: ")
    assert message in err, err
    assert "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mapping.yaml"]


# --- bad input ---------------------------------------------------------------------------


def test_an_unreadable_video_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = tmp_path / "notes.mp4"
    video.write_text("not a video")
    code, _, err = run(capsys, "import", "video", video, tmp_path / "r", "--hfov-deg", "60")
    assert code == 2
    assert (
        err == f"fusionscope import video: {video}: cannot open as a video; expected a file "
        "OpenCV reads (mp4, avi, mkv, ...)\n"
    )
    assert not (tmp_path / "r").exists()


def test_a_missing_video_or_still_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code, _, err = run(
        capsys, "import", "video", tmp_path / "no.mp4", tmp_path / "r", "--hfov-deg", "60"
    )
    assert (code, err) == (2, f"fusionscope import video: {tmp_path / 'no.mp4'}: video not found\n")
    code, _, err = run(
        capsys, "import", "still", tmp_path / "no.png", tmp_path / "r", "--hfov-deg", "60"
    )
    assert (code, err) == (2, f"fusionscope import still: {tmp_path / 'no.png'}: image not found\n")


def test_a_still_declaring_a_huge_image_is_refused_before_it_is_decoded(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    ok, buf = cv2.imencode(".png", np.zeros((48, 64), np.uint8))
    assert ok
    bomb = bytearray(buf.tobytes())
    bomb[16:24] = struct.pack(">II", 40_000, 40_000)  # IHDR width, height
    still = tmp_path / "bomb.png"
    still.write_bytes(bytes(bomb))

    def no_decoding(*args: object) -> None:
        raise AssertionError("decoded")

    monkeypatch.setattr(cv2, "imread", no_decoding)
    code, _, err = run(capsys, "import", "still", still, tmp_path / "r", "--hfov-deg", "60")
    assert (code, err) == (
        2,
        f"fusionscope import still: {still}: the image declares 40000x40000 pixels, more than "
        "the 67,108,864 an import decodes; not decoded\n",
    )
    assert not (tmp_path / "r").exists()
    with pytest.raises(RecordingError, match=r"declares 40000x40000 pixels, expected 64x48 \(f"):
        read_grey(still, (64, 48), "f")


def test_a_non_empty_out_dir_is_refused_and_left_alone(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=3, fps=10.0, size=(64, 48))
    out = tmp_path / "out"
    out.mkdir()
    (out / "keep.txt").write_text("mine")
    code, _, err = run(capsys, "import", "video", video, out, "--hfov-deg", "60")
    assert code == 2
    assert f"{out}: expected a new or empty folder for the recording, it is not empty" in err
    assert [p.name for p in out.iterdir()] == ["keep.txt"]
    code, _, err = run(capsys, "import", "video", video, out / "keep.txt", "--hfov-deg", "60")
    assert (
        code == 2
        and "keep.txt: expected a new or empty folder for the recording, it is a file" in err
    )
    assert (out / "keep.txt").read_text() == "mine"


def test_an_empty_out_dir_is_filled(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=3, fps=10.0, size=(64, 48))
    out = tmp_path / "out"
    out.mkdir()
    assert run(capsys, "import", "video", video, out, "--hfov-deg", "60")[0] == 0
    assert (out / "recording.yaml").is_file()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "ramp.mkv"]


def test_an_error_after_writing_began_leaves_nothing_behind(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=10, fps=10.0, size=(64, 48))
    code, _, err = run(
        capsys, "import", "video", video, tmp_path / "r", "--from-s", "5", "--hfov-deg", "60"
    )
    assert code == 2
    assert "no frames between --from-s 5 and the end; the video lasts 0.9 s" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ramp.mkv"]


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        ([], "calibration: expected exactly one of --camera-info FILE, --hfov-deg D and --fx"),
        (["--hfov-deg", "60", "--fx", "500"], "got --hfov-deg, --fx"),
        (["--hfov-deg", "60", "--cy", "20"], "--cy: only with --fx"),
        (["--hfov-deg", "60", "--radar-y-m", "1"], "--radar-y-m: only with --radar-x-m"),
        (["--hfov-deg", "60", "--mapping", "m.yaml"], "CAN input also needs --can, --dbc"),
        (["--hfov-deg", "60", "--video-start-s", "3"], "--video-start-s: only with --can"),
        (
            ["--hfov-deg", "60", "--to-s", "0.5", "--from-s", "1"],
            "--to-s 0.5: expected a time after",
        ),
        (["--hfov-deg", "200"], "--hfov-deg: expected a field of view in (0, 180) degrees"),
        (["--camera-info", "nowhere.yaml"], "nowhere.yaml: camera_info file not found"),
    ],
)
def test_flags_that_do_not_go_together_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], message: str
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=3, fps=10.0, size=(64, 48))
    code, _, err = run(capsys, "import", "video", video, tmp_path / "r", *flags)
    assert code == 2
    assert err.startswith("fusionscope import video: ") and message in err, err


def test_can_with_a_video_needs_its_start_time(
    realdata: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=3, fps=10.0, size=(64, 48))
    mapping = tmp_path / "m.yaml"
    mapping.write_text(RAV4_MAPPING)
    code, _, err = run(
        capsys,
        *("import", "video", video, tmp_path / "r", "--hfov-deg", "60"),
        *rav4_flags(realdata, mapping),
    )
    assert code == 2 and "--video-start-s: required with --can" in err


def test_bad_numbers_are_refused_by_the_parser(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for flags in (["--fps", "0"], ["--width", "-3"], ["--assume-speed-mps", "nan"]):
        with pytest.raises(SystemExit) as exit_:
            main(["import", "video", "v.mp4", str(tmp_path / "r"), "--hfov-deg", "60", *flags])
        assert exit_.value.code == 2
        assert f"argument {flags[0]}: expected" in capsys.readouterr().err


def test_a_camera_info_of_another_aspect_ratio_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    video = tmp_path / "ramp.mkv"
    write_ramp_video(video, frames=3, fps=10.0, size=(64, 48))
    info = tmp_path / "wide.yaml"
    save_camera_info(Intrinsics(100.0, 100.0, 63.5, 23.5, 128, 48), info)
    code, _, err = run(capsys, "import", "video", video, tmp_path / "r", "--camera-info", info)
    assert code == 2
    assert f"--camera-info {info}: calibrated at 128x48, but the video is 64x48" in err


# --- bags --------------------------------------------------------------------------------

BAG_T0_NS = 1_700_000_000 * NS
BAG_FRAMES = 5
BAG_SIZE = (64, 48)
RADAR_RETURN = (20.0, 0.1)  # range m, azimuth rad
BAG_SPEED_KMH = 72.0


def bag_image(k: int) -> npt.NDArray[np.uint8]:
    """Frame k of the bags: a horizontal ramp shifted by k (a known, non-uniform image)."""
    w, h = BAG_SIZE
    return np.asarray((np.arange(w)[None, :] * 3 + 7 * k + np.zeros((h, 1))) % 256, np.uint8)


def can_frames_of_the_synthetic_car(t_ns: int) -> list[tuple[int, bytes]]:
    """SPEED (BAG_SPEED_KMH) and KINEMATICS (yaw rate 0) as the synthetic car's DBC encodes."""
    db = cantools.database.load_file(str(vehicle_dbc_path()))
    speed = db.get_message_by_name("SPEED")
    kinematics = db.get_message_by_name("KINEMATICS")
    return [
        (speed.frame_id, bytes(speed.encode({"SPEED": BAG_SPEED_KMH, "ENCODER": 0}))),
        (kinematics.frame_id, bytes(kinematics.encode({"YAW_RATE": 0.0}))),
    ]


def ros1_typestore() -> Typestore:
    store = get_typestore(Stores.ROS1_NOETIC)
    store.register(
        get_types_from_msg(
            radar_msgs.RADAR_MSG_DEFINITIONS[radar_msgs.CAN_FRAME], radar_msgs.CAN_FRAME
        )
    )
    return store


def header(store: Typestore, t_ns: int, ros1: bool) -> Any:
    sec, nanosec = divmod(t_ns, NS)
    stamp = store.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nanosec)
    extra = {"seq": 0} if ros1 else {}
    return store.types["std_msgs/msg/Header"](**extra, stamp=stamp, frame_id="")


def can_msg(store: Typestore, t_ns: int, frame_id: int, data: bytes, ros1: bool) -> Any:
    return store.types[radar_msgs.CAN_FRAME](
        header=header(store, t_ns, ros1),
        id=frame_id,
        is_rtr=False,
        is_extended=False,
        is_error=False,
        dlc=len(data),
        data=np.frombuffer(data.ljust(8, b"\0"), dtype=np.uint8).copy(),
    )


def write_ros2_bag(path: Path) -> None:
    """MCAP: /cam CompressedImage (PNG), /radar RadarScan (one return), /can can_msgs/Frame."""
    store = radar_msgs.typestore()
    with rosbag2.Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        cam = writer.add_connection("/cam", radar_msgs.COMPRESSED_IMAGE, typestore=store)
        radar = writer.add_connection("/radar", radar_msgs.RADAR_SCAN, typestore=store)
        can_ = writer.add_connection("/can", radar_msgs.CAN_FRAME, typestore=store)
        for k in range(BAG_FRAMES):
            t = BAG_T0_NS + k * NS // 10
            writer.write(cam, t, png_image_message(store, t, bag_image(k)))
            ret = store.types[radar_msgs.RADAR_RETURN](
                range=np.float32(RADAR_RETURN[0]),
                azimuth=np.float32(RADAR_RETURN[1]),
                elevation=np.float32(0.0),
                doppler_velocity=np.float32(-1.0),
                amplitude=np.float32(10.0),
            )
            scan = store.types[radar_msgs.RADAR_SCAN](header=header(store, t, False), returns=[ret])
            writer.write(radar, t, store.serialize_cdr(scan, radar_msgs.RADAR_SCAN))
            for frame_id, data in can_frames_of_the_synthetic_car(t):
                msg = can_msg(store, t, frame_id, data, False)
                writer.write(can_, t, store.serialize_cdr(msg, radar_msgs.CAN_FRAME))


def write_ros1_bag(path: Path) -> None:
    """ROS 1: /image sensor_msgs/Image mono8, /can can_msgs/Frame."""
    store = ros1_typestore()
    with rosbag1.Writer(path) as writer:
        img = writer.add_connection("/image", radar_msgs.IMAGE, typestore=store)
        can_ = writer.add_connection("/can", radar_msgs.CAN_FRAME, typestore=store)
        w, h = BAG_SIZE
        for k in range(BAG_FRAMES):
            t = BAG_T0_NS + k * NS // 10
            msg = store.types[radar_msgs.IMAGE](
                header=header(store, t, True),
                height=h,
                width=w,
                encoding="mono8",
                is_bigendian=0,
                step=w,
                data=bag_image(k).ravel(),
            )
            writer.write(img, t, store.serialize_ros1(msg, radar_msgs.IMAGE))
            for frame_id, data in can_frames_of_the_synthetic_car(t):
                frame = can_msg(store, t, frame_id, data, True)
                writer.write(can_, t, store.serialize_ros1(frame, radar_msgs.CAN_FRAME))


def bag_can_flags(tmp_path: Path) -> list[str | Path]:
    mapping = tmp_path / "speed.yaml"
    mapping.write_text(SYNTH_SPEED_MAPPING)
    return ["--dbc", vehicle_dbc_path(), "--mapping", mapping]


def test_a_ros2_mcap_bag_with_radar_and_can(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = tmp_path / "drive"
    write_ros2_bag(bag)
    out = tmp_path / "rec"
    code, printed, err = run(
        capsys,
        *("import", "bag", bag, out, "--hfov-deg", "60", "--radar-x-m", "3.5"),
        *bag_can_flags(tmp_path),
    )
    assert code == 0, err
    assert f"{out}: 5 frames, 64x48" in printed
    m = load_manifest(out)
    assert m.name == "drive"
    assert m.camera == BagStream("drive", "/cam")
    assert m.radar == BagStream("drive", "/radar")
    assert m.can is not None
    assert (m.can.bus.bag, m.can.bus.topic, m.can.bus.log) == ("drive", "/can", None)
    assert m.can.bus.dbc == ("vehicle.dbc",)
    for part in bag.iterdir():
        assert filecmp.cmp(part, out / "drive" / part.name, shallow=False)
    with Drive(out) as drive:
        assert len(drive) == BAG_FRAMES
        assert drive.times_ns.tolist() == [BAG_T0_NS + k * NS // 10 for k in range(BAG_FRAMES)]
        np.testing.assert_array_equal(drive.frame(3).image, bag_image(3))
        (target,) = drive.frame(0).radar
        r, a = RADAR_RETURN
        assert target.x_m == pytest.approx(3.5 + r * math.cos(a), abs=1e-4)
        assert target.y_m == pytest.approx(r * math.sin(a), abs=1e-4)


def test_drive_reads_speed_from_the_bags_can_topic(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = tmp_path / "drive"
    write_ros2_bag(bag)
    out = tmp_path / "rec"
    code, _, err = run(
        capsys,
        *("import", "bag", bag, out, "--hfov-deg", "60", "--radar-x-m", "3.5"),
        *bag_can_flags(tmp_path),
    )
    assert code == 0, err
    with Drive(out) as drive:
        assert drive.frame(2).speed_mps == pytest.approx(BAG_SPEED_KMH / 3.6, abs=0.01)


def test_a_ros1_bag_with_raw_images_and_can(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = tmp_path / "drive.bag"
    write_ros1_bag(bag)
    out = tmp_path / "rec"
    code, _, err = run(
        capsys,
        *("import", "bag", bag, out, "--fx", "50", "--name", "ros1"),
        *bag_can_flags(tmp_path),
    )
    assert code == 0, err
    m = load_manifest(out)
    assert m.camera == BagStream("drive.bag", "/image") and m.radar is None
    assert m.can is not None and (m.can.bus.bag, m.can.bus.topic) == ("drive.bag", "/can")
    assert filecmp.cmp(bag, out / "drive.bag", shallow=False)
    with Drive(out) as drive:
        assert drive.name == "ros1" and len(drive) == BAG_FRAMES
        np.testing.assert_array_equal(drive.frame(4).image, bag_image(4))
        i = drive.camera.intrinsics
        assert (i.fx_px, i.fy_px, i.cx_px, i.cy_px) == (50.0, 50.0, 31.5, 23.5)


def test_a_bag_with_a_camera_info_of_another_size_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = tmp_path / "drive"
    write_ros2_bag(bag)
    info = tmp_path / "camera_info.yaml"
    save_camera_info(Intrinsics(100.0, 100.0, 63.5, 47.5, 128, 96), info)
    code, _, err = run(
        capsys, "import", "bag", bag, tmp_path / "r", "--camera-info", info, "--radar-x-m", "3"
    )
    assert code == 2
    assert (
        f"--camera-info {info}: calibrated at 128x96, but the bag's images are 64x48; give a "
        "camera_info (or --fx/--fy/--cx/--cy) at 64x48"
    ) in err
    assert not (tmp_path / "r").exists()


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--radar-topic", "/nope"], "no radar topic '/nope'; topics in the bag: /cam"),
        (["--camera-topic", "/radar"], "camera topic '/radar' has type radar_msgs/msg/RadarScan"),
        (["--can-topic", "/can"], "--can-topic: CAN input also needs --dbc, --mapping"),
    ],
)
def test_bad_bag_topics_are_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], message: str
) -> None:
    bag = tmp_path / "drive"
    write_ros2_bag(bag)
    code, _, err = run(
        capsys, "import", "bag", bag, tmp_path / "r", "--hfov-deg", "60", "--radar-x-m", "3", *flags
    )
    assert code == 2 and message in err, err


def test_a_missing_bag_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, _, err = run(
        capsys, "import", "bag", tmp_path / "none", tmp_path / "r", "--hfov-deg", "60"
    )
    assert (code, err) == (2, f"fusionscope import bag: {tmp_path / 'none'}: bag not found\n")
