"""Known-answer tests of the off-the-shelf baselines (core/baselines.py).

The answers come from the scenes: a person rendered by the bundled drives' renderer (its
label image gives the true box), a straight road with lane markings rendered at a known
pitch, a road-shaped polygon drawn to meet at a known vanishing point, a bright block moved
over a standing camera's view, a coarse-grained road under a moving camera.

The HOG tests need an OpenCV with the HOG people detector (OpenCV 5's main package has
none, see the module docstring); they are skipped, with the reason, on one without it.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
import pytest

from core.baselines import (
    HogParams,
    HogPeople,
    HoughPitchParams,
    Mog2Obstacles,
    Mog2Params,
    hough_pitch,
)
from core.hog import HOG_PERSON_HEIGHT, HogUnavailableError, hog_available
from core.search_area import iou
from core.synth.sensors import camera_noise
from tests.core.roadscenes import RoadRenderer, camera, standing_person, straight_road

Box = tuple[float, float, float, float]
U8 = npt.NDArray[np.uint8]

# pyproject.toml depends on opencv-contrib-python-headless, which has HOG in OpenCV 5 too: a
# missing detector is a broken install, so these tests fail rather than skip
requires_hog = pytest.mark.usefixtures("_hog_installed")


@pytest.fixture
def _hog_installed() -> None:
    assert hog_available(), (
        f"OpenCV {cv2.__version__} has no HOG people detector: install "
        "opencv-contrib-python-headless instead of opencv-python-headless"
    )


PERSON_ID = 7
PERSON_HEIGHT_M = 1.75


@cache
def _person_scene(s_m: float, d_m: float) -> tuple[U8, Box]:
    """`roadscenes.standing_person` of the module's person, computed once."""
    return standing_person(s_m, d_m, PERSON_ID, PERSON_HEIGHT_M)


@cache
def _empty_road(markings: bool) -> U8:
    scene = straight_road(speed_mps=0.0, markings=markings)
    return RoadRenderer(scene)(0.0, camera().extrinsics.pitch_rad, noise=False)[0]


@cache
def _hog() -> HogPeople:
    return HogPeople()


# --- HOG people ------------------------------------------------------------------------------


@requires_hog
@pytest.mark.parametrize(("s_m", "d_m"), [(10.0, 2.0), (14.0, -2.0)])
def test_a_standing_person_is_found_with_a_box_over_the_true_one(s_m: float, d_m: float) -> None:
    image, truth = _person_scene(s_m, d_m)
    result = _hog().detect_scored(image, camera().row_window_px)
    assert len(result.boxes_px) == 1
    box = result.boxes_px[0]
    width, height = truth[2] - truth[0], truth[3] - truth[1]
    # The box has the window's person aspect, 1:2, and the rendered person is narrower
    # (about 0.3 as wide as tall): a box of the right height around the person overlaps at
    # most 2 w / h of it. The pyramid steps 5 % and the sample's shrinking is a rule of
    # thumb: a height up to 15 % off leaves (1 / 1.15)^2 of that.
    assert iou(box, truth) >= 2.0 * width / height / 1.15**2
    assert abs((box[3] - box[1]) / height - 1.0) <= 0.15
    # the centre column on the windows' grid: 8 px stride in the 2x image is 4 px here
    assert abs((box[0] + box[2]) / 2 - (truth[0] + truth[2]) / 2) <= 4.0
    window = result.window_boxes_px[0]
    assert window[0] <= box[0] and box[2] <= window[2]
    assert (box[3] - box[1]) == pytest.approx(HOG_PERSON_HEIGHT * (window[3] - window[1]))


@requires_hog
@pytest.mark.parametrize("markings", [False, True])
def test_an_empty_road_has_no_person(markings: bool) -> None:
    assert _hog().detect(_empty_road(markings), camera().row_window_px) == ()


@requires_hog
def test_a_blank_or_tiny_image_has_no_person() -> None:
    assert _hog().detect(np.full((480, 640), 128, np.uint8)) == ()
    # smaller than the 64x128 window even scaled up: nothing to search
    assert _hog().detect(np.zeros((40, 30), np.uint8)) == ()


@requires_hog
def test_only_the_given_rows_are_searched_and_boxes_stay_in_image_rows() -> None:
    image, truth = _person_scene(14.0, -2.0)
    above = (0, math.floor(truth[1]) - 20)  # ends 20 rows above the head
    assert _hog().detect(image, above) == ()
    # a band tight around the person, starting elsewhere than the camera's window: found,
    # in full-image rows
    around = (math.floor(truth[1]) - 24, math.ceil(truth[3]) + 24)
    result = _hog().detect_scored(image, around)
    assert result.rows_px == around
    assert len(result.boxes_px) == 1
    width, height = truth[2] - truth[0], truth[3] - truth[1]
    assert iou(result.boxes_px[0], truth) >= 2.0 * width / height / 1.15**2


@requires_hog
def test_boxes_come_strongest_first() -> None:
    # two people: whatever their scores, the order follows them
    a, _ = _person_scene(10.0, 2.0)
    b, _ = _person_scene(14.0, -2.0)
    both = np.where(np.arange(640)[None, :] < 320, a, b).astype(np.uint8)
    result = _hog().detect_scored(both, camera().row_window_px)
    assert len(result.scores) == 2
    assert list(result.scores) == sorted(result.scores, reverse=True)


@requires_hog
def test_hog_rejects_bad_images_and_rows() -> None:
    hog = _hog()
    with pytest.raises(ValueError, match="image"):
        hog.detect(np.zeros((480, 640), np.float32))
    with pytest.raises(ValueError, match="image"):
        hog.detect(np.zeros((480, 640, 3), np.uint8))
    for rows in [(200, 200), (0, 481), (-1, 100), (1.5, 300)]:
        with pytest.raises(ValueError, match="rows_px"):
            hog.detect(np.zeros((480, 640), np.uint8), rows)  # type: ignore[arg-type]


def test_hog_params_name_what_they_reject() -> None:
    bad: list[tuple[str, Any]] = [
        ("win_stride_px", 12),
        ("win_stride_px", 0),
        ("padding_px", -8),
        ("scale", 1.0),
        ("hit_threshold", math.nan),
        ("upscale", 0.0),
        ("group_threshold", -1),
    ]
    for field, value in bad:
        with pytest.raises(ValueError, match=field):
            HogParams(**{field: value})


def test_without_hog_opencv_the_error_says_what_to_install(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.delattr(cv2, "HOGDescriptor", raising=False)
    assert not hog_available()
    with pytest.raises(HogUnavailableError, match="opencv-contrib-python-headless"):
        HogPeople()


# --- Hough pitch -----------------------------------------------------------------------------


def _road_polygon(vp_px: tuple[int, int], top_row_px: int) -> U8:
    """A bright road-shaped trapezoid on a dark image, its two sides at 45 deg running
    towards vp_px from row 430 up to top_row_px (top and bottom horizontal: only the sides
    are slanted). At 45 deg the rasterised border is an exact pixel diagonal."""
    image = np.full((480, 640), 60, np.uint8)
    u, v = vp_px
    bottom = 430
    corners = [
        (u - (bottom - v), bottom),
        (u + (bottom - v), bottom),
        (u + (top_row_px - v), top_row_px),
        (u - (top_row_px - v), top_row_px),
    ]
    cv2.fillPoly(image, [np.array(corners, dtype=np.int32)], 200)
    return image


def test_two_road_sides_give_their_vanishing_point_and_its_pitch() -> None:
    cam = camera()
    vp = (330, 226)  # 6 px above and 10 px right of the calibrated vanishing point
    result = hough_pitch(_road_polygon(vp, 260), cam)
    assert result.lines >= 2
    du = result.segments_px[:, 2] - result.segments_px[:, 0]
    dv = result.segments_px[:, 3] - result.segments_px[:, 1]
    assert np.abs(du) == pytest.approx(np.abs(dv))  # every segment on a side
    assert result.vanishing_point_px is not None and result.pitch_rad is not None
    # Canny's edges along each side are the border's pixel diagonal shifted by a at most
    # one column (a for the left side, b for the right): the lines u = u_p - (v - v_p) + a
    # and u = u_p + (v - v_p) + b meet at v_p + (b - a) / 2, u_p + (a + b) / 2: 1 px.
    assert result.vanishing_point_px == pytest.approx(vp, abs=1.0)
    i = cam.intrinsics
    assert result.pitch_rad == pytest.approx(
        math.atan2(i.cy_px - vp[1], i.fy_px), abs=1.0 / i.fy_px
    )
    assert result.pitch_rad == cam.pitch_from_horizon_row(result.vanishing_point_px[1])


@pytest.mark.parametrize("pitch_rad", [0.025, 0.01, -0.005])
def test_a_rendered_straight_road_gives_its_pitch(pitch_rad: float) -> None:
    cam = camera()  # calibrated at 0.01 rad
    image, _ = RoadRenderer(straight_road(speed_mps=0.0))(0.0, pitch_rad, noise=True)
    result = hough_pitch(image, cam)
    assert result.lines >= 2
    assert result.pitch_rad is not None
    # The markings' borders are blurred and noisy: each Canny edge lies within 1 px of its
    # border, and extrapolating a segment of at least 40 px up to as far again beyond its
    # end can double that: 2 px of row, atan(2 / fy) = 0.15 deg.
    assert abs(result.pitch_rad - pitch_rad) <= math.atan2(2.0, cam.intrinsics.fy_px)


def test_nothing_slanted_gives_no_pitch() -> None:
    cam = camera()
    blank = np.full((480, 640), 128, np.uint8)
    result = hough_pitch(blank, cam)
    assert result.pitch_rad is None and result.vanishing_point_px is None and result.lines == 0
    assert not result.edges.any()
    # a horizontal and a vertical line (a kerb, a pole): edges and segments, no slant
    crossed = blank.copy()
    cv2.line(crossed, (50, 350), (600, 350), 255, 3)
    cv2.line(crossed, (320, 240), (320, 420), 255, 3)
    result = hough_pitch(crossed, cam)
    assert result.edges.any()
    assert result.lines == 0 and result.pitch_rad is None


def test_an_intersection_far_from_the_calibration_is_not_used() -> None:
    # the sides meet 100 px above the calibrated vanishing point, beyond the 40 px region
    result = hough_pitch(_road_polygon((320, 132), 260), camera())
    assert result.lines >= 2
    assert len(result.intersections_px) >= 1 and not result.intersection_used.any()
    assert result.pitch_rad is None and result.vanishing_point_px is None


def test_hough_pitch_rejects_bad_images_and_params() -> None:
    cam = camera()
    with pytest.raises(ValueError, match="image"):
        hough_pitch(np.zeros((300, 640), np.uint8), cam)
    with pytest.raises(ValueError, match="image"):
        hough_pitch(np.zeros((480, 640), np.float64), cam)
    with pytest.raises(ValueError, match="canny_high"):
        HoughPitchParams(canny_low=100.0, canny_high=50.0)
    with pytest.raises(ValueError, match="min_lines"):
        HoughPitchParams(min_lines=1)
    with pytest.raises(ValueError, match="min_angle_from_horizontal_rad"):
        HoughPitchParams(min_angle_from_horizontal_rad=1.0, min_angle_from_vertical_rad=1.0)


# --- MOG2 ------------------------------------------------------------------------------------

BLOCK = (30, 40)  # rows, columns of the bright block
BLOCK_ROW = 330


def _with_block(image: U8, u0: int, v0: int = BLOCK_ROW) -> tuple[U8, npt.NDArray[np.bool_]]:
    out = image.copy()
    out[v0 : v0 + BLOCK[0], u0 : u0 + BLOCK[1]] = 250
    where = np.zeros(image.shape, dtype=np.bool_)
    where[v0 : v0 + BLOCK[0], u0 : u0 + BLOCK[1]] = True
    return out, where


def test_a_moving_block_before_a_standing_camera_is_marked_and_little_else() -> None:
    road = _empty_road(True)
    rng = np.random.default_rng(3)
    rows = camera().row_window_px
    mog = Mog2Obstacles()
    for _ in range(30):  # warm-up on the empty road, fresh sensor noise each frame
        assert not mog.update(camera_noise(road, rng), rows).any()
    window = np.zeros(road.shape, dtype=np.bool_)
    window[rows[0] : rows[1]] = True
    for k in range(10):
        image, block = _with_block(camera_noise(road, rng), 100 + 12 * k)
        mask = mog.update(image, rows)
        assert set(np.unique(mask)) <= {0, 255}
        # grey 250 on a road of about 110 with noise of 0.3 grey levels: far beyond the
        # 4 sigma (var_threshold 16) of every pixel's mixture
        assert np.count_nonzero(mask[block]) >= 0.95 * block.sum()
        assert np.count_nonzero(mask[window & ~block]) <= 0.001 * window.sum()


@cache
def _road_shares(speed_mps: float) -> list[float]:
    """Share of the road rows (from 20 rows below the horizon to the end of the camera's
    window) MOG2 marks on each of 15 frames of a coarse-grained road without markings."""
    cam = camera()
    first, stop = cam.row_window_px
    road0 = math.ceil(cam.horizon_row_px()) + 20
    renderer = RoadRenderer(straight_road(speed_mps=speed_mps, markings=False, texture=1.0))
    mog = Mog2Obstacles()
    shares: list[float] = []
    for k in range(15):
        image, _ = renderer(0.1 * k, cam.extrinsics.pitch_rad)
        mask = mog.update(image, (first, stop))
        shares.append(np.count_nonzero(mask[road0:stop]) / mask[road0:stop].size)
    return shares


def test_a_moving_camera_marks_much_of_a_textured_road() -> None:
    # Without ego compensation the road's grain moves under every pixel: the mixtures keep
    # widening, yet after 5 frames each frame still marks a sizeable share of the road
    # (0.2 to 0.3 here), where a standing camera marks none of it.
    moving, standing = _road_shares(15.0), _road_shares(0.0)
    assert moving[0] == standing[0] == 0.0  # the first frame is empty
    assert min(moving[5:]) >= 0.15
    assert max(standing) <= 0.001


def test_reset_forgets_the_background_and_the_size() -> None:
    road = _empty_road(True)
    mog = Mog2Obstacles()
    for _ in range(5):
        mog.update(road)
    image, block = _with_block(road, 200)
    assert mog.update(image)[block].all()
    mog.reset()
    assert not mog.update(image).any()  # first frame again
    with pytest.raises(ValueError, match="image"):
        mog.update(image[:240])
    mog.reset()
    assert not mog.update(image[:240]).any()


def test_rows_outside_the_given_ones_stay_zero() -> None:
    road = _empty_road(True)
    rows = (250, 400)
    mog = Mog2Obstacles()
    for _ in range(5):
        mog.update(road, rows)
    image, block = _with_block(road, 200, v0=230)  # rows 230-259: half outside
    mask = mog.update(image, rows)
    assert mask[250:260][block[250:260]].all()
    assert not mask[:250].any() and not mask[400:].any()


def test_mog2_rejects_bad_images_rows_and_params() -> None:
    mog = Mog2Obstacles()
    with pytest.raises(ValueError, match="image"):
        mog.update(np.zeros((480, 640), np.float32))
    with pytest.raises(ValueError, match="image"):
        mog.update(np.zeros((480, 640, 3), np.uint8))
    with pytest.raises(ValueError, match="rows_px"):
        mog.update(np.zeros((480, 640), np.uint8), (300, 100))
    mog.update(np.zeros((480, 640), np.uint8), (100, 300))
    with pytest.raises(ValueError, match="rows_px"):
        mog.update(np.zeros((480, 640), np.uint8), (100, 301))
    bad: list[tuple[str, Any]] = [
        ("history_frames", 0),
        ("var_threshold", 0.0),
        ("learning_rate", 1.5),
    ]
    for field, value in bad:
        with pytest.raises(ValueError, match=field):
            Mog2Params(**{field: value})
