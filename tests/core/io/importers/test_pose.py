"""core.io.importers.pose: quaternions, yaw and a camera's pose as core.camera.Extrinsics.

Known rotations are written out by hand; the camera pose is checked both on a hand-made
rotation (a camera pitched down) and as a round trip through core.camera.CameraModel.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from core.camera import R_VEHICLE_OPTICAL, CameraModel, Extrinsics, Intrinsics
from core.io.importers.pose import camera_extrinsics, quaternion_matrix, yaw_rad

S = math.sqrt(0.5)  # cos and sin of 45 deg: the half angle of a quarter turn


@pytest.mark.parametrize(
    ("wxyz", "expected"),
    [
        ([1.0, 0.0, 0.0, 0.0], np.eye(3)),
        ([2.0, 0.0, 0.0, 0.0], np.eye(3)),  # normalised first
        ([S, 0.0, 0.0, S], [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),  # z, +90
        ([S, 0.0, S, 0.0], [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]),  # y, +90
        ([0.0, 1.0, 0.0, 0.0], np.diag([1.0, -1.0, -1.0])),  # x, 180
        ([-S, 0.0, 0.0, -S], [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),  # -q = q
        # a turn of 120 deg about (1, 1, 1): x -> y -> z -> x
        ([0.5, 0.5, 0.5, 0.5], [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
    ],
)
def test_quaternion_matrix_of_known_rotations(wxyz: list[float], expected: object) -> None:
    assert quaternion_matrix(wxyz) == pytest.approx(np.asarray(expected), abs=1e-12)


@pytest.mark.parametrize(
    "wxyz", [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0], [1.0, math.nan, 0.0, 0.0], [math.inf, 0, 0, 0]]
)
def test_bad_quaternion(wxyz: list[float]) -> None:
    with pytest.raises(ValueError, match=r"rotation: expected a quaternion \(w, x, y, z\), got \["):
        quaternion_matrix(wxyz)


def test_yaw_of_a_turn_about_z() -> None:
    for yaw in (0.0, 0.3, -1.2, 3.0):
        q = [math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)]
        assert yaw_rad(quaternion_matrix(q)) == pytest.approx(yaw, abs=1e-12)


def test_camera_extrinsics_of_a_camera_pitched_down() -> None:
    # pitched down by p: the optical axis points (cos p, 0, -sin p), the image's right -y,
    # the image's down (z cross x) (-sin p, 0, -cos p); columns of R are these axes
    p = 0.1
    c, s = math.cos(p), math.sin(p)
    R = np.array([[0.0, -s, c], [-1.0, 0.0, 0.0], [0.0, -c, -s]])
    e = camera_extrinsics(R, (1.5, -0.2, 1.2))
    assert (e.x_m, e.y_m, e.height_m) == pytest.approx((1.5, -0.2, 1.2))
    assert (e.pitch_rad, e.yaw_rad, e.roll_rad) == pytest.approx((p, 0.0, 0.0), abs=1e-12)
    level = camera_extrinsics(R_VEHICLE_OPTICAL, (0.0, 0.0, 1.0))
    assert (level.pitch_rad, level.yaw_rad, level.roll_rad) == (0.0, 0.0, 0.0)


@settings(max_examples=200, deadline=None)
@given(
    pitch=st.floats(-0.4, 0.4),
    yaw=st.floats(-0.4, 0.4),
    roll=st.floats(-0.4, 0.4),
    x=st.floats(-2.0, 4.0),
    y=st.floats(-1.0, 1.0),
    height=st.floats(0.3, 3.0),
)
def test_camera_extrinsics_undoes_core_camera(
    pitch: float, yaw: float, roll: float, x: float, y: float, height: float
) -> None:
    built = Extrinsics(height_m=height, x_m=x, y_m=y, pitch_rad=pitch, yaw_rad=yaw, roll_rad=roll)
    camera = CameraModel(Intrinsics(800.0, 800.0, 320.0, 240.0, 640, 480), built)
    back = camera_extrinsics(camera.R_vehicle_camera, camera.position_vehicle_m)
    got = (back.pitch_rad, back.yaw_rad, back.roll_rad, back.x_m, back.y_m, back.height_m)
    assert got == pytest.approx((pitch, yaw, roll, x, y, height), abs=1e-9)


def test_camera_looking_backwards_is_refused() -> None:
    behind = np.diag([-1.0, -1.0, 1.0]) @ R_VEHICLE_OPTICAL  # turned half round about z
    with pytest.raises(ValueError, match=r"yaw_rad: expected \|angle\| < pi/2, got 3.14"):
        camera_extrinsics(behind, (0.0, 0.0, 1.2))
