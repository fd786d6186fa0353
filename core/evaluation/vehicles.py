"""Paper 001's vehicle statistics (section III): frame-based RD, FN, RFN, FP, NVO, and events.

Paper 001 defines, per frame:
- RD  vehicles detected by radar and validated and refined by vision;
- FN  vehicles detected by radar but not validated or not correctly refined by vision;
- RFN vehicles not detected by radar or detected with a too low precision, made precise as
      "vehicles not contained, or not entirely contained, in any search area";
- FP  not-vehicle obstacles detected by radar and validated by vision;
- NVO not-vehicle obstacles detected by radar and not validated by vision;
and "refined" as position and size "with an error lower than 40 centimeters".

Here, on each frame:
- A *framed* vehicle is a truth car, van or truck less than MAX_OCCLUSION hidden, 0 to
  MAX_DISTANCE_M ahead. Each framed vehicle gets exactly one of RD, FN, RFN:
  - RD when an estimate (a detected vehicle, or a confirmed track for tracked output) lies
    within `refined_error_m` of it in distance (to its near face), lateral position and
    width;
  - otherwise RFN when no search area contains it entirely: across, the area's sides
    (at its target's distance) enclose the vehicle's width; in depth, the area's target
    lies on the vehicle (from ON_VEHICLE_MARGIN_M before its near face to as far behind
    it, past its length);
  - otherwise FN.
- Every radar target with a search area (a target supplied to vision) that lies on no truth
  vehicle (framed or not: a return from a hidden car is not a not-vehicle obstacle) is an
  NVO when no estimate came from it (a target the guard-rail filter labelled is one vision
  did not validate), and an FP when one did and that estimate's position (distance,
  lateral centre) lies on no truth vehicle either. A radar places some of a vehicle's
  returns beside it (paper 001 fig. 2; the synthetic radar 12 % of them, 0.2-0.8 m beyond
  its side): vision boxing that vehicle from such a return reports a vehicle that is there,
  which the first version of this module counted as an FP (Notes).
- Beyond the paper, an estimate that came from no radar target (a vehicle vision found
  where the tracker expected one, `core.track_search`; a track coasting through a frame
  without a detection) is an FP when its position lies on no truth vehicle, listed under
  the index -1 - its place among the frame's estimates.

Where the paper is ambiguous, and what was chosen:
- It counts a vehicle either refined or not contained, never both. A vehicle refined by an
  estimate although no area contains it entirely (the box may overshoot the area by less
  than the tolerance) counts RD: radar supplied it and vision refined it.
- "Refined" tolerances apply to the distance, the lateral centre and the width, each
  below `refined_error_m` (paper: "position and size").
- An event is "a vehicle present in more than 10 frames": more than EVENT_MIN_FRAMES frames
  in which it is framed, consecutive or not. It is a radar miss when no frame of it has an
  area containing it (RFN on all), refined by vision when at least one frame is RD, else
  not refined. Shares: refined / events, and refined / (events - radar misses), paper 001's
  "73 % of objects supplied to vision".

Notes:
    - The FP of a return beside a vehicle whose estimate lies on it: on drives of new seeds
      (20 s each, seeds 1818-2525), highway / exurban / stop_and_go, vehicle FP per frame
      0.069 / 0.121 / 0.084 counted per target alone, 0.037 / 0.065 / 0.050 with the
      estimate's position; of the highway boxes no longer counted, 14 of 19 overlapped a
      true vehicle's box by IoU >= 0.5. nuScenes and aiMotive: the same FP. The papers'
      preset on the bundled stop_and_go: FP 24 -> 22.

Beyond the paper, RD / (RD + FN) per class (`FrameStats.supplied_refined_share`): for the
framed cars, vans and trucks apart, the share of those radar supplied to vision that
vision refined (RFN left out); and the same share for the framed vehicles within
SUPPLIED_NEAR_M (`FrameStats.supplied_refined_share_near`), those a driver must not miss.

Beyond the paper, the distance error: for each framed vehicle that an estimate finds across
(lateral position and width within `refined_error_m`) less than DISTANCE_MATCH_M off in
distance, the estimate's distance minus the distance of the vehicle's near face, of the
estimate nearest in distance. Its median (signed: a bias) and the 90th percentile of its
size say how far the reported distance lies from the near face, RD or not.
"""

from __future__ import annotations

import math
import statistics
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

from core.io.frame import RadarTarget
from core.io.groundtruth import TruthObject
from core.search_area import iou

from .counts import add_fields

VEHICLE_CLASSES = ("car", "van", "truck")
MAX_OCCLUSION = 0.5  # a vehicle hidden this much or more is not framed
MAX_DISTANCE_M = 60.0  # beyond this no vehicle is framed
ON_VEHICLE_MARGIN_M = 0.5  # a radar point this close to a vehicle's footprint lies on it
EVENT_MIN_FRAMES = 10  # an event is a vehicle framed in more than this many frames
DISTANCE_MATCH_M = 5.0  # an estimate found across this near in distance measures the error
SUPPLIED_NEAR_M = 50.0  # RD / (RD + FN) is also given for the framed vehicles this near

VehicleVerdict = Literal["rd", "fn", "rfn"]
ObstacleVerdict = Literal["fp", "nvo"]


class Area(Protocol):
    """What the statistics read of a search area (core.search_area.SearchArea)."""

    @property
    def target_index(self) -> int: ...
    @property
    def y_left_m(self) -> float: ...
    @property
    def y_right_m(self) -> float: ...
    @property
    def x_m(self) -> float: ...


@dataclass(frozen=True)
class Estimate:
    """A vehicle the system reports: a detection, or a confirmed track for tracked output.
    distance_m: radar distance of its near face; lateral_m: centre, positive left;
    target_indices: the radar targets it came from; box_px: its image box (u0, v0, u1, v1),
    None when it has none."""

    distance_m: float
    lateral_m: float
    width_m: float
    target_indices: tuple[int, ...]
    box_px: tuple[float, float, float, float] | None = None


@dataclass(frozen=True)
class FrameVehicles:
    """One frame's verdicts: (truth id, verdict) per framed vehicle and (radar target index,
    verdict) per supplied target on no vehicle; rd_iou: for each RD vehicle in order, the
    IoU of its true image box with the best box of the estimates that refine it (NaN when
    none has a box); distance_error_m: the distance errors of the framed vehicles found
    across (module docstring); classes, distances_m: each framed vehicle's class and the
    distance of its near face, in `vehicles`' order."""

    index: int
    vehicles: tuple[tuple[int, VehicleVerdict], ...]
    obstacles: tuple[tuple[int, ObstacleVerdict], ...]
    rd_iou: tuple[float, ...] = ()
    distance_error_m: tuple[float, ...] = ()
    classes: tuple[str, ...] = ()
    distances_m: tuple[float, ...] = ()


@dataclass(frozen=True)
class FrameStats:
    """Frame-based counts over a drive, with (frame index, truth id) of every FN and RFN and
    (frame index, radar target index) of every FP and NVO."""

    rd: int
    fn: int
    rfn: int
    fp: int
    nvo: int
    fn_at: tuple[tuple[int, int], ...]
    rfn_at: tuple[tuple[int, int], ...]
    fp_at: tuple[tuple[int, int], ...]
    nvo_at: tuple[tuple[int, int], ...]
    # the box IoU of every RD (`FrameVehicles.rd_iou`): how well the box frames the vehicle,
    # which the 0.40 m criterion (distance, lateral centre, width) does not judge
    rd_iou: tuple[float, ...] = ()
    # `FrameVehicles.distance_error_m` of every frame: estimate minus near face, metres
    distance_error_m: tuple[float, ...] = ()
    # (class, verdict) of every framed vehicle on every frame
    class_verdicts: tuple[tuple[str, VehicleVerdict], ...] = ()
    # the verdict of every framed vehicle within SUPPLIED_NEAR_M on every frame
    near_verdicts: tuple[VehicleVerdict, ...] = ()

    @property
    def framed(self) -> int:
        return self.rd + self.fn + self.rfn

    @property
    def rd_iou_median(self) -> float:
        """Median box IoU of the RD with a box (NaN without one)."""
        known = [v for v in self.rd_iou if not math.isnan(v)]
        return statistics.median(known) if known else math.nan

    def rd_iou_share(self, at_least: float) -> float:
        """Share of the RD with a box whose IoU reaches `at_least` (NaN without one)."""
        known = [v for v in self.rd_iou if not math.isnan(v)]
        return sum(v >= at_least for v in known) / len(known) if known else math.nan

    @property
    def distance_error_median_m(self) -> float:
        """Median signed distance error (estimate minus near face; NaN without one)."""
        return statistics.median(self.distance_error_m) if self.distance_error_m else math.nan

    @property
    def distance_error_p90_m(self) -> float:
        """90th percentile of the distance error's size (NaN without one)."""
        if not self.distance_error_m:
            return math.nan
        sizes = sorted(abs(e) for e in self.distance_error_m)
        return sizes[min(len(sizes) - 1, math.ceil(0.9 * len(sizes)) - 1)]

    def supplied_refined_share(self, cls: str) -> float:
        """RD / (RD + FN) of the framed vehicles of class `cls`: the share of those radar
        supplied to vision that vision refined (NaN without one)."""
        rd = sum(c == cls and v == "rd" for c, v in self.class_verdicts)
        fn = sum(c == cls and v == "fn" for c, v in self.class_verdicts)
        return rd / (rd + fn) if rd + fn else math.nan

    @property
    def supplied_refined_share_near(self) -> float:
        """RD / (RD + FN) of the framed vehicles within SUPPLIED_NEAR_M (NaN without one)."""
        rd, fn = self.near_verdicts.count("rd"), self.near_verdicts.count("fn")
        return rd / (rd + fn) if rd + fn else math.nan

    def __add__(self, other: FrameStats) -> FrameStats:
        return add_fields(self, other)


@dataclass(frozen=True)
class EventStats:
    """Paper 001's table I row: events, radar misses, not refined, refined by vision."""

    events: int
    radar_miss: int
    not_refined: int
    refined: int

    @property
    def refined_share(self) -> float:
        return self.refined / self.events if self.events else 0.0

    @property
    def refined_share_of_radar_supplied(self) -> float:
        supplied = self.events - self.radar_miss
        return self.refined / supplied if supplied else 0.0

    def __add__(self, other: EventStats) -> EventStats:
        return add_fields(self, other)


def framed(o: TruthObject) -> bool:
    """A vehicle the statistics count on this frame."""
    return (
        o.cls in VEHICLE_CLASSES
        and o.occlusion < MAX_OCCLUSION
        and 0.0 < o.position_m[0] <= MAX_DISTANCE_M
    )


def lies_on(x_m: float, y_m: float, o: TruthObject) -> bool:
    """Is the point (x_m, y_m) on vehicle o's footprint (position_m: centre of its face
    towards the ego car; size_m: length, width, height), give or take ON_VEHICLE_MARGIN_M?"""
    x, y, _ = o.position_m
    length, width, _ = o.size_m
    return (
        x - ON_VEHICLE_MARGIN_M <= x_m <= x + length + ON_VEHICLE_MARGIN_M
        and abs(y_m - y) <= width / 2 + ON_VEHICLE_MARGIN_M
    )


def _contained(o: TruthObject, areas: Sequence[Area]) -> bool:
    _, y, _ = o.position_m
    half = o.size_m[1] / 2
    return any(
        a.y_right_m <= y - half and a.y_left_m >= y + half and lies_on(a.x_m, y, o) for a in areas
    )


def _across(o: TruthObject, e: Estimate, tolerance_m: float) -> bool:
    """The estimate finds o across: lateral position and width within the tolerance."""
    return abs(e.lateral_m - o.position_m[1]) < tolerance_m and (
        abs(e.width_m - o.size_m[1]) < tolerance_m
    )


def _refining(o: TruthObject, estimates: Sequence[Estimate], tolerance_m: float) -> list[Estimate]:
    x = o.position_m[0]
    return [
        e for e in estimates if abs(e.distance_m - x) < tolerance_m and _across(o, e, tolerance_m)
    ]


def _distance_error_m(o: TruthObject, estimates: Sequence[Estimate], tolerance_m: float) -> float:
    """Distance error of the estimate that finds o across nearest in distance (NaN: none)."""
    x = o.position_m[0]
    errors = [
        e.distance_m - x
        for e in estimates
        if _across(o, e, tolerance_m) and abs(e.distance_m - x) < DISTANCE_MATCH_M
    ]
    return min(errors, key=abs, default=math.nan)


def _best_iou(o: TruthObject, refining: Sequence[Estimate]) -> float:
    return max(
        (iou(e.box_px, o.box_px) for e in refining if e.box_px is not None), default=math.nan
    )


def score_frame(
    index: int,
    objects: Sequence[TruthObject],
    radar: Sequence[RadarTarget],
    areas: Sequence[Area],
    estimates: Sequence[Estimate],
    refined_error_m: float,
) -> FrameVehicles:
    """One frame's verdicts (module docstring): truth objects, the frame's radar targets,
    the search areas built for them, and the estimates to score."""
    vehicles: list[tuple[int, VehicleVerdict]] = []
    classes: list[str] = []
    distances_m: list[float] = []
    rd_iou: list[float] = []
    distance_error_m: list[float] = []
    for o in objects:
        if not framed(o):
            continue
        if not math.isnan(error := _distance_error_m(o, estimates, refined_error_m)):
            distance_error_m.append(error)
        verdict: VehicleVerdict
        if refining := _refining(o, estimates, refined_error_m):
            verdict = "rd"
            rd_iou.append(_best_iou(o, refining))
        elif not _contained(o, areas):
            verdict = "rfn"
        else:
            verdict = "fn"
        vehicles.append((o.id, verdict))
        classes.append(o.cls)
        distances_m.append(o.position_m[0])
    all_vehicles = [o for o in objects if o.cls in VEHICLE_CLASSES]

    def on_a_vehicle(x_m: float, y_m: float) -> bool:
        return any(lies_on(x_m, y_m, o) for o in all_vehicles)

    estimate_of = {i: e for e in estimates for i in e.target_indices}
    obstacles: list[tuple[int, ObstacleVerdict]] = []
    for i in sorted({a.target_index for a in areas}):
        t = radar[i]
        if on_a_vehicle(t.x_m, t.y_m):
            continue
        e = estimate_of.get(i)
        if e is None:
            obstacles.append((i, "nvo"))
        elif not on_a_vehicle(e.distance_m, e.lateral_m):
            obstacles.append((i, "fp"))
    for k, e in enumerate(estimates):
        if not e.target_indices and not on_a_vehicle(e.distance_m, e.lateral_m):
            obstacles.append((-1 - k, "fp"))
    return FrameVehicles(
        index,
        tuple(vehicles),
        tuple(obstacles),
        tuple(rd_iou),
        tuple(distance_error_m),
        tuple(classes),
        tuple(distances_m),
    )


def frame_stats(frames: Sequence[FrameVehicles]) -> FrameStats:
    """Counts over frames, with where each FN, RFN, FP and NVO happened."""
    at: dict[str, list[tuple[int, int]]] = {k: [] for k in ("rd", "fn", "rfn", "fp", "nvo")}
    for f in frames:
        for truth_id, verdict in f.vehicles:
            at[verdict].append((f.index, truth_id))
        for target, obstacle in f.obstacles:
            at[obstacle].append((f.index, target))
    return FrameStats(
        rd=len(at["rd"]),
        fn=len(at["fn"]),
        rfn=len(at["rfn"]),
        fp=len(at["fp"]),
        nvo=len(at["nvo"]),
        fn_at=tuple(at["fn"]),
        rfn_at=tuple(at["rfn"]),
        fp_at=tuple(at["fp"]),
        nvo_at=tuple(at["nvo"]),
        rd_iou=tuple(v for f in frames for v in f.rd_iou),
        distance_error_m=tuple(e for f in frames for e in f.distance_error_m),
        class_verdicts=tuple(  # frames built without classes (by hand) add none
            (c, v)
            for f in frames
            if f.classes
            for c, (_, v) in zip(f.classes, f.vehicles, strict=True)
        ),
        near_verdicts=tuple(
            v
            for f in frames
            if f.distances_m
            for d, (_, v) in zip(f.distances_m, f.vehicles, strict=True)
            if d <= SUPPLIED_NEAR_M
        ),
    )


def event_stats(frames: Sequence[FrameVehicles]) -> EventStats:
    """Paper 001's events over one drive's frames (module docstring)."""
    verdicts: dict[int, list[VehicleVerdict]] = defaultdict(list)
    for f in frames:
        for truth_id, verdict in f.vehicles:
            verdicts[truth_id].append(verdict)
    events = radar_miss = refined = 0
    for seen in verdicts.values():
        if len(seen) <= EVENT_MIN_FRAMES:
            continue
        events += 1
        if "rd" in seen:
            refined += 1
        elif all(v == "rfn" for v in seen):
            radar_miss += 1
    return EventStats(events, radar_miss, events - radar_miss - refined, refined)
