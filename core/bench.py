"""`fusionscope bench`: how fast each stage runs, against the paper's timing table.

Paper 000, section III, timed its stages on 640x300 images on a Pentium 4 at 3.0 GHz. Here
each stage runs on frames of a bundled drive (whose processed window is 640x300) on one
thread (`cv2.setNumThreads(1)`): every chosen frame is run `repeat` times after `warmup`
runs, and the median of all timed runs is reported with the paper's figure and the
speed-up. Stages that carry state across frames are given the state of the frame before,
rebuilt for every run, so each run does the same work.

Figures, not verdicts: the budget is printed beside the median, and nothing fails on time.
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from core.camera import CameraModel
    from core.io.frame import FrameInput
    from core.params import Params

# Paper 000, section III: "640x300 images using standard Pentium 4 at 3.0 GHz"
PAPER_MS = {"pitch": 4.0, "motion_stereo": 43.0}
# What this implementation promises on one core of a current machine
BUDGET_MS = {"pitch": 0.5, "motion_stereo": 1.0}
STAGES = tuple(PAPER_MS)


@dataclass(frozen=True)
class StageTiming:
    """Timing of one stage: median and 90th percentile over all timed runs (ms)."""

    median_ms: float
    p90_ms: float
    paper_ms: float
    speedup: float  # paper_ms / median_ms
    budget_ms: float
    runs: int
    frames: int
    image: str  # "WxH" of the processed rows


# A run: an untimed set-up that returns the call to time.
Run = Callable[[], Callable[[], object]]


def _time_runs(runs: Sequence[Run], warmup: int, repeat: int) -> list[float]:
    times: list[float] = []
    for run in runs:
        for _ in range(warmup):
            run()()
        for _ in range(repeat):
            timed = run()
            t0 = time.perf_counter()
            timed()
            times.append((time.perf_counter() - t0) * 1e3)
    return times


Pair = tuple["FrameInput", "FrameInput"]  # a frame and the one before it


def _pitch_runs(camera: CameraModel, pairs: Sequence[Pair], params: Params) -> list[Run]:
    """detect_pitch on each frame, with the previous frame's memory (horizon tracking)."""
    from core.pitch import detect_pitch

    runs: list[Run] = []
    for before, now in pairs:
        previous = detect_pitch(before.image, camera, params.pitch).memory

        def run(image=now.image, previous=previous) -> Callable[[], object]:
            return lambda: detect_pitch(image, camera, params.pitch, previous)

        runs.append(run)
    return runs


def _motion_stereo_runs(camera: CameraModel, pairs: Sequence[Pair], params: Params) -> list[Run]:
    """MotionStereo.update on each frame, its background built from the frame before (the
    calibrated pitch throughout: the work does not depend on it)."""
    from core.motion_stereo import MotionStereo

    runs: list[Run] = []
    for before, now in pairs:

        def run(before=before, now=now) -> Callable[[], object]:
            stage = MotionStereo(params.motion_stereo)
            stage.update(before.image, camera, None)
            return lambda: stage.update(now.image, camera, now.ego)

        runs.append(run)
    return runs


def bench_stages(
    stages: Sequence[str],
    recording: Path | str,
    params: Params | None = None,
    frames: int = 20,
    warmup: int = 5,
    repeat: int = 50,
) -> dict[str, StageTiming]:
    """Time each of `stages` (from STAGES) on `frames` frames spread over `recording`."""
    import cv2
    import numpy as np

    from core.io.drive import Drive
    from core.params import Params

    for stage in stages:
        if stage not in STAGES:
            raise ValueError(f"stage: expected one of {', '.join(STAGES)}, got {stage!r}")
    params = params or Params()
    cv2.setNumThreads(1)
    with Drive(recording) as drive:
        if len(drive) < 2:
            raise ValueError(f"{recording}: expected at least 2 frames to bench, got {len(drive)}")
        chosen = sorted({int(k) for k in np.linspace(1, len(drive) - 1, frames)})
        pairs = [(drive.frame(k - 1), drive.frame(k)) for k in chosen]
        camera = drive.camera
    first, stop = camera.row_window_px
    make = {"pitch": _pitch_runs, "motion_stereo": _motion_stereo_runs}
    timings = {}
    for stage in stages:
        times = _time_runs(make[stage](camera, pairs, params), warmup, repeat)
        median = float(np.median(times))
        timings[stage] = StageTiming(
            median_ms=median,
            p90_ms=float(np.percentile(times, 90)),
            paper_ms=PAPER_MS[stage],
            speedup=PAPER_MS[stage] / median,
            budget_ms=BUDGET_MS[stage],
            runs=len(times),
            frames=len(pairs),
            image=f"{camera.intrinsics.width_px}x{stop - first}",
        )
    return timings


def format_table(timings: dict[str, StageTiming]) -> str:
    lines = [
        f"{'stage':<14} {'median ms':>10} {'p90 ms':>8} {'budget ms':>10} "
        f"{'paper ms':>9} {'speed-up':>9}  image, runs"
    ]
    for name, t in timings.items():
        lines.append(
            f"{name:<14} {t.median_ms:>10.3f} {t.p90_ms:>8.3f} {t.budget_ms:>10.2f} "
            f"{t.paper_ms:>9.1f} {t.speedup:>8.1f}x  {t.image}, {t.runs} runs on {t.frames} frames"
        )
    return "\n".join(lines)


def format_json(timings: dict[str, StageTiming]) -> str:
    return json.dumps({"stages": {name: asdict(t) for name, t in timings.items()}}, indent=2)
