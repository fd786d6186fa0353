"""One rendered frame for one client: the camera image with the engine's overlays, the stage
panels and the read-out, all from the same `FrameResult`.

`render_view` is what the render worker runs after the engine: it draws with `app.draw`,
`app.overlays` and `app.panels` and returns everything together, so a frame's picture is
never published with another frame's overlays or read-out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

import numpy as np
import numpy.typing as npt

from app import draw, overlays, panels
from app.state import Layers, ViewState
from core.camera import CameraModel
from core.engine import FrameResult, StageTimings
from core.io.frame import FrameInput
from core.io.groundtruth import FrameTruth

MPS_TO_KMH = 3.6
NS_PER_S = 1e9
# the state's layers as app.overlays names them (ground truth is app.draw's)
OVERLAY_OF_LAYER = {
    "radar": "radar",
    "areas": "search areas",
    "vehicles": "vehicles",
    "guardrails": "guard rails",
    "pedestrians": "pedestrians",
    "pruned": "pruned pedestrians",
    "strip": "pedestrian strip",
    "horizon": "pitch",
    "tracks": "tracks",
}


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
    """A rendered frame: its index, the (H + strip, W, 3) uint8 RGB camera picture, the
    read-out line, the engine's stage timings, and the stage panels as (title, RGB image)."""

    frame: int
    image: draw.RgbImage
    readout: str
    timings: StageTimings
    panels: tuple[tuple[str, draw.RgbImage], ...] = ()


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


def timings_markdown(t: StageTimings) -> str:
    """This frame's stage times as a markdown table."""
    rows = [
        ("pitch", t.pitch_ms),
        ("motion stereo", t.motion_stereo_ms),
        ("search areas + guard rails", t.guardrail_ms),
        ("vehicles", t.vehicle_ms),
        ("pedestrians", t.pedestrian_ms),
        ("tracking", t.tracking_ms),
        ("**total**", t.total_ms),
    ]
    return "| stage | ms |\n| --- | ---: |\n" + "\n".join(f"| {n} | {ms:.2f} |" for n, ms in rows)


def render_view(
    drive: FrameSource, state: ViewState, result: FrameResult, frame: FrameInput
) -> FrameView:
    """Frame `state.frame` of `drive` (`frame`, and the engine's `result` on it) with the
    layers of `state`. Raises ValueError when `result` or `frame` is of another frame."""
    if not (result.index == frame.index == state.frame):
        raise ValueError(
            f"result, frame: expected frame {state.frame}, got {result.index} and {frame.index}"
        )
    rgb = draw.grey_to_rgb(frame.image)
    if state.layers.truth:
        rgb = draw.draw_truth(rgb, drive.truth(state.frame))
    rgb = overlays.draw_layers(rgb, result, overlay_names(state.layers))
    t_s = (frame.t_ns - int(drive.times_ns[0])) / NS_PER_S
    text = readout_text(state.frame, len(drive), t_s, frame.speed_mps, frame.yaw_rate_radps)
    return FrameView(
        state.frame, draw.add_caption(rgb, text), text, result.timings, stage_panels(result, state)
    )


def overlay_names(layers: Layers) -> list[str]:
    """The `app.overlays.LAYERS` names of the layers switched on."""
    return [OVERLAY_OF_LAYER[name] for name in OVERLAY_OF_LAYER if getattr(layers, name)]


def stage_panels(result: FrameResult, state: ViewState) -> tuple[tuple[str, draw.RgbImage], ...]:
    """The stage images beside the camera: (tab title, RGB image)."""
    threshold = state.params.pedestrian.symmetry_threshold
    return (
        ("Motion stereo", panels.motion_stereo_panel(result.motion_stereo)),
        ("Symmetry", panels.symmetry_panel(result.vehicle.targets)),
        ("Pedestrians", panels.pedestrian_symmetry_panel(result.pedestrian, threshold)),
        ("Guard rails", panels.guard_rail_panel(result.guardrail.checks, result.areas)),
    )
