"""Pinhole camera on a car: vehicle-frame points <-> image pixels, the road plane, the
bird's-eye grid.

Frames (the README has the table):

- vehicle: x forward, y left, z up, metres; origin on the road under the reference point.
- camera: OpenCV optical frame, x right, y down, z along the optical axis, metres.
- image: (u, v) pixels, u = column to the right, v = row down, origin at the top-left
  corner of the top-left pixel's centre (OpenCV convention: pixel (0, 0) is centred at 0.0).
- bird's-eye grid: (col, row) cells; row 0 is the farthest x (ahead is up), col 0 the
  leftmost y, cell (c, r) centred at x = x_max_m - (r + 0.5) * cell_m,
  y = y_max_m - (c + 0.5) * cell_m.

Orientation: R_vehicle_camera = Rz(yaw) @ Ry(pitch) @ Rx(roll) @ R_vehicle_optical, with
pitch_rad > 0 when the optical axis tilts down towards the road (the horizon then rises
above the principal point: v_horizon = cy - fy * tan(pitch), as in paper 000 eq. 2).

Notes:
    Homographies and the road-plane functions work on undistorted pixels; `undistort_px`
    and `distort_px` convert when the intrinsics carry lens distortion.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import cv2
import numpy as np
import numpy.typing as npt

from core.checks import require_finite

FloatArray = npt.NDArray[np.float64]

# Optical frame axes expressed in the vehicle frame: camera z (optical axis) -> vehicle x,
# camera x (right) -> vehicle -y, camera y (down) -> vehicle -z.
R_VEHICLE_OPTICAL = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])

# A ray must point below the horizon by at least this much to meet the road ahead.
MIN_RAY_DESCENT = 1e-9

# cv2.undistortPoints stops after 5 fixed-point iterations by default, which leaves errors of
# ~1e-3 px for k1 = -0.3 near the image edge; iterate to convergence instead.
UNDISTORT_CRITERIA = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 100, 1e-12)


def _rot_x(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _as_points(name: str, pts: npt.ArrayLike, dim: int) -> FloatArray:
    arr = np.asarray(pts, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == dim:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != dim:
        raise ValueError(f"{name}: expected an array of shape (N, {dim}), got {arr.shape}")
    return arr


@dataclass(frozen=True)
class Intrinsics:
    """Pinhole intrinsics in pixels, ROS camera_info style, with optional OpenCV distortion.

    `distortion` is OpenCV's (k1, k2, p1, p2[, k3[, k4, k5, k6]]); empty means none.
    """

    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    width_px: int
    height_px: int
    distortion: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        for name in ("fx_px", "fy_px", "cx_px", "cy_px"):
            require_finite(name, getattr(self, name))
        if self.fx_px <= 0 or self.fy_px <= 0:
            raise ValueError(
                f"fx_px, fy_px: expected focal lengths > 0, got {self.fx_px}, {self.fy_px}"
            )
        if self.width_px <= 0 or self.height_px <= 0:
            raise ValueError(
                f"width_px, height_px: expected an image size > 0, "
                f"got {self.width_px}x{self.height_px}"
            )
        if len(self.distortion) not in (0, 4, 5, 8):
            raise ValueError(
                f"distortion: expected 0, 4, 5 or 8 OpenCV coefficients, got {len(self.distortion)}"
            )

    @property
    def K(self) -> FloatArray:  # noqa: N802 (frame-naming convention, STYLE 6)
        """(3, 3) camera matrix."""
        return np.array(
            [[self.fx_px, 0.0, self.cx_px], [0.0, self.fy_px, self.cy_px], [0.0, 0.0, 1.0]]
        )

    @property
    def horizontal_fov_rad(self) -> float:
        return 2.0 * math.atan2(self.width_px / 2.0, self.fx_px)

    @property
    def vertical_fov_rad(self) -> float:
        return 2.0 * math.atan2(self.height_px / 2.0, self.fy_px)

    @classmethod
    def from_fov(cls, width_px: int, height_px: int, horizontal_fov_rad: float) -> Intrinsics:
        """Square pixels, principal point at the image centre."""
        if not 0.0 < horizontal_fov_rad < math.pi:
            raise ValueError(
                f"horizontal_fov_rad: expected 0 < fov < pi, got {horizontal_fov_rad!r}"
            )
        f = (width_px / 2.0) / math.tan(horizontal_fov_rad / 2.0)
        return cls(f, f, (width_px - 1) / 2.0, (height_px - 1) / 2.0, width_px, height_px)


@dataclass(frozen=True)
class Extrinsics:
    """Camera pose in the vehicle frame: optical centre position and yaw/pitch/roll."""

    height_m: float
    x_m: float = 0.0
    y_m: float = 0.0
    pitch_rad: float = 0.0
    yaw_rad: float = 0.0
    roll_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("height_m", "x_m", "y_m", "pitch_rad", "yaw_rad", "roll_rad"):
            require_finite(name, getattr(self, name))
        if self.height_m <= 0:
            raise ValueError(
                f"height_m: expected a camera above the road (> 0), got {self.height_m}"
            )
        for name in ("pitch_rad", "yaw_rad", "roll_rad"):
            if abs(getattr(self, name)) >= math.pi / 2:
                raise ValueError(f"{name}: expected |angle| < pi/2, got {getattr(self, name)}")


@dataclass(frozen=True)
class BirdEyeGrid:
    """A metric grid on the road plane in the vehicle frame (inverse perspective mapping).

    x in [x_min_m, x_max_m] ahead, y in [y_min_m, y_max_m] sideways (left positive),
    `cell_m` metres per cell. Rows run from far (row 0) to near, columns from left to right,
    so the grid reads like a map with the car at the bottom.
    """

    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float
    cell_m: float

    def __post_init__(self) -> None:
        for name in ("x_min_m", "x_max_m", "y_min_m", "y_max_m", "cell_m"):
            require_finite(name, getattr(self, name))
        if self.cell_m <= 0:
            raise ValueError(f"cell_m: expected > 0, got {self.cell_m}")
        if self.x_max_m <= self.x_min_m:
            raise ValueError(f"x_max_m: expected > x_min_m={self.x_min_m}, got {self.x_max_m}")
        if self.y_max_m <= self.y_min_m:
            raise ValueError(f"y_max_m: expected > y_min_m={self.y_min_m}, got {self.y_max_m}")

    @property
    def shape(self) -> tuple[int, int]:
        """(rows, cols) of the grid image."""
        rows = round((self.x_max_m - self.x_min_m) / self.cell_m)
        cols = round((self.y_max_m - self.y_min_m) / self.cell_m)
        return rows, cols

    @property
    def T_grid_ground(self) -> FloatArray:  # noqa: N802 (frame-naming convention, STYLE 6)
        """(3, 3) map from road-plane (x_m, y_m, 1) to grid (col, row, 1)."""
        s = 1.0 / self.cell_m
        return np.array(
            [
                [0.0, -s, self.y_max_m * s - 0.5],
                [-s, 0.0, self.x_max_m * s - 0.5],
                [0.0, 0.0, 1.0],
            ]
        )

    def ground_from_cells(self, cells: npt.ArrayLike) -> FloatArray:
        """(N, 2) grid (col, row) -> (N, 2) road-plane (x_m, y_m)."""
        c = _as_points("cells", cells, 2)
        x = self.x_max_m - (c[:, 1] + 0.5) * self.cell_m
        y = self.y_max_m - (c[:, 0] + 0.5) * self.cell_m
        return np.stack([x, y], axis=1)

    def cells_from_ground(self, pts_ground_m: npt.ArrayLike) -> FloatArray:
        """(N, 2) road-plane (x_m, y_m) -> (N, 2) fractional grid (col, row)."""
        p = _as_points("pts_ground_m", pts_ground_m, 2)
        col = (self.y_max_m - p[:, 1]) / self.cell_m - 0.5
        row = (self.x_max_m - p[:, 0]) / self.cell_m - 0.5
        return np.stack([col, row], axis=1)


@dataclass(frozen=True)
class CameraModel:
    """Intrinsics, extrinsics and the image rows the engine processes.

    `rows_used_px` = (first, stop) rows of the full image the stages work on (the papers use
    640x300 of 640x480; None: all rows); every coordinate stays in full-image pixels.
    """

    intrinsics: Intrinsics
    extrinsics: Extrinsics
    rows_used_px: tuple[int, int] | None = None

    def __post_init__(self) -> None:
        if self.rows_used_px is not None and len(self.rows_used_px) != 2:
            raise ValueError(
                f"rows_used_px: expected (first, stop) or None, got {self.rows_used_px!r}"
            )
        first, stop = self.row_window_px
        if not 0 <= first < stop <= self.intrinsics.height_px:
            raise ValueError(
                f"rows_used_px: expected 0 <= first < stop <= {self.intrinsics.height_px}, "
                f"got {self.rows_used_px}"
            )

    @property
    def row_window_px(self) -> tuple[int, int]:
        """(first, stop) image rows the engine processes."""
        if self.rows_used_px is None:
            return 0, self.intrinsics.height_px
        return self.rows_used_px

    def check_image(self, image: object) -> None:
        """ValueError naming `image` unless it is an (H, W) uint8 grey image of this camera."""
        i = self.intrinsics
        expected = f"a ({i.height_px}, {i.width_px}) uint8 grey image (the camera's intrinsics)"
        if not isinstance(image, np.ndarray):
            raise ValueError(f"image: expected {expected}, got {type(image).__name__}")
        if image.dtype != np.uint8 or image.shape != (i.height_px, i.width_px):
            raise ValueError(f"image: expected {expected}, got {image.dtype} {image.shape}")

    # --- pose ---------------------------------------------------------------------------
    def with_pitch(self, pitch_rad: float) -> CameraModel:
        """The same camera with the pitch replaced (the engine feeds each frame's detected
        pitch)."""
        return replace(self, extrinsics=replace(self.extrinsics, pitch_rad=pitch_rad))

    @functools.cached_property
    def R_vehicle_camera(self) -> FloatArray:  # noqa: N802 (frame-naming convention, STYLE 6)
        """(3, 3) rotates camera-frame directions into the vehicle frame (read-only, computed
        once per model: every projection uses it)."""
        e = self.extrinsics
        R = _rot_z(e.yaw_rad) @ _rot_y(e.pitch_rad) @ _rot_x(e.roll_rad) @ R_VEHICLE_OPTICAL
        R.flags.writeable = False
        return R

    @property
    def position_vehicle_m(self) -> FloatArray:
        e = self.extrinsics
        return np.array([e.x_m, e.y_m, e.height_m])

    @property
    def T_vehicle_camera(self) -> FloatArray:  # noqa: N802 (frame-naming convention, STYLE 6)
        """(4, 4) maps camera-frame points into the vehicle frame."""
        T = np.eye(4)
        T[:3, :3] = self.R_vehicle_camera
        T[:3, 3] = self.position_vehicle_m
        return T

    @functools.cached_property
    def T_camera_vehicle(self) -> FloatArray:  # noqa: N802 (frame-naming convention, STYLE 6)
        """(4, 4) maps vehicle-frame points into the camera frame (read-only, computed once)."""
        R = self.R_vehicle_camera
        T = np.eye(4)
        T[:3, :3] = R.T
        T[:3, 3] = -R.T @ self.position_vehicle_m
        T.flags.writeable = False
        return T

    # --- lens ---------------------------------------------------------------------------
    def undistort_px(self, pts_img_px: npt.ArrayLike) -> FloatArray:
        """(N, 2) distorted pixels -> (N, 2) ideal pinhole pixels."""
        p = _as_points("pts_img_px", pts_img_px, 2)
        if not self.intrinsics.distortion or len(p) == 0:
            return p
        K = self.intrinsics.K
        out = cv2.undistortPoints(
            p.reshape(-1, 1, 2),
            K,
            np.asarray(self.intrinsics.distortion),
            P=K,
            criteria=UNDISTORT_CRITERIA,
        )
        return np.asarray(out, dtype=np.float64).reshape(-1, 2)

    def distort_px(self, pts_img_px: npt.ArrayLike) -> FloatArray:
        """(N, 2) ideal pinhole pixels -> (N, 2) pixels as the lens images them."""
        p = _as_points("pts_img_px", pts_img_px, 2)
        if not self.intrinsics.distortion or len(p) == 0:
            return p
        i = self.intrinsics
        norm = np.stack(
            [(p[:, 0] - i.cx_px) / i.fx_px, (p[:, 1] - i.cy_px) / i.fy_px, np.ones(len(p))], axis=1
        )
        out, _ = cv2.projectPoints(norm, np.zeros(3), np.zeros(3), i.K, np.asarray(i.distortion))
        return np.asarray(out, dtype=np.float64).reshape(-1, 2)

    # --- projection ---------------------------------------------------------------------
    def project(self, pts_vehicle_m: npt.ArrayLike) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
        """(N, 3) vehicle-frame points -> ((N, 2) pixels (u, v), (N,) in front of the camera).

        Pixels of points behind the camera are NaN. Distortion is applied when present.
        """
        p = _as_points("pts_vehicle_m", pts_vehicle_m, 3)
        T = self.T_camera_vehicle
        pc = p @ T[:3, :3].T + T[:3, 3]
        in_front = pc[:, 2] > 0
        z = np.where(in_front, pc[:, 2], np.nan)
        i = self.intrinsics
        uv = pc[:, :2] / z[:, None] * (i.fx_px, i.fy_px) + (i.cx_px, i.cy_px)
        if i.distortion and in_front.any():
            uv[in_front] = self.distort_px(uv[in_front])
        return uv, in_front

    def rays_vehicle(self, pts_img_px: npt.ArrayLike) -> FloatArray:
        """(N, 2) pixels -> (N, 3) unit ray directions in the vehicle frame."""
        p = self.undistort_px(pts_img_px)
        i = self.intrinsics
        d_cam = np.ones((len(p), 3))
        d_cam[:, :2] = (p - (i.cx_px, i.cy_px)) / (i.fx_px, i.fy_px)
        d = d_cam @ self.R_vehicle_camera.T
        return d / np.sqrt((d * d).sum(axis=1, keepdims=True))

    def point_at_height(self, pts_img_px: npt.ArrayLike, z_m: float | npt.ArrayLike) -> FloatArray:
        """(N, 2) pixels -> (N, 3) vehicle-frame points where their rays cross the plane z = z_m.

        Rows are NaN where the ray never reaches that plane in front of the camera (for the
        road, z_m = 0: at or above the horizon).
        """
        d = self.rays_vehicle(pts_img_px)
        c = self.position_vehicle_m
        z = np.broadcast_to(np.asarray(z_m, dtype=np.float64), (len(d),))
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # t: see ok
            t = (z - c[2]) / d[:, 2]
        ok = np.isfinite(t) & (t > 0) & (np.abs(d[:, 2]) > MIN_RAY_DESCENT)
        out = c[None, :] + np.where(ok, t, 0.0)[:, None] * d
        out[~ok] = np.nan
        return out

    def ground_point(self, pts_img_px: npt.ArrayLike) -> FloatArray:
        """(N, 2) pixels -> (N, 3) points on the road plane z = 0 (NaN at or above the horizon)."""
        return self.point_at_height(pts_img_px, 0.0)

    # --- horizon ------------------------------------------------------------------------
    def horizon_row_px(self, u_px: float | None = None) -> float:
        """Row of the road plane's vanishing line at column `u_px` (default: the principal point).

        Ideal pinhole pixels (the horizon is a straight line only without distortion).
        """
        i = self.intrinsics
        u = i.cx_px if u_px is None else u_px
        n_cam = self.R_vehicle_camera.T @ np.array([0.0, 0.0, 1.0])
        line = np.linalg.inv(i.K).T @ n_cam  # l . (u, v, 1) = 0
        if abs(line[1]) < 1e-12:
            raise ValueError("horizon_row_px: the camera is rolled 90 deg, the horizon is vertical")
        return float(-(line[0] * u + line[2]) / line[1])

    @functools.cached_property
    def ahead_px(self) -> tuple[float, float]:
        """(u, v) ideal pixels of the vanishing point of the car's axis, where the image of a
        point straight ahead goes as it recedes (computed once per model). ValueError when
        the camera does not look ahead."""
        d_cam = self.R_vehicle_camera.T @ np.array([1.0, 0.0, 0.0])
        if not d_cam[2] > 1e-12:
            raise ValueError("ahead_px: the camera looks away from the car's axis")
        u, v, w = self.intrinsics.K @ d_cam
        return float(u / w), float(v / w)

    def pitch_from_horizon_row(self, v_px: float) -> float:
        """Pitch (rad) that puts the horizon at row `v_px` (roll = 0), paper 000 eq. 2 with
        v0 = cy."""
        i = self.intrinsics
        return math.atan2(i.cy_px - v_px, i.fy_px)

    # --- bird's-eye view ----------------------------------------------------------------
    @property
    def H_image_ground(self) -> FloatArray:  # noqa: N802 (frame-naming convention, STYLE 6)
        """(3, 3) map from road-plane (x_m, y_m, 1) to ideal image pixels (u, v, 1)."""
        T = self.T_camera_vehicle
        M = np.column_stack([T[:3, 0], T[:3, 1], T[:3, 3]])
        return self.intrinsics.K @ M

    def H_image_grid(self, grid: BirdEyeGrid) -> FloatArray:  # noqa: N802
        """(3, 3) map from grid (col, row, 1) to ideal image pixels (u, v, 1)."""
        return self.H_image_ground @ np.linalg.inv(grid.T_grid_ground)

    def H_grid_image(self, grid: BirdEyeGrid) -> FloatArray:  # noqa: N802
        """(3, 3) map from ideal image pixels (u, v, 1) to grid (col, row, 1)."""
        return np.asarray(np.linalg.inv(self.H_image_grid(grid)), dtype=np.float64)

    def grid_cells_visible(self, grid: BirdEyeGrid) -> npt.NDArray[np.bool_]:
        """(rows, cols) bool: grid cells whose road point is in front of the camera and inside
        the image."""
        rows, cols = grid.shape
        cc, rr = np.meshgrid(np.arange(cols, dtype=np.float64), np.arange(rows, dtype=np.float64))
        ground = grid.ground_from_cells(np.stack([cc.ravel(), rr.ravel()], axis=1))
        pts = np.column_stack([ground, np.zeros(len(ground))])
        uv, front = self.project(pts)
        i = self.intrinsics
        with np.errstate(invalid="ignore"):
            inside = (
                front
                & (uv[:, 0] >= -0.5)
                & (uv[:, 0] <= i.width_px - 0.5)
                & (uv[:, 1] >= -0.5)
                & (uv[:, 1] <= i.height_px - 0.5)
            )
        return inside.reshape(rows, cols)

    def warp_to_grid(
        self, image: npt.NDArray[np.uint8], grid: BirdEyeGrid
    ) -> npt.NDArray[np.uint8]:
        """(H, W) image -> (rows, cols) bird's-eye view, bilinear; cells outside the image are 0.

        Notes:
            Expects an undistorted image when the intrinsics carry distortion.
        """
        rows, cols = grid.shape
        warped = cv2.warpPerspective(
            image,
            self.H_grid_image(grid),
            (cols, rows),
            flags=cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=0,
        )
        return np.asarray(warped, dtype=np.uint8)

    def warp_from_grid(
        self, grid_image: npt.NDArray[np.uint8], grid: BirdEyeGrid
    ) -> npt.NDArray[np.uint8]:
        """(rows, cols) grid image -> (H, W) image, nearest neighbour (for masks)."""
        i = self.intrinsics
        warped = cv2.warpPerspective(
            grid_image,
            self.H_image_grid(grid),
            (i.width_px, i.height_px),
            flags=cv2.INTER_NEAREST,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=0,
        )
        return np.asarray(warped, dtype=np.uint8)
