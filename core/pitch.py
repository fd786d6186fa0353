"""Camera pitch from the vanishing point of edge lines, with horizon tracking as fallback
(paper 000, section II-A).

Steps, each visible in `PitchResult`:

1. vertical edges: horizontal Sobel derivative d/du (3x3) with its sign; only |d| above
   `sobel_threshold`;
2. clusters: 8-connected edge pixels of one sign;
3. one least-squares line per cluster of at least `min_cluster_px` pixels, minimising the
   deviation on columns (u = m v + q, written a u + b v + c = 0 with a^2 + b^2 = 1), the
   cluster size as confidence;
4. lines meeting at less than `merge_angle_rad` merged with eq. (1), alpha from the two
   confidences, confidences summed;
5. the `lines_kept` most confident lines; their pairwise intersections inside a square of
   half-size `vp_region_px` around the calibrated vanishing point, averaged with weight =
   the smaller confidence of the two lines: the vanishing point; its confidence is the sum
   of those weights;
6. pitch from the vanishing-point row with eq. (2);
7. when the vanishing point is not confident (or, beyond the paper, its row lies more than
   `max_vp_jump_px` from the previous frame's horizon), horizon tracking instead: the
   histogram of edge pixels per row is compared with the previous frame's, and the row
   shift that minimises the difference moves the previous horizon; with no previous frame
   the calibration's horizon is used. `method` says which of the three gave the pitch;
8. beyond the paper, `leave_out_vehicles`: edges inside the vehicle boxes of the previous
   frame are left out of steps 2-7 (off by default, Notes).

Coordinates: everything is in full-image pixels (u column, v row); the edge and label
images of the result cover the clustered rows (`row0_px`, every `row_step_px`-th row) and
the histogram the tracked rows (from `window_row0_px`).

Notes:
    - Rows: the paper processes its whole 640x300 image. Here edges are clustered from
      `rows_above_vp_px` above the calibrated vanishing point down, and tracked from
      `tracking_rows_above_vp_px` above it: road lines lie below the horizon, and the sky,
      trees and buildings higher up gave wrong lines and cost time.
    - Step 2: clusters are grown on every `row_step_px`-th row (default 3; 1 is the
      paper), 8-connected on those rows, which keeps the detector within its time budget
      (about 0.45 ms instead of 0.7 ms at 640x300) and was as accurate on the synthetic
      known-pitch scenes (0.06 deg RMS either way); a cluster's size counts the pixels it
      stands for, its pixel count times the step. Clusters are found with OpenCV's
      connected-component labelling in one pass for both signs (the paper grows them
      "beginning from the bottom part of the image": the same clusters in another order).
    - Step 3: a line's row span, used for drawing and for the check below, is its pixels'
      mean row -+ sqrt(3) standard deviations (exact for a line's evenly spread rows).
    - Step 4: the paper does not say in what order to merge. Lines are visited from the
      most confident down; each joins the first group whose founding (most confident) line
      is within the merge angle, so a chain of small angles cannot drift a group away from
      its founder. A group is merged in one go as the confidence-weighted mean of its unit
      lines: eq. (1) pair by pair without renormalising in between (less than 1e-4 apart
      within 0.02 rad). Lines within `min_tilt_rad` of the image vertical (poles, trunks,
      vehicle sides; a lane marking is vertical only right under the camera) are left out
      of steps 4 and 5.
    - Step 5, beyond the paper: an intersection's weight is also multiplied by the sine of
      the angle between the two lines (`weight_by_crossing_angle`; off: the paper's
      weight), because nearly parallel lines, such as the two borders of one marking,
      cross far from where they should when either is slightly off (on the synthetic
      scenes the error fell from 0.16 to 0.05 deg RMS); and an intersection must lie
      beyond an end of both segments (within `segment_margin_px`), as a vanishing point
      does, which rejects a pole crossing a lane line.
    - Step 5, the region: the paper does not size it. At 40 px (4.5 deg of pitch at
      fy = 500 px) the lines of a curve met well inside it but far from the horizon, and
      exurban's pitch was three times worse than keeping the calibration (0.76-0.94 deg
      RMS, up to 3 deg, against 0.25). A car's pitch moves by about a degree, so the
      region is 14 px, 1.0 deg at the synthetic drives' fy of 773 px (the papers' preset:
      40): a pitch further from the calibration than that falls back to horizon tracking.
      Pitch RMS on new-seed drives (20 s, seeds 101, 202 and the held-out 303): exurban
      0.76 / 0.94 / 0.83 -> 0.21 / 0.24 / 0.17 deg (calibration 0.25), highway 0.14 /
      0.18 / 0.16 -> 0.10 / 0.11 / 0.13, stop_and_go 0.18 / 0.19 / 0.17 -> 0.12 / 0.08 /
      0.12. 12 px did as well, 20 px and more let exurban's curves back in, 8 px kept too
      few intersections.
    - Step 6: eq. (2) theta = arctan((1 - v_p / v_0) tan(beta / 2)) assumes the principal
      point at the image centre (tan(beta / 2) = v_0 / f_y). Written as
      arctan((c_y - v_p) / f_y) it holds for any principal point; the two agree when
      c_y = H / 2. Roll is taken as zero, as in the paper.
    - Step 7: "too low" is a summed weight below `min_confidence` or, beyond the paper, a
      weighted spread of the intersections above `max_spread_px` (on curves the
      intersections scatter). The paper does not say how far the tracker searches nor how
      the histograms are compared: +-`max_tracking_offset_px` rows, the sum of absolute
      differences over the rows all shifts overlap, ties towards no shift. Beyond the
      paper, each tracked horizon is pulled `tracking_pull` of the way back to the
      calibrated one, which bounds the drift the paper warns of.
    - Step 7, the jump (beyond the paper): on curves a confident vanishing point now and
      then lands a degree from the true one, inside the region, and horizon tracking then
      carries the error on for frames (exurban seed 3131, frame 69: +1.1 deg, the
      frames before within 0.05 deg). A car's pitch moves less than that between two
      frames: the true pitch of the new-seed and bundled drives by at most 0.59 deg at 10
      fps (0.39 deg the median of their largest steps). A point more
      than `max_vp_jump_px` rows (11, 0.8 deg at fy 773 px) from the previous frame's
      horizon is not taken; without a previous frame it is. Pitch RMS on the 48 new-seed
      drives (seeds 1313-3636, 20 s each), highway / exurban / stop_and_go, off -> on:
      0.120 / 0.199 / 0.117 -> 0.120 / 0.188 / 0.099 deg; better on 13 drives, worse on
      none, and none now worse than keeping the calibration (exurban 2929 and 3131 were:
      0.250 and 0.262 against 0.246 and 0.248); the bundled drives the same. 8 rows did
      better on exurban and stop_and_go (0.186 / 0.096) but worse on the bundled highway
      (0.154 -> 0.163), 14 rows left exurban 3131 behind the calibration. The check is
      per frame, as `max_tracking_offset_px`: at other frame rates the same rows are
      another pitch rate (nuScenes and aiMotive never find a confident vanishing point).
      The papers' preset: 0, no such check.
    - Step 8 is not in the paper and is off by default (the papers' preset keeps it on, as
      it stood). Once moving targets got wide search areas (`core.search_area`), vehicle
      boxes covered more of the road and took lane-marking edges with them: exurban's pitch
      became worse than keeping the calibration (new-seed drives 404 and 505: 0.29 and
      0.27 deg against 0.24). Without step 8, pitch RMS on exurban seeds 101 / 404 / 505
      and the bundled drive: 0.25 / 0.29 / 0.27 / 0.28 -> 0.21 / 0.21 / 0.22 / 0.19 deg;
      stop_and_go seed 101 0.15 -> 0.09; highway and the other drives within 0.01 deg.
      Lines within `min_tilt_rad` of the vertical already drop vehicle sides.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.params import PitchParams

FloatArray = npt.NDArray[np.float64]
BoolImage = npt.NDArray[np.bool_]
LabelImage = npt.NDArray[np.int32]

Method = Literal["vanishing_point", "horizon_tracking", "calibration"]
ROW_SPAN_PER_SIGMA = math.sqrt(3.0)  # half-range / standard deviation of a uniform spread
# Lines whose normals are this close to parallel have no usable intersection.
MIN_INTERSECTION_SINE = 1e-9


@dataclass(frozen=True, eq=False)
class Lines:
    """Image lines a u + b v + c = 0 in full-image pixels.

    abc: (N, 3) with a^2 + b^2 = 1 and a >= 0; confidence: (N,) edge pixels behind each
    line; rows_px: (N, 2) first and last image row of the pixels the line was fitted to
    (for drawing a segment instead of an infinite line).
    """

    abc: FloatArray
    confidence: FloatArray
    rows_px: FloatArray

    def __len__(self) -> int:
        return len(self.confidence)

    @property
    def angle_rad(self) -> FloatArray:
        """(N,) direction of each line, in (-pi/2, pi/2], 0 for a vertical line."""
        return np.asarray(np.arctan2(-self.abc[:, 1], self.abc[:, 0]), dtype=np.float64)

    def top(self, count: int) -> Lines:
        """The `count` most confident lines, most confident first."""
        return self.select(np.argsort(-self.confidence, kind="stable")[:count])

    def select(self, index: npt.NDArray[np.intp] | npt.NDArray[np.bool_]) -> Lines:
        return Lines(self.abc[index], self.confidence[index], self.rows_px[index])

    @classmethod
    def empty(cls) -> Lines:
        return cls(np.zeros((0, 3)), np.zeros(0), np.zeros((0, 2)))

    @classmethod
    def through_segments(cls, segments_px: FloatArray) -> Lines:
        """The lines through (N, 4) segments (u0, v0, u1, v1), confidence their length."""
        u0, v0, u1, v1 = segments_px.T
        length = np.hypot(u1 - u0, v1 - v0)
        a, b = (v1 - v0) / length, (u0 - u1) / length
        sign = np.where(a < 0, -1.0, 1.0)  # a >= 0
        a, b = a * sign, b * sign
        abc = np.stack([a, b, -(a * u0 + b * v0)], axis=1)
        return cls(abc, length, np.stack([np.minimum(v0, v1), np.maximum(v0, v1)], axis=1))


@dataclass(frozen=True, eq=False)
class Clusters:
    """The clusters big enough for a line: sign (K,) +1 or -1 of their edges, label (K,) in
    the label image of that sign, size_px (K,) pixel count. Cluster k was fitted to line k of
    `PitchResult.fitted`."""

    sign: npt.NDArray[np.int8]
    label: npt.NDArray[np.int32]
    size_px: npt.NDArray[np.int64]

    def __len__(self) -> int:
        return len(self.size_px)


@dataclass(frozen=True, eq=False)
class PitchMemory:
    """What the next frame's horizon tracking needs: this frame's edge histogram (h,) per
    processed row and the horizon row it settled on (full-image pixels)."""

    row_histogram: npt.NDArray[np.int64]
    horizon_row_px: float


@dataclass(frozen=True, eq=False)
class PitchResult:
    """Everything the pitch detector computed for one frame (full-image pixels).

    - row0_px, row_step_px: the edges were clustered on rows row0_px + k row_step_px;
    - edges_positive, edges_negative: (n, W) bool thresholded vertical edges on those rows
      (d/du above the threshold: dark to bright to the right; below minus it), vehicle
      boxes removed;
    - labels_positive, labels_negative: (n, W) int32 cluster of each of those edge pixels
      (0 = none; one numbering for both signs);
    - clusters: those of at least min_cluster_px; fitted: one line per cluster; merged:
      the slanted fitted lines after eq. (1); chosen: the most confident merged lines;
    - intersections_px: (P, 2) pairwise intersections of the chosen lines,
      intersection_weight: (P,) their weights, intersection_used: (P,) inside the region
      around calibrated_vp_px (2,) and beyond both segments;
    - vanishing_point_px: (2,) weighted mean of the used intersections (None without
      any), confidence: the sum of their weights, spread_px: their weighted RMS distance
      from the vanishing point (inf without one);
    - window_row0_px, row_histogram: (h,) edge pixels of both signs on each row from
      window_row0_px down; tracking_shift_px: rows the histogram moved since the previous
      frame (None without one);
    - horizon_row_px, pitch_rad: the answer; method: which `Method` gave it;
    - memory: what the next frame needs.
    """

    row0_px: int
    row_step_px: int
    window_row0_px: int
    edges_positive: BoolImage
    edges_negative: BoolImage
    labels_positive: LabelImage
    labels_negative: LabelImage
    clusters: Clusters
    fitted: Lines
    merged: Lines
    chosen: Lines
    intersections_px: FloatArray
    intersection_weight: FloatArray
    intersection_used: npt.NDArray[np.bool_]
    calibrated_vp_px: FloatArray
    vanishing_point_px: FloatArray | None
    confidence: float
    spread_px: float
    row_histogram: npt.NDArray[np.int64]
    tracking_shift_px: int | None
    horizon_row_px: float
    pitch_rad: float
    method: Method
    memory: PitchMemory


# --- steps 1-3: edges, clusters, lines ------------------------------------------------------


def _fit_lines(
    labels: npt.NDArray[np.int32],
    n_labels: int,
    negative: npt.NDArray[np.bool_],
    u: npt.NDArray[np.intp],
    v: npt.NDArray[np.intp],
    min_cluster_px: int,
    row_step_px: int,
) -> tuple[Clusters, Lines]:
    """Least-squares u = m v + q for every cluster of at least min_cluster_px pixels.

    labels: (P,) cluster (> 0) of each edge pixel; negative: (P,) its edge is negative;
    u, v: (P,) full-image coordinates on every row_step_px-th row: a cluster's size is its
    pixel count times row_step_px, the pixels it stands for in the full image.
    """
    n = np.bincount(labels, minlength=n_labels) * row_step_px
    big = np.flatnonzero(n >= min_cluster_px)
    if len(big) == 0:
        return Clusters(np.zeros(0, np.int8), np.zeros(0, np.int32), n[big]), Lines.empty()
    nb = n[big].astype(np.float64)
    # Means over the pixels of each cluster (integer products are exact in float64)
    uf, vf = u.astype(np.float64), v.astype(np.float64)
    mu = np.bincount(labels, uf, n_labels)[big] * row_step_px / nb
    mv = np.bincount(labels, vf, n_labels)[big] * row_step_px / nb
    var_v = np.bincount(labels, vf * vf, n_labels)[big] * row_step_px / nb - mv * mv
    cov = np.bincount(labels, uf * vf, n_labels)[big] * row_step_px / nb - mu * mv
    fit = var_v > 1e-9  # a cluster on one row has no column-on-row regression
    big, nb, mu, mv, var_v, cov = big[fit], nb[fit], mu[fit], mv[fit], var_v[fit], cov[fit]
    slope = cov / var_v
    norm = np.sqrt(1.0 + slope * slope)
    abc = np.stack([1.0 / norm, -slope / norm, (slope * mv - mu) / norm], axis=1)
    # Rows spanned: a line's pixels spread evenly over its rows, whose first and last are
    # then the mean -+ sqrt(3) standard deviations.
    half = ROW_SPAN_PER_SIGMA * np.sqrt(var_v)
    is_negative = np.zeros(n_labels, dtype=np.bool_)
    is_negative[labels[negative]] = True
    sign = np.where(is_negative[big], -1, 1).astype(np.int8)
    clusters = Clusters(sign, big.astype(np.int32), n[big])
    return clusters, Lines(abc, nb, np.stack([mv - half, mv + half], axis=1))


# --- step 4: merging ------------------------------------------------------------------------


def merge_pair(
    abc1: FloatArray, confidence1: float, abc2: FloatArray, confidence2: float
) -> tuple[FloatArray, float]:
    """Eq. (1): two lines (3,) into one, alpha = c2 / (c1 + c2); confidences summed.

    The result is renormalised to a^2 + b^2 = 1.
    """
    if not confidence1 + confidence2 > 0:
        raise ValueError(
            f"confidence1, confidence2: expected a sum > 0, got {confidence1}, {confidence2}"
        )
    alpha = confidence2 / (confidence1 + confidence2)
    n1 = math.hypot(abc1[0], abc1[1])
    n2 = math.hypot(abc2[0], abc2[1])
    merged = abc1 * ((1.0 - alpha) / n2) + abc2 * (alpha / n1)
    return merged / math.hypot(merged[0], merged[1]), confidence1 + confidence2


def merge_lines(lines: Lines, merge_angle_rad: float) -> Lines:
    """Step 4: lines meeting at less than merge_angle_rad merged with eq. (1).

    Visited from the most confident; each line joins the first group whose founding line is
    within the angle (see the module Notes), else founds a new group. A group is merged in
    one go as the confidence-weighted mean of its unit lines, which is eq. (1) applied pair
    by pair without renormalising in between (the two differ by less than 1e-4 for lines
    within 0.02 rad).
    """
    ordered = lines.top(len(lines))
    angle = ordered.angle_rad
    diff = np.abs(angle[:, None] - angle[None, :])  # angles in (-pi/2, pi/2]
    close = np.packbits(np.minimum(diff, np.pi - diff) < merge_angle_rad, axis=1, bitorder="little")
    # Founders as a bit set over the visiting order: the lowest set bit of (close & founders)
    # is the first, most confident founder within the angle.
    founders = 0
    founder = [0] * len(ordered)  # of each line, in the visiting order
    group = [0] * len(ordered)
    count = 0
    packed, width = close.tobytes(), close.shape[1]
    for k in range(len(ordered)):
        hit = int.from_bytes(packed[k * width : (k + 1) * width], "little") & founders
        if hit:
            founder[k] = (hit & -hit).bit_length() - 1
            group[k] = group[founder[k]]
        else:
            founders |= 1 << k
            founder[k], group[k] = k, count
            count += 1
    member = np.arange(count)[:, None] == np.array(group)[None, :]  # (groups, lines)
    # Normals turned to agree with their founder's: near the horizontal, lines within the
    # angle can have opposite normals, which would cancel in the sum.
    agree = np.where((ordered.abc[:, :2] * ordered.abc[founder, :2]).sum(axis=1) < 0, -1.0, 1.0)
    confidence = member @ ordered.confidence
    abc = member @ (ordered.abc * (ordered.confidence * agree)[:, None])
    abc /= np.hypot(abc[:, 0], abc[:, 1])[:, None]
    abc[abc[:, 0] < 0] *= -1.0  # a >= 0, as fitted lines
    rows = np.stack(
        [
            np.where(member, ordered.rows_px[:, 0], np.inf).min(axis=1),
            np.where(member, ordered.rows_px[:, 1], -np.inf).max(axis=1),
        ],
        axis=1,
    )
    return Lines(abc, confidence, rows)


# --- step 5: the vanishing point ------------------------------------------------------------


def intersections(
    lines: Lines, by_crossing_angle: bool, segment_margin_px: float
) -> tuple[FloatArray, FloatArray, npt.NDArray[np.bool_]]:
    """Pairwise intersections of lines that are not parallel.

    Returns (P, 2) points (u, v); (P,) weights: the smaller confidence of the pair, times
    the sine of the angle between the two lines when by_crossing_angle; (P,) beyond: the
    point lies past an end of both segments (not more than segment_margin_px inside the
    rows either was fitted to), as a vanishing point must (see the module Notes).
    """
    if len(lines) < 2:
        return np.zeros((0, 2)), np.zeros(0), np.zeros(0, dtype=np.bool_)
    i, j = _pairs(len(lines))
    (a1, b1, c1), (a2, b2, c2) = lines.abc[i].T, lines.abc[j].T
    w = a1 * b2 - a2 * b1  # unit normals: |w| = |sin(angle between the lines)|
    sine = np.abs(w)
    ok = sine > MIN_INTERSECTION_SINE
    points = np.empty((int(ok.sum()), 2))
    points[:, 0] = (b1 * c2 - b2 * c1)[ok] / w[ok]
    points[:, 1] = (a2 * c1 - a1 * c2)[ok] / w[ok]
    weight = np.minimum(lines.confidence[i], lines.confidence[j])
    if by_crossing_angle:
        weight *= sine
    top, bottom = lines.rows_px[:, 0], lines.rows_px[:, 1]
    row = points[:, 1]
    beyond = np.ones(len(points), dtype=np.bool_)
    for k in (i[ok], j[ok]):
        beyond &= (row <= top[k] + segment_margin_px) | (row >= bottom[k] - segment_margin_px)
    return points, weight[ok], beyond


@functools.lru_cache(maxsize=32)
def _pairs(n: int) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]:
    i, j = np.triu_indices(n, k=1)
    i.flags.writeable = j.flags.writeable = False
    return i, j


# --- step 7: horizon tracking ---------------------------------------------------------------


def histogram_shift(
    histogram: npt.NDArray[np.int64], previous: npt.NDArray[np.int64], max_shift_px: int
) -> int:
    """Rows s that best explain histogram[v] = previous[v - s] (content moved down by s),
    minimising the sum of absolute differences over the rows every shift overlaps (all but
    max_shift_px at each end); ties go to the smallest |s|."""
    if histogram.shape != previous.shape:
        raise ValueError(
            f"previous.row_histogram: expected {histogram.shape[0]} rows, got {previous.shape[0]}"
        )
    h = len(histogram)
    reach = min(max_shift_px, (h - 1) // 2)
    cost = np.abs(previous[_shifted_rows(h, reach)] - histogram[reach : h - reach]).sum(axis=1)
    shifts = reach - np.arange(len(cost))
    best = np.flatnonzero(cost == cost.min())
    return int(shifts[best[np.argmin(np.abs(shifts[best]))]])


@functools.lru_cache(maxsize=16)
def _shifted_rows(h: int, reach: int) -> npt.NDArray[np.intp]:
    """(2 reach + 1, h - 2 reach) rows of previous that line up with the central rows
    [reach, h - reach) of the current histogram: row k holds the shift s = reach - k."""
    index = np.arange(2 * reach + 1)[:, None] + np.arange(h - 2 * reach)[None, :]
    index.flags.writeable = False
    return index


# --- the stage -------------------------------------------------------------------------------


def calibrated_vanishing_point_px(camera: CameraModel) -> FloatArray:
    """(2,) where the vehicle's forward direction vanishes in the image of `camera`."""
    d = camera.intrinsics.K @ (camera.R_vehicle_camera.T @ np.array([1.0, 0.0, 0.0]))
    return np.asarray(d[:2] / d[2], dtype=np.float64)


@functools.lru_cache(maxsize=16)
def _region(
    camera: CameraModel, rows_above_vp_px: int, tracking_rows_above_vp_px: int
) -> tuple[FloatArray, float, int, int, int]:
    """Calibrated vanishing point, calibrated horizon row, and the image rows the detector
    reads: from tracking_rows_above_vp_px above the calibrated vanishing point (edge
    histogram) and from rows_above_vp_px above it (clusters) down to the end of the
    processed window."""
    vp = calibrated_vanishing_point_px(camera)
    vp.flags.writeable = False
    first, stop = camera.row_window_px
    top = math.floor(vp[1])

    def row(above: int) -> int:
        return min(max(first, top - above), stop - 1)

    return vp, camera.horizon_row_px(), row(tracking_rows_above_vp_px), row(rows_above_vp_px), stop


def _check_boxes(boxes_px: Sequence[tuple[float, float, float, float]]) -> None:
    for box in boxes_px:
        if len(box) != 4 or not all(math.isfinite(c) for c in box):
            raise ValueError(
                f"vehicle_boxes_px: expected boxes of 4 finite numbers (u0, v0, u1, v1), "
                f"got {box!r}"
            )


@dataclass(frozen=True, eq=False)
class _Edges:
    """Thresholded signed edges, both signs in one image for labelling.

    stacked: (2 n + 1, W) uint8 0/1, rows [0, n) d/du > threshold and rows [n + 1, 2n + 1)
    d/du < -threshold on the n rows clustered (every row_step_px-th from the first), row n
    empty so the signs never touch; histogram: (h,) edge pixels of either sign on every
    row of the window.
    """

    stacked: npt.NDArray[np.uint8]
    histogram: npt.NDArray[np.int64]


def _signed_edges(
    window: npt.NDArray[np.uint8],
    row0_px: int,
    cluster_row0_px: int,
    threshold: float,
    row_step_px: int,
    boxes_px: Sequence[tuple[float, float, float, float]],
) -> _Edges:
    """Steps 1 and 8: the 3x3 Sobel d/du of the (h, W) window starting at image row
    row0_px, thresholded with its sign and cleared inside the boxes."""
    h, w = window.shape
    d = cv2.Sobel(window, cv2.CV_16S, 1, 0, ksize=3)
    for u0, v0, u1, v1 in boxes_px:
        c0, c1 = max(math.floor(u0), 0), min(math.ceil(u1) + 1, w)
        r0, r1 = max(math.floor(v0) - row0_px, 0), min(math.ceil(v1) + 1 - row0_px, h)
        if c0 < c1 and r0 < r1:
            d[r0:r1, c0:c1] = 0
    # |d| saturates at 255 in uint8, far above any useful threshold
    edge = cv2.threshold(cv2.convertScaleAbs(d), threshold, 1, cv2.THRESH_BINARY)[1]
    per_row = cv2.reduce(edge, 1, cv2.REDUCE_SUM, dtype=cv2.CV_32S)
    used = d[cluster_row0_px - row0_px :: row_step_px]
    n = len(used)
    stacked = np.empty((2 * n + 1, w), dtype=np.uint8)
    np.greater(used, threshold, out=stacked[:n].view(np.bool_))
    stacked[n] = 0
    np.less(used, -threshold, out=stacked[n + 1 :].view(np.bool_))
    return _Edges(stacked, per_row.ravel().astype(np.int64))


def detect_pitch(
    image: npt.NDArray[np.uint8],
    camera: CameraModel,
    params: PitchParams,
    previous: PitchMemory | None = None,
    vehicle_boxes_px: Sequence[tuple[float, float, float, float]] = (),
) -> PitchResult:
    """Pitch of `camera` (its calibrated pose) for this frame, paper 000 II-A.

    image: (H, W) uint8 grey full frame, as `camera.intrinsics` says; previous: the memory
    of the previous frame's result (None on the first frame or after a seek);
    vehicle_boxes_px: (u0, v0, u1, v1) full-image boxes of the vehicles found on the
    previous frame, whose edges are left out when `params.leave_out_vehicles`.
    """
    camera.check_image(image)
    _check_boxes(vehicle_boxes_px)
    if not params.leave_out_vehicles:
        vehicle_boxes_px = ()
    calibrated_vp, calibrated_horizon, window_row0, row0, stop = _region(
        camera, params.rows_above_vp_px, params.tracking_rows_above_vp_px
    )
    window = image[window_row0:stop]
    w = window.shape[1]

    # 1. vertical edges with sign (8. vehicles removed)
    edges = _signed_edges(
        window, window_row0, row0, params.sobel_threshold, params.row_step_px, vehicle_boxes_px
    )
    n = (edges.stacked.shape[0] - 1) // 2

    # 2. clusters of one sign
    n_labels, found = cv2.connectedComponents(edges.stacked, connectivity=8)
    labels_image = np.asarray(found, dtype=np.int32)
    flat = np.flatnonzero(edges.stacked.view(np.bool_))
    labels = labels_image.ravel().take(flat)
    row = flat // w
    u = flat - row * w
    negative = row > n
    v = (row - negative * (n + 1)) * params.row_step_px + row0

    # 3. one line per big cluster
    clusters, fitted = _fit_lines(
        labels, n_labels, negative, u, v, params.min_cluster_px, params.row_step_px
    )

    # 4. merge nearly parallel lines (but not the images of vertical things)
    slanted = fitted.select(np.abs(fitted.angle_rad) >= params.min_tilt_rad)
    merged = merge_lines(slanted, params.merge_angle_rad) if len(slanted) else slanted

    # 5. vanishing point from the most confident lines
    chosen = merged.top(params.lines_kept)
    points, weight, beyond = intersections(
        chosen, params.weight_by_crossing_angle, params.segment_margin_px
    )
    used = beyond & np.all(np.abs(points - calibrated_vp) <= params.vp_region_px, axis=1)
    confidence = float(weight[used].sum())
    vp, spread = None, math.inf
    if confidence > 0:
        vp = weight[used] @ points[used] / confidence
        spread = math.sqrt(
            float(weight[used] @ ((points[used] - vp) ** 2).sum(axis=1)) / confidence
        )

    # 6-7. pitch from the vanishing point, else from horizon tracking, else calibration
    shift = (
        None
        if previous is None
        else histogram_shift(edges.histogram, previous.row_histogram, params.max_tracking_offset_px)
    )
    jumped = (
        vp is not None
        and previous is not None
        and params.max_vp_jump_px > 0
        and abs(float(vp[1]) - previous.horizon_row_px) > params.max_vp_jump_px
    )
    method: Method
    if (
        vp is not None
        and confidence >= params.min_confidence
        and spread <= params.max_spread_px
        and not jumped
    ):
        method, horizon = "vanishing_point", float(vp[1])
    elif shift is not None and previous is not None:
        # Pulled back towards the calibration, so the tracker's drift stays bounded.
        tracked = previous.horizon_row_px + shift
        method = "horizon_tracking"
        horizon = tracked + params.tracking_pull * (calibrated_horizon - tracked)
    else:
        method, horizon = "calibration", calibrated_horizon
    return PitchResult(
        row0_px=row0,
        row_step_px=params.row_step_px,
        window_row0_px=window_row0,
        edges_positive=edges.stacked[:n].view(np.bool_),
        edges_negative=edges.stacked[n + 1 :].view(np.bool_),
        labels_positive=labels_image[:n],
        labels_negative=labels_image[n + 1 :],
        clusters=clusters,
        fitted=fitted,
        merged=merged,
        chosen=chosen,
        intersections_px=points,
        intersection_weight=weight,
        intersection_used=used,
        calibrated_vp_px=calibrated_vp,
        vanishing_point_px=vp,
        confidence=confidence,
        spread_px=spread,
        row_histogram=edges.histogram,
        tracking_shift_px=shift,
        horizon_row_px=horizon,
        pitch_rad=camera.pitch_from_horizon_row(horizon),
        method=method,
        memory=PitchMemory(edges.histogram, horizon),
    )
