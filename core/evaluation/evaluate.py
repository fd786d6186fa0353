"""One recording played through the engine and scored against its ground truth.

`evaluate_recording` runs `FusionEngine` over every frame, in order, and scores each frame
that has ground truth (frames without it are not counted at all, neither as hits nor as
misses) with `vehicles` and `objects`, and the tracked output with `mot`. `total` adds
recordings together; events are per recording (a vehicle id is a recording's own), so the
total's events are the sum of the recordings'.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TypeVar

from core.bench import GuardRailSavings, guard_rail_savings, one_thread
from core.engine import FrameResult, Frames, FusionEngine
from core.io.drive import Drive
from core.io.errors import RecordingError
from core.io.frame import FrameInput
from core.io.groundtruth import FrameTruth
from core.params import Params
from core.pedestrian import FUSION_VERDICTS, Verdict
from core.tracking import Track

from . import objects, vehicles
from .baselines import BaselineReport, BaselineScorer
from .counts import sum_fields
from .mot import MotAccumulator, MotScore
from .objects import BoxScore, MaskScore, PitchScore, RailScore
from .vehicles import Estimate, EventStats, FrameStats, FrameVehicles

# the pedestrian outputs compared: the detector alone (its candidates that passed the size
# and perspective constraints), after the motion-stereo filter, after the vehicle filter
# (paper 000's output), after the radar filter, the image-motion filter and the HOG
# verification (all three beyond the paper; the last is the engine's output,
# FINAL_PEDESTRIAN_STAGE)
PEDESTRIAN_STAGES: dict[str, tuple[Verdict, ...]] = {
    "symmetry": FUSION_VERDICTS,
    "motion_stereo": ("pedestrian", "vehicle", "radar", "image_motion", "hog"),
    "vehicles": ("pedestrian", "radar", "image_motion", "hog"),
    "radar": ("pedestrian", "image_motion", "hog"),
    "image_motion": ("pedestrian", "hog"),
    "hog": ("pedestrian",),
}
FINAL_PEDESTRIAN_STAGE = "hog"

Progress = Callable[[int, int], None]
T = TypeVar("T")


@dataclass(frozen=True)
class TrackingReport:
    """Tracked output scored as the per-frame detections are, plus CLEAR-MOT and IDF1."""

    vehicles: FrameStats
    events: EventStats
    pedestrians: BoxScore
    guardrails: RailScore
    vehicle_mot: MotScore
    pedestrian_mot: MotScore


@dataclass(frozen=True)
class RecordingReport:
    """Every figure of one recording (or a total: name "total")."""

    name: str
    frames: int  # frames with ground truth, the ones scored
    vehicles: FrameStats
    events: EventStats
    guardrails: RailScore
    pedestrians: dict[str, BoxScore]  # PEDESTRIAN_STAGES
    motion_stereo: MaskScore
    pitch: PitchScore
    tracking: TrackingReport
    # paper 002's table I (None when not timed); a total holds each recording's
    guardrail_timing: tuple[tuple[str, GuardRailSavings], ...] = field(default=())
    # core.baselines on the same frames (None when not asked for)
    baselines: BaselineReport | None = None
    # what was skipped or repaired on reading the recording (Drive.warnings); a total holds
    # each recording's, named
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True)
class ErrorListing:
    """One kind of error a report lists under "Where the errors are": kind, e.g. "vehicle
    FN"; title, the listing's row in `fusionscope evaluate`; at, (frame index, id) pairs;
    ids: whether the ids name something (a truth id, a radar target) or only count."""

    kind: str
    title: str
    at: tuple[tuple[int, int], ...]
    ids: bool = True


def error_listings(r: RecordingReport) -> tuple[ErrorListing, ...]:
    """The errors of `r` by kind: vehicle FN, RFN and FP, guard-rail FN and FP (the vehicles
    labelled guard rail are among the FP), pedestrians missed and false boxes after the
    fusion filters (the engine's output). NVO are right answers and the tracked output
    repeats the detections' frames, so neither is listed."""
    final = r.pedestrians[FINAL_PEDESTRIAN_STAGE]
    return (
        ErrorListing("vehicle FN", "vehicle FN (truth id: frames)", r.vehicles.fn_at),
        ErrorListing("vehicle RFN", "vehicle RFN (truth id: frames)", r.vehicles.rfn_at),
        ErrorListing("vehicle FP", "vehicle FP (radar target: frames)", r.vehicles.fp_at),
        ErrorListing("guard-rail FN", "guard-rail FN (radar target: frames)", r.guardrails.fn_at),
        ErrorListing("guard-rail FP", "guard-rail FP (radar target: frames)", r.guardrails.fp_at),
        ErrorListing(
            "pedestrian FN",
            "pedestrians missed after the fusion filters (truth id: frames)",
            final.missed_at,
        ),
        ErrorListing(
            "pedestrian FP",
            "pedestrian FP after the fusion filters (frames)",
            final.false_at,
            False,
        ),
    )


def _vehicle_estimates(result: FrameResult) -> list[Estimate]:
    return [
        Estimate(v.distance_m, v.lateral_m, v.width_m, v.target_indices, v.outline_px)
        for v in result.vehicle.vehicles
    ]


def _track_estimates(result: FrameResult) -> list[Estimate]:
    # a track's source_index indexes the frame's vehicles, then its appearance matches
    found = result.vehicle.vehicles + tuple(m.vehicle for m in result.appearance)
    return [
        Estimate(
            t.x_m,
            t.y_m,
            t.width_m,
            () if t.source_index is None else found[t.source_index].target_indices,
            t.outline_px,
        )
        for t in result.tracked_vehicles
    ]


def _truth_vehicles(
    truth: FrameTruth,
) -> tuple[list[tuple[int, objects.Box]], list[objects.Box]]:
    """The framed vehicles the radar saw, to be tracked, and the boxes of those it did not,
    ignored: a radar-guided tracker cannot follow what the radar never returned."""
    framed = [o for o in truth.objects if vehicles.framed(o)]
    seen = [(o.id, o.box_px) for o in framed if o.radar_seen]
    return seen, [o.box_px for o in framed if not o.radar_seen]


def _truth_people(truth: FrameTruth, params: Params) -> list[tuple[int, objects.Box]]:
    p = params.pedestrian
    return [
        (o.id, o.box_px)
        for o in truth.objects
        if objects.visible_person(o, p.min_distance_m, p.max_distance_m)
    ]


def _track_boxes(tracks: Sequence[Track]) -> list[tuple[int, objects.Box]]:
    return [(t.id, t.outline_px) for t in tracks]


class _Scorer:
    """Accumulates one recording's figures frame by frame."""

    def __init__(self, params: Params) -> None:
        self.params = params
        self.frames = 0
        self.vehicle_frames: list[FrameVehicles] = []
        self.tracked_frames: list[FrameVehicles] = []
        self.rails: list[RailScore] = []
        self.tracked_rails: list[RailScore] = []
        self.pedestrians: dict[str, list[BoxScore]] = {stage: [] for stage in PEDESTRIAN_STAGES}
        self.tracked_pedestrians: list[BoxScore] = []
        self.mask: list[MaskScore] = [MaskScore()]  # none on a first frame
        self.pitch: list[PitchScore] = []
        self.vehicle_mot = MotAccumulator()
        self.pedestrian_mot = MotAccumulator()

    def add(
        self, frame: FrameInput, result: FrameResult, truth: FrameTruth, calibrated_rad: float
    ) -> MaskScore | None:
        """Score one frame; returns its motion-stereo mask score (None when the engine has
        no mask on it), which the baselines split by whether the car moves."""
        p = self.params
        i = frame.index
        self.frames += 1
        tolerance = p.vehicle.refined_error_m
        self.vehicle_frames.append(
            vehicles.score_frame(
                i, truth.objects, frame.radar, result.areas, _vehicle_estimates(result), tolerance
            )
        )
        self.tracked_frames.append(
            vehicles.score_frame(
                i, truth.objects, frame.radar, result.areas, _track_estimates(result), tolerance
            )
        )
        # the true pitch when the truth has one (NaN on annotated drives: the detected one)
        camera = result.camera
        if not math.isnan(truth.pitch_rad):
            camera = camera.with_pitch(truth.pitch_rad)
        rails_m = objects.rails_on_road_m(truth, camera)
        checked = [c.target_index for c in result.guardrail.checks]
        self.rails.append(
            objects.score_rails(
                i, checked, result.guardrail.guard_rail_targets, frame.radar, truth, rails_m
            )
        )
        self.tracked_rails.append(
            objects.score_rails(i, checked, result.tracked_guard_rails, frame.radar, truth, rails_m)
        )
        lo, hi = p.pedestrian.min_distance_m, p.pedestrian.max_distance_m
        for stage, verdicts in PEDESTRIAN_STAGES.items():
            boxes = [
                c.extended_box_px for c in result.pedestrian.candidates if c.verdict in verdicts
            ]
            self.pedestrians[stage].append(
                objects.score_pedestrians(i, boxes, truth.objects, lo, hi)
            )
        tracked = [t.box_px for t in result.tracked_pedestrians]
        self.tracked_pedestrians.append(
            objects.score_pedestrians(i, tracked, truth.objects, lo, hi)
        )
        ms = result.motion_stereo
        mask = None
        if ms.mode in ("motion_stereo", "background_subtraction"):
            mask = objects.score_mask(
                i,
                ms.image_mask,
                ms.image_mask_first_row_px,
                truth,
                p.motion_stereo,
                ms.mode == "background_subtraction",
            )
            self.mask.append(mask)
        self.pitch.append(
            objects.score_pitch(result.pitch.pitch_rad, truth.pitch_rad, calibrated_rad)
        )
        seen, unseen = _truth_vehicles(truth)
        self.vehicle_mot.update(i, seen, _track_boxes(result.tracked_vehicles), unseen)
        self.pedestrian_mot.update(
            i, _truth_people(truth, p), _track_boxes(result.tracked_pedestrians)
        )
        return mask

    def report(self, name: str) -> RecordingReport:
        events = vehicles.event_stats(self.vehicle_frames)
        return RecordingReport(
            name=name,
            frames=self.frames,
            vehicles=vehicles.frame_stats(self.vehicle_frames),
            events=events,
            guardrails=sum_fields(self.rails),
            pedestrians={k: sum_fields(v) for k, v in self.pedestrians.items()},
            motion_stereo=sum_fields(self.mask),
            pitch=sum_fields(self.pitch),
            tracking=TrackingReport(
                vehicles=vehicles.frame_stats(self.tracked_frames),
                events=vehicles.event_stats(self.tracked_frames),
                pedestrians=sum_fields(self.tracked_pedestrians),
                guardrails=sum_fields(self.tracked_rails),
                vehicle_mot=self.vehicle_mot.score(),
                pedestrian_mot=self.pedestrian_mot.score(),
            ),
        )


def evaluate_recording(
    path: Path | str,
    params: Params,
    progress: Progress | None = None,
    timing: bool = True,
    baselines: bool = False,
    frames: Frames | None = None,
    strict: bool = False,
) -> RecordingReport:
    """Play the recording at `path` through the engine and score it (module docstring); a
    frame that cannot be read is not scored and is named in the report's warnings (the
    engine starts over after it), or with `strict` its RecordingError is raised;
    timing: also time paper 002's table I (VD, GRD, OBM) on it, one thread; baselines:
    also run and score core.baselines on the same frames (evaluation.baselines); frames:
    the recording's frames already open (the inspector's drive, which keeps the frames it
    decoded) to read instead of decoding them again; the ground truth is read from `path`
    as it is now. RecordingError when it cannot be read; ValueError when it has no ground
    truth, or `frames` are not as many as the recording's. OpenCV runs on one thread, so
    that the stage and baseline times are one thread's."""
    with one_thread(), Drive(path) as drive:
        source: Frames = drive if frames is None else frames
        if len(source) != len(drive):
            raise ValueError(
                f"frames: expected the {len(drive)} frames of {drive.path}, got {len(source)}"
            )
        if not drive.has_truth:
            why = drive.truth_problem or (
                "found none (annotations count only on frames marked fully annotated)"
            )
            raise ValueError(
                f"{drive.path}: expected ground truth to evaluate against (a generated "
                f"groundtruth.json, or annotations with frames marked annotated), {why}"
            )
        engine = FusionEngine(params, drive.camera)
        scorer = _Scorer(params)
        baseline = BaselineScorer(params, drive.camera) if baselines else None
        calibrated = drive.camera.extrinsics.pitch_rad
        unread: list[str] = []
        for i in range(len(drive)):
            try:
                frame = source.frame(i)
            except RecordingError as err:
                if strict:
                    raise
                unread.append(f"frame {i} could not be read and is not scored: {err}")
                if progress is not None:
                    progress(i + 1, len(drive))
                continue
            result = engine.process(frame)
            truth = drive.truth(i)
            mask = None if truth is None else scorer.add(frame, result, truth, calibrated)
            if baseline is not None:
                baseline.add(frame, result, truth, calibrated, mask)
            if progress is not None:
                progress(i + 1, len(drive))
        report = dataclasses.replace(
            scorer.report(drive.path.name), warnings=(*drive.warnings, *unread)
        )
        if baseline is not None:
            report = dataclasses.replace(report, baselines=baseline.report())
        if timing and len(drive) >= 2 and not unread:  # the timing reads every frame
            timed = guard_rail_savings(drive, params)
            report = dataclasses.replace(report, guardrail_timing=((report.name, timed),))
        return report


def total(reports: Sequence[RecordingReport]) -> RecordingReport:
    """The recordings' figures added up (listings concatenate; frame indices in them are
    their own recording's, so `report.as_json` leaves them out of a total)."""
    if not reports:
        raise ValueError("reports: expected at least one recording's report, got none")

    def summed(part: Callable[[RecordingReport], T]) -> T:
        return sum_fields([part(r) for r in reports])

    return RecordingReport(
        name="total",
        frames=sum(r.frames for r in reports),
        vehicles=summed(lambda r: r.vehicles),
        events=summed(lambda r: r.events),
        guardrails=summed(lambda r: r.guardrails),
        pedestrians={k: sum_fields([r.pedestrians[k] for r in reports]) for k in PEDESTRIAN_STAGES},
        motion_stereo=summed(lambda r: r.motion_stereo),
        pitch=summed(lambda r: r.pitch),
        tracking=summed(lambda r: r.tracking),
        guardrail_timing=tuple(t for r in reports for t in r.guardrail_timing),
        warnings=tuple(f"{r.name}: {w}" for r in reports for w in r.warnings),
        baselines=None
        if any(r.baselines is None for r in reports)
        else sum_fields([r.baselines for r in reports if r.baselines is not None]),
    )
