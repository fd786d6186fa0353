"""Annotations as ground truth: positions and sizes worked out from a projected known car,
only the annotated frames, guard rails and classes mapped."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from core.annotation.model import Annotations, AttributeChange, Keyframe, Track
from core.annotation.store import GROUNDTRUTH_NAME
from core.annotation.truth import (
    OCCLUDED_FRACTION,
    TYPICAL_LENGTH_M,
    frame_truths,
    recording_truth,
)
from core.cli import DEFAULT_RECORDINGS
from core.io.drive import Drive

X_M, Y_M, WIDTH_M, HEIGHT_M = 20.0, -1.5, 1.8, 1.5  # a car's near face on the road


@pytest.fixture(scope="module")
def camera():  # type: ignore[no-untyped-def]
    with Drive(DEFAULT_RECORDINGS / "highway") as drive:
        return drive.camera


def face_box(camera, x_m: float) -> tuple[float, float, float, float]:  # type: ignore[no-untyped-def]
    """The image box of a car's near face at (x_m, Y_M), WIDTH_M x HEIGHT_M."""
    corners = np.array(
        [
            [x_m, Y_M - WIDTH_M / 2, 0.0],
            [x_m, Y_M + WIDTH_M / 2, 0.0],
            [x_m, Y_M - WIDTH_M / 2, HEIGHT_M],
            [x_m, Y_M + WIDTH_M / 2, HEIGHT_M],
        ]
    )
    px, ok = camera.project(corners)
    assert ok.all()
    u, v = px[:, 0], px[:, 1]
    return (float(u.min()), float(v.min()), float(u.max()), float(v.max()))


def test_a_drawn_box_becomes_the_car_it_shows(camera) -> None:  # type: ignore[no-untyped-def]
    box = face_box(camera, X_M)
    track = Track(4, "car", (Keyframe(0, box), Keyframe(10, box)))
    truths = frame_truths(Annotations((track,), ((0, 5),)), camera, list(range(0, 200, 10)))
    assert sorted(truths) == [0, 1, 2, 3, 4, 5]  # the annotated frames only
    (o,) = truths[3].objects
    assert o.id == 4 and o.cls == "car" and o.box_px == box
    # the box's bottom centre lies under the face's centre; the lens's distortion and the
    # pixel box around the projected corners keep it within a few centimetres
    assert o.position_m[0] == pytest.approx(X_M, rel=0.01)
    assert o.position_m[1] == pytest.approx(Y_M, abs=0.05)
    assert o.size_m[1] == pytest.approx(WIDTH_M, rel=0.02)
    assert o.size_m[2] == pytest.approx(HEIGHT_M, rel=0.02)
    assert o.size_m[0] == TYPICAL_LENGTH_M["car"]
    assert o.occlusion == 0.0 and not o.radar_seen and math.isnan(o.velocity_mps[0])
    assert truths[3].t_ns == 30 and math.isnan(truths[3].pitch_rad)


def test_a_snapped_radar_distance_places_the_object(camera) -> None:  # type: ignore[no-untyped-def]
    box = face_box(camera, X_M)
    track = Track(1, "van", (Keyframe(0, box, distance_m=25.0),))
    (o,) = frame_truths(Annotations((track,), ((0, 0),)), camera, [0])[0].objects
    cx, cy, _ = camera.position_vehicle_m
    scale = (25.0 - cx) / (X_M - cx)  # along the rays from the camera, 25 m instead of X_M
    assert o.position_m[0] == pytest.approx(25.0)
    assert o.position_m[1] == pytest.approx(cy + (Y_M - cy) * scale, abs=0.05)
    assert o.size_m[1] == pytest.approx(WIDTH_M * scale, rel=0.02)


def test_attributes_classes_and_guard_rails(camera) -> None:  # type: ignore[no-untyped-def]
    box = face_box(camera, X_M)
    occluded = Track(
        1,
        "other_obstacle",
        (Keyframe(0, box),),
        changes=(AttributeChange(0, "occluded", True), AttributeChange(0, "radar_seen", True)),
    )
    w = camera.intrinsics.width_px
    rail = Track(2, "guard_rail", (Keyframe(0, (w * 0.6, 250.0, w * 0.95, 300.0)),))
    truth = frame_truths(Annotations((occluded, rail), ((0, 0),)), camera, [0])[0]
    (o,) = truth.objects
    assert o.cls == "other" and o.occlusion == OCCLUDED_FRACTION and o.radar_seen
    (g,) = truth.guard_rails
    # right of the image centre: from the near bottom-right corner to the far top-left one
    assert g.side == "right" and g.polyline_px == ((w * 0.95, 300.0), (w * 0.6, 250.0))


def test_a_box_above_the_horizon_has_no_position(camera) -> None:  # type: ignore[no-untyped-def]
    track = Track(1, "car", (Keyframe(0, (100.0, 1.0, 140.0, 20.0)),))
    (o,) = frame_truths(Annotations((track,), ((0, 0),)), camera, [0])[0].objects
    assert math.isnan(o.position_m[0]) and math.isnan(o.size_m[1])


def test_frames_marked_beyond_the_drive_are_left_out(camera) -> None:  # type: ignore[no-untyped-def]
    assert sorted(frame_truths(Annotations(annotated=((2, 9),)), camera, [0, 1, 2, 3])) == [2, 3]


def test_a_generated_truth_the_manifest_does_not_name_is_not_used(camera, tmp_path) -> None:  # type: ignore[no-untyped-def]
    shutil.copy(DEFAULT_RECORDINGS / "highway" / GROUNDTRUTH_NAME, tmp_path / GROUNDTRUTH_NAME)
    truths, why = recording_truth(tmp_path, None, camera, [0, 1, 2])
    assert truths == {} and why is not None and "format_version 1" in why
    (tmp_path / GROUNDTRUTH_NAME).write_text("{not json")
    truths, why = recording_truth(tmp_path, None, camera, [0, 1, 2])
    assert truths == {} and why is not None and why.startswith("ground truth not used: ")
    (tmp_path / GROUNDTRUTH_NAME).unlink()
    assert recording_truth(tmp_path, None, camera, [0, 1, 2]) == ({}, None)
