"""Motion stereo on the bird's-eye view: the road cancels, what stands on it does not
(paper 000, II-B, fig. 4, eq. 6-7).

Each frame, as in the paper:

1. A: the camera's row window warped onto the bird's-eye grid (inverse perspective mapping)
   with this frame's camera, pitch included (fig. 4.a).
2. B: the background of the previous frame, rotated and translated by the ego motion of
   eq. 4 (a 2x2 rotation and a translation: one affine warp of the grid, fig. 4.b). On the
   first frame B = A.
3. C = |A - B| (fig. 4.c); m = the mean of C over a 3x3 square; D = m > xi (fig. 4.d).
4. The next background B' = w A + (1 - w) B with w = 0.25 where m > xi and 1 elsewhere
   (eq. 6-7).
5. D reprojected into the image (fig. 4.e), the region of interest of pedestrian detection,
   and D's connected regions as obstacle candidates on the road.
6. With the car standing still the same steps are background subtraction: only moving
   obstacles differ from the background (the paper's last paragraph of II-B).

Grids: A, B, C, m, D, the valid mask and B' are (rows, cols) uint8 images on
`grid_for(params)` (row 0 = farthest x, col 0 = leftmost y, see core.camera.BirdEyeGrid),
A to D and B' in grey levels, the masks 0 or 255 so the inspector shows them as they are.

Modes (`MotionStereoResult.mode`):

- "first_frame": no background yet (a new engine or after `reset()`): B = A, D is empty.
- "motion_stereo": the car moved; static and moving obstacles differ from B.
- "background_subtraction": the car stood still (its speed over the interval below
  `params.standstill_speed_mps`); only moving obstacles differ from B.
- "restarted": the ego motion is unknown (None) on a later frame; B cannot be moved, so it
  is reset to A as on a first frame and D is empty.

Vehicles that keep pace with the ego car leave a trail of D on the road between it and
them, as eq. 7 makes it: B keeps 0.75 of their old smear per frame while it differs from A,
and each frame's move of B carries that smear towards the ego car.

Notes:
    - Valid cells (beyond the paper, which does not say what happens at the border of the
      seen area): C, m and D are kept only on grid cells seen in both A and the moved B,
      with one cell eroded off the border where the bilinear warps mix in the fill value;
      elsewhere C = 0 (so m at the border of the valid area averages in zeros) and D = 0.
      The grid starts at 4 m, nearer than the window's bottom row sees (about 6.5 m with
      the bundled camera), and the moved B leaves the grid on one side.
    - Outside the valid cells w = 1: B' = A there, so the background covers exactly what
      the camera saw this frame.
    - D thresholds the exact mean (the window's sum > n^2 xi); the `local_mean` image m is
      that mean rounded to whole grey levels for display. m = xi exactly takes w = 1
      (eq. 7 leaves m = xi open).
    - Only the camera's row window (`CameraModel.row_window_px`, the papers' 640x300 of
      640x480) is read; grid cells outside it or above the horizon are not valid.
    - The image is taken as undistorted (the bundled drives have no lens distortion; a lens
      with distortion needs its image undistorted first, not done here).
    - "restarted" and the standstill label are beyond the paper, which always has odometry.
    - The obstacle regions (connected components of D of at least `min_region_m2`, with
      their extent on the road and their footprint's box in the image) are beyond the
      paper, which uses D only as a region of interest.
    - Seeking (beyond the paper): with w = 1 on free cells the background forgets the
      past; replaying the `frames_to_forget(params)` frames (22 with the paper's weights)
      before a frame after `reset()` rebuilds its background. D can still differ on cells
      whose mean sits at xi, where a flip changes w and feeds back: 99.8 % to 100 % of the
      valid cells agree on the bundled drives. `state()` and `restore()` (beyond the paper)
      carry the background across a jump exactly instead.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal, TypeVar

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import BirdEyeGrid, CameraModel
from core.ego import EgoMotion
from core.params import MotionStereoParams

U8Array = npt.NDArray[np.uint8]
FloatArray = npt.NDArray[np.float64]

ArrayT = TypeVar("ArrayT", U8Array, FloatArray)

Mode = Literal["first_frame", "motion_stereo", "background_subtraction", "restarted"]

MASK_ON = 255  # value of a set cell or pixel in the 0/255 masks

# Grid cells must lie in front of the camera by at least this depth to be valid (rays near
# the horizon meet the road at infinity).
MIN_DEPTH_M = 1e-3

# fillConvexPoly takes fixed-point vertices with this many fractional bits.
POLY_SHIFT_BITS = 8

# Half a grey level: a replayed background agrees with the original once the old state's
# weight times the largest grey difference falls below it.
HALF_GREY_LEVEL = 0.5
MAX_GREY = 255

# Float slack when an area becomes a cell count: 0.1 m2 / 0.01 m2 is 10 cells, not 11.
AREA_SLACK_CELLS = 1e-9

_ERODE_KERNEL = np.ones((3, 3), dtype=np.uint8)  # the one-cell erosion of the valid mask

# A convex polygon in grid cell coordinates (col, row), cell centres at whole numbers.
Polygon = list[tuple[float, float]]
# A half-plane a * col + b * row + c >= 0.
HalfPlane = tuple[float, float, float]


def grid_for(params: MotionStereoParams) -> BirdEyeGrid:
    """The bird's-eye grid of the parameters: x in [x_min_m, x_max_m] ahead,
    y in [-y_half_width_m, y_half_width_m], cell_m per cell."""
    return BirdEyeGrid(
        x_min_m=params.x_min_m,
        x_max_m=params.x_max_m,
        y_min_m=-params.y_half_width_m,
        y_max_m=params.y_half_width_m,
        cell_m=params.cell_m,
    )


def window_homography(H_image_grid: FloatArray, first_row_px: int) -> FloatArray:
    """(3, 3) map from grid cells to the pixels of a window whose row 0 is image row
    first_row_px, from H_image_grid (grid cells to full-image pixels)."""
    H_window_grid = H_image_grid.copy()
    H_window_grid[1] -= first_row_px * H_image_grid[2]
    return H_window_grid


def warp_to_grid(window: U8Array, H_window_grid: FloatArray, bird_eye: U8Array) -> None:
    """Step 1's inverse perspective mapping: `bird_eye` (rows, cols) filled from `window`
    by bilinear sampling, 0 where a cell's road point falls outside it."""
    rows, cols = bird_eye.shape
    cv2.warpPerspective(
        window,
        H_window_grid,
        (cols, rows),
        dst=bird_eye,
        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=0,
    )


def frames_to_forget(params: MotionStereoParams) -> int | None:
    """Frames after which the background no longer depends on what came before them.

    A background cell keeps (1 - w) of its old value per frame (eq. 6); after N frames an old
    state weighs (1 - w)^N at most, and it changes no grey level once 255 (1 - w)^N < 0.5.
    So `reset()` and then the N frames before frame k rebuild frame k's background (a
    seek), up to cells where D flips at the threshold. None: a weight of 0 keeps the old
    background for ever.
    """
    keep = 1.0 - min(params.weight_obstacle, params.weight_free)
    if keep >= 1.0:
        return None
    if keep <= 0.0:
        return 1
    return math.ceil(math.log(HALF_GREY_LEVEL / MAX_GREY) / math.log(keep))


@dataclass(frozen=True)
class ObstacleRegion:
    """One connected region of D (8-connected cells), an obstacle's smear on the road.

    grid_box_cells: (col0, row0, col_stop, row_stop) in grid cells, stops exclusive;
    x_min_m..y_max_m: the cells' extent on the road in the vehicle frame (metres, cell
    edges); box_px: (u_min, v_min, u_max, v_max) in full-image pixels, the box of the grid
    box's footprint projected into the image, clipped to the row window.
    """

    cells: int
    area_m2: float
    grid_box_cells: tuple[int, int, int, int]
    x_min_m: float
    x_max_m: float
    y_min_m: float
    y_max_m: float
    box_px: tuple[float, float, float, float]

    @property
    def nearest_x_m(self) -> float:
        """The region's near edge: the base of an obstacle standing on the road."""
        return self.x_min_m


@dataclass(frozen=True, eq=False)
class MotionStereoResult:
    """One frame of motion stereo with every intermediate image (paper 000, fig. 4).

    Grid images are (rows, cols) = grid.shape uint8, read-only:
    bird_eye: A, grey levels (fig. 4.a); background: B moved by the ego motion (fig. 4.b);
    difference: C = |A - B| on valid cells, 0 elsewhere (fig. 4.c); local_mean: m, the
    3x3 mean of C rounded to grey levels; obstacles: D, 255 where m > xi on valid cells
    (fig. 4.d); valid: 255 on cells seen in both A and the moved B; next_background: B'
    (eq. 6-7), the background of the next frame.

    image_mask: (stop - first, W) uint8 0/255, D reprojected into the camera's row window
    (fig. 4.e); its row 0 is full-image row `image_mask_first_row_px`.
    T_prevgrid_grid: (2, 3) float64 affine map from this frame's grid cells (col, row) to the
    previous frame's (identity on "first_frame" and "restarted"); H_image_grid: (3, 3)
    float64 homography from grid cells to full-image ideal pixels of this frame's camera.
    ego: the motion used (None on "first_frame" and "restarted"); min_region_cells: the
    smallest region `regions` reports, in cells (params.min_region_m2).
    """

    mode: Mode
    grid: BirdEyeGrid
    ego: EgoMotion | None
    T_prevgrid_grid: FloatArray
    H_image_grid: FloatArray
    bird_eye: U8Array
    background: U8Array
    difference: U8Array
    local_mean: U8Array
    obstacles: U8Array
    valid: U8Array
    next_background: U8Array
    image_mask: U8Array
    image_mask_first_row_px: int
    min_region_cells: int

    @functools.cached_property
    def regions(self) -> tuple[ObstacleRegion, ...]:
        """D's 8-connected regions of at least min_region_cells, nearest first; labelled on
        first use, as no later stage needs them (a quarter of the stage's time)."""
        return _regions(self)


# --- polygons -------------------------------------------------------------------------------
def _clip(poly: Polygon, plane: HalfPlane) -> Polygon:
    """Sutherland-Hodgman: the part of a convex polygon where a col + b row + c >= 0."""
    a, b, c = plane
    out: Polygon = []
    n = len(poly)
    for i in range(n):
        p, q = poly[i], poly[(i + 1) % n]
        fp = a * p[0] + b * p[1] + c
        fq = a * q[0] + b * q[1] + c
        if fp >= 0.0:
            out.append(p)
        if (fp >= 0.0) != (fq >= 0.0):
            t = fp / (fp - fq)
            out.append((p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])))
    return out


def _visible_polygon(
    H_window_grid: FloatArray, width_px: int, height_px: int, shape: tuple[int, int]
) -> Polygon:
    """Grid cells whose road point lies in front of the camera and inside the row window,
    where a bilinear sample uses window pixels only (u in [0, W-1], v in [0, H-1]).

    With depth w > 0, u = h1.p / w >= 0 is h1.p >= 0 and so on: every bound is a half-plane
    in the grid, and the visible area is convex.
    """
    rows, cols = shape
    h1, h2, h3 = (_row(H_window_grid, k) for k in range(3))
    poly: Polygon = [(0.0, 0.0), (cols - 1.0, 0.0), (cols - 1.0, rows - 1.0), (0.0, rows - 1.0)]
    planes: list[HalfPlane] = [
        (h3[0], h3[1], h3[2] - MIN_DEPTH_M),
        h1,
        (
            (width_px - 1) * h3[0] - h1[0],
            (width_px - 1) * h3[1] - h1[1],
            (width_px - 1) * h3[2] - h1[2],
        ),
        h2,
        (
            (height_px - 1) * h3[0] - h2[0],
            (height_px - 1) * h3[1] - h2[1],
            (height_px - 1) * h3[2] - h2[2],
        ),
    ]
    for plane in planes:
        if len(poly) < 3:
            return []
        poly = _clip(poly, plane)
    return poly if len(poly) >= 3 else []


def _rows_covering(poly: Polygon, H_window_grid: FloatArray, height_px: int) -> tuple[int, int]:
    """(first, stop) window rows whose pixels can fall on the polygon's cells (the polygon
    grown by one cell, for the rasterisation of its fill and the nearest-cell lookup)."""
    if not poly:
        return 0, 0
    _, (b0, b1, b2), (w0, w1, w2) = (_row(H_window_grid, k) for k in range(3))
    vs: list[float] = []
    for c, r in poly:
        for cc, rr in (
            (c - 1.0, r - 1.0),
            (c + 1.0, r - 1.0),
            (c - 1.0, r + 1.0),
            (c + 1.0, r + 1.0),
        ):
            w = w0 * cc + w1 * rr + w2
            if w <= MIN_DEPTH_M:
                return 0, height_px
            vs.append((b0 * cc + b1 * rr + b2) / w)
    return (
        min(max(math.floor(min(vs)) - 1, 0), height_px),
        min(max(math.ceil(max(vs)) + 2, 0), height_px),
    )


def _row(H: FloatArray, k: int) -> HalfPlane:
    return float(H[k, 0]), float(H[k, 1]), float(H[k, 2])


def _intersect(poly: Polygon, clipper: Polygon) -> Polygon:
    """The intersection of two convex polygons."""
    n = len(clipper)
    if n < 3:
        return []
    area2 = sum(
        clipper[i][0] * clipper[(i + 1) % n][1] - clipper[(i + 1) % n][0] * clipper[i][1]
        for i in range(n)
    )
    orient = 1.0 if area2 > 0 else -1.0
    for i in range(n):
        if len(poly) < 3:
            return []
        (x0, y0), (x1, y1) = clipper[i], clipper[(i + 1) % n]
        # inside: the side of edge (x0, y0) -> (x1, y1) the polygon turns to
        a, b = -(y1 - y0) * orient, (x1 - x0) * orient
        poly = _clip(poly, (a, b, -(a * x0 + b * y0)))
    return poly if len(poly) >= 3 else []


def _affine_apply(M: FloatArray, poly: Polygon) -> Polygon:
    return [
        (
            float(M[0, 0] * c + M[0, 1] * r + M[0, 2]),
            float(M[1, 0] * c + M[1, 1] * r + M[1, 2]),
        )
        for c, r in poly
    ]


# --- ego motion on the grid -------------------------------------------------------------------
def _prevgrid_from_grid(G: FloatArray, G_inv: FloatArray, ego: EgoMotion) -> FloatArray:
    """(2, 3) affine map from this frame's grid cells to the previous frame's (eq. 4).

    The car moved by (dx, dy) and turned by dyaw in the previous vehicle frame, so a road
    point p here was R(dyaw) p + (dx, dy) there. G: the grid's T_grid_ground, G_inv its
    inverse.
    """
    c, s = math.cos(ego.dyaw_rad), math.sin(ego.dyaw_rad)
    T_prev_cur = np.array([[c, -s, ego.dx_m], [s, c, ego.dy_m], [0.0, 0.0, 1.0]])
    return np.asarray((G @ T_prev_cur @ G_inv)[:2], dtype=np.float64)


def _is_still(ego: EgoMotion, standstill_speed_mps: float) -> bool:
    return math.hypot(ego.dx_m, ego.dy_m) <= standstill_speed_mps * ego.dt_s


# --- inputs ---------------------------------------------------------------------------------
def _check_ego(ego: object) -> None:
    if ego is None:
        return
    if not isinstance(ego, EgoMotion):
        raise ValueError(f"ego: expected an EgoMotion or None, got {type(ego).__name__}")
    for name in ("dx_m", "dy_m", "dyaw_rad", "dt_s"):
        value = getattr(ego, name)
        if not math.isfinite(value):
            raise ValueError(
                f"ego.{name}: expected a finite number (None for an unknown motion), got {value!r}"
            )


def _frozen(a: ArrayT) -> ArrayT:
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class MotionStereoState:
    """What `MotionStereo.update` carries from one frame to the next.

    background: B', (rows, cols) uint8 grey levels on the grid, read-only (None before a
    first frame); background_poly: the convex polygon of grid cells (col, row) that frame's
    A saw, the cells where B' holds the camera's view. Immutable, so a state is kept by
    reference, and restoring it any number of times gives the same next update.
    """

    background: U8Array | None
    background_poly: tuple[tuple[float, float], ...]


class MotionStereo:
    """The background B and the steps of paper 000 II-B, one `update()` per camera frame.

    Build one per drive; call `reset()` before a frame that does not follow the last one
    (a seek), then replay `frames_to_forget(params)` frames before the wanted one to rebuild
    its background, or `restore()` the `state()` kept after the frame before it. Results
    never share memory that a later update writes.
    """

    def __init__(self, params: MotionStereoParams) -> None:
        self.params = params
        self.grid = grid_for(params)
        rows, cols = self.grid.shape
        n = params.mean_window_px
        self._T_grid_ground = self.grid.T_grid_ground
        self._T_ground_grid = np.asarray(np.linalg.inv(self._T_grid_ground), dtype=np.float64)
        # D is m > xi, i.e. the window's sum > n^2 xi: exact on whole grey levels, in 16 bits
        # while the largest sum fits
        self._threshold_sum = np.array([n * n * params.threshold_xi])
        sum_16u = n * n * MAX_GREY <= np.iinfo(np.uint16).max
        self._sum_depth = cv2.CV_16U if sum_16u else cv2.CV_32F
        self._window_sum = np.empty((rows, cols), dtype=np.uint16 if sum_16u else np.float32)
        cells = params.min_region_m2 / params.cell_m**2
        self._min_region_cells = max(1, math.ceil(cells - AREA_SLACK_CELLS))
        self._background: U8Array | None = None
        self._background_poly: Polygon = []
        # scratch buffers, never handed out
        self._poly_mask = np.zeros((rows, cols), dtype=np.uint8)
        self._blend = np.empty((rows, cols), dtype=np.uint8)

    @property
    def has_background(self) -> bool:
        return self._background is not None

    def reset(self) -> None:
        """Forget the background: the next update is a first frame."""
        self._background = None
        self._background_poly = []

    def state(self) -> MotionStereoState:
        """The background the next update reads (no copy: the background is read-only and
        every update makes a new one)."""
        return MotionStereoState(self._background, tuple(self._background_poly))

    def restore(self, state: MotionStereoState) -> None:
        """Take up `state` (from `state()` of a MotionStereo with these parameters): the next
        update is the one that followed it. ValueError naming state.background when it is
        not a read-only uint8 image of this grid's shape."""
        background = state.background
        if background is not None and (
            background.shape != self.grid.shape
            or background.dtype != np.uint8
            or background.flags.writeable
        ):
            raise ValueError(
                f"state.background: expected a read-only uint8 {self.grid.shape} grid image, "
                f"got a {'writeable' if background.flags.writeable else 'read-only'} "
                f"{background.dtype} {background.shape} array"
            )
        self._background = background
        self._background_poly = list(state.background_poly)

    def update(
        self, image: U8Array, camera: CameraModel, ego: EgoMotion | None
    ) -> MotionStereoResult:
        """One frame: A from `image`, B moved by `ego`, C, m, D, B' and the reprojected D.

        image: (H, W) uint8 grey, the full camera frame, H x W as camera.intrinsics;
        camera: this frame's camera, pitch included; ego: the car's motion since the
        previous frame (core.ego.EgoMotion, metres and radians in the previous vehicle
        frame), None when unknown. ValueError naming the argument on a wrong image or a
        non-finite motion.
        """
        camera.check_image(image)
        _check_ego(ego)
        p = self.params
        grid = self.grid
        rows, cols = grid.shape
        first, stop = camera.row_window_px
        width = camera.intrinsics.width_px
        window = image[first:stop]

        # 1. A: the bird's-eye view of this frame (inverse perspective mapping).
        H_image_grid = camera.H_image_grid(grid)
        H_window_grid = window_homography(H_image_grid, first)
        bird_eye = np.empty((rows, cols), dtype=np.uint8)
        warp_to_grid(window, H_window_grid, bird_eye)
        poly_a = _visible_polygon(H_window_grid, width, stop - first, (rows, cols))

        # 2. B: the background moved by the ego motion; B = A without one.
        mode: Mode
        if self._background is None or ego is None:
            mode = "first_frame" if self._background is None else "restarted"
            used_ego = None
            M = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
            previous, poly_prev = bird_eye, poly_a
        else:
            still = _is_still(ego, p.standstill_speed_mps)
            mode = "background_subtraction" if still else "motion_stereo"
            used_ego = ego
            M = _prevgrid_from_grid(self._T_grid_ground, self._T_ground_grid, ego)
            previous, poly_prev = self._background, self._background_poly
        background = np.empty((rows, cols), dtype=np.uint8)
        cv2.warpAffine(
            previous,
            M,
            (cols, rows),
            dst=background,
            flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
            borderMode=cv2.BORDER_CONSTANT,
            borderValue=0,
        )
        poly_b = _affine_apply(np.asarray(cv2.invertAffineTransform(M), np.float64), poly_prev)
        poly_valid = _intersect(poly_a, poly_b)
        self._poly_mask.fill(0)
        if poly_valid:
            pts = np.round(np.array(poly_valid) * (1 << POLY_SHIFT_BITS)).astype(np.int32)
            cv2.fillConvexPoly(self._poly_mask, pts, MASK_ON, cv2.LINE_8, POLY_SHIFT_BITS)
        valid = np.empty((rows, cols), dtype=np.uint8)
        cv2.erode(self._poly_mask, _ERODE_KERNEL, dst=valid)

        # 3. C = |A - B|, m = its local mean, D = m > xi.
        difference = np.empty((rows, cols), dtype=np.uint8)
        cv2.absdiff(bird_eye, background, dst=difference)
        cv2.bitwise_and(difference, valid, dst=difference)
        n = p.mean_window_px
        cv2.boxFilter(
            difference,
            self._sum_depth,
            (n, n),
            dst=self._window_sum,
            normalize=False,
            borderType=cv2.BORDER_CONSTANT,
        )
        local_mean = np.empty((rows, cols), dtype=np.uint8)
        cv2.convertScaleAbs(self._window_sum, dst=local_mean, alpha=1.0 / (n * n))
        obstacles = np.empty((rows, cols), dtype=np.uint8)
        cv2.compare(self._window_sum, self._threshold_sum, cv2.CMP_GT, dst=obstacles)
        cv2.bitwise_and(obstacles, valid, dst=obstacles)

        # 4. B' = w A + (1 - w) B, eq. 6-7 (w = 1 outside the valid cells).
        next_background = bird_eye.copy()
        if p.weight_free != 1.0:
            free = cv2.bitwise_xor(valid, obstacles)
            cv2.addWeighted(
                bird_eye, p.weight_free, background, 1.0 - p.weight_free, 0.0, dst=self._blend
            )
            cv2.copyTo(self._blend, free, dst=next_background)
        cv2.addWeighted(
            bird_eye, p.weight_obstacle, background, 1.0 - p.weight_obstacle, 0.0, dst=self._blend
        )
        cv2.copyTo(self._blend, obstacles, dst=next_background)

        # 5. D in the image window (fig. 4.e) and D's regions.
        # D lies inside the valid polygon: warp only the window rows that polygon covers.
        image_mask = np.empty((stop - first, width), dtype=np.uint8)
        v_lo, v_hi = _rows_covering(poly_valid, H_window_grid, stop - first)
        image_mask[:v_lo] = 0
        image_mask[v_hi:] = 0
        if v_hi > v_lo:
            H_grid_band = np.linalg.inv(H_window_grid)
            H_grid_band[:, 2] += v_lo * H_grid_band[:, 1]
            cv2.warpPerspective(
                obstacles,
                H_grid_band,
                (width, v_hi - v_lo),
                dst=image_mask[v_lo:v_hi],
                flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP,
                borderMode=cv2.BORDER_CONSTANT,
                borderValue=0,
            )

        self._background = _frozen(next_background)
        self._background_poly = poly_a
        return MotionStereoResult(
            mode=mode,
            grid=grid,
            ego=used_ego,
            T_prevgrid_grid=_frozen(M),
            H_image_grid=_frozen(H_image_grid),
            bird_eye=_frozen(bird_eye),
            background=_frozen(background),
            difference=_frozen(difference),
            local_mean=_frozen(local_mean),
            obstacles=_frozen(obstacles),
            valid=_frozen(valid),
            next_background=next_background,
            image_mask=_frozen(image_mask),
            image_mask_first_row_px=first,
            min_region_cells=self._min_region_cells,
        )


def _regions(result: MotionStereoResult) -> tuple[ObstacleRegion, ...]:
    """D's 8-connected regions of at least result.min_region_cells, nearest first."""
    obstacles, H_image_grid = result.obstacles, result.H_image_grid
    rows, cols = obstacles.shape
    # 8-connected regions are at most one per 2x2 block: 16-bit labels (half the memory
    # traffic of 32-bit ones) while they fit
    most_labels = ((rows + 1) // 2) * ((cols + 1) // 2) + 1
    label_type = cv2.CV_16U if most_labels <= np.iinfo(np.uint16).max else cv2.CV_32S
    col0, row0, width, height = cv2.boundingRect(obstacles)
    if width == 0 or height == 0:
        return ()
    col_stop, row_stop = col0 + width, row0 + height
    # Grana's block-based labelling: a third of the default's time with statistics
    count, _, stats, _ = cv2.connectedComponentsWithStatsWithAlgorithm(
        obstacles[row0:row_stop, col0:col_stop], 8, label_type, cv2.CCL_GRANA
    )
    if count <= 1:
        return ()
    stats = stats[1:]
    stats = stats[stats[:, cv2.CC_STAT_AREA] >= result.min_region_cells]
    if len(stats) == 0:
        return ()
    stats = stats[np.argsort(-(stats[:, cv2.CC_STAT_TOP] + stats[:, cv2.CC_STAT_HEIGHT]))]
    c0 = stats[:, cv2.CC_STAT_LEFT] + col0
    r0 = stats[:, cv2.CC_STAT_TOP] + row0
    c1 = c0 + stats[:, cv2.CC_STAT_WIDTH]
    r1 = r0 + stats[:, cv2.CC_STAT_HEIGHT]
    # The grid box's four corners (cell edges: cell (c, r) spans c - 0.5 .. c + 0.5) in
    # the image, as (4, N) u and v.
    cols_e = np.concatenate([c0, c1, c1, c0]) - 0.5
    rows_e = np.concatenate([r0, r0, r1, r1]) - 0.5
    hom = H_image_grid[:, :2] @ np.stack([cols_e, rows_e]) + H_image_grid[:, 2:]
    u = (hom[0] / hom[2]).reshape(4, -1)
    v = (hom[1] / hom[2]).reshape(4, -1)
    first = result.image_mask_first_row_px
    stop = first + result.image_mask.shape[0]
    u_hi = result.image_mask.shape[1] - 1.0
    boxes_px = np.stack(
        [
            np.clip(u.min(axis=0), 0.0, u_hi),
            np.clip(v.min(axis=0), first, stop - 1.0),
            np.clip(u.max(axis=0), 0.0, u_hi),
            np.clip(v.max(axis=0), first, stop - 1.0),
        ],
        axis=1,
    )
    g, cell = result.grid, result.grid.cell_m
    return tuple(
        ObstacleRegion(
            cells=n,
            area_m2=n * cell * cell,
            grid_box_cells=(a, b, c, d),
            x_min_m=g.x_max_m - d * cell,
            x_max_m=g.x_max_m - b * cell,
            y_min_m=g.y_max_m - c * cell,
            y_max_m=g.y_max_m - a * cell,
            box_px=(bu0, bv0, bu1, bv1),
        )
        for n, a, b, c, d, (bu0, bv0, bu1, bv1) in zip(
            stats[:, cv2.CC_STAT_AREA].tolist(),
            c0.tolist(),
            r0.tolist(),
            c1.tolist(),
            r1.tolist(),
            boxes_px.tolist(),
            strict=True,
        )
    )
