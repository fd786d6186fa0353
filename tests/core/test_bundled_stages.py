"""Pitch detector and motion stereo on the bundled drives, against their exact ground truth.

Each drive runs as the engine will run it: the pitch detector with the previous frame's
memory and the previous frame's vehicle boxes (here the true ones: the vehicle detector
comes later), then motion stereo with the camera at the detected pitch and the CAN ego
motion. The figures go to the report at the end of the test run; the floors below are set
under what the stages reach today, so a regression fails.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS
from core.io.drive import Drive
from core.io.groundtruth import FrameTruth
from core.motion_stereo import MotionStereo, MotionStereoResult
from core.params import Params
from core.pitch import detect_pitch

VEHICLES = ("car", "van", "truck")
BOX_MARGIN_PX = 4.0  # a D cell within this of an object's box is explained by the object
MIN_VISIBLE = 0.5  # obstacles less occluded than this are expected in D
MIN_BOX_HEIGHT_PX = 8.0  # smaller boxes are too far for the grid's resolution


@dataclass(frozen=True)
class DriveFigures:
    pitch_rms_deg: float
    pitch_max_deg: float
    calibration_rms_deg: float  # the error of keeping the calibrated pitch
    vanishing_point_share: float
    recall: float  # obstacles on the grid with D on them
    precision: float  # D cells inside some object's box (this frame or the one before)


def _inside(uv: np.ndarray, boxes: list[tuple[float, float, float, float]]) -> np.ndarray:
    hit = np.zeros(len(uv), dtype=bool)
    for u0, v0, u1, v1 in boxes:
        hit |= (
            (uv[:, 0] >= u0 - BOX_MARGIN_PX)
            & (uv[:, 0] <= u1 + BOX_MARGIN_PX)
            & (uv[:, 1] >= v0 - BOX_MARGIN_PX)
            & (uv[:, 1] <= v1 + BOX_MARGIN_PX)
        )
    return hit


def _d_pixels(result: MotionStereoResult) -> np.ndarray:
    """(N, 2) image pixels of the cells marked in D."""
    rows, cols = np.nonzero(result.obstacles)
    cells = np.stack([cols, rows, np.ones(len(rows))], axis=1).astype(np.float64)
    uvw = cells @ result.H_image_grid.T
    return uvw[:, :2] / uvw[:, 2:3]


def _expected(truth: FrameTruth, still: bool) -> list[tuple[float, float, float, float]]:
    """Boxes of the obstacles motion stereo should see: on the grid, visible, big enough;
    when the car stands still, only the moving ones."""
    params = Params().motion_stereo
    boxes = []
    for o in truth.objects:
        x, y, _ = o.position_m
        moving = math.hypot(*o.velocity_mps) > 0.5
        if (
            params.x_min_m <= x <= params.x_max_m
            and abs(y) <= params.y_half_width_m
            and o.occlusion < MIN_VISIBLE
            and o.box_px[3] - o.box_px[1] >= MIN_BOX_HEIGHT_PX
            and (moving or not still)
        ):
            boxes.append(o.box_px)
    return boxes


def _run(name: str) -> DriveFigures:
    params = Params()
    errors, calibration_errors, methods = [], [], []
    found = expected = explained = marked = 0
    with Drive(DEFAULT_RECORDINGS / name) as drive:
        stage = MotionStereo(params.motion_stereo)
        memory, boxes, previous_truth = None, (), None
        for k in range(len(drive)):
            frame, truth = drive.frame(k), drive.truth(k)
            assert truth is not None
            pitch = detect_pitch(frame.image, drive.camera, params.pitch, memory, boxes)
            memory = pitch.memory
            boxes = tuple(o.box_px for o in truth.objects if o.cls in VEHICLES)
            errors.append(math.degrees(pitch.pitch_rad - truth.pitch_rad))
            calibration_errors.append(
                math.degrees(drive.camera.extrinsics.pitch_rad - truth.pitch_rad)
            )
            methods.append(pitch.method)
            result = stage.update(frame.image, drive.camera.with_pitch(pitch.pitch_rad), frame.ego)
            if result.mode in ("motion_stereo", "background_subtraction") and previous_truth:
                uv = _d_pixels(result)
                all_boxes = [o.box_px for o in truth.objects + previous_truth.objects]
                explained += int(_inside(uv, all_boxes).sum())
                marked += len(uv)
                for box in _expected(truth, result.mode == "background_subtraction"):
                    expected += 1
                    found += bool(_inside(uv, [box]).any())
            previous_truth = truth
    e, c = np.array(errors), np.array(calibration_errors)
    return DriveFigures(
        pitch_rms_deg=float(np.sqrt(np.mean(e**2))),
        pitch_max_deg=float(np.abs(e).max()),
        calibration_rms_deg=float(np.sqrt(np.mean(c**2))),
        vanishing_point_share=methods.count("vanishing_point") / len(methods),
        recall=found / max(expected, 1),
        precision=explained / max(marked, 1),
    )


# name: (pitch RMS ceiling deg, vanishing point share floor, recall floor, precision floor)
# Highway's precision is lowest: cars keeping pace leave D on the road in front of them, as
# eq. 7 makes it (B keeps 0.75 of their old smear per frame). Exurban's curves scatter the
# vanishing point (the paper warns of curves): since the region around the calibrated one
# narrowed to 14 px (core/pitch.py Notes) it is found on 14 % of frames, and the pitch RMS
# is 0.27 deg against the calibration's 0.24 (0.44 before). Today: highway 0.18 deg, stop
# and go 0.11.
FLOORS = {
    "highway": (0.22, 0.6, 0.9, 0.45),
    "exurban": (0.32, 0.1, 0.75, 0.6),
    "stop_and_go": (0.15, 0.7, 0.85, 0.75),
}


@pytest.mark.parametrize("name", sorted(FLOORS))
def test_pitch_and_motion_stereo_on_bundled_drive(name: str, report: Callable[[str], None]) -> None:
    f = _run(name)
    report(
        f"{name:<12} pitch RMS {f.pitch_rms_deg:.3f} deg (calibration alone "
        f"{f.calibration_rms_deg:.3f}), max {f.pitch_max_deg:.2f} deg, vanishing point on "
        f"{f.vanishing_point_share:.0%} of frames | motion stereo: obstacles found "
        f"{f.recall:.0%}, D on obstacles {f.precision:.0%}"
    )
    rms_ceiling, vp_floor, recall_floor, precision_floor = FLOORS[name]
    assert f.pitch_rms_deg <= rms_ceiling
    assert f.vanishing_point_share >= vp_floor
    assert f.recall >= recall_floor
    assert f.precision >= precision_floor
