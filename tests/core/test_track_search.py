"""Vision searches for tracked vehicles the radar did not return (beyond the papers): a
rendered car whose position and width the test knows, searched for with and without a
radar return, hidden, disagreeing and overlapping."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from roadscenes import RoadRenderer, camera, straight_road

from core.io.frame import RadarTarget
from core.params import ParamsError, VehicleParams
from core.synth.scene import Trajectory
from core.synth.scene import Vehicle as SceneVehicle
from core.track_search import search_tracks, to_search
from core.tracking import Track
from core.vehicle import Vehicle, VehicleResult

PARAMS = VehicleParams()
NOTHING_FOUND = VehicleResult((), ())
CAR_X_M, CAR_Y_M, CAR_WIDTH_M = 20.0, 1.0, 1.8


@pytest.fixture(scope="module")
def car_image() -> np.ndarray:
    """A 1.8 m wide car whose rear face is 20 m ahead, centred 1.0 m left, on the bundled
    drives' road and camera."""
    length = 4.4
    keys = [(0.0, CAR_X_M + length / 2, CAR_Y_M), (10.0, CAR_X_M + length / 2, CAR_Y_M)]
    car = SceneVehicle(1, "car", length, CAR_WIDTH_M, 1.5, 70, Trajectory.from_waypoints(keys))
    image, _ = RoadRenderer(straight_road(speed_mps=0.0, vehicles=[car]), seed=1)(
        0.0, camera().extrinsics.pitch_rad
    )
    return image


def track(
    y_m: float = CAR_Y_M,
    width_m: float = CAR_WIDTH_M,
    unreturned: int = 1,
    confirmed: bool = True,
) -> Track:
    """The tracker's prediction of the car: 20 m ahead, its last box 0.8 x its width high."""
    return Track(
        7, "vehicle", CAR_X_M, y_m, 0.0, 0.0, width_m, 0.2, 0.1, (0.0, 0.0, 10.0, 8.0),
        9, 1, 10, confirmed, None, ((CAR_X_M, y_m),), unreturned,
    )  # fmt: skip


def radar_at(x_m: float, y_m: float) -> RadarTarget:
    return RadarTarget(math.hypot(x_m, y_m), math.atan2(y_m, x_m), 0.0, 10.0, x_m, y_m)


def found_vehicle(box_px: tuple[float, float, float, float], distance_m: float) -> VehicleResult:
    return VehicleResult((), (Vehicle(box_px, distance_m, 0.0, 1.8, distance_m, (0,)),))


def test_a_tracked_car_the_radar_missed_is_found_where_the_track_expects_it(
    car_image: np.ndarray, tmp_path: Path
) -> None:
    result = search_tracks(car_image, camera(), [track()], (), NOTHING_FOUND, PARAMS)
    assert result.track_ids == (7,) and result.track_of == (7,)
    (v,) = result.vehicles
    assert v.target_indices == ()  # no radar target
    assert v.distance_m == CAR_X_M  # the track's prediction
    assert v.lateral_m == pytest.approx(CAR_Y_M, abs=0.1)  # from vision
    assert v.width_m == pytest.approx(CAR_WIDTH_M, abs=0.1)
    (searched,) = result.search.targets
    assert searched.verdict == "vehicle" and searched.area is not None
    assert searched.area.tracked  # the tracked targets' wide area, on the track
    assert searched.area.y_left_m - searched.area.y_right_m == PARAMS.moving_search_width_m
    overlay = cv2.cvtColor(car_image, cv2.COLOR_GRAY2BGR)
    u0, v0, u1, v1 = (round(b) for b in v.box_px)
    cv2.rectangle(overlay, (u0, v0), (u1, v1), (0, 255, 0), 1)
    cv2.imwrite(str(tmp_path / "searched_car.png"), overlay)


def test_only_confirmed_tracks_without_a_return_and_not_long_unreturned_are_searched() -> None:
    cam = camera()
    assert [t.id for t in to_search([track()], (), NOTHING_FOUND, cam, PARAMS)] == [7]
    # a radar target within track_gate_m of the prediction: the radar returned it
    returned = (radar_at(CAR_X_M + 1.0, CAR_Y_M + 0.5),)
    assert to_search([track()], returned, NOTHING_FOUND, cam, PARAMS) == []
    beyond = (radar_at(CAR_X_M + 1.5, CAR_Y_M + 1.0),)  # 1.8 m away
    assert len(to_search([track()], beyond, NOTHING_FOUND, cam, PARAMS)) == 1
    # vision alone has kept it for track_search_frames frames already
    long_unreturned = track(unreturned=PARAMS.track_search_frames)
    assert to_search([long_unreturned], (), NOTHING_FOUND, cam, PARAMS) == []
    assert to_search([track(confirmed=False)], (), NOTHING_FOUND, cam, PARAMS) == []
    off = dataclasses.replace(PARAMS, track_search_frames=0)  # the papers' preset
    assert to_search([track()], (), NOTHING_FOUND, cam, off) == []


def test_a_track_hidden_by_a_nearer_vehicle_is_not_searched(car_image: np.ndarray) -> None:
    cam = camera()
    nearer = found_vehicle((0.0, 0.0, 640.0, 480.0), CAR_X_M - 5.0)
    assert to_search([track()], (), nearer, cam, PARAMS) == []
    # the same box as far as the track: it hides nothing
    beside = found_vehicle((0.0, 0.0, 640.0, 480.0), CAR_X_M)
    assert len(to_search([track()], (), beside, cam, PARAMS)) == 1
    # a nearer box over a corner of the page, not over the car
    corner = found_vehicle((0.0, 0.0, 20.0, 20.0), CAR_X_M - 5.0)
    assert len(search_tracks(car_image, cam, [track()], (), corner, PARAMS).vehicles) == 1


def test_a_box_that_disagrees_with_its_track_or_repeats_a_radar_vehicle_is_dropped(
    car_image: np.ndarray,
) -> None:
    cam = camera()
    (v,) = search_tracks(car_image, cam, [track()], (), NOTHING_FOUND, PARAMS).vehicles
    # the track 1.0 m wider than the car vision finds: searched, not kept
    wide = search_tracks(car_image, cam, [track(width_m=2.8)], (), NOTHING_FOUND, PARAMS)
    assert wide.track_ids == (7,) and wide.vehicles == () and wide.track_of == ()
    # the car already detected from a radar target as far away: not twice
    twice = search_tracks(car_image, cam, [track()], (), found_vehicle(v.box_px, CAR_X_M), PARAMS)
    assert twice.vehicles == ()


def test_nothing_to_search_on_an_empty_road(car_image: np.ndarray) -> None:
    blank = np.full_like(car_image, 90)
    result = search_tracks(blank, camera(), [track()], (), NOTHING_FOUND, PARAMS)
    assert result.track_ids == (7,) and result.vehicles == ()
    assert search_tracks(blank, camera(), [], (), NOTHING_FOUND, PARAMS).track_ids == ()


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("track_search_frames", -1),
        ("track_search_hidden_fraction", 1.5),
        ("track_search_agreement_m", 0.0),
        ("track_search_agreement_m", math.nan),
    ],
)
def test_bad_track_search_params_name_the_field(field: str, value: float) -> None:
    with pytest.raises(ParamsError, match=f"^{field}: expected"):
        VehicleParams(**{field: value})  # type: ignore[arg-type]
