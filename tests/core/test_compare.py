"""A/B compare of one frame's detections: hand-made vehicles, pedestrians and guard-rail labels
put into a real frame result of the bundled highway drive, whose pairs the tests work out."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS
from core.compare import Detection, detections, diff_detections
from core.engine import FrameResult, FusionEngine
from core.guardrail import GuardRailCheck, GuardRailResult
from core.io.drive import Drive
from core.params import Params
from core.pedestrian import PedestrianCandidate, Verdict
from core.vehicle import Box, Vehicle, VehicleResult

NO_PIXELS = np.zeros((0, 2), dtype=np.int32)


@pytest.fixture(scope="module")
def real() -> FrameResult:
    """Frame 0 of the bundled highway drive: 8 search areas, one vehicle, guard rails."""
    with Drive(DEFAULT_RECORDINGS / "highway") as drive:
        return FusionEngine(Params(), drive.camera).process(drive.frame(0))


def car(
    box: Box, distance_m: float = 20.0, lateral_m: float = 1.2, width_m: float = 1.8
) -> Vehicle:
    return Vehicle(box, distance_m, lateral_m, width_m, distance_m, (0,))


def person(
    box: Box, verdict: Verdict = "pedestrian", distance_m: float = 12.0
) -> PedestrianCandidate:
    axis = (box[0] + box[2] - 1) / 2  # pixel centres at whole numbers
    return PedestrianCandidate(
        band=0,
        axis_px=axis,
        half_width_px=(box[2] - box[0] - 1) / 2,
        score=0.8,
        edge_symmetry=0.8,
        grey_symmetry=0.8,
        edge_density=0.1,
        box_px=box,
        extended_box_px=box,
        extended=False,
        distance_m=distance_m,
        lateral_m=0.0,
        height_m=1.7,
        width_m=0.6,
        obstacle_fraction=0.5,
        verdict=verdict,
    )


def rail(target_index: int, verdict: str = "guard_rail") -> GuardRailCheck:
    return GuardRailCheck(
        target_index=target_index,
        side="right",
        real_speed_mps=0.0,
        edges=np.zeros((0, 0), dtype=np.uint8),
        line_px=NO_PIXELS,
        holes_px=NO_PIXELS,
        coverage=0.0,
        verdict=verdict,
        overlapped_by=None,
    )


def made(
    real: FrameResult,
    vehicles: tuple[Vehicle, ...] = (),
    people: tuple[PedestrianCandidate, ...] = (),
    rails: tuple[GuardRailCheck, ...] = (),
    index: int | None = None,
) -> FrameResult:
    """The real frame with these detections instead of its own."""
    return dataclasses.replace(
        real,
        index=real.index if index is None else index,
        vehicle=VehicleResult(real.vehicle.targets, vehicles),
        pedestrian=dataclasses.replace(real.pedestrian, candidates=people),
        guardrail=GuardRailResult(rails),
    )


CAR_1 = car((100.0, 200.0, 180.0, 250.0), 20.0)
CAR_2 = car((300.0, 210.0, 340.0, 240.0), 35.0, -2.0)
WALKER = person((500.0, 150.0, 520.0, 210.0))


def test_detections_are_the_final_vehicles_kept_pedestrians_and_labelled_targets(
    real: FrameResult,
) -> None:
    result = made(
        real,
        (car((100.0, 200.0, 180.0, 250.0), 23.44, 1.23, 1.81),),
        (
            person((300.0, 150.0, 321.0, 210.0)),
            person((400.0, 150.0, 420.0, 210.0), "motion_stereo"),  # dropped by a filter
            person((450.0, 150.0, 470.0, 210.0), "vehicle"),
            person((460.0, 150.0, 480.0, 210.0), "size"),
        ),
        (rail(3), rail(5, "not_guard_rail"), rail(2, "overlap")),
    )
    found = detections(result)
    assert [d.kind for d in found] == ["vehicle", "pedestrian", "guard rail", "guard rail"]
    vehicle, walker, rail_2, rail_3 = found
    assert vehicle == Detection(
        "vehicle",
        (100.0, 200.0, 180.0, 250.0),
        23.44,
        "vehicle at 23.4 m, lateral +1.2 m, 1.8 m wide",
    )
    # a box 21 px wide from column 300 has its axis on the centre of pixel 310
    assert walker.label == "pedestrian at col 310, 12 m"
    assert walker.box_px == (300.0, 150.0, 321.0, 210.0)
    # guard rails by target, with their area's box in pixel edges and the radar's distance
    area = {a.target_index: a for a in real.areas}[2]
    c0, r0, c1, r1 = area.box_px
    assert rail_2.box_px == pytest.approx((c0 - 0.5, r0 - 0.5, c1 - 0.5, r1 - 0.5))
    assert (rail_2.target_index, rail_2.distance_m) == (2, area.x_m)
    assert rail_2.label == f"guard rail: radar target 2 at {area.x_m:.1f} m"
    assert rail_3.target_index == 3


def test_an_unknown_width_reads_as_a_question_mark(real: FrameResult) -> None:
    (vehicle,) = detections(made(real, (car((0.0, 0.0, 10.0, 10.0), 8.0, math.nan, math.nan),)))
    assert vehicle.label == "vehicle at 8.0 m, lateral ? m, ? m wide"


def test_a_lateral_just_right_of_the_axis_reads_as_zero_not_minus_zero(real: FrameResult) -> None:
    (vehicle,) = detections(made(real, (car((0.0, 0.0, 10.0, 10.0), 8.0, -0.04, 1.8),)))
    assert vehicle.label == "vehicle at 8.0 m, lateral +0.0 m, 1.8 m wide"


def test_a_real_frame_has_its_results_detections_and_nothing_differs_from_itself(
    real: FrameResult,
) -> None:
    found = detections(real)
    kinds = [d.kind for d in found]
    assert kinds.count("vehicle") == len(real.vehicle.vehicles) >= 1
    assert kinds.count("pedestrian") == len(real.pedestrian.kept)
    rails = {d.target_index for d in found if d.kind == "guard rail"}
    assert rails == real.guardrail.guard_rail_targets and rails
    diff = diff_detections(real, real)
    assert (diff.only_a, diff.only_b, diff.matched) == ((), (), len(found))


def test_identical_results_differ_in_nothing(real: FrameResult) -> None:
    a = made(real, (CAR_1, CAR_2), (WALKER,), (rail(3),))
    b = made(real, (CAR_1, CAR_2), (WALKER,), (rail(3),))
    diff = diff_detections(a, b)
    assert (diff.only_a, diff.only_b, diff.matched) == ((), (), 4)


def test_a_vehicle_missing_from_b_is_only_in_a(real: FrameResult) -> None:
    a = made(real, (CAR_1, CAR_2), (WALKER,))
    b = made(real, (CAR_1,), (WALKER,))
    diff = diff_detections(a, b)
    assert diff.only_a == (detections(a)[1],)
    assert diff.only_a[0].box_px == CAR_2.box_px
    assert (diff.only_b, diff.matched) == ((), 2)


@pytest.mark.parametrize(("shift_px", "pairs"), [(33.0, 1), (34.0, 0)])
def test_a_shifted_box_matches_while_its_iou_reaches_the_threshold(
    real: FrameResult, shift_px: float, pairs: int
) -> None:
    # two 100 x 50 boxes, one shifted right by s: they share (100 - s) x 50 of a union of
    # (100 + s) x 50, IoU = (100 - s) / (100 + s): 67 / 133 = 0.504 at s = 33 px,
    # 66 / 134 = 0.493 at s = 34 px, either side of 0.5
    width = 100.0
    iou = (width - shift_px) / (width + shift_px)
    assert (iou >= 0.5) == (pairs == 1)
    a = made(real, (car((100.0, 200.0, 200.0, 250.0)),))
    b = made(real, (car((100.0 + shift_px, 200.0, 200.0 + shift_px, 250.0)),))
    diff = diff_detections(a, b, iou_min=0.5)
    assert diff.matched == pairs
    assert len(diff.only_a) == len(diff.only_b) == 1 - pairs


def test_an_iou_equal_to_the_threshold_matches(real: FrameResult) -> None:
    # 120 px wide, shifted 40: 80 / 160 = 0.5 exactly
    a = made(real, (), (person((100.0, 100.0, 220.0, 300.0)),))
    b = made(real, (), (person((140.0, 100.0, 260.0, 300.0)),))
    assert diff_detections(a, b, iou_min=0.5).matched == 1
    assert diff_detections(a, b, iou_min=0.51).matched == 0


def test_pairs_are_taken_greedily_best_iou_first(real: FrameResult) -> None:
    # A's box overlaps B's first box by 90 / 110 = 0.82 and its second by 80 / 120 = 0.67
    # (100 wide boxes shifted 10 and 20 px): the better one pairs, the other stays B's own
    a = made(real, (car((100.0, 0.0, 200.0, 50.0)),))
    near, far = car((110.0, 0.0, 210.0, 50.0)), car((80.0, 0.0, 180.0, 50.0))
    diff = diff_detections(a, made(real, (far, near)))
    assert diff.matched == 1
    assert [d.box_px for d in diff.only_b] == [far.box_px]


def test_a_vehicle_and_a_pedestrian_in_one_box_do_not_match(real: FrameResult) -> None:
    box = (100.0, 100.0, 140.0, 200.0)
    diff = diff_detections(made(real, (car(box),)), made(real, (), (person(box),)))
    assert [d.kind for d in diff.only_a] == ["vehicle"]
    assert [d.kind for d in diff.only_b] == ["pedestrian"]
    assert diff.matched == 0


def test_a_guard_rail_label_only_in_b_is_matched_by_its_target(real: FrameResult) -> None:
    a = made(real, rails=(rail(3),))
    b = made(real, rails=(rail(2, "overlap"), rail(3)))
    diff = diff_detections(a, b)
    assert diff.only_a == ()
    assert [(d.kind, d.target_index) for d in diff.only_b] == [("guard rail", 2)]
    assert diff.matched == 1


def test_results_without_detections_differ_in_nothing(real: FrameResult) -> None:
    empty = made(real)
    assert detections(empty) == ()
    diff = diff_detections(empty, empty)
    assert (diff.only_a, diff.only_b, diff.matched) == ((), (), 0)


def test_results_of_two_frames_are_refused(real: FrameResult) -> None:
    with pytest.raises(ValueError, match=r"got frame 0 \(a\) and frame 7 \(b\)"):
        diff_detections(real, made(real, index=7))
    later = dataclasses.replace(real, t_ns=real.t_ns + 1)
    with pytest.raises(ValueError, match="two recordings"):
        diff_detections(real, later)


@pytest.mark.parametrize("iou_min", [0.0, -0.1, 1.5, math.nan])
def test_an_iou_threshold_outside_0_1_is_refused(real: FrameResult, iou_min: float) -> None:
    with pytest.raises(ValueError, match=r"iou_min: expected an overlap in \(0, 1\], got"):
        diff_detections(real, real, iou_min)
