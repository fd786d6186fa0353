"""Radar points steadied over frames (core/radar_smoothing.py): known answers derived from the
module's steps."""

from __future__ import annotations

import math

import pytest

from core.ego import EgoMotion
from core.io.frame import RadarTarget
from core.radar_smoothing import MISSED_SCANS, RememberedPoint, smooth_centres

DT_S = 0.1
SMOOTHING_S = 0.2
GATE_M = 1.0
WEIGHT = 1 - math.exp(-DT_S / SMOOTHING_S)
MOVING_SPEED_MPS = 3.0


def _target(x_m: float, y_m: float, range_rate_mps: float = 0.0) -> RadarTarget:
    """A target seen by a radar at the vehicle frame's origin."""
    return RadarTarget.from_polar(
        math.hypot(x_m, y_m), math.atan2(y_m, x_m), range_rate_mps, 10.0, 0.0, 0.0
    )


def _scan(
    remembered: tuple[RememberedPoint, ...],
    radar: list[RadarTarget],
    ego: EgoMotion | None = None,
    speed_mps: float = 0.0,
    smoothing_s: float = SMOOTHING_S,
) -> tuple[tuple[float, ...], tuple[RememberedPoint, ...]]:
    return smooth_centres(
        remembered, radar, ego, speed_mps, DT_S, smoothing_s, GATE_M, MOVING_SPEED_MPS
    )


def test_off_centres_every_area_on_its_own_point_and_remembers_nothing():
    radar = [_target(20.0, 1.0), _target(30.0, -2.0)]
    assert _scan((), radar, smoothing_s=0.0) == ((1.0, -2.0), ())


def test_a_first_scan_centres_on_the_points():
    centres, remembered = _scan((), [_target(20.0, 1.0)])
    assert centres == pytest.approx((1.0,))
    assert [(round(p.x_m, 9), round(p.y_m, 9), p.missed) for p in remembered] == [(20.0, 1.0, 0)]


def test_points_scattered_about_a_still_vehicle_are_centred_nearer_it():
    """Points alternate 0.4 m either side of a still vehicle at y = 1 m, the car still: the
    exponential mean c_n = c_(n-1) + w (y_n - c_(n-1)) swings by 0.4 w / (2 - w) about it."""
    remembered: tuple[RememberedPoint, ...] = ()
    centres = []
    for n in range(60):
        centre, remembered = _scan(remembered, [_target(20.0, 1.0 + 0.4 * (-1) ** n)])
        centres.append(centre[0])
    swing = 0.4 * WEIGHT / (2 - WEIGHT)
    assert max(abs(c - 1.0) for c in centres[-6:]) == pytest.approx(swing, abs=1e-6)
    assert swing < 0.1


def test_a_still_object_seen_while_the_car_moves_and_turns_is_where_it_is_measured():
    """The car drives 1 m and turns 0.02 rad per frame; an object standing at (30, 3) in the
    first frame is measured exactly: moved by the car's motion, the remembered point lies on
    every new measurement, so each centre is the measurement itself."""
    speed_mps = 1.0 / DT_S
    ego = EgoMotion(1.0, 0.0, 0.02, DT_S)
    x, y = 30.0, 3.0
    remembered: tuple[RememberedPoint, ...] = ()
    for _ in range(8):
        target = _target(x, y, range_rate_mps=-speed_mps * x / math.hypot(x, y))
        centre, remembered = _scan(remembered, [target], ego, speed_mps)
        assert centre[0] == pytest.approx(y, abs=1e-9)
        cos, sin = math.cos(-ego.dyaw_rad), math.sin(-ego.dyaw_rad)
        x, y = cos * (x - ego.dx_m) - sin * y, sin * (x - ego.dx_m) + cos * y


def test_a_slow_vehicle_pulling_away_along_its_line_of_sight_is_predicted_there():
    """The car still, a vehicle recedes at 2 m/s (slower than moving) along its line of sight
    from (20, 2): the remembered point moves on by 0.2 m along it per frame and meets each
    measurement."""
    speed_mps = 2.0
    x, y = 20.0, 2.0
    remembered: tuple[RememberedPoint, ...] = ()
    for _ in range(6):
        centre, remembered = _scan(
            remembered, [_target(x, y, range_rate_mps=speed_mps)], EgoMotion.still(DT_S)
        )
        assert centre[0] == pytest.approx(y, abs=1e-9)
        r = math.hypot(x, y)
        x, y = x + speed_mps * DT_S * x / r, y + speed_mps * DT_S * y / r


def test_a_point_beyond_the_lateral_gate_is_its_own_and_the_old_one_is_kept_then_forgotten():
    _, remembered = _scan((), [_target(20.0, 0.0)])
    centre, remembered = _scan(remembered, [_target(20.0, GATE_M + 0.2)])
    assert centre == pytest.approx((GATE_M + 0.2,))
    assert sorted((round(p.y_m, 9), p.missed) for p in remembered) == [(0.0, 1), (GATE_M + 0.2, 0)]
    for _ in range(MISSED_SCANS):
        _, remembered = _scan(remembered, [])
    assert [(round(p.y_m, 9), p.missed) for p in remembered] == [(GATE_M + 0.2, MISSED_SCANS)]
    _, remembered = _scan(remembered, [])
    assert remembered == ()


def test_one_remembered_point_centres_one_target_the_nearest():
    _, remembered = _scan((), [_target(20.0, 0.0)])
    centres, _ = _scan(remembered, [_target(20.0, 0.8), _target(20.0, 0.2)])
    assert centres == pytest.approx((0.8, WEIGHT * 0.2))


def test_a_moving_target_keeps_its_own_point():
    """A target faster than MOVING_SPEED_MPS has a wide area: it is centred on its point."""
    _, remembered = _scan((), [_target(20.0, 0.0, range_rate_mps=5.0)])
    centres, _ = _scan(remembered, [_target(20.5, 0.6, range_rate_mps=5.0)])
    assert centres == (0.6,)
