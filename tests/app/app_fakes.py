"""A small in-memory drive with the interface of `core.io.Drive`, for tests of app/ alone."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.io.frame import FrameInput, RadarTarget
from core.io.groundtruth import FrameTruth, TruthGuardRail, TruthObject

WIDTH_PX, HEIGHT_PX = 640, 480
FRAME_PERIOD_NS = 40_000_000
SPEED_MPS = 25.0
YAW_RATE_RADPS = 0.01


@dataclass(frozen=True)
class Recordings:
    """A recordings root and the recording the tests open."""

    root: Path
    name: str


def fake_camera() -> CameraModel:
    return CameraModel(
        Intrinsics.from_fov(WIDTH_PX, HEIGHT_PX, math.radians(50.0)),
        Extrinsics(height_m=1.3, x_m=1.5, pitch_rad=0.02),
    )


class FakeDrive:
    """`frames` frames of a grey ramp whose brightness grows with the index, one radar target
    20 m ahead, one car box and one guard rail per frame."""

    def __init__(self, frames: int = 10, name: str = "fake") -> None:
        self.name = name
        self.path = Path("/nonexistent") / name
        self.camera = fake_camera()
        self.times_ns = tuple(1_000_000_000 + i * FRAME_PERIOD_NS for i in range(frames))
        self.frame_rate_hz = 1e9 / FRAME_PERIOD_NS
        self.notes: tuple[str, ...] = ()
        self.closed = False

    def __len__(self) -> int:
        return len(self.times_ns)

    @property
    def has_truth(self) -> bool:
        return True

    def speed_at(self, t_ns: int) -> float:
        return SPEED_MPS

    def yaw_rate_at(self, t_ns: int) -> float:
        return YAW_RATE_RADPS

    def frame(self, index: int) -> FrameInput:
        ramp = np.tile(np.linspace(0, 120, WIDTH_PX, dtype=np.float64), (HEIGHT_PX, 1))
        image = (ramp + 10 * index).astype(np.uint8)
        target = RadarTarget(20.0, 0.0, -1.0, 1.0, x_m=20.0 + index, y_m=0.5)
        return FrameInput(
            index,
            self.times_ns[index],
            image,
            (target,),
            self.times_ns[index],
            speed_mps=SPEED_MPS,
            yaw_rate_radps=YAW_RATE_RADPS,
        )

    def truth(self, index: int) -> FrameTruth | None:
        car = TruthObject(
            7,
            "car",
            (280.0, 230.0, 360.0, 290.0),
            (20.0, 0.5, 0.0),
            (4.0, 1.8, 1.5),
            (0.0, 0.0),
            True,
            0.0,
        )
        rail = TruthGuardRail(3, "right", ((400.0, 300.0), (600.0, 420.0)))
        return FrameTruth(index, self.times_ns[index], 0.02, (car,), (rail,))

    def close(self) -> None:
        self.closed = True
