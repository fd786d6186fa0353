"""core.image_motion: a rendered person standing by the road, and one keeping pace with the
car, seen on two frames 0.1 s apart; the answer follows from how each of them moved."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.ego import EgoMotion, step
from core.image_motion import PREVIOUS_SCALE, box_motion, keep, kept_shape
from tests.core.roadscenes import camera, two_frames

DT_S = 0.1
Box = tuple[float, float, float, float]


def _on_road(box: Box) -> tuple[float, float]:
    """(x_m, y_m) where the ray through the middle of the box's base meets the road."""
    cam = camera()
    (ray,) = cam.rays_vehicle([((box[0] + box[2]) / 2, box[3])])
    origin = cam.position_vehicle_m
    t = -origin[2] / ray[2]
    return float(origin[0] + t * ray[0]), float(origin[1] + t * ray[1])


def test_a_person_standing_by_the_road_moves_as_a_still_object() -> None:
    previous, image, box = two_frames(25.0, 0.0)
    motion = box_motion(image, keep(previous), camera(), box, *_on_road(box), step(25.0, 0, DT_S))
    assert motion is not None
    assert motion.shift_px > 10  # 2.5 m nearer: the box moved and grew
    assert motion.still_ncc > 0.8 and motion.still_ncc > motion.with_car_ncc + 0.2
    assert not motion.with_car(0.2)


def test_a_person_keeping_pace_with_the_car_moves_with_it() -> None:
    previous, image, box = two_frames(25.0, 25.0)
    motion = box_motion(image, keep(previous), camera(), box, *_on_road(box), step(25.0, 0, DT_S))
    assert motion is not None
    # the legs swing and the road moves behind the person: the match is not perfect (a
    # truck's wheel is rigid); the detector's own box of this person is removed at the
    # default margin (tests/core/test_pedestrian.py)
    assert motion.with_car_ncc > motion.still_ncc + 0.1 and motion.with_car(0.1)


def test_a_standing_car_cannot_tell_and_says_none() -> None:
    previous, image, box = two_frames(0.0, 0.0)
    x_m, y_m = _on_road(box)
    assert box_motion(image, keep(previous), camera(), box, x_m, y_m, EgoMotion.still(DT_S)) is None
    nan = math.nan
    ego = step(25.0, 0, DT_S)
    assert box_motion(image, keep(previous), camera(), box, nan, y_m, ego) is None


def test_the_previous_frame_is_kept_at_a_lower_resolution_read_only() -> None:
    image = np.arange(480 * 640, dtype=np.uint32).reshape(480, 640).astype(np.uint8)
    kept = keep(image)
    assert kept.shape == (480 // PREVIOUS_SCALE, 640 // PREVIOUS_SCALE) == kept_shape(480, 640)
    assert kept_shape(481, 639) == keep(np.zeros((481, 639), np.uint8)).shape
    assert (
        np.array_equal(kept, image[::PREVIOUS_SCALE, ::PREVIOUS_SCALE]) and not kept.flags.writeable
    )
    with pytest.raises(ValueError):
        kept[0, 0] = 1
