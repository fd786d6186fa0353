"""The off-the-shelf detectors of core.baselines, run on the frames the engine plays and
scored with the engine's scorers, so that `fusionscope evaluate --baselines` shows each
stage beside what a user would pick instead.

- Pedestrians: OpenCV's HOG people detector on the camera's row window, scored as the
  engine's pedestrians are (`objects.score_pedestrians`); the engine's figure to compare
  is its output after both filters (`RecordingReport.pedestrians["vehicles"]`).
- Pitch: the Hough-line vanishing point. On a frame where it finds none, a user keeps the
  calibrated pitch: that is what is scored, and the frame is counted in `hough_missing`.
- Obstacles: MOG2 on the camera's row window. It learns from every frame, truth or not,
  and is scored on the frames the engine's mask is scored on (the engine has a mask), with
  the same truth. Both are split by whether the car moves (the engine runs motion stereo)
  or stands (it runs background subtraction, and only moving objects count): MOG2 cannot
  undo the ego motion, and the moving half shows what that costs it.
- Time: each baseline call's wall time, and the engine's matching stage from the same
  frame (`StageTimings`), in ms; the caller sets the thread count (evaluate: one).
"""

from __future__ import annotations

import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TypeVar

from core.baselines import HogPeople, Mog2Obstacles, hough_pitch
from core.camera import CameraModel
from core.engine import FrameResult
from core.io.frame import FrameInput
from core.io.groundtruth import FrameTruth
from core.params import Params

from . import objects
from .counts import add_fields, sum_fields
from .objects import BoxScore, MaskScore, PitchScore

T = TypeVar("T")


@dataclass(frozen=True)
class Timing:
    """Milliseconds per frame, one entry per frame timed."""

    ms: tuple[float, ...] = ()

    @property
    def median_ms(self) -> float:
        return statistics.median(self.ms) if self.ms else math.nan

    def __add__(self, other: Timing) -> Timing:
        return add_fields(self, other)


@dataclass(frozen=True)
class MaskSplit:
    """An obstacle mask's score while the car moves and while it stands still."""

    moving: MaskScore = field(default_factory=MaskScore)
    still: MaskScore = field(default_factory=MaskScore)

    def __add__(self, other: MaskSplit) -> MaskSplit:
        return add_fields(self, other)


@dataclass(frozen=True)
class BaselineReport:
    """The baselines' figures and the engine's matching ones, on the same frames."""

    hog: BoxScore = field(default_factory=BoxScore)
    hog_time: Timing = field(default_factory=Timing)
    symmetry_time: Timing = field(default_factory=Timing)  # the engine's pedestrian stage
    hough: PitchScore = field(default_factory=PitchScore)
    hough_missing: int = 0  # frames without a Hough vanishing point
    hough_time: Timing = field(default_factory=Timing)
    pitch_time: Timing = field(default_factory=Timing)  # the engine's pitch stage
    mog2: MaskSplit = field(default_factory=MaskSplit)
    # the engine's mask, split the same way
    motion_stereo: MaskSplit = field(default_factory=MaskSplit)
    mog2_time: Timing = field(default_factory=Timing)
    motion_stereo_time: Timing = field(default_factory=Timing)  # the engine's motion-stereo stage

    def __add__(self, other: BaselineReport) -> BaselineReport:
        return add_fields(self, other)


def _split(score: MaskScore, still: bool) -> MaskSplit:
    return MaskSplit(still=score) if still else MaskSplit(moving=score)


def _timed(call: Callable[[], T]) -> tuple[T, float]:
    start = time.perf_counter()
    value = call()
    return value, (time.perf_counter() - start) * 1e3


class BaselineScorer:
    """Runs the baselines frame by frame beside the engine and accumulates their scores."""

    def __init__(self, params: Params, camera: CameraModel) -> None:
        self.params = params
        self.camera = camera
        self.rows_px = camera.row_window_px
        self.hog = HogPeople()
        self.mog2 = Mog2Obstacles()
        self.frames: list[BaselineReport] = []

    def add(
        self,
        frame: FrameInput,
        result: FrameResult,
        truth: FrameTruth | None,
        calibrated_rad: float,
        engine_mask: MaskScore | None,
    ) -> None:
        """One frame, in order; truth None: MOG2 learns it, nothing is scored. engine_mask:
        the engine's mask score on this frame (`evaluate._Scorer.add`), None without one;
        MOG2 is scored on the same frames."""
        image = frame.image
        mask, mog2_ms = _timed(lambda: self.mog2.update(image, self.rows_px))
        if truth is None:
            return
        p, i = self.params, frame.index
        timings = result.timings
        boxes, hog_ms = _timed(lambda: self.hog.detect(image, self.rows_px))
        hough, hough_ms = _timed(lambda: hough_pitch(image, self.camera))
        pitch_rad = calibrated_rad if hough.pitch_rad is None else hough.pitch_rad
        lo, hi = p.pedestrian.min_distance_m, p.pedestrian.max_distance_m
        engine, mog2 = MaskSplit(), MaskSplit()
        mask_times = Timing(), Timing()
        ms = result.motion_stereo
        if engine_mask is not None:
            still = ms.mode == "background_subtraction"
            first, stop = (
                ms.image_mask_first_row_px,
                ms.image_mask_first_row_px + len(ms.image_mask),
            )
            mog2_score = objects.score_mask(
                i, mask[first:stop], first, truth, p.motion_stereo, still
            )
            engine, mog2 = _split(engine_mask, still), _split(mog2_score, still)
            mask_times = Timing((timings.motion_stereo_ms,)), Timing((mog2_ms,))
        self.frames.append(
            BaselineReport(
                hog=objects.score_pedestrians(i, boxes, truth.objects, lo, hi),
                hog_time=Timing((hog_ms,)),
                symmetry_time=Timing((timings.pedestrian_ms,)),
                hough=objects.score_pitch(pitch_rad, truth.pitch_rad, calibrated_rad),
                hough_missing=int(hough.pitch_rad is None),
                hough_time=Timing((hough_ms,)),
                pitch_time=Timing((timings.pitch_ms,)),
                motion_stereo=engine,
                mog2=mog2,
                motion_stereo_time=mask_times[0],
                mog2_time=mask_times[1],
            )
        )

    def report(self) -> BaselineReport:
        return sum_fields(self.frames) if self.frames else BaselineReport()
