"""`fusionscope import bag --ego-from-radar`: the speed estimated from the bag's radar and
written into the recording as CAN (a known small bag, the bundled highway drive against its
CAN speed), and the combinations it refuses."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from bagmaker import Message, radar_scan, raw_image, write_bag

from core.cli import DEFAULT_RECORDINGS, main
from core.io import Drive, load_calibration, load_manifest
from core.io.importers.can_mapping import PreparedCan
from core.io.importers.finish import ImportOptions, check_ego_from_radar
from core.io.radar_msgs import IMAGE, RADAR_SCAN
from core.io.writer import CAN_LOG, DBC_NAME, VehicleState, write_vehicle_can

NS = 1_000_000_000
T0_NS = 1_700_000_000 * NS
PERIOD_NS = NS // 10
KMH_STEP_MPS = 0.01 / 3.6  # the DBC's SPEED quantisation
POSTS = ((12.0, 0.3), (18.0, -0.25), (25.0, 0.15), (33.0, -0.1), (41.0, 0.05))  # m, rad
CAR = (20.0, 0.02, -2.0, 30.0)  # range m, azimuth rad, range rate m/s, amplitude
# Scans 0-1 at 10 m/s, 2-6 traffic only, 7-8 at 12 m/s. The running median over five scans
# gives 10 on scans 0-3, 12 on 5-8 and nothing on 4, whose window holds no fit.
SCAN_SPEEDS = (10.0, 10.0, None, None, None, None, None, 12.0, 12.0)
SPEED_FLAGS = ("--hfov-deg", "60", "--radar-x-m", "3")


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def scan_returns(speed_mps: float | None) -> list[tuple[float, float, float, float]]:
    """POSTS seen from a car at `speed_mps` and CAR; only CAR when None."""
    posts = [(r, a, -speed_mps * math.cos(a), 10.0) for r, a in POSTS] if speed_mps else []
    return [*posts, CAR]


def write_small_bag(path: Path, radar: bool = True) -> Path:
    """A ROS 2 MCAP bag: /camera (32x24 mono8) and /radar (SCAN_SPEEDS) every 0.1 s."""
    pixels = np.zeros((24, 32), np.uint8)
    messages: list[Message] = []
    for k, v in enumerate(SCAN_SPEEDS):
        t = T0_NS + k * PERIOD_NS
        messages.append(("/camera", IMAGE, t, raw_image(t, pixels, "mono8")))
        if radar:
            messages.append(("/radar", RADAR_SCAN, t, radar_scan(t, scan_returns(v))))
    return write_bag(path, "mcap", messages)


def test_the_speed_of_each_fitted_scan_is_written_and_interpolated_between(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bag = write_small_bag(tmp_path / "drive")
    out = tmp_path / "rec"
    code, printed, err = run(capsys, "import", "bag", bag, out, *SPEED_FLAGS, "--ego-from-radar")
    assert code == 0, err
    assert (
        "note: speed from the radar's stationary returns on 8 of 9 scans (10.0-12.0 m/s; "
        "between them the speed is interpolated); yaw rate not recorded: 0"
    ) in printed
    assert "no speed" not in printed
    m = load_manifest(out)
    assert m.can is not None and (m.can.bus.log, m.can.bus.dbc) == (CAN_LOG, (DBC_NAME,))
    assert m.assumptions.speed_mps is None
    assert "Speed estimated from the radar's stationary returns (core.radar_ego) on 8 of 9 " in (
        m.description
    )
    assert "yaw rate not recorded: 0 (the radar gives no usable yaw rate)" in m.description
    with Drive(out) as drive:
        got = [drive.speed_at(T0_NS + k * PERIOD_NS) for k in range(len(SCAN_SPEEDS))]
        # scan 4 has no sample: halfway between scan 3 (10) and scan 5 (12)
        expected = [10.0] * 4 + [11.0] + [12.0] * 4
        np.testing.assert_allclose(got, expected, atol=KMH_STEP_MPS)
        assert drive.yaw_rate_at(T0_NS + 4 * PERIOD_NS) == 0.0
        assert drive.vehicle_signals.speed_t_ns.tolist() == [
            T0_NS + k * PERIOD_NS for k in range(9) if k != 4
        ]


def calibration_flags(path: Path) -> list[str]:
    """The import flags giving the calibration in `path` (the bundled drives' YAML)."""
    cal = load_calibration(path)
    i, e, m = cal.camera.intrinsics, cal.camera.extrinsics, cal.radar_mount
    values = {
        "--fx": i.fx_px,
        "--fy": i.fy_px,
        "--cx": i.cx_px,
        "--cy": i.cy_px,
        "--camera-height-m": e.height_m,
        "--camera-x-m": e.x_m,
        "--pitch-rad": e.pitch_rad,
        "--yaw-rad": e.yaw_rad,
        "--radar-x-m": m.x_m,
        "--radar-y-m": m.y_m,
        "--radar-z-m": m.z_m,
        "--radar-yaw-rad": m.yaw_rad,
    }
    return [a for flag, v in values.items() for a in (flag, repr(float(v)))]


def test_the_highway_bag_gets_its_can_speed_back_from_the_radar(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """The bundled highway drive's bag imported without its CAN log: the speed at its 150
    camera frames against the drive's CAN speed measured |error| median 0.024 m/s, p95
    0.18, max 0.51 (all 150 radar scans fitted; exurban by hand: 114 of 150, 0.038 / 0.14 /
    0.25; stop_and_go: 30 of 150, 0.71 / 2.6 / 2.8, core/radar_ego.py Notes)."""
    highway = DEFAULT_RECORDINGS / "highway"
    out = tmp_path / "highway"
    flags = calibration_flags(highway / "calibration.yaml")
    code, printed, err = run(
        capsys, "import", "bag", highway / "bag", out, *flags, "--ego-from-radar"
    )
    assert code == 0, err
    assert "on 150 of 150 scans" in printed
    with Drive(highway) as original, Drive(out) as imported:
        assert imported.calibration.radar_mount == original.calibration.radar_mount
        np.testing.assert_array_equal(imported.times_ns, original.times_ns)
        error = np.abs(
            [imported.speed_at(int(t)) - original.speed_at(int(t)) for t in original.times_ns]
        )
        assert {imported.yaw_rate_at(int(t)) for t in original.times_ns} == {0.0}
    assert float(np.median(error)) < 0.1
    assert float(np.percentile(error, 95)) < 0.3
    assert float(error.max()) < 1.0


# --- refused -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (
            ["--assume-speed-mps", "10"],
            "--ego-from-radar: not with --assume-speed-mps or --assume-yaw-rate-radps",
        ),
        (
            ["--assume-yaw-rate-radps", "0.1"],
            "--ego-from-radar: not with --assume-speed-mps or --assume-yaw-rate-radps",
        ),
    ],
)
def test_with_an_assumed_speed_or_yaw_rate_it_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], flags: list[str], message: str
) -> None:
    bag = write_small_bag(tmp_path / "drive")
    code, _, err = run(
        capsys, "import", "bag", bag, tmp_path / "r", *SPEED_FLAGS, "--ego-from-radar", *flags
    )
    assert code == 2 and message in err, err
    assert not (tmp_path / "r").exists()


def test_with_can_speed_it_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_small_bag(tmp_path / "drive")
    can_dir = tmp_path / "can"
    can_dir.mkdir()
    samples = [VehicleState(T0_NS + k * PERIOD_NS, 10.0, 0.0) for k in range(9)]
    written = write_vehicle_can(can_dir, samples)
    mapping = tmp_path / "speed.yaml"  # the `can:` section of what was written
    signals = {"speed": written.speed, "yaw_rate": written.yaw_rate}
    section = {
        k: {"message": m.message, "signal": m.signal, "unit": m.unit} for k, m in signals.items()
    }
    mapping.write_text(yaml.safe_dump({"can": section}))
    can = ["--can", can_dir / CAN_LOG, "--dbc", can_dir / DBC_NAME, "--mapping", mapping]
    code, _, err = run(
        capsys, "import", "bag", bag, tmp_path / "r", *SPEED_FLAGS, *can, "--ego-from-radar"
    )
    assert code == 2
    assert (
        "fusionscope import bag: --ego-from-radar: the mapping's `can:` section records speed "
        "and yaw rate; --ego-from-radar is for recordings without them"
    ) in err
    assert not (tmp_path / "r").exists()


def test_without_radar_it_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bag = write_small_bag(tmp_path / "drive", radar=False)
    code, _, err = run(
        capsys, "import", "bag", bag, tmp_path / "r", "--hfov-deg", "60", "--ego-from-radar"
    )
    assert (code, err) == (
        2,
        f"fusionscope import bag: --ego-from-radar: {bag} gives no radar to estimate the "
        "speed from (no radar topic, no `radar:` section in the mapping)\n",
    )
    assert not (tmp_path / "r").exists()


def test_a_radar_that_never_sees_the_roadside_is_refused_naming_the_bag(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pixels = np.zeros((24, 32), np.uint8)
    messages: list[Message] = []
    for k in range(3):
        t = T0_NS + k * PERIOD_NS
        messages.append(("/camera", IMAGE, t, raw_image(t, pixels, "mono8")))
        messages.append(("/radar", RADAR_SCAN, t, radar_scan(t, scan_returns(None))))
    bag = write_bag(tmp_path / "drive", "mcap", messages)
    code, _, err = run(
        capsys, "import", "bag", bag, tmp_path / "r", *SPEED_FLAGS, "--ego-from-radar"
    )
    assert code == 2
    assert err.endswith(  # after the copy's progress bar
        f"\nfusionscope import bag: {bag}: --ego-from-radar: none of the radar's 3 scans has "
        "4 stationary returns at distinct places agreeing on one speed (core/radar_ego.py); "
        "give the speed another way (CAN, --assume-speed-mps)\n"
    )
    assert sorted(p.name for p in tmp_path.iterdir()) == ["drive"]  # nothing left behind


def test_a_can_file_taking_a_name_it_writes_is_refused(tmp_path: Path) -> None:
    dbc = tmp_path / "vehicle.dbc"
    prepared = PreparedCan(
        can=None,
        radar=None,
        files={DBC_NAME: dbc},
        span_ns=None,
        radar_times_ns=np.zeros(0, np.int64),
        description="",
        notes=(),
    )
    with pytest.raises(ValueError) as err:
        check_ego_from_radar(ImportOptions(ego_from_radar=True), prepared, True, tmp_path)
    assert str(err.value) == (
        f"--ego-from-radar: writes {DBC_NAME}, and a CAN file of that name is copied into the "
        f"recording ({dbc}); rename the file"
    )
    check_ego_from_radar(ImportOptions(), prepared, False, tmp_path)  # not asked: no check


def test_a_vehicle_state_that_is_not_finite_is_refused() -> None:
    with pytest.raises(ValueError) as err:
        VehicleState(0, math.nan, 0.0)
    assert str(err.value) == "speed_mps, yaw_rate_radps: expected finite numbers, got nan, 0.0"
