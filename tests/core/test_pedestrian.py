"""Known-answer tests of the symmetry pedestrian detector and its fusion filters.

People, poles and tree trunks are rendered by the bundled drives' renderer on a straight
road, seen by a standing car, without sensor noise; the label image gives each object's true
box, and the camera gives where a box's base meets the road.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from functools import cache

import numpy as np
import numpy.typing as npt
import pytest

from core import hog
from core.ego import step
from core.evaluation.objects import iou
from core.image_motion import keep
from core.io.frame import RadarTarget
from core.params import PedestrianParams
from core.pedestrian import (
    PedestrianResult,
    _constraints,
    _px_per_m,
    _verified,
    bands_for,
    detect_pedestrians,
)
from core.synth.scene import Pedestrian, StaticObject, Trajectory
from tests.core.roadscenes import RoadRenderer, camera, straight_road, two_frames

PERSON_ID = 7
PERSON_S_M, PERSON_D_M, PERSON_HEIGHT_M = 14.0, 2.0, 1.75
PARAMS = PedestrianParams()

Box = tuple[float, float, float, float]


def _person(s_m: float = PERSON_S_M, d_m: float = PERSON_D_M) -> Pedestrian:
    standing = Trajectory.from_waypoints([(0.0, s_m, d_m), (10.0, s_m, d_m)])
    return Pedestrian(PERSON_ID, PERSON_HEIGHT_M, 150, 40, standing)


@cache
def _scene(what: str) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint16]]:
    """A standing car's view of `what`: "person", "empty", "pole" or "trunk"."""
    people = (_person(),) if what == "person" else ()
    statics = {
        "pole": (StaticObject(PERSON_ID, "pole", PERSON_S_M, PERSON_D_M, 0.15, 6.0, 150),),
        "trunk": (StaticObject(PERSON_ID, "tree", PERSON_S_M, PERSON_D_M, 0.45, 7.0, 60),),
    }.get(what, ())
    scene = straight_road(speed_mps=0.0, markings=False, pedestrians=people, statics=statics)
    return RoadRenderer(scene)(0.0, camera().extrinsics.pitch_rad, noise=False)


def _truth_box(labels: npt.NDArray[np.uint16]) -> Box:
    rows, cols = np.nonzero(labels == PERSON_ID)
    return float(cols.min()), float(rows.min()), float(cols.max() + 1), float(rows.max() + 1)


def _mask(value: int) -> npt.NDArray[np.uint8]:
    first, stop = camera().row_window_px
    return np.full((stop - first, camera().intrinsics.width_px), value, dtype=np.uint8)


def _detect(
    image: npt.NDArray[np.uint8],
    mask_value: int = 255,
    vehicles: tuple[Box, ...] = (),
    params: PedestrianParams = PARAMS,
    radar: tuple[RadarTarget, ...] = (),
    ego_speed_mps: float = 0.0,
) -> PedestrianResult:
    first, _ = camera().row_window_px
    return detect_pedestrians(
        image, camera(), _mask(mask_value), first, vehicles, radar, ego_speed_mps, params
    )


def _target(x_m: float, y_m: float, range_rate_mps: float) -> RadarTarget:
    return RadarTarget(math.hypot(x_m, y_m), math.atan2(y_m, x_m), range_rate_mps, 1.0, x_m, y_m)


def _on(result: PedestrianResult, box: Box) -> list[str]:
    """Verdicts of the candidates whose axis lies inside `box`'s columns."""
    return [c.verdict for c in result.candidates if box[0] <= c.axis_px <= box[2]]


def test_a_standing_person_is_found_with_the_right_box() -> None:
    image, labels = _scene("person")
    u0, v0, u1, v1 = _truth_box(labels)
    result = _detect(image)
    (found,) = result.kept
    a0, b0, a1, b1 = found.extended_box_px
    assert abs(b0 - v0) <= 2 and abs(b1 - v1) <= 2  # head and feet rows
    assert abs(found.axis_px - (u0 + u1) / 2) <= 2
    # the border columns are the arms', the widest part of the silhouette
    assert abs((a1 - a0) - (u1 - u0)) <= 0.3 * (u1 - u0)
    base = camera().ground_point([[found.axis_px, v1]])[0]
    assert found.distance_m == pytest.approx(base[0], abs=0.02 * base[0])
    assert found.lateral_m == pytest.approx(base[1], abs=0.2)
    assert found.height_m == pytest.approx(PERSON_HEIGHT_M, rel=0.05)
    assert not found.extended  # standing straight: the legs are symmetric to the road
    assert found.obstacle_fraction == 1.0


def test_legs_that_break_the_symmetry_are_extended_down_to_the_road() -> None:
    image, labels = _scene("person")
    box = _truth_box(labels)
    _, v0, _, v1 = (round(x) for x in box)
    result = _detect(_walking(image, box))
    (found,) = result.kept
    assert found.extended
    assert found.box_px[3] < v1 - PARAMS.gap_fraction * (v1 - v0)  # symmetry ends above
    assert found.extended_box_px[3] == pytest.approx(v1, abs=2)  # down to the feet
    assert found.extended_box_px[1] == pytest.approx(v0, abs=2)
    assert found.height_m == pytest.approx(PERSON_HEIGHT_M, rel=0.05)


def _walking(image: npt.NDArray[np.uint8], box: Box) -> npt.NDArray[np.uint8]:
    """`image` with the person of `box` mid-stride: below the hands one leg stands upright,
    the other swings outwards."""
    empty, _ = _scene("empty")
    u0, v0, u1, v1 = (round(x) for x in box)
    hands = round(v1 - 0.45 * (v1 - v0))
    axis, leg = (u0 + u1) // 2, max(3, round(0.15 * (u1 - u0)))
    walking = image.copy()
    walking[hands:v1, u0 - 2 : u1 + 2] = empty[hands:v1, u0 - 2 : u1 + 2]
    for row in range(hands, v1):
        swing = axis + 2 + round(2 * leg * (row - hands) / (v1 - hands))
        walking[row, axis - 2 - leg : axis - 2] = 40
        walking[row, swing : swing + leg] = 40
    return walking


def test_the_legs_end_at_the_feet_above_a_road_marking() -> None:
    image, labels = _scene("person")
    box = _truth_box(labels)
    u0, v0, u1, v1 = (round(x) for x in box)
    walking = _walking(image, box)
    # a zebra crossing's slanted stripes, starting a tenth of the height below the feet:
    # their edges lie inside the box's columns, as the legs' do
    top, axis = v1 + round(0.1 * (v1 - v0)), (u0 + u1) // 2
    for k, row in enumerate(range(top, top + round(0.15 * (v1 - v0)))):
        walking[row, u0 - 10 + k : u0 + 4 + k] = 230
        walking[row, axis + k : axis + 14 + k] = 230
    (found,) = _detect(walking).kept
    assert found.extended
    assert found.extended_box_px[3] == pytest.approx(v1, abs=2)  # the feet, not the stripes
    assert found.height_m == pytest.approx(PERSON_HEIGHT_M, rel=0.05)


def test_a_near_person_is_framed_head_to_feet() -> None:
    # 8 m ahead the band's bins are 5 px: the axis, a bin's centre, can lie 2 px off the
    # body's, and a 1 px mirror tolerance lost the chest and head rows
    near = straight_road(
        speed_mps=0.0, markings=False, pedestrians=(_person(s_m=8.0, d_m=0.5),), statics=()
    )
    image, labels = RoadRenderer(near)(0.0, camera().extrinsics.pitch_rad, noise=False)
    _, v0, _, v1 = _truth_box(labels)
    (found,) = _detect(image).kept
    _, top, _, bottom = found.extended_box_px
    assert abs(top - v0) <= 3 and abs(bottom - v1) <= 2
    assert found.height_m == pytest.approx(PERSON_HEIGHT_M, rel=0.05)


def test_a_box_off_its_bands_distance_is_kept_when_a_persons_size_there() -> None:
    # world rows: distance, lateral, width, height of each box's base; all scanned in a band
    # at 18 m. A person 8 m away whom the refinement framed head to feet, the same box 0.5 m
    # tall (a torso), and a base above the horizon (NaN)
    world = np.array(
        [[8.0, 0.0, 0.5, 1.75], [8.0, 0.0, 0.5, 0.5], [np.nan, np.nan, np.nan, np.nan]]
    )
    no_top, band_m = np.zeros(3, dtype=bool), np.full(3, 18.0)
    kept, off_band = _constraints(no_top, band_m, world, PARAMS)
    assert kept == [None, "size", "size"]
    assert off_band.tolist() == [True, True, True]
    papers, _ = _constraints(no_top, band_m, world, replace(PARAMS, keep_off_band_boxes=False))
    assert papers == ["perspective", "perspective", "perspective"]
    near_band = np.full(3, 8.5)
    assert _constraints(no_top, near_band, world, PARAMS)[1].tolist() == [False, False, True]


@pytest.mark.parametrize(
    ("what", "verdicts"), [("pole", {"no_top", "aspect"}), ("trunk", {"no_top"})]
)
def test_poles_and_trunks_are_pruned_by_the_constraints(what: str, verdicts: set[str]) -> None:
    image, labels = _scene(what)
    result = _detect(image)
    assert not result.kept
    on_it = _on(result, _truth_box(labels))
    assert set(on_it) <= verdicts


def test_a_person_outside_the_motion_stereo_mask_is_rejected_with_that_reason() -> None:
    image, labels = _scene("person")
    # the paper's filter alone (no verification): dropped, never scored
    papers = replace(PARAMS, verify_with_hog=False)
    result = _detect(image, mask_value=0, params=papers)
    assert not result.kept
    (found,) = result.rejected_by_motion_stereo
    assert found.obstacle_fraction == 0.0
    assert math.isnan(found.hog_score)
    assert _on(result, _truth_box(labels)) == ["motion_stereo"]
    # with the verification the SVM may keep it, at the stricter threshold for unmarked boxes
    (marked,) = _detect(image).kept
    assert marked.hog_score > PARAMS.hog_without_motion_min_score
    (kept,) = _detect(image, mask_value=0).kept
    assert kept.hog_score == pytest.approx(marked.hog_score)
    strict = replace(PARAMS, hog_without_motion_min_score=marked.hog_score + 0.01)
    result = _detect(image, mask_value=0, params=strict)
    assert not result.kept
    (dropped,) = result.rejected_by_motion_stereo
    assert dropped.hog_score == pytest.approx(marked.hog_score)
    # a marked box needs only hog_min_score
    assert _detect(image, params=strict).kept


def test_a_person_inside_a_detected_vehicle_is_rejected_with_that_reason() -> None:
    image, labels = _scene("person")
    u0, v0, u1, v1 = _truth_box(labels)
    around = (u0 - 20, v0 - 10, u1 + 20, v1 + 5)
    result = _detect(image, vehicles=(around,))
    assert not result.kept
    assert len(result.rejected_by_vehicle) == 1
    # the motion-stereo filter comes first: a box it rejects is never checked against vehicles
    both = _detect(image, mask_value=0, vehicles=(around,))
    assert [c.verdict for c in both.candidates if c.verdict in ("vehicle", "motion_stereo")] == [
        "motion_stereo"
    ]


def test_a_person_keeping_pace_with_the_car_is_rejected_by_image_motion() -> None:
    # the same person seen from a car at 25 m/s, standing and keeping pace with the car
    # (tests/core/test_image_motion.py renders them); the second moves with the car
    first, _ = camera().row_window_px
    ego = step(25.0, 0.0, 0.1)

    def verdicts(person_speed_mps: float, params: PedestrianParams = PARAMS) -> list[str]:
        previous, image, box = two_frames(25.0, person_speed_mps)
        result = detect_pedestrians(
            image, camera(), _mask(255), first, (), (), 25.0, params, keep(previous), ego
        )
        return [c.verdict for c in result.candidates if iou(c.extended_box_px, box) >= 0.5]

    assert verdicts(0.0) == ["pedestrian"]
    assert verdicts(25.0) == ["image_motion"]
    assert verdicts(25.0, replace(PARAMS, image_motion_margin=2.0)) == ["pedestrian"]
    previous, image, _ = two_frames(25.0, 0.0)
    with pytest.raises(
        ValueError, match=r"previous: expected .* shape \(120, 160\), got \(480, 640\)"
    ):
        detect_pedestrians(image, camera(), _mask(255), first, (), (), 25.0, PARAMS, previous, ego)


def test_a_person_where_radar_sees_a_fast_target_is_rejected_with_that_reason() -> None:
    image, labels = _scene("person")
    (found,) = _detect(image).kept
    d, y = found.distance_m, found.lateral_m
    gate_d = PARAMS.radar_gate_distance_fraction * d
    fast, jog = PARAMS.radar_min_speed_mps + 5.0, PARAMS.radar_min_speed_mps - 0.5

    def verdicts(radar: tuple[RadarTarget, ...], **kwargs: object) -> list[str]:
        return _on(_detect(image, radar=radar, **kwargs), _truth_box(labels))  # type: ignore[arg-type]

    # a target receding at `fast` from a standing car, by the person's base within both gates
    near = _target(d + 0.9 * gate_d, y + 0.9 * PARAMS.radar_gate_lateral_m, fast)
    assert verdicts((near,)) == ["radar"]
    # the ego speed counts: a target closing at the car's own speed stands still
    assert verdicts((_target(d, y, -10.0),), ego_speed_mps=10.0) == ["pedestrian"]
    assert verdicts((_target(d, y, fast - 10.0),), ego_speed_mps=10.0) == ["radar"]
    # kept: too slow, outside a gate, the car's speed unknown, the filter off
    assert verdicts((_target(d, y, jog),)) == ["pedestrian"]
    assert verdicts((_target(d + 1.1 * gate_d, y, fast),)) == ["pedestrian"]
    assert verdicts((_target(d, y - 1.1 * PARAMS.radar_gate_lateral_m, fast),)) == ["pedestrian"]
    assert verdicts((near,), ego_speed_mps=math.nan) == ["pedestrian"]
    off = replace(PARAMS, radar_gate_lateral_m=0.0)
    assert verdicts((near,), params=off) == ["pedestrian"]
    # the paper's filters come first: a box in a vehicle's stays the vehicle filter's
    u0, v0, u1, v1 = _truth_box(labels)
    assert verdicts((near,), vehicles=((u0 - 20, v0 - 10, u1 + 20, v1 + 5),)) == ["vehicle"]


def test_the_hog_verification_keeps_a_person_and_says_why_it_drops_a_box() -> None:
    image, labels = _scene("person")
    (found,) = _detect(image).kept
    # the flat-shaded person scores well above the SVM's own threshold (0)
    assert found.hog_score > 0.0
    # a box the SVM scores below hog_min_score is dropped with that reason, score kept
    strict = replace(PARAMS, hog_min_score=found.hog_score + 0.01)
    (dropped,) = [c for c in _detect(image, params=strict).candidates if c.verdict == "hog"]
    assert dropped.hog_score == pytest.approx(found.hog_score)
    assert _on(_detect(image, params=strict), _truth_box(labels)) == ["hog"]
    # the papers' preset does not verify: no score, the box kept
    papers = replace(PARAMS, verify_with_hog=False, hog_min_score=found.hog_score + 0.01)
    (kept,) = _detect(image, params=papers).kept
    assert math.isnan(kept.hog_score)
    # only boxes that passed every filter are scored
    u0, v0, u1, v1 = _truth_box(labels)
    rejected = _detect(image, vehicles=((u0 - 20, v0 - 10, u1 + 20, v1 + 5),)).candidates
    assert rejected and all(math.isnan(c.hog_score) for c in rejected)


def _scripted_svm(
    monkeypatch: pytest.MonkeyPatch, score: Callable[[int], float]
) -> list[list[Box]]:
    """Replace the SVM by one scoring every box of its n-th call (from 1) score(n); the
    boxes of each call are appended to the list returned."""
    calls: list[list[Box]] = []

    def scripted(_: npt.NDArray[np.uint8], boxes: list[Box]) -> tuple[float, ...]:
        calls.append(list(boxes))
        return tuple(score(len(calls)) for _ in boxes)

    monkeypatch.setattr(hog, "people_scores", scripted)
    return calls


def test_a_rejected_box_gives_way_to_another_framing_the_same_person(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    image, labels = _scene("person")
    truth = _truth_box(labels)
    (chosen,) = _detect(image).kept
    # an SVM that rejects every box it sees first (the chosen ones) and keeps the others
    calls = _scripted_svm(monkeypatch, lambda call: -5.0 if call == 1 else 5.0)
    result = _detect(image)
    (kept,) = result.kept
    assert calls[0] == [chosen.extended_box_px]  # the chosen box first, then another
    assert kept.extended_box_px != chosen.extended_box_px and kept.hog_score == 5.0
    # it frames the person head to feet, and replaces the chosen box: one box per person
    assert abs(kept.extended_box_px[1] - truth[1]) <= 2
    assert abs(kept.extended_box_px[3] - truth[3]) <= 2
    assert iou(kept.extended_box_px, truth) >= 0.6 and _on(result, truth) == ["pedestrian"]
    # no alternatives (the papers' preset): the chosen box stays, rejected
    calls.clear()
    alone = _detect(image, params=replace(PARAMS, hog_alternatives=0))
    assert alone.kept == () and _on(alone, truth) == ["hog"] and len(calls) == 1


def test_a_box_of_only_the_legs_is_scored_again_as_a_person_standing_on_its_base(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    image, labels = _scene("person")
    truth = _truth_box(labels)
    (found,) = _detect(image).kept
    # the symmetric area ended at the hips: the box holds the lower half of the person
    u0, v0, u1, v1 = found.extended_box_px
    legs = replace(found, extended_box_px=(u0, (v0 + v1) / 2, u1, v1), verdict="pedestrian")
    (low,) = _verified(image, camera(), [legs], replace(PARAMS, hog_person_at_base=False))
    assert low.verdict == "hog" and low.hog_score < PARAMS.hog_min_score
    (kept,) = _verified(image, camera(), [legs], PARAMS)
    # scored again as a person of scan_height_m (1.7 m) on its base: the 1.75 m person
    assert kept.verdict == "pedestrian" and kept.hog_score >= PARAMS.hog_min_score
    assert kept.height_m == PARAMS.scan_height_m and kept.extended_box_px[3] == v1
    assert abs(kept.extended_box_px[1] - truth[1]) <= 0.05 * (truth[3] - truth[1]) + 1
    assert iou(kept.extended_box_px, truth) >= 0.7
    # a box already as tall as that person gets no second window
    calls = _scripted_svm(monkeypatch, lambda _: -5.0)
    whole = replace(found, verdict="pedestrian")
    (rejected,) = _verified(image, camera(), [whole], PARAMS)
    assert rejected.verdict == "hog" and calls == [[found.extended_box_px]]


def test_the_height_scale_on_the_road_follows_the_bands() -> None:
    bands = bands_for(camera(), PARAMS)
    # on a flat road it is linear in the row: the fit goes through every band's figure,
    # within the half row the foot rows are rounded to
    fitted = _px_per_m(bands, bands.foot_row_px)
    slope = (bands.px_per_m[0] - bands.px_per_m[-1]) / (
        bands.foot_row_px[0] - bands.foot_row_px[-1]
    )
    assert np.abs(fitted - bands.px_per_m).max() <= 0.5 * slope
    # and beyond them: nearer than the nearest band it is larger
    assert _px_per_m(bands, bands.foot_row_px[:1] + 20)[0] > bands.px_per_m[0]


def test_an_empty_road_has_no_pedestrian() -> None:
    image, _ = _scene("empty")
    assert not _detect(image).kept
    blank = np.full_like(image, 128)
    result = _detect(blank)
    assert result.candidates == ()
    assert not result.symmetry.any()


def test_bands_follow_the_road_plane() -> None:
    bands = bands_for(camera(), PARAMS)
    first, stop = camera().row_window_px
    assert np.all(np.diff(bands.distance_m) > 0)
    assert np.all(np.diff(bands.foot_row_px) < 0)  # farther people stand higher
    assert np.all((bands.foot_row_px > first) & (bands.foot_row_px <= stop))
    zeros = np.zeros_like(bands.distance_m)
    feet, _ = camera().project(np.column_stack([bands.distance_m, zeros, zeros]))
    np.testing.assert_allclose(bands.foot_row_px, feet[:, 1], atol=0.5)
    # a band's box is a scan_height_m person there
    heads, _ = camera().project(
        np.column_stack([bands.distance_m, zeros, np.full_like(zeros, PARAMS.scan_height_m)])
    )
    np.testing.assert_allclose(bands.height_px, feet[:, 1] - heads[:, 1], atol=1.0)
    result = _detect(_scene("empty")[0])
    top, bottom = result.strip_rows_px
    assert first <= top < bottom <= stop
    assert result.symmetry.shape == (len(bands), camera().intrinsics.width_px)


def test_a_range_outside_the_window_gives_an_empty_result() -> None:
    params = replace(PARAMS, min_distance_m=0.5, max_distance_m=1.5)  # under the window
    result = _detect(_scene("person")[0], params=params)
    assert len(result.bands) == 0
    assert result.candidates == ()


def test_bad_inputs_name_the_argument() -> None:
    image, _ = _scene("person")
    first, _ = camera().row_window_px
    with pytest.raises(ValueError, match="image"):
        detect_pedestrians(image[:100], camera(), _mask(255), first, (), (), 0.0, PARAMS)
    with pytest.raises(ValueError, match="obstacle_mask"):
        detect_pedestrians(image, camera(), _mask(255)[:, :100], first, (), (), 0.0, PARAMS)
    with pytest.raises(ValueError, match="obstacle_mask"):
        float_mask = _mask(255).astype(np.float32)
        detect_pedestrians(image, camera(), float_mask, first, (), (), 0.0, PARAMS)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("distance_step_ratio", 1.0),
        ("scan_bins", 2),
        ("max_candidates", 0),
        ("gap_fraction", 1.5),
        ("aspect_max", 0.1),
        ("radar_min_speed_mps", 0.0),
        ("radar_gate_lateral_m", -1.0),
        ("radar_gate_distance_fraction", 1.5),
    ],
)
def test_bad_parameters_name_the_field(field: str, value: object) -> None:
    with pytest.raises(ValueError, match=field):
        replace(PARAMS, **{field: value})
