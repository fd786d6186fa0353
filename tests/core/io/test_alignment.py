"""Time alignment, ego motion, assumptions, outlier stamps and the index cache of Drive."""

from __future__ import annotations

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from recording_fixture import (
    CALIBRATION,
    CAMERA_PERIOD_NS,
    N_FRAMES,
    RADAR_LAG_NS,
    image,
    speed_mps,
    yaw_rate_radps,
)

from core.ego import integrate, step
from core.io import Drive, RecordingError, RecordingWriter
from core.io.diagnostics import drive_report, format_report
from core.io.index import cache_dir, index_key

S = 1_000_000_000


def edit_manifest(folder: Path, **changes: object) -> None:
    path = folder / "recording.yaml"
    raw = yaml.safe_load(path.read_text())
    for key, value in changes.items():
        if value is None:
            raw.pop(key, None)
        else:
            raw[key] = value
    path.write_text(yaml.safe_dump(raw))


def copy(recording: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(recording, tmp_path / "copy"))


def test_ego_motion_is_integrated_over_every_can_sample(recording: Path) -> None:
    with Drive(recording) as drive:
        assert drive.frame(0).ego is None
        f = drive.frame(3)
        v = drive.vehicle_signals
    assert f.ego is not None
    # CAN every 20 ms: the 100 ms frame interval is cut into 5 pieces.
    assert f.ego.pieces == 5
    assert f.ego.dt_s == pytest.approx(0.1)
    expected = integrate(
        2 * CAMERA_PERIOD_NS,
        3 * CAMERA_PERIOD_NS,
        v.speed_t_ns,
        v.speed_mps,
        v.yaw_rate_t_ns,
        v.yaw_rate_radps,
    )
    assert f.ego == expected
    # Against the true signals: distance = integral of the speed, turn = integral of yaw rate.
    t0, t1 = 2 * CAMERA_PERIOD_NS, 3 * CAMERA_PERIOD_NS
    distance = (speed_mps(t0) + speed_mps(t1)) / 2 * 0.1
    turn = (yaw_rate_radps(t0) + yaw_rate_radps(t1)) / 2 * 0.1
    assert math.hypot(f.ego.dx_m, f.ego.dy_m) == pytest.approx(distance, abs=2e-3)
    assert f.ego.dyaw_rad == pytest.approx(turn, abs=math.radians(0.244) * 0.1)


def test_radar_skew_limit_from_the_manifest(recording: Path, tmp_path: Path) -> None:
    with Drive(recording) as drive:
        # Default: half the 50 ms scan period; scans lag frames by 10 ms.
        assert drive.max_radar_skew_ns == pytest.approx(25e6)
        assert drive.frame(1).radar_t_ns == CAMERA_PERIOD_NS + RADAR_LAG_NS
    folder = copy(recording, tmp_path)
    edit_manifest(folder, max_radar_skew_ms=5)
    with Drive(folder) as drive:
        f = drive.frame(1)
        assert (f.radar, f.radar_t_ns) == ((), None)
        report = drive_report(drive)
    assert report.skew is not None
    assert report.skew.frames_without_radar == N_FRAMES
    assert report.skew.median_ms == pytest.approx(RADAR_LAG_NS / 1e6)


def test_assumed_speed_without_can(recording: Path, tmp_path: Path) -> None:
    folder = copy(recording, tmp_path)
    edit_manifest(folder, can=None, assumptions={"speed_mps": 27.0, "yaw_rate_radps": 0.0})
    with Drive(folder) as drive:
        f = drive.frame(2)
        text = format_report(drive_report(drive))
    assert (f.speed_mps, f.yaw_rate_radps) == (27.0, 0.0)
    assert f.ego == step(27.0, 0.0, 0.1)
    assert "speed 27 m/s is assumed, not measured" in text
    edit_manifest(folder, assumptions=None)
    with Drive(folder) as drive:
        f = drive.frame(2)
    assert math.isnan(f.speed_mps) and math.isnan(f.yaw_rate_radps) and f.ego is None


def write_frames(out: Path, stamps_ns: list[int]) -> Path:
    with RecordingWriter(out, name="stamps", calibration=CALIBRATION) as w:
        for i, t in enumerate(stamps_ns):
            w.add_image(t, image(i))
    edit_manifest(out, radar=None, can=None)
    return out


def test_outlier_stamps_are_skipped_and_frames_come_in_time_order(tmp_path: Path) -> None:
    start = 1_700_000_000 * S
    # Frame 2 carries a 1970 stamp; frames 3 and 4 were logged in swapped order.
    stamps = [
        start,
        start + CAMERA_PERIOD_NS,
        5 * S,
        start + 3 * CAMERA_PERIOD_NS,
        start + 2 * CAMERA_PERIOD_NS,
    ]
    with Drive(write_frames(tmp_path / "r", stamps)) as drive:
        assert len(drive) == 4
        np.testing.assert_array_equal(drive.times_ns - start, np.arange(4) * CAMERA_PERIOD_NS)
        # Frames come in time order with their own images.
        np.testing.assert_array_equal(drive.frame(2).image, image(4))
        np.testing.assert_array_equal(drive.frame(3).image, image(3))
        report = drive_report(drive)
        warnings = " ".join(drive.warnings)
    assert "skipped 1 frame(s)" in warnings and "main time span" in warnings
    assert report.camera_skipped == 1
    camera = report.streams[0]
    assert camera.last_s - camera.first_s == pytest.approx(0.3)


def test_frames_with_the_same_stamp_are_all_kept(tmp_path: Path) -> None:
    with Drive(write_frames(tmp_path / "r", [0, S, S, 2 * S])) as drive:
        images = [drive.frame(i).image for i in range(4)]
    for i, img in enumerate(images):
        np.testing.assert_array_equal(img, image(i))


def test_index_cache_reopens_without_reading_follows_moves_and_notices_changes(
    recording: Path, tmp_path: Path
) -> None:
    folder = copy(recording, tmp_path)
    edit_manifest(folder, max_radar_skew_ms=40)  # files no other test has opened
    with Drive(folder) as first:
        assert not first.index_cached
        first_ego = first.frame(1).ego
    with Drive(folder) as second:
        assert second.index_cached
        np.testing.assert_array_equal(second.times_ns, first.times_ns)
        assert second.radar is not None and first.radar is not None
        np.testing.assert_array_equal(second.radar.range_m, first.radar.range_m)
        np.testing.assert_array_equal(
            second.vehicle_signals.speed_mps, first.vehicle_signals.speed_mps
        )
        assert second.frame(1).ego == first_ego
    moved = folder.rename(tmp_path / "moved")
    with Drive(moved) as renamed:
        assert renamed.index_cached
    edit_manifest(moved, max_radar_skew_ms=30)
    with Drive(moved) as third:
        assert not third.index_cached
    with Drive(moved, use_cache=False) as fourth:
        assert not fourth.index_cached


def test_image_cache_stays_within_its_byte_budget(recording: Path) -> None:
    frame_bytes = image(0).nbytes
    with Drive(recording, cache_bytes=2 * frame_bytes) as drive:
        for i in [0, 1, 2, 3, 4, 0]:
            drive.frame(i)
        assert drive._cached_bytes <= 2 * frame_bytes
        assert list(drive._cache) == [4, 0]


def test_a_damaged_cache_entry_is_rebuilt(recording: Path, tmp_path: Path) -> None:
    folder = copy(recording, tmp_path)
    with Drive(folder) as first:
        expected = first.times_ns.copy()
    (entry,) = [
        p for p in (cache_dir() / "index").iterdir() if p.name.startswith(index_key(first.manifest))
    ]
    entry.write_bytes(b"PK\x03\x04 not a zip")
    with Drive(folder) as second:
        assert not second.index_cached
        np.testing.assert_array_equal(second.times_ns, expected)
    with Drive(folder) as third:
        assert third.index_cached


def test_time_offsets_move_each_stream_onto_the_camera_clock(
    recording: Path, tmp_path: Path
) -> None:
    folder = copy(recording, tmp_path)
    # Camera +1 s; radar +1 s - 10 ms (now exactly on the frames); CAN +1 s + 40 ms.
    offsets = {"camera": S, "radar": S - RADAR_LAG_NS, "can": S + 40_000_000}
    edit_manifest(folder, time_offsets_ns=offsets)
    with Drive(folder) as drive:
        assert drive.times_ns[0] == S
        f = drive.frame(2)
        v = drive.vehicle_signals
    assert f.radar_t_ns == f.t_ns
    assert v.speed_t_ns[0] == S + 40_000_000
    # The frame at camera time 0.2 s sees the CAN sample logged at 0.16 s.
    assert f.speed_mps == pytest.approx(speed_mps(160_000_000), abs=0.01)


@pytest.mark.parametrize("outside", ["../elsewhere.yaml", "/etc/hostname", "bag/../../x"])
def test_a_manifest_may_not_point_outside_its_folder(
    recording: Path, tmp_path: Path, outside: str
) -> None:
    folder = copy(recording, tmp_path)
    (tmp_path / "elsewhere.yaml").write_text("format_version: 1\n")
    edit_manifest(folder, calibration=outside)
    with pytest.raises(RecordingError, match="outside the recording folder"):
        Drive(folder)
