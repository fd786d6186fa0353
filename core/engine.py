"""The whole pipeline of paper 000 for one frame, and the state it carries across frames.

`FusionEngine.process(frame)` runs, in the order of paper 000's fig. 1:

1. pitch (II-A), with the previous frame's horizon memory and its vehicle boxes left out;
2. the camera model for this frame (the calibrated camera with the detected pitch);
3. motion stereo (II-B) on the bird's-eye view, with the car's motion since the last frame;
4. the search areas of the radar targets (wider where the tracker expects a vehicle it
   follows, `Tracker.predicted`, and centred on that vehicle; a still target's centred on
   its point smoothed over the last scans, `core.radar_smoothing`), and the guard-rail
   filter on the slow ones (paper 002), with the lines of the rail returns it found over
   the last seconds (`core.rail_lines`);
5. vehicle detection by symmetry on the others (II-C, paper 001), then the vision searches
   for the vehicles it follows that no radar target returned (`core.track_search`) and
   for those still unframed by their look (`core.appearance`), beyond the papers;
6. pedestrian detection with both fusion filters (II-D);
7. tracking of vehicles, pedestrians and guard-rail targets (`core.tracking`, beyond the
   papers).

The engine is the only module that knows this order. It owns what crosses frames: the pitch
memory, the previous frame's vehicle boxes, the remembered radar points and rail returns,
the tracked vehicles' looks (`core.appearance`), motion stereo's background and the
tracker.
`process` expects frames in order; `seek(drive, index)` brings the engine to any frame of a
drive: a frame a little ahead is reached by processing the frames in between (as playback
skipping frames would), any other by resetting that state and replaying the
`replay_window(params)` frames before it. `preview(state, frame)` runs one frame from a state
an engine under other parameters kept: the inspector shows it at once when a parameter
changes, while the exact seek under the new parameters replays the window.

State snapshots (`keep_states`, for the inspector's scrubbing): after each frame it
processes, an engine built with `keep_states > 0` keeps that cross-frame state under the
frame's index, the `keep_states` used last (least recently used dropped first). A seek to
frame k first looks for a kept state of a frame j with k - replay_window < j < k, takes up
the latest and processes j + 1 .. k. From a restored state the engine gives exactly what it
gave when it processed on from that state the first time, so a seek's result depends on
the path that made the snapshot: the same as a playback from the start when the snapshot
was played to, the same as a fresh replay (within the tolerance below) when it was
replayed to. A snapshot is valid only for the frames it came from and the engine's own
parameters: an engine never changes its parameters and serves one drive; `reset()` drops
every snapshot. The kept background, pitch histogram and previous frame are read-only and
kept by reference; the tracks, which the tracker updates in place, are copied.

From the start: a frame's result is from the start when the engine reached it by processing
every frame from the drive's first (or from the frame after the last one that could not be
read, where a playback starts again too) without a break. Such a result is the playback's,
its tracks and their ids included, however the frame was reached (`FrameResult.from_start`);
a replay's tracks are not. A seek takes the latest from-start state before the wanted frame
it has (its own, a kept one, or a milestone) and plays on from it when that costs at most
`catch_up_frames` frames (None: whatever it costs; the default 0 only when the frame follows
it). Milestones (`Milestones`) are the from-start states of every few frames of a drive under
one set of parameters, which the engines serving it share and fill as they process: played
once from the start, every frame of a drive is at most `every` frames from one.

Replay tolerance (what a seek reproduces of playing the drive from its start):
    - motion stereo's background forgets a frame after `frames_to_forget` frames up to half
      a grey level (`core.motion_stereo`); the window is at least that long, so the
      obstacle mask agrees except where a cell's mean sits on the threshold;
    - the tracker restarts: its ids differ from a playback's, and a track confirmed before
      the window is confirmed again within `confirm_frames` of its start; a track older
      than the window carries less history and a less settled velocity; the search areas
      that tracks widen (`core.search_area`) follow the replayed tracks;
    - pitch's horizon tracking and the vehicle boxes it leaves out, and the pedestrians'
      image-motion filter (`core.image_motion`), depend on one frame back, and are rebuilt
      by the first replayed frame.
    `tests/core/test_engine.py` checks these on a bundled drive.
"""

from __future__ import annotations

import dataclasses
import threading
import time
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Protocol, TypeVar

import numpy as np
import numpy.typing as npt

from core.appearance import AppearanceMatch, Template, find_by_appearance, remember
from core.camera import CameraModel
from core.ego import NS_PER_S, EgoMotion
from core.guardrail import GuardRailResult, detect_guard_rails
from core.image_motion import keep as keep_for_image_motion
from core.io.errors import RecordingError
from core.io.frame import FrameInput
from core.motion_stereo import (
    MotionStereo,
    MotionStereoResult,
    MotionStereoState,
    frames_to_forget,
)
from core.params import Params
from core.pedestrian import PedestrianResult, detect_pedestrians
from core.pitch import PitchMemory, PitchResult, detect_pitch
from core.radar_smoothing import RememberedPoint, smooth_centres
from core.rail_lines import RailLine, RailReturns, along_rail_lines
from core.search_area import SearchArea, search_areas
from core.track_search import NOTHING as NOTHING_SEARCHED
from core.track_search import TrackSearchResult, search_tracks
from core.tracking import (
    Measurement,
    Track,
    Tracker,
    TrackerState,
    TrackResult,
    clipped_to_image,
    coasting_boxes,
    confirmed_sources,
)
from core.vehicle import VehicleResult, body_box, detect_vehicles

U8Array = npt.NDArray[np.uint8]
MS_PER_S = 1000.0
# A background whose weights never forget (frames_to_forget None) is rebuilt from this many
# frames on a seek.
LONGEST_REPLAY_FRAMES = 200
# Frames between two milestones: a seek from the nearest costs at most this many frames, less
# than a replay's window (22 frames under the defaults). About 140 KB a state (app.engines), so
# 168 MB for a 20-minute drive at 10 Hz, were there no cap (app.engines.MOST_MILESTONES).
MILESTONE_EVERY_FRAMES = 10

T = TypeVar("T")

Box = tuple[float, float, float, float]


@dataclass(frozen=True)
class StageTimings:
    """Milliseconds each stage took on this frame (wall clock, one thread)."""

    pitch_ms: float
    motion_stereo_ms: float
    guardrail_ms: float  # search areas included
    vehicle_ms: float  # the track search and the search by look included
    pedestrian_ms: float
    tracking_ms: float  # the looks kept for the next frame included

    @property
    def total_ms(self) -> float:
        return (
            self.pitch_ms
            + self.motion_stereo_ms
            + self.guardrail_ms
            + self.vehicle_ms
            + self.pedestrian_ms
            + self.tracking_ms
        )


@dataclass(frozen=True, eq=False)
class FrameResult:
    """Everything the engine found on one frame, with every stage's intermediates.

    camera: this frame's camera (calibration with the detected pitch); areas: the radar
    targets' search areas; guardrail: the guard-rail labels (paper 002's and along the rail
    lines, `core.rail_lines`); rail_lines: those lines; vehicle, pedestrian: the papers'
    per-frame detections (vehicle's vehicles end with those `track_search` found, which have
    no radar target); track_search: the vision searches for tracked vehicles no radar
    target returned (`core.track_search`); appearance: the tracked vehicles found by their
    look after both (`core.appearance`; measurements of their tracks, not detections);
    tracking: every live track after this frame; tracked_vehicles / tracked_pedestrians:
    the shown tracks of each kind (`Track.shown`); tracked_guard_rails: indices of this
    frame's radar targets labelled guard rail and associated with a confirmed guard-rail
    track;
    replayed: frames processed before this one to rebuild the state (0 when it followed
    the previous frame); preview: made by `preview`, from the state other parameters left;
    from_start: processed on from the drive's start (module docstring), so its tracks and
    their ids are those of a playback from the first frame, however the frame was reached.
    """

    index: int
    t_ns: int
    camera: CameraModel
    pitch: PitchResult
    motion_stereo: MotionStereoResult
    areas: tuple[SearchArea, ...]
    guardrail: GuardRailResult
    vehicle: VehicleResult
    pedestrian: PedestrianResult
    tracking: TrackResult
    timings: StageTimings
    replayed: int
    preview: bool = False
    from_start: bool = False
    rail_lines: tuple[RailLine, ...] = ()
    track_search: TrackSearchResult = NOTHING_SEARCHED
    appearance: tuple[AppearanceMatch, ...] = ()

    @property
    def tracked_vehicles(self) -> tuple[Track, ...]:
        return self.tracking.of_kind("vehicle")

    @property
    def tracked_pedestrians(self) -> tuple[Track, ...]:
        return self.tracking.of_kind("pedestrian")

    @property
    def tracked_guard_rails(self) -> frozenset[int]:
        return confirmed_sources(self.tracking, "guard_rail")


class Frames(Protocol):
    """What `FusionEngine.seek` reads: a drive's frames by index (`core.io.drive.Drive`)."""

    def __len__(self) -> int: ...

    def frame(self, i: int) -> FrameInput: ...


@dataclass(frozen=True)
class _LastFrame:
    """What the next frame reads of the previous one: its index (does it follow?), its
    time (the tracker's interval) and whether it was processed on from the drive's start.
    Not the FrameInput: a kept state would hold its image."""

    index: int
    t_ns: int
    from_start: bool


@dataclass(frozen=True, eq=False)
class EngineState:
    """The engine's cross-frame state after one frame, as `process` of the next reads it."""

    motion_stereo: MotionStereoState
    tracker: TrackerState
    pitch_memory: PitchMemory | None
    vehicle_boxes: tuple[Box, ...]
    radar_points: tuple[RememberedPoint, ...]
    rail_returns: RailReturns
    templates: Mapping[int, Template]  # core.appearance, by track id
    last: _LastFrame
    # the frame as core.image_motion reads it on the next (a quarter of the resolution)
    previous_image: U8Array | None = None


def replay_window(params: Params) -> int:
    """Frames a seek replays before the wanted one: long enough for motion stereo's
    background to forget the frames before it and for a track to be confirmed again."""
    forget = frames_to_forget(params.motion_stereo)
    t = params.tracking
    # the longest confirmation: a miss kept between every two hits
    longest = max(t.confirm_frames, t.pedestrian_confirm_frames)
    confirming = longest + (longest - 1) * t.tentative_max_missed_frames
    tracking = confirming + t.max_missed_frames
    return max(LONGEST_REPLAY_FRAMES if forget is None else forget, tracking)


class Milestones:
    """The from-start states (module docstring) of one drive under one set of parameters at
    every `every`-th frame, shared by the engines that serve the drive under them. Safe to
    use from several threads. ValueError naming every when it is not an integer >= 1."""

    def __init__(self, params: Params, every: int = MILESTONE_EVERY_FRAMES) -> None:
        if isinstance(every, bool) or not isinstance(every, int) or every < 1:
            raise ValueError(f"every: expected an integer >= 1, got {every!r}")
        self.params = params
        self.every = every
        self._states: dict[int, EngineState] = {}
        self._lock = threading.Lock()

    def due(self, last: _LastFrame) -> bool:
        """Is the state after frame `last` one to keep?"""
        return last.from_start and last.index % self.every == 0

    def add(self, state: EngineState) -> None:
        """Keep `state` when it is due (others are ignored)."""
        if self.due(state.last):
            with self._lock:
                self._states[state.last.index] = state

    def latest_before(self, index: int) -> EngineState | None:
        """The kept state of the latest frame before `index` (None when none is)."""
        with self._lock:
            j = max((j for j in self._states if j < index), default=None)
            return None if j is None else self._states[j]

    @property
    def reach(self) -> int:
        """The latest frame whose state is kept (-1 when none is)."""
        with self._lock:
            return max(self._states, default=-1)


def _check_count(name: str, value: object) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise ValueError(f"{name}: expected an integer >= 0, got {value!r}")


def _timed(run: Callable[[], T]) -> tuple[T, float]:
    start = time.perf_counter()
    out = run()
    return out, (time.perf_counter() - start) * MS_PER_S


def tracker_measurements(
    vehicle: VehicleResult,
    pedestrian: PedestrianResult,
    areas: tuple[SearchArea, ...],
    guard_rails: frozenset[int],
    searched: TrackSearchResult = NOTHING_SEARCHED,
    appearance: Sequence[AppearanceMatch] = (),
) -> list[Measurement]:
    """This frame's detections as the tracker's measurements: vehicles at the radar's
    distance with vision's lateral position and width (the last ones, those `searched`
    found, for the tracks they were searched for; then the `appearance` matches, source
    indices after the vehicles', each for its track), kept pedestrians where their base
    meets the road, guard-rail targets at the radar's position."""
    first_searched = len(vehicle.vehicles) - len(searched.vehicles)
    out = [
        Measurement(
            "vehicle",
            v.distance_m,
            v.lateral_m,
            v.width_m,
            v.box_px,
            i,
            None if i < first_searched else searched.track_of[i - first_searched],
        )
        for i, v in enumerate(vehicle.vehicles)
    ]
    out += [
        Measurement(
            "vehicle",
            m.vehicle.distance_m,
            m.vehicle.lateral_m,
            m.vehicle.width_m,
            m.vehicle.box_px,
            len(vehicle.vehicles) + k,
            m.track_id,
        )
        for k, m in enumerate(appearance)
    ]
    out += [
        Measurement("pedestrian", p.distance_m, p.lateral_m, p.width_m, p.extended_box_px, i)
        for i, p in enumerate(pedestrian.candidates)
        if p.verdict == "pedestrian"
    ]
    for a in sorted(areas, key=lambda a: a.target_index):
        if a.target_index in guard_rails:
            u0, v0, u1, v1 = a.box_px
            box = (float(u0), float(v0), float(u1), float(v1))
            out.append(
                Measurement("guard_rail", a.target.x_m, a.target.y_m, 0.0, box, a.target_index)
            )
    return out


def update_tracks(
    tracker: Tracker,
    measurements: Sequence[Measurement],
    ego: EgoMotion | None,
    dt_s: float,
    camera: CameraModel,
    params: Params,
) -> TrackResult:
    """The tracking stage: the tracker's update with this frame's measurements, then the
    boxes of confirmed tracks missed this frame moved to where they are expected
    (`coasting_boxes`, a pedestrian's at a walking pace at most) unless
    `tracking.coasting_boxes_follow` is off, then each vehicle track's body around its box
    (`core.vehicle.body_box`, step 12), every box cut to the image (`clipped_to_image`)."""
    tracks = tracker.update(measurements, ego, dt_s)
    if params.tracking.coasting_boxes_follow:
        step_m = params.tracking.pedestrian_coasting_speed_mps * dt_s
        tracks = coasting_boxes(tracks, camera, step_m)
    length_m = params.vehicle.body_length_m
    if length_m > 0:  # the papers' boxes have no body (Track.outline_px is box_px)
        tracks = dataclasses.replace(
            tracks,
            tracks=tuple(
                dataclasses.replace(t, body_px=body_box(t.box_px, t.x_m, camera, length_m))
                if t.kind == "vehicle"
                else t
                for t in tracks.tracks
            ),
        )
    return clipped_to_image(tracks, camera)


class FusionEngine:
    """Paper 000's system on one drive: `process` one frame after the other, or `seek`.

    camera: the drive's calibrated camera (its pitch is the calibrated one; each frame's
    detected pitch replaces it for that frame). keep_states: how many frames' cross-frame
    states to keep for `seek` (module docstring; 0, the default, keeps none). catch_up_frames:
    how many frames a seek may process from the latest from-start state to give the wanted
    frame's from-start result (None: any number, every seek is from the start; 0, the
    default: only when it follows). milestones: where to keep and find the from-start states
    of every few frames, shared with other engines (None: none). ValueError naming the
    argument for a keep_states or catch_up_frames that is not an integer >= 0 and for
    milestones of other parameters.
    """

    def __init__(
        self,
        params: Params,
        camera: CameraModel,
        keep_states: int = 0,
        catch_up_frames: int | None = 0,
        milestones: Milestones | None = None,
    ) -> None:
        _check_count("keep_states", keep_states)
        if catch_up_frames is not None:
            _check_count("catch_up_frames", catch_up_frames)
        if milestones is not None and milestones.params != params:
            raise ValueError("milestones: expected those of the engine's parameters, got others")
        self.params = params
        self.camera = camera
        self.keep_states = keep_states
        self.catch_up_frames = catch_up_frames
        self.milestones = milestones
        self._motion_stereo = MotionStereo(params.motion_stereo)
        self._tracker = Tracker(params.tracking)
        self._pitch_memory: PitchMemory | None = None
        self._vehicle_boxes: tuple[Box, ...] = ()
        self._radar_points: tuple[RememberedPoint, ...] = ()
        self._rail_returns = RailReturns.none()
        self._templates: Mapping[int, Template] = MappingProxyType({})
        self._last: _LastFrame | None = None
        self._previous_image: U8Array | None = None
        # after a start over: is the next frame's result from the start (a frame that cannot
        # be read within a from-start run breaks the drive as it breaks a playback)
        self._next_from_start = False
        self._states: OrderedDict[int, EngineState] = OrderedDict()

    @property
    def last_index(self) -> int | None:
        """Index of the frame processed last (None after a reset)."""
        return None if self._last is None else self._last.index

    @property
    def kept_states(self) -> tuple[int, ...]:
        """Indices of the frames whose state is kept, least recently used first."""
        return tuple(self._states)

    def reset(self) -> None:
        """Forget every cross-frame state and every kept one: the next frame is processed
        as a drive's first."""
        self._start_over()
        self._states.clear()

    def _start_over(self, from_start: bool = False) -> None:
        """Forget the cross-frame state (not the kept ones): a new start within the drive,
        the next frame from the start when `from_start` (after a break in a from-start run)."""
        self._motion_stereo.reset()
        self._tracker.reset()
        self._pitch_memory = None
        self._vehicle_boxes = ()
        self._radar_points = ()
        self._rail_returns = RailReturns.none()
        self._templates = MappingProxyType({})
        self._last = None
        self._previous_image = None
        self._next_from_start = from_start

    def _state(self, last: _LastFrame) -> EngineState:
        return EngineState(
            self._motion_stereo.state(),
            self._tracker.state(),
            self._pitch_memory,
            self._vehicle_boxes,
            self._radar_points,
            self._rail_returns,
            self._templates,
            last,
            self._previous_image,
        )

    def _keep(self, state: EngineState) -> None:
        """Keep `state`, the most recently used."""
        index = state.last.index
        self._states[index] = state
        self._states.move_to_end(index)
        while len(self._states) > self.keep_states:
            self._states.popitem(last=False)

    def kept_state(self, index: int) -> EngineState | None:
        """The state kept after frame `index` (None when none is), left where it is in the
        least-recently-used order."""
        return self._states.get(index)

    def _restore(self, index: int) -> None:
        """Take up the state kept after frame `index`, now the most recently used."""
        self._states.move_to_end(index)
        self._take_up(self._states[index])

    def _take_up(self, state: EngineState) -> None:
        self._motion_stereo.restore(state.motion_stereo)
        self._tracker.restore(state.tracker)
        self._pitch_memory = state.pitch_memory
        self._vehicle_boxes = state.vehicle_boxes
        self._radar_points = state.radar_points
        self._rail_returns = state.rail_returns
        self._templates = state.templates
        self._last = state.last
        self._previous_image = state.previous_image

    def _nearest_kept(self, index: int, window: int) -> int | None:
        """The latest frame j with index - window < j < index whose state is kept."""
        return max((j for j in self._states if index - window < j < index), default=None)

    def _from_start_before(self, index: int) -> tuple[int, EngineState | None]:
        """The latest frame j before `index` whose from-start state the engine has (its own:
        None), keeps or finds among the milestones, with that state; (-1, None) when none:
        the drive's start."""
        j, state = -1, None
        if self._last is not None and self._last.from_start and self._last.index < index:
            j = self._last.index
        for k, kept in self._states.items():
            if kept.last.from_start and j < k < index:
                j, state = k, kept
        milestone = None if self.milestones is None else self.milestones.latest_before(index)
        if milestone is not None and milestone.last.index > j:
            j, state = milestone.last.index, milestone
        return j, state

    def _next_is_from_start(self, index: int) -> bool:
        """Would frame `index`, processed next, be from the start?"""
        if self._last is None:
            return index == 0 or self._next_from_start
        return self._last.from_start and index == self._last.index + 1

    def _catches_up(self, index: int, start: int) -> bool:
        """Is frame `index` within `catch_up_frames` of the from-start state after `start`?"""
        return self.catch_up_frames is None or index - start - 1 <= self.catch_up_frames

    def reaches_from_start(self, index: int) -> bool:
        """Would a seek to frame `index` now give its from-start result?"""
        return self._catches_up(index, self._from_start_before(index)[0])

    def seek(self, frames: Frames, index: int) -> FrameResult:
        """The result of frame `index` of `frames`: from the start when the latest from-start
        state before it (the engine's, a kept one or a milestone; the drive's start when
        none) lies at most `catch_up_frames` frames before it, after the frames in between;
        else after the frames in between from the latest state kept of a frame j with
        index - replay_window < j < index (module docstring); else processed next when it
        follows the last frame, and after the frames in between when it lies ahead of the
        last frame within `replay_window` (as playing on would); otherwise after a reset of
        the cross-frame state (the kept states stay) and a replay of up to `replay_window`
        frames. A frame in between that cannot be read (RecordingError) resets the state, as
        a gap in the drive would; the wanted frame's own RecordingError passes through.
        `replayed` counts the frames processed before `index`."""
        if not 0 <= index < len(frames):
            raise ValueError(f"index: expected a frame 0..{len(frames) - 1}, got {index}")
        window = replay_window(self.params)
        last = self.last_index
        wanted = frames.frame(index)
        start, state = self._from_start_before(index)
        kept = self._nearest_kept(index, window)
        if self._catches_up(index, start):
            if start < 0:
                self._start_over()
            elif state is not None:  # else play on from the engine's own
                self._take_up(state)
                if self._states.get(start) is state:
                    self._states.move_to_end(start)  # now the most recently used
            first = start + 1
        elif kept is not None:
            self._restore(kept)
            first = kept + 1
        elif last is not None and last < index <= last + window:
            first = last + 1  # play on from the state the engine has
        else:
            self._start_over()
            first = max(0, index - window)
        for i in range(first, index):
            try:
                frame = frames.frame(i)
            except RecordingError:
                self._start_over(self._next_is_from_start(i))
                continue
            self.process(frame)
        result = self.process(wanted)
        return replace(result, replayed=index - first)

    def preview(self, state: EngineState, frame: FrameInput) -> FrameResult:
        """`frame` processed on from `state`, which an engine under other parameters kept
        after the frame before it: what the inspector shows at once when a parameter
        changes, while `seek` replays the window under the new parameters.

        This frame's stages run under this engine's parameters; what they read of earlier
        frames (motion stereo's background, the pitch memory, the previous vehicle boxes,
        the tracks) is what the old parameters made, so the result is exact only where the
        change does not reach that state. The engine forgets its cross-frame state (the
        next `seek` starts over) and keeps no state of the preview. ValueError when
        `frame` does not follow `state`, or the state does not fit this engine's
        parameters (another bird's-eye grid, another pitch row step)."""
        if frame.index != state.last.index + 1:
            raise ValueError(
                f"frame: expected frame {state.last.index + 1}, which follows the state, "
                f"got frame {frame.index}"
            )
        try:
            self._take_up(state)
            return replace(self._process(frame), preview=True, from_start=False)
        finally:
            self._start_over()

    def process(self, frame: FrameInput) -> FrameResult:
        """One frame, the stages in the paper's order (module docstring). A frame that does
        not follow the last one (its index is not the next) starts over without history
        (the kept states stay)."""
        result = self._process(frame)
        last = self._last
        assert last is not None
        milestone = self.milestones is not None and self.milestones.due(last)
        if self.keep_states or milestone:
            state = self._state(last)
            if self.keep_states:
                self._keep(state)
            if milestone:
                assert self.milestones is not None
                self.milestones.add(state)
        return result

    def _process(self, frame: FrameInput) -> FrameResult:
        if self._last is not None and frame.index != self._last.index + 1:
            self._start_over()
        from_start = self._next_is_from_start(frame.index)
        p = self.params
        image = frame.image
        pitch, pitch_ms = _timed(
            lambda: detect_pitch(
                image, self.camera, p.pitch, self._pitch_memory, self._vehicle_boxes
            )
        )
        camera = self.camera.with_pitch(pitch.pitch_rad)
        ego = frame.ego if self._last is not None else None
        motion, motion_ms = _timed(lambda: self._motion_stereo.update(image, camera, ego))

        dt_s = 0.0 if self._last is None else max((frame.t_ns - self._last.t_ns) / NS_PER_S, 0.0)

        predicted = (
            self._tracker.predicted("vehicle", ego, dt_s)
            if p.vehicle.track_gate_m > 0
            or p.vehicle.track_search_frames > 0
            or p.vehicle.appearance_max_age_frames > 0
            else ()
        )

        def guard() -> tuple[tuple[SearchArea, ...], GuardRailResult, tuple[RailLine, ...]]:
            tracked_m = (
                [(t.x_m, t.y_m, t.width_m) for t in predicted] if p.vehicle.track_gate_m > 0 else []
            )
            centres_y_m, self._radar_points = smooth_centres(
                self._radar_points,
                frame.radar,
                ego,
                frame.speed_mps,
                dt_s,
                p.vehicle.lateral_smoothing_s,
                p.vehicle.lateral_smoothing_gate_m,
                p.vehicle.moving_speed_mps,
            )
            areas = search_areas(
                image, camera, frame.radar, p.vehicle, frame.speed_mps, tracked_m, centres_y_m
            )
            found = detect_guard_rails(areas, frame.speed_mps, p.guardrail)
            rails, lines, self._rail_returns = along_rail_lines(
                found, frame.radar, self._rail_returns, ego, dt_s, p.guardrail
            )
            return areas, rails, lines

        (areas, rails, rail_lines), rails_ms = _timed(guard)

        def vehicles() -> tuple[VehicleResult, TrackSearchResult, tuple[AppearanceMatch, ...]]:
            found = detect_vehicles(
                areas, frame.radar, camera, p.vehicle, rails.guard_rail_targets, image
            )
            searched = search_tracks(
                image, camera, predicted, frame.radar, found, p.vehicle, frame.speed_mps
            )
            vehicle = VehicleResult(found.targets, found.vehicles + searched.vehicles)
            looks = find_by_appearance(
                image, camera, predicted, self._templates, vehicle.vehicles, p.vehicle
            )
            return vehicle, searched, looks

        (vehicle, searched, appearance), vehicle_ms = _timed(vehicles)
        boxes = tuple(v.outline_px for v in vehicle.vehicles)
        pedestrian, pedestrian_ms = _timed(
            lambda: detect_pedestrians(
                image,
                camera,
                motion.image_mask,
                motion.image_mask_first_row_px,
                boxes,
                frame.radar,
                frame.speed_mps,
                p.pedestrian,
                self._previous_image,
                ego,
            )
        )
        measurements = tracker_measurements(
            vehicle, pedestrian, areas, rails.guard_rail_targets, searched, appearance
        )

        def track() -> TrackResult:
            tracks = update_tracks(self._tracker, measurements, ego, dt_s, camera, p)
            radar_vehicles = len(vehicle.vehicles) - len(searched.vehicles)
            self._templates = MappingProxyType(
                remember(
                    self._templates,
                    tracks.tracks,
                    image,
                    vehicle.vehicles,
                    radar_vehicles,
                    p.vehicle,
                )
            )
            return tracks

        tracks, tracking_ms = _timed(track)
        # read-only: the next frame reads it, and a kept state holds it by reference
        pitch.memory.row_histogram.flags.writeable = False
        self._pitch_memory = pitch.memory
        self._vehicle_boxes = boxes
        self._previous_image = (
            keep_for_image_motion(image) if p.pedestrian.image_motion_filter else None
        )
        self._last = _LastFrame(frame.index, frame.t_ns, from_start)
        return FrameResult(
            index=frame.index,
            t_ns=frame.t_ns,
            camera=camera,
            pitch=pitch,
            motion_stereo=motion,
            areas=areas,
            guardrail=rails,
            rail_lines=rail_lines,
            track_search=searched,
            appearance=appearance,
            vehicle=vehicle,
            pedestrian=pedestrian,
            tracking=tracks,
            timings=StageTimings(
                pitch_ms,
                motion_ms,
                rails_ms,
                vehicle_ms,
                pedestrian_ms,
                tracking_ms,
            ),
            replayed=0,
            from_start=from_start,
        )
