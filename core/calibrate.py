"""Camera intrinsics from views of a chessboard, and the ROS camera_info file that holds them.

`calibrate_chessboard` is Zhang's method as OpenCV implements it: the inner corners of the
board are found in each view (`cv2.findChessboardCorners`), refined to sub-pixel accuracy
(`cv2.cornerSubPix`), and one pinhole camera with plumb_bob distortion (k1, k2, p1, p2, k3)
is fitted to all views together (`cv2.calibrateCamera`).

    views = read_views(Path("chessboard/"))            # the only I/O: image files -> grey
    result = calibrate_chessboard(views, Chessboard(9, 6, square_m=0.025))
    save_camera_info(result.intrinsics, Path("camera_info.yaml"), camera_name="front")  # core.io

camera_info YAML (ROS camera_calibration_parsers' layout, written and read by
core/io/calibration.py; `fusionscope import --camera-info` reads it back):

    image_width: 1280
    image_height: 720
    camera_name: front
    camera_matrix: {rows: 3, cols: 3, data: [fx, 0, cx, 0, fy, cy, 0, 0, 1]}
    distortion_model: plumb_bob
    distortion_coefficients: {rows: 1, cols: 5, data: [k1, k2, p1, p2, k3]}
    rectification_matrix: {rows: 3, cols: 3, data: [1, 0, 0, 0, 1, 0, 0, 0, 1]}
    projection_matrix: {rows: 3, cols: 4, data: [fx, 0, cx, 0, 0, fy, cy, 0, 0, 0, 1, 0]}

Notes:
    The projection matrix written is [K | 0], the monocular camera's matrix for the
    distorted image; ROS's own calibrator puts the matrix of the rectified image there.
    Only the camera matrix and the distortion are read back.

    Views whose image size differs from that of most views are skipped, not fatal: two of the
    20 views of the Udacity chessboard set are 1281x721 among 1280x720 ones.
"""

from __future__ import annotations

import math
import re
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import Intrinsics
from core.checks import require_grey_image

FloatArray = npt.NDArray[np.float64]
GreyImage = npt.NDArray[np.uint8]

# Zhang's method needs several views of the plane; with fewer than three the five intrinsics
# and the distortion are not constrained (Zhang 2000, section 3.1).
MIN_VIEWS = 3
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff")


@dataclass(frozen=True)
class Chessboard:
    """A planar chessboard: inner corners per row (`cols`) and per column (`rows`), square edge.

    A 9x6 board has 10x7 squares; the corners lie in the board frame's z = 0 plane.
    """

    cols: int
    rows: int
    square_m: float = 0.025

    def __post_init__(self) -> None:
        if self.cols < 2 or self.rows < 2:
            raise ValueError(
                f"board: expected at least 2x2 inner corners, got {self.cols}x{self.rows}"
            )
        if not (math.isfinite(self.square_m) and self.square_m > 0):
            raise ValueError(f"square_m: expected a square edge > 0 m, got {self.square_m!r}")

    @classmethod
    def from_text(cls, text: str, square_m: float = 0.025) -> Chessboard:
        """`'9x6'` -> Chessboard(9, 6); ValueError naming the expected form otherwise."""
        match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
        if match is None:
            raise ValueError(f"board: expected COLSxROWS inner corners such as 9x6, got {text!r}")
        return cls(int(match[1]), int(match[2]), square_m)

    @property
    def pattern_size(self) -> tuple[int, int]:
        """(cols, rows) as OpenCV's patternSize."""
        return self.cols, self.rows

    def object_points_m(self) -> npt.NDArray[np.float32]:
        """(cols * rows, 3) float32 corners in the board frame (m), row by row as OpenCV."""
        grid = np.mgrid[0 : self.cols, 0 : self.rows].T.reshape(-1, 2)
        points = np.zeros((self.cols * self.rows, 3), dtype=np.float32)
        points[:, :2] = grid * self.square_m
        return points


@dataclass(frozen=True)
class ChessboardParams:
    """Corner detection and refinement settings.

    subpix_half_window_px: half side of cornerSubPix's search window (11, as OpenCV's
    calibration sample), reduced per view to keep clear of the neighbouring corners;
    subpix_max_iterations, subpix_epsilon_px: its stopping rule.
    """

    subpix_half_window_px: int = 11
    subpix_max_iterations: int = 30
    subpix_epsilon_px: float = 1e-3

    def __post_init__(self) -> None:
        if self.subpix_half_window_px < 1:
            raise ValueError(
                f"subpix_half_window_px: expected >= 1, got {self.subpix_half_window_px}"
            )
        if self.subpix_max_iterations < 1:
            raise ValueError(
                f"subpix_max_iterations: expected >= 1, got {self.subpix_max_iterations}"
            )
        if not self.subpix_epsilon_px > 0:
            raise ValueError(f"subpix_epsilon_px: expected > 0, got {self.subpix_epsilon_px}")


@dataclass(frozen=True, eq=False)
class ChessboardView:
    """One input view and what became of it.

    corners_px: (cols * rows, 2) float64 sub-pixel (u, v) of the inner corners, None when the
    board was not found; skipped: why the view was not used ("" when used); rvec, tvec: (3,)
    float64 board pose in the camera frame (Rodrigues vector, metres), reprojection_rms_px:
    the view's RMS reprojection error -- both None for skipped views.
    """

    name: str
    width_px: int
    height_px: int
    corners_px: FloatArray | None
    skipped: str = ""
    rvec: FloatArray | None = None
    tvec: FloatArray | None = None
    reprojection_rms_px: float | None = None


@dataclass(frozen=True, eq=False)
class ChessboardCalibration:
    """The fitted camera, its overall RMS reprojection error (px), and every view."""

    intrinsics: Intrinsics
    rms_reprojection_px: float
    board: Chessboard
    views: tuple[ChessboardView, ...] = field(default_factory=tuple)

    @property
    def used(self) -> tuple[ChessboardView, ...]:
        return tuple(v for v in self.views if not v.skipped)

    @property
    def skipped(self) -> tuple[ChessboardView, ...]:
        return tuple(v for v in self.views if v.skipped)


def _refine_window(corners: FloatArray, board: Chessboard, params: ChessboardParams) -> int:
    """Half window for cornerSubPix: at most half the smallest neighbour spacing, less 1 px."""
    grid = corners.reshape(board.rows, board.cols, 2)
    along_rows = np.linalg.norm(np.diff(grid, axis=1), axis=2).min()
    along_cols = np.linalg.norm(np.diff(grid, axis=0), axis=2).min()
    spacing = float(min(along_rows, along_cols))
    return max(1, min(params.subpix_half_window_px, int(spacing / 2) - 1))


def find_corners(
    image: GreyImage, board: Chessboard, params: ChessboardParams = ChessboardParams()
) -> FloatArray | None:
    """(cols * rows, 2) float64 sub-pixel inner corners of `board` in `image`, None if absent.

    image: (H, W) uint8 grey.
    """
    flags = cv2.CALIB_CB_ADAPTIVE_THRESH | cv2.CALIB_CB_NORMALIZE_IMAGE
    found, corners = cv2.findChessboardCorners(image, board.pattern_size, None, flags)
    if not found:
        return None
    half = _refine_window(corners.reshape(-1, 2).astype(np.float64), board, params)
    criteria = (
        cv2.TERM_CRITERIA_EPS | cv2.TERM_CRITERIA_COUNT,
        params.subpix_max_iterations,
        params.subpix_epsilon_px,
    )
    refined = cv2.cornerSubPix(image, corners, (half, half), (-1, -1), criteria)
    return np.asarray(refined, dtype=np.float64).reshape(-1, 2)


def _reference_size(images: Sequence[tuple[str, GreyImage]]) -> tuple[int, int]:
    """(width, height) shared by most views; ValueError when no single size is the most common."""
    counts = Counter((img.shape[1], img.shape[0]) for _, img in images)
    ranked = counts.most_common()
    if len(ranked) > 1 and ranked[0][1] == ranked[1][1]:
        listing = ", ".join(f"{w}x{h} ({n} views)" for (w, h), n in ranked)
        raise ValueError(
            f"views: expected one image size shared by most views, got {listing}; "
            "calibrate the sizes separately"
        )
    return ranked[0][0]


def calibrate_chessboard(
    images: Sequence[tuple[str, GreyImage]],
    board: Chessboard,
    params: ChessboardParams = ChessboardParams(),
) -> ChessboardCalibration:
    """Fit a pinhole camera with plumb_bob distortion to chessboard views (Zhang's method).

    images: (name, (H, W) uint8 grey) per view. Views where the board is not found, or whose
    size differs from the most common one, are skipped and listed in the result's `views`.
    ValueError when fewer than MIN_VIEWS views are usable; the message lists the skipped ones.
    """
    for name, img in images:
        require_grey_image(name, img)
    if not images:
        raise ValueError(f"views: expected at least {MIN_VIEWS} chessboard images, got none")
    width, height = _reference_size(images)

    # 1. Corners per view.
    found: list[ChessboardView] = []
    for name, img in images:
        h, w = img.shape
        if (w, h) != (width, height):
            skip = f"{w}x{h}, not the {width}x{height} of most views"
            found.append(ChessboardView(name, w, h, None, skip))
            continue
        corners = find_corners(img, board, params)
        skip = "" if corners is not None else f"{board.cols}x{board.rows} board not found"
        found.append(ChessboardView(name, w, h, corners, skip))
    usable = [v for v in found if not v.skipped]
    if len(usable) < MIN_VIEWS:
        listing = "; ".join(f"{v.name}: {v.skipped}" for v in found if v.skipped)
        raise ValueError(
            f"views: expected at least {MIN_VIEWS} views with the {board.cols}x{board.rows} board "
            f"found, got {len(usable)} of {len(found)} (skipped: {listing or 'none'})"
        )

    # 2. One camera for all views.
    obj = board.object_points_m()
    img_pts = [np.asarray(v.corners_px, dtype=np.float32).reshape(-1, 1, 2) for v in usable]
    rms, K, dist, rvecs, tvecs = cv2.calibrateCamera(
        [obj] * len(usable), img_pts, (width, height), None, None
    )

    # 3. Per-view reprojection error, poses.
    views: list[ChessboardView] = []
    k = 0
    for v in found:
        if v.skipped:
            views.append(v)
            continue
        projected, _ = cv2.projectPoints(obj, rvecs[k], tvecs[k], K, dist)
        err = projected.reshape(-1, 2) - np.asarray(v.corners_px)
        views.append(
            ChessboardView(
                v.name,
                v.width_px,
                v.height_px,
                v.corners_px,
                rvec=np.asarray(rvecs[k], dtype=np.float64).ravel(),
                tvec=np.asarray(tvecs[k], dtype=np.float64).ravel(),
                reprojection_rms_px=float(np.sqrt(np.mean(np.sum(err**2, axis=1)))),
            )
        )
        k += 1
    intrinsics = Intrinsics(
        fx_px=float(K[0, 0]),
        fy_px=float(K[1, 1]),
        cx_px=float(K[0, 2]),
        cy_px=float(K[1, 2]),
        width_px=width,
        height_px=height,
        distortion=tuple(float(d) for d in np.ravel(dist)[:5]),
    )
    return ChessboardCalibration(intrinsics, float(rms), board, tuple(views))


def _natural_key(path: Path) -> list[int | str]:
    return [int(part) if part.isdigit() else part for part in re.split(r"(\d+)", path.name)]


def read_views(folder: Path) -> list[tuple[str, GreyImage]]:
    """(file name, (H, W) uint8 grey) of every image file in `folder`, in natural name order.

    ValueError naming the folder or the file when it is not a folder, holds no images, or a
    file cannot be decoded.
    """
    if not folder.is_dir():
        raise ValueError(f"{folder}: expected a folder of chessboard images, it does not exist")
    paths = sorted(
        (p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_SUFFIXES),
        key=_natural_key,
    )
    if not paths:
        raise ValueError(
            f"{folder}: expected chessboard images ({', '.join(IMAGE_SUFFIXES)}), found none"
        )
    views = []
    for p in paths:
        img = cv2.imread(str(p), cv2.IMREAD_GRAYSCALE)
        if img is None:
            raise ValueError(f"{p}: cannot decode the image; expected a readable image file")
        views.append((p.name, np.asarray(img, dtype=np.uint8)))
    return views
