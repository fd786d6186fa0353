"""The off-the-shelf detectors a user would pick instead of the papers' stages, so the
evaluation can show both side by side.

- Pedestrians: OpenCV's HOG people detector (Dalal and Triggs' linear SVM on 64x128 HOG
  windows, `cv2.HOGDescriptor_getDefaultPeopleDetector`) against paper 000's symmetry
  detector (core.pedestrian). `HogPeople`.
- Pitch: the vanishing point of Hough lines (Canny edges, `cv2.HoughLinesP`, the median of
  the pairwise intersections) against paper 000's clustered-edge vanishing point
  (core.pitch). `hough_pitch`.
- Obstacles: OpenCV's MOG2 background subtractor on the perspective image against paper
  000's motion stereo on the bird's-eye view (core.motion_stereo). `Mog2Obstacles`.

Each is the library's method with its documented knobs; defaults were chosen on the
bundled drives (recordings/highway, exurban, stop_and_go) and each parameter says why.
They take the same (H, W) uint8 grey frames as the engine and answer in full-image pixels
(u column, v row), so the evaluation scores them with the papers' scorers. None of them
times itself, prints or sets OpenCV's thread count (the caller's `cv2.setNumThreads`
holds).

Notes:
    - HOG needs OpenCV's contrib build with OpenCV 5 (`core.hog` Notes); `HogPeople` raises
      `core.hog.HogUnavailableError` saying what to install when this OpenCV has none.
    - HOG boxes: the default people detector's 64x128 window frames a 96 px tall person
      with margins of about 1/8 of the window around it. Boxes are shrunk to the person as
      OpenCV's people-detection sample does (peopledetect.cpp: 10 % off the left, 80 % of
      the width, 7 % off the top, 80 % of the height).
    - HOG is run on the searched rows only, scaled up by `HogParams.upscale` (people
      20-40 m ahead are smaller than the window's person), and OpenCV pads each pyramid
      image by `HogParams.padding_px` (mirroring its border) so that a person whose head or
      feet touch the searched rows still fits a window with its margins.
    - MOG2 models every pixel of the perspective image on its own and cannot undo the ego
      motion: on a moving car the whole static scene moves in the image, and whatever has
      texture or edges (road grain, lane markings, trees, poles, parked cars) becomes
      foreground, which paper 000's bird's-eye motion stereo is built to avoid. The
      mixtures widen as they learn the flicker, so a uniform moving texture fades: on a
      coarse-grained synthetic road about a fifth of the road is still marked after 10
      frames (tests/core/test_baselines.py), and 12-17 % of the camera's row window on the
      bundled drives while the car moves (6 % while it stands, moving objects). It works as
      meant only while the car stands still.
    - MOG2's first frame after a reset is returned empty (OpenCV marks all of it
      foreground: there is no background yet), as motion stereo's first frame.
    - Lens distortion is not undone: the Hough lines are straight only in undistorted
      images (the bundled drives have none).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.checks import require_grey_image
from core.hog import (
    HOG_BLOCK_STRIDE_PX,
    HOG_PERSON_HEIGHT,
    HOG_PERSON_LEFT,
    HOG_PERSON_TOP,
    HOG_PERSON_WIDTH,
    HOG_WINDOW_PX,
    require_hog,
)
from core.pitch import Lines, calibrated_vanishing_point_px, intersections

Box = tuple[float, float, float, float]
U8Array = npt.NDArray[np.uint8]
FloatArray = npt.NDArray[np.float64]


def _require_rows(rows_px: tuple[int, int], height_px: int) -> tuple[int, int]:
    """(first, stop) as ints; ValueError naming `rows_px` unless 0 <= first < stop <= H."""
    if len(rows_px) != 2:
        raise ValueError(f"rows_px: expected (first, stop) image rows, got {rows_px!r}")
    first, stop = rows_px
    if not (
        isinstance(first, (int, np.integer))
        and isinstance(stop, (int, np.integer))
        and 0 <= first < stop <= height_px
    ):
        raise ValueError(
            f"rows_px: expected integer rows 0 <= first < stop <= {height_px} (the image "
            f"height), got {rows_px!r}"
        )
    return int(first), int(stop)


# --- pedestrians: HOG ------------------------------------------------------------------------


@dataclass(frozen=True)
class HogParams:
    """OpenCV's HOG people detector (`HOGDescriptor.detectMultiScale`) and what is done
    around it. The figures below: every third frame of the bundled drives, 113 visible
    people (less than half hidden, 3-40 m ahead), a box found at IoU >= 0.3."""

    # window step in the pyramid images (OpenCV's default 8 = one HOG cell; 4 found about
    # 1.2x the people at 3.6x the time)
    win_stride_px: int = 8
    # OpenCV pads each pyramid image by this (mirroring its border) so that windows reach
    # past the searched rows: a person whose head or feet touch them still fits a window
    # with its margins (OpenCV's sample uses 8; 16 found 3 more of 113 people for 8 % more
    # time, 32 another 3 for 11 % more and 20 % more false boxes)
    padding_px: int = 16
    # pyramid step between detection scales (OpenCV's default 1.05; 1.1 took 0.6x the time
    # and found 0.85x the people)
    scale: float = 1.05
    # SVM margin a window must pass (OpenCV's default 0); raise it to trade recall for
    # precision (the grouped boxes' scores are in `HogResult.scores`)
    hit_threshold: float = 0.0
    # the searched rows are scaled up by this before detection: the window's person is
    # 96 px tall and people 20-40 m ahead are 30-60 px here; 2 found 2.5x the people
    # that 1 found (at 5x the time), 2.5 no more than 2
    upscale: float = 2.0
    # a detection needs more than this many overlapping windows (OpenCV's default 2; 1
    # found 3 more of 113 people with 1.3x the false boxes, 3 found 10 fewer)
    group_threshold: int = 2

    def __post_init__(self) -> None:
        if self.win_stride_px < 1 or self.win_stride_px % HOG_BLOCK_STRIDE_PX:
            raise ValueError(
                f"win_stride_px: expected a positive multiple of {HOG_BLOCK_STRIDE_PX} (the "
                f"descriptor's block stride), got {self.win_stride_px!r}"
            )
        if self.padding_px < 0:
            raise ValueError(f"padding_px: expected >= 0, got {self.padding_px!r}")
        if not (math.isfinite(self.scale) and self.scale > 1.0):
            raise ValueError(f"scale: expected a pyramid step > 1, got {self.scale!r}")
        if not math.isfinite(self.hit_threshold):
            raise ValueError(f"hit_threshold: expected a finite number, got {self.hit_threshold!r}")
        if not (math.isfinite(self.upscale) and self.upscale > 0.0):
            raise ValueError(f"upscale: expected a factor > 0, got {self.upscale!r}")
        if self.group_threshold < 0:
            raise ValueError(f"group_threshold: expected >= 0, got {self.group_threshold!r}")


@dataclass(frozen=True)
class HogResult:
    """One frame's HOG people, strongest first.

    boxes_px: (u0, v0, u1, v1) full-image person boxes (the window's margin removed,
    clipped to the image); scores: the SVM margin of each box's strongest window;
    window_boxes_px: the same detections' whole HOG windows (before shrinking, unclipped);
    rows_px: the (first, stop) rows searched.
    """

    boxes_px: tuple[Box, ...]
    scores: tuple[float, ...]
    window_boxes_px: tuple[Box, ...]
    rows_px: tuple[int, int]


class HogPeople:
    """OpenCV's default HOG people detector on the rows where people can be.

    On all frames of the bundled drives with the defaults (visible people: less than half
    hidden, 3-40 m ahead; a box matches at IoU >= 0.3): recall 0.64 (217 of 338), precision
    0.40 (230 of 569 boxes), about 240 ms a frame on one thread (the 640x300 row window
    scaled to 1280x600). Keeping only boxes scoring at least 1.5 gives 0.48 / 0.71, at
    least 2.0 gives 0.40 / 0.88. The flat-shaded synthetic people are found best between
    about 40 and 150 px tall; people closer than about 10 m (200 px and taller) score low
    with the SVM and are often missed; the smallest window (128 px in the 2x image) frames
    a person about 50 px tall, so smaller people are matched loosely or missed.
    """

    def __init__(self, params: HogParams | None = None) -> None:
        require_hog("HogPeople")
        self.params = HogParams() if params is None else params
        # Any: OpenCV 5's own type stubs have no HOG (the module Notes)
        opencv: Any = cv2
        self._hog = opencv.HOGDescriptor()
        self._hog.setSVMDetector(opencv.HOGDescriptor_getDefaultPeopleDetector())

    def detect(self, image: U8Array, rows_px: tuple[int, int] | None = None) -> tuple[Box, ...]:
        """(u0, v0, u1, v1) full-image person boxes, strongest first.

        image: (H, W) uint8 grey frame; rows_px: (first, stop) rows to search (None: all;
        the evaluation passes the camera's `row_window_px`).
        """
        return self.detect_scored(image, rows_px).boxes_px

    def detect_scored(self, image: U8Array, rows_px: tuple[int, int] | None = None) -> HogResult:
        """`detect` with each box's score and HOG window (see `HogResult`)."""
        require_grey_image("image", image)
        h, w = image.shape
        first, stop = (0, h) if rows_px is None else _require_rows(rows_px, h)
        p = self.params

        # 1. the searched rows, scaled up
        region = image[first:stop]
        if p.upscale != 1.0:
            region = np.asarray(
                cv2.resize(
                    region, None, fx=p.upscale, fy=p.upscale, interpolation=cv2.INTER_LINEAR
                ),
                dtype=np.uint8,
            )
        empty = HogResult((), (), (), (first, stop))
        if region.shape[0] < HOG_WINDOW_PX[1] or region.shape[1] < HOG_WINDOW_PX[0]:
            return empty

        # 2. windows over the pyramid, grouped by OpenCV (a group keeps its best score)
        rects, weights = self._hog.detectMultiScale(
            region,
            hitThreshold=p.hit_threshold,
            winStride=(p.win_stride_px, p.win_stride_px),
            padding=(p.padding_px, p.padding_px),
            scale=p.scale,
            groupThreshold=p.group_threshold,
        )
        if len(rects) == 0:
            return empty
        rect = np.asarray(rects, dtype=np.float64).reshape(-1, 4) / p.upscale
        score = np.asarray(weights, dtype=np.float64).reshape(-1)
        order = np.argsort(-score, kind="stable").tolist()

        # 3. full-image windows, strongest first, and the person inside each, clipped
        windows, boxes = [], []
        for x, y, ww, wh in rect[order].tolist():
            windows.append((x, y + first, x + ww, y + first + wh))
            u0 = x + HOG_PERSON_LEFT * ww
            v0 = y + first + HOG_PERSON_TOP * wh
            u1 = u0 + HOG_PERSON_WIDTH * ww
            v1 = v0 + HOG_PERSON_HEIGHT * wh
            boxes.append((max(u0, 0.0), max(v0, 0.0), min(u1, float(w)), min(v1, float(h))))
        return HogResult(
            boxes_px=tuple(boxes),
            scores=tuple(float(score[k]) for k in order),
            window_boxes_px=tuple(windows),
            rows_px=(first, stop),
        )


# --- pitch: Hough vanishing point ------------------------------------------------------------


@dataclass(frozen=True)
class HoughPitchParams:
    """Canny edges, probabilistic Hough segments, the median of their intersections.
    Figures: pitch RMS error over all frames of the bundled drives (`hough_pitch`)."""

    # Canny hysteresis thresholds on the 3x3 Sobel gradient (grey levels; the 1:3 ratio
    # of OpenCV's tutorial; 30 / 90 gave 0.44 deg instead of 0.46)
    canny_low: float = 50.0
    canny_high: float = 150.0
    # edges are read from this many rows above the calibrated vanishing point down to the
    # end of the camera's row window: road lines lie below the horizon (core.pitch reads
    # from 10 above; here 10 gave 0.51 deg RMS on the bundled drives, 0 gave 0.46)
    rows_above_vp_px: int = 0
    # HoughLinesP accumulator resolution (1 px, 1 deg) and the votes a line needs (as
    # many edge pixels as the shortest segment kept has)
    rho_px: float = 1.0
    theta_rad: float = math.pi / 180.0
    votes: int = 40
    # shortest segment kept and the largest gap bridged within one (paper 000 keeps
    # clusters of 40 px and more)
    min_line_length_px: float = 40.0
    max_line_gap_px: float = 5.0
    # slanted lines only: at least this far from the image horizontal (vehicle bottoms,
    # crosswalk stripes, shadows; a marking 5.4 m to the side is 0.24 rad from it) ...
    min_angle_from_horizontal_rad: float = 0.15
    # ... and from the image vertical (poles, trunks, vehicle sides; as core.pitch)
    min_angle_from_vertical_rad: float = 0.05
    # the longest slanted segments kept (bounds the pairs on textured roads)
    max_lines: int = 40
    # fewer slanted segments than this: no vanishing point
    min_lines: int = 2
    # intersections farther than this (either axis) from the calibrated vanishing point
    # are left out of the median (as core.pitch's vp_region_px)
    vp_region_px: float = 40.0

    def __post_init__(self) -> None:
        for name in ("canny_low", "canny_high", "rho_px", "theta_rad", "vp_region_px"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name}: expected a number > 0, got {value!r}")
        if self.canny_high < self.canny_low:
            raise ValueError(
                f"canny_high: expected >= canny_low={self.canny_low}, got {self.canny_high!r}"
            )
        if self.rows_above_vp_px < 0:
            raise ValueError(f"rows_above_vp_px: expected >= 0, got {self.rows_above_vp_px!r}")
        if self.votes < 1:
            raise ValueError(f"votes: expected an integer >= 1, got {self.votes!r}")
        for name in ("min_line_length_px", "max_line_gap_px"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name}: expected a number >= 0, got {value!r}")
        lo, hi = self.min_angle_from_horizontal_rad, self.min_angle_from_vertical_rad
        if not (0.0 <= lo and 0.0 <= hi and lo + hi < math.pi / 2):
            raise ValueError(
                "min_angle_from_horizontal_rad, min_angle_from_vertical_rad: expected two "
                f"angles >= 0 that leave some slant (sum < pi/2), got {lo!r}, {hi!r}"
            )
        if self.min_lines < 2:
            raise ValueError(f"min_lines: expected an integer >= 2, got {self.min_lines!r}")
        if self.max_lines < self.min_lines:
            raise ValueError(
                f"max_lines: expected >= min_lines={self.min_lines}, got {self.max_lines!r}"
            )


@dataclass(frozen=True, eq=False)
class HoughPitchResult:
    """One frame's Hough vanishing point (full-image pixels).

    - pitch_rad: from the vanishing point's row with paper 000 eq. 2 (None without one);
    - vanishing_point_px: (u, v), the median of the used intersections (None without one);
    - lines: slanted segments kept;
    - row0_px: first image row of `edges`, which run to the end of the row window;
    - edges: (h, W) uint8 Canny edges 0/255 of those rows;
    - segments_px: (lines, 4) float64 (u0, v0, u1, v1) of the kept segments;
    - intersections_px: (P, 2) pairwise intersections of their lines, intersection_used:
      (P,) bool inside the region around calibrated_vp_px (2,).
    """

    pitch_rad: float | None
    vanishing_point_px: tuple[float, float] | None
    lines: int
    row0_px: int
    edges: U8Array
    segments_px: FloatArray
    intersections_px: FloatArray
    intersection_used: npt.NDArray[np.bool_]
    calibrated_vp_px: FloatArray


def hough_pitch(
    image: U8Array, camera: CameraModel, params: HoughPitchParams | None = None
) -> HoughPitchResult:
    """Camera pitch from the median vanishing point of Hough lines on the road.

    image: (H, W) uint8 grey frame of `camera` (its calibrated pose gives the region and
    the expected vanishing point).

    Steps: 1. Canny edges from `rows_above_vp_px` above the calibrated vanishing point to
    the end of the camera's row window; 2. `cv2.HoughLinesP` segments; 3. the slanted ones
    (neither near the horizontal nor near the vertical), the `max_lines` longest;
    4. intersections of every pair of their lines; 5. those within `vp_region_px` of the
    calibrated vanishing point, their coordinate-wise median the vanishing point; 6. the
    pitch from its row, paper 000 eq. 2 (`CameraModel.pitch_from_horizon_row`, roll
    taken as zero).

    Too few slanted lines (< `min_lines`) or no intersection near the calibrated vanishing
    point: pitch_rad and vanishing_point_px are None (a caller keeps the calibration).

    On all frames of the bundled drives: 0.07 deg RMS on `highway`, 0.15 on
    `stop_and_go`, 0.78 on the curves of `exurban` (the chords of two curved road edges
    meet on the road, below the horizon; keeping the calibration gives 0.24 there), 0.46
    overall; about 2 ms a frame. It never answered None there.
    """
    camera.check_image(image)
    p = HoughPitchParams() if params is None else params
    vp_cal = calibrated_vanishing_point_px(camera)
    first, stop = camera.row_window_px
    row0 = min(max(first, math.floor(vp_cal[1]) - p.rows_above_vp_px), stop - 1)

    # 1. edges
    edges = np.asarray(cv2.Canny(image[row0:stop], p.canny_low, p.canny_high), dtype=np.uint8)

    # 2. segments
    found = cv2.HoughLinesP(
        edges,
        p.rho_px,
        p.theta_rad,
        p.votes,
        minLineLength=p.min_line_length_px,
        maxLineGap=p.max_line_gap_px,
    )
    segments = np.zeros((0, 4)) if found is None else np.asarray(found, np.float64).reshape(-1, 4)
    segments[:, [1, 3]] += row0

    # 3. slanted segments, longest first
    du = segments[:, 2] - segments[:, 0]
    dv = segments[:, 3] - segments[:, 1]
    from_horizontal = np.arctan2(np.abs(dv), np.abs(du))
    slanted = (from_horizontal >= p.min_angle_from_horizontal_rad) & (
        from_horizontal <= math.pi / 2 - p.min_angle_from_vertical_rad
    )
    order = np.argsort(-np.hypot(du, dv)[slanted], kind="stable")[: p.max_lines]
    kept = segments[slanted][order]

    # 4-5. intersections near the calibrated vanishing point, their median
    points, _, _ = intersections(Lines.through_segments(kept), False, 0.0)
    used = np.all(np.abs(points - vp_cal) <= p.vp_region_px, axis=1)
    vp: tuple[float, float] | None = None
    pitch: float | None = None
    if len(kept) >= p.min_lines and used.any():
        median = np.median(points[used], axis=0)
        vp = (float(median[0]), float(median[1]))
        # 6. pitch from the row, eq. 2
        pitch = camera.pitch_from_horizon_row(vp[1])
    return HoughPitchResult(
        pitch_rad=pitch,
        vanishing_point_px=vp,
        lines=len(kept),
        row0_px=row0,
        edges=edges,
        segments_px=kept,
        intersections_px=points,
        intersection_used=used,
        calibrated_vp_px=vp_cal,
    )


# --- obstacles: MOG2 background subtraction --------------------------------------------------


@dataclass(frozen=True)
class Mog2Params:
    """OpenCV's MOG2 background subtractor (`cv2.createBackgroundSubtractorMOG2`), shadows
    off (the mask is 0/255)."""

    # frames the background model remembers (OpenCV's default; 50 s at the drives' 10 fps)
    history_frames: int = 500
    # squared Mahalanobis distance beyond which a pixel is foreground (OpenCV's default)
    var_threshold: float = 16.0
    # learning rate per frame; None: OpenCV's automatic 1 / min(2 n, history_frames) on
    # the n-th frame (OpenCV uses that on the first frame whatever is given)
    learning_rate: float | None = None

    def __post_init__(self) -> None:
        if self.history_frames < 1:
            raise ValueError(
                f"history_frames: expected an integer >= 1, got {self.history_frames!r}"
            )
        if not (math.isfinite(self.var_threshold) and self.var_threshold > 0):
            raise ValueError(f"var_threshold: expected a number > 0, got {self.var_threshold!r}")
        if self.learning_rate is not None and not 0.0 <= self.learning_rate <= 1.0:
            raise ValueError(
                f"learning_rate: expected None or a fraction in [0, 1], got {self.learning_rate!r}"
            )


class Mog2Obstacles:
    """MOG2 foreground of the perspective image: what differs from each pixel's learnt
    mixture of grey levels.

    State: the background model, learnt from every frame given to `update` since the
    construction or the last `reset()`; one image size and row range per model. Without
    ego-motion compensation it marks what moves in the image: standing still, the moving
    obstacles; on a moving car also the textured static scene (module Notes).
    """

    def __init__(self, params: Mog2Params | None = None) -> None:
        self.params = Mog2Params() if params is None else params
        self._shape: tuple[int, int] | None = None
        self._rows: tuple[int, int] | None = None
        self._model = self._new_model()

    def _new_model(self) -> cv2.BackgroundSubtractorMOG2:
        return cv2.createBackgroundSubtractorMOG2(
            history=self.params.history_frames,
            varThreshold=self.params.var_threshold,
            detectShadows=False,
        )

    def reset(self) -> None:
        """Forget the background (after a seek or a new drive)."""
        self._model = self._new_model()
        self._shape = None
        self._rows = None

    def update(self, image: U8Array, rows_px: tuple[int, int] | None = None) -> U8Array:
        """Learn this frame and return its (H, W) uint8 foreground mask, 0 or 255.

        image: (H, W) uint8 grey frame, the same size on every call until `reset()`;
        rows_px: (first, stop) rows modelled (None: all), the same on every call until
        `reset()`; the mask is 0 outside them. The first frame after a reset is learnt
        and its mask is empty (no background to differ from yet).
        """
        require_grey_image("image", image)
        h, w = image.shape
        first, stop = (0, h) if rows_px is None else _require_rows(rows_px, h)
        if self._shape is not None and self._shape != (h, w):
            raise ValueError(
                f"image: expected the {self._shape} size of the previous frames (reset() "
                f"first for another camera), got {(h, w)}"
            )
        if self._rows is not None and self._rows != (first, stop):
            raise ValueError(
                f"rows_px: expected the rows {self._rows} of the previous frames (reset() "
                f"first to change them), got {rows_px!r}"
            )
        first_frame = self._shape is None
        self._shape, self._rows = (h, w), (first, stop)
        rate = -1.0 if self.params.learning_rate is None else self.params.learning_rate
        foreground = self._model.apply(np.ascontiguousarray(image[first:stop]), learningRate=rate)
        mask = np.zeros((h, w), dtype=np.uint8)
        if not first_frame:
            mask[first:stop] = foreground
        return mask
