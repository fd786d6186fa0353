"""Bad recordings raise RecordingError naming the file, what was expected and what came."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest
import yaml
from recording_fixture import CALIBRATION, image
from rosbags.rosbag2 import StoragePlugin, Writer

from core.io import Drive, RecordingError
from core.io.calibration import save_calibration
from core.io.radar_msgs import COMPRESSED_IMAGE, typestore


def _copy(recording: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(recording, tmp_path / "rec"))


def _edit_manifest(rec: Path, change: dict[str, object]) -> None:
    path = rec / "recording.yaml"
    raw = yaml.safe_load(path.read_text())
    raw.update(change)
    path.write_text(yaml.safe_dump(raw, sort_keys=False))


def test_missing_folder_and_manifest(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match=r"nowhere: expected a recording folder"):
        Drive(tmp_path / "nowhere")
    with pytest.raises(RecordingError, match=r"recording.yaml: recording manifest not found"):
        Drive(tmp_path)


def test_malformed_yaml(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    (rec / "recording.yaml").write_text("name: [unclosed\n")
    with pytest.raises(
        RecordingError, match=r"recording.yaml: recording manifest is not valid YAML"
    ):
        Drive(rec)


def test_unknown_and_missing_keys(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    _edit_manifest(rec, {"camra": {}})
    with pytest.raises(RecordingError, match=r"recording.yaml: camra: unknown key; known keys"):
        Drive(rec)
    raw = yaml.safe_load((rec / "recording.yaml").read_text())
    del raw["camra"], raw["calibration"]
    (rec / "recording.yaml").write_text(yaml.safe_dump(raw))
    with pytest.raises(RecordingError, match=r"recording.yaml: calibration: missing key"):
        Drive(rec)


def test_part_that_does_not_exist(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    _edit_manifest(rec, {"calibration": "calib.yaml"})
    with pytest.raises(
        RecordingError, match=r"names 'calib.yaml', but .*calib.yaml does not exist"
    ):
        Drive(rec)


def test_unknown_unit(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    raw = yaml.safe_load((rec / "recording.yaml").read_text())
    raw["can"]["speed"]["unit"] = "furlong/fortnight"
    _edit_manifest(rec, raw)
    with pytest.raises(
        RecordingError,
        match=r"can.speed.unit: expected one of m/s, km/h, mph, got 'furlong/fortnight'",
    ):
        Drive(rec)


def test_dbc_signal_missing_lists_close_names(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    raw = yaml.safe_load((rec / "recording.yaml").read_text())
    raw["can"]["yaw_rate"]["signal"] = "YAWRATE"
    _edit_manifest(rec, raw)
    with pytest.raises(
        RecordingError,
        match=r"can \(log vehicle.blf, DBC vehicle.dbc\): message 'KINEMATICS' has no signal "
        r"'YAWRATE'; close names: YAW_RATE",
    ):
        Drive(rec)
    raw["can"]["yaw_rate"]["message"] = "KINEMATIC"
    _edit_manifest(rec, raw)
    with pytest.raises(
        RecordingError, match=r"no message 'KINEMATIC' in the DBC; close names: KINEMATICS"
    ):
        Drive(rec)


def test_missing_topic_lists_the_topics(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    _edit_manifest(rec, {"camera": {"bag": "bag", "topic": "/front/image"}})
    with pytest.raises(RecordingError, match=r"no camera topic '/front/image'; topics in the bag: "
                       r"/camera/image/compressed \(sensor_msgs/msg/CompressedImage\), "
                       r"/radar/scan \(radar_msgs/msg/RadarScan\)"):  # fmt: skip
        Drive(rec)


def test_wrong_message_type(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    _edit_manifest(rec, {"camera": {"bag": "bag", "topic": "/radar/scan"}})
    with pytest.raises(
        RecordingError,
        match=r"camera topic '/radar/scan' has type radar_msgs/msg/RadarScan; "
        r"expected sensor_msgs/msg/CompressedImage or sensor_msgs/msg/Image",
    ):
        Drive(rec)


def test_topic_found_by_type_when_not_named(recording: Path, tmp_path: Path) -> None:
    rec = _copy(recording, tmp_path)
    _edit_manifest(rec, {"camera": {"bag": "bag"}, "radar": {"bag": "bag"}})
    with Drive(rec) as drive:
        np.testing.assert_array_equal(drive.frame(1).image, image(1))
        assert drive.frame(1).radar


def _bag_recording(tmp_path: Path, images: list[bytes], topics: tuple[str, ...]) -> Path:
    """A recording whose bag is written directly with rosbags (PNG payloads given)."""
    rec = tmp_path / "raw"
    rec.mkdir()
    store = typestore()
    t = store.types
    with Writer(rec / "bag", version=9, storage_plugin=StoragePlugin.MCAP) as w:
        conns = [w.add_connection(topic, COMPRESSED_IMAGE, typestore=store) for topic in topics]
        for k, data in enumerate(images):
            header = t["std_msgs/msg/Header"](
                stamp=t["builtin_interfaces/msg/Time"](sec=k, nanosec=0), frame_id="camera"
            )
            msg = t[COMPRESSED_IMAGE](
                header=header,
                format="mono8; png compressed mono8",
                data=np.frombuffer(data, np.uint8),
            )
            w.write(conns[0], k * 1_000_000_000, store.serialize_cdr(msg, COMPRESSED_IMAGE))
    save_calibration(CALIBRATION, rec / "calibration.yaml")
    (rec / "recording.yaml").write_text(yaml.safe_dump({
        "format_version": 1, "name": "raw", "camera": {"bag": "bag"},
        "calibration": "calibration.yaml",
    }))  # fmt: skip
    return rec


def _png(i: int) -> bytes:
    ok, buf = cv2.imencode(".png", image(i))
    assert ok
    return buf.tobytes()


def test_corrupt_png_names_topic_and_stamp(tmp_path: Path) -> None:
    good = _png(0)
    bad = good[:40] + bytes(200)
    rec = _bag_recording(tmp_path, [good, bad], ("/camera/image/compressed",))
    with Drive(rec) as drive:
        assert drive.frame(0).image.shape == (48, 64)
        assert np.isnan(drive.frame(0).speed_mps)  # no CAN section
        with pytest.raises(
            RecordingError,
            match=r"/camera/image/compressed at 1.000000000 s \(frame 1\): damaged PNG data: "
            r"240 bytes .* that OpenCV cannot decode",
        ):
            drive.frame(1)


def test_empty_camera_stream(tmp_path: Path) -> None:
    rec = _bag_recording(tmp_path, [], ("/camera/image/compressed",))
    with pytest.raises(RecordingError, match=r"camera topic /camera/image/compressed: expected "
                       r"images, the stream is empty"):  # fmt: skip
        Drive(rec)


def test_several_candidate_topics_are_listed(tmp_path: Path) -> None:
    rec = _bag_recording(tmp_path, [_png(0)], ("/cam/left", "/cam/right"))
    with pytest.raises(RecordingError, match=r"several camera topics .* \(/cam/left, /cam/right\)"):
        Drive(rec)


def test_image_size_must_match_the_calibration(tmp_path: Path) -> None:
    ok, buf = cv2.imencode(".png", np.zeros((10, 20), np.uint8))
    assert ok
    rec = _bag_recording(tmp_path, [buf.tobytes()], ("/camera/image/compressed",))
    with pytest.raises(
        RecordingError,
        match=r"\(frame 0\): the PNG image declares 20x10 pixels, the calibration says 64x48; "
        "not decoded",
    ):
        Drive(rec)
