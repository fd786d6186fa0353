"""Did an image box move as a still object would under the car's own motion, or with the
car? (beyond the papers: the pedestrian detector's image-motion filter, `core.pedestrian`
step 5).

A box standing on the road at (x_m, y_m) in this frame's vehicle frame is compared with the
previous frame in two places:

1. still: where a still object at that ground point stood on the previous frame. The car
   moved by ego = (dx, dy, dyaw) since, so the point was at R(dyaw) (x, y) + (dx, dy) in the
   previous vehicle frame; its base there is the camera's projection of that point, and the
   box is scaled by x / x_prev (nearer is larger);
2. with the car: the same place in the image, where an object keeping the car's speed and
   heading (a wheel of a truck beside the car) stood.

Each is the normalised cross-correlation (NCC) of the box's pixels with the previous frame's
there, both resampled to SAMPLE_PX. A box whose two places lie less than MIN_SHIFT_PX apart
(the car standing or slow, or the box far away) cannot tell them apart: `box_motion` says
None. The previous frame is kept at a quarter of the resolution (`keep`: every fourth row
and column, 19 KB of a 640 x 480 frame in every engine state that holds it): on drives of new
seeds (2,400 frames per scenario) it removed nearly the boxes it did at half resolution
(false boxes per frame on highway 0.004 against 0.003, recall the same within 0.001).

Coordinates: boxes (u0, v0, u1, v1) in full-image pixels, pixel centres at integers, as
`core.pedestrian` gives them; the vehicle frame x forward, y left.

Notes:
    - A person walks at 1-2 m/s, so a person's box follows the still hypothesis within
      0.1-0.2 m a frame at 10 Hz; at highway speed the car moves 2.5-3 m a frame, which
      moves and scales a still box by tens of pixels, while a part of a vehicle keeping
      pace stays where it was. The camera's pitch of this frame is used for both
      projections (pitch changes by a fraction of a pixel between frames).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.ego import EgoMotion
from core.resample import box_to_grid

Box = tuple[float, float, float, float]
U8Array = npt.NDArray[np.uint8]

# the two places must lie this far apart (base shift across and down plus the height's
# change, pixels) for the comparison to say anything
MIN_SHIFT_PX = 4.0
# each place's pixels are resampled to this many columns and rows before the NCC
SAMPLE_PX = (16, 32)
# the previous frame is kept at 1 / PREVIOUS_SCALE of the image's resolution (`keep`)
PREVIOUS_SCALE = 4


@dataclass(frozen=True)
class BoxMotion:
    """still_ncc: the box against the previous frame where a still object stood;
    with_car_ncc: against the same place of the previous frame; shift_px: how far apart the
    two places are."""

    still_ncc: float
    with_car_ncc: float
    shift_px: float

    def with_car(self, margin: float) -> bool:
        """Does the box match where it was better, by more than `margin`, than where a still
        object would have been?"""
        return self.with_car_ncc > self.still_ncc + margin


def keep(image: U8Array) -> U8Array:
    """The frame as `box_motion` reads it on the next frame: every PREVIOUS_SCALE-th row and
    column."""
    kept = np.ascontiguousarray(image[::PREVIOUS_SCALE, ::PREVIOUS_SCALE])
    kept.flags.writeable = False
    return kept


def kept_shape(height_px: int, width_px: int) -> tuple[int, int]:
    """The shape `keep` gives a frame of height_px x width_px."""
    return -(-height_px // PREVIOUS_SCALE), -(-width_px // PREVIOUS_SCALE)


def _sample(image: U8Array, box: Box, scale: float) -> U8Array:
    """The pixels of `box` (full-image pixels) of `image` held at 1 / scale resolution,
    resampled to SAMPLE_PX."""
    u0, v0, u1, v1 = box
    return box_to_grid(image, (u0 / scale, v0 / scale, u1 / scale, v1 / scale), SAMPLE_PX)


@numba.njit(cache=True, nogil=True)
def _ncc(a: U8Array, b: U8Array) -> float:
    """Normalised cross-correlation of two samples of the same shape, 0 when either is flat
    (compiled: as five numpy reductions on float copies it cost more than the resampling)."""
    n = a.size
    sum_a = sum_b = sum_aa = sum_bb = sum_ab = 0.0
    flat_a, flat_b = a.ravel(), b.ravel()
    for k in range(n):
        x, y = float(flat_a[k]), float(flat_b[k])
        sum_a += x
        sum_b += y
        sum_aa += x * x
        sum_bb += y * y
        sum_ab += x * y
    var_a = sum_aa - sum_a * sum_a / n
    var_b = sum_bb - sum_b * sum_b / n
    norm = math.sqrt(max(var_a, 0.0) * max(var_b, 0.0))
    return (sum_ab - sum_a * sum_b / n) / norm if norm > 1e-6 else 0.0


def box_motion(
    image: U8Array,
    previous: U8Array,
    camera: CameraModel,
    box_px: Box,
    distance_m: float,
    lateral_m: float,
    ego: EgoMotion,
) -> BoxMotion | None:
    """The box's two comparisons (module docstring). image: this frame (H, W) uint8 grey;
    previous: the previous frame as `keep` gave it; box_px: a box whose base stands on the
    road at (distance_m, lateral_m); ego: the car's motion from the previous frame to this
    one. None when the two places lie less than MIN_SHIFT_PX apart or the still point is
    not in front of the camera."""
    if not (math.isfinite(distance_m) and math.isfinite(lateral_m)):
        return None
    cos, sin = math.cos(ego.dyaw_rad), math.sin(ego.dyaw_rad)
    x_prev = cos * distance_m - sin * lateral_m + ego.dx_m
    y_prev = sin * distance_m + cos * lateral_m + ego.dy_m
    points = np.array([[x_prev, y_prev, 0.0], [distance_m, lateral_m, 0.0]])
    pixels, in_front = camera.project(points)
    if not (in_front.all() and x_prev > 0):
        return None
    (u_prev, v_prev), (u_now, _) = pixels.tolist()
    u0, v0, u1, v1 = box_px
    scale = distance_m / x_prev  # the still object's size then, as a share of now
    width, height = (u1 - u0) * scale, (v1 - v0) * scale
    centre = (u0 + u1) / 2 + u_prev - u_now
    still = (centre - width / 2, v_prev - height, centre + width / 2, v_prev)
    shift = abs(u_prev - u_now) + abs(v_prev - v1) + abs(height - (v1 - v0))
    if shift < MIN_SHIFT_PX:
        return None
    now = _sample(image, box_px, 1.0)
    return BoxMotion(
        _ncc(now, _sample(previous, still, PREVIOUS_SCALE)),
        _ncc(now, _sample(previous, box_px, PREVIOUS_SCALE)),
        shift,
    )
