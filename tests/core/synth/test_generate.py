"""The generator end to end: same seed same bytes, the sensors' difficulties are really there,
and bad arguments are refused with a clear message."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS, main
from core.io import Drive, RecordingError
from core.synth.generate import CAMERA_PITCH_RAD, generate

BUNDLED = DEFAULT_RECORDINGS


def _files(folder: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()
    }


def test_same_seed_same_bytes_and_another_seed_differs(tmp_path: Path) -> None:
    a = generate("exurban", 0.8, 5, tmp_path / "a" / "drive")
    b = generate("exurban", 0.8, 5, tmp_path / "b" / "drive")
    c = generate("exurban", 0.8, 6, tmp_path / "c" / "drive")
    files_a, files_b = _files(a), _files(b)
    assert set(files_a) >= {
        "recording.yaml",
        "calibration.yaml",
        "groundtruth.json",
        "vehicle.blf",
        "vehicle.dbc",
    }
    assert files_a == files_b
    assert _files(c)["groundtruth.json"] != files_a["groundtruth.json"]


def test_cli_synth_writes_a_recording_the_reader_opens(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "hw"
    assert main(["synth", "--scenario", "highway", "--seconds", "1", "--seed", "2", str(out)]) == 0
    with Drive(out) as drive:
        assert len(drive) == 10
        assert drive.frame_rate_hz == pytest.approx(10.0)
        frame = drive.frame(9)
        assert frame.image.shape == (480, 640)
        assert drive.truth(9) is not None
        assert 20 < frame.speed_mps < 30
    assert "synth highway" in capsys.readouterr().err  # the progress bar


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--seconds", "-1"], "seconds: expected a duration in (0, 600], got -1.0"),
        (["--seconds", "1", "--seed", "-3"], "seed: expected an integer >= 0, got -3"),
    ],
)
def test_cli_synth_refuses_bad_arguments(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    assert main(["synth", "--scenario", "highway", *args, str(tmp_path / "x")]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


def test_cli_synth_names_the_scenarios_it_knows(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with pytest.raises(SystemExit):
        main(["synth", "--scenario", "city", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert "invalid choice: 'city'" in err
    assert all(name in err for name in ("exurban", "highway", "stop_and_go"))


def test_synth_refuses_a_folder_that_is_not_empty(tmp_path: Path) -> None:
    (tmp_path / "busy").mkdir()
    (tmp_path / "busy" / "notes.txt").write_text("mine")
    with pytest.raises(RecordingError, match="busy"):
        generate("highway", 0.5, 0, tmp_path / "busy")
    assert (tmp_path / "busy" / "notes.txt").read_text() == "mine"


@pytest.fixture(scope="module")
def highway() -> Drive:
    return Drive(BUNDLED / "highway")


@pytest.fixture(scope="module")
def stop_and_go() -> Drive:
    return Drive(BUNDLED / "stop_and_go")


def test_bundled_drives_are_15_to_30_s_at_10_fps_and_small() -> None:
    total = 0
    for name in ("highway", "exurban", "stop_and_go"):
        with Drive(BUNDLED / name) as drive:
            assert 15.0 <= len(drive) / drive.frame_rate_hz <= 30.0
            assert drive.has_truth
        total += sum(p.stat().st_size for p in (BUNDLED / name).rglob("*") if p.is_file())
    assert total <= 40 * 2**20


def test_radar_points_fall_near_the_vehicles_they_came_from(highway: Drive) -> None:
    hits = misses = 0
    for i in range(0, len(highway), 5):
        frame, truth = highway.frame(i), highway.truth(i)
        assert truth is not None
        for o in truth.objects:
            if not o.radar_seen or o.cls not in ("car", "van", "truck"):
                continue
            d = min(
                (math.hypot(t.x_m - o.position_m[0], t.y_m - o.position_m[1]) for t in frame.radar),
                default=99.0,
            )
            hits += d < 3.0
            misses += d >= 3.0
    assert hits > 20
    assert (
        misses <= 0.25 * hits
    )  # a few points merged between two vehicles or thrown off the vehicle


def test_guard_rails_give_many_slow_radar_returns(highway: Drive) -> None:
    slow = []
    for i in range(0, len(highway), 10):
        frame = highway.frame(i)
        # over-ground speed along the line of sight of a stationary target is ~0
        slow.append(
            sum(
                abs(t.range_rate_mps + frame.speed_mps * math.cos(t.azimuth_rad)) < 1.0
                and abs(t.y_m) > 6
                for t in frame.radar
            )
        )
    assert np.mean(slow) >= 2


def test_pitch_oscillates_about_the_calibration_and_dips_when_braking(highway: Drive) -> None:
    pitch = np.array([highway.truth(i).pitch_rad for i in range(len(highway))])  # type: ignore[union-attr]
    rough = np.std(pitch[:40] - CAMERA_PITCH_RAD)
    assert math.radians(0.15) < rough < math.radians(0.8)  # about +-0.5 deg (paper 001 fig. 1)
    assert pitch.max() - CAMERA_PITCH_RAD > math.radians(0.5)  # the braking dip


def test_stop_and_go_stands_still_with_a_biased_gyro(stop_and_go: Drive) -> None:
    speeds = np.array([stop_and_go.frame(i).speed_mps for i in range(len(stop_and_go))])
    yaw = np.array([stop_and_go.frame(i).yaw_rate_radps for i in range(len(stop_and_go))])
    standing = speeds == 0.0
    assert standing.sum() >= 30  # at least 3 s standing still
    # The manifest asks for the bias to be estimated at standstill and removed on reading:
    # what was removed is the gyro's -0.4 deg/s, and what is left averages to zero there.
    assert stop_and_go.manifest.can is not None
    assert stop_and_go.manifest.can.yaw_rate_bias == "standstill"
    removed = stop_and_go.vehicle_signals.yaw_rate_bias_radps
    assert abs(removed - math.radians(-0.4)) < math.radians(0.25)
    assert abs(np.mean(yaw[standing])) < math.radians(0.25)
    assert speeds.max() > 7.0
    crossing = [
        o
        for i in np.nonzero(standing)[0]
        for o in stop_and_go.truth(int(i)).objects
        if o.cls == "pedestrian" and abs(o.position_m[1]) < 1.5
    ]  # type: ignore[union-attr]
    assert crossing  # people cross in front of the standing car
