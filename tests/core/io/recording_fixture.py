"""A small recording with known content, written with RecordingWriter (shared by the tests)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.io import Calibration, FrameTruth, RadarMount, RadarTarget, RecordingWriter, TruthObject

WIDTH_PX, HEIGHT_PX = 64, 48
N_FRAMES = 5
CAMERA_PERIOD_NS = 100_000_000  # 10 Hz
RADAR_PERIOD_NS = 50_000_000  # 20 Hz, 10 ms after the camera
RADAR_LAG_NS = 10_000_000
CAN_PERIOD_NS = 20_000_000
MOUNT = RadarMount(x_m=3.5, y_m=0.2, z_m=0.5, yaw_rad=0.05)

CALIBRATION = Calibration(
    CameraModel(
        Intrinsics.from_fov(WIDTH_PX, HEIGHT_PX, math.radians(60.0)),
        Extrinsics(height_m=1.2, x_m=1.5, pitch_rad=0.01),
        rows_used_px=(8, 40),
    ),
    MOUNT,
)


def image(i: int) -> np.ndarray:
    """Frame i: a gradient plus a bright square at column 5 + 8 i (distinct per frame)."""
    img = (np.arange(WIDTH_PX, dtype=np.uint8)[None, :] * 3 + np.uint8(i)).repeat(HEIGHT_PX, 0)
    img[10:20, 5 + 8 * i : 15 + 8 * i] = 255
    return img


def targets(k: int) -> list[RadarTarget]:
    """Radar scan k: k + 1 targets (scan 0 has one) at known range/azimuth."""
    return [
        RadarTarget(
            range_m=20.0 + k + 0.123 * j,
            azimuth_rad=0.01 * (j - 1),
            range_rate_mps=-1.5 + j,
            amplitude=10.0 + j,
            x_m=0.0,
            y_m=0.0,
        )
        for j in range(k + 1)
    ]


def speed_mps(t_ns: int) -> float:
    return 20.0 + 0.5 * t_ns / 1e9


def yaw_rate_radps(t_ns: int) -> float:
    return math.radians(2.0) - math.radians(4.0) * t_ns / 1e9


def truth() -> list[FrameTruth]:
    return [
        FrameTruth(
            i,
            i * CAMERA_PERIOD_NS,
            0.01,
            (
                TruthObject(
                    1,
                    "car",
                    (5.0 + 8 * i, 10.0, 15.0 + 8 * i, 20.0),
                    (20.0, 0.5, 0.0),
                    (4.5, 1.8, 1.5),
                    (-1.0, 0.0),
                    True,
                    0.0,
                ),
            ),
            (),
        )
        for i in range(N_FRAMES)
        if i != 3
    ]


def write_recording(out: Path) -> Path:
    with RecordingWriter(
        out,
        name="tiny",
        description="five known frames",
        calibration=CALIBRATION,
        generator={"scenario": "test", "seed": 1},
    ) as w:
        for i in range(N_FRAMES):
            w.add_image(i * CAMERA_PERIOD_NS, image(i))
        for k in range(2 * N_FRAMES):
            w.add_radar_scan(k * RADAR_PERIOD_NS + RADAR_LAG_NS, targets(k))
        for t in range(0, N_FRAMES * CAMERA_PERIOD_NS, CAN_PERIOD_NS):
            w.add_vehicle_state(t, speed_mps(t), yaw_rate_radps(t))
        w.set_groundtruth(truth())
    return out
