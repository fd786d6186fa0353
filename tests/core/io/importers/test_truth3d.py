"""core.io.importers.truth3d: 3D boxes -> the evaluation's truth, on a level pinhole camera.

The camera sits at the vehicle frame's origin, 1.5 m above the road, looking straight ahead
(fx = fy = 500 px, principal point at the centre of a 640x480 image). A vehicle-frame point
(x, y, z) then lands at u = cx - fx y / x, v = cy + fy (1.5 - z) / x: every expected box below
is worked out from that. A yaw-0 box's extremes are its corners (each edge is sampled at its
ends), and the visible box extends half a pixel beyond the extreme pixel centres.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.io.importers.truth3d import RADAR_MARGIN_M, Box3D, image_box_px, truth_object

F_PX, CX_PX, CY_PX = 500.0, 319.5, 239.5
WIDTH_PX, HEIGHT_PX = 640, 480
CAMERA_HEIGHT_M = 1.5
CAMERA = CameraModel(
    Intrinsics(F_PX, F_PX, CX_PX, CY_PX, WIDTH_PX, HEIGHT_PX), Extrinsics(height_m=CAMERA_HEIGHT_M)
)


def _box(
    centre: tuple[float, float, float],
    size: tuple[float, float, float] = (4.0, 2.0, 2.0),
    yaw: float = 0.0,
    hidden: float = 0.0,
) -> Box3D:
    return Box3D(7, "car", centre, size, yaw, (1.0, 0.0), hidden)


def _u(x: float, y: float) -> float:
    return CX_PX - F_PX * y / x


def _v(x: float, z: float) -> float:
    return CY_PX + F_PX * (CAMERA_HEIGHT_M - z) / x


# --- Box3D ---------------------------------------------------------------------------------
def test_corners_of_a_box_turned_a_quarter_left() -> None:
    # length 4 along y after the turn, width 2 along x
    box = _box((20.0, 3.0, 1.0), (4.0, 2.0, 2.0), yaw=math.pi / 2)
    expected = {(x, y, z) for x in (19.0, 21.0) for y in (1.0, 5.0) for z in (0.0, 2.0)}
    got = {tuple(round(float(c), 9) for c in corner) for corner in box.corners_m()}
    assert got == expected


def test_near_face_is_the_side_facing_the_car() -> None:
    assert _box((20.0, 0.0, 1.0)).near_face_m() == pytest.approx((18.0, 0.0))  # the rear
    assert _box((-20.0, 0.0, 1.0)).near_face_m() == pytest.approx((-18.0, 0.0))  # the front
    # beside the car: its right side (length 4 along x, width 2)
    assert _box((0.0, 10.0, 1.0)).near_face_m() == pytest.approx((0.0, 9.0))
    # turned a quarter: the near face is a long side, half the width nearer
    assert _box((20.0, 0.0, 1.0), yaw=math.pi / 2).near_face_m() == pytest.approx((19.0, 0.0))


def test_contains_xy_with_and_without_margin() -> None:
    box = _box((20.0, 0.0, 1.0), (4.0, 2.0, 2.0), yaw=math.pi / 2)  # x 19-21, y -2-2
    pts = [(20.9, 1.9), (21.2, 0.0), (20.0, 2.4), (20.0, 2.6), (50.0, 0.0)]
    assert box.contains_xy(pts, 0.0).tolist() == [True, False, False, False, False]
    assert box.contains_xy(pts, 0.5).tolist() == [True, True, True, False, False]
    assert box.contains_xy(np.empty((0, 2)), 0.5).tolist() == []


def test_non_finite_or_empty_box_names_the_object() -> None:
    with pytest.raises(ValueError, match=r"object 7: expected finite numbers, got \(nan"):
        _box((math.nan, 0.0, 1.0))
    with pytest.raises(ValueError, match="object 7: expected finite numbers"):
        Box3D(7, "car", (20.0, 0.0, 1.0), (4.0, 2.0, 2.0), 0.0, (math.inf, 0.0), 0.0)
    with pytest.raises(ValueError, match=r"object 7: size_m: expected > 0, got \(4.0, 0.0, 2.0\)"):
        _box((20.0, 0.0, 1.0), (4.0, 0.0, 2.0))


# --- image_box_px --------------------------------------------------------------------------
def test_box_straight_ahead_projects_to_its_near_face() -> None:
    # centre 20 m ahead, 4 long, 2 wide, 2 high: the near face at x = 18 spans the box
    seen = image_box_px(CAMERA, _box((20.0, 0.0, 1.0)))
    assert seen is not None
    box_px, outside = seen
    expected = (
        _u(18.0, 1.0) - 0.5,
        _v(18.0, 2.0) - 0.5,
        _u(18.0, -1.0) + 0.5,
        _v(18.0, 0.0) + 0.5,
    )
    assert box_px == pytest.approx(expected, abs=1e-9)
    assert outside == pytest.approx(0.0, abs=1e-12)


def test_box_behind_the_camera_is_not_in_the_image() -> None:
    assert image_box_px(CAMERA, _box((-10.0, 0.0, 1.0))) is None
    assert truth_object(CAMERA, _box((-10.0, 0.0, 1.0)), [(-8.0, 0.0)]) is None


def test_box_beside_the_image_is_not_in_it() -> None:
    # 5 m ahead, 30 m to the left: in front of the camera, outside its 65 deg view
    assert image_box_px(CAMERA, _box((5.0, 30.0, 1.0))) is None


def test_box_half_outside_is_clipped_and_its_outside_part_measured() -> None:
    # a 2x2x2 box 20 m ahead, 13 m left: u from the near left corners (x 19, y 14) to the
    # far right ones (x 21, y 12), v from the near face's top and bottom
    seen = image_box_px(CAMERA, _box((20.0, 13.0, 1.0), (2.0, 2.0, 2.0)))
    assert seen is not None
    box_px, outside = seen
    u0, u1 = _u(19.0, 14.0) - 0.5, _u(21.0, 12.0) + 0.5
    v0, v1 = _v(19.0, 2.0) - 0.5, _v(19.0, 0.0) + 0.5
    assert u0 < -0.5 < u1
    assert box_px == pytest.approx((-0.5, v0, u1, v1), abs=1e-9)
    assert outside == pytest.approx(1 - (u1 + 0.5) / (u1 - u0), abs=1e-9)  # 0.584
    assert 0.5 < outside < 0.7


# --- truth_object ----------------------------------------------------------------------------
def test_truth_object_radar_seen_within_the_margin_of_the_footprint() -> None:
    box = _box((20.0, 0.0, 1.0), hidden=0.3)
    in_front = 18.0 - RADAR_MARGIN_M + 0.1  # 0.4 m before the rear face
    seen = truth_object(CAMERA, box, [(40.0, 6.0), (in_front, 0.5)])
    assert seen is not None
    assert seen.radar_seen
    assert seen.id == 7 and seen.cls == "car"
    assert seen.position_m == pytest.approx((18.0, 0.0, 0.0))
    assert seen.size_m == (4.0, 2.0, 2.0) and seen.velocity_mps == (1.0, 0.0)
    assert seen.occlusion == pytest.approx(0.3)  # the labelled part: none is outside

    unseen = truth_object(CAMERA, box, [(40.0, 6.0), (18.0 - RADAR_MARGIN_M - 0.1, 0.0)])
    assert unseen is not None and not unseen.radar_seen
    empty = truth_object(CAMERA, box, np.empty((0, 2)))
    assert empty is not None and not empty.radar_seen


def test_truth_object_occlusion_is_the_larger_of_hidden_and_outside() -> None:
    seen = truth_object(CAMERA, _box((20.0, 13.0, 1.0), (2.0, 2.0, 2.0), hidden=0.1), [])
    assert seen is not None
    clipped = image_box_px(CAMERA, _box((20.0, 13.0, 1.0), (2.0, 2.0, 2.0)))
    assert clipped is not None
    assert seen.occlusion == pytest.approx(clipped[1])
    assert seen.box_px == clipped[0]
