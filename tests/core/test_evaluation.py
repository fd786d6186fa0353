"""The evaluation's statistics on hand-made truth and detections whose figures the tests work
out, and `fusionscope evaluate` on the bundled drives (JSON keys and types, formats, bad
input, the baselines beside the engine, the README's tables).
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS, main
from core.evaluation import report
from core.evaluation.evaluate import RecordingReport, evaluate_recording, total
from core.evaluation.mot import IOU_MATCH, MotAccumulator
from core.evaluation.objects import (
    RAIL_HEIGHT_M,
    score_mask,
    score_pedestrians,
    score_pitch,
    score_rails,
)
from core.evaluation.report import BASELINE_TIMING_TITLE, TIMED_TITLES
from core.evaluation.vehicles import (
    DISTANCE_MATCH_M,
    EVENT_MIN_FRAMES,
    SUPPLIED_NEAR_M,
    Estimate,
    FrameVehicles,
    event_stats,
    frame_stats,
    lies_on,
    score_frame,
)
from core.io.frame import RadarTarget
from core.io.groundtruth import FrameTruth, TruthObject
from core.params import MotionStereoParams, Params, params_from
from core.search_area import iou
from tests.conftest import REAL_IMPORTS

TOLERANCE_M = 0.4


@dataclass(frozen=True)
class Area:
    target_index: int
    x_m: float
    y_left_m: float
    y_right_m: float


def car(
    id_: int, x_m: float, y_m: float, width_m: float = 1.8, occlusion: float = 0.0
) -> TruthObject:
    return TruthObject(
        id=id_,
        cls="car",
        box_px=(0.0, 0.0, 10.0, 10.0),
        position_m=(x_m, y_m, 0.0),
        size_m=(4.5, width_m, 1.5),
        velocity_mps=(0.0, 0.0),
        radar_seen=True,
        occlusion=occlusion,
    )


def target(x_m: float, y_m: float) -> RadarTarget:
    return RadarTarget(math.hypot(x_m, y_m), math.atan2(y_m, x_m), 0.0, 1.0, x_m, y_m)


def area(i: int, t: RadarTarget, half_m: float = 1.25) -> Area:
    return Area(i, t.x_m, t.y_m + half_m, t.y_m - half_m)


# --- paper 001's frame-based statistics ------------------------------------------------------


def _twelve_frames() -> list[FrameVehicles]:
    """12 frames; on each, car 1 at 20 m straight ahead, car 2 at 30 m, 4 m to the left, a
    sign at 15 m, 3 m to the right, and a hidden car 3 (70 % occluded, never counted).

    - car 1: a target on its rear in every frame; refined on frames 0-5 (RD), found 1 m off on
      6-8 (FN: not refined), not validated on 9-11 (FN);
    - car 2: its target 1.2 m to its side (on its footprint, give or take the margin), so its
      area does not contain it (RFN), except on frame 11 where the target is on its centre
      and an estimate refines it (RD);
    - the sign: a target every frame, validated by vision on frames 0-1 (FP), not on 2-11
      (NVO);
    - car 3's target is on a vehicle: neither FP nor NVO although it is validated.
    """
    frames = []
    for i in range(12):
        objects = [car(1, 20.0, 0.0), car(2, 30.0, 4.0), car(3, 25.0, -4.0, occlusion=0.7)]
        t1 = target(20.5, 0.0)
        t2 = target(31.0, 4.0 if i == 11 else 5.2)
        sign = target(15.0, -3.0)
        t3 = target(26.0, -4.0)
        radar = [t1, t2, sign, t3]
        areas = [area(k, t) for k, t in enumerate(radar)]
        estimates = [Estimate(26.0, -4.0, 1.8, (3,))]
        if i <= 5:
            estimates.append(Estimate(20.1, 0.1, 1.9, (0,)))
        elif i <= 8:
            estimates.append(Estimate(21.0, 0.0, 1.8, (0,)))
        if i == 11:
            estimates.append(Estimate(30.2, 4.1, 1.7, (1,)))
        if i <= 1:
            estimates.append(Estimate(15.0, -3.0, 0.8, (2,)))
        frames.append(score_frame(i, objects, radar, areas, estimates, TOLERANCE_M))
    return frames


def test_frame_statistics_on_a_twelve_frame_example() -> None:
    s = frame_stats(_twelve_frames())
    assert (s.rd, s.fn, s.rfn, s.fp, s.nvo) == (6 + 1, 6, 11, 2, 10)
    assert s.framed == 24  # cars 1 and 2 on 12 frames; car 3 is hidden
    assert s.fn_at == tuple((i, 1) for i in range(6, 12))
    assert s.rfn_at == tuple((i, 2) for i in range(11))
    assert s.fp_at == ((0, 2), (1, 2))
    assert s.nvo_at == tuple((i, 2) for i in range(2, 12))


def test_the_distance_error_of_every_vehicle_found_across() -> None:
    frames = _twelve_frames()
    # car 1: +0.1 m on frames 0-5, +1.0 m on 6-8 (found across, not refined), none on 9-11;
    # car 2: +0.2 m on frame 11; the hidden car 3 and the sign count not
    assert [f.distance_error_m for f in frames[5:9]] == [(pytest.approx(0.1),)] + [
        (pytest.approx(1.0),)
    ] * 3
    assert frames[11].distance_error_m == (pytest.approx(0.2),)
    s = frame_stats(frames)
    assert len(s.distance_error_m) == 10
    assert s.distance_error_median_m == pytest.approx(0.1)
    assert s.distance_error_p90_m == pytest.approx(1.0)
    # an estimate found across but farther than DISTANCE_MATCH_M measures nothing
    objects, radar = [car(1, 20.0, 0.0)], [target(20.0, 0.0)]
    far = Estimate(20.0 + DISTANCE_MATCH_M + 0.1, 0.0, 1.8, (0,))
    assert (
        score_frame(0, objects, radar, [area(0, radar[0])], [far], TOLERANCE_M).distance_error_m
        == ()
    )
    assert math.isnan(frame_stats([]).distance_error_median_m)


def test_rd_over_rd_and_fn_by_class() -> None:
    """A car refined on 3 frames and not on 1, a van refined on 1 of 4, a truck never
    supplied to vision (RFN): 0.75, 0.25 and none."""
    frames = []
    for i in range(4):
        van = dataclasses.replace(car(2, 30.0, 4.0), cls="van")
        truck = dataclasses.replace(car(3, 40.0, -4.0), cls="truck")
        radar = [target(20.0, 0.0), target(30.0, 4.0)]  # none on the truck
        estimates = [Estimate(20.0 if i < 3 else 22.0, 0.0, 1.8, (0,))]
        if i == 0:
            estimates.append(Estimate(30.0, 4.0, 1.8, (1,)))
        areas = [area(k, t) for k, t in enumerate(radar)]
        frames.append(
            score_frame(i, [car(1, 20.0, 0.0), van, truck], radar, areas, estimates, TOLERANCE_M)
        )
    s = frame_stats(frames)
    assert s.supplied_refined_share("car") == 0.75
    assert s.supplied_refined_share("van") == 0.25
    assert math.isnan(s.supplied_refined_share("truck")) and s.rfn == 4
    assert report._by_class(s) == "0.75 / 0.25 / -"
    assert (s + s).supplied_refined_share("van") == 0.25  # drives add up


def test_rd_over_rd_and_fn_within_50_m() -> None:
    """Cars at 20, 45 and 55 m, each supplied to vision (in an area): refined at 20 and 55 m,
    not at 45 m. Within SUPPLIED_NEAR_M the share is 1 of 2; the 55 m car counts in the
    overall figure only."""
    distances = (20.0, 45.0, 55.0)
    objects = [car(k + 1, x, 0.0 if k == 0 else 4.0 * k) for k, x in enumerate(distances)]
    radar = [target(o.position_m[0], o.position_m[1]) for o in objects]
    estimates = [
        Estimate(x, y, 1.8, (k,))
        for k, (x, y, _) in enumerate(o.position_m for o in objects)
        if k != 1
    ]
    areas = [area(k, t) for k, t in enumerate(radar)]
    s = frame_stats([score_frame(0, objects, radar, areas, estimates, TOLERANCE_M)])
    assert (s.rd, s.fn, s.rfn) == (2, 1, 0) and SUPPLIED_NEAR_M == 50.0
    assert s.supplied_refined_share_near == 0.5
    assert (s + s).supplied_refined_share_near == 0.5  # drives add up
    assert math.isnan(frame_stats([]).supplied_refined_share_near)


def test_refined_needs_distance_lateral_and_width_each_within_the_tolerance() -> None:
    objects, radar = [car(1, 20.0, 0.0, width_m=1.8)], [target(20.0, 0.0)]
    areas = [area(0, radar[0])]

    def verdict(e: Estimate) -> str:
        return score_frame(0, objects, radar, areas, [e], TOLERANCE_M).vehicles[0][1]

    assert verdict(Estimate(20.39, 0.39, 2.19, (0,))) == "rd"
    assert verdict(Estimate(20.41, 0.0, 1.8, (0,))) == "fn"
    assert verdict(Estimate(20.0, -0.41, 1.8, (0,))) == "fn"
    assert verdict(Estimate(20.0, 0.0, 2.21, (0,))) == "fn"


def test_each_refined_vehicle_gets_the_best_box_iou_of_the_estimates_that_refine_it() -> None:
    objects = [car(1, 20.0, 0.0), car(2, 30.0, 4.0)]  # true boxes (0, 0, 10, 10)
    radar = [target(20.0, 0.0), target(30.0, 4.0)]
    areas = [area(k, t) for k, t in enumerate(radar)]
    estimates = [
        Estimate(20.0, 0.0, 1.8, (0,), (0.0, 0.0, 10.0, 5.0)),  # half the box: 0.5
        Estimate(20.1, 0.0, 1.8, (0,), (0.0, 0.0, 10.0, 8.0)),  # 0.8, the best of car 1's
        Estimate(30.0, 4.0, 1.8, (1,), None),  # car 2: refined, but no box
        Estimate(40.0, 0.0, 1.8, (), (0.0, 0.0, 10.0, 10.0)),  # refines nothing
    ]
    frame = score_frame(0, objects, radar, areas, estimates, TOLERANCE_M)
    assert frame.vehicles == ((1, "rd"), (2, "rd"))
    assert frame.rd_iou[0] == pytest.approx(0.8) and math.isnan(frame.rd_iou[1])
    s = frame_stats([frame, frame])
    assert s.rd_iou_median == pytest.approx(0.8)  # NaN (no box) is left out
    assert s.rd_iou_share(0.6) == 1.0 and s.rd_iou_share(0.9) == 0.0


def test_an_estimate_without_radar_off_every_vehicle_is_a_false_positive() -> None:
    """Vision found it where a track expected a vehicle (core.track_search), or a track
    coasted there: an FP listed as -1 - its place among the estimates, unless it lies on a
    truth vehicle (framed or not)."""
    objects = [car(1, 20.0, 0.0), car(2, 25.0, -4.0, occlusion=0.7)]
    radar = [target(20.0, 0.0)]
    estimates = [
        Estimate(20.1, 0.0, 1.8, ()),  # refines car 1 without radar: RD, not FP
        Estimate(26.0, -4.0, 1.8, ()),  # on the hidden car 2: not FP
        Estimate(40.0, 3.0, 1.8, ()),  # on nothing: FP
    ]
    frame = score_frame(0, objects, radar, [area(0, radar[0])], estimates, TOLERANCE_M)
    assert frame.vehicles == ((1, "rd"),)
    assert frame.obstacles == ((-3, "fp"),)
    s = frame_stats([frame])
    assert (s.rd, s.fp, s.nvo) == (1, 1, 0) and s.fp_at == ((0, -3),)


def test_a_return_beside_a_vehicle_is_a_false_positive_only_when_its_estimate_is_off_it() -> None:
    """A radar point 1.6 m from a car's centre line (0.2 m beyond the margin) is no
    vehicle's; vision boxing the car from it reports the car (no FP), vision boxing empty
    road beside it reports nothing true (FP), and without an estimate it is a not-validated
    obstacle."""
    objects = [car(1, 20.0, 0.0)]
    radar = [target(20.0, 1.6), target(30.0, 1.6), target(40.0, 1.6)]
    assert not any(lies_on(t.x_m, t.y_m, objects[0]) for t in radar)
    estimates = [
        Estimate(20.0, 0.1, 1.8, (0,)),  # the car, found from the point beside it
        Estimate(30.0, 1.0, 1.8, (1,)),  # 10 m behind the car: on nothing
    ]
    areas = [area(k, t) for k, t in enumerate(radar)]
    frame = score_frame(0, objects, radar, areas, estimates, TOLERANCE_M)
    assert frame.vehicles == ((1, "rd"),)
    assert frame.obstacles == ((1, "fp"), (2, "nvo"))


def test_a_vehicle_wider_than_the_area_is_a_radar_false_negative() -> None:
    truck = car(1, 20.0, 0.0, width_m=2.6)  # wider than the 2.5 m area
    radar = [target(20.0, 0.0)]
    (verdict,) = score_frame(0, [truck], radar, [area(0, radar[0])], [], TOLERANCE_M).vehicles
    assert verdict == (1, "rfn")


def test_an_area_whose_target_lies_on_another_vehicle_does_not_contain_this_one() -> None:
    near, far = car(1, 20.0, 0.0), car(2, 40.0, 0.0)
    radar = [target(20.0, 0.0)]  # only the near car returned
    result = score_frame(0, [near, far], radar, [area(0, radar[0])], [], TOLERANCE_M)
    assert dict(result.vehicles) == {1: "fn", 2: "rfn"}


# --- events (paper 001, table I) ------------------------------------------------------------


def _frames_of(verdicts: dict[int, list[str]]) -> list[FrameVehicles]:
    length = max(len(v) for v in verdicts.values())
    return [
        FrameVehicles(
            i,
            tuple((vid, v[i]) for vid, v in verdicts.items() if i < len(v)),
            (),  # type: ignore[misc]
        )
        for i in range(length)
    ]


def test_an_event_is_a_vehicle_framed_in_more_than_ten_frames() -> None:
    assert EVENT_MIN_FRAMES == 10
    ten = {1: ["rd"] * 10}
    eleven = {1: ["rd"] * 11}
    assert event_stats(_frames_of(ten)).events == 0
    assert event_stats(_frames_of(eleven)).events == 1


def test_events_are_radar_misses_not_refined_or_refined() -> None:
    e = event_stats(
        _frames_of(
            {
                1: ["rfn"] * 12,  # radar never supplied it
                2: ["rfn"] * 6 + ["fn"] * 6,  # supplied, never refined
                3: ["rfn"] * 11 + ["rd"],  # refined once is refined
                4: ["fn"] * 5 + ["rd"] * 7,
                5: ["rd"] * 3,  # too short: no event
            }
        )
    )
    assert (e.events, e.radar_miss, e.not_refined, e.refined) == (4, 1, 1, 2)
    assert e.refined_share == 0.5
    assert e.refined_share_of_radar_supplied == pytest.approx(2 / 3)


def test_the_papers_table_totals_give_its_shares() -> None:
    # paper 001, table I: 69 events, 9 radar misses, 16 not refined, 44 refined
    from core.evaluation.vehicles import EventStats

    e = EventStats(69, 9, 16, 44)
    assert round(e.refined_share, 2) == 0.64
    assert round(e.refined_share_of_radar_supplied, 2) == 0.73


# --- pedestrians, guard rails, motion stereo, pitch -------------------------------------------


def person(id_: int, box: tuple[float, float, float, float], x_m: float = 10.0) -> TruthObject:
    return TruthObject(
        id_, "pedestrian", box, (x_m, 0.0, 0.0), (0.5, 0.6, 1.7), (0.0, 0.0), False, 0.0
    )


def test_pedestrian_recall_and_precision_at_thirty_percent_overlap() -> None:
    truth = [person(1, (100, 100, 120, 160)), person(2, (300, 100, 320, 160), x_m=60.0)]
    boxes = [
        (102, 100, 122, 160),  # on person 1: IoU 18/22 > 0.3
        (300, 100, 320, 160),  # person 2 beyond 40 m: not visible, but a true box
        (500, 100, 520, 160),  # on nobody
        (110, 130, 130, 190),  # IoU 100/1100 with person 1: false
    ]
    s = score_pedestrians(7, boxes, truth, 3.0, 40.0)
    assert (s.visible, s.found, s.boxes, s.true_boxes) == (1, 1, 4, 2)
    assert s.false_at == ((7, 2), (7, 3)) and s.missed_at == ()
    assert score_pedestrians(7, [], truth, 3.0, 40.0).missed_at == ((7, 1),)


def test_guard_rail_false_negatives_false_positives_and_vehicles_labelled() -> None:
    rail = np.array([[5.0, -5.0], [60.0, -5.0]])  # a rail 5 m to the right
    radar = [target(20.0, -5.2), target(30.0, -5.0), target(25.0, 0.0), target(40.0, 3.0)]
    truth = FrameTruth(3, 0, 0.0, (car(1, 24.0, 0.0),), ())
    labelled = frozenset({0, 2, 3})
    s = score_rails(3, [0, 1, 2, 3], labelled, radar, truth, [rail])
    assert (s.slow_targets, s.rail_returns, s.labelled) == (4, 2, 3)
    assert s.fn_at == ((3, 1),)  # the rail return at 30 m was not labelled
    assert s.fp_at == ((3, 2), (3, 3))  # the car and a target on nothing
    assert s.vehicles_labelled_at == ((3, 2),)
    assert RAIL_HEIGHT_M > 0


def test_mask_recall_and_precision_on_a_hand_made_mask() -> None:
    params = MotionStereoParams()
    walker = TruthObject(
        5, "pedestrian", (9.5, 109.5, 19.5, 129.5), (10.0, 0.0, 0.0), (0.5, 0.6, 1.7),
        (1.0, 0.0), False, 0.0,
    )  # fmt: skip
    truth = FrameTruth(0, 0, 0.0, (walker,), ())
    mask = np.zeros((100, 64), dtype=np.uint8)  # image rows 100..199
    mask[10:20, 10:20] = 255  # half the walker's 10 x 20 box
    mask[80:90, 50:60] = 255  # 100 pixels on nothing
    s = score_mask(0, mask, 100, truth, params, still=False)
    assert (s.obstacles, s.obstacles_hit) == (1, 1)
    assert (s.truth_px, s.truth_marked_px) == (200, 100)
    assert s.marked_px == 200 and s.marked_on_objects_px == 100
    standing = score_mask(
        0, mask, 100, FrameTruth(0, 0, 0.0, (person(6, walker.box_px),), ()), params, still=True
    )
    assert standing.obstacles == 0  # background subtraction cannot see a standing person


def test_pitch_errors_in_degrees() -> None:
    s = score_pitch(0.02, 0.01, 0.0) + score_pitch(0.0, 0.01, 0.0)
    assert s.rms_deg == pytest.approx(math.degrees(0.01))
    assert s.max_deg == pytest.approx(math.degrees(0.01))
    assert s.calibration_rms_deg == pytest.approx(math.degrees(0.01))


# --- CLEAR-MOT and IDF1 ------------------------------------------------------------------------


def _box(u: float) -> tuple[float, float, float, float]:
    return (u, 100.0, u + 20.0, 140.0)


def test_perfect_tracking_scores_one() -> None:
    acc = MotAccumulator()
    for i in range(5):
        acc.update(i, [(1, _box(10 * i)), (2, _box(300))], [(7, _box(10 * i)), (8, _box(300))])
    s = acc.score()
    assert (s.mota, s.motp, s.idf1, s.id_switches) == (1.0, 1.0, 1.0, 0)


def test_a_track_on_an_ignored_object_is_neither_a_hit_nor_false() -> None:
    acc = MotAccumulator()
    # object 1 tracked by 7; track 8 follows an object the radar never saw (ignored); track 9
    # overlaps the ignored box by less than IOU_MATCH and stays false
    ignored = _box(300)
    barely = (300.0 + 20.0 * (1 - IOU_MATCH) + 1.0, 100.0, 340.0, 140.0)
    assert iou(barely, ignored) < IOU_MATCH
    acc.update(0, [(1, _box(0))], [(7, _box(0)), (8, _box(300))], [ignored])
    acc.update(1, [(1, _box(0))], [(7, _box(0)), (9, barely)], [ignored])
    s = acc.score()
    assert (s.truth, s.hypotheses, s.matches, s.false_positives) == (2, 3, 2, 1)
    assert s.mota == pytest.approx(1 - 1 / 2)
    # an ignored box never takes a track away from an object to track
    acc = MotAccumulator()
    acc.update(0, [(1, _box(0))], [(7, _box(0))], [_box(0)])
    assert (acc.score().matches, acc.score().false_positives) == (1, 0)


def test_an_id_switch_a_miss_and_a_false_positive() -> None:
    acc = MotAccumulator()
    # object 1 tracked by 7 on frames 0-1, by 9 on frames 2-3 (a switch on frame 2); missed on
    # frame 4; a false track 8 far away on frame 3
    acc.update(0, [(1, _box(0))], [(7, _box(0))])
    acc.update(1, [(1, _box(0))], [(7, _box(0))])
    acc.update(2, [(1, _box(0))], [(9, _box(0))])
    acc.update(3, [(1, _box(0))], [(9, _box(0)), (8, _box(400))])
    acc.update(4, [(1, _box(0))], [])
    s = acc.score()
    assert (s.truth, s.matches, s.misses, s.false_positives, s.id_switches) == (5, 4, 1, 1, 1)
    assert s.mota == pytest.approx(1 - 3 / 5)
    assert s.switches_at == ((2, 1),)
    # IDF1: object 1 is given track 7 or 9 (2 frames each): IDTP 2 of 5 truth + 5 track boxes
    assert s.idf1 == pytest.approx(2 * 2 / 10)


def test_a_kept_match_wins_over_a_better_new_one() -> None:
    acc = MotAccumulator()
    acc.update(0, [(1, _box(0))], [(7, _box(0))])
    # track 7 drifts (IoU 0.6) while track 9 sits exactly on the object: CLEAR-MOT keeps 7
    acc.update(1, [(1, _box(0))], [(7, _box(5)), (9, _box(0))])
    s = acc.score()
    assert s.id_switches == 0 and s.false_positives == 1


# --- the command ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def stop_and_go_json() -> dict:  # type: ignore[type-arg]
    import contextlib
    import io

    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        assert main(["evaluate", str(DEFAULT_RECORDINGS / "stop_and_go"), "--format", "json"]) == 0
    return json.loads(out.getvalue())  # type: ignore[no-any-return]


def test_json_has_every_figure_with_its_type(stop_and_go_json: dict) -> None:  # type: ignore[type-arg]
    (rec,) = stop_and_go_json["recordings"]
    for figures in (rec, stop_and_go_json["total"]):
        frames = figures["vehicles"]["frames"]
        assert all(isinstance(frames[k], int) for k in ("rd", "fn", "rfn", "fp", "nvo"))
        assert all(0.0 < frames[k] <= 1.0 for k in ("rd_iou_median", "rd_iou_good_share"))
        events = figures["vehicles"]["events"]
        assert all(
            isinstance(events[k], int) for k in ("events", "radar_miss", "not_refined", "refined")
        )
        for k in ("refined_share", "refined_share_of_radar_supplied"):
            assert events[k] is None or 0.0 <= events[k] <= 1.0
        by_class = frames["supplied_refined_share_by_class"]
        assert set(by_class) == {"car", "van", "truck"}
        assert all(v is None or 0.0 <= v <= 1.0 for v in by_class.values())
        assert set(figures) >= {
            "vehicles", "guardrails", "pedestrians", "motion_stereo", "pitch", "tracking"
        }  # fmt: skip
        assert set(figures["pedestrians"]) == {
            "symmetry",
            "motion_stereo",
            "vehicles",
            "radar",
            "image_motion",
            "hog",
        }
        for p in figures["pedestrians"].values():
            assert 0.0 <= p["recall"] <= 1.0 and 0.0 <= p["precision"] <= 1.0
        assert isinstance(figures["pitch"]["rms_deg"], float)
        mot = figures["tracking"]["vehicles"]["mot"]
        assert {"mota", "motp", "idf1", "id_switches"} <= set(mot)
    assert rec["name"] == "stop_and_go" and rec["frames"] == 150
    # every FN listed with its frame, and the listing adds up to the count
    assert len(rec["vehicles"]["frames"]["fn_at"]) == rec["vehicles"]["frames"]["fn"]
    assert all(len(pair) == 2 for pair in rec["vehicles"]["frames"]["fn_at"])
    assert "fn_at" not in stop_and_go_json["total"]["vehicles"]["frames"]


@pytest.mark.parametrize("fmt", ["table", "markdown", "csv"])
def test_the_other_formats_print_the_papers_tables(
    fmt: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["evaluate", str(DEFAULT_RECORDINGS / "stop_and_go"), "--format", fmt]) == 0
    out = capsys.readouterr().out
    if fmt == "csv":
        assert out.startswith("recording,figure,value\n")
        assert "stop_and_go,vehicles.frames.rd," in out
    else:
        assert "REFINED BY VISION" in out and "RFN" in out and "MOTA" in out


def test_a_recording_without_ground_truth_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["evaluate", str(tmp_path / "nowhere")]) == 2
    err = capsys.readouterr().err
    assert "fusionscope evaluate:" in err and "nowhere" in err and "Traceback" not in err


README = Path(__file__).resolve().parents[2] / "README.md"
README_BEGIN, README_END = "<!-- evaluate:begin -->\n", "<!-- evaluate:end -->\n"


def _untimed(markdown: str) -> list[str]:
    """The markdown's tables but the timed ones, whose figures change from run to run."""
    tables = [t.strip() for t in markdown.split("\n\n**")]
    return [t for t in tables if not any(title in t for title in TIMED_TITLES)]


def test_the_readmes_tables_are_the_commands_output_today(
    bundled_reports: list[RecordingReport],
) -> None:
    text = README.read_text(encoding="utf-8")
    block = text[text.index(README_BEGIN) + len(README_BEGIN) : text.index(README_END)]
    # what `_cmd_evaluate` prints for --format markdown
    out = report.format_markdown(
        report.tables(bundled_reports, total(bundled_reports), listings=False)
    )
    assert _untimed(block) == _untimed(out), (
        "README.md's 'How good is it' tables are stale: paste the output of "
        "`fusionscope evaluate recordings/highway recordings/exurban recordings/stop_and_go "
        "--baselines --format markdown` between its evaluate markers"
    )
    assert len(_untimed(out)) == len(out.split("\n\n**")) - len(TIMED_TITLES)


REAL_BEGIN, REAL_END = "<!-- evaluate-real:begin -->\n", "<!-- evaluate-real:end -->\n"


def test_the_readmes_real_drive_tables_are_the_commands_output_today(
    real_recordings: Path,
) -> None:
    reports = [
        evaluate_recording(real_recordings / name, Params(), timing=False) for name in REAL_IMPORTS
    ]
    text = README.read_text(encoding="utf-8")
    block = text[text.index(REAL_BEGIN) + len(REAL_BEGIN) : text.index(REAL_END)]
    out = report.format_markdown(report.tables(reports, total(reports), listings=False))
    assert _untimed(block) == _untimed(out), (
        "README.md's 'Real drives' tables are stale: paste the output of `fusionscope "
        "evaluate recordings-real/nuscenes-scene-0523 recordings-real/aimotive-night-motorway "
        "--format markdown` between its evaluate-real markers"
    )
    # what the truth lacks is not scored: no pitch, no guard-rail FN/FP, only vehicles labelled
    for r in reports:
        assert r.pitch.errors_deg == () and r.guardrails.rail_truth_frames == 0
        assert r.guardrails.fn == r.guardrails.fp == 0


def test_the_baselines_are_scored_on_the_engines_frames(
    bundled_reports: list[RecordingReport],
) -> None:
    for r in bundled_reports:
        b = r.baselines
        assert b is not None
        # the same frames and the same truth as the engine's figures
        assert len(b.hough.errors_deg) == len(b.hog_time.ms) == r.frames
        assert b.hough.calibration_errors_deg == r.pitch.calibration_errors_deg
        assert b.hog.visible == r.pedestrians["vehicles"].visible
        assert b.hog.boxes == b.hog.true_boxes + len(b.hog.false_at)
        # the engine's mask, split by whether the car moves, adds up to its figure
        split = b.motion_stereo.moving + b.motion_stereo.still
        assert dataclasses.replace(split, missed_at=tuple(sorted(split.missed_at))) == (
            r.motion_stereo
        )
        masks = b.mog2.moving + b.mog2.still
        assert masks.obstacles == r.motion_stereo.obstacles
        assert len(b.mog2_time.ms) == len(b.motion_stereo_time.ms)
        assert 0 < len(b.mog2_time.ms) < r.frames  # none on the first frame
        assert all(t > 0 for t in b.hog_time.ms + b.hough_time.ms + b.mog2_time.ms)
    # only stop_and_go stands still
    assert [r.baselines.mog2.still.obstacles > 0 for r in bundled_reports if r.baselines] == [
        False,
        False,
        True,
    ]
    summed = total(bundled_reports)
    assert summed.baselines is not None
    assert summed.baselines.hog.visible == sum(
        r.pedestrians["vehicles"].visible for r in bundled_reports
    )


def test_the_baselines_json_beside_the_engines(bundled_reports: list[RecordingReport]) -> None:
    figures = json.loads(json.dumps(report.as_json(bundled_reports, total(bundled_reports))))
    for rec in [*figures["recordings"], figures["total"]]:
        b = rec["baselines"]
        hog = b["pedestrians"]["hog"]
        # null where undefined: highway has no visible person
        assert (hog["recall"] is None) == (hog["visible"] == 0)
        assert all(hog[k] is None or 0.0 <= hog[k] <= 1.0 for k in ("recall", "precision"))
        assert b["pedestrians"]["hog_ms"] > 0 and b["pedestrians"]["symmetry_ms"] > 0
        assert isinstance(b["pitch"]["hough"]["rms_deg"], float)
        assert isinstance(b["pitch"]["hough"]["no_vanishing_point"], int)
        assert b["pitch"]["hough_ms"] > 0 and b["pitch"]["pitch_ms"] > 0
        for state in ("moving", "still"):
            assert set(b["motion_stereo"][state]) == {"motion_stereo", "mog2"}
        assert b["motion_stereo"]["mog2_ms"] > 0
    moving = figures["total"]["baselines"]["motion_stereo"]["moving"]
    assert moving["motion_stereo"]["object_recall"] is not None
    assert "missed_at" in figures["recordings"][0]["baselines"]["pedestrians"]["hog"]
    assert "missed_at" not in figures["total"]["baselines"]["pedestrians"]["hog"]


def test_baselines_on_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    path = str(DEFAULT_RECORDINGS / "stop_and_go")
    assert main(["evaluate", path, "--baselines"]) == 0
    out = capsys.readouterr().out
    assert "HOG" in out and "Hough" in out and "MOG2" in out and BASELINE_TIMING_TITLE in out


def test_compare_sets_the_headline_figures_of_two_parameter_sets_side_by_side(
    capsys: pytest.CaptureFixture[str],
) -> None:
    stop_and_go = str(DEFAULT_RECORDINGS / "stop_and_go")
    wide = ["--params", "papers", "--compare", "papers", "--format", "markdown"]
    assert main(["evaluate", stop_and_go, *wide]) == 0
    out = capsys.readouterr().out
    assert "**Compared: papers against papers**" in out
    rows = [line.split(" | ") for line in out.splitlines() if line.startswith("| stop_and_go")]
    figures = [name for name, _ in report.HEADLINE_FIGURES]
    assert [r[1] for r in rows] == figures
    assert all(r[2] == r[3].rstrip(" |") for r in rows)  # the same set: the same figures
    assert [line for line in out.splitlines() if line.startswith("| total")]
    assert main(["evaluate", stop_and_go, "--compare", "papers", "--format", "json"]) == 2
    assert "--compare: prints a table or markdown, not json" in capsys.readouterr().err


def test_the_papers_preset_reproduces_the_figures_from_before_the_departures() -> None:
    # README's stop_and_go vehicle row before the defaults departed from the papers (commit
    # 0b0e792): RD 56, FN 97, RFN 341, FP 24; pitch 0.26 deg RMS. FP 22 since a box from a
    # return beside a vehicle that lies on the vehicle is no FP (core/evaluation/vehicles.py)
    r = evaluate_recording(DEFAULT_RECORDINGS / "stop_and_go", params_from("papers"), timing=False)
    v = r.vehicles
    assert (v.rd, v.fn, v.rfn, v.fp) == (56, 97, 341, 22)
    assert r.pitch.rms_deg == pytest.approx(0.26, abs=0.005)
