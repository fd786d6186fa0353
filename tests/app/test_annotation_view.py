"""Annotation mode's pure parts: the plane's pixel mapping, what a drag does, the drawn
boxes pixel by pixel, radar snapping."""

from __future__ import annotations

import numpy as np
import pytest

from app.annotation_view import (
    ANNOTATION_COLOURS,
    CORNER_GRAB_PX,
    DRAFT_COLOUR,
    PX_TO_M,
    SELECTED_COLOUR,
    DragAction,
    annotated_picture,
    box_under,
    drag_action,
    dragged_box,
    pixel_of,
    plane_pixel,
    snapped_distance_m,
)
from core.annotation.model import Shown

SIZE = (640, 480)
NONE = {"occluded": False, "truncated": False, "radar_seen": False}


def shown(track_id: int, box: tuple[float, float, float, float], keyframe: bool = True) -> Shown:
    return Shown(track_id, "car", box, keyframe, None, NONE)


def test_the_plane_maps_to_pixels() -> None:
    assert pixel_of((0.0, 0.0, 50.0), SIZE) == (320.0, 240.0)  # the centre
    # image right is +x, image up is +y: the top-left corner is at (-W/2, +H/2)
    top_left = (-320 * PX_TO_M, 240 * PX_TO_M, 50.0)
    assert pixel_of(top_left, SIZE) == pytest.approx((0.0, 0.0))
    assert pixel_of((1.0, -1.0, 50.0), SIZE) == pytest.approx(
        (320 + 1 / PX_TO_M, 240 + 1 / PX_TO_M)
    )


def test_a_pointer_ray_meets_the_plane_and_selects_the_smallest_box_under_it() -> None:
    # straight down from 10 m above the plane's centre: the centre pixel
    assert plane_pixel((0.0, 0.0, 60.0), (0.0, 0.0, -1.0), SIZE) == (320.0, 240.0)
    # 45 degrees toward +x from 1 m above: 1 m right of the centre, 100 px at PX_TO_M
    above = (0.0, 0.0, 50.0 + 1.0)
    assert plane_pixel(above, (0.7071, 0.0, -0.7071), SIZE) == pytest.approx((420.0, 240.0))
    assert plane_pixel(above, (1.0, 0.0, 0.0), SIZE) is None  # parallel
    boxes = [shown(1, (100, 100, 200, 200)), shown(2, (120, 120, 140, 140))]
    assert box_under((130, 130), boxes) == boxes[1] and box_under((10, 10), boxes) is None


def test_what_a_drag_does() -> None:
    boxes = [shown(1, (100, 100, 200, 200)), shown(2, (120, 120, 140, 140))]
    assert drag_action((50, 50), boxes, None) == DragAction("draw")
    assert drag_action((130, 130), boxes, None) == DragAction("move", 2)  # the smaller one
    assert drag_action((150, 150), boxes, None) == DragAction("move", 1)
    near = 200 + CORNER_GRAB_PX - 1
    assert drag_action((near, near), boxes, 1) == DragAction("corner", 1, 2)  # bottom-right
    assert drag_action((near, near), boxes, None) == DragAction("draw")  # not selected


def test_dragged_boxes() -> None:
    box = (100.0, 100.0, 200.0, 200.0)
    assert dragged_box(DragAction("draw"), None, (300, 50), (250, 90), SIZE) == (250, 50, 300, 90)
    assert dragged_box(DragAction("draw"), None, (300, 50), (301, 90), SIZE) is None  # a click
    assert dragged_box(DragAction("draw"), None, (630, 470), (700, 500), SIZE) == (
        630,
        470,
        640,
        480,
    )
    assert dragged_box(DragAction("move", 1), box, (150, 150), (160, 140), SIZE) == (
        110,
        90,
        210,
        190,
    )
    # the top-left corner dragged past the bottom-right one: the box flips around it
    assert dragged_box(DragAction("corner", 1, 0), box, (100, 100), (250, 260), SIZE) == (
        200,
        200,
        250,
        260,
    )


def test_keyframes_solid_interpolated_dashed_selected_and_draft() -> None:
    rgb = np.zeros((480, 640, 3), np.uint8)
    out = annotated_picture(
        rgb,
        [shown(1, (100, 100, 200, 200)), shown(2, (300, 100, 400, 200), keyframe=False)],
        selected=1,
        draft=(450, 300, 500, 350),
    )
    assert not rgb.any()  # a new image
    # the selected keyframe's left edge: every row of it, two pixels thick around u = 100
    assert (out[120:190, 99:101] == SELECTED_COLOUR).all()
    # the interpolated box's left edge is dashed: some rows drawn, some not
    left = (out[120:190, 300] == ANNOTATION_COLOURS["car"]).all(axis=1)
    assert 0.3 < left.mean() < 0.7
    assert (out[310:340, 450] == DRAFT_COLOUR).all() and not out[320, 470].any()


def test_snapping_takes_the_nearest_radar_target_in_the_box() -> None:
    bases = [(150.0, 190.0, 30.0), (160.0, 195.0, 25.0), (500.0, 190.0, 10.0)]
    assert snapped_distance_m((100, 100, 200, 200), bases) == 25.0
    assert snapped_distance_m((0, 0, 50, 50), bases) is None
