"""One rendered camera panel: a frame with the layers a client asked for, and its read-out.

`render_view` is what the render worker runs: it reads the frame and its ground truth from
the drive, draws with `app.draw`, and returns image and text together, so a frame's picture
is never published with another frame's read-out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
import numpy.typing as npt

from app import draw
from app.state import ViewState
from core.camera import CameraModel
from core.io.frame import FrameInput
from core.io.groundtruth import FrameTruth

MPS_TO_KMH = 3.6
NS_PER_S = 1e9


class FrameSource(Protocol):
    """What the inspector needs of an open recording (`core.io.Drive` provides it)."""

    @property
    def name(self) -> str: ...
    @property
    def path(self) -> Path: ...
    @property
    def camera(self) -> CameraModel: ...
    @property
    def times_ns(self) -> npt.NDArray[np.int64] | tuple[int, ...]: ...
    @property
    def frame_rate_hz(self) -> float: ...
    @property
    def notes(self) -> tuple[str, ...]: ...
    def __len__(self) -> int: ...
    def frame(self, index: int) -> FrameInput: ...
    def truth(self, index: int) -> FrameTruth | None: ...
    def close(self) -> None: ...


@dataclass(frozen=True, eq=False)
class FrameView:
    """A rendered camera panel: frame index, (H + strip, W, 3) uint8 RGB picture, read-out."""

    frame: int
    image: draw.RgbImage
    readout: str


def readout_text(
    index: int, count: int, t_s: float, speed_mps: float, yaw_rate_radps: float
) -> str:
    """One line: frame index of count, time since the drive's start, speed, yaw rate.

    Speed and yaw rate are NaN in recordings without CAN; they read "n/a".
    """
    speed = f"{speed_mps * MPS_TO_KMH:.1f} km/h" if math.isfinite(speed_mps) else "speed n/a"
    yaw = (
        f"yaw {math.degrees(yaw_rate_radps):+.2f} deg/s"
        if math.isfinite(yaw_rate_radps)
        else "yaw n/a"
    )
    return f"frame {index} / {count - 1} | t {t_s:.2f} s | {speed} | {yaw}"


def render_view(drive: FrameSource, state: ViewState) -> FrameView:
    """The camera panel for `state.frame` of `drive` with the layers of `state`.

    Raises IndexError when the frame is outside the drive; reader errors pass through.
    """
    count = len(drive)
    if not 0 <= state.frame < count:
        raise IndexError(f"frame: expected an index in [0, {count}), got {state.frame}")
    frame = drive.frame(state.frame)
    rgb = draw.grey_to_rgb(frame.image)
    if state.layers.horizon:
        rgb = draw.draw_horizon(rgb, drive.camera)
    if state.layers.truth:
        rgb = draw.draw_truth(rgb, drive.truth(state.frame))
    if state.layers.radar:
        rgb = draw.draw_radar(rgb, frame.radar, drive.camera)
    t_s = (frame.t_ns - int(drive.times_ns[0])) / NS_PER_S
    text = readout_text(state.frame, count, t_s, frame.speed_mps, frame.yaw_rate_radps)
    return FrameView(state.frame, draw.add_caption(rgb, text), text)
