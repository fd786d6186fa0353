"""Round trips through RecordingWriter and Drive, with values the test knows."""

from __future__ import annotations

import math
import threading
from pathlib import Path

import numpy as np
import pytest
from recording_fixture import (
    CALIBRATION,
    CAMERA_PERIOD_NS,
    MOUNT,
    N_FRAMES,
    RADAR_LAG_NS,
    RADAR_PERIOD_NS,
    image,
    speed_mps,
    targets,
    truth,
    write_recording,
    yaw_rate_radps,
)

from core.io import Drive, RecordingError, RecordingWriter

SPEED_STEP_MPS = 0.01 / 3.6  # DBC SPEED: 0.01 km/h per bit
YAW_STEP_RADPS = math.radians(0.244)  # DBC YAW_RATE: 0.244 deg/s per bit


def test_frames_come_back_exactly(recording: Path) -> None:
    with Drive(recording) as drive:
        assert len(drive) == N_FRAMES
        assert drive.name == "tiny"
        assert drive.frame_rate_hz == pytest.approx(10.0)
        np.testing.assert_array_equal(drive.times_ns, np.arange(N_FRAMES) * CAMERA_PERIOD_NS)
        assert drive.camera == CALIBRATION.camera
        assert drive.calibration.radar_mount == MOUNT
        assert drive.manifest.generator == {"scenario": "test", "seed": 1}
        for i in range(N_FRAMES):
            f = drive.frame(i)
            assert f.index == i and f.t_ns == i * CAMERA_PERIOD_NS
            np.testing.assert_array_equal(f.image, image(i))


def test_radar_is_the_nearest_scan_with_positions_from_the_mount(recording: Path) -> None:
    with Drive(recording) as drive:
        f = drive.frame(2)
    # Camera at 200 ms; scans every 50 ms starting at 10 ms: scan 4 at 210 ms is nearest.
    k = 4
    assert f.radar_t_ns == k * RADAR_PERIOD_NS + RADAR_LAG_NS
    expected = targets(k)
    assert len(f.radar) == len(expected)
    for got, want in zip(f.radar, expected, strict=True):
        assert got.range_m == np.float32(want.range_m)
        assert got.azimuth_rad == np.float32(want.azimuth_rad)
        assert got.range_rate_mps == np.float32(want.range_rate_mps)
        assert got.amplitude == np.float32(want.amplitude)
        a = got.azimuth_rad + MOUNT.yaw_rad
        assert got.x_m == pytest.approx(MOUNT.x_m + got.range_m * math.cos(a), abs=1e-12)
        assert got.y_m == pytest.approx(MOUNT.y_m + got.range_m * math.sin(a), abs=1e-12)
        assert got.track_id is None


def test_speed_and_yaw_rate_within_dbc_quantisation(recording: Path) -> None:
    with Drive(recording) as drive:
        for i in range(N_FRAMES):
            f = drive.frame(i)
            assert f.speed_mps == pytest.approx(speed_mps(f.t_ns), abs=SPEED_STEP_MPS / 2 + 1e-9)
            assert f.yaw_rate_radps == pytest.approx(
                yaw_rate_radps(f.t_ns), abs=YAW_STEP_RADPS / 2 + 1e-9
            )
        # CAN frames every 20 ms: five per camera period, both signals.
        assert len(drive.vehicle_signals.speed_t_ns) == N_FRAMES * 5
        assert len(drive.vehicle_signals.yaw_rate_t_ns) == N_FRAMES * 5


def test_ground_truth_per_frame(recording: Path) -> None:
    with Drive(recording) as drive:
        assert drive.has_truth
        by_index = {t.index: t for t in truth()}
        for i in range(N_FRAMES):
            assert drive.truth(i) == by_index.get(i)
        assert drive.truth(3) is None


def test_random_access_out_of_order_and_from_threads(recording: Path) -> None:
    with Drive(recording, cache_bytes=2 * image(0).nbytes) as drive:
        for i in (4, 0, 3, 1, 4, 2, 0):
            np.testing.assert_array_equal(drive.frame(i).image, image(i))
        errors: list[BaseException] = []

        def work(i: int) -> None:
            try:
                for _ in range(3):
                    np.testing.assert_array_equal(drive.frame(i).image, image(i))
            except BaseException as err:  # collected and re-raised in the test thread
                errors.append(err)

        threads = [threading.Thread(target=work, args=(i,)) for i in range(N_FRAMES)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        assert errors == []


def test_bad_index_names_the_valid_range(recording: Path) -> None:
    with Drive(recording) as drive:
        with pytest.raises(IndexError, match=r"0 <= i <= 4, got 5"):
            drive.frame(5)
        with pytest.raises(IndexError, match=r"got -1"):
            drive.truth(-1)


def test_same_inputs_give_identical_bytes(tmp_path: Path, recording: Path) -> None:
    again = write_recording(tmp_path / "again")
    files = sorted(p.relative_to(recording) for p in recording.rglob("*") if p.is_file())
    assert [str(f) for f in files] == [
        "bag/bag_0.mcap", "bag/metadata.yaml", "calibration.yaml", "groundtruth.json",
        "recording.yaml", "vehicle.blf", "vehicle.dbc",
    ]  # fmt: skip
    for f in files:
        assert (again / f).read_bytes() == (recording / f).read_bytes(), f


def test_a_bag_split_over_several_files_reads_as_one(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    one_image_bytes = image(0).nbytes // 4  # a few messages per file
    monkeypatch.setattr("core.io.writer.MAX_BAG_FILE_BYTES", one_image_bytes)
    split = write_recording(tmp_path / "split")
    files = sorted(p.name for p in (split / "bag").iterdir())
    assert len(files) > 2 and files[-1] == "metadata.yaml"
    assert all(f"bag_{k}.mcap" in files for k in range(len(files) - 1))
    with Drive(split) as drive:
        assert len(drive) == N_FRAMES
        for i in reversed(range(N_FRAMES)):
            np.testing.assert_array_equal(drive.frame(i).image, image(i))
        assert drive.frame(2).radar_t_ns == 4 * RADAR_PERIOD_NS + RADAR_LAG_NS


def test_writer_refuses_a_non_empty_folder(tmp_path: Path) -> None:
    (tmp_path / "x.txt").write_text("hello")
    with pytest.raises(RecordingError, match=r"not empty"):
        RecordingWriter(tmp_path, name="x", calibration=CALIBRATION)


def test_writer_rejects_an_image_of_the_wrong_size(tmp_path: Path) -> None:
    with RecordingWriter(tmp_path / "r", name="x", calibration=CALIBRATION) as w:
        with pytest.raises(ValueError, match=r"expected \(48, 64\) uint8"):
            w.add_image(0, np.zeros((10, 10), np.uint8))
        w.add_image(0, image(0))


def test_recording_without_radar_scans_near_gives_no_targets(tmp_path: Path) -> None:
    with RecordingWriter(tmp_path / "r", name="x", calibration=CALIBRATION) as w:
        w.add_image(0, image(0))
        w.add_image(CAMERA_PERIOD_NS, image(1))
        w.add_vehicle_state(0, 10.0, 0.0)
    with Drive(tmp_path / "r") as drive:
        f = drive.frame(1)
        assert f.radar == () and f.radar_t_ns is None
        assert f.speed_mps == pytest.approx(10.0, abs=SPEED_STEP_MPS)
        assert not drive.has_truth and drive.truth(0) is None
