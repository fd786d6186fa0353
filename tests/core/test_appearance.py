"""Tracked vehicles found again by their look (beyond the papers): a rendered car whose
template is taken at 20 m and matched at 25 m, where the test knows its box from the
symmetry search; an empty road, a detected track, a disagreeing track, an old template and
the papers' preset, which find nothing."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from roadscenes import RoadRenderer, camera, straight_road

from core.appearance import Template, find_by_appearance, remember
from core.engine import tracker_measurements
from core.params import VehicleParams
from core.pedestrian import PedestrianResult
from core.synth.scene import Trajectory
from core.synth.scene import Vehicle as SceneVehicle
from core.track_search import search_tracks
from core.tracking import Track
from core.vehicle import Vehicle, VehicleResult

PARAMS = VehicleParams()
NOTHING_FOUND = VehicleResult((), ())
NEAR_X_M, FAR_X_M, CAR_Y_M, CAR_WIDTH_M = 20.0, 25.0, 1.0, 1.8


@pytest.fixture(scope="module")
def frames() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The car's rear face 20 m ahead, then 25 m ahead two seconds later, 1.0 m left; and
    the same road without it."""
    length = 4.4
    keys = [(0.0, NEAR_X_M + length / 2, CAR_Y_M), (2.0, FAR_X_M + length / 2, CAR_Y_M)]
    car = SceneVehicle(1, "car", length, CAR_WIDTH_M, 1.5, 70, Trajectory.from_waypoints(keys))
    pitch = camera().extrinsics.pitch_rad
    render = RoadRenderer(straight_road(speed_mps=0.0, vehicles=[car]), seed=1)
    near, _ = render(0.0, pitch)
    far, _ = render(2.0, pitch)
    empty, _ = RoadRenderer(straight_road(speed_mps=0.0), seed=1)(0.0, pitch)
    return near, far, empty


def track(
    x_m: float, width_m: float = CAR_WIDTH_M, misses: int = 1, source: int | None = None
) -> Track:
    return Track(
        7, "vehicle", x_m, CAR_Y_M, 0.0, 0.0, width_m, 0.2, 0.1, (0.0, 0.0, 10.0, 8.0),
        9, misses, 10, True, source, ((x_m, CAR_Y_M),), 0,
    )  # fmt: skip


def symmetry_box(image: np.ndarray, x_m: float) -> Vehicle:
    """The car's box as the symmetry search frames it on `image`, `x_m` ahead."""
    (v,) = search_tracks(image, camera(), [track(x_m)], (), NOTHING_FOUND, PARAMS).vehicles
    return v


def template_at_near(near: np.ndarray) -> dict[int, Template]:
    seen = dataclasses.replace(symmetry_box(near, NEAR_X_M), target_indices=(0,))
    return remember({}, [track(NEAR_X_M, misses=0, source=0)], near, [seen], 1, PARAMS)


def test_a_tracked_car_is_found_by_its_look_where_the_track_expects_it(
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    near, far, _ = frames
    templates = template_at_near(near)
    (template,) = templates.values()
    assert template.distance_m == NEAR_X_M and template.age_frames == 0
    assert not template.patch.flags.writeable
    (match,) = find_by_appearance(far, camera(), [track(FAR_X_M)], templates, (), PARAMS)
    assert match.track_id == 7 and match.ncc >= PARAMS.appearance_min_ncc
    v = match.vehicle
    assert v.target_indices == () and v.distance_m == FAR_X_M  # the track's prediction
    assert v.lateral_m == pytest.approx(CAR_Y_M, abs=0.1)
    assert v.width_m == pytest.approx(CAR_WIDTH_M, abs=0.15)
    # where the symmetry search frames the car at 25 m, within a pixel and a half
    assert v.box_px == pytest.approx(symmetry_box(far, FAR_X_M).box_px, abs=1.5)


def test_nothing_is_found_on_an_empty_road_or_for_a_track_vision_already_framed(
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    near, far, empty = frames
    templates = template_at_near(near)
    assert find_by_appearance(empty, camera(), [track(FAR_X_M)], templates, (), PARAMS) == ()
    framed = symmetry_box(far, FAR_X_M)
    assert find_by_appearance(far, camera(), [track(FAR_X_M)], templates, [framed], PARAMS) == ()
    # a track 1 m wider than the car: the match disagrees with it
    wide = [track(FAR_X_M, width_m=CAR_WIDTH_M + 1.0)]
    assert find_by_appearance(far, camera(), wide, templates, (), PARAMS) == ()
    off = dataclasses.replace(PARAMS, appearance_max_age_frames=0)  # the papers' preset
    assert find_by_appearance(far, camera(), [track(FAR_X_M)], templates, (), off) == ()
    assert find_by_appearance(far, camera(), [track(-1.0)], templates, (), PARAMS) == ()


def test_a_template_ages_without_radar_vehicles_and_is_forgotten(
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    near, _, _ = frames
    templates = template_at_near(near)
    missed = [track(NEAR_X_M, misses=1)]
    for age in range(1, PARAMS.appearance_max_age_frames + 1):
        templates = remember(templates, missed, near, (), 0, PARAMS)
        assert templates[7].age_frames == age
    assert remember(templates, missed, near, (), 0, PARAMS) == {}
    # measured by a vehicle found without radar (the track search's): no new template
    searched = [track(NEAR_X_M, misses=0, source=0)]
    assert remember({}, searched, near, [symmetry_box(near, NEAR_X_M)], 0, PARAMS) == {}
    off = dataclasses.replace(PARAMS, appearance_max_age_frames=0)  # the papers' preset
    measured = [track(NEAR_X_M, misses=0, source=0)]
    assert remember({}, measured, near, [symmetry_box(near, NEAR_X_M)], 1, off) == {}
    tentative = [dataclasses.replace(track(NEAR_X_M, misses=0, source=0), confirmed=False)]
    assert remember({}, tentative, near, [symmetry_box(near, NEAR_X_M)], 1, PARAMS) == {}


def test_a_match_is_a_measurement_of_its_track_alone(
    frames: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    near, far, _ = frames
    (match,) = find_by_appearance(
        far, camera(), [track(FAR_X_M)], template_at_near(near), (), PARAMS
    )
    detected = Vehicle((0.0, 0.0, 10.0, 8.0), 40.0, -3.0, 1.7, 40.0, (0,))
    no_people = PedestrianResult((0, 0), None, np.zeros((0, 1)), np.zeros((0, 1)), ())  # type: ignore[arg-type]
    first, second = tracker_measurements(
        VehicleResult((), (detected,)), no_people, (), frozenset(), appearance=(match,)
    )
    assert first.for_track is None and first.source_index == 0
    assert second.for_track == 7 and second.source_index == 1  # after the frame's vehicles
    assert second.x_m == FAR_X_M and second.box_px == match.vehicle.box_px
