"""Ground truth from a data set's 3D boxes: what `groundtruth.json` holds, per labelled frame.

A labelled 3D box (centre, size, yaw in the vehicle frame of the camera's time) becomes a
`TruthObject` as the evaluation reads it:

- box_px: the visible 2D box, the extent of the box's projected edges (sampled along each
  of its 12 edges, the parts in front of the camera's near plane), clipped to the image;
  a box with no edge in front of the camera or none in the image is not in the frame.
- position_m: the centre of the footprint's side facing the ego car (of its four side
  centres the one nearest the reference point), on the road (z = 0).
- size_m: (length, width, height) as labelled.
- velocity_mps: over ground, vehicle-frame axes, as the data set gives it.
- occlusion: the larger of the labelled hidden fraction and the part of the full
  projected box outside the image (truncation).
- radar_seen: a radar point of the frame lies on the footprint, grown by RADAR_MARGIN_M.

The camera must be the pinhole of the written images (undistorted): boxes are projected
without lens distortion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.groundtruth import TruthObject

FloatArray = npt.NDArray[np.float64]

NEAR_PLANE_M = 0.5  # edge points nearer the camera than this (along its axis) are not drawn
EDGE_SAMPLES = 24  # points per box edge
RADAR_MARGIN_M = 0.5  # a radar point this close to a footprint lies on it (the evaluation's)
# corner signs (length, width, height) of the 12 edges, as pairs of corner indices
_CORNER_SIGNS = np.array(
    [[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)], dtype=np.float64
)
_EDGES = [
    (a, b)
    for a in range(8)
    for b in range(a + 1, 8)
    if np.count_nonzero(_CORNER_SIGNS[a] != _CORNER_SIGNS[b]) == 1
]


@dataclass(frozen=True)
class Box3D:
    """One labelled object at the camera's time, in the vehicle frame (x forward, y left, z up,
    on the road under the reference point).

    centre_m: (x, y, z) of the box's centre; size_m: (length, width, height); yaw_rad: the
    heading of its length axis, left positive; velocity_mps: (vx, vy) over ground; hidden:
    the labelled hidden fraction in [0, 1]; cls: the evaluation's class
    (core.io.groundtruth.OBJECT_CLASSES).
    """

    id: int
    cls: str
    centre_m: tuple[float, float, float]
    size_m: tuple[float, float, float]
    yaw_rad: float
    velocity_mps: tuple[float, float]
    hidden: float

    def __post_init__(self) -> None:
        values = (*self.centre_m, *self.size_m, self.yaw_rad, *self.velocity_mps, self.hidden)
        if not all(math.isfinite(v) for v in values):
            raise ValueError(f"object {self.id}: expected finite numbers, got {values}")
        if min(self.size_m) <= 0:
            raise ValueError(f"object {self.id}: size_m: expected > 0, got {self.size_m}")

    def corners_m(self) -> FloatArray:
        """(8, 3) corners in the vehicle frame."""
        half = np.asarray(self.size_m) / 2
        local = _CORNER_SIGNS * half
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        out: FloatArray = local @ R.T + np.asarray(self.centre_m)
        return out

    def near_face_m(self) -> tuple[float, float]:
        """(x, y) of the centre of the footprint's side facing the reference point."""
        length, width, _ = self.size_m
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        ax, ay = np.array([c, s]) * length / 2, np.array([-s, c]) * width / 2
        centre = np.asarray(self.centre_m[:2])
        faces = np.array([centre - ax, centre + ax, centre - ay, centre + ay])
        near = faces[int(np.argmin(np.hypot(faces[:, 0], faces[:, 1])))]
        return float(near[0]), float(near[1])

    def contains_xy(self, pts_xy_m: npt.ArrayLike, margin_m: float) -> npt.NDArray[np.bool_]:
        """(N,) which of the (N, 2) points lie on the footprint grown by `margin_m`."""
        p = np.asarray(pts_xy_m, dtype=np.float64).reshape(-1, 2) - np.asarray(self.centre_m[:2])
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        along, across = p @ np.array([c, s]), p @ np.array([-s, c])
        length, width, _ = self.size_m
        inside: npt.NDArray[np.bool_] = (np.abs(along) <= length / 2 + margin_m) & (
            np.abs(across) <= width / 2 + margin_m
        )
        return inside


def _edge_points_m(box: Box3D) -> FloatArray:
    """(12 * EDGE_SAMPLES, 3) points along the box's edges."""
    corners = box.corners_m()
    t = np.linspace(0.0, 1.0, EDGE_SAMPLES)[:, None]
    return np.concatenate([corners[a] + t * (corners[b] - corners[a]) for a, b in _EDGES])


def image_box_px(
    camera: CameraModel, box: Box3D
) -> tuple[tuple[float, float, float, float], float] | None:
    """The visible box (u0, v0, u1, v1) in continuous pixel coordinates (edges of the pixels,
    as core.io.groundtruth), and the fraction of the full projected box outside the image;
    None when no part of the box is both in front of the camera and in the image."""
    pts = _edge_points_m(box)
    T = camera.T_camera_vehicle
    depth = pts @ T[2, :3] + T[2, 3]
    pts = pts[depth > NEAR_PLANE_M]
    if len(pts) == 0:
        return None
    uv, _ = camera.project(pts)
    i = camera.intrinsics
    u0, v0 = uv.min(axis=0) - 0.5
    u1, v1 = uv.max(axis=0) + 0.5
    full = (u1 - u0) * (v1 - v0)
    cu0, cv0 = max(u0, -0.5), max(v0, -0.5)
    cu1, cv1 = min(u1, i.width_px - 0.5), min(v1, i.height_px - 0.5)
    if cu1 <= cu0 or cv1 <= cv0 or full <= 0:
        return None
    outside = 1.0 - (cu1 - cu0) * (cv1 - cv0) / full
    return (float(cu0), float(cv0), float(cu1), float(cv1)), float(outside)


def truth_object(camera: CameraModel, box: Box3D, radar_xy_m: npt.ArrayLike) -> TruthObject | None:
    """`box` as the evaluation's truth (module docstring); None when it is not in the image.

    radar_xy_m: (N, 2) the frame's radar points in the vehicle frame.
    """
    seen = image_box_px(camera, box)
    if seen is None:
        return None
    box_px, outside = seen
    x, y = box.near_face_m()
    on = box.contains_xy(radar_xy_m, RADAR_MARGIN_M)
    return TruthObject(
        id=box.id,
        cls=box.cls,
        box_px=box_px,
        position_m=(x, y, 0.0),
        size_m=box.size_m,
        velocity_mps=box.velocity_mps,
        radar_seen=bool(on.any()),
        occlusion=min(1.0, max(box.hidden, outside)),
    )
