"""Tracking (beyond the papers): ego compensation, convergence, lifecycle, ids, assignment."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.ego import EgoMotion, step
from core.params import ParamsError, TrackingParams
from core.tracking import (
    Kind,
    Measurement,
    Track,
    Tracker,
    TrackResult,
    clipped_to_image,
    coasting_boxes,
    confirmed_sources,
    expected_boxes,
    solve_assignment,
)

DT_S = 0.1
P = TrackingParams()
STILL = EgoMotion.still(DT_S)


def _m(
    x_m: float, y_m: float, index: int = 0, kind: Kind = "vehicle", width_m: float = 1.8
) -> Measurement:
    return Measurement(kind, x_m, y_m, width_m, (0.0, 0.0, 10.0, 10.0), index)


def _by_source(result: TrackResult, kind: Kind = "vehicle") -> dict[int, Track]:
    return {t.source_index: t for t in result.of_kind(kind, False) if t.source_index is not None}


def _vehicle_frame(
    world_xy: tuple[float, float], pose: tuple[float, float, float]
) -> tuple[float, float]:
    """A world point seen from the car at pose (x, y, heading): R(-heading) (p - car)."""
    dx, dy = world_xy[0] - pose[0], world_xy[1] - pose[1]
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return (c * dx + s * dy, -s * dx + c * dy)


def _compose(pose: tuple[float, float, float], ego: EgoMotion) -> tuple[float, float, float]:
    """The car's world pose after `ego`, which is expressed in the car's frame at `pose`."""
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return (
        pose[0] + c * ego.dx_m - s * ego.dy_m,
        pose[1] + s * ego.dx_m + c * ego.dy_m,
        pose[2] + ego.dyaw_rad,
    )


# --- ego compensation and the motion model ---------------------------------------------------


@pytest.mark.parametrize("yaw_rate_radps", [0.0, 0.2, -0.3])
def test_parked_car_stays_parked_while_the_ego_car_drives_and_turns(
    yaw_rate_radps: float,
) -> None:
    # The parked car is at a fixed world point; the ego car drives at 5 m/s, straight or on a
    # circle; each frame measures the exact point in the current vehicle frame.
    parked = (30.0, 4.0)
    ego = step(5.0, yaw_rate_radps, DT_S)
    tracker = Tracker(P)
    pose = (0.0, 0.0, 0.0)
    result = tracker.update([_m(*_vehicle_frame(parked, pose))], None, DT_S)
    for _ in range(35):
        pose = _compose(pose, ego)
        truth = _vehicle_frame(parked, pose)
        result = tracker.update([_m(*truth)], ego, DT_S)
        (track,) = result.tracks
        assert (track.x_m, track.y_m) == pytest.approx(truth, abs=1e-9)
        assert (track.vx_mps, track.vy_mps) == pytest.approx((0.0, 0.0), abs=1e-9)
    assert track.id == 1 and track.confirmed and track.hits == 36
    # A car parked in the world stood at the same point of the current frame all along.
    assert len(track.history_m) == P.history_length
    for point in track.history_m:
        assert point == pytest.approx(truth, abs=1e-9)


def test_parked_car_with_noisy_measurements_keeps_speed_near_zero() -> None:
    rng = np.random.default_rng(7)
    parked = (25.0, -3.0)
    ego = step(15.0, 0.15, DT_S)
    tracker = Tracker(P)
    pose = (0.0, 0.0, 0.0)
    result = tracker.update([_m(*_vehicle_frame(parked, pose))], STILL, DT_S)
    for _ in range(30):
        pose = _compose(pose, ego)
        truth = _vehicle_frame(parked, pose)
        noisy = truth + rng.normal(0.0, (0.3, 0.1))
        result = tracker.update([_m(noisy[0], noisy[1])], ego, DT_S)
    (track,) = result.tracks
    assert track.id == 1
    assert math.hypot(track.vx_mps, track.vy_mps) < 1.0
    assert (track.x_m, track.y_m) == pytest.approx(truth, abs=0.3)


def test_constant_velocity_target_converges_to_its_true_velocity() -> None:
    # Ego straight at 10 m/s; the target drives at (12, -0.5) m/s over the ground, so it is
    # seen at (30 + 2 t, 3 - 0.5 t) in the vehicle frame.
    ego = step(10.0, 0.0, DT_S)
    tracker = Tracker(P)
    for k in range(50):
        t_s = k * DT_S
        result = tracker.update([_m(30.0 + 2.0 * t_s, 3.0 - 0.5 * t_s)], ego, DT_S)
    (track,) = result.tracks
    assert (track.vx_mps, track.vy_mps) == pytest.approx((12.0, -0.5), abs=0.05)
    assert (track.x_m, track.y_m) == pytest.approx((30.0 + 2.0 * 4.9, 3.0 - 0.5 * 4.9), abs=0.01)
    assert track.width_m == pytest.approx(1.8)


def test_unknown_ego_motion_inflates_the_position_sigma() -> None:
    # confirm_frames = 1: a tentative track would end at its first miss
    params = dataclasses.replace(P, confirm_frames=1)
    known, unknown = Tracker(params), Tracker(params)
    for tracker in (known, unknown):
        tracker.update([_m(20.0, 0.0)], None, DT_S)
    a = known.update([], STILL, DT_S).tracks[0]
    b = unknown.update([], None, DT_S).tracks[0]
    assert b.sigma_x_m**2 == pytest.approx(a.sigma_x_m**2 + P.unknown_ego_sigma_m**2)
    assert b.sigma_y_m**2 == pytest.approx(a.sigma_y_m**2 + P.unknown_ego_sigma_m**2)


@pytest.mark.parametrize("dyaw_rad", [math.pi / 2, math.pi / 4, -0.3])
def test_an_ego_turn_turns_the_position_covariance(dyaw_rad: float) -> None:
    # A vehicle track is born with variances (radar_sigma_x_m^2, vision_sigma_y_m^2); with
    # dt = 0 nothing is added, so after the car turns in place by dyaw the track sees the
    # same ellipse turned by -dyaw: var_x = cos^2 a + sin^2 b, var_y = sin^2 a + cos^2 b.
    tracker = Tracker(dataclasses.replace(P, confirm_frames=1))
    tracker.update([_m(20.0, 0.0)], None, 0.0)
    (track,) = tracker.update([], EgoMotion(0.0, 0.0, dyaw_rad, 0.0), 0.0).tracks
    c2, s2 = math.cos(dyaw_rad) ** 2, math.sin(dyaw_rad) ** 2
    a, b = P.radar_sigma_x_m**2, P.vision_sigma_y_m**2
    assert (track.x_m, track.y_m) == pytest.approx(
        (20.0 * math.cos(dyaw_rad), -20.0 * math.sin(dyaw_rad)), abs=1e-12
    )
    assert track.sigma_x_m**2 == pytest.approx(c2 * a + s2 * b, abs=1e-12)
    assert track.sigma_y_m**2 == pytest.approx(s2 * a + c2 * b, abs=1e-12)
    assert track.history_m == ((track.x_m, track.y_m),) * 2


def test_measurement_sigma_per_kind_at_birth() -> None:
    # A new track's position covariance is the measurement's.
    result = Tracker(P).update(
        [
            _m(20.0, 0.0, 0, "vehicle"),
            _m(20.0, 0.0, 0, "pedestrian", 0.6),
            _m(2.0, 0.0, 1, "pedestrian", 0.6),
            _m(20.0, 5.0, 0, "guard_rail", 0.0),
        ],
        None,
        DT_S,
    )
    sigmas = [(t.kind, t.sigma_x_m, t.sigma_y_m) for t in result.tracks]
    assert sigmas == [
        ("vehicle", P.radar_sigma_x_m, P.vision_sigma_y_m),
        ("pedestrian", pytest.approx(0.1 * 20.0), P.vision_sigma_y_m),
        ("pedestrian", P.pedestrian_min_sigma_x_m, P.vision_sigma_y_m),
        ("guard_rail", P.radar_sigma_x_m, P.guard_rail_sigma_y_m),
    ]


# --- lifecycle --------------------------------------------------------------------------------


def test_a_detection_missing_for_one_frame_keeps_its_track_and_id() -> None:
    tracker = Tracker(P)
    seen = []
    for k in range(10):
        result = tracker.update([] if k == 5 else [_m(20.0, 1.0)], STILL, DT_S)
        (track,) = result.tracks
        seen.append(track.id)
        assert result.ended == ()
        if k == 5:
            assert (track.misses, track.source_index, track.confirmed) == (1, None, True)
            assert confirmed_sources(result, "vehicle") == frozenset()
    assert seen == [1] * 10
    assert (track.hits, track.misses, track.age) == (9, 0, 10)


def test_predicted_gives_where_the_next_update_expects_confirmed_tracks() -> None:
    tracker = Tracker(P)
    ego = EgoMotion(dx_m=1.0, dy_m=0.0, dyaw_rad=0.0, dt_s=DT_S)
    assert tracker.predicted("vehicle", ego, DT_S) == ()
    # a car 20 m ahead keeping pace with the ego car (its ground speed that of the ego car)
    for _ in range(P.confirm_frames + 20):
        tracker.update([_m(20.0, 1.0), _m(8.0, -3.0, 0, "pedestrian")], ego, DT_S)
    before = tracker.state()
    (ahead,) = tracker.predicted("vehicle", ego, DT_S)
    # the ego car moves 1 m, the car as much: still 20 m ahead
    assert (ahead.x_m, ahead.y_m) == pytest.approx((20.0, 1.0), abs=0.05)
    assert ahead.confirmed and ahead.kind == "vehicle"
    # the tracker is unchanged: the next update gives what it gave without the look ahead
    (expected,) = tracker.update([], ego, DT_S).of_kind("vehicle")
    tracker.restore(before)
    tracker.predicted("vehicle", ego, DT_S)
    (again,) = tracker.update([], ego, DT_S).of_kind("vehicle")
    assert (again.x_m, again.y_m, again.sigma_x_m) == (
        expected.x_m,
        expected.y_m,
        expected.sigma_x_m,
    )
    assert (again.x_m, again.y_m) == pytest.approx((ahead.x_m, ahead.y_m))
    # tentative tracks are not expected anywhere
    fresh = Tracker(P)
    fresh.update([_m(20.0, 1.0)], ego, DT_S)
    assert fresh.predicted("vehicle", ego, DT_S) == ()
    with pytest.raises(ValueError, match="kind"):
        tracker.predicted("car", ego, DT_S)  # type: ignore[arg-type]


def test_a_confirmed_track_is_kept_through_max_missed_frames_then_ended() -> None:
    tracker = Tracker(P)
    for _ in range(P.confirm_frames):
        tracker.update([_m(20.0, 1.0)], STILL, DT_S)
    for misses in range(1, P.max_missed_frames + 1):
        (track,) = tracker.update([], STILL, DT_S).tracks
        assert track.misses == misses
    result = tracker.update([], STILL, DT_S)
    assert result == TrackResult((), (1,))
    # ids are never reused
    assert tracker.update([_m(20.0, 1.0)], STILL, DT_S).tracks[0].id == 2


def test_confirmation_after_confirm_frames_hits() -> None:
    tracker = Tracker(P)
    flags = [tracker.update([_m(20.0, 1.0)], STILL, DT_S).tracks[0].confirmed for _ in range(4)]
    assert flags == [False, False, True, True]  # confirm_frames = 3
    once = Tracker(dataclasses.replace(P, confirm_frames=1))
    assert once.update([_m(20.0, 1.0)], STILL, DT_S).tracks[0].confirmed


def test_a_pedestrian_is_confirmed_after_its_own_number_of_hits() -> None:
    # the same object seen as a vehicle, a person and a rail return on every frame: each kind
    # confirms after its own count (a pedestrian after 2, the others after 3)
    assert (P.pedestrian_confirm_frames, P.confirm_frames) == (2, 3)
    tracker = Tracker(P)
    kinds: tuple[Kind, ...] = ("vehicle", "pedestrian", "guard_rail")
    seen = []
    for _ in range(3):
        frame = [_m(20.0, 4.0 * k, 0, kind, 0.6) for k, kind in enumerate(kinds)]
        result = tracker.update(frame, STILL, DT_S)
        seen.append({t.kind: t.confirmed for t in result.tracks})
    assert [s["pedestrian"] for s in seen] == [False, True, True]
    assert [s["vehicle"] for s in seen] == [s["guard_rail"] for s in seen] == [False, False, True]
    papers = Tracker(dataclasses.replace(P, pedestrian_confirm_frames=3))
    flags = [
        papers.update([_m(20.0, 0.0, 0, "pedestrian", 0.6)], STILL, DT_S).tracks[0].confirmed
        for _ in range(3)
    ]
    assert flags == [False, False, True]


def test_a_one_frame_false_positive_is_never_confirmed_and_is_ended() -> None:
    tracker = Tracker(P)
    for k in range(8):
        ghost = [_m(40.0, -5.0, 1)] if k == 4 else []
        result = tracker.update([_m(20.0, 1.0), *ghost], STILL, DT_S)
        if k == 4:
            fp = _by_source(result)[1]
            assert (fp.id, fp.confirmed) == (2, False)
            assert confirmed_sources(result, "vehicle") == frozenset({0})
        # kept, tentative, through tentative_max_missed_frames misses, then ended
        if k == 5 + P.tentative_max_missed_frames:
            assert result.ended == (2,)
        assert [t.id for t in result.confirmed] == ([1] if k >= P.confirm_frames - 1 else [])
    assert [t.id for t in result.tracks] == [1]


@pytest.mark.parametrize("tentative_max_missed_frames", [0, 1])
def test_a_vehicle_seen_on_two_frames_of_three_is_confirmed_when_a_miss_is_kept(
    tentative_max_missed_frames: int,
) -> None:
    params = dataclasses.replace(P, tentative_max_missed_frames=tentative_max_missed_frames)
    tracker = Tracker(params)
    seen = [k % 3 != 2 for k in range(9)]  # hit, hit, miss, hit, hit, miss, ...
    results = [tracker.update([_m(20.0, 1.0)] if hit else [], STILL, DT_S) for hit in seen]
    if tentative_max_missed_frames:
        # one track: tentative after two hits, kept through the miss, confirmed at its third
        assert [[t.id for t in r.tracks] for r in results] == [[1]] * 9
        assert [bool(r.confirmed) for r in results] == [False] * 3 + [True] * 6
    else:
        # born again after every miss, never reaching three hits
        assert all(not r.confirmed for r in results)
        assert [r.ended for r in results if r.ended] == [(1,), (2,), (3,)]


def test_a_vehicle_track_is_shown_from_its_second_hit_only_on_frames_it_is_measured() -> None:
    assert (P.show_vehicles_after_hits, P.confirm_frames) == (2, 3)
    seen = [True, True, False, True, True]  # hit, hit, miss, hit (the third: confirmed), hit
    tracker, papers = Tracker(P), Tracker(dataclasses.replace(P, show_vehicles_after_hits=0))
    shown, confirmed, ids, shown_papers = [], [], [], []
    for hit in seen:
        frame = [_m(20.0, 1.0)] if hit else []
        result = tracker.update(frame, STILL, DT_S)
        shown.append([t.id for t in result.of_kind("vehicle")])
        confirmed.append([t.id for t in result.confirmed])
        ids.append([t.id for t in result.tracks])
        shown_papers.append([t.id for t in papers.update(frame, STILL, DT_S).of_kind("vehicle")])
    assert shown == [[], [1], [], [1], [1]]  # the miss: a tentative track coasts unseen
    assert confirmed == [[], [], [], [1], [1]]  # its life is a tentative track's
    assert ids == [[1]] * 5
    assert shown_papers == [[], [], [], [1], [1]]
    # only vehicles: guard-rail labels come from confirmed tracks, people confirm on their own
    rails = Tracker(P)
    for _ in range(2):
        result = rails.update([_m(20.0, -4.0, 0, "guard_rail", 0.3)], STILL, DT_S)
    assert result.of_kind("guard_rail") == () and confirmed_sources(result, "guard_rail") == set()


def test_an_early_track_within_the_clearance_of_a_confirmed_one_is_not_shown() -> None:
    assert (P.early_clearance_ahead_m, P.early_clearance_across_m) == (4.0, 2.0)
    tracker = Tracker(P)
    for _ in range(3):
        tracker.update([_m(20.0, 1.0)], STILL, DT_S)  # track 1, confirmed at its third hit
    # two newcomers: 3 m ahead and 1.5 m across of track 1 (within), and 5 m across (clear)
    shown = []
    for _ in range(3):
        frame = [_m(20.0, 1.0, 0), _m(23.0, 2.5, 1), _m(20.0, 6.0, 2)]
        shown.append([t.id for t in tracker.update(frame, STILL, DT_S).of_kind("vehicle")])
    assert shown == [[1], [1, 3], [1, 2, 3]]  # track 2 waits until it is confirmed itself


def test_two_pedestrians_crossing_keep_their_ids() -> None:
    # Same distance, opposite lateral speeds, crossing at y = 0 at t = 2.05 s (between frames).
    rng = np.random.default_rng(3)
    tracker = Tracker(P)
    ids: list[tuple[int, int]] = []
    for k in range(41):
        t_s = k * DT_S
        y_a = 3.075 - 1.5 * t_s
        noise = rng.normal(0.0, (0.2, 0.02, 0.2, 0.02))
        walkers = [
            _m(15.0 + noise[0], y_a + noise[1], 0, "pedestrian", 0.6),
            _m(15.0 + noise[2], -y_a + noise[3], 1, "pedestrian", 0.6),
        ]
        result = tracker.update(walkers, STILL, DT_S)
        tracks = _by_source(result, "pedestrian")
        ids.append((tracks[0].id, tracks[1].id))
    assert set(ids) == {(1, 2)}
    a, b = result.of_kind("pedestrian")
    assert a.y_m < -2.5 < 2.5 < b.y_m
    assert (a.vy_mps, b.vy_mps) == pytest.approx((-1.5, 1.5), abs=0.2)


def test_kinds_never_associate_with_each_other() -> None:
    tracker = Tracker(P)
    for _ in range(3):
        tracker.update([_m(20.0, 0.0)], STILL, DT_S)
    result = tracker.update(
        [_m(20.0, 0.0, 0, "guard_rail", 0.0), _m(20.0, 0.0, 0, "pedestrian", 0.6)], STILL, DT_S
    )
    kinds = [(t.id, t.kind, t.source_index, t.confirmed) for t in result.tracks]
    assert kinds == [
        (1, "vehicle", None, True),
        (2, "guard_rail", 0, False),
        (3, "pedestrian", 0, False),
    ]
    assert result.of_kind("vehicle") == (result.tracks[0],)
    assert result.of_kind("guard_rail") == ()
    assert confirmed_sources(result, "vehicle") == frozenset()


@pytest.mark.parametrize("likelihood_cost", [True, False])
def test_a_newborn_duplicate_does_not_take_the_confirmed_tracks_detection(
    likelihood_cost: bool,
) -> None:
    # A car at 20 m is tracked; one frame adds a second detection of it 2 m too far (a second
    # radar point), which starts a track whose speed is unknown. The next frame's single
    # detection at 20.9 m lies 0.9 m from the confirmed track, whose S is small
    # (nu^T S^-1 nu ~ 6), and 1.1 m from the newborn, whose S is large (~ 0.5): by the
    # Mahalanobis distance alone the newborn takes it, by the likelihood the confirmed track.
    params = dataclasses.replace(P, likelihood_cost=likelihood_cost)
    tracker = Tracker(params)
    for _ in range(5):
        tracker.update([_m(20.0, 0.0)], STILL, DT_S)
    tracker.update([_m(20.0, 0.0), _m(22.0, 0.0, index=1)], STILL, DT_S)
    result = tracker.update([_m(20.9, 0.0)], STILL, DT_S)
    taker = _by_source(result)[0]
    assert taker.id == (1 if likelihood_cost else 2)


def test_the_gate_cap_in_metres_splits_far_detections() -> None:
    tracker = Tracker(P)
    tracker.update([_m(20.0, 0.0)], STILL, DT_S)
    result = tracker.update([_m(20.0 + P.gate_m + 0.1, 0.0)], STILL, DT_S)
    assert [(t.id, t.misses) for t in result.tracks] == [(1, 1), (2, 0)]  # 1 missed it


def test_a_fast_lead_car_is_kept_from_its_second_frame() -> None:
    # Both cars at 30 m/s: the lead car stays 40 m ahead, but its new track (speed 0) predicts
    # it 3 m nearer on the second frame, beyond a 2 m cap and inside the default gate.
    ego = step(30.0, 0.0, DT_S)
    tracker = Tracker(P)
    results = [tracker.update([_m(40.0, 0.0)], ego, DT_S) for _ in range(5)]
    assert [r.tracks[0].id for r in results] == [1] * 5
    (track,) = results[-1].tracks
    assert track.confirmed and track.vx_mps == pytest.approx(30.0, abs=3.0)
    narrow = Tracker(dataclasses.replace(P, gate_m=2.0, tentative_max_missed_frames=0))
    narrow.update([_m(40.0, 0.0)], ego, DT_S)
    assert narrow.update([_m(40.0, 0.0)], ego, DT_S).ended == (1,)


def _follow(
    params: TrackingParams, kind: Kind, ego_speed_mps: float, speed_mps: float, frames: int = 30
) -> list[TrackResult]:
    """Exact detections of one object starting 15 m ahead, 1 m left, moving along x over
    the ground at speed_mps, seen from the ego car at ego_speed_mps."""
    tracker, ego = Tracker(params), step(ego_speed_mps, 0.0, DT_S)
    results = []
    for k in range(frames):
        x_m = 15.0 + (speed_mps - ego_speed_mps) * k * DT_S
        results.append(tracker.update([_m(x_m, 1.0, 0, kind, 0.6)], ego, DT_S))
    return results


@pytest.mark.parametrize(
    ("ego_speed_mps", "speed_mps", "kept"),
    [
        (0.0, 1.5, True),  # walking away from a stopped car
        (25.0, 2.5, True),  # a jog beside the road, seen at highway speed
        (0.0, 6.0, False),  # a sprint: faster than the gate's person
        (25.0, 25.0, False),  # a wheel of the car ahead, keeping pace with the ego car
    ],
)
def test_a_pedestrian_track_faster_than_a_person_is_not_confirmed_a_vehicle_track_is(
    ego_speed_mps: float, speed_mps: float, kept: bool
) -> None:
    vehicle = _follow(P, "vehicle", ego_speed_mps, speed_mps)
    assert [r.tracks[0].id for r in vehicle] == [1] * 30 and vehicle[-1].tracks[0].confirmed
    pedestrian = _follow(P, "pedestrian", ego_speed_mps, speed_mps)
    # one track takes every detection: none is ended, no second one starts
    assert [[t.id for t in r.tracks] for r in pedestrian] == [[1]] * 30
    last = pedestrian[-1].tracks[0]
    assert last.vx_mps == pytest.approx(speed_mps, abs=0.1)
    assert last.confirmed == kept
    if not kept:  # without the gate it would be shown
        off = dataclasses.replace(P, pedestrian_max_speed_mps=1e6)
        assert _follow(off, "pedestrian", ego_speed_mps, speed_mps)[-1].tracks[0].confirmed


def test_at_highway_speed_a_vehicle_part_is_shown_two_frames_at_most() -> None:
    # confirmed on its second hit, the speed estimate is sure by the fourth
    results = _follow(P, "pedestrian", 25.0, 25.0)
    assert sum(r.tracks[0].confirmed for r in results) <= 2
    papers = _follow(dataclasses.replace(P, pedestrian_confirm_frames=3), "pedestrian", 25.0, 25.0)
    assert sum(r.tracks[0].confirmed for r in papers) <= 1


def test_the_speed_gate_waits_for_the_speed_to_be_sure() -> None:
    # the first speed estimates are uncertain: without a margin a 6 m/s runner's track
    # stops being shown sooner than with one (here: it is never shown), and with a huge
    # margin never
    def last_shown(sigmas: float) -> int:
        params = dataclasses.replace(P, pedestrian_speed_gate_sigmas=sigmas)
        results = _follow(params, "pedestrian", 0.0, 6.0)
        return max((k for k, r in enumerate(results) if r.tracks[0].confirmed), default=-1)

    assert last_shown(0.0) < last_shown(P.pedestrian_speed_gate_sigmas) < 29
    assert last_shown(100.0) == 29


def test_a_too_fast_pedestrian_track_ends_at_its_first_miss() -> None:
    tracker, ego = Tracker(P), step(25.0, 0.0, DT_S)
    for _ in range(10):
        result = tracker.update([_m(15.0, 1.0, 0, "pedestrian", 0.6)], ego, DT_S)
    assert not result.tracks[0].confirmed
    assert tracker.update([], ego, DT_S).ended == (1,)


def test_guard_rail_verdicts_are_confirmed_by_time_correlation() -> None:
    # A rail post seen every frame while driving; a slow vehicle mislabelled once is not.
    ego = step(10.0, 0.0, DT_S)
    tracker = Tracker(P)
    for k in range(4):
        rail = _m(30.0 - 1.0 * k, 6.0, 0, "guard_rail", 0.0)
        once = [_m(15.0, -2.0, 1, "guard_rail", 0.0)] if k == 3 else []
        result = tracker.update([rail, *once], ego, DT_S)
        expected = {0} if k >= P.confirm_frames - 1 else set()
        assert confirmed_sources(result, "guard_rail") == expected


def test_reset_restarts_ids_and_replays_identically() -> None:
    rng = np.random.default_rng(11)
    frames = [
        [_m(20.0 + rng.normal(0, 0.3), rng.normal(0, 0.1), j) for j in range(int(rng.integers(3)))]
        for _ in range(15)
    ]
    egos = [None if k % 5 == 0 else step(12.0, 0.1, DT_S) for k in range(15)]
    tracker = Tracker(P)
    first = [tracker.update(f, e, DT_S) for f, e in zip(frames, egos, strict=True)]
    tracker.reset()
    second = [tracker.update(f, e, DT_S) for f, e in zip(frames, egos, strict=True)]
    assert second == first
    assert min(t.id for r in first for t in r.tracks) == 1


def test_a_restored_state_gives_the_updates_that_followed_it() -> None:
    # a lead car and a pedestrian, a passing false positive, the ego car turning: every
    # step changes the kept tracks' filters in place
    frames = [
        [_m(20.0 - 0.5 * k, 0.2, 0), _m(12.0, 3.0 - 0.1 * k, 0, "pedestrian", 0.6)]
        + ([_m(35.0, -4.0, 1)] if k in (4, 9) else [])
        for k in range(14)
    ]
    ego = step(12.0, 0.1, DT_S)
    tracker = Tracker(P)
    for f in frames[:6]:
        tracker.update(f, ego, DT_S)
    kept = tracker.state()
    assert {t.kind for t in kept.tracks} == {"vehicle", "pedestrian"}
    after = [tracker.update(f, ego, DT_S) for f in frames[6:]]
    assert any(t.confirmed and t.age > 6 for t in after[-1].tracks)
    assert max(t.id for r in after for t in r.tracks) >= kept.next_id  # a track born after
    for taker in (Tracker(P), tracker):
        taker.restore(kept)
        assert [taker.update(f, ego, DT_S) for f in frames[6:]] == after


def test_a_state_whose_next_id_is_taken_is_refused_by_name() -> None:
    tracker = Tracker(P)
    tracker.update([_m(20.0, 0.0, 0), _m(30.0, 2.0, 1)], STILL, DT_S)
    kept = tracker.state()
    assert kept.next_id == 3
    with pytest.raises(ValueError, match=r"state\.next_id: expected an id above the tracks' \(2\)"):
        tracker.restore(dataclasses.replace(kept, next_id=2))


def test_empty_measurements_and_zero_dt() -> None:
    tracker = Tracker(P)
    assert tracker.update([], None, DT_S) == TrackResult((), ())
    assert tracker.update([], STILL, 0.0) == TrackResult((), ())
    tracker.update([_m(20.0, 0.0)], STILL, 0.0)
    (track,) = tracker.update([_m(20.0, 0.0)], STILL, 0.0).tracks
    assert (track.x_m, track.y_m, track.hits) == (pytest.approx(20.0), pytest.approx(0.0), 2)


# --- the assignment ---------------------------------------------------------------------------


def _brute_force(cost: np.ndarray) -> tuple[int, float]:
    """Most allowed pairs, then least cost, over every partial matching."""
    rows, cols = cost.shape
    best = (0, 0.0)
    for choice in itertools.product([None, *range(cols)], repeat=rows):
        used = [c for c in choice if c is not None]
        if len(set(used)) != len(used):
            continue
        pairs = [(r, c) for r, c in enumerate(choice) if c is not None]
        if any(not math.isfinite(cost[r, c]) for r, c in pairs):
            continue
        total = float(sum(cost[r, c] for r, c in pairs))
        if len(pairs) > best[0] or (len(pairs) == best[0] and total < best[1]):
            best = (len(pairs), total)
    return best


def test_assignment_equals_brute_force_on_random_small_matrices() -> None:
    rng = np.random.default_rng(2024)
    for _ in range(400):
        shape = (int(rng.integers(0, 6)), int(rng.integers(0, 6)))
        cost = rng.uniform(0.0, 10.0, shape)
        cost[rng.random(shape) < rng.uniform(0.0, 0.7)] = np.inf
        pairs = solve_assignment(cost)
        rows = [r for r, _ in pairs]
        cols = [c for _, c in pairs]
        assert rows == sorted(set(rows)) and len(set(cols)) == len(cols)
        assert all(math.isfinite(cost[r, c]) for r, c in pairs)
        count, total = _brute_force(cost)
        assert len(pairs) == count
        assert sum(cost[r, c] for r, c in pairs) == pytest.approx(total, abs=1e-9)


def test_assignment_prefers_the_global_optimum_to_greedy() -> None:
    # Greedy takes (0, 0) = 1 and leaves row 1 to column 1 = 10; optimal: 2 + 2.
    cost = np.array([[1.0, 2.0], [2.0, 10.0]])
    assert solve_assignment(cost) == ((0, 1), (1, 0))
    assert solve_assignment(np.full((2, 3), np.inf)) == ()
    assert solve_assignment(np.zeros((0, 3))) == ()


def test_assignment_rejects_bad_costs() -> None:
    with pytest.raises(ValueError, match=r"^cost: "):
        solve_assignment(np.array([[np.nan]]))
    with pytest.raises(ValueError, match=r"^cost: "):
        solve_assignment(np.zeros(3))


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"kind": "car"}, "kind"),
        ({"x_m": math.nan}, "x_m"),
        ({"y_m": math.inf}, "y_m"),
        ({"width_m": -0.1}, "width_m"),
        ({"box_px": (10.0, 0.0, 5.0, 5.0)}, "box_px"),
        ({"box_px": (0.0, 0.0, math.nan, 5.0)}, "box_px"),
        ({"box_px": (0.0, 0.0, 5.0)}, "box_px"),
        ({"source_index": -1}, "source_index"),
        ({"for_track": "7"}, "for_track"),
    ],
)
def test_bad_measurement_names_the_field(change: dict[str, object], field: str) -> None:
    good = {"kind": "vehicle", "x_m": 20.0, "y_m": 0.0, "width_m": 1.8}
    good |= {"box_px": (0.0, 0.0, 1.0, 1.0), "source_index": 0}
    with pytest.raises(ValueError, match=f"^{field}: expected"):
        Measurement(**(good | change))  # type: ignore[arg-type]


@pytest.mark.parametrize("dt_s", [-0.1, math.nan, math.inf])
def test_bad_dt_names_dt_s(dt_s: float) -> None:
    with pytest.raises(ValueError, match=r"^dt_s: expected"):
        Tracker(P).update([], None, dt_s)


def test_duplicate_source_index_and_unknown_kind_are_rejected() -> None:
    with pytest.raises(ValueError, match=r"^measurements: .*'vehicle', 0\) appears twice"):
        Tracker(P).update([_m(20.0, 0.0), _m(30.0, 0.0)], None, DT_S)
    # the same index in two kinds is fine: each kind has its own list
    Tracker(P).update([_m(20.0, 0.0), _m(20.0, 0.0, 0, "pedestrian")], None, DT_S)
    with pytest.raises(ValueError, match=r"^kind: expected one of vehicle, pedestrian"):
        TrackResult((), ()).of_kind("car")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("confirm_frames", 0),
        ("show_vehicles_after_hits", -1),
        ("early_clearance_ahead_m", -1.0),
        ("early_clearance_across_m", math.nan),
        ("max_missed_frames", -1),
        ("tentative_max_missed_frames", -1),
        ("gate_m", 0.0),
        ("gate_chi2", math.nan),
        ("vehicle_accel_psd_m2ps3", -1.0),
        ("pedestrian_accel_psd_m2ps3", 0.0),
        ("guard_rail_accel_psd_m2ps3", -0.1),
        ("radar_sigma_x_m", 0.0),
        ("vision_sigma_y_m", -0.3),
        ("guard_rail_sigma_y_m", math.inf),
        ("pedestrian_sigma_x_fraction", 0.0),
        ("pedestrian_min_sigma_x_m", 0.0),
        ("width_sigma_m", 0.0),
        ("width_walk_m2ps", -0.01),
        ("initial_velocity_sigma_mps", 0.0),
        ("unknown_ego_sigma_m", math.nan),
        ("history_length", 0),
        ("pedestrian_max_speed_mps", 0.0),
        ("pedestrian_max_speed_mps", math.nan),
        ("pedestrian_speed_gate_sigmas", -1.0),
        ("pedestrian_coasting_speed_mps", 0.0),
        ("pedestrian_coasting_speed_mps", math.inf),
    ],
)
def test_bad_tracking_params_name_the_field(field: str, value: float) -> None:
    with pytest.raises(ParamsError, match=f"^{field}: expected"):
        TrackingParams(**{field: value})  # type: ignore[arg-type]
    assert TrackingParams(guard_rail_accel_psd_m2ps3=0.0, unknown_ego_sigma_m=0.0)


# --- coasting boxes ----------------------------------------------------------------------------

# a pinhole 1.3 m above the road at the vehicle frame's origin, looking straight ahead: the
# ground point (x, y, 0) lands at u = 320 - 700 y / x, v = 240 + 700 * 1.3 / x
FLAT_CAMERA = CameraModel(Intrinsics(700.0, 700.0, 320.0, 240.0, 640, 480), Extrinsics(1.3))


def _track(
    track_id: int, x_m: float, misses: int, kind: Kind = "vehicle", confirmed: bool = True
) -> Track:
    return Track(
        track_id, kind, x_m, 1.0, 0.0, 0.0, 2.0, 0.3, 0.2, (300.0, 200.0, 340.0, 230.0),
        5, misses, 6, confirmed, None if misses else 0, ((x_m, 1.0),),
    )  # fmt: skip


def test_a_coasting_track_shows_its_last_box_where_it_expects_its_object_now() -> None:
    coasting, measured = _track(1, 20.0, misses=2), _track(2, 20.0, misses=0)
    result = coasting_boxes(TrackResult((coasting, measured), (7,)), FLAT_CAMERA)
    # sides at y = 2 and 0 m, bottom on the road at 20 m; the last box's height / width
    # (30 / 40) kept for the new width of 70 px
    assert result.tracks[0].box_px == pytest.approx((250.0, 285.5 - 52.5, 320.0, 285.5))
    assert result.tracks[0] == dataclasses.replace(coasting, box_px=result.tracks[0].box_px)
    assert result.tracks[1] == measured
    assert result.ended == (7,)


def test_a_coasting_pedestrian_moves_at_most_a_step_per_miss_from_its_last_hit() -> None:
    # measured at (20, 1), then predicted 3 m on (a noisy speed) over 2 misses: at 0.5 m per
    # miss the box stands 1 m on, at (21, 1); with a long step, where predicted
    walked = dataclasses.replace(
        _track(1, 23.0, misses=2, kind="pedestrian"),
        history_m=((19.0, 1.0), (20.0, 1.0), (21.5, 1.0), (23.0, 1.0)),
    )
    short = coasting_boxes(TrackResult((walked,), ()), FLAT_CAMERA, 0.5).tracks[0]
    long = coasting_boxes(TrackResult((walked,), ()), FLAT_CAMERA, 10.0).tracks[0]
    assert short.box_px[3] == pytest.approx(240.0 + 700.0 * 1.3 / 21.0)
    assert long.box_px[3] == pytest.approx(240.0 + 700.0 * 1.3 / 23.0)
    assert (short.x_m, short.y_m) == (23.0, 1.0)  # the track itself is not moved
    # a vehicle's box follows its prediction whatever the step
    car = dataclasses.replace(walked, kind="vehicle")
    moved = coasting_boxes(TrackResult((car,), ()), FLAT_CAMERA, 0.5).tracks[0]
    assert moved.box_px[3] == pytest.approx(240.0 + 700.0 * 1.3 / 23.0)
    # a history too short to reach the last hit: the prediction
    young = dataclasses.replace(walked, history_m=((23.0, 1.0),))
    alone = coasting_boxes(TrackResult((young,), ()), FLAT_CAMERA, 0.5).tracks[0]
    assert alone.box_px[3] == pytest.approx(240.0 + 700.0 * 1.3 / 23.0)


def test_only_confirmed_coasting_boxes_in_front_of_the_camera_move() -> None:
    kept = (
        _track(1, 20.0, misses=1, confirmed=False),  # tentative: not shown
        _track(2, 20.0, misses=1, kind="guard_rail"),  # a radar point, no box of its own
        _track(3, -4.0, misses=1),  # behind the camera
    )
    assert coasting_boxes(TrackResult(kept, ()), FLAT_CAMERA).tracks == kept


def test_boxes_running_off_the_image_are_cut_at_its_border() -> None:
    w, h = FLAT_CAMERA.intrinsics.width_px, FLAT_CAMERA.intrinsics.height_px
    inside = _track(1, 20.0, misses=0)
    beside = dataclasses.replace(
        _track(2, 6.0, misses=1),
        box_px=(-80.0, 150.0, 60.0, h + 40.0),
        body_px=(-80.0, 150.0, 90.0, h + 40.0),
    )
    out = (w + 10.0, 100.0, w + 50.0, 200.0)
    gone = dataclasses.replace(_track(3, 6.0, misses=1), box_px=out)
    person_gone = dataclasses.replace(_track(5, 6.0, misses=1, kind="pedestrian"), box_px=out)
    # a guard-rail track's box is its search area: it stays, cut to an empty box
    rail = dataclasses.replace(_track(6, 6.0, misses=1, kind="guard_rail"), box_px=out)
    result = clipped_to_image(
        TrackResult((inside, beside, gone, person_gone, rail), (4,)), FLAT_CAMERA
    )
    assert [t.id for t in result.tracks] == [1, 2, 6]  # the camera sees nothing of 3 and 5
    assert result.tracks[0] == inside
    assert result.tracks[1].box_px == (-0.5, 150.0, 60.0, h - 0.5)
    assert result.tracks[1].body_px == (-0.5, 150.0, 90.0, h - 0.5)
    assert result.tracks[2].box_px == (w - 0.5, 100.0, w - 0.5, 200.0)
    assert result.ended == (4,)


# --- detections searched for a track (core.track_search) ------------------------------------


def _confirmed_pair() -> tuple[Tracker, dict[int, Track]]:
    """Two parked cars 20 m ahead, 3.5 m apart across, confirmed over confirm_frames."""
    tracker = Tracker(P)
    for _ in range(P.confirm_frames):
        result = tracker.update([_m(20.0, 0.0, 0), _m(20.0, 3.5, 1)], STILL, DT_S)
    return tracker, _by_source(result)


def test_a_searched_detection_goes_to_its_track_and_does_not_measure_distance() -> None:
    tracker, before = _confirmed_pair()
    ahead = {t.id: t for t in tracker.predicted("vehicle", STILL, DT_S)}
    near, far = before[0].id, before[1].id
    # searched for the far track, at its predicted distance, 0.2 m nearer the other car
    searched = Measurement("vehicle", ahead[far].x_m, 3.3, 1.8, (0.0, 0.0, 9.0, 9.0), 0, far)
    result = {t.id: t for t in tracker.update([searched], STILL, DT_S).tracks}
    assert result[far].source_index == 0 and result[far].misses == 0
    assert result[far].unreturned == 1
    assert result[far].x_m == pytest.approx(ahead[far].x_m, abs=1e-6)  # x left as predicted
    assert 3.3 < result[far].y_m < 3.5  # y measured
    assert result[far].box_px == (0.0, 0.0, 9.0, 9.0)
    assert result[near].misses == 1 and result[near].unreturned == 1
    # radar-backed again: unreturned starts over
    result = {t.id: t for t in tracker.update([_m(20.0, 3.5)], STILL, DT_S).tracks}
    assert result[far].unreturned == 0 and result[near].unreturned == 2


def test_a_searched_detection_never_starts_a_track_or_goes_to_another() -> None:
    tracker, before = _confirmed_pair()
    ids = sorted(t.id for t in before.values())
    # for a track that does not exist, and for one whose gates it misses by far
    lost = Measurement("vehicle", 20.0, 0.0, 1.8, (0.0, 0.0, 1.0, 1.0), 0, 99)
    beyond = Measurement("vehicle", 20.0, 30.0, 1.8, (0.0, 0.0, 1.0, 1.0), 1, ids[0])
    result = tracker.update([lost, beyond], STILL, DT_S)
    assert sorted(t.id for t in result.tracks) == ids
    assert all(t.misses == 1 for t in result.tracks)


def test_expected_boxes_are_the_coasting_geometry() -> None:
    ahead, behind, flat = _track(1, 20.0, 0), _track(2, -4.0, 0), _track(3, 20.0, 0)
    flat = dataclasses.replace(flat, box_px=(5.0, 5.0, 5.0, 9.0))  # no width to scale
    assert expected_boxes([ahead, behind, flat], FLAT_CAMERA) == [
        pytest.approx((250.0, 285.5 - 52.5, 320.0, 285.5)),
        None,
        None,
    ]
    assert expected_boxes([], FLAT_CAMERA) == []
