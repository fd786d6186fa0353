"""Overlays land where the camera model says, in their colours; empty inputs leave the image."""

from __future__ import annotations

import numpy as np
import pytest
from app_fakes import HEIGHT_PX, WIDTH_PX, fake_camera

from app import draw
from core.io.frame import RadarTarget
from core.io.groundtruth import FrameTruth, TruthGuardRail, TruthObject


def black() -> np.ndarray:
    return np.zeros((HEIGHT_PX, WIDTH_PX, 3), dtype=np.uint8)


def target(x_m: float, y_m: float) -> RadarTarget:
    return RadarTarget(float(np.hypot(x_m, y_m)), float(np.arctan2(y_m, x_m)), 0.0, 1.0, x_m, y_m)


def car(box_px: tuple[float, float, float, float]) -> TruthObject:
    return TruthObject(4, "car", box_px, (20.0, 0.0, 0.0), (4.0, 1.8, 1.5), (0.0, 0.0), True, 0.0)


def truth(objects=(), rails=()) -> FrameTruth:
    return FrameTruth(0, 0, 0.0, tuple(objects), tuple(rails))


def test_grey_to_rgb_copies_grey_into_three_channels() -> None:
    grey = np.arange(12, dtype=np.uint8).reshape(3, 4)
    rgb = draw.grey_to_rgb(grey)
    assert rgb.shape == (3, 4, 3)
    for c in range(3):
        np.testing.assert_array_equal(rgb[:, :, c], grey)


def test_grey_to_rgb_takes_views_and_empty_images() -> None:
    grey = np.arange(100, dtype=np.uint8).reshape(10, 10)[::2, ::3]
    np.testing.assert_array_equal(draw.grey_to_rgb(grey)[:, :, 1], grey)
    assert draw.grey_to_rgb(np.zeros((0, 5), dtype=np.uint8)).shape == (0, 5, 3)


def test_grey_to_rgb_rejects_colour_input() -> None:
    with pytest.raises(ValueError, match=r"image: expected an \(H, W\) uint8 grey image"):
        draw.grey_to_rgb(np.zeros((4, 4, 3), dtype=np.uint8))


def test_filled_is_every_pixel_of_the_colour() -> None:
    out = draw.filled(5, 7, (10, 20, 30))
    assert out.shape == (5, 7, 3) and out.dtype == np.uint8
    assert (out.reshape(-1, 3) == (10, 20, 30)).all()
    assert draw.filled(0, 7, (1, 2, 3)).shape == (0, 7, 3)
    assert draw.filled(3, 0, (1, 2, 3)).shape == (3, 0, 3)


def test_fill_paints_a_view_and_nothing_around_it() -> None:
    out = np.zeros((6, 8, 3), dtype=np.uint8)
    draw.fill(out[2:4, 1:5], (200, 100, 50))
    inside = np.zeros((6, 8), dtype=bool)
    inside[2:4, 1:5] = True
    assert (out[inside] == (200, 100, 50)).all()
    assert (out[~inside] == 0).all()


def test_radar_cross_is_centred_where_the_camera_projects_the_target() -> None:
    camera = fake_camera()
    uv_px, in_front = camera.project(np.array([[25.0, -1.5, 0.0]]))
    assert in_front[0]
    u, v = uv_px[0]
    out = draw.draw_radar(black(), [target(25.0, -1.5)], camera)
    row, col = round(v), round(u)
    assert tuple(out[row, col]) == draw.RADAR_COLOUR
    # the arms reach half the marker size along the row and the column
    arm = draw.RADAR_CROSS_SIZE_PX // 2 - 1
    assert tuple(out[row, col + arm]) == draw.RADAR_COLOUR
    assert tuple(out[row + arm, col]) == draw.RADAR_COLOUR
    # and the diagonal beside the centre stays black
    assert tuple(out[row + arm, col + arm]) == (0, 0, 0)


def test_radar_target_behind_the_camera_draws_nothing() -> None:
    out = draw.draw_radar(black(), [target(-10.0, 0.0)], fake_camera())
    assert not out.any()


def test_no_radar_targets_give_the_plain_image() -> None:
    image = black()
    out = draw.draw_radar(image, [], fake_camera())
    np.testing.assert_array_equal(out, image)
    assert out is not image


def test_truth_box_draws_its_class_colour_on_its_border_only() -> None:
    out = draw.draw_truth(black(), truth([car((100.0, 200.0, 180.0, 260.0))]))
    colour = draw.CLASS_COLOURS["car"]
    assert tuple(out[230, 100]) == colour  # left border
    assert tuple(out[230, 180]) == colour  # right border
    assert tuple(out[260, 140]) == colour  # bottom border
    assert tuple(out[230, 140]) == (0, 0, 0)  # inside
    # the "car 4" tag sits above the box
    assert out[185:198, 100:140].any()


def test_guard_rail_polyline_passes_through_its_vertices() -> None:
    rail = TruthGuardRail(1, "right", ((400.0, 300.0), (500.0, 400.0), (600.0, 400.0)))
    out = draw.draw_truth(black(), truth(rails=[rail]))
    for u, v in rail.polyline_px:
        assert tuple(out[int(v), int(u)]) == draw.GUARD_RAIL_COLOUR
    assert tuple(out[400, 550]) == draw.GUARD_RAIL_COLOUR


def test_no_truth_gives_the_plain_image() -> None:
    np.testing.assert_array_equal(draw.draw_truth(black(), None), black())
    np.testing.assert_array_equal(draw.draw_truth(black(), truth()), black())


def test_horizon_is_drawn_on_the_row_the_camera_model_gives() -> None:
    camera = fake_camera()
    row = round(camera.horizon_row_px())
    out = black()
    draw.put_horizon(out, camera)
    assert all(tuple(out[row, col]) == draw.HORIZON_COLOUR for col in (0, 320, WIDTH_PX - 1))
    assert not out[row + 2].any()


def test_caption_adds_a_strip_below_and_keeps_the_image() -> None:
    image = black()
    out = draw.add_caption(image, "frame 3")
    assert out.shape == (HEIGHT_PX + draw.STRIP_HEIGHT_PX, WIDTH_PX, 3)
    np.testing.assert_array_equal(out[:HEIGHT_PX], image)
    strip = out[HEIGHT_PX:]
    assert (strip == draw.TEXT_COLOUR).all(axis=2).any()  # some text pixels
    assert tuple(strip[0, -1]) == draw.STRIP_COLOUR
