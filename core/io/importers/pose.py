"""Rotations of the data sets' calibrations: quaternions, yaw, and a camera's pose as
`core.camera.Extrinsics`."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from core.camera import R_VEHICLE_OPTICAL, Extrinsics

FloatArray = npt.NDArray[np.float64]


def quaternion_matrix(wxyz: Sequence[float]) -> FloatArray:
    """(3, 3) rotation of the unit quaternion (w, x, y, z), normalised first; ValueError when
    it is not four finite numbers with a length."""
    q = np.asarray(wxyz, dtype=np.float64).ravel()
    norm = float(np.linalg.norm(q)) if q.size == 4 else math.nan
    if not (math.isfinite(norm) and norm > 1e-9):
        raise ValueError(f"rotation: expected a quaternion (w, x, y, z), got {list(wxyz)}")
    w, x, y, z = q / norm
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def yaw_rad(R: FloatArray) -> float:
    """Heading (rad, left positive) of the x axis of rotation `R` (3, 3)."""
    return math.atan2(float(R[1, 0]), float(R[0, 0]))


def camera_extrinsics(R_vehicle_optical: FloatArray, position_m: npt.ArrayLike) -> Extrinsics:
    """`Extrinsics` of a camera whose OpenCV optical frame (x right, y down, z ahead) is
    rotated by `R_vehicle_optical` (3, 3) into the vehicle frame and sits at `position_m`
    (x, y, z; z its height above the road).

    core.camera builds R_vehicle_camera = Rz(yaw) Ry(pitch) Rx(roll) R_VEHICLE_OPTICAL; this
    undoes it (Z-Y-X angles of R R_VEHICLE_OPTICAL^T), pitch positive down.
    """
    M = np.asarray(R_vehicle_optical, dtype=np.float64) @ R_VEHICLE_OPTICAL.T
    pitch = math.asin(max(-1.0, min(1.0, -float(M[2, 0]))))
    yaw = math.atan2(float(M[1, 0]), float(M[0, 0]))
    roll = math.atan2(float(M[2, 1]), float(M[2, 2]))
    x, y, z = (float(v) for v in np.asarray(position_m, dtype=np.float64).ravel())
    return Extrinsics(height_m=z, x_m=x, y_m=y, pitch_rad=pitch, yaw_rad=yaw, roll_rad=roll)
