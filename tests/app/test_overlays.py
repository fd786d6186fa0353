"""Overlays on the camera picture: each layer draws where the geometry says, in its colour,
and nothing else; empty results leave the picture; bad pictures are refused by name."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np
import pytest
from app_fakes import HEIGHT_PX, WIDTH_PX, fake_camera
from engine_frames import engine_image, engine_result

from app import draw, overlays
from core.appearance import AppearanceMatch
from core.guardrail import GuardRailCheck
from core.io.frame import RadarTarget
from core.pedestrian import PedestrianCandidate
from core.pitch import Lines
from core.search_area import SearchArea
from core.tracking import Track
from core.vehicle import Candidate, TargetResult, Vehicle

BLACK = (0, 0, 0)


def black() -> np.ndarray:
    return np.zeros((HEIGHT_PX, WIDTH_PX, 3), dtype=np.uint8)


def drawn(put: Callable[..., None], rgb: np.ndarray, *args: object) -> np.ndarray:
    """What the in-place drawing function `put` draws on a copy of `rgb`."""
    out = rgb.copy()
    put(out, *args)
    return out


def radar(x_m: float, y_m: float) -> RadarTarget:
    return RadarTarget(float(np.hypot(x_m, y_m)), float(np.arctan2(y_m, x_m)), 0.0, 1.0, x_m, y_m)


def target_result(
    verdict: str, x_m: float = 25.0, y_m: float = -1.5, box_px=None, index: int = 0
) -> TargetResult:
    candidates: tuple[Candidate, ...] = ()
    chosen = None
    if box_px is not None:
        candidates = (Candidate(10.0, 8, 8.0, 5.0, 20, None, box_px),)
        chosen = 0
    return TargetResult(
        index,
        radar(x_m, y_m),
        None,
        np.zeros((0, 0), np.int8),
        np.zeros((32, 0), np.float32),
        0.0,
        candidates,
        chosen,
        verdict,  # type: ignore[arg-type]
        None,
    )


def vehicle(box_px: tuple[float, float, float, float]) -> Vehicle:
    return Vehicle(box_px, 20.0, 0.0, 1.8, 20.0, (0,))


def area(box_px: tuple[int, int, int, int], index: int = 0, y_m: float = 2.0) -> SearchArea:
    """An area whose patch is the crop at scale 1: patch pixel (r, c) is image pixel
    (row0 + r, col0 + c)."""
    c0, r0, c1, r1 = box_px
    return SearchArea(
        index,
        radar(20.0, y_m),
        ((c0 + c1) / 2, r1 - 5.0),
        (c0 - 0.5, r0 - 0.5, c1 - 0.5, r1 - 0.5),
        box_px,
        y_m + 1.0,
        y_m - 1.0,
        np.zeros((r1 - r0, c1 - c0), np.uint8),
        10.0,
    )


def check(index: int, verdict: str, line_px=(), overlapped_by=None) -> GuardRailCheck:
    line = np.array(line_px, dtype=np.int32).reshape(-1, 2)
    return GuardRailCheck(
        index,
        "left",
        0.0,
        np.zeros((0, 0), np.uint8),
        line,
        np.zeros((0, 2), np.int32),
        0.0,
        verdict,
        overlapped_by,
    )


def pedestrian(box_px: tuple[float, float, float, float], verdict: str) -> PedestrianCandidate:
    axis = (box_px[0] + box_px[2] - 1) / 2
    return PedestrianCandidate(
        0,
        axis,
        4.0,
        0.8,
        0.8,
        0.5,
        0.1,
        box_px,
        box_px,
        False,
        10.0,
        0.0,
        1.7,
        0.6,
        0.5,
        verdict,  # type: ignore[arg-type]
    )


def ring(c0: int, r0: int, c1: int, r1: int, thickness: int) -> np.ndarray:
    """(H, W) bool: the pixels of a rectangle outline from (c0, r0) to (c1, r1) inclusive,
    `thickness` pixels deep inwards."""
    mask = np.zeros((HEIGHT_PX, WIDTH_PX), bool)
    mask[r0 : r1 + 1, c0 : c1 + 1] = True
    mask[r0 + thickness : r1 + 1 - thickness, c0 + thickness : c1 + 1 - thickness] = False
    return mask


def is_colour(image: np.ndarray, colour: tuple[int, int, int]) -> np.ndarray:
    return np.all(image == np.array(colour, np.uint8), axis=-1)


# --- radar ----------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("verdict", "colour"),
    [
        ("vehicle", overlays.RADAR_REFINED_COLOUR),
        ("no_symmetry", overlays.RADAR_DISCARDED_COLOUR),
        ("size_filter", overlays.RADAR_DISCARDED_COLOUR),
        ("guard_rail", overlays.RADAR_GUARD_RAIL_COLOUR),
    ],
)
def test_radar_cross_lands_where_the_camera_projects_in_its_verdict_colour(
    verdict: str, colour: tuple[int, int, int]
) -> None:
    camera = fake_camera()
    ((u, v),) = camera.project(np.array([[25.0, -1.5, 0.0]]))[0]
    out = drawn(overlays.put_radar_targets, black(), [target_result(verdict)], camera)
    row, col = round(v), round(u)
    arm = draw.RADAR_CROSS_SIZE_PX // 2 - 1
    for r, c in (
        (row, col),
        (row, col - arm),
        (row, col + arm),
        (row - arm, col),
        (row + arm, col),
    ):
        assert tuple(out[r, c]) == colour
    assert tuple(out[row - arm, col - arm]) == BLACK  # beside the arms
    assert (
        len(
            {
                overlays.RADAR_REFINED_COLOUR,
                overlays.RADAR_DISCARDED_COLOUR,
                overlays.RADAR_GUARD_RAIL_COLOUR,
            }
        )
        == 3
    )


def test_radar_target_behind_the_camera_or_none_draws_nothing() -> None:
    image = black()
    out = drawn(
        overlays.put_radar_targets, image, [target_result("vehicle", x_m=-10.0)], fake_camera()
    )
    assert not out.any()
    out = drawn(overlays.put_radar_targets, image, [], fake_camera())
    np.testing.assert_array_equal(out, image)


# --- search areas and vehicles --------------------------------------------------------------


def test_search_area_draws_the_border_pixels_of_its_crop() -> None:
    out = drawn(overlays.put_search_areas, black(), [area((10, 20, 50, 40))])
    # the crop is image[20:40, 10:50]: its first and last rows and columns
    expected = ring(10, 20, 49, 39, 1)
    np.testing.assert_array_equal(is_colour(out, overlays.SEARCH_AREA_COLOUR), expected)
    assert not out[~expected].any()


def test_vehicle_box_draws_exactly_its_outline_in_the_vehicle_colour() -> None:
    # pixel edges 99.5 .. 180.5 and 199.5 .. 260.5: pixels 100 .. 180 and 200 .. 260
    out = drawn(overlays.put_vehicle_boxes, black(), [vehicle((99.5, 199.5, 180.5, 260.5))])
    expected = ring(100, 200, 180, 260, overlays.BOX_THICKNESS_PX)
    np.testing.assert_array_equal(is_colour(out, overlays.VEHICLE_COLOUR), expected)
    assert not out[~expected].any()


def test_a_vehicle_hidden_on_one_side_is_tagged_so() -> None:
    hidden = dataclasses.replace(vehicle((99.5, 199.5, 180.5, 260.5)), hidden_side="left")
    out = drawn(overlays.put_vehicle_boxes, black(), [hidden])
    plain = drawn(overlays.put_vehicle_boxes, black(), [vehicle((99.5, 199.5, 180.5, 260.5))])
    np.testing.assert_array_equal(out[200:], plain[200:])  # the same box
    assert out[185:199, 100:160].any() and not plain[:199].any()  # the tag above it


def test_a_vehicle_without_radar_and_a_searched_area_are_drawn_in_dashes() -> None:
    searched = dataclasses.replace(vehicle((99.5, 199.5, 180.5, 260.5)), target_indices=())
    out = drawn(overlays.put_vehicle_boxes, black(), [searched])
    solid = ring(100, 200, 180, 260, overlays.BOX_THICKNESS_PX)
    dashes = is_colour(out, overlays.VEHICLE_COLOUR)
    assert not out[~solid].any()  # on the outline only
    # dash_px on from each corner, dash_px off
    d = overlays.DASH_PX
    assert dashes[200, 100 : 100 + d].all() and not dashes[200, 100 + d : 100 + 2 * d].any()
    assert dashes[200 : 200 + d, 180].all() and not dashes[200 + d : 200 + 2 * d, 180].any()
    assert 0.4 < np.count_nonzero(dashes) / np.count_nonzero(solid) < 0.65
    # an area searched for track 12: dashed, tagged with the id above it
    out = drawn(overlays.put_search_areas, black(), [], [(area((100, 200, 160, 230)), 12)])
    grey = is_colour(out, overlays.SEARCH_AREA_COLOUR)
    assert grey[200, 100 : 100 + d].all() and not grey[200, 100 + d : 100 + 2 * d].any()
    assert grey[185:199, 100:120].any()  # the "#12" tag
    # where track 12's look was found (core.appearance): its box dashed, tagged "#12 look"
    look = AppearanceMatch(12, vehicle((99.5, 199.5, 180.5, 260.5)), 0.9)
    out = drawn(overlays.put_search_areas, black(), [], [], [look])
    grey = is_colour(out, overlays.SEARCH_AREA_COLOUR)
    assert grey[200, 100 : 100 + d].all() and not grey[200, 100 + d : 100 + 2 * d].any()
    assert grey[185:199, 100:150].any() and not grey[185:199, 160:].any()  # the tag


def test_exclusive_boxes_become_pixel_edges() -> None:
    assert overlays.exclusive_to_edges((10, 20, 50, 40)) == (9.5, 19.5, 49.5, 39.5)


def test_box_dropped_by_the_size_filter_is_drawn_in_the_rejected_colour_with_a_tag() -> None:
    dropped = target_result("size_filter", box_px=(99.5, 199.5, 180.5, 260.5))
    merged = target_result("vehicle", box_px=(299.5, 199.5, 380.5, 260.5))
    out = drawn(overlays.put_vehicle_boxes, black(), [], [dropped, merged])
    rejected = is_colour(out, overlays.VEHICLE_REJECTED_COLOUR)
    assert rejected[230, 100] and rejected[230, 180] and rejected[200, 140]
    assert rejected[185:199, 100:130].any()  # the "size" tag above the box
    # a target's box that became (part of) a vehicle is drawn as the vehicle, not here
    assert not out[:, 290:].any()


# --- guard rails ----------------------------------------------------------------------------


def test_followed_line_is_drawn_on_its_pixels_in_the_image() -> None:
    rail_area = area((100, 200, 160, 230), index=3)
    line = [(20, 2), (20, 3), (19, 4), (19, 5), (18, 6), (18, 7)]
    out = drawn(overlays.put_guard_rails, black(), [check(3, "guard_rail", line)], [rail_area])
    rail = is_colour(out, overlays.GUARD_RAIL_LINE_COLOUR)
    for r, c in line:
        assert rail[200 + r, 100 + c]
    assert not out[:195].any() and not out[240:].any()
    short = drawn(
        overlays.put_guard_rails, black(), [check(3, "not_guard_rail", line)], [rail_area]
    )
    assert is_colour(short, overlays.SHORT_LINE_COLOUR)[220, 102]


@pytest.mark.parametrize("verdict", ["overlap", "line"])
def test_area_labelled_by_overlap_or_rail_line_is_hatched_inside_its_crop_only(
    verdict: str,
) -> None:
    skipped = area((100, 200, 160, 230), index=4)
    out = drawn(
        overlays.put_guard_rails,
        black(),
        [check(4, verdict, overlapped_by=3 if verdict == "overlap" else None)],
        [skipped, area((0, 0, 10, 10), 3)],
    )
    hatch = is_colour(out, overlays.OVERLAP_COLOUR)
    for row in hatch[200:230, 100:160]:  # every row crosses the lines HATCH_STEP_PX apart
        np.testing.assert_array_equal(np.diff(np.flatnonzero(row)), overlays.HATCH_STEP_PX)
    outside = np.ones(hatch.shape, bool)
    outside[200:230, 100:160] = False
    assert not out[outside].any()


def test_no_checks_or_a_check_without_its_area_draw_nothing() -> None:
    assert not drawn(overlays.put_guard_rails, black(), [], []).any()
    assert not drawn(
        overlays.put_guard_rails, black(), [check(7, "guard_rail", [(1, 1)])], []
    ).any()


# --- pedestrians ----------------------------------------------------------------------------


def test_pedestrian_strip_blends_grey_into_its_rows_only() -> None:
    out = drawn(overlays.put_pedestrian_strip, black(), (100, 300))
    grey = round(overlays.STRIP_ALPHA * overlays.STRIP_GREY[0])
    assert (out[100:300] == grey).all()
    assert not out[:100].any() and not out[300:].any()
    assert not drawn(overlays.put_pedestrian_strip, black(), (100, 100)).any()


def test_kept_pedestrian_box_draws_exactly_its_outline_in_bright_green() -> None:
    # columns 100 .. 109 and rows 200 .. 239, ends exclusive
    out = drawn(
        overlays.put_pedestrians, black(), [pedestrian((100.0, 200.0, 110.0, 240.0), "pedestrian")]
    )
    expected = ring(100, 200, 109, 239, overlays.BOX_THICKNESS_PX)
    np.testing.assert_array_equal(is_colour(out, overlays.PEDESTRIAN_COLOUR), expected)
    assert not out[~expected].any()


def test_rejected_pedestrian_is_dark_green_with_its_reason_above() -> None:
    box = (100.0, 200.0, 110.0, 240.0)
    out = drawn(overlays.put_pedestrians, black(), [pedestrian(box, "motion_stereo")])
    dark = is_colour(out, overlays.PEDESTRIAN_REJECTED_COLOUR)
    assert dark[220, 100] and dark[220, 109] and dark[239, 105]
    assert not dark[220, 101]  # one pixel thick
    assert dark[185:199, 100:140].any()  # the tag
    assert not is_colour(out, overlays.PEDESTRIAN_COLOUR).any()


def test_pedestrians_of_other_verdicts_are_left_out_when_asked() -> None:
    candidates = [pedestrian((100.0, 200.0, 110.0, 240.0), "size")]
    assert drawn(overlays.put_pedestrians, black(), candidates).any()
    assert not drawn(overlays.put_pedestrians, black(), candidates, overlays.FUSION_VERDICTS).any()


# --- pitch ----------------------------------------------------------------------------------


def test_pitch_draws_the_horizon_the_lines_and_both_vanishing_points() -> None:
    result = engine_result()
    camera = fake_camera()
    # one line through (200, 400) and the vanishing point (320, 250): u = 200 + 0.8 (400 - v)
    segments = np.array([[200.0, 400.0, 280.0, 300.0]])
    pitch = dataclasses.replace(
        result.pitch,
        chosen=Lines.through_segments(segments),
        intersections_px=np.zeros((0, 2)),
        intersection_used=np.zeros(0, bool),
        calibrated_vp_px=np.array([300.0, 240.0]),
        vanishing_point_px=np.array([320.0, 250.0]),
    )
    out = drawn(overlays.put_pitch, black(), pitch, camera)
    assert tuple(out[round(camera.horizon_row_px(0.0)), 0]) == draw.HORIZON_COLOUR
    hint = is_colour(out, overlays.LINE_HINT_COLOUR)
    for v in (400, 350, 300, 270):  # up to the vanishing point's row
        assert hint[v, round(200 + 0.8 * (400 - v)) - 1 : round(200 + 0.8 * (400 - v)) + 2].any()
    assert not hint[400 + 5 :].any()
    assert tuple(out[240, 300]) == overlays.CALIBRATED_VP_COLOUR
    assert tuple(out[250, 320]) == overlays.VANISHING_POINT_COLOUR


def test_line_segments_run_over_the_rows_of_their_pixels() -> None:
    lines = Lines.through_segments(np.array([[200.0, 400.0, 280.0, 300.0]]))
    np.testing.assert_allclose(overlays.line_segments_px(lines), [[280, 300, 200, 400]])
    np.testing.assert_allclose(overlays.line_segments_px(lines, 250.0), [[320, 250, 200, 400]])


# --- tracks ---------------------------------------------------------------------------------


def track(kind: str, box_px, misses: int = 0, id_: int = 7) -> Track:
    return Track(
        id_,
        kind,  # type: ignore[arg-type]
        20.0,
        0.0,
        0.0,
        0.0,
        1.8,
        0.1,
        0.1,
        box_px,
        5,
        misses,
        5,
        True,
        0,
        (),
    )


def test_track_id_is_tagged_under_its_box_in_the_colour_of_its_kind() -> None:
    out = drawn(
        overlays.put_track_ids,
        black(),
        [
            track("vehicle", (100.0, 200.0, 180.0, 260.0)),
            track("pedestrian", (400.0, 200.0, 420.0, 260.0)),
        ],
    )
    assert is_colour(out[262:280, 100:130], overlays.VEHICLE_COLOUR).any()
    assert is_colour(out[262:280, 400:430], overlays.PEDESTRIAN_COLOUR).any()
    assert not out[:262].any()


def test_tags_of_tracks_in_the_same_place_go_one_under_the_other() -> None:
    box = (100.0, 200.0, 180.0, 260.0)
    out = drawn(overlays.put_track_ids, black(), [track("vehicle", box), track("pedestrian", box)])
    vehicle_rows = np.flatnonzero(is_colour(out, overlays.VEHICLE_COLOUR).any(axis=1))
    pedestrian_rows = np.flatnonzero(is_colour(out, overlays.PEDESTRIAN_COLOUR).any(axis=1))
    assert vehicle_rows.size and pedestrian_rows.size
    assert pedestrian_rows.min() > vehicle_rows.max()  # the second tag below the first


def test_a_track_missed_this_frame_is_tagged_only_as_coasting() -> None:
    seen = track("vehicle", (100.0, 200.0, 180.0, 260.0), id_=7)
    missed = track("pedestrian", (400.0, 200.0, 420.0, 260.0), misses=2, id_=8)
    measured = drawn(overlays.put_track_ids, black(), [seen, missed])
    coasting = drawn(overlays.put_track_ids, black(), [seen, missed], True)
    assert is_colour(measured[262:280, 100:130], overlays.VEHICLE_COLOUR).any()
    assert not measured[:, 300:].any()  # no tag under the missed track's box
    assert is_colour(coasting[262:280, 400:440], overlays.PEDESTRIAN_COLOUR).any()
    assert not coasting[:, :300].any()  # the measured track's tag is the other layer's
    # "#8 ?" is wider than "#8"
    assert np.flatnonzero(coasting.any(axis=(0, 2))).max() > 400 + 20


def test_a_missed_tag_goes_under_a_measured_one_in_the_same_place_whichever_layer_draws() -> None:
    box = (100.0, 200.0, 180.0, 260.0)
    tracks = [track("pedestrian", box, misses=1, id_=3), track("vehicle", box, id_=9)]
    measured = drawn(overlays.put_track_ids, black(), tracks)
    coasting = drawn(overlays.put_track_ids, black(), tracks, True)
    measured_rows = np.flatnonzero(measured.any(axis=(1, 2)))
    coasting_rows = np.flatnonzero(coasting.any(axis=(1, 2)))
    assert measured_rows.size and coasting_rows.size
    assert coasting_rows.min() > measured_rows.max()  # placed after the measured one
    # the measured tag is where it is without the missed track
    alone = drawn(overlays.put_track_ids, black(), tracks[1:])
    np.testing.assert_array_equal(measured, alone)


def test_guard_rail_tracks_get_no_tag() -> None:
    assert not drawn(
        overlays.put_track_ids, black(), [track("guard_rail", (1.0, 2.0, 30.0, 40.0))]
    ).any()


def test_confirmed_tracks_measured_this_frame_are_boxed_with_their_ids() -> None:
    vehicle_box = (100.0, 200.0, 180.0, 260.0)
    person_box = (400.0, 200.0, 420.0, 260.0)  # exclusive ends, as a pedestrian candidate's
    tentative = dataclasses.replace(track("vehicle", (300.0, 100.0, 340.0, 140.0)), confirmed=False)
    tracks = [
        track("vehicle", vehicle_box, id_=7),
        track("pedestrian", person_box, id_=8),
        track("vehicle", (500.0, 100.0, 540.0, 140.0), misses=1, id_=9),
        tentative,
        track("guard_rail", (10.0, 10.0, 60.0, 60.0), id_=10),
    ]
    out = drawn(overlays.put_confirmed_tracks, black(), tracks)
    # the vehicle's box on its edge pixels, the pedestrian's on its last pixels
    assert is_colour(out[200, 100:181], overlays.VEHICLE_COLOUR).all()
    assert is_colour(out[200, 400:420], overlays.PEDESTRIAN_COLOUR).all()
    assert not is_colour(out[200, 420:422], overlays.PEDESTRIAN_COLOUR).any()
    # their ids under the boxes, as put_track_ids places them
    tags = drawn(overlays.put_track_ids, black(), tracks[:2])
    np.testing.assert_array_equal(out[262:], tags[262:])
    # nothing for the missed, the tentative and the guard-rail tracks
    assert not out[:150, 280:].any() and not out[:70, :70].any()


# --- all layers of an engine frame, bad inputs ---------------------------------------------


def test_every_layer_of_an_engine_frame_draws_something_and_draw_layers_on_a_copy() -> None:
    result = engine_result()
    rgb = draw.grey_to_rgb(engine_image())
    before = rgb.copy()
    for name, layer in overlays.LAYERS.items():
        if name == "pedestrians":
            continue  # the highway has no people, and no false ones are kept on this frame
        if name == "coasting tracks":
            continue  # every confirmed track is measured on this frame
        out = drawn(layer, rgb, result)
        assert (out != rgb).any(), name  # the highway frame has something for every other layer
    before_rgb = draw.grey_to_rgb(engine_image("highway", 97))  # a vehicle track coasts
    coasting = drawn(overlays.LAYERS["coasting tracks"], before_rgb, engine_result("highway", 97))
    assert (coasting != before_rgb).any()
    people = drawn(
        overlays.LAYERS["pedestrians"],
        draw.grey_to_rgb(engine_image("stop_and_go", 30)),
        engine_result("stop_and_go", 30),
    )
    assert (people != draw.grey_to_rgb(engine_image("stop_and_go", 30))).any()
    everything = overlays.draw_layers(rgb, result, list(overlays.LAYERS))
    np.testing.assert_array_equal(rgb, before)
    assert everything.shape == rgb.shape and (everything != rgb).any()


def test_what_was_found_and_what_was_rejected_are_separate_layers() -> None:
    result = engine_result()
    rgb = draw.grey_to_rgb(engine_image())
    found = overlays.draw_layers(rgb, result, ["vehicles", "pedestrians"])
    rejected = overlays.draw_layers(rgb, result, ["rejected"])
    for colour in (overlays.VEHICLE_REJECTED_COLOUR, overlays.PEDESTRIAN_REJECTED_COLOUR):
        assert not is_colour(found, colour).any()
    assert (
        is_colour(rejected, overlays.VEHICLE_REJECTED_COLOUR).any()
        or is_colour(rejected, overlays.PEDESTRIAN_REJECTED_COLOUR).any()
    )
    for colour in (overlays.VEHICLE_COLOUR, overlays.PEDESTRIAN_COLOUR):
        assert not is_colour(rejected, colour).any()


def test_draw_layers_refuses_an_unknown_layer() -> None:
    with pytest.raises(ValueError, match=r"names: expected layers among .*'lanes'"):
        overlays.draw_layers(black(), engine_result(), ["radar", "lanes"])


@pytest.mark.parametrize(
    "bad",
    [
        np.zeros((HEIGHT_PX, WIDTH_PX), np.uint8),
        np.zeros((HEIGHT_PX, WIDTH_PX, 3), np.float32),
        [1, 2],
    ],
)
def test_overlays_refuse_a_picture_that_is_not_rgb(bad: object) -> None:
    calls = [
        lambda: overlays.put_radar_targets(bad, [], fake_camera()),  # type: ignore[arg-type]
        lambda: overlays.put_search_areas(bad, []),  # type: ignore[arg-type]
        lambda: overlays.put_vehicle_boxes(bad, []),  # type: ignore[arg-type]
        lambda: overlays.put_guard_rails(bad, [], []),  # type: ignore[arg-type]
        lambda: overlays.put_pedestrian_strip(bad, (0, 1)),  # type: ignore[arg-type]
        lambda: overlays.put_pedestrians(bad, []),  # type: ignore[arg-type]
        lambda: overlays.put_pitch(bad, engine_result().pitch, fake_camera()),  # type: ignore[arg-type]
        lambda: overlays.put_track_ids(bad, []),  # type: ignore[arg-type]
    ]
    for call in calls:
        with pytest.raises(ValueError, match=r"out: expected an \(H, W, 3\) uint8 RGB image"):
            call()
