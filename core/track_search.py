"""Vision searches for the vehicles the tracker follows when no radar target returned them on
this frame (beyond the papers).

Paper 001 searches only where the radar points: a vehicle the radar drops for a frame is
not refined on that frame, and radar returns come and go (on drives of new seeds, 450 of
the 661 framed vehicles outside every search area on two stop_and_go drives had no return
on their footprint on that frame, though the radar saw them on others). The tracker knows
where each vehicle it follows should be. For each confirmed vehicle track as the tracker
predicts it on this frame (`core.tracking.Tracker.predicted`):

1. it is searched for when no radar target of the frame lies within `track_gate_m` of its
   prediction and it has gone fewer than `track_search_frames` consecutive frames without a
   detection backed by radar (`Track.unreturned`), so that vision alone never keeps a track
   alive for long;
2. not when the vehicles detected on this frame that are nearer than it by more than
   NEARER_GAP_M cover more than `track_search_hidden_fraction` of its expected box
   (`core.tracking.expected_boxes`): what a nearer vehicle hides, vision cannot frame;
3. a stand-in target at its predicted position (x_m, y_m) takes the radar return's place:
   its area is built as a tracked target's (`core.search_area.search_areas`: the moving
   targets' width, centred on the track) and searched as any other (`core.vehicle`, steps
   4-11);
4. the box found is kept when its lateral position and width agree with the track's within
   `track_search_agreement_m` (not a neighbour in the same area) and it overlaps no vehicle
   detected from a radar target by more than `merge_overlap_fraction` of the smaller box.

A vehicle found so carries no radar target (target_indices ()); its distance is the track's
prediction. The tracker gives it to the track it was searched for alone and does not take
its distance as measured (`core.tracking.Measurement.for_track`).

Notes:
    - All of it goes beyond the papers; `track_search_frames` 0 (the papers' preset) turns
      it off.
    - Step 1, at most 2 frames: on drives of new seeds (20 s each, seeds 1414 and 1717),
      unbounded, the raw refined vehicles rose most (stop_and_go RD 332 -> 516) but tracks
      kept alive by vision on vehicles the truth no longer frames doubled the track false
      positives (0.26 -> 0.58 per frame) and radar-seen MOTA fell (0.30 -> 0.21); 1 frame
      gained less on every scenario than 2.
    - Step 2: in a queue the van behind a car shows only its roof above it; without the
      check the searched box framed the whole van, whose truth box is its visible part
      (stop_and_go MOTA 0.268 without, 0.296 at 0.2, 0.290 at 0.5).
    - Step 4, 0.3 m: radar-seen MOTA on seeds 1414 + 1717 (highway / exurban /
      stop_and_go) 0.679 / 0.524 / 0.303 at 0.4 m, 0.662 / 0.526 / 0.337 at 0.3, 0.662 /
      0.526 / 0.333 at 0.25, 0.654 / 0.514 / 0.334 at 0.2: a box in a queue otherwise takes
      a neighbour's border.
    - Measured with `fusionscope evaluate` on held-out drives of new seeds (1313, 1818,
      1919, 2020; 20 s each), highway / exurban / stop_and_go, off -> on: RD / (RD + FN)
      0.869 / 0.730 / 0.550 -> 0.891 / 0.767 / 0.625; RD / framed 0.475 / 0.503 / 0.255 ->
      0.579 / 0.607 / 0.345; vehicle FP per frame (counting the found vehicles on no truth
      vehicle) 0.146 / 0.163 / 0.083 -> 0.149 / 0.168 / 0.090; radar-seen MOTA 0.581 /
      0.578 / 0.296 -> 0.623 / 0.590 / 0.361; track FP per frame 0.236 / 0.311 / 0.176 ->
      0.264 / 0.323 / 0.204; id switches 27 / 12 / 50 -> 15 / 9 / 32. The real drives do
      not change: nuScenes' tracks at 2 Hz and the aiMotive van, never refined, give
      nothing to search for.
    - The x of a searched detection is the prediction fed back; its variance (1 km)^2
      makes the update leave x and the velocity as predicted.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.frame import RadarTarget
from core.params import VehicleParams
from core.search_area import intersection_area, rect_area, search_areas
from core.tracking import Track, expected_boxes
from core.vehicle import Vehicle, VehicleResult, detect_vehicles, overlap_of_smaller

# Step 2: a detected vehicle hides a track's box only when it is nearer by more than this.
NEARER_GAP_M = 1.0


@dataclass(frozen=True, eq=False)
class TrackSearchResult:
    """track_ids: the tracks searched for, in the order of `search.targets` (their stand-in
    targets); search: the vehicle detector's work on their areas (verdicts, matrices,
    boxes); vehicles: the vehicles kept (step 4), without radar targets; track_of: the id
    of the track each of `vehicles` was searched for."""

    track_ids: tuple[int, ...]
    search: VehicleResult
    vehicles: tuple[Vehicle, ...]
    track_of: tuple[int, ...]


NOTHING = TrackSearchResult((), VehicleResult((), ()), (), ())


def _hidden_fraction(
    box: tuple[float, float, float, float], x_m: float, found: VehicleResult
) -> float:
    """The share of `box` covered by the found vehicles nearer than x_m - NEARER_GAP_M."""
    covered = sum(
        intersection_area(box, v.box_px)
        for v in found.vehicles
        if v.distance_m < x_m - NEARER_GAP_M
    )
    return min(covered / max(rect_area(box), 1e-9), 1.0)


def to_search(
    predicted: Sequence[Track],
    radar: Sequence[RadarTarget],
    found: VehicleResult,
    camera: CameraModel,
    params: VehicleParams,
) -> list[Track]:
    """Steps 1-2: the predicted confirmed vehicle tracks to search for on this frame."""
    if params.track_search_frames == 0:
        return []
    gate = params.track_gate_m
    unreturned = [
        t
        for t in predicted
        if t.kind == "vehicle"
        and t.confirmed
        and t.unreturned < params.track_search_frames
        and all(math.hypot(r.x_m - t.x_m, r.y_m - t.y_m) > gate for r in radar)
    ]
    boxes = expected_boxes(unreturned, camera)
    return [
        t
        for t, box in zip(unreturned, boxes, strict=True)
        if box is not None
        and _hidden_fraction(box, t.x_m, found) <= params.track_search_hidden_fraction
    ]


def search_tracks(
    image: npt.NDArray[np.uint8],
    camera: CameraModel,
    predicted: Sequence[Track],
    radar: Sequence[RadarTarget],
    found: VehicleResult,
    params: VehicleParams,
    ego_speed_mps: float = math.nan,
) -> TrackSearchResult:
    """Steps 1-4 on one frame (module docstring).

    image: the frame's (H, W) uint8 grey image; camera: the frame's camera; predicted: the
    tracker's vehicle tracks as predicted for this frame; radar: the frame's targets;
    found: the vehicles detected from them (`core.vehicle.detect_vehicles`);
    ego_speed_mps: the car's speed (NaN: unknown).
    """
    tracks = to_search(predicted, radar, found, camera, params)
    if not tracks:
        return NOTHING
    stand_ins = tuple(
        RadarTarget(math.hypot(t.x_m, t.y_m), math.atan2(t.y_m, t.x_m), 0.0, 0.0, t.x_m, t.y_m)
        for t in tracks
    )
    areas = search_areas(
        image,
        camera,
        stand_ins,
        params,
        ego_speed_mps,
        [(t.x_m, t.y_m, t.width_m) for t in tracks],
        [t.y_m for t in tracks],
    )
    search = detect_vehicles(areas, stand_ins, camera, params, frozenset(), image)
    kept: list[Vehicle] = []
    track_of: list[int] = []
    agreement = params.track_search_agreement_m
    for v in search.vehicles:
        agreeing = [
            tracks[i]
            for i in v.target_indices
            if abs(v.lateral_m - tracks[i].y_m) <= agreement
            and abs(v.width_m - tracks[i].width_m) <= agreement
        ]
        overlapping = any(
            overlap_of_smaller(v.box_px, f.box_px) > params.merge_overlap_fraction
            for f in found.vehicles
        )
        if agreeing and not overlapping:
            track = min(agreeing, key=lambda t: abs(v.lateral_m - t.y_m))
            # its body was placed at its stand-in targets' distance, the tracks' own
            kept.append(dataclasses.replace(v, distance_m=track.x_m, target_indices=()))
            track_of.append(track.id)
    return TrackSearchResult(tuple(t.id for t in tracks), search, tuple(kept), tuple(track_of))
