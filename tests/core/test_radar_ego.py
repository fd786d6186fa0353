"""Ego speed from the radar's stationary returns: scans whose answer the test writes down
(stationary returns at known azimuths beside traffic, a yawed mount, a standing car, too
few stationary positions, traffic pulling away), the running median, bad input, and the
bundled drives and the aiMotive sample against their known speeds."""

from __future__ import annotations

import glob
import json
import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS
from core.io.drive import Drive
from core.radar_ego import RadarEgoParams, running_median, speed_from_scan, speeds_from_scans

V_MPS = 20.0
# Roadside posts, each at its own place: (range m, azimuth rad in the radar frame).
POSTS = ((12.0, 0.35), (18.0, -0.30), (25.0, 0.20), (33.0, -0.10), (41.0, 0.0))


def scan(
    posts: tuple[tuple[float, float], ...],
    speed_mps: float,
    traffic: tuple[tuple[float, float, float], ...] = (),
    mount_yaw_rad: float = 0.0,
) -> tuple[list[float], list[float], list[float]]:
    """(range m, azimuth rad, range rate m/s) of stationary `posts` seen from a car at
    `speed_mps`, then `traffic` (range, azimuth, range rate) as given."""
    rows = [(r, a, -speed_mps * math.cos(a + mount_yaw_rad)) for r, a in posts]
    rows += list(traffic)
    rg, az, rr = (list(c) for c in zip(*rows, strict=True))
    return rg, az, rr


# --- one scan -------------------------------------------------------------------------------


def test_stationary_returns_beside_traffic_give_the_speed_exactly() -> None:
    # a car ahead closing slowly, one pulling away, an oncoming car at 25 m/s
    traffic = ((22.0, 0.02, -3.0), (30.0, -0.04, 1.5), (45.0, 0.15, -(V_MPS + 25.0) * 0.99))
    rg, az, rr = scan(POSTS, V_MPS, traffic)
    fit = speed_from_scan(rr, az, range_m=rg)
    assert fit.speed_mps == pytest.approx(V_MPS, abs=1e-12)
    assert fit.stationary.tolist() == [True] * 5 + [False] * 3
    assert fit.support == 5


def test_a_yawed_mount_turns_the_azimuths_into_the_vehicle_frame() -> None:
    yaw = 0.4  # radar looking 0.4 rad left: a return at azimuth a lies at a + 0.4
    rg, az, rr = scan(POSTS, V_MPS, ((20.0, -0.3, -2.0),), mount_yaw_rad=yaw)
    assert speed_from_scan(rr, az, yaw, range_m=rg).speed_mps == pytest.approx(V_MPS, abs=1e-12)
    # taken as straight ahead, the same returns give no consistent speed: 20 m/s is wrong
    assert not speed_from_scan(rr, az, 0.0, range_m=rg).speed_mps == pytest.approx(V_MPS, abs=0.5)


def test_a_standing_car_gets_zero() -> None:
    traffic = ((15.0, 0.05, 4.0), (28.0, -0.1, 6.0))  # traffic pulling away
    rg, az, rr = scan(POSTS, 0.0, traffic)
    fit = speed_from_scan(rr, az, range_m=rg)
    assert fit.speed_mps == 0.0
    assert fit.support == 5


def test_too_few_stationary_positions_give_nan() -> None:
    # three posts against one vehicle at one speed: no fit (min_stationary 4)
    rg, az, rr = scan(POSTS[:3], V_MPS, ((30.0, 0.0, -2.0), (45.0, 0.1, -8.0)))
    fit = speed_from_scan(rr, az, range_m=rg)
    assert math.isnan(fit.speed_mps) and not fit.stationary.any() and fit.support == 0


def test_one_vehicles_returns_count_as_one_position() -> None:
    # a truck 30 m ahead closing at 5 m/s gives five returns within 0.6 m of each other;
    # four posts outvote it by position although its returns outnumber them
    azimuths = [0.05 + 0.004 * k for k in range(5)]
    truck = tuple((30.0 + 0.1 * k, a, -5.0 * math.cos(a)) for k, a in enumerate(azimuths))
    rg, az, rr = scan(POSTS[:4], V_MPS, truck)
    fit = speed_from_scan(rr, az, range_m=rg)
    assert fit.speed_mps == pytest.approx(V_MPS, abs=1e-12)
    assert fit.support == 4
    # counted by returns (no ranges, or positions 0 m apart), the truck wins
    wrong = speed_from_scan(rr, az)
    assert wrong.speed_mps == pytest.approx(5.0, abs=1e-12) and wrong.support == 5
    zero = RadarEgoParams(same_position_m=0.0)
    assert speed_from_scan(rr, az, params=zero, range_m=rg).speed_mps == wrong.speed_mps


def test_traffic_pulling_away_from_a_standing_car_gives_nan_not_a_negative_speed() -> None:
    # every return recedes: five cars pulling away at 3 m/s, nothing stationary in view
    cars = tuple((10.0 + 8.0 * k, 0.1 * (k - 2), 3.0 * math.cos(0.1 * (k - 2))) for k in range(5))
    rg, az, rr = scan((), 0.0, cars)
    assert math.isnan(speed_from_scan(rr, az, range_m=rg).speed_mps)


def test_returns_too_far_off_axis_propose_nothing() -> None:
    # posts at 70 deg (cos 0.34 < min_cos 0.5) propose no speed
    wide = tuple((10.0 + 5 * k, math.radians(70.0) * (-1) ** k) for k in range(6))
    rg, az, rr = scan(wide, V_MPS)
    assert math.isnan(speed_from_scan(rr, az, range_m=rg).speed_mps)
    relaxed = RadarEgoParams(min_cos=0.3)
    assert speed_from_scan(rr, az, params=relaxed, range_m=rg).speed_mps == pytest.approx(V_MPS)


def test_an_empty_scan_gives_nan() -> None:
    fit = speed_from_scan([], [], range_m=[])
    assert math.isnan(fit.speed_mps) and fit.stationary.shape == (0,)


# --- a drive --------------------------------------------------------------------------------


def test_speeds_from_scans_fills_a_scan_without_fit_from_its_neighbours() -> None:
    speeds = (10.0, 10.5, None, 11.0, 11.5)  # scan 2 holds only traffic
    rows: list[tuple[list[float], list[float], list[float]]] = []
    for v in speeds:
        rows.append(scan(POSTS, v) if v is not None else scan((), 0.0, ((20.0, 0.0, 3.0),)))
    start = np.cumsum([0] + [len(r[0]) for r in rows])
    rg, az, rr = (np.concatenate([r[i] for r in rows]) for i in range(3))
    got = speeds_from_scans(rr, az, start, range_m=rg)
    # medians of (10, 10.5), (10, 10.5, 11), (10, 10.5, 11, 11.5), (10.5, 11, 11.5), (11, 11.5)
    np.testing.assert_allclose(got, [10.25, 10.5, 10.75, 11.0, 11.25], atol=1e-12)
    one = RadarEgoParams(median_scans=1)
    raw = speeds_from_scans(rr, az, start, params=one, range_m=rg)
    np.testing.assert_allclose(raw, [10.0, 10.5, np.nan, 11.0, 11.5], atol=1e-12)


def test_no_scans_give_no_speeds() -> None:
    assert speeds_from_scans([], [], [0]).shape == (0,)


@pytest.mark.parametrize(
    ("values", "length", "expected"),
    [
        ([1.0, 100.0, 2.0, 3.0, 4.0], 3, [50.5, 2.0, 3.0, 3.0, 3.5]),
        ([1.0, 100.0, 2.0, 3.0, 4.0], 5, [2.0, 2.5, 3.0, 3.5, 3.0]),
        ([5.0, math.nan, math.nan, math.nan, 7.0], 3, [5.0, 5.0, math.nan, 7.0, 7.0]),
        ([1.0, math.nan, 3.0], 1, [1.0, math.nan, 3.0]),
        ([], 5, []),
    ],
)
def test_running_median(values: list[float], length: int, expected: list[float]) -> None:
    np.testing.assert_array_equal(running_median(values, length), expected)


# --- bad input ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("min_cos", 0.0, "min_cos: expected a cosine in (0, 1], got 0.0"),
        ("min_cos", 1.5, "min_cos: expected a cosine in (0, 1], got 1.5"),
        ("tolerance_mps", 0.0, "tolerance_mps: expected > 0 m/s, got 0.0"),
        ("tolerance_mps", math.nan, "tolerance_mps: expected > 0 m/s, got nan"),
        ("min_stationary", 1, "min_stationary: expected >= 2 positions, got 1"),
        ("same_position_m", -1.0, "same_position_m: expected >= 0 m, got -1.0"),
        ("median_scans", 4, "median_scans: expected an odd count >= 1, got 4"),
        ("median_scans", 0, "median_scans: expected an odd count >= 1, got 0"),
        ("min_speed_mps", math.inf, "min_speed_mps: expected a finite number, got inf"),
    ],
)
def test_bad_params_are_refused(field: str, value: float, message: str) -> None:
    with pytest.raises(ValueError) as err:
        RadarEgoParams(**{field: value})
    assert str(err.value) == message


def test_mismatched_lengths_are_refused() -> None:
    expected = "range_rate_mps, azimuth_rad, range_m: expected as many of each, got 3, 2 and 3"
    with pytest.raises(ValueError) as err:
        speed_from_scan([1.0, 2.0, 3.0], [0.0, 0.1], range_m=[5.0, 6.0, 7.0])
    assert str(err.value) == expected
    with pytest.raises(ValueError) as err:
        speeds_from_scans([1.0, 2.0, 3.0], [0.0, 0.1], [0, 3], range_m=[5.0, 6.0, 7.0])
    assert str(err.value) == expected
    with pytest.raises(ValueError, match="got 2, 2 and 1"):
        speed_from_scan([1.0, 2.0], [0.0, 0.1], range_m=[5.0])


@pytest.mark.parametrize("start", [[1, 3], [0, 2], [0, 4], [0, 2, 1, 3], []])
def test_bad_scan_start_is_refused(start: list[int]) -> None:
    with pytest.raises(ValueError) as err:
        speeds_from_scans([-1.0, -2.0, -3.0], [0.0, 0.1, 0.2], start)
    assert str(err.value) == (
        f"scan_start: expected ascending row offsets from 0 to 3, got {len(start)} offsets "
        "that are not"
    )


def test_a_mount_yaw_that_is_not_finite_is_refused() -> None:
    with pytest.raises(ValueError, match=r"mount_yaw_rad: expected a finite number, got nan"):
        speed_from_scan([-1.0], [0.0], math.nan)
    with pytest.raises(ValueError, match=r"mount_yaw_rad: expected a finite number, got nan"):
        speeds_from_scans([], [], [0], math.nan)


# --- recorded drives ------------------------------------------------------------------------


def drive_errors(name: str) -> tuple[float, np.ndarray]:
    """(fraction of scans with a speed, |speed - CAN speed| (m/s) on those) of a bundled drive."""
    with Drive(DEFAULT_RECORDINGS / name) as d:
        r = d.radar
        assert r is not None
        yaw = d.calibration.radar_mount.yaw_rad
        v = speeds_from_scans(r.range_rate_mps, r.azimuth_rad, r.start, yaw, range_m=r.range_m)
        can = np.array([d.speed_at(int(t)) for t in r.t_ns])
    fitted = np.isfinite(v)
    return float(fitted.mean()), np.abs(v[fitted] - can[fitted])


@pytest.mark.parametrize("name", ["highway", "exurban"])
def test_bundled_drives_with_roadside_give_the_can_speed(
    name: str, report: Callable[[str], None]
) -> None:
    """Measured (same_position_m 1 m), over the scans with a speed: highway 100 % of
    150 scans fitted, |error| median 0.024 m/s, p95 0.18, max 0.51; exurban 76 %, median
    0.032, p95 0.10, max 0.13."""
    fitted, err = drive_errors(name)
    median, p95 = float(np.median(err)), float(np.percentile(err, 95))
    report(
        f"radar ego speed {name}: {fitted:.0%} of scans, |error| median {median:.3f} m/s, "
        f"p95 {p95:.2f}, max {err.max():.2f}"
    )
    assert fitted >= (0.95 if name == "highway" else 0.7)
    assert median < 0.1 and p95 < 0.3


def test_stop_and_go_mostly_has_no_fit_but_no_wrong_one(report: Callable[[str], None]) -> None:
    """The synthetic radar gives stop_and_go 3-8 returns a scan, mostly on vehicles: measured
    20 % of 150 scans with a speed, |error| median 0.019 m/s, p95 0.48, max 0.70
    (a lone fit carried by the running median while the car brakes). Counting returns, not
    positions, gave 40 % but errors up to 9 m/s (module Notes)."""
    fitted, err = drive_errors("stop_and_go")
    report(
        f"radar ego speed stop_and_go: {fitted:.0%} of scans, |error| median "
        f"{float(np.median(err)):.3f} m/s, max {err.max():.2f}"
    )
    assert 0.1 <= fitted < 0.5
    assert float(np.median(err)) < 0.1 and err.max() < 1.0


def test_aimotive_motorway_gets_about_30_mps_on_every_scan(realdata: Path) -> None:
    """The aiMotive night-motorway sample drives at ~30 m/s (the shared data's README);
    measured 29.89-30.13 m/s on all 50 scans of its front radar."""
    files = sorted(glob.glob(str(realdata / "aimotive-night-motorway/sensor/radar/F_LRR_C/*.json")))
    targets = [json.loads(Path(f).read_text())["targets"] for f in files]
    start = np.cumsum([0] + [len(t) for t in targets])
    rows = [x for t in targets for x in t]
    v = speeds_from_scans(
        [x["speed"] for x in rows],
        [x["azimuth"] for x in rows],
        start,
        range_m=[x["range"] for x in rows],
    )
    assert len(v) == 50
    assert np.all((v > 29.5) & (v < 30.5)), v
