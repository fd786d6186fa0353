"""Motion stereo (paper 000, II-B): known answers on rendered roads and a textured plane.

The answers come from the scene, never from the code under test: on a flat road the
bird's-eye views of two frames coincide once the known ego motion is undone; an object's
differences can only lie on road cells whose ground point the camera sees covered by the
object (the renderer's label image) in one of the two frames; a wrong ego motion cannot
cancel the road.
"""

from __future__ import annotations

import math
from dataclasses import replace

import cv2
import numpy as np
import numpy.typing as npt
import pytest
from roadscenes import RoadRenderer, camera, straight_road

from core.camera import BirdEyeGrid, CameraModel
from core.cli import DEFAULT_RECORDINGS
from core.ego import EgoMotion
from core.io.canlog import STANDSTILL_SPEED_MPS
from core.io.drive import Drive
from core.motion_stereo import (
    MotionStereo,
    MotionStereoResult,
    frames_to_forget,
    grid_for,
)
from core.params import MotionStereoParams
from core.synth.scene import StaticObject, Trajectory, Vehicle

BUNDLED = DEFAULT_RECORDINGS

Mask = npt.NDArray[np.bool_]
U8 = npt.NDArray[np.uint8]

FRAME_S = 0.1  # the bundled drives' and these scenes' frame interval
SPEED_MPS = 15.0  # ego speed of the moving scenes: 1.5 m per frame
CAR_ID, SIGN_ID = 1, 2
# Differences spread at most this far beyond the cells an object covers: the 3x3 mean
# reaches one cell out and both bilinear warps half a cell each.
SPREAD_CELLS = 3


def _parked_car(s_m: float, d_m: float, speed_mps: float = 0.0) -> Vehicle:
    """A car in the lane at offset d_m, its centre at s_m at t = 0, driving at speed_mps."""
    keys = [(0.0, s_m, d_m), (10.0, s_m + 10.0 * speed_mps, d_m)]
    return Vehicle(CAR_ID, "car", 4.4, 1.8, 1.5, 70, Trajectory.from_waypoints(keys))


SIGN = StaticObject(SIGN_ID, "sign", 12.5, -3.0, 0.6, 2.0, 200)


@pytest.fixture(scope="module")
def cam() -> CameraModel:
    return camera()


@pytest.fixture(scope="module")
def params() -> MotionStereoParams:
    return MotionStereoParams()


@pytest.fixture(scope="module")
def flat(cam: CameraModel) -> tuple[U8, U8]:
    """Two frames 0.1 s apart of an empty textured road, the ego car at 15 m/s."""
    render = RoadRenderer(straight_road(speed_mps=SPEED_MPS), seed=1)
    pitch = cam.extrinsics.pitch_rad
    return render(0.0, pitch)[0], render(FRAME_S, pitch)[0]


@pytest.fixture(scope="module")
def box(cam: CameraModel) -> tuple[tuple[U8, npt.NDArray[np.uint16]], ...]:
    """A parked car in the left lane and a sign on the right, the ego car at 15 m/s."""
    scene = straight_road(speed_mps=SPEED_MPS, vehicles=[_parked_car(16.0, 3.6)], statics=[SIGN])
    render = RoadRenderer(scene, seed=2)
    pitch = cam.extrinsics.pitch_rad
    return render(0.0, pitch), render(FRAME_S, pitch)


@pytest.fixture(scope="module")
def still(cam: CameraModel) -> tuple[tuple[U8, npt.NDArray[np.uint16]], ...]:
    """The ego car stands still; a car drives away at 6 m/s ahead, a sign stands by."""
    scene = straight_road(speed_mps=0.0, vehicles=[_parked_car(14.0, 3.6, 6.0)], statics=[SIGN])
    render = RoadRenderer(scene, seed=3)
    pitch = cam.extrinsics.pitch_rad
    return render(0.0, pitch), render(FRAME_S, pitch)


def _two_frames(
    params: MotionStereoParams, cam: CameraModel, im0: U8, im1: U8, ego: EgoMotion
) -> MotionStereoResult:
    ms = MotionStereo(params)
    ms.update(im0, cam, None)
    return ms.update(im1, cam, ego)


def _seen_covered(
    grid: BirdEyeGrid,
    cam: CameraModel,
    labels: npt.NDArray[np.uint16],
    ids: list[int],
    ahead_m: float,
) -> Mask:
    """Grid cells whose road point, `ahead_m` further ahead, the camera sees covered by one of
    the objects `ids` (labels: the renderer's object id per pixel)."""
    rows, cols = grid.shape
    cc, rr = np.meshgrid(np.arange(cols, dtype=np.float64), np.arange(rows, dtype=np.float64))
    ground = grid.ground_from_cells(np.stack([cc.ravel(), rr.ravel()], axis=1))
    pts = np.column_stack([ground[:, 0] + ahead_m, ground[:, 1], np.zeros(len(ground))])
    uv, front = cam.project(pts)
    h, w = labels.shape
    with np.errstate(invalid="ignore"):
        u, v = np.rint(uv[:, 0]), np.rint(uv[:, 1])
        inside = front & (u >= 0) & (u < w) & (v >= 0) & (v < h)
    covered = np.zeros(len(pts), dtype=bool)
    covered[inside] = np.isin(labels[v[inside].astype(int), u[inside].astype(int)], ids)
    return covered.reshape(rows, cols)


def _dilate(mask: Mask, cells: int) -> Mask:
    kernel = np.ones((2 * cells + 1, 2 * cells + 1), dtype=np.uint8)
    return cv2.dilate(mask.astype(np.uint8), kernel) > 0


def _erode(mask: Mask, cells: int) -> Mask:
    kernel = np.ones((2 * cells + 1, 2 * cells + 1), dtype=np.uint8)
    return cv2.erode(mask.astype(np.uint8), kernel, borderValue=0) > 0


def _rows_of(mask: Mask) -> npt.NDArray[np.intp]:
    return np.nonzero(mask.any(axis=1))[0]


# --- the flat road --------------------------------------------------------------------------
def test_flat_road_under_known_ego_motion_cancels(
    params: MotionStereoParams, cam: CameraModel, flat: tuple[U8, U8]
) -> None:
    r = _two_frames(params, cam, *flat, EgoMotion(SPEED_MPS * FRAME_S, 0.0, 0.0, FRAME_S))
    valid = r.valid > 0
    assert r.mode == "motion_stereo"
    assert valid.sum() > 0.5 * valid.size
    assert not r.obstacles.any()
    assert r.regions == ()
    assert not r.image_mask.any()
    # 1.5 m forward: the moved background's far 1.5 m (15 cells) come from beyond the
    # previous grid, plus the one-cell erosion of the valid border.
    assert _rows_of(valid)[0] == pytest.approx(15 + 1, abs=1)
    # the near edge: the ground seen by the window's last row
    stop = cam.row_window_px[1]
    x_near = cam.ground_point([cam.intrinsics.cx_px, stop - 1])[0, 0]
    near_row = (r.grid.x_max_m - x_near) / r.grid.cell_m - 0.5
    assert _rows_of(valid)[-1] == pytest.approx(near_row - 1, abs=2)


def test_bird_eye_view_is_the_camera_ipm_of_the_window(
    params: MotionStereoParams, cam: CameraModel, flat: tuple[U8, U8]
) -> None:
    r = MotionStereo(params).update(flat[1], cam, None)
    valid = r.valid > 0
    assert r.grid == grid_for(params) == BirdEyeGrid(4.0, 40.0, -10.0, 10.0, 0.1)
    assert r.bird_eye.shape == r.grid.shape == (360, 200)
    # the same bilinear warp from the window instead of the whole image: the fixed-point
    # sample positions may round a grey level differently
    ipm = cam.warp_to_grid(flat[1], r.grid)
    assert np.abs(r.bird_eye[valid].astype(int) - ipm[valid]).max() <= 1
    np.testing.assert_allclose(r.H_image_grid, cam.H_image_grid(r.grid))


def test_wrong_ego_motion_leaves_much_of_the_road(
    params: MotionStereoParams, cam: CameraModel, flat: tuple[U8, U8]
) -> None:
    # The car moved 1.5 m but the odometry says it stood still.
    r = _two_frames(params, cam, *flat, EgoMotion.still(FRAME_S))
    assert r.mode == "background_subtraction"
    assert np.count_nonzero(r.obstacles) > 0.02 * np.count_nonzero(r.valid)
    assert r.image_mask.any()


# --- a textured plane under known rotation ------------------------------------------------------
TEXTURE_CELL_M = 0.05
TEXTURE_ORIGIN_M = (-10.0, -30.0)  # world (x, y) of texture pixel (row 0, col 0)


def _plane_frame(cam: CameraModel, texture: npt.NDArray[np.float32], pose: EgoMotion) -> U8:
    """The image of a flat textured plane from a car at `pose` (dx_m, dy_m, dyaw_rad) in the
    world frame (the car's frame at pose 0); the sky is grey 200."""
    h, w = cam.intrinsics.height_px, cam.intrinsics.width_px
    vv, uu = np.mgrid[0:h, 0:w]
    g = cam.ground_point(np.stack([uu.ravel(), vv.ravel()], axis=1).astype(np.float64))
    c, s = math.cos(pose.dyaw_rad), math.sin(pose.dyaw_rad)
    wx = pose.dx_m + c * g[:, 0] - s * g[:, 1]
    wy = pose.dy_m + s * g[:, 0] + c * g[:, 1]
    map_col = ((wy - TEXTURE_ORIGIN_M[1]) / TEXTURE_CELL_M).reshape(h, w).astype(np.float32)
    map_row = ((wx - TEXTURE_ORIGIN_M[0]) / TEXTURE_CELL_M).reshape(h, w).astype(np.float32)
    sky = ~np.isfinite(map_col)
    map_col[sky] = -1.0
    map_row[sky] = -1.0
    image = cv2.remap(texture, map_col, map_row, cv2.INTER_LINEAR, borderValue=200.0)
    return np.clip(np.rint(image), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module")
def plane(cam: CameraModel) -> tuple[U8, U8, EgoMotion]:
    """Two frames of a plane with a smooth random texture (0.8 m grain, coarse enough not to
    alias at 40 m); the car drives 1.2 m, slides 0.3 m left and turns 0.06 rad left."""
    rng = np.random.default_rng(5)
    noise = rng.normal(0.0, 1.0, (int(80 / TEXTURE_CELL_M), int(60 / TEXTURE_CELL_M)))
    smooth = cv2.GaussianBlur(noise.astype(np.float32), (0, 0), 0.8 / TEXTURE_CELL_M)
    texture = np.clip(128.0 + smooth / smooth.std() * 40.0, 0, 255).astype(np.float32)
    ego = EgoMotion(1.2, 0.3, 0.06, FRAME_S)
    return _plane_frame(cam, texture, EgoMotion.still()), _plane_frame(cam, texture, ego), ego


def test_plane_cancels_under_rotation_and_translation(
    params: MotionStereoParams, cam: CameraModel, plane: tuple[U8, U8, EgoMotion]
) -> None:
    im0, im1, ego = plane
    r = _two_frames(params, cam, im0, im1, ego)
    assert r.mode == "motion_stereo"
    assert r.ego == ego
    assert np.count_nonzero(r.valid) > 0.5 * r.valid.size
    assert not r.obstacles.any()


@pytest.mark.parametrize(
    "wrong",
    [
        EgoMotion(1.2, 0.3, -0.06, FRAME_S),  # turned the other way
        EgoMotion(1.2, 0.3, 0.0, FRAME_S),  # did not turn
        EgoMotion(1.2, -0.3, 0.06, FRAME_S),  # slid the other way
        EgoMotion(0.0, 0.3, 0.06, FRAME_S),  # did not drive forward
    ],
)
def test_plane_does_not_cancel_under_a_wrong_motion(
    params: MotionStereoParams,
    cam: CameraModel,
    plane: tuple[U8, U8, EgoMotion],
    wrong: EgoMotion,
) -> None:
    im0, im1, _ = plane
    r = _two_frames(params, cam, im0, im1, wrong)
    assert np.count_nonzero(r.obstacles) > 0.05 * np.count_nonzero(r.valid)


# --- objects --------------------------------------------------------------------------------
def test_standing_objects_give_differences_only_where_they_are_seen(
    params: MotionStereoParams,
    cam: CameraModel,
    box: tuple[tuple[U8, npt.NDArray[np.uint16]], ...],
) -> None:
    (im0, lab0), (im1, lab1) = box
    dx = SPEED_MPS * FRAME_S
    r = _two_frames(params, cam, im0, im1, EgoMotion(dx, 0.0, 0.0, FRAME_S))
    d = r.obstacles > 0
    grid = r.grid

    def seen(ids: list[int]) -> Mask:
        # in this frame, or in the previous one from 1.5 m further back
        return _seen_covered(grid, cam, lab1, ids, 0.0) | _seen_covered(grid, cam, lab0, ids, dx)

    objects = _dilate(seen([CAR_ID, SIGN_ID]), SPREAD_CELLS)
    assert np.count_nonzero(d & ~objects) <= 0.01 * np.count_nonzero(d)
    for obj in (CAR_ID, SIGN_ID):
        assert np.count_nonzero(d & _dilate(seen([obj]), SPREAD_CELLS)) >= 50, obj

    # the car's differences start at its base, not in front of it
    car_now = _seen_covered(grid, cam, lab1, [CAR_ID], 0.0)
    base_x = grid.x_max_m - (_rows_of(car_now)[-1] + 1) * grid.cell_m
    car_d = d & _dilate(seen([CAR_ID]), SPREAD_CELLS)
    nearest_d_x = grid.x_max_m - (_rows_of(car_d)[-1] + 1) * grid.cell_m
    assert base_x - 0.3 <= nearest_d_x <= base_x + 3.0

    # a region is on the car, its image box over the car's lower part
    on_car = [
        g
        for g in r.regions
        if car_d[
            g.grid_box_cells[1] : g.grid_box_cells[3], g.grid_box_cells[0] : g.grid_box_cells[2]
        ].any()
    ]
    assert on_car
    rows, cols = np.nonzero(lab1 == CAR_ID)
    u0, v0, u1, v1 = on_car[0].box_px
    assert u0 < cols.max() and u1 > cols.min() and v0 < rows.max() and v1 > rows.min()
    assert all(g.cells * grid.cell_m**2 >= params.min_region_m2 for g in r.regions)
    assert [g.nearest_x_m for g in r.regions] == sorted(g.nearest_x_m for g in r.regions)

    # The image mask is D reprojected: on the objects, and between where they are and where
    # they were (B's old smear seen from here runs from the base towards the old column), so
    # inside the columns the objects span in the two frames, below the horizon.
    first, stop = cam.row_window_px
    mask = np.zeros(lab1.shape, dtype=bool)
    mask[first:stop] = r.image_mask > 0
    assert (mask & (lab1 == CAR_ID)).any()
    columns = np.zeros(lab1.shape[1], dtype=bool)
    for obj in (CAR_ID, SIGN_ID):
        spanned = np.nonzero(((lab0 == obj) | (lab1 == obj)).any(axis=0))[0]
        columns[max(spanned.min() - 8, 0) : spanned.max() + 9] = True
    assert not mask[:, ~columns].any()
    assert not mask[: math.ceil(cam.horizon_row_px())].any()


def test_eq_6_7_background_update(
    params: MotionStereoParams,
    cam: CameraModel,
    box: tuple[tuple[U8, npt.NDArray[np.uint16]], ...],
) -> None:
    (im0, _), (im1, _) = box
    r = _two_frames(params, cam, im0, im1, EgoMotion(SPEED_MPS * FRAME_S, 0.0, 0.0, FRAME_S))
    d = r.obstacles > 0
    a = r.bird_eye.astype(np.float64)
    b = r.background.astype(np.float64)
    nb = r.next_background.astype(np.float64)
    assert d.any()
    # w = 0.25 on obstacle cells (rounded to whole grey levels), w = 1 elsewhere
    assert np.abs(nb[d] - (0.25 * a[d] + 0.75 * b[d])).max() <= 0.5 + 1e-9
    np.testing.assert_array_equal(nb[~d], a[~d])
    # D is m > xi: the rounded mean clears xi by a grey level where D is set, and not elsewhere
    m = r.local_mean.astype(np.float64)
    valid = r.valid > 0
    assert (m[d] >= params.threshold_xi).all()
    assert (d | ~valid | (m <= params.threshold_xi)).all()
    assert not (d & ~valid).any()
    # C is |A - B| on valid cells, 0 elsewhere
    c = r.difference.astype(np.float64)
    np.testing.assert_array_equal(c[valid], np.abs(a - b)[valid])
    assert not r.difference[~valid].any()


def test_still_ego_car_is_background_subtraction(
    params: MotionStereoParams,
    cam: CameraModel,
    still: tuple[tuple[U8, npt.NDArray[np.uint16]], ...],
) -> None:
    (im0, lab0), (im1, lab1) = still
    r = _two_frames(params, cam, im0, im1, EgoMotion.still(FRAME_S))
    assert r.mode == "background_subtraction"
    d = r.obstacles > 0
    grid = r.grid

    car = _seen_covered(grid, cam, lab1, [CAR_ID], 0.0) | _seen_covered(
        grid, cam, lab0, [CAR_ID], 0.0
    )
    # its shadow moves with it: its footprint at both instants, grown by a metre
    footprint = np.zeros(grid.shape, dtype=np.uint8)
    for t in (0.0, FRAME_S):
        s = 14.0 + 6.0 * t
        corners = grid.cells_from_ground([(s - 3.2, 3.6 - 1.9), (s + 3.2, 3.6 + 1.9)])
        (c0, r0), (c1, r1) = np.rint(corners).astype(int)
        footprint[min(r0, r1) : max(r0, r1) + 1, min(c0, c1) : max(c0, c1) + 1] = 1
    moving = _dilate(car | (footprint > 0), SPREAD_CELLS)
    assert np.count_nonzero(d & moving) >= 200
    assert np.count_nonzero(d & ~moving) <= 0.01 * np.count_nonzero(d)
    # the sign stands still: nothing there
    sign = _dilate(_seen_covered(grid, cam, lab1, [SIGN_ID], 0.0), SPREAD_CELLS)
    assert sign.any()
    assert not (d & sign & ~moving).any()


# --- degenerate input and states ---------------------------------------------------------------
def test_first_frame_takes_the_background_from_itself(
    params: MotionStereoParams, cam: CameraModel, flat: tuple[U8, U8]
) -> None:
    ms = MotionStereo(params)
    assert not ms.has_background
    r = ms.update(flat[0], cam, EgoMotion(1.5, 0.0, 0.0, FRAME_S))
    assert r.mode == "first_frame"
    assert r.ego is None
    np.testing.assert_array_equal(r.background, r.bird_eye)
    np.testing.assert_array_equal(r.next_background, r.bird_eye)
    np.testing.assert_array_equal(r.T_prevgrid_grid, np.eye(3)[:2])
    assert not r.difference.any() and not r.obstacles.any() and r.regions == ()
    assert r.image_mask.shape == (300, 640) and r.image_mask_first_row_px == 130
    assert not r.image_mask.any()
    assert ms.has_background
    ms.reset()
    assert not ms.has_background
    assert ms.update(flat[1], cam, None).mode == "first_frame"


def test_unknown_ego_motion_restarts_the_background(
    params: MotionStereoParams,
    cam: CameraModel,
    box: tuple[tuple[U8, npt.NDArray[np.uint16]], ...],
) -> None:
    (im0, _), (im1, _) = box
    ms = MotionStereo(params)
    ms.update(im0, cam, None)
    r = ms.update(im1, cam, None)
    assert r.mode == "restarted" and r.ego is None
    np.testing.assert_array_equal(r.background, r.bird_eye)
    assert not r.obstacles.any()
    # and the next frame with a known motion works again: here back to frame 0 by moving
    # 1.5 m backwards, against the restarted background of frame 1
    back = ms.update(im0, cam, EgoMotion(-SPEED_MPS * FRAME_S, 0.0, 0.0, FRAME_S))
    assert back.mode == "motion_stereo"
    assert back.obstacles.any()


def test_blank_image_gives_nothing(params: MotionStereoParams, cam: CameraModel) -> None:
    blank = np.zeros((480, 640), dtype=np.uint8)
    ms = MotionStereo(params)
    ms.update(blank, cam, None)
    r = ms.update(blank, cam, EgoMotion(1.5, 0.1, 0.02, FRAME_S))
    assert r.mode == "motion_stereo"
    assert not r.obstacles.any() and r.regions == () and not r.image_mask.any()


def test_standing_still_on_a_static_road_gives_nothing(
    params: MotionStereoParams, cam: CameraModel
) -> None:
    render = RoadRenderer(straight_road(speed_mps=0.0), seed=4)
    pitch = cam.extrinsics.pitch_rad
    r = _two_frames(
        params, cam, render(0.0, pitch)[0], render(FRAME_S, pitch)[0], EgoMotion.still(FRAME_S)
    )
    assert r.mode == "background_subtraction"
    assert not r.obstacles.any()


def test_standstill_is_a_speed_over_the_interval(params: MotionStereoParams) -> None:
    assert params.standstill_speed_mps == STANDSTILL_SPEED_MPS
    blank = np.full((480, 640), 90, dtype=np.uint8)
    slow = 0.5 * STANDSTILL_SPEED_MPS * FRAME_S
    fast = 2.0 * STANDSTILL_SPEED_MPS * FRAME_S
    for dx, mode in ((slow, "background_subtraction"), (fast, "motion_stereo")):
        ms = MotionStereo(params)
        ms.update(blank, camera(), None)
        assert ms.update(blank, camera(), EgoMotion(dx, 0.0, 0.0, FRAME_S)).mode == mode


@pytest.mark.parametrize(
    ("image", "got"),
    [
        (np.zeros((300, 640), dtype=np.uint8), r"got uint8 \(300, 640\)"),
        (np.zeros((480, 640), dtype=np.float32), r"got float32 \(480, 640\)"),
        (np.zeros((480, 640, 3), dtype=np.uint8), r"got uint8 \(480, 640, 3\)"),
        ([[0] * 640] * 480, "got list"),
    ],
)
def test_wrong_image_is_refused_by_name(
    params: MotionStereoParams, cam: CameraModel, image: object, got: str
) -> None:
    with pytest.raises(
        ValueError, match=r"image: expected a \(480, 640\) uint8 grey image.*" + got
    ):
        MotionStereo(params).update(image, cam, None)  # type: ignore[arg-type]


def test_bad_ego_is_refused_by_name(params: MotionStereoParams, cam: CameraModel) -> None:
    blank = np.zeros((480, 640), dtype=np.uint8)
    ms = MotionStereo(params)
    with pytest.raises(ValueError, match="ego: expected an EgoMotion or None, got tuple"):
        ms.update(blank, cam, (1.5, 0.0, 0.0))  # type: ignore[arg-type]
    nan_ego = EgoMotion(1.5, 0.0, 0.0, FRAME_S)
    object.__setattr__(nan_ego, "dyaw_rad", math.nan)  # as if built around the validation
    with pytest.raises(ValueError, match=r"ego\.dyaw_rad: expected a finite number.*nan"):
        ms.update(blank, cam, nan_ego)
    with pytest.raises(ValueError, match="dx_m: expected a finite number"):
        EgoMotion(math.nan, 0.0, 0.0, FRAME_S)


# --- results and state --------------------------------------------------------------------------
def test_results_survive_later_updates(
    params: MotionStereoParams,
    cam: CameraModel,
    box: tuple[tuple[U8, npt.NDArray[np.uint16]], ...],
) -> None:
    (im0, _), (im1, _) = box
    ms = MotionStereo(params)
    ms.update(im0, cam, None)
    r = ms.update(im1, cam, EgoMotion(1.5, 0.0, 0.0, FRAME_S))
    names = [
        "bird_eye",
        "background",
        "difference",
        "local_mean",
        "obstacles",
        "valid",
        "next_background",
        "image_mask",
    ]
    kept = {n: getattr(r, n).copy() for n in names}
    ms.update(im0, cam, EgoMotion(-1.5, 0.0, 0.0, FRAME_S))
    ms.update(im1, cam, EgoMotion(1.5, 0.0, 0.0, FRAME_S))
    for n in names:
        arr = getattr(r, n)
        assert arr.dtype == np.uint8 and not arr.flags.writeable, n
        np.testing.assert_array_equal(arr, kept[n], err_msg=n)


def test_frames_to_forget() -> None:
    # 255 * 0.75^22 = 0.44 < 0.5 <= 255 * 0.75^21 = 0.59
    assert frames_to_forget(MotionStereoParams()) == 22
    assert frames_to_forget(MotionStereoParams(weight_obstacle=1.0)) == 1
    assert frames_to_forget(MotionStereoParams(weight_obstacle=0.0)) is None
    assert frames_to_forget(MotionStereoParams(weight_obstacle=0.5)) == 9  # 255 / 2^9 < 0.5


@pytest.fixture(scope="module")
def highway_run() -> tuple[Drive, list[CameraModel], list[MotionStereoResult]]:
    """The first frames of the bundled highway drive, with each frame's true pitch."""
    drive = Drive(BUNDLED / "highway")
    cams = [drive.camera.with_pitch(drive.truth(i).pitch_rad) for i in range(REPLAY_AT + 1)]
    ms = MotionStereo(MotionStereoParams())
    run = [ms.update(drive.frame(i).image, cams[i], drive.frame(i).ego) for i in range(len(cams))]
    return drive, cams, run


REPLAY_AT = 40


def _replayed(drive: Drive, cams: list[CameraModel], frames_before: int) -> MotionStereoResult:
    ms = MotionStereo(MotionStereoParams())
    start = REPLAY_AT - frames_before
    result = ms.update(drive.frame(start).image, cams[start], None)
    for i in range(start + 1, REPLAY_AT + 1):
        result = ms.update(drive.frame(i).image, cams[i], drive.frame(i).ego)
    return result


def test_seek_by_replaying_the_frames_the_background_remembers(
    highway_run: tuple[Drive, list[CameraModel], list[MotionStereoResult]],
) -> None:
    # An obstacle cell keeps 0.75 of its background per frame: after frames_to_forget (22)
    # frames the state before them weighs under half a grey level. One frame is not enough,
    # which shows the background does remember.
    drive, cams, run = highway_run
    full = run[REPLAY_AT]
    assert full.mode == "motion_stereo" and full.obstacles.any()

    def agreement(frames_before: int) -> float:
        replay = _replayed(drive, cams, frames_before)
        seen = (full.valid > 0) | (replay.valid > 0)
        return float(((full.obstacles > 0) == (replay.obstacles > 0))[seen].mean())

    assert agreement(frames_to_forget(MotionStereoParams()) or 0) >= 0.99
    assert agreement(1) < 0.95


RESTORE_AFTER = 20  # the highway frame whose state is kept and taken up again


def test_a_restored_state_gives_the_updates_that_followed_it(
    highway_run: tuple[Drive, list[CameraModel], list[MotionStereoResult]],
) -> None:
    drive, cams, run = highway_run
    ms = MotionStereo(MotionStereoParams())
    for i in range(RESTORE_AFTER + 1):
        ms.update(drive.frame(i).image, cams[i], drive.frame(i).ego)
    kept = ms.state()
    assert kept.background is not None and not kept.background.flags.writeable
    following = range(RESTORE_AFTER + 1, REPLAY_AT + 1)
    for i in following:  # the background moves on; the kept state does not
        ms.update(drive.frame(i).image, cams[i], drive.frame(i).ego)
    for taker in (MotionStereo(MotionStereoParams()), ms):
        taker.restore(kept)
        for i in following:
            r = taker.update(drive.frame(i).image, cams[i], drive.frame(i).ego)
            assert r.mode == run[i].mode == "motion_stereo"
            for name in ("background", "valid", "obstacles", "next_background", "image_mask"):
                np.testing.assert_array_equal(getattr(r, name), getattr(run[i], name), name)
    assert run[REPLAY_AT].obstacles.any()  # the frames compared have obstacles to get wrong


def test_the_state_before_a_first_frame_restores_a_first_frame(
    params: MotionStereoParams,
    cam: CameraModel,
    box: tuple[tuple[U8, npt.NDArray[np.uint16]], ...],
) -> None:
    (im0, _), (im1, _) = box
    ms = MotionStereo(params)
    empty = ms.state()
    assert empty.background is None and empty.background_poly == ()
    ms.update(im0, cam, None)
    ms.restore(empty)
    assert not ms.has_background
    assert ms.update(im1, cam, EgoMotion(1.5, 0.0, 0.0, FRAME_S)).mode == "first_frame"


def test_a_wrong_background_is_refused_by_name(
    params: MotionStereoParams,
    cam: CameraModel,
    box: tuple[tuple[U8, npt.NDArray[np.uint16]], ...],
) -> None:
    (im0, _), _ = box
    ms = MotionStereo(params)
    ms.update(im0, cam, None)
    kept = ms.state()
    assert kept.background is not None
    shape = grid_for(params).shape
    writeable = kept.background.copy()
    smaller = np.zeros((shape[0] - 1, shape[1]), dtype=np.uint8)
    smaller.flags.writeable = False
    for bad, got in ((writeable, "got a writeable uint8"), (smaller, rf"\({shape[0] - 1}, ")):
        with pytest.raises(ValueError, match=rf"state\.background: expected a read-only.*{got}"):
            ms.restore(replace(kept, background=bad))


def test_image_mask_is_d_reprojected(
    highway_run: tuple[Drive, list[CameraModel], list[MotionStereoResult]],
) -> None:
    _, cams, run = highway_run
    r, cam = run[REPLAY_AT], cams[REPLAY_AT]
    first, stop = cam.row_window_px
    assert r.image_mask_first_row_px == first
    full = cam.warp_from_grid(r.obstacles, r.grid)
    np.testing.assert_array_equal(r.image_mask, full[first:stop])
    assert not full[:first].any() and not full[stop:].any()
    assert r.image_mask.any()


def test_grid_follows_the_parameters(cam: CameraModel) -> None:
    p = replace(MotionStereoParams(), x_max_m=30.0, y_half_width_m=5.0, cell_m=0.2)
    r = MotionStereo(p).update(np.zeros((480, 640), dtype=np.uint8), cam, None)
    assert r.grid == BirdEyeGrid(4.0, 30.0, -5.0, 5.0, 0.2)
    assert r.bird_eye.shape == r.obstacles.shape == r.valid.shape == (130, 50)
