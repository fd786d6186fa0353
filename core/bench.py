"""`fusionscope bench`: how fast each stage runs, against the paper's timing table.

Paper 000, section III, timed its stages on 640x300 images on a Pentium 4 at 3.0 GHz. Here
each stage runs on frames of a bundled drive (whose processed window is 640x300) on one
thread (`cv2.setNumThreads(1)`): every chosen frame is run `repeat` times after `warmup`
runs, and the median, 10th and 90th percentiles of all timed runs are reported with the
paper's figure and the speed-up. Stages that carry state across frames are given the state
of the frame before, rebuilt for every run, so each run does the same work. The vehicle
detector runs on 8 radar targets of each frame (the frame's first 8, repeated when it has
fewer), the guard-rail filter on one slow target's area at a time, the tracker on the
measurements the engine builds from the frame's own detections, starting each run from a
copy of the tracks a playback of the drive had after the frame before. `total` is the whole
`FusionEngine.process` on a frame of 8 radar targets.

Figures from different machines are made comparable by a reference kernel timed in the same
run and the same way: `cv2.warpPerspective` of a frame's 640x300 window to motion stereo's
bird's-eye grid, the first step of `MotionStereo.update`. Every stage's median is also given
as a multiple of it ("x ref"): a machine twice as fast halves both.

With `total`, the throughput of `fusionscope run` is measured too: every frame of the drive
decoded, processed and written as JSON lines to a temporary file, in frames per second.
`guard_rail_savings` reproduces paper 002's table I: vehicle detection alone (VD), with the
guard-rail filter (GRD) and with overlapping-boxes management too (OBM), per frame with all
its radar targets.

Figures, not verdicts: the budget is printed beside the median, and nothing fails on time.
"""

from __future__ import annotations

import contextlib
import copy
import dataclasses
import functools
import itertools
import json
import os
import platform
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from core.camera import CameraModel
    from core.ego import EgoMotion
    from core.io.drive import Drive
    from core.io.frame import FrameInput, RadarTarget
    from core.params import GuardRailParams, Params
    from core.tracking import Measurement, Tracker

# Paper 000, section III: "640x300 images using standard Pentium 4 at 3.0 GHz" (None: the
# papers give no figure for the stage alone)
PAPER_MS: dict[str, float | None] = {
    "pitch": 4.0,
    "motion_stereo": 43.0,
    "vehicle": 1.0,
    "guardrail": None,
    "pedestrian": 83.0,
    "tracking": None,  # the papers do not track
    "total": 1000.0 / 7.0,  # "the whole system is able to reach a 7 Hz rate"
}
# What this implementation promises on one core of a current machine
BUDGET_MS = {
    "pitch": 0.5,
    "motion_stereo": 1.0,
    "vehicle": 0.5,
    "guardrail": 0.1,
    "pedestrian": 1.5,
    "tracking": 0.2,
    "total": 3.0,
}
# What one timed run covers
UNIT = {
    "pitch": "frame",
    "motion_stereo": "frame",
    "vehicle": "frame of 8 radar targets",
    "guardrail": "slow target",
    "pedestrian": "frame",
    "tracking": "frame of the engine's detections",
    "total": "frame of 8 radar targets, all stages and tracking",
}
STAGES = tuple(PAPER_MS)
TOTAL = "total"  # the whole frame: reported apart from the stages
VEHICLE_TARGETS = 8  # the budget is for 8 radar targets per frame
# Paper 002, table I, the highway average (ms per frame)
PAPER_002_MS = {"vd": 26.6, "grd": 23.2, "obm": 21.4}
RUN_PASSES = 3  # passes over the drive for the `fusionscope run` throughput (median taken)
PERCENTILES = (10.0, 50.0, 90.0)
THREADS = 1


@contextlib.contextmanager
def one_thread() -> Iterator[None]:
    """OpenCV on THREADS thread(s) inside the block, its previous thread count after it."""
    import cv2

    before = cv2.getNumThreads()
    cv2.setNumThreads(THREADS)
    try:
        yield
    finally:
        cv2.setNumThreads(before)


@dataclass(frozen=True)
class StageTiming:
    """Timing of one stage over all timed runs: median, 10th and 90th percentiles (ms).

    paper_ms: the paper's figure (None when it gives none); speedup: paper_ms / median_ms;
    ref_multiple: median_ms / the reference kernel's median in the same run; image: "WxH"
    of the processed rows; unit: what one run covers.
    """

    median_ms: float
    p10_ms: float
    p90_ms: float
    paper_ms: float | None
    speedup: float | None
    ref_multiple: float
    budget_ms: float
    runs: int
    frames: int
    image: str
    unit: str


@dataclass(frozen=True)
class ReferenceKernel:
    """The machine's yardstick: `cv2.warpPerspective` (bilinear, inverse map) of a frame's
    processed window (`image`, "WxH") to motion stereo's bird's-eye grid (`grid`, "WxH"),
    median, 10th and 90th percentiles over all timed runs (ms)."""

    median_ms: float
    p10_ms: float
    p90_ms: float
    runs: int
    frames: int
    image: str
    grid: str


@dataclass(frozen=True)
class RunThroughput:
    """`fusionscope run` end to end: frames per second over every frame of `recording`,
    opening, decoding, processing and writing JSON lines included; the median of `passes`
    passes, each with a fresh drive (nothing decoded before)."""

    frames_per_s: float
    frames: int
    passes: int
    recording: str


@dataclass(frozen=True)
class Machine:
    """Where the figures come from. cpu: /proc/cpuinfo's model name, else
    platform.processor(), else platform.machine(); threads: threads the bench used."""

    python: str
    numpy: str
    opencv: str
    numba: str
    cpu: str
    logical_cpus: int | None
    threads: int
    platform: str


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


def _percentiles(times: Sequence[float]) -> tuple[float, float, float]:
    """(p10, median, p90) of `times`, linear interpolation, so p10 <= median <= p90."""
    import numpy as np

    p10, median, p90 = (float(x) for x in np.percentile(times, PERCENTILES))
    return p10, median, p90


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


def _eight(radar: tuple[RadarTarget, ...]) -> tuple[RadarTarget, ...]:
    return tuple(itertools.islice(itertools.cycle(radar), VEHICLE_TARGETS)) if radar else ()


def _vehicle_runs(camera: CameraModel, pairs: Sequence[Pair], params: Params) -> list[Run]:
    """Search areas and vehicle detection on 8 radar targets of each frame."""
    from core.search_area import search_areas
    from core.vehicle import detect_vehicles

    runs: list[Run] = []
    for _, now in pairs:
        radar = _eight(now.radar)

        def run(image=now.image, radar=radar) -> Callable[[], object]:
            p = params.vehicle
            return lambda: detect_vehicles(search_areas(image, camera, radar, p), radar, camera, p)

        runs.append(run)
    return runs


def _guardrail_runs(camera: CameraModel, pairs: Sequence[Pair], params: Params) -> list[Run]:
    """The guard-rail search on each slow target's area alone (no overlap management)."""
    from core.guardrail import detect_guard_rails, is_slow
    from core.search_area import search_areas

    p = dataclasses.replace(params.guardrail, manage_overlaps=False)
    runs: list[Run] = []
    for _, now in pairs:
        for area in search_areas(now.image, camera, now.radar, params.vehicle):
            if is_slow(area.target, now.speed_mps, p):

                def run(area=area, speed=now.speed_mps) -> Callable[[], object]:
                    return lambda: detect_guard_rails((area,), speed, p)

                runs.append(run)
    return runs


def _pedestrian_runs(camera: CameraModel, pairs: Sequence[Pair], params: Params) -> list[Run]:
    """Pedestrian detection on each frame with its motion-stereo mask (background from the
    frame before), the vehicles found on the frame's radar targets, and the frame before as
    the image-motion filter reads it."""
    from core.image_motion import keep
    from core.motion_stereo import MotionStereo
    from core.pedestrian import detect_pedestrians
    from core.search_area import search_areas
    from core.vehicle import detect_vehicles

    runs: list[Run] = []
    for before, now in pairs:
        stage = MotionStereo(params.motion_stereo)
        stage.update(before.image, camera, None)
        motion = stage.update(now.image, camera, now.ego)
        areas = search_areas(now.image, camera, now.radar, params.vehicle)
        vehicles = detect_vehicles(areas, now.radar, camera, params.vehicle).vehicles
        boxes = [v.box_px for v in vehicles]
        kept = keep(before.image)

        def run(
            image=now.image, mask=motion.image_mask, row=motion.image_mask_first_row_px,
            boxes=boxes, radar=now.radar, speed=now.speed_mps, previous=kept, ego=now.ego,
        ) -> Callable[[], object]:  # fmt: skip
            return lambda: detect_pedestrians(
                image, camera, mask, row, boxes, radar, speed, params.pedestrian, previous, ego
            )

        runs.append(run)
    return runs


@dataclass(frozen=True)
class _TrackingCase:
    """One frame's tracker input as a playback of the drive gives it: the tracker after
    the frame before, and this frame's measurements, ego motion and interval."""

    tracker: Tracker
    measurements: tuple[Measurement, ...]
    ego: EgoMotion | None
    dt_s: float
    camera: CameraModel


def _tracking_cases(drive: Drive, pairs: Sequence[Pair], params: Params) -> list[_TrackingCase]:
    """Play the drive from its first frame to the last of `pairs` with a `FusionEngine`,
    feeding a tracker of our own the measurements the engine builds (`tracker_measurements`, with
    the engine's ego motion and interval); before each frame of `pairs`, keep a copy of that
    tracker. Ids included, it is the engine's tracker: both start empty and see the same
    measurements (`Tracker.reset`)."""
    from core.ego import NS_PER_S
    from core.engine import FusionEngine, tracker_measurements
    from core.tracking import Tracker

    wanted = {now.index for _, now in pairs}
    engine = FusionEngine(params, drive.camera)
    tracker = Tracker(params.tracking)
    cases: list[_TrackingCase] = []
    last: FrameInput | None = None
    for i in range(max(wanted) + 1):
        frame = drive.frame(i)
        result = engine.process(frame)
        measurements = tuple(
            tracker_measurements(
                result.vehicle,
                result.pedestrian,
                result.areas,
                result.guardrail.guard_rail_targets,
                result.track_search,
                result.appearance,
            )
        )
        ego = frame.ego if last is not None else None
        dt_s = 0.0 if last is None else max((frame.t_ns - last.t_ns) / NS_PER_S, 0.0)
        if i in wanted:
            cases.append(
                _TrackingCase(copy.deepcopy(tracker), measurements, ego, dt_s, result.camera)
            )
        tracker.update(measurements, ego, dt_s)
        last = frame
    return cases


def _tracking_runs(cases: Sequence[_TrackingCase], params: Params) -> list[Run]:
    """The engine's tracking stage (`update_tracks`) on each case, on a fresh copy of the
    tracker after the frame before."""
    from core.engine import update_tracks

    runs: list[Run] = []
    for case in cases:

        def run(case=case) -> Callable[[], object]:
            tracker = copy.deepcopy(case.tracker)
            return lambda: update_tracks(
                tracker, case.measurements, case.ego, case.dt_s, case.camera, params
            )

        runs.append(run)
    return runs


def _total_runs(camera: CameraModel, pairs: Sequence[Pair], params: Params) -> list[Run]:
    """`FusionEngine.process` on each frame with 8 of its radar targets, the engine having
    processed the frame before."""
    from core.engine import FusionEngine

    runs: list[Run] = []
    for before, now in pairs:
        frame = dataclasses.replace(now, index=before.index + 1, radar=_eight(now.radar))

        def run(before=before, frame=frame) -> Callable[[], object]:
            engine = FusionEngine(params, camera)
            engine.process(before)
            return lambda: engine.process(frame)

        runs.append(run)
    return runs


def _reference_runs(camera: CameraModel, pairs: Sequence[Pair], params: Params) -> list[Run]:
    """The reference kernel on each frame: motion stereo's `warp_to_grid` (one
    `cv2.warpPerspective`) of the processed window, with the calibrated pitch."""
    import numpy as np

    from core.motion_stereo import grid_for, warp_to_grid, window_homography

    grid = grid_for(params.motion_stereo)
    first, stop = camera.row_window_px
    H_window_grid = window_homography(camera.H_image_grid(grid), first)
    runs: list[Run] = []
    for _, now in pairs:

        def run(window=now.image[first:stop]) -> Callable[[], object]:
            out = np.empty(grid.shape, dtype=np.uint8)
            return lambda: warp_to_grid(window, H_window_grid, out)

        runs.append(run)
    return runs


def _frame_pairs(drive: Drive, frames: int) -> list[Pair]:
    import numpy as np

    if len(drive) < 2:
        raise ValueError(f"{drive.path}: expected at least 2 frames to bench, got {len(drive)}")
    chosen = sorted({int(k) for k in np.linspace(1, len(drive) - 1, frames)})
    return [(drive.frame(k - 1), drive.frame(k)) for k in chosen]


def _image(camera: CameraModel) -> str:
    first, stop = camera.row_window_px
    return f"{camera.intrinsics.width_px}x{stop - first}"


def _reference_kernel(
    camera: CameraModel, pairs: Sequence[Pair], params: Params, warmup: int, repeat: int
) -> ReferenceKernel:
    from core.motion_stereo import grid_for

    times = _time_runs(_reference_runs(camera, pairs, params), warmup, repeat)
    p10, median, p90 = _percentiles(times)
    rows, cols = grid_for(params.motion_stereo).shape
    return ReferenceKernel(
        median, p10, p90, len(times), len(pairs), _image(camera), f"{cols}x{rows}"
    )


def _stage_timing(
    stage: str,
    runs: Sequence[Run],
    frames: int,
    image: str,
    ref_ms: float,
    warmup: int,
    repeat: int,
) -> StageTiming:
    if not runs:
        raise ValueError(f"no {UNIT[stage]} to time {stage} on in {frames} frames")
    p10, median, p90 = _percentiles(_time_runs(runs, warmup, repeat))
    paper = PAPER_MS[stage]
    return StageTiming(
        median_ms=median,
        p10_ms=p10,
        p90_ms=p90,
        paper_ms=paper,
        speedup=None if paper is None else paper / median,
        ref_multiple=median / ref_ms,
        budget_ms=BUDGET_MS[stage],
        runs=len(runs) * repeat,
        frames=frames,
        image=image,
        unit=UNIT[stage],
    )


@dataclass(frozen=True)
class GuardRailSavings:
    """Paper 002's table I on one drive: median ms per frame of vehicle detection alone
    (vd_ms), with the guard-rail filter (grd_ms) and with overlapping-boxes management
    (obm_ms); reduction = 1 - obm / vd. Per frame on average: radar targets, slow ones,
    areas the line search ran on with and without overlap management, targets labelled
    guard rail."""

    vd_ms: float
    grd_ms: float
    obm_ms: float
    reduction: float
    paper_ms: dict[str, float]
    targets: float
    slow_targets: float
    searched_grd: float
    searched_obm: float
    guard_rails: float
    frames: int


def _guard_rail_savings(
    camera: CameraModel, pairs: Sequence[Pair], params: Params, warmup: int, repeat: int
) -> GuardRailSavings:
    """VD, GRD and OBM (paper 002, table I) on the frames of `pairs`."""
    import numpy as np

    from core.guardrail import detect_guard_rails
    from core.search_area import search_areas
    from core.vehicle import detect_vehicles

    p = params.vehicle
    grd = dataclasses.replace(params.guardrail, manage_overlaps=False)
    obm = dataclasses.replace(params.guardrail, manage_overlaps=True)

    def run(now: FrameInput, gp: GuardRailParams | None) -> Callable[[], object]:
        def frame() -> object:
            areas = search_areas(now.image, camera, now.radar, p)
            skip: frozenset[int] = frozenset()
            if gp is not None:
                skip = detect_guard_rails(areas, now.speed_mps, gp).guard_rail_targets
            return detect_vehicles(areas, now.radar, camera, p, skip)

        return frame

    medians = {
        mode: float(
            np.median(
                _time_runs([functools.partial(run, now, gp) for _, now in pairs], warmup, repeat)
            )
        )
        for mode, gp in (("vd", None), ("grd", grd), ("obm", obm))
    }
    counts = []  # per frame: targets, slow, searched without and with OBM, guard rails
    for _, now in pairs:
        areas = search_areas(now.image, camera, now.radar, p)
        without, with_obm = (detect_guard_rails(areas, now.speed_mps, gp) for gp in (grd, obm))
        counts.append(
            (
                len(now.radar),
                len(without.checks),
                without.searched,
                with_obm.searched,
                len(with_obm.guard_rail_targets),
            )
        )
    targets, slow, searched_grd, searched_obm, rails = np.mean(counts, axis=0).tolist()
    return GuardRailSavings(
        vd_ms=medians["vd"],
        grd_ms=medians["grd"],
        obm_ms=medians["obm"],
        reduction=1.0 - medians["obm"] / medians["vd"],
        paper_ms=dict(PAPER_002_MS),
        targets=targets,
        slow_targets=slow,
        searched_grd=searched_grd,
        searched_obm=searched_obm,
        guard_rails=rails,
        frames=len(pairs),
    )


def guard_rail_savings(
    drive: Drive, params: Params, frames: int = 20, warmup: int = 2, repeat: int = 10
) -> GuardRailSavings:
    """Paper 002's table I on `frames` frames spread over `drive`, one thread (for
    `fusionscope evaluate`)."""
    with one_thread():
        return _guard_rail_savings(
            drive.camera, _frame_pairs(drive, min(frames, len(drive) - 1)), params, warmup, repeat
        )


def _run_throughput(recording: Path | str, params: Params, passes: int) -> RunThroughput:
    """Frames per second of `fusionscope run`'s loop (`core.cli._cmd_run`: `Drive.frame`,
    `FusionEngine.process`, `core.results.frame_record`, one compact JSON line per frame)
    over the whole drive into a temporary file, the median of `passes` passes. The progress
    bar is left out: it draws a few dozen times a drive."""
    import statistics
    import tempfile

    from core.io.drive import Drive
    from core.results import write_results

    rates: list[float] = []
    frames = 0
    name = Path(recording).name
    with tempfile.TemporaryDirectory(prefix="fusionscope-bench-") as folder:
        out = Path(folder) / "results.jsonl"
        for _ in range(passes):
            t0 = time.perf_counter()
            with Drive(recording) as drive, out.open("w", encoding="utf-8") as sink:
                write_results(drive, drive.camera, params, sink, strict=True)
                frames, name = len(drive), drive.path.name
            rates.append(frames / (time.perf_counter() - t0))
    return RunThroughput(statistics.median(rates), frames, passes, name)


def _cpu_model() -> str:
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as info:
            for line in info:
                key, _, value = line.partition(":")
                if key.strip() == "model name" and value.strip():
                    return value.strip()
    except OSError:
        pass  # not Linux: ask platform
    return platform.processor() or platform.machine() or "unknown"


def machine() -> Machine:
    """This machine and the libraries that do the work (cv2's threads as the bench sets
    them)."""
    import cv2
    import numba
    import numpy as np

    return Machine(
        python=platform.python_version(),
        numpy=np.__version__,
        opencv=cv2.__version__,
        numba=numba.__version__,
        cpu=_cpu_model(),
        logical_cpus=os.cpu_count(),
        threads=THREADS,
        platform=platform.platform(),
    )


@dataclass(frozen=True)
class BenchReport:
    """Each stage's timing (`total` apart, None when not timed), the reference kernel they
    are multiples of, `fusionscope run`'s throughput (with total), paper 002's table I (with
    vehicle and guardrail) and the machine."""

    stages: dict[str, StageTiming]
    total: StageTiming | None
    reference: ReferenceKernel
    run: RunThroughput | None
    guard_rail_savings: GuardRailSavings | None
    machine: Machine


def bench(
    stages: Sequence[str],
    recording: Path | str,
    params: Params | None = None,
    frames: int = 20,
    warmup: int = 5,
    repeat: int = 50,
    run_passes: int = RUN_PASSES,
) -> BenchReport:
    """Time each of `stages` (from STAGES) on `frames` frames spread over `recording`, opened
    and decoded once, and the reference kernel on the same frames; with total, also
    `fusionscope run`'s throughput over `run_passes` passes of the whole drive; with both
    vehicle and guardrail, paper 002's table I. ValueError naming the argument on a stage
    not in STAGES, frames below 2, warmup below 0, repeat or run_passes below 1, or a
    stage with nothing to time on the chosen frames."""
    from core.io.drive import Drive
    from core.params import Params

    for stage in stages:
        if stage not in STAGES:
            raise ValueError(f"stage: expected one of {', '.join(STAGES)}, got {stage!r}")
    for name, value, least in (
        ("frames", frames, 2),
        ("warmup", warmup, 0),
        ("repeat", repeat, 1),
        ("run_passes", run_passes, 1),
    ):
        if value < least:
            raise ValueError(f"{name}: expected a whole number >= {least}, got {value}")
    chosen = list(dict.fromkeys(stages))
    params = params or Params()
    with one_thread():
        make = {
            "pitch": _pitch_runs,
            "motion_stereo": _motion_stereo_runs,
            "vehicle": _vehicle_runs,
            "guardrail": _guardrail_runs,
            "pedestrian": _pedestrian_runs,
            "total": _total_runs,
        }
        with Drive(recording) as drive:
            pairs = _frame_pairs(drive, frames)
            camera = drive.camera
            cases = _tracking_cases(drive, pairs, params) if "tracking" in chosen else []
        reference = _reference_kernel(camera, pairs, params, warmup, repeat)
        timings: dict[str, StageTiming] = {}
        try:
            for stage in chosen:
                runs = (
                    _tracking_runs(cases, params)
                    if stage == "tracking"
                    else make[stage](camera, pairs, params)
                )
                timings[stage] = _stage_timing(
                    stage, runs, len(pairs), _image(camera), reference.median_ms, warmup, repeat
                )
        except ValueError as err:
            raise ValueError(f"{recording}: {err}") from None
        savings = None
        if "vehicle" in chosen and "guardrail" in chosen:
            savings = _guard_rail_savings(camera, pairs, params, warmup, repeat)
        total = timings.pop(TOTAL, None)
        run = _run_throughput(recording, params, run_passes) if total is not None else None
        return BenchReport(timings, total, reference, run, savings, machine())


def format_table(report: BenchReport) -> str:
    """The report for people: one row per stage, total last, then the reference kernel,
    `fusionscope run`'s throughput, the machine and paper 002's table I."""
    rows = list(report.stages.items())
    if report.total is not None:
        rows.append((TOTAL, report.total))
    lines = [
        f"{'stage':<14} {'median ms':>10} {'p10 ms':>8} {'p90 ms':>8} {'x ref':>7} "
        f"{'budget ms':>10} {'paper ms':>9} {'speed-up':>9}  per, image, runs"
    ]
    for name, t in rows:
        paper = "-" if t.paper_ms is None else f"{t.paper_ms:.1f}"
        speedup = "-" if t.speedup is None else f"{t.speedup:.1f}x"
        lines.append(
            f"{name:<14} {t.median_ms:>10.3f} {t.p10_ms:>8.3f} {t.p90_ms:>8.3f} "
            f"{t.ref_multiple:>7.2f} {t.budget_ms:>10.2f} {paper:>9} {speedup:>9}  "
            f"{t.unit}, {t.image}, {t.runs} runs on {t.frames} frames"
        )
    r = report.reference
    lines += [
        "",
        f"reference kernel (x ref): cv2.warpPerspective {r.image} -> {r.grid} bird's-eye grid, "
        f"median {r.median_ms:.3f} ms (p10 {r.p10_ms:.3f}, p90 {r.p90_ms:.3f}; "
        f"{r.runs} runs on {r.frames} frames)",
    ]
    if report.run is not None:
        u = report.run
        lines.append(
            f"fusionscope run: {u.frames_per_s:.0f} frames/s, decoding and writing included "
            f"({u.frames} frames of {u.recording}, median of {u.passes} passes)"
        )
    m = report.machine
    lines.append(
        f"machine: {m.cpu}, {m.logical_cpus} logical CPUs, {m.threads} thread used; "
        f"Python {m.python}, numpy {m.numpy}, OpenCV {m.opencv}, numba {m.numba}"
    )
    savings = report.guard_rail_savings
    if savings is not None:
        s, p002 = savings, savings.paper_ms
        lines += [
            "",
            "guard-rail savings (paper 002, table I), ms per frame with all radar targets:",
            f"{'':<6} {'VD':>7} {'GRD':>7} {'OBM':>7} {'reduction':>10}",
            f"{'here':<6} {s.vd_ms:>7.3f} {s.grd_ms:>7.3f} {s.obm_ms:>7.3f} {s.reduction:>10.0%}",
            f"{'paper':<6} {p002['vd']:>7.1f} {p002['grd']:>7.1f} {p002['obm']:>7.1f} "
            f"{1 - p002['obm'] / p002['vd']:>10.0%}",
            f"per frame: {s.targets:.1f} radar targets, {s.slow_targets:.1f} slow, "
            f"{s.guard_rails:.1f} labelled guard rail; line searches {s.searched_grd:.1f} "
            f"without overlap management, {s.searched_obm:.1f} with ({s.frames} frames)",
        ]
    return "\n".join(lines)


def format_json(report: BenchReport) -> str:
    """The report as one JSON object: "stages" (without total), "total", the reference
    kernel's median as "reference_kernel_ms" (details in "reference_kernel"),
    "run_frames_per_s" (details in "run"), "guard_rail_savings" and "machine"; what was not
    measured is null."""
    run, savings = report.run, report.guard_rail_savings
    out: dict[str, object] = {
        "stages": {name: asdict(t) for name, t in report.stages.items()},
        "total": None if report.total is None else asdict(report.total),
        "reference_kernel_ms": report.reference.median_ms,
        "reference_kernel": asdict(report.reference),
        "run_frames_per_s": None if run is None else run.frames_per_s,
        "run": None if run is None else asdict(run),
        "guard_rail_savings": None if savings is None else asdict(savings),
        "machine": asdict(report.machine),
    }
    return json.dumps(out, indent=2)
