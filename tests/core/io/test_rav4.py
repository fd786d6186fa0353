"""The real RAV4: its still frame and CAN log imported, its radar tracks on the cars they saw.

The import is the `rav4` fixture of tests/conftest.py, which says how the camera's pose was
estimated. The boxes below were measured on the frame.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
import pytest

from app.draw import draw_radar, grey_to_rgb
from core.io import Drive

SOURCE_SIZE_PX = (1164, 874)
# Pixel-edge boxes (left, top, right, bottom) on the 1164x874 frame.
SILVER_CAR_AHEAD_PX = (565, 380, 624, 432)
WHITE_SUV_RIGHT_PX = (695, 355, 830, 452)


def scaled(box: tuple[int, int, int, int], width_px: int, height_px: int) -> np.ndarray:
    sx, sy = width_px / SOURCE_SIZE_PX[0], height_px / SOURCE_SIZE_PX[1]
    return np.array(box, dtype=float) * [sx, sy, sx, sy]


def test_radar_tracks_fall_on_the_cars_they_measured(rav4: Path, tmp_path: Path) -> None:
    with Drive(rav4) as drive:
        frame = drive.frame(0)
        camera = drive.camera
    i = camera.intrinsics
    assert frame.radar_t_ns is not None
    assert abs(frame.radar_t_ns - frame.t_ns) < 50_000_000
    ahead = min(frame.radar, key=lambda t: np.hypot(t.x_m - 29.3, t.y_m))
    right = min(frame.radar, key=lambda t: np.hypot(t.x_m - 18.3, t.y_m + 2.9))
    assert ahead.x_m == pytest.approx(29.3, abs=0.3) and abs(ahead.y_m) < 0.3
    assert right.x_m == pytest.approx(18.3, abs=0.3) and right.y_m == pytest.approx(-2.9, abs=0.3)

    rgb = draw_radar(grey_to_rgb(frame.image), frame.radar, camera)
    for box in (SILVER_CAR_AHEAD_PX, WHITE_SUV_RIGHT_PX):
        x0, y0, x1, y1 = scaled(box, i.width_px, i.height_px).round().astype(int)
        cv2.rectangle(rgb, (x0, y0), (x1, y1), (0, 255, 0), 1)
    cv2.imwrite(str(tmp_path / "rav4_radar_overlay.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))

    for target, box in ((ahead, SILVER_CAR_AHEAD_PX), (right, WHITE_SUV_RIGHT_PX)):
        # The radar point on the road: the bottom of the car, between its sides.
        uv, in_front = camera.project(np.array([[target.x_m, target.y_m, 0.0]]))
        x0, y0, x1, y1 = scaled(box, i.width_px, i.height_px)
        u, v = uv[0]
        assert in_front[0]
        assert x0 <= u <= x1, (target, u, (x0, x1))
        # The base lies within the lowest fifth of the box (a few pixels of pitch error).
        assert y1 - (y1 - y0) / 5 <= v <= y1 + 3, (target, v, (y0, y1))


def test_speed_and_yaw_rate_in_si_units(rav4: Path) -> None:
    with Drive(rav4) as drive:
        frame = drive.frame(0)
        v = drive.vehicle_signals
    assert frame.speed_mps == pytest.approx(29.38 / 3.6, abs=0.05)
    assert 5.0 < v.speed_mps.max() < 25.0
    # The gyro reads in 0.244 deg/s steps, here as rad/s.
    steps = np.unique(np.round(np.diff(np.unique(v.yaw_rate_radps)), 6))
    assert steps.min() == pytest.approx(np.radians(0.244), rel=0.05)
