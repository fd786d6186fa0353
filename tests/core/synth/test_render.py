"""Known-answer checks of the renderer: truth boxes sit where the camera model puts the objects,
vehicles carry the symmetry and the dark base the detector looks for, guard rails are oblique."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.synth import render
from core.synth.generate import CAMERA_PITCH_RAD, synthetic_calibration
from core.synth.render import Renderer
from core.synth.scenarios import SCENARIOS

CAMERA = synthetic_calibration().camera


@pytest.fixture(scope="module")
def highway_frames() -> list:
    rng = np.random.default_rng(7)
    scene = SCENARIOS["highway"](12.0, rng)
    renderer = Renderer(scene, CAMERA, rng)
    return [
        renderer.render(t, CAMERA_PITCH_RAD + 0.004 * math.sin(t), 1.0)[0]
        for t in (0.5, 2.0, 4.0, 6.5)
    ]


def _clear_vehicles(frame, max_lateral_m: float):
    return [
        o
        for o in frame.objects
        if o.cls in ("car", "van", "truck")
        and o.occlusion < 0.02
        and abs(o.position_m[1]) < max_lateral_m
        and 6 < o.position_m[0] < 60
    ]


def test_truth_box_bottom_and_width_follow_the_camera_model(highway_frames: list) -> None:
    checked = 0
    for t, frame in zip((0.5, 2.0, 4.0, 6.5), highway_frames, strict=True):
        cam = CAMERA.with_pitch(CAMERA_PITCH_RAD + 0.004 * math.sin(t))
        for o in _clear_vehicles(frame, 1.0):
            u0, _v0, u1, v1 = o.box_px
            ((u, v),) = cam.project(np.array([o.position_m]))[0]
            x_cam = o.position_m[0] - cam.extrinsics.x_m
            expected_width_px = cam.intrinsics.fx_px * o.size_m[1] / x_cam
            assert u0 - 1 <= u <= u1 + 1
            assert v == pytest.approx(
                v1, abs=1.5
            )  # the base of the nearest face is the lowest pixel
            assert (u1 - u0) == pytest.approx(expected_width_px, abs=2.5)
            checked += 1
    assert checked >= 3


def test_vehicles_seen_from_behind_are_symmetric_with_a_dark_base(highway_frames: list) -> None:
    checked = 0
    for frame in highway_frames:
        for o in _clear_vehicles(frame, 0.3):
            u0, v0, u1, v1 = (round(c) for c in o.box_px)
            if u1 - u0 < 24:
                continue
            crop = frame.image[v0:v1, u0:u1].astype(float)
            asym = np.abs(crop - crop[:, ::-1]).mean()
            assert asym < 0.15 * crop.std() + 3.0
            base = frame.image[
                v1 - max((v1 - v0) // 8, 2) : v1, u0 + (u1 - u0) // 4 : u1 - (u1 - u0) // 4
            ].mean()
            road = frame.image[v1 + 2 : v1 + 8, u0:u1].mean()
            assert base < road - 15  # the shadow beneath the vehicle (paper 001)
            checked += 1
    assert checked >= 2


def test_guard_rails_are_oblique_lines_below_the_horizon(highway_frames: list) -> None:
    for frame in highway_frames:
        assert frame.guard_rails
        for rail in frame.guard_rails:
            pts = np.array(rail.polyline_px)
            near, far = pts[0], pts[-1]
            if len(pts) < 3 or abs(near[0] - far[0]) < 20:
                continue
            slope = (far[1] - near[1]) / (far[0] - near[0])
            assert 0.02 < abs(slope) < 3.0  # neither horizontal nor vertical
            # the near end is lower in the image than the far end: it converges to the horizon
            assert near[1] > far[1]


def test_labels_match_truth_boxes(highway_frames: list) -> None:
    for frame in highway_frames:
        for o in frame.objects:
            rows, cols = np.nonzero(frame.labels == o.id)
            assert (
                cols.min() - 0.5,
                rows.min() - 0.5,
                cols.max() + 0.5,
                rows.max() + 0.5,
            ) == o.box_px


def test_pedestrians_have_a_human_aspect_ratio() -> None:
    rng = np.random.default_rng(3)
    scene = SCENARIOS["stop_and_go"](15.0, rng)
    renderer = Renderer(scene, CAMERA, rng)
    frame = renderer.render(8.0, CAMERA_PITCH_RAD, 1.0)[0]
    people = [o for o in frame.objects if o.cls == "pedestrian" and o.occlusion < 0.05]
    assert people
    for o in people:
        u0, v0, u1, v1 = o.box_px
        assert 0.2 < (u1 - u0) / (v1 - v0) < 0.75


def test_guard_rail_truth_lies_inside_the_image_and_follows_the_frame_pitch() -> None:
    rng = np.random.default_rng(11)
    scene = SCENARIOS["highway"](6.0, rng)
    renderer = Renderer(scene, CAMERA, rng)
    level = renderer.render(2.0, CAMERA_PITCH_RAD, 1.0)[0]
    pitched = renderer.render(2.0, CAMERA_PITCH_RAD + 0.01, 1.0)[0]  # looking further down
    w, h = CAMERA.intrinsics.width_px, CAMERA.intrinsics.height_px
    for rail in level.guard_rails:
        pts = np.array(rail.polyline_px)
        assert (pts[:, 0] >= -0.5).all() and (pts[:, 0] <= w - 0.5).all()
        assert (pts[:, 1] >= -0.5).all() and (pts[:, 1] <= h - 0.5).all()
    # the far end of each rail sits near the horizon, which rises when the camera pitches down
    far_level = min(np.array(r.polyline_px)[:, 1].min() for r in level.guard_rails)
    far_pitched = min(np.array(r.polyline_px)[:, 1].min() for r in pitched.guard_rails)
    assert far_pitched < far_level - 3


def test_a_long_drives_texture_is_sampled_beyond_opencvs_remap_limit() -> None:
    """remap takes images under 32767 rows; a minute of highway is a longer texture."""
    rows = np.arange(40_000, dtype=np.float32)[:, None] * np.ones((1, 6), np.float32)
    texture = rows + np.arange(6, dtype=np.float32)[None, :] * 0.25
    row = np.array([-3.0, 0.0, 35_000.25, 39_998.5, 39_999.0, 41_000.0], np.float32)
    col = np.array([0.0, 1.5, 2.0, 4.0, 5.0, 9.0], np.float32)
    expected = np.clip(row, 0, 39_999) + np.clip(col, 0, 5) * 0.25  # bilinear, edges clamped
    np.testing.assert_allclose(render._gather(texture, col, row), expected, rtol=0, atol=0.02)
    assert render._gather(texture, col[:0], row[:0]).shape == (0,)
