"""OpenCV's HOG people detector (Dalal and Triggs' linear SVM on 64x128 px HOG windows,
`cv2.HOGDescriptor_getDefaultPeopleDetector`), shared by the pedestrian verification
(`core.pedestrian`, step 6, beyond the papers) and the HOG baseline (`core.baselines`).

`people_scores(image, boxes)` scores given person boxes instead of searching the image:
for each box, the window that frames it as the SVM's training windows frame a person (96 of
its 128 rows, centred), is resampled to 64x128 px (bilinear, border replicated);
its score is the SVM's decision value, the HOG descriptor dotted with the SVM's weights plus
its bias. The detector's own threshold is 0 (`HOGDescriptor.detectMultiScale`'s
hitThreshold); the verification's is `PedestrianParams.hog_min_score`.

Coordinates: full-image pixels, (u0, v0, u1, v1) box bounds as `core.pedestrian` gives
them.

Notes:
    - OpenCV 5 moved `HOGDescriptor` out of the main package (objdetect) into the contrib
      module xobjdetect: `opencv-python-headless` 5.x has no HOG, while
      `opencv-contrib-python-headless` 5.x (this project's dependency) and every 4.x wheel
      have it. `hog_available()` says whether this OpenCV has it; `people_scores` raises
      `HogUnavailableError` with that advice when it does not.
    - The window's width follows from its height (1:2), not from the box's width: the
      symmetry detector's box is the body's width, which the SVM's window does not fix.
    - The descriptor is computed here (`_window_score`, compiled with numba), not by
      `HOGDescriptor.compute`, as OpenCV's default descriptor defines it (hog.cpp): the
      square roots of the grey levels, centred differences with the window's border
      reflected (BORDER_REFLECT_101), OpenCV's polynomial arctangent, 9 unsigned bins
      interpolated linearly, each pixel weighted by a Gaussian of sigma 4 px over its 16x16
      px block and shared bilinearly among the block's four 8x8 px cells, L2-Hys
      normalisation clipped at 0.2. Its scores equal `HOGDescriptor.compute`'s dotted with
      the weights within 1e-4 (`tests/core/test_hog.py`, on random and drive windows), and
      the evaluation of the bundled and real drives is unchanged. One window costs about
      three quarters of OpenCV's time (paired runs, 2026-12-03: 0.17 against 0.23 ms), as
      the Gaussian and bilinear weights are applied along rows, then along columns, one row
      of gradients at a time. The SVM's weights still come from OpenCV.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any

import cv2
import numba
import numpy as np
import numpy.typing as npt

from core.checks import require_grey_image
from core.resample import box_to_grid

Box = tuple[float, float, float, float]

# OpenCV's default people detector: a 64x128 px window, 8 px block stride (a window stride
# must be a multiple of it).
HOG_WINDOW_PX = (64, 128)
HOG_BLOCK_STRIDE_PX = 8
# OpenCV samples/cpp/peopledetect.cpp: "the HOG detector returns slightly larger rectangles
# than the real objects, so we slightly shrink the rectangles": x + 10 % of the width, 80 %
# of the width; y + 7 % of the height, 80 % of the height.
HOG_PERSON_LEFT = 0.10
HOG_PERSON_TOP = 0.07
HOG_PERSON_WIDTH = 0.80
HOG_PERSON_HEIGHT = 0.80
# The SVM was trained on INRIA's 64x128 windows, a person about 96 px tall centred in each
# (Dalal and Triggs 2005, section 3: "a margin of about 16 pixels around the person on all
# four sides").
TRAINING_PERSON_PX = 96
# OpenCV's default descriptor (HOGDescriptor(), hog.cpp): 16x16 px blocks of 2x2 cells of
# 8x8 px every cell (7 x 15 blocks in a 64x128 window); 9 unsigned orientation bins; a
# Gaussian of sigma (16 + 16) / 8 px over each block (winSigma's default); L2-Hys clipped
# at 0.2.
CELL_PX = 8
BLOCK_PX = 16
BINS = 9
BLOCK_SIGMA_PX = 4.0
L2HYS_CLIP = 0.2
# OpenCV's fastAtan2 (core/src/mathfuncs_core): an odd polynomial in degrees of
# min(|x|, |y|) / max(|x|, |y|), folded into the four quadrants
_ATAN_COEFFS = tuple(
    np.float32(np.float32(c) * np.float32(180 / math.pi))
    for c in (0.9997878412794807, -0.3258083974640975, 0.1555786518463281, -0.04432655554792128)
)
_ATAN_EPS = np.float32(np.finfo(np.float64).eps)
_jit = numba.njit(cache=True, nogil=True, error_model="numpy")


class HogUnavailableError(RuntimeError):
    """The installed OpenCV has no HOG; the message says what to install."""


def hog_available() -> bool:
    """Whether this OpenCV has the HOG people detector (OpenCV 5's main package has not)."""
    return hasattr(cv2, "HOGDescriptor") and hasattr(cv2, "HOGDescriptor_getDefaultPeopleDetector")


def require_hog(who: str) -> None:
    """HogUnavailableError naming `who` unless this OpenCV has HOG."""
    if not hog_available():
        raise HogUnavailableError(
            f"{who}: OpenCV {cv2.__version__} has no cv2.HOGDescriptor (OpenCV 5 moved it to "
            "the contrib module xobjdetect); install opencv-contrib-python-headless instead "
            "of opencv-python-headless, or opencv-python-headless<5"
        )


@functools.cache
def _svm() -> tuple[npt.NDArray[np.float32], float]:
    """The default people detector's weights, in the descriptor's order, and its bias."""
    # Any: OpenCV 5's own type stubs have no HOG (the module Notes)
    opencv: Any = cv2
    svm = np.asarray(opencv.HOGDescriptor_getDefaultPeopleDetector(), np.float32).ravel()
    return np.ascontiguousarray(svm[:-1]), float(svm[-1])


@functools.cache
def _tables() -> tuple[npt.NDArray[np.float32], npt.NDArray[np.float32]]:
    """The gamma table (square roots of 0..255) and, per pixel offset 0..15 along one axis
    of a block, the weight it gives the block's first and second cell on that axis: the
    Gaussian of its offset from the block's centre times the linear interpolation between
    the cells' centres (a pixel beyond the outer cell centre gives that cell the rest)."""
    gamma = np.sqrt(np.arange(256, dtype=np.float32)).astype(np.float32)
    axis = np.zeros((BLOCK_PX, 2), dtype=np.float32)
    for j in range(BLOCK_PX):
        at = (j + 0.5) / CELL_PX - 0.5  # in cells, 0 and 1 the cells' centres
        first = math.floor(at)
        gauss = math.exp(-((j - BLOCK_PX / 2) ** 2) / (2 * BLOCK_SIGMA_PX**2))
        for cell, share in ((first, 1.0 - (at - first)), (first + 1, at - first)):
            if 0 <= cell < 2:
                axis[j, cell] = gauss * share
    return gamma, axis


@_jit
def _gradient_row(
    above: npt.NDArray[np.float32],
    row: npt.NDArray[np.float32],
    below: npt.NDArray[np.float32],
    low: npt.NDArray[np.float32],
    high: npt.NDArray[np.float32],
    bin_low: npt.NDArray[np.int32],
    bin_high: npt.NDArray[np.int32],
) -> None:
    """One row of gamma-corrected grey levels with the rows above and below (reflected at
    the window's border): each pixel's gradient magnitude shared between its two nearest
    orientation bins (low, high: the shares; bin_low, bin_high: the bins)."""
    width = row.shape[0]
    dx = np.empty(width, dtype=np.float32)
    dx[0] = dx[width - 1] = 0.0  # the border reflected: the same neighbour on both sides
    for x in range(1, width - 1):
        dx[x] = row[x + 1] - row[x - 1]
    dy = np.empty(width, dtype=np.float32)
    for x in range(width):
        dy[x] = below[x] - above[x]
    p1, p3, p5, p7 = _ATAN_COEFFS
    scale = np.float32(BINS / math.pi)
    to_rad = np.float32(math.pi / 180)
    for x in range(width):
        ax, ay = abs(dx[x]), abs(dy[x])
        c = min(ax, ay) / (max(ax, ay) + _ATAN_EPS)
        c2 = c * c
        poly = (((p7 * c2 + p5) * c2 + p3) * c2 + p1) * c
        deg = poly if ax >= ay else np.float32(90.0) - poly
        deg = np.float32(180.0) - deg if dx[x] < 0 else deg
        deg = np.float32(360.0) - deg if dy[x] < 0 else deg
        at = (deg * to_rad) * scale - np.float32(0.5)
        floor = np.floor(at)
        share = at - floor
        magnitude = np.sqrt(dx[x] * dx[x] + dy[x] * dy[x])
        low[x] = magnitude * (np.float32(1.0) - share)
        high[x] = magnitude * share
        b = np.int32(floor)
        b = b + BINS if b < 0 else (b - BINS if b >= BINS else b)
        bin_low[x] = b
        bin_high[x] = 0 if b + 1 >= BINS else b + 1


@_jit
def _window_score(
    window: npt.NDArray[np.uint8],
    gamma: npt.NDArray[np.float32],
    axis: npt.NDArray[np.float32],
    weights: npt.NDArray[np.float32],
    bias: float,
) -> float:
    """The SVM's decision value of one (128, 64) window (the module Notes): per row, each
    pixel's two orientation shares weighted along x into the cells of the two blocks it
    lies in; per block, the rows weighted along y into its 2x2 cells, L2-Hys normalised
    and dotted with the block's weights (block-major across, then down; cells across,
    then down; then bins, as OpenCV orders the descriptor)."""
    rows, cols = window.shape
    across, down = (cols - BLOCK_PX) // CELL_PX + 1, (rows - BLOCK_PX) // CELL_PX + 1
    width = 2 * BINS
    grey = np.empty((3, cols), dtype=np.float32)  # the rows above, at and below, cyclically
    for x in range(cols):
        grey[1, x] = gamma[window[1, x]]  # above row 0: row 1, reflected
        grey[0, x] = gamma[window[0, x]]
    low = np.empty(cols, dtype=np.float32)
    high = np.empty(cols, dtype=np.float32)
    bin_low = np.empty(cols, dtype=np.int32)
    bin_high = np.empty(cols, dtype=np.int32)
    # per row, block across and cell across: the orientation histogram weighted along x
    by_row = np.zeros(rows * across * width, dtype=np.float32)
    for y in range(rows):
        below = y + 1 if y < rows - 1 else rows - 2
        for x in range(cols):
            grey[(y + 1) % 3, x] = gamma[window[below, x]]
        above = grey[(y + 2) % 3] if y > 0 else grey[1]
        _gradient_row(above, grey[y % 3], grey[(y + 1) % 3], low, high, bin_low, bin_high)
        for x in range(cols):
            last = x // CELL_PX
            for bx in range(last - 1, last + 1):
                if bx < 0 or bx >= across:
                    continue
                j = x - CELL_PX * bx
                at = (y * across + bx) * width
                for cx in range(2):
                    w = axis[j, cx]
                    if w != 0:
                        by_row[at + cx * BINS + bin_low[x]] += w * low[x]
                        by_row[at + cx * BINS + bin_high[x]] += w * high[x]
    total = np.float32(0.0)
    upper = np.empty(width, dtype=np.float32)  # the block's upper cells: (cell across, bin)
    lower = np.empty(width, dtype=np.float32)
    for bx in range(across):
        for by in range(down):
            upper[:] = 0
            lower[:] = 0
            for i in range(BLOCK_PX):
                at = ((CELL_PX * by + i) * across + bx) * width
                w0, w1 = axis[i, 0], axis[i, 1]
                for k in range(width):
                    upper[k] += w0 * by_row[at + k]
                    lower[k] += w1 * by_row[at + k]
            norm2 = np.float32(0.0)
            for k in range(width):
                norm2 += upper[k] * upper[k] + lower[k] * lower[k]
            scale = np.float32(1.0) / (np.sqrt(norm2) + np.float32(0.1 * 2 * width))
            norm2 = np.float32(0.0)
            for k in range(width):
                upper[k] = min(upper[k] * scale, np.float32(L2HYS_CLIP))
                lower[k] = min(lower[k] * scale, np.float32(L2HYS_CLIP))
                norm2 += upper[k] * upper[k] + lower[k] * lower[k]
            scale = np.float32(1.0) / (np.sqrt(norm2) + np.float32(1e-3))
            at = (bx * down + by) * 2 * width
            dot = np.float32(0.0)
            for cx in range(2):
                for b in range(BINS):
                    dot += upper[cx * BINS + b] * weights[at + (2 * cx) * BINS + b]
                    dot += lower[cx * BINS + b] * weights[at + (2 * cx + 1) * BINS + b]
            total += dot * scale
    return float(total) + bias


def window_for(box: Box) -> Box:
    """The 64x128 detector window (u0, v0, u1, v1) that frames person box `box` as the SVM's
    training windows frame a person: `TRAINING_PERSON_PX` of its 128 rows, centred."""
    u0, v0, u1, v1 = box
    height = (v1 - v0) * HOG_WINDOW_PX[1] / TRAINING_PERSON_PX
    width = height * HOG_WINDOW_PX[0] / HOG_WINDOW_PX[1]
    u, v = (u0 + u1) / 2, (v0 + v1) / 2
    return (u - width / 2, v - height / 2, u + width / 2, v + height / 2)


def people_scores(image: npt.NDArray[np.uint8], boxes_px: Sequence[Box]) -> tuple[float, ...]:
    """The SVM's decision value for each person box of `image` ((H, W) uint8 grey): positive
    is a person by the detector's own threshold. Boxes must have a positive height."""
    require_grey_image("image", image)
    require_hog("people_scores")
    if not boxes_px:
        return ()
    weights, bias = _svm()
    gamma, axis = _tables()
    scores = []
    for box in boxes_px:
        if not box[3] > box[1]:
            raise ValueError(f"boxes_px: expected boxes with v1 > v0, got {box!r}")
        window = box_to_grid(image, window_for(box), HOG_WINDOW_PX)
        scores.append(_window_score(window, gamma, axis, weights, bias))
    return tuple(scores)
