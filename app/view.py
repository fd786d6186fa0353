"""One rendered frame for one client: the camera image with the engine's overlays (A and B
side by side when comparing), the stage picture shown, the list of detections A and B
disagree on, and the read-out, all from the same frame.

`render_view` is what the render worker runs after the engine: it draws with `app.draw`,
`app.overlays` and `app.panels` and returns everything together, so a frame's picture is
never published with another frame's overlays or read-out. Also here: the CAN signals
around the playhead and the running median of the stage timings, as the page shows them.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Protocol

import cv2
import numpy as np
import numpy.typing as npt

from app import draw, overlays, panels
from app.annotation_view import SEED_KINDS, Seeds
from app.bird_eye import BirdEyeGeometry, bird_eye_geometry
from app.presenter_view import HeadlineFigures, headline_figures
from app.state import Layers, ViewState
from core.camera import CameraModel
from core.compare import Detection, detections, diff_detections
from core.engine import FrameResult, StageTimings
from core.io.frame import FrameInput
from core.io.groundtruth import FrameTruth
from core.params import Params

MPS_TO_KMH = 3.6
NS_PER_S = 1e9
CAN_WINDOW_HALF_S = 5.0  # the CAN plot shows this long before and after the playhead
AB_GAP_PX = 8  # between the A and B camera pictures
AB_GAP_COLOUR = (255, 255, 255)
STAGE_GAP_PX = 8  # between the camera picture and the stage picture under it
AB_BIRD_EYE_GAP_M = 2.0  # between the A and B bird's-eye views in the 3D scene
# the stage pictures' names, by `app.state.STAGES`
STAGE_TITLES = {
    "motion_stereo": "Motion stereo",
    "symmetry": "Symmetry",
    "pedestrians": "Pedestrians",
    "guard_rails": "Guard rails",
    "timings": "Timings",
    "none": "none",
}
# the state's layers as app.overlays names them (ground truth is app.draw's)
OVERLAY_OF_LAYER = {
    "radar": "radar",
    "areas": "search areas",
    "vehicles": "vehicles",
    "guardrails": "guard rails",
    "pedestrians": "pedestrians",
    "rejected": "rejected",  # vehicle boxes and pedestrians, with the reason
    "pruned": "pruned pedestrians",
    "strip": "pedestrian strip",
    "horizon": "pitch",
    "tracks": "tracks",
    "coasting": "coasting tracks",
    "confirmed": "confirmed tracks",
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
    @property
    def has_truth(self) -> bool: ...
    def __len__(self) -> int: ...
    def frame(self, index: int) -> FrameInput: ...
    def truth(self, index: int) -> FrameTruth | None: ...
    def speed_at(self, t_ns: int) -> float: ...
    def yaw_rate_at(self, t_ns: int) -> float: ...
    def close(self) -> None: ...


@dataclass(frozen=True, eq=False)
class FrameView:
    """A rendered frame: its index, the (H + strip, W, 3) uint8 RGB camera picture (A and B
    side by side, (H + strip, 2 W + gap, 3), when comparing), the same with the stage
    picture shown under it (`stage_under`; the camera picture alone when none is shown),
    which is what the inspector's camera panel shows, the read-out line, set A's stage
    timings, and the markdown list of detections only A or only B has ("" when not
    comparing); the bird's-eye views
    as (geometry, ground texture) for A, and B beside it, when that panel is on; preview:
    a result in it is the engine's preview (`FusionEngine.preview`), to be replaced by the
    exact one; settling: a result in it is not from the start yet (`app.engines`): its track
    ids will change when it is; annotation: when the tab annotates, the bare frame as RGB
    and what the engine found on it under A, to seed annotations from; figures: A's headline
    figures (`app.presenter_view`)."""

    frame: int
    image: draw.RgbImage
    with_stage: draw.RgbImage
    readout: str
    timings: StageTimings
    diff: str = ""
    bird_eyes: tuple[tuple[BirdEyeGeometry, draw.RgbImage], ...] = ()
    preview: bool = False
    annotation: tuple[draw.RgbImage, Seeds] | None = None
    figures: HeadlineFigures | None = None
    settling: bool = False


PREVIEW_NOTE = "preview: replaying under the new values"
SETTLING_NOTE = "track ids settling: playing the drive from its start"


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


def timings_markdown(t: StageTimings, median: StageTimings | None = None, frames: int = 0) -> str:
    """This frame's stage times as a markdown table, beside the running median over the
    last `frames` frames shown when given."""
    rows = [
        ("pitch", "pitch_ms"),
        ("motion stereo", "motion_stereo_ms"),
        ("search areas + guard rails", "guardrail_ms"),
        ("vehicles", "vehicle_ms"),
        ("pedestrians", "pedestrian_ms"),
        ("tracking", "tracking_ms"),
        ("**total**", "total_ms"),
    ]
    if median is None:
        head = "| stage | ms |\n| --- | ---: |\n"
        return head + "\n".join(f"| {n} | {getattr(t, a):.2f} |" for n, a in rows)
    head = f"| stage | ms | median of {frames} |\n| --- | ---: | ---: |\n"
    return head + "\n".join(
        f"| {n} | {getattr(t, a):.2f} | {getattr(median, a):.2f} |" for n, a in rows
    )


def render_view(
    drive: FrameSource,
    state: ViewState,
    result: FrameResult,
    frame: FrameInput,
    result_b: FrameResult | None = None,
) -> FrameView:
    """Frame `state.frame` of `drive` (`frame`, and the engine's `result` on it; `result_b`
    under set B when comparing) with the layers and panels of `state`. Raises ValueError
    when a result or `frame` is of another frame."""
    indices = (result.index, frame.index) + (() if result_b is None else (result_b.index,))
    if any(i != state.frame for i in indices):
        raise ValueError(f"result, frame: expected frame {state.frame}, got {indices}")
    t_s = seconds_from_start(drive, frame.t_ns)
    text = readout_text(state.frame, len(drive), t_s, frame.speed_mps, frame.yaw_rate_radps)
    preview = result.preview or (result_b is not None and result_b.preview)
    settling = not preview and not (result.from_start and (result_b is None or result_b.from_start))
    if preview:
        text += f" | {PREVIEW_NOTE}"
    elif settling:
        text += f" | {SETTLING_NOTE}"
    picture = camera_picture(drive, state, result, frame)
    diff = ""
    if result_b is not None:
        picture_b = camera_picture(drive, state, result_b, frame)
        picture = side_by_side(
            draw.add_caption(picture, "A | " + text), draw.add_caption(picture_b, "B")
        )
        diff = diff_markdown(result, result_b)
    else:
        picture = draw.add_caption(picture, text)
    bird_eyes: tuple[tuple[BirdEyeGeometry, draw.RgbImage], ...] = ()
    if state.panels.bird_eye:
        bird_eyes = (bird_eye_view(result, state.params, state.layers),)
        if result_b is not None and state.params_b is not None:
            offset = b_offset_y_m(state.params)
            bird_eyes += (bird_eye_view(result_b, state.params_b, state.layers, offset),)
    annotation = None
    if state.annotating:
        annotation = (draw.grey_to_rgb(frame.image), seeds(result))
    stage = stage_picture(result, state)
    return FrameView(
        state.frame,
        picture,
        picture if stage is None else stage_under(picture, stage),
        text,
        result.timings,
        diff,
        bird_eyes,
        preview,
        annotation,
        headline_figures(result),
        settling,
    )


def seeds(result: FrameResult) -> Seeds:
    """What annotation can take from a frame's result: its vehicles and kept pedestrians
    (`core.compare.detections`), each searched radar target's base point and distance, and
    the confirmed vehicle and pedestrian tracks."""
    boxes = tuple((d.kind, d.box_px) for d in detections(result) if d.kind in SEED_KINDS)
    bases = tuple((a.base_px[0], a.base_px[1], a.target.x_m) for a in result.areas)
    tracks = tuple(
        (t.kind, t.id, t.outline_px)
        for t in (*result.tracked_vehicles, *result.tracked_pedestrians)
    )
    return Seeds(result.index, boxes, bases, tracks)


def bird_eye_view(
    result: FrameResult, params: Params, layers: Layers, offset_y_m: float = 0.0
) -> tuple[BirdEyeGeometry, draw.RgbImage]:
    """The 3D bird's-eye view of `result` under `layers`: its geometry and the bird's-eye
    image as texture."""
    texture = draw.grey_to_rgb(result.motion_stereo.bird_eye)
    return bird_eye_geometry(result, params, offset_y_m, layers), texture


def b_offset_y_m(params: Params) -> float:
    """Where set B's bird's-eye view goes: to the right of A's road, `AB_BIRD_EYE_GAP_M`
    apart."""
    _, _, y_min_m, y_max_m = panels.bird_eye_extent_m(params.motion_stereo)
    return -(y_max_m - y_min_m + AB_BIRD_EYE_GAP_M)


def camera_picture(
    drive: FrameSource, state: ViewState, result: FrameResult, frame: FrameInput
) -> draw.RgbImage:
    """The camera frame with the layers of `state` drawn from `result`."""
    rgb = draw.grey_to_rgb(frame.image)
    if state.layers.truth:
        rgb = draw.draw_truth(rgb, drive.truth(state.frame))
    overlays.put_layers(rgb, result, overlay_names(state.layers))
    return rgb


def side_by_side(a: draw.RgbImage, b: draw.RgbImage) -> draw.RgbImage:
    """`a`, a white gap of AB_GAP_PX and `b`, left to right (both of one height)."""
    gap = draw.filled(a.shape[0], AB_GAP_PX, AB_GAP_COLOUR)
    return np.ascontiguousarray(np.hstack([a, gap, b]))


def stage_under(picture: draw.RgbImage, stage: draw.RgbImage) -> draw.RgbImage:
    """`picture` with `stage` under it, a white gap of STAGE_GAP_PX between, as one picture
    of `picture`'s width: `stage` shrunk to that width (aspect kept) when wider, centred on
    white when narrower.

    The inspector sends the page this one picture, not two: playing highway at 4x (40
    frames a second asked) in headless Chromium on two cores, the page showed 4-10 frames
    a second as two pictures and 17-28 as one (`scripts/bench_inspector.py`).

    Shrinking is bilinear down to half the width (the stage pictures are 806-1060 px wide
    for a 640 px camera; their thinnest marks, 1 px lines, stay visible and even) and area
    averaging below, where bilinear would drop pixels. Area averaging at these ratios took
    4-5 ms a frame, bilinear 0.7."""
    draw.require_rgb_image("picture", picture)
    draw.require_rgb_image("stage", stage)
    width = picture.shape[1]
    h, w = stage.shape[:2]
    if w > width:
        size = (width, max(1, round(h * width / w)))
        how = cv2.INTER_LINEAR if 2 * width >= w else cv2.INTER_AREA
        stage = np.asarray(cv2.resize(stage, size, interpolation=how), dtype=np.uint8)
    out = draw.filled(picture.shape[0] + STAGE_GAP_PX + stage.shape[0], width, AB_GAP_COLOUR)
    out[: picture.shape[0]] = picture
    left = (width - stage.shape[1]) // 2
    out[picture.shape[0] + STAGE_GAP_PX :, left : left + stage.shape[1]] = stage
    return out


def diff_markdown(a: FrameResult, b: FrameResult) -> str:
    """Markdown: the detections set A has that B lacks, and the reverse."""
    diff = diff_detections(a, b)

    def listed(title: str, found: Sequence[Detection]) -> str:
        items = "".join(f"\n- {d.label}" for d in found) if found else "\n- none"
        return f"**{title}**{items}"

    return "\n\n".join(
        [
            listed("A has, B lacks", diff.only_a),
            listed("B has, A lacks", diff.only_b),
            f"{diff.matched} detections in both",
        ]
    )


def overlay_names(layers: Layers) -> list[str]:
    """The `app.overlays.LAYERS` names of the layers switched on."""
    return [OVERLAY_OF_LAYER[name] for name in OVERLAY_OF_LAYER if getattr(layers, name)]


def stage_picture(result: FrameResult, state: ViewState) -> draw.RgbImage | None:
    """The stage picture `state.panels` shows under the camera; None for "timings" (a
    table) and "none"."""
    threshold = state.params.pedestrian.symmetry_threshold
    makers = {
        "motion_stereo": lambda: panels.motion_stereo_panel(result.motion_stereo),
        "symmetry": lambda: panels.symmetry_panel(result.vehicle.targets),
        "pedestrians": lambda: panels.pedestrian_symmetry_panel(result.pedestrian, threshold),
        "guard_rails": lambda: panels.guard_rail_panel(result.guardrail.checks, result.areas),
    }
    make = makers.get(state.panels.stage)
    return None if make is None else make()


@dataclass(frozen=True, eq=False)
class CanSeries:
    """A drive's CAN signals at its camera frames: seconds from the first frame, speed in
    km/h and yaw rate in deg/s (NaN where the drive has none)."""

    t_s: npt.NDArray[np.float64]
    speed_kmh: npt.NDArray[np.float64]
    yaw_rate_degps: npt.NDArray[np.float64]


def can_series(drive: FrameSource) -> CanSeries | None:
    """The drive's CAN signals at its frames; None when it has neither speed nor yaw rate
    (not measured, nothing assumed)."""
    times = [int(t) for t in drive.times_ns]
    series = CanSeries(
        np.array([(t - times[0]) / NS_PER_S for t in times], dtype=np.float64),
        np.array([drive.speed_at(t) * MPS_TO_KMH for t in times], dtype=np.float64),
        np.array([math.degrees(drive.yaw_rate_at(t)) for t in times], dtype=np.float64),
    )
    known = np.isfinite(series.speed_kmh).any() or np.isfinite(series.yaw_rate_degps).any()
    return series if known else None


def can_window(
    series: CanSeries, frame: int, half_width_s: float = CAN_WINDOW_HALF_S
) -> tuple[npt.NDArray[np.float64], ...]:
    """The CAN plot's data around frame `frame`: (seconds from the playhead, speed_kmh,
    yaw_rate_degps) of the frames within `half_width_s` of it, so the playhead is at 0."""
    t_now = series.t_s[frame]
    near = np.flatnonzero(np.abs(series.t_s - t_now) <= half_width_s)
    return series.t_s[near] - t_now, series.speed_kmh[near], series.yaw_rate_degps[near]


def median_timings(timings: Sequence[StageTimings]) -> StageTimings:
    """Stage by stage, the median of `timings` (at least one)."""
    if not timings:
        raise ValueError("timings: expected at least one frame's timings, got none")
    return StageTimings(
        *(statistics.median(getattr(t, f.name) for t in timings) for f in fields(StageTimings))
    )


def check_clip(drive: FrameSource, first_frame: int, last_frame: int) -> None:
    """ValueError naming first_frame or last_frame unless they are frames of `drive` in
    order (a clip, both included)."""
    count = len(drive)
    if not 0 <= first_frame < count:
        raise ValueError(
            f"first_frame: expected a frame of {drive.path} (0 .. {count - 1}), got {first_frame}"
        )
    if not first_frame <= last_frame < count:
        raise ValueError(
            f"last_frame: expected a frame of {drive.path} from first_frame {first_frame} to "
            f"{count - 1}, got {last_frame}"
        )


def seconds_from_start(drive: FrameSource, t_ns: int) -> float:
    """The time `t_ns` as seconds from the drive's first frame (as the read-out and the
    exports' banner give it)."""
    return (t_ns - int(drive.times_ns[0])) / NS_PER_S
