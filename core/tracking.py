"""Tracks of vehicles, pedestrians and guard-rail targets over time (beyond the papers).

Paper 001 (conclusions): "A tracking algorithm might be very helpful to increase the robustness
of the system and the detection persistence." Paper 002: "False positives are never consecutive
and may be easily filtered using a simple time correlation method." This module is both: one
track per object, confirmed after `confirm_frames` hits, kept through `max_missed_frames`
misses. The engine reports the papers' per-frame detections beside the confirmed tracks.

State of a track, in the current vehicle frame (x forward, y left, origin on the ground under
the rear axle): s = (x_m, y_m, vx_mps, vy_mps), the velocity over the ground expressed in the
vehicle axes (a parked car has 0), with its 4x4 covariance P; the width is a separate scalar
filter (a random walk).

`Tracker.update(measurements, ego, dt_s)`, one call per frame:

1. ego compensation: ego = (dx, dy, dyaw), the car's motion since the previous frame in the
   previous vehicle frame, moves every track into the new frame:
       p' = R(-dyaw) (p - (dx, dy)),   v' = R(-dyaw) v,   P' = T P T^T,  T = diag(R, R)(-dyaw)
   and the history points as p. Unknown ego motion (None) is taken as none, with
   `unknown_ego_sigma_m` added in quadrature to the position sigma on each axis.
2. prediction, constant velocity over dt_s: p += v dt_s; white acceleration of spectral
   density q per kind adds q [[dt^3/3, dt^2/2], [dt^2/2, dt]] per axis to P. The width's
   variance grows by `width_walk_m2ps` dt_s.
3. association, per kind only: innovation nu = z - p, S = P_pos + R; a pair is allowed when
   nu^T S^-1 nu <= `gate_chi2` and |nu| <= `gate_m` (a hard cap in metres, whatever the
   covariance). Among the allowed pairs the assignment with the most pairs, then the least sum
   of costs, is taken (`solve_assignment`, Hungarian method). A pair's cost is
   nu^T S^-1 nu + ln det S, twice the innovation's negative log-likelihood less a constant
   (`likelihood_cost`; without it nu^T S^-1 nu alone): an uncertain track, a newborn one
   whose speed is unknown, pays for its large S and does not take the detection a confirmed
   track predicted well. A detection searched for a track (`Measurement.for_track`,
   `core.track_search`) takes no part: it goes to that track when the track is left free
   and within its gates, else to none.
4. update, Kalman with z = (x_m, y_m), Joseph form. Measurement sigmas per kind: vehicles
   radar distance `radar_sigma_x_m` and vision lateral `vision_sigma_y_m`; pedestrians
   distance from the foot row `pedestrian_sigma_x_fraction` * x (at least
   `pedestrian_min_sigma_x_m`) and `vision_sigma_y_m`; guard rails `radar_sigma_x_m` and
   `guard_rail_sigma_y_m`. Width: sigma `width_sigma_m`. A searched detection's x_m is the
   track's prediction, not a measurement: its x variance is UNMEASURED_VAR_M2.
5. lifecycle: an unmatched measurement (not a searched one) starts a tentative track (its
   position and width measured, speed 0 with sigma `initial_velocity_sigma_mps`, id = the
   next integer). A track is confirmed once it has `confirm_frames` hits (a pedestrian's:
   `pedestrian_confirm_frames`) and stays confirmed. A tentative track is dropped at its
   (`tentative_max_missed_frames` + 1)-th consecutive miss, so a one-frame false positive is
   never confirmed, while a vehicle detected on two frames of three is;
   a confirmed track is dropped at its (`max_missed_frames` + 1)-th consecutive miss. The
   tracks reported (`Track.shown`, `TrackResult.of_kind`) are the confirmed ones and, beyond
   the papers, a tentative vehicle track on each frame it is measured once it has
   `show_vehicles_after_hits` hits (Notes), unless it lies within `early_clearance_ahead_m`
   and `early_clearance_across_m` of a confirmed vehicle track; nothing else about it
   changes: it lives, coasts and is searched for as a tentative track. A tentative track
   keeps its last box through its misses. A pedestrian track whose speed over the ground
   |v| is surely above a person's,
       |v| - `pedestrian_speed_gate_sigmas` sigma_v > `pedestrian_max_speed_mps`,
   sigma_v = sqrt(v^T C v) / |v|, C the velocity block of P, is tentative from then on: a
   "person" keeping pace with the traffic is a part of a vehicle (its wheels, its side),
   whose boxes would otherwise draw a track moving at highway speed. It keeps taking that
   object's detections, so they start no new track, until its first miss ends it. Dropped
   ids are listed in `TrackResult.ended` and never reused (until `Tracker.reset`).

6. boxes of tracks missed on this frame (`coasting_boxes`, the engine's step, with the frame's
   camera; `coasting_boxes_follow`): a confirmed vehicle or pedestrian track shows its last
   box where it expects its object now, from the predicted ground point and width, not where
   the box was last measured (a car drawing near while vision misses it for a frame or two).
   A pedestrian's expected ground point lies at most `pedestrian_coasting_speed_mps` dt_s
   per miss from its track's position at its last hit (a walking pace): the velocity of a
   pedestrian track of a few hits is mostly the noise of distances read from foot rows.

7. boxes cut to the image (`clipped_to_image`, the engine's step): a box is what the camera
   shows of its object. A vehicle drawing near beside the car runs off the image, and its
   coasting box with it, while its truth box (the visible part) ends at the border. A
   vehicle or pedestrian track whose outline lies wholly outside the image is not reported
   (the tracker keeps it; it shows again when its box comes back into the image).

`Tracker.state()` and `Tracker.restore(state)` keep and take up the tracks and the next id
(a seek back to a frame whose state was kept).

Guard rails are correlated the same way: every radar target labelled guard rail is a
measurement of kind "guard_rail"; its tracked verdict is membership of
`confirmed_sources(result, "guard_rail")`.

Notes:
    - All of it goes beyond the papers, which have no tracker; no parameter comes from them.
    - The association maximises the number of gated pairs before minimising the cost (what a
      cost matrix with large finite entries for the gated pairs gives); a track never takes a
      measurement of another kind.
    - Step 5, the papers' preset drops a tentative track at its first miss
      (`tentative_max_missed_frames` 0). Refined vehicles flicker (a box on one frame, none
      on the next), and such a vehicle's track was born again and again, never confirmed:
      on stop_and_go half the raw detections that fit their vehicle were taken by tentative
      tracks. Kept through one miss, radar-seen MOTA, 0 -> 1, on drives of new seeds (20 s
      each): seeds 404-606 highway 0.46 -> 0.49, exurban 0.41 -> 0.42, stop_and_go 0.20 ->
      0.23; seeds 101-303 and 707-909 0.55 -> 0.57, 0.42 -> 0.44, 0.24 -> 0.27, tracked RD /
      (RD + FN) up by 0.02-0.11 and above the raw detections' on stop_and_go, track FP per
      frame +0.00-0.01; nuScenes the same. Two misses did about as well on the synthetic
      drives and had, before the stricter vehicle bottoms, turned nuScenes' (2 Hz) MOTA
      from 0.14 to 0.03. With today's detections two misses do better (1 -> 2, radar-seen
      MOTA highway / exurban / stop_and_go, seeds 1818-2525: 0.629 / 0.555 / 0.424 ->
      0.619 / 0.552 / 0.453; seeds 1313-1717 + 2727: 0.681 / 0.574 / 0.385 -> 0.691 / 0.581
      / 0.392; seed 2929: 0.705 / 0.553 / 0.222 -> 0.705 / 0.566 / 0.222; track FP per frame
      within +0.02, raw vehicle FP per frame within 0.002; nuScenes and aiMotive the
      same).
    - Step 5, pedestrians confirmed after 2 hits (`pedestrian_confirm_frames`; vehicles and
      guard rails 3; the papers' preset 3 for every kind): after the HOG verification
      (`core.pedestrian`, step 6) a pedestrian detection is rarely false (precision
      0.97-1.00 on drives of new seeds), and the third hit a confirmation waited for lost
      the people the detector finds on two frames of three: tracked recall on exurban was
      below the raw detections'. Tracked pedestrian recall / precision, 3 -> 2, on drives of
      new seeds (20 s each), exurban and stop_and_go: seeds 1818-2525 0.208 / 0.956 -> 0.258
      / 0.901 and 0.595 / 0.979 -> 0.635 / 0.977; held out, seeds 4242 + 4343 0.179 / 0.897
      -> 0.274 / 0.924 and 0.685 / 0.980 -> 0.731 / 0.962, seeds 5151 + 5252 (made after
      the change) 0.174 / 0.929 -> 0.235 / 0.877 and 0.559 / 0.989 -> 0.590 / 0.979;
      pedestrian MOTA the same or higher everywhere (exurban 0.151 / 0.101 / 0.128 -> 0.155
      / 0.111 / 0.161); false pedestrian tracks per frame on highway (no people) 0 -> 0.005
      to 0.011, every false box a confirmed track coasting after it lost its detection.
      Vehicles, guard rails and the real drives the same. One hit (no confirmation) gave
      exurban 0.37 / 0.91 and highway 0.075 false tracks per frame.
    - Step 5, vehicle tracks shown from their second hit on the frames they are measured
      (`show_vehicles_after_hits` 2; the papers' preset 0: once confirmed, the third hit):
      of the framed vehicles the raw detections refined and the confirmed tracks did not,
      70 of 81 (exurban 1818 + 1919, highway 1818) were tentative tracks of one or two
      hits, and tracked RD / (RD + FN) on exurban was below the raw detections'.
      Confirming on the second hit instead gained as much but raised track FP per frame
      0.002 -> 0.033 (highway) and 0.037 -> 0.099 (stop_and_go), and on the aiMotive night
      motorway a box on oncoming lights became a track kept for 10 frames by its look
      (`core.appearance`): two-hit tracks coasted, were searched for and carried their
      look. Shown early, a track does none of that, and the raw detections stay exactly the
      same. Measured on drives of new seeds (20 s each), highway / exurban / stop_and_go,
      off -> on, tracked RD / (RD + FN), radar-seen MOTA, track FP per frame: seeds
      1818-2121 0.921 / 0.779 / 0.739 -> 0.934 / 0.809 / 0.759, 0.849 / 0.594 / 0.553 ->
      0.859 / 0.618 / 0.559, 0.002 / 0.026 / 0.037 -> 0.005 / 0.030 / 0.045; held out,
      seeds 4242 + 4343 + 5151 + 5252 0.911 / 0.758 / 0.760 -> 0.927 / 0.786 / 0.785,
      0.833 / 0.626 / 0.596 -> 0.847 / 0.647 / 0.598, 0.006 / 0.013 / 0.040 -> 0.007 /
      0.016 / 0.052; seeds 6161 + 6262 0.910 / 0.782 / 0.683 -> 0.924 / 0.811 / 0.708,
      0.843 / 0.674 / 0.487 -> 0.859 / 0.697 / 0.486, 0.007 / 0.020 / 0.072 -> 0.007 /
      0.022 / 0.080. Tracked RD is now above the raw detections' on every set. nuScenes
      tracked RD 0.642 -> 0.660, MOTA 0.221 -> 0.228; aiMotive one false track frame in 50
      (the oncoming lights' box on its second frame).
    - Step 5, no early track shown within 4 m ahead and 2 m across of a confirmed vehicle
      track (`early_clearance_ahead_m`, `early_clearance_across_m`): such a track was most
      often a second one on the confirmed track's vehicle, a false box and an id switch.
      Measured on drives of new seeds (20 s each), stop_and_go track FP per frame and
      vehicle id switches over all three scenarios, without -> with: seeds 1818-2121 0.045
      -> 0.040, 41 -> 40; held out, seeds 4242-5252 0.052 -> 0.043, 57 -> 48; seeds 6161 +
      6262 0.080 -> 0.072, 24 -> 23; seeds 8181 + 8282 0.048 -> 0.043, 19 -> 19.
      Radar-seen MOTA the same or higher on every set and scenario (stop_and_go +0.004 to
      +0.011), tracked RD / (RD + FN) within -0.002; the real drives the same.
    - Step 6: a coasting box left where it was measured no longer overlaps its vehicle by the
      tracking figures' IoU 0.5 once the vehicle has moved a few pixels in the image: on drives
      of seeds 1313 and 1414 (tuning, 20 s each), radar-seen MOTA highway / exurban /
      stop_and_go 0.595 / 0.562 / 0.347 -> 0.598 / 0.578 / 0.349; held out, seeds 1717-2020:
      0.585 / 0.501 / 0.226 -> 0.591 / 0.533 / 0.270, track FP per frame 0.27 / 0.41 / 0.29 ->
      0.26 / 0.37 / 0.23; nuScenes scene-0523 0.179 -> 0.207. Raw detections are the same.
    - Step 6, pedestrians at a walking pace: every false pedestrian track box was a confirmed
      track coasting, most of 2-3 hits, whose velocity (4-14 m/s, from foot-row distances
      whose sigma is 10 % of x) carried the box off its person by a box's width in a frame
      or two. Tracked pedestrian recall / precision, exurban and stop_and_go, predicted ->
      at most 1.5 m/s from the last hit, on drives of new seeds (20 s each): seeds 1818-2121
      0.240 / 0.897 -> 0.256 / 0.949 and 0.620 / 0.979 -> 0.620 / 0.978; held out, seeds
      4242, 4343, 5151: 0.263 / 0.932 -> 0.268 / 0.945 and 0.633 / 0.963 -> 0.644 / 0.980,
      pedestrian MOTA up by 0.01-0.02; highway, the vehicles and the real drives the same.
      Checked afterwards on seeds not used before (7373, 7474): exurban 0.276 / 0.923 ->
      0.283 / 0.945, but stop_and_go 0.634 / 0.983 -> 0.629 / 0.974 (people 10-12 m away
      crossing at about 2 m/s, whose coasting boxes now lag). Pooled over the three sets
      (nine seeds): exurban 0.255 / 0.915 -> 0.265 / 0.947, stop_and_go 0.628 / 0.975 ->
      0.630 / 0.978, false tracked boxes per frame 0.019 / 0.027 -> 0.012 / 0.023.
      1.0 m/s did as well or a little better (held out stop_and_go 0.646 / 0.985; kept at
      1.5, a normal walking pace, rather than the synthetic walkers' own), 2.0 and 3.0 less
      (exurban precision 0.931, 0.920); the box left where the track was at its last hit
      (no walking) lost stop_and_go's crossing people (0.613 / 0.969); a prior of 1-4 m/s
      on a new pedestrian's velocity instead of 15 made it worse (exurban precision
      0.86-0.90). Not showing the coasting boxes of tracks under 3 hits gave exurban 0.223
      / 0.986, the raw detections' figures.
    - Step 7: the truth boxes of the evaluation are the visible parts, which end at the
      image border; oncoming and overtaking cars 3-10 m away in the next lane ran off the
      image while their coasting boxes (and their bodies) kept the whole vehicle, IoU 0 with
      the truth. Radar-seen MOTA, highway / exurban / stop_and_go, unclipped -> clipped, on
      drives of new seeds (20 s each): seeds 1818, 2121, 2424, 2525 0.703 / 0.570 / 0.461 ->
      0.703 / 0.596 / 0.461; seeds 1919, 2020, 2222, 2323 0.600 / 0.594 / 0.499 -> 0.603 /
      0.618 / 0.499; the real drives and the detections the same.
    - Step 7, tracks wholly outside the image: a person walking out of the image, or a car
      overtaken, left a confirmed track coasting for up to max_missed_frames with an empty
      box, which the evaluation counted as a false box. Not reporting them, seeds
      1818-2525: tracked pedestrian precision exurban / stop_and_go 0.872 / 0.974 -> 0.956 /
      0.979 (recall the same), radar-seen MOTA highway / exurban / stop_and_go 0.834 / 0.581
      / 0.478 -> 0.836 / 0.594 / 0.478, tracked RD / framed on exurban 0.642 -> 0.635 (a
      vehicle at the image's edge whose track's box had run just outside); held out, seeds
      4242 and 4343: exurban pedestrian precision 0.792 -> 0.897, MOTA 0.611 -> 0.618, the
      others the same; nuScenes and aiMotive the same.
    - `ego.dt_s` is not used: `dt_s` is the interval of the prediction (the engine passes the
      same interval to both).
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.checks import require_finite
from core.ego import EgoMotion
from core.params import TrackingParams

Kind = Literal["vehicle", "pedestrian", "guard_rail"]
KINDS: tuple[Kind, ...] = ("vehicle", "pedestrian", "guard_rail")

Box = tuple[float, float, float, float]
# The x variance of a detection searched for a track (`Measurement.for_track`), whose x_m
# is the track's own prediction: (1 km)^2, so that the update leaves x as predicted.
UNMEASURED_VAR_M2 = 1e6
FloatArray = npt.NDArray[np.float64]


def _require_kind(name: str, kind: object) -> None:
    if kind not in KINDS:
        raise ValueError(f"{name}: expected one of {', '.join(KINDS)}, got {kind!r}")


@dataclass(frozen=True)
class Measurement:
    """One detection of this frame in the current vehicle frame (x forward, y left).

    x_m: distance ahead (radar for vehicles and guard rails; ground plane for pedestrians);
    y_m: lateral centre, positive left; width_m: vision width (0.0 for guard rails); box_px:
    (u0, v0, u1, v1) full-image pixels ((0, 0, 0, 0) allowed); source_index: index of the
    detection in the engine's per-frame list of its kind; for_track: the id of the track
    this detection was searched for without a radar return (`core.track_search`): x_m is
    that track's prediction, not a measurement, and the detection goes to that track or to
    none (None: an ordinary detection). ValueError naming the field when a number is not
    finite, width_m < 0, the box is inverted or source_index < 0.
    """

    kind: Kind
    x_m: float
    y_m: float
    width_m: float
    box_px: Box
    source_index: int
    for_track: int | None = None

    def __post_init__(self) -> None:
        _require_kind("kind", self.kind)
        for name in ("x_m", "y_m", "width_m"):
            require_finite(name, getattr(self, name))
        if self.width_m < 0:
            raise ValueError(f"width_m: expected a width >= 0, got {self.width_m}")
        if len(self.box_px) != 4:
            raise ValueError(f"box_px: expected (u0, v0, u1, v1), got {self.box_px!r}")
        for value in self.box_px:
            require_finite("box_px", value)
        u0, v0, u1, v1 = self.box_px
        if u1 < u0 or v1 < v0:
            raise ValueError(f"box_px: expected u1 >= u0 and v1 >= v0, got {self.box_px!r}")
        index = self.source_index
        if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
            raise ValueError(f"source_index: expected an integer >= 0, got {self.source_index!r}")
        track = self.for_track
        if track is not None and (isinstance(track, bool) or not isinstance(track, int)):
            raise ValueError(f"for_track: expected a track id or None, got {track!r}")


@dataclass(frozen=True)
class Track:
    """One tracked object after an update, in the current vehicle frame.

    id: unique within a Tracker since its last reset, from 1. x_m, y_m: filtered position;
    vx_mps, vy_mps: velocity over the ground in the vehicle axes; width_m: filtered width;
    sigma_x_m, sigma_y_m: sqrt of the position covariance diagonal; box_px: the last associated
    detection's box (moved by `coasting_boxes` for a confirmed track missed this frame); hits:
    frames with a detection; misses: consecutive frames without one (0 when measured this
    frame); age: frames since birth (1 on the first); confirmed: hits reached
    confirm_frames; shown_early: a vehicle track not yet confirmed, measured this frame with
    `show_vehicles_after_hits` hits or more (step 5); source_index: this frame's
    Measurement.source_index, None when missed; history_m: up to history_length filtered
    positions (x_m, y_m), oldest first, this frame's last, all in the current vehicle frame;
    unreturned: consecutive frames without a detection backed by radar (a miss or a
    detection searched for the track, `for_track`); body_px: the box of a vehicle's body
    around box_px (`core.vehicle.body_box`, set by the engine; None: box_px's).
    """

    id: int
    kind: Kind
    x_m: float
    y_m: float
    vx_mps: float
    vy_mps: float
    width_m: float
    sigma_x_m: float
    sigma_y_m: float
    box_px: Box
    hits: int
    misses: int
    age: int
    confirmed: bool
    source_index: int | None
    history_m: tuple[tuple[float, float], ...]
    unreturned: int = 0
    body_px: Box | None = None
    shown_early: bool = False

    @property
    def shown(self) -> bool:
        """Reported as a track (step 5): confirmed, or shown early."""
        return self.confirmed or self.shown_early

    @property
    def outline_px(self) -> Box:
        """The box shown and scored: the body's, else box_px."""
        return self.box_px if self.body_px is None else self.body_px


@dataclass(frozen=True)
class TrackResult:
    """Every live track after an update (tentative and confirmed), ordered by id, and the ids
    dropped by it (tentative tracks after more than tentative_max_missed_frames misses,
    confirmed ones after more than max_missed_frames), ascending."""

    tracks: tuple[Track, ...]
    ended: tuple[int, ...]

    @property
    def confirmed(self) -> tuple[Track, ...]:
        return tuple(t for t in self.tracks if t.confirmed)

    @property
    def shown(self) -> tuple[Track, ...]:
        """The tracks reported: confirmed or shown early (`Track.shown`)."""
        return tuple(t for t in self.tracks if t.shown)

    def of_kind(self, kind: Kind, shown_only: bool = True) -> tuple[Track, ...]:
        """The tracks of one kind, only the shown ones (`Track.shown`) by default."""
        _require_kind("kind", kind)
        return tuple(t for t in self.tracks if t.kind == kind and (t.shown or not shown_only))


def confirm_frames_of(kind: Kind, params: TrackingParams) -> int:
    """The hits that confirm a track of `kind` (step 5)."""
    return params.pedestrian_confirm_frames if kind == "pedestrian" else params.confirm_frames


def confirmed_sources(result: TrackResult, kind: Kind) -> frozenset[int]:
    """source_index of this frame's measurements of `kind` taken by a confirmed track."""
    _require_kind("kind", kind)
    return frozenset(
        t.source_index
        for t in result.tracks
        if t.kind == kind and t.confirmed and t.source_index is not None
    )


def expected_boxes(tracks: Sequence[Track], camera: CameraModel) -> list[Box | None]:
    """Where each track's box is expected on this frame from its position and width: the
    bottom row is the image of the ground point (x_m, y_m, 0), the sides the images of
    (x_m, y_m +- width_m / 2, 0), the height the last box's height / width times the new
    width. None for a track without a width or a last box, or whose points do not all land
    in front of the camera."""
    if not tracks:
        return []
    points = np.array(
        [(t.x_m, t.y_m + side * t.width_m / 2, 0.0) for t in tracks for side in (0, 1, -1)]
    )
    uv, in_front = camera.project(points)
    boxes: list[Box | None] = []
    for i, t in enumerate(tracks):
        (_, v), (u_left, _), (u_right, _) = uv[3 * i : 3 * i + 3].tolist()
        u0, v0, u1, v1 = t.box_px
        if not (in_front[3 * i : 3 * i + 3].all() and u_right > u_left and u1 > u0):
            boxes.append(None)
            continue
        height_px = (v1 - v0) / (u1 - u0) * (u_right - u_left)
        boxes.append((u_left, v - height_px, u_right, v))
    return boxes


def _walked(track: Track, step_m: float) -> Track:
    """A missed pedestrian track at most step_m per miss from its position at its last hit
    (step 6); the track as it is when its history does not reach back to that hit."""
    if len(track.history_m) <= track.misses:
        return track
    x_m, y_m = track.history_m[-1 - track.misses]
    dx_m, dy_m = track.x_m - x_m, track.y_m - y_m
    share = min(1.0, step_m * track.misses / max(math.hypot(dx_m, dy_m), 1e-9))
    return replace(track, x_m=x_m + share * dx_m, y_m=y_m + share * dy_m)


def coasting_boxes(
    result: TrackResult, camera: CameraModel, pedestrian_step_m: float = math.inf
) -> TrackResult:
    """`result` with each confirmed vehicle or pedestrian track missed on this frame showing
    its last box where the track expects its object now (step 6, `expected_boxes`), a
    pedestrian's at most pedestrian_step_m per miss from where it was at its last hit; a
    track without an expected box keeps its last box."""
    moving = [
        t
        for t in result.tracks
        if t.confirmed and t.misses and t.kind != "guard_rail" and t.width_m > 0
    ]
    expected = [_walked(t, pedestrian_step_m) if t.kind == "pedestrian" else t for t in moving]
    boxes = {t.id: b for t, b in zip(moving, expected_boxes(expected, camera), strict=True) if b}
    if not boxes:
        return result
    return TrackResult(
        tuple(replace(t, box_px=boxes[t.id]) if t.id in boxes else t for t in result.tracks),
        result.ended,
    )


def _clipped(box: Box, width_px: int, height_px: int) -> Box:
    u0, v0, u1, v1 = box
    right, bottom = width_px - 0.5, height_px - 0.5  # the image's outer pixel edges
    return (
        min(max(u0, -0.5), right),
        min(max(v0, -0.5), bottom),
        min(max(u1, -0.5), right),
        min(max(v1, -0.5), bottom),
    )


def clipped_to_image(result: TrackResult, camera: CameraModel) -> TrackResult:
    """`result` with every box (`box_px`, `body_px`) cut to the image and without the vehicle
    and pedestrian tracks whose outline lies wholly outside it (step 7); the tracks whose
    boxes lie inside it are the same objects."""
    w, h = camera.intrinsics.width_px, camera.intrinsics.height_px
    tracks = []
    for t in result.tracks:
        box = _clipped(t.box_px, w, h)
        body = None if t.body_px is None else _clipped(t.body_px, w, h)
        cut = t if box == t.box_px and body == t.body_px else replace(t, box_px=box, body_px=body)
        u0, v0, u1, v1 = cut.outline_px
        if cut is t or t.kind == "guard_rail" or (u1 > u0 and v1 > v0):
            tracks.append(cut)
    return TrackResult(tuple(tracks), result.ended)


def solve_assignment(cost: FloatArray) -> tuple[tuple[int, int], ...]:
    """Optimal assignment of rows to columns, (row, col) pairs in ascending row order.

    cost: (R, C) float64; +inf marks a forbidden pair, the others must be finite. The result
    has the most pairs possible among the allowed ones and, among those, the least total cost.
    Hungarian method with potentials (O(n^2 m)), forbidden pairs as a finite cost larger than
    any difference of allowed totals, so the most pairs come first. When every row and every
    column has at most one allowed pair, those pairs are the answer and the method is skipped.
    """
    if cost.ndim != 2:
        raise ValueError(f"cost: expected an (R, C) array, got shape {cost.shape}")
    if np.isnan(cost).any() or np.isneginf(cost).any():
        raise ValueError("cost: expected finite costs or +inf for a forbidden pair, got nan/-inf")
    return tuple(sorted(_assign(cost.astype(np.float64).tolist())))


def _assign(cost: list[list[float]]) -> list[tuple[int, int]]:
    """solve_assignment on a checked cost matrix given as rows of floats, pairs in any order.

    When every row and every column has at most one allowed pair (no pair allowed included),
    those pairs are the only largest matching, which the Hungarian method would return too.
    """
    allowed = [[j for j, c in enumerate(row) if c != math.inf] for row in cost]
    if all(len(cols) <= 1 for cols in allowed):
        pairs = [(i, cols[0]) for i, cols in enumerate(allowed) if cols]
        if len({j for _, j in pairs}) == len(pairs):
            return pairs
    transposed = len(cost) > len(cost[0])
    a = [list(col) for col in zip(*cost, strict=True)] if transposed else cost
    n, m = len(a), len(a[0])
    finite = [c for row in a for c in row if c != math.inf]
    top = max(finite)
    forbidden = top + 2.0 * n * (top - min(finite)) + 1.0
    big = [[forbidden if c == math.inf else c for c in row] for row in a]
    # e-maxx formulation, 1-based with a virtual column 0
    u = [0.0] * (n + 1)
    v = [0.0] * (m + 1)
    row_of = [0] * (m + 1)  # row_of[j]: row assigned to column j (0: none)
    way = [0] * (m + 1)
    for i in range(1, n + 1):
        row_of[0] = i
        j0 = 0
        minv = [math.inf] * (m + 1)
        used = [False] * (m + 1)
        while True:
            used[j0] = True
            i0 = row_of[j0]
            row, u_i0 = big[i0 - 1], u[i0]
            delta, j1 = math.inf, 0
            for j in range(1, m + 1):
                if not used[j]:
                    reduced = row[j - 1] - u_i0 - v[j]
                    if reduced < minv[j]:
                        minv[j] = reduced
                        way[j] = j0
                    if minv[j] < delta:
                        delta, j1 = minv[j], j
            for j in range(m + 1):
                if used[j]:
                    u[row_of[j]] += delta
                    v[j] -= delta
                else:
                    minv[j] -= delta
            j0 = j1
            if row_of[j0] == 0:
                break
        while j0 != 0:
            j1 = way[j0]
            row_of[j0] = row_of[j1]
            j0 = j1
    pairs = [
        (row_of[j] - 1, j - 1)
        for j in range(1, m + 1)
        if row_of[j] != 0 and a[row_of[j] - 1][j - 1] != math.inf
    ]
    return [(c, r) for r, c in pairs] if transposed else pairs


def _measurement_var(params: TrackingParams, m: Measurement) -> tuple[float, float]:
    """The diagonal of R, the covariance of a measurement's (x_m, y_m), m^2. A detection
    searched for a track does not measure x_m: its variance is UNMEASURED_VAR_M2."""
    if m.for_track is not None:
        return UNMEASURED_VAR_M2, params.vision_sigma_y_m**2
    if m.kind == "vehicle":
        sx, sy = params.radar_sigma_x_m, params.vision_sigma_y_m
    elif m.kind == "pedestrian":
        sx = max(params.pedestrian_sigma_x_fraction * abs(m.x_m), params.pedestrian_min_sigma_x_m)
        sy = params.vision_sigma_y_m
    else:
        sx, sy = params.radar_sigma_x_m, params.guard_rail_sigma_y_m
    return sx * sx, sy * sy


def _process_noise(params: TrackingParams, dt_s: float) -> dict[Kind, tuple[float, float, float]]:
    """Per kind, the entries of Q on one axis: (q dt^3/3, q dt^2/2, q dt)."""
    psd: dict[Kind, float] = {
        "vehicle": params.vehicle_accel_psd_m2ps3,
        "pedestrian": params.pedestrian_accel_psd_m2ps3,
        "guard_rail": params.guard_rail_accel_psd_m2ps3,
    }
    return {k: (q * dt_s**3 / 3.0, q * dt_s**2 / 2.0, q * dt_s) for k, q in psd.items()}


def _turned(
    m00: float, m01: float, m10: float, m11: float, cos: float, sin: float
) -> tuple[float, float, float, float]:
    """R M R^T for R = [[cos, -sin], [sin, cos]] and M = [[m00, m01], [m10, m11]], row by row."""
    r00, r01 = cos * m00 - sin * m10, cos * m01 - sin * m11  # R M
    r10, r11 = sin * m00 + cos * m10, sin * m01 + cos * m11
    return (
        r00 * cos - r01 * sin,
        r00 * sin + r01 * cos,
        r10 * cos - r11 * sin,
        r10 * sin + r11 * cos,
    )


Row = tuple[float, float, float, float]


def _minus(v: Row, a: float, w0: Row, b: float, w1: Row) -> Row:
    """v - a w0 - b w1 for 4-vectors."""
    return (
        v[0] - a * w0[0] - b * w1[0],
        v[1] - a * w0[1] - b * w1[1],
        v[2] - a * w0[2] - b * w1[2],
        v[3] - a * w0[3] - b * w1[3],
    )


class _TrackState:
    """The mutable filter behind one Track: s and P as in the module docstring.

    s = (x, y, vx, vy) are four floats; P is kept as its upper triangle, row by row,
    (P00, P01, P02, P03, P11, P12, P13, P22, P23, P33), and read in 2x2 blocks: A = P[:2, :2]
    (position), B = P[:2, 2:] (position-velocity), C = P[2:, 2:] (velocity). Plain floats,
    because numpy's overhead per call dwarfs the arithmetic of 4x4 matrices.
    """

    def __init__(
        self, track_id: int, m: Measurement, r: tuple[float, float], params: TrackingParams
    ) -> None:
        self.id = track_id
        self.kind: Kind = m.kind
        self.x, self.y, self.vx, self.vy = float(m.x_m), float(m.y_m), 0.0, 0.0
        v0 = params.initial_velocity_sigma_mps**2
        self.P = (r[0], 0.0, 0.0, 0.0, r[1], 0.0, 0.0, v0, 0.0, v0)
        self.width_m = float(m.width_m)
        self.width_var_m2 = params.width_sigma_m**2
        self.box_px = m.box_px
        self.hits, self.misses, self.age = 1, 0, 1
        self.unreturned = 0  # a searched detection never starts a track
        self.confirmed = self.hits >= confirm_frames_of(self.kind, params)
        self.too_fast = False  # a pedestrian track that moved surely faster than a person
        self.source_index: int | None = m.source_index
        self.history_m: tuple[tuple[float, float], ...] = ((self.x, self.y),)

    def move(self, cos: float, sin: float, dx_m: float, dy_m: float) -> None:
        """Step 1: into the new vehicle frame; (cos, sin) of -dyaw.

        Every block of P turns as R(-dyaw) M R(-dyaw)^T, which is T P T^T.
        """
        x, y = self.x - dx_m, self.y - dy_m
        self.x, self.y = cos * x - sin * y, sin * x + cos * y
        self.vx, self.vy = cos * self.vx - sin * self.vy, sin * self.vx + cos * self.vy
        p00, p01, p02, p03, p11, p12, p13, p22, p23, p33 = self.P
        a00, a01, _, a11 = _turned(p00, p01, p01, p11, cos, sin)
        b00, b01, b10, b11 = _turned(p02, p03, p12, p13, cos, sin)
        c00, c01, _, c11 = _turned(p22, p23, p23, p33, cos, sin)
        self.P = (a00, a01, b00, b01, a11, b10, b11, c00, c01, c11)
        history = []
        for hx, hy in self.history_m:
            x, y = hx - dx_m, hy - dy_m
            history.append((cos * x - sin * y, sin * x + cos * y))
        self.history_m = tuple(history)

    def stay(self, lost_var_m2: float) -> None:
        """Step 1 for an unknown ego motion: no move, lost_var_m2 added to P00 and P11."""
        p00, p01, p02, p03, p11, p12, p13, p22, p23, p33 = self.P
        self.P = (p00 + lost_var_m2, p01, p02, p03, p11 + lost_var_m2, p12, p13, p22, p23, p33)

    def predict(self, dt_s: float, q: tuple[float, float, float], width_growth_m2: float) -> None:
        """Step 2: constant velocity with white acceleration, P = F P F^T + Q.

        In blocks, F P F^T has C' = C, B' = B + dt C and A' = A + dt (B^T + B'); q is Q's
        (position, cross, velocity) entry on each axis.
        """
        self.x += self.vx * dt_s
        self.y += self.vy * dt_s
        q_pos, q_cross, q_vel = q
        p00, p01, p02, p03, p11, p12, p13, p22, p23, p33 = self.P
        b00, b01, b10, b11 = p02 + dt_s * p22, p03 + dt_s * p23, p12 + dt_s * p23, p13 + dt_s * p33
        self.P = (
            p00 + dt_s * p02 + dt_s * b00 + q_pos,
            p01 + dt_s * p12 + dt_s * b01,
            b00 + q_cross,
            b01,
            p11 + dt_s * p13 + dt_s * b11 + q_pos,
            b10,
            b11 + q_cross,
            p22 + q_vel,
            p23,
            p33 + q_vel,
        )
        self.width_var_m2 += width_growth_m2

    def gated_cost(
        self, z_x: float, z_y: float, r: tuple[float, float], params: TrackingParams
    ) -> float:
        """Step 3: the cost of taking z, or inf outside the gates; r: the diagonal of R."""
        nu_x, nu_y = z_x - self.x, z_y - self.y
        if math.hypot(nu_x, nu_y) > params.gate_m:
            return math.inf
        p00, p01, _, _, p11 = self.P[:5]
        s00, s01, s11 = p00 + r[0], p01, p11 + r[1]
        det = s00 * s11 - s01 * s01
        d2 = (s11 * nu_x * nu_x - 2.0 * s01 * nu_x * nu_y + s00 * nu_y * nu_y) / det
        if d2 > params.gate_chi2:
            return math.inf
        return d2 + math.log(det) if params.likelihood_cost else d2

    def correct(
        self, m: Measurement, z: tuple[float, float], r: tuple[float, float], params: TrackingParams
    ) -> None:
        """Step 4: Kalman update of position and width; a hit. z: (x_m, y_m); r: diag of R.

        K = P H^T S^-1 (4, 2); Joseph form P' = (I - K H) P (I - K H)^T + K R K^T, computed
        as W = P - K P[:2] and P' = W - (W[:, :2] - K R) K^T, row by row.
        """
        p00, p01, p02, p03, p11, p12, p13, p22, p23, p33 = self.P
        rows = (
            (p00, p01, p02, p03),
            (p01, p11, p12, p13),
            (p02, p12, p22, p23),
            (p03, p13, p23, p33),
        )
        r_x, r_y = r
        s00, s01, s11 = p00 + r_x, p01, p11 + r_y
        det = s00 * s11 - s01 * s01
        i00, i01, i11 = s11 / det, -s01 / det, s00 / det  # S^-1
        gain = [(row[0] * i00 + row[1] * i01, row[0] * i01 + row[1] * i11) for row in rows]
        nu_x, nu_y = z[0] - self.x, z[1] - self.y
        (k00, k01), (k10, k11), (k20, k21), (k30, k31) = gain
        self.x += k00 * nu_x + k01 * nu_y
        self.y += k10 * nu_x + k11 * nu_y
        self.vx += k20 * nu_x + k21 * nu_y
        self.vy += k30 * nu_x + k31 * nu_y
        k_col0, k_col1 = (k00, k10, k20, k30), (k01, k11, k21, k31)
        w = [
            _minus(row, k0, rows[0], k1, rows[1]) for row, (k0, k1) in zip(rows, gain, strict=True)
        ]
        n0, n1, n2, n3 = (
            _minus(wi, wi[0] - r_x * k0, k_col0, wi[1] - r_y * k1, k_col1)
            for wi, (k0, k1) in zip(w, gain, strict=True)
        )
        self.P = (n0[0], n0[1], n0[2], n0[3], n1[1], n1[2], n1[3], n2[2], n2[3], n3[3])
        r_w = params.width_sigma_m**2
        gain_w = self.width_var_m2 / (self.width_var_m2 + r_w)
        self.width_m += gain_w * (m.width_m - self.width_m)
        self.width_var_m2 *= 1.0 - gain_w
        self.box_px = m.box_px
        self.hits += 1
        self.misses = 0
        self.unreturned = 0 if m.for_track is None else self.unreturned + 1
        self.confirmed = not self.too_fast and (
            self.confirmed or self.hits >= confirm_frames_of(self.kind, params)
        )
        self.source_index = m.source_index

    def surely_faster_than(self, speed_mps: float, sigmas: float) -> bool:
        """Whether the speed over the ground |v| is above speed_mps by more than `sigmas`
        of its sigma, sqrt(v^T C v) / |v| (C: the velocity block of P)."""
        speed = math.hypot(self.vx, self.vy)
        if speed <= speed_mps:
            return False
        p22, p23, p33 = self.P[7:]  # C, the velocity block
        ux, uy = self.vx / speed, self.vy / speed
        sigma = math.sqrt(max(ux * ux * p22 + 2.0 * ux * uy * p23 + uy * uy * p33, 0.0))
        return speed - sigmas * sigma > speed_mps

    def not_a_person(self) -> None:
        """Step 5's speed gate: tentative from now on, so never shown, and ended at its
        first miss; until then it takes this object's detections, which start no track."""
        self.too_fast = True
        self.confirmed = False

    def misses_kept(self, params: TrackingParams) -> int:
        """Step 5: the consecutive misses this track survives (none once not a person)."""
        if self.confirmed:
            return params.max_missed_frames
        return 0 if self.too_fast else params.tentative_max_missed_frames

    def miss(self) -> None:
        self.misses += 1
        self.unreturned += 1
        self.source_index = None

    def record(self, params: TrackingParams) -> None:
        """Append this frame's position to the history, keeping the last history_length."""
        self.history_m = (*self.history_m, (self.x, self.y))[-params.history_length :]

    def copied(self) -> _TrackState:
        """An independent twin: every attribute is a float, int, bool, str, None or a tuple
        of floats, so a shallow copy shares nothing that the in-place steps change."""
        return copy.copy(self)

    def snapshot(
        self, params: TrackingParams, confirmed_at_m: Sequence[tuple[float, float]] = ()
    ) -> Track:
        """This track as reported. confirmed_at_m: the positions of this frame's confirmed
        vehicle tracks, within whose clearance a vehicle track is not shown early (step 5)."""
        return Track(
            id=self.id,
            kind=self.kind,
            x_m=self.x,
            y_m=self.y,
            vx_mps=self.vx,
            vy_mps=self.vy,
            width_m=self.width_m,
            sigma_x_m=math.sqrt(self.P[0]),
            sigma_y_m=math.sqrt(self.P[4]),
            box_px=self.box_px,
            hits=self.hits,
            misses=self.misses,
            age=self.age,
            confirmed=self.confirmed,
            source_index=self.source_index,
            history_m=self.history_m,
            unreturned=self.unreturned,
            shown_early=self._shown_early(params, confirmed_at_m),
        )

    def _shown_early(
        self, p: TrackingParams, confirmed_at_m: Sequence[tuple[float, float]]
    ) -> bool:
        """Step 5: a tentative vehicle track measured this frame with
        `show_vehicles_after_hits` hits or more, not within `early_clearance_ahead_m` and
        `early_clearance_across_m` of a confirmed vehicle track (there it is most often a
        second track on that vehicle, whose box would be a false one and an id switch)."""
        if self.confirmed or self.kind != "vehicle" or self.misses:
            return False
        if not 0 < p.show_vehicles_after_hits <= self.hits:
            return False
        return not any(
            abs(self.x - x_m) < p.early_clearance_ahead_m
            and abs(self.y - y_m) < p.early_clearance_across_m
            for x_m, y_m in confirmed_at_m
        )


@dataclass(frozen=True, eq=False)
class TrackerState:
    """What `Tracker.update` carries from one frame to the next: the live tracks' filters
    (private copies that nothing changes; `Tracker.restore` copies them again) and the id
    the next new track gets."""

    tracks: tuple[_TrackState, ...]
    next_id: int


class Tracker:
    """The tracks of one drive (STYLE 12): feed it every frame's measurements in order.

    `reset()` forgets every track (a seek) and restarts ids at 1, so replaying the same
    measurements after a reset gives identical results, ids included. `state()` keeps the
    tracks after an update and `restore()` takes them up again: the updates that follow
    are those that followed the state, ids included.
    """

    def __init__(self, params: TrackingParams) -> None:
        self.params = params
        self.reset()

    def reset(self) -> None:
        self._tracks: list[_TrackState] = []
        self._next_id = 1

    def state(self) -> TrackerState:
        """The tracks and next id the next update reads, copied (updates change a track's
        filter in place)."""
        return TrackerState(tuple(t.copied() for t in self._tracks), self._next_id)

    def restore(self, state: TrackerState) -> None:
        """Take up `state` (from `state()` of a Tracker with these parameters); the state
        stays as it was, so it can be restored again. ValueError naming state.next_id when
        it is not above every track's id."""
        highest = max((t.id for t in state.tracks), default=0)
        if state.next_id <= highest:
            raise ValueError(
                f"state.next_id: expected an id above the tracks' ({highest}), got {state.next_id}"
            )
        self._tracks = [t.copied() for t in state.tracks]
        self._next_id = state.next_id

    def _move_and_predict(
        self, tracks: Sequence[_TrackState], ego: EgoMotion | None, dt_s: float
    ) -> None:
        """Steps 1-2 on `tracks`, in place."""
        p = self.params
        if ego is None:
            lost_var_m2 = p.unknown_ego_sigma_m**2
            for track in tracks:
                track.stay(lost_var_m2)
        else:
            cos, sin = math.cos(-ego.dyaw_rad), math.sin(-ego.dyaw_rad)
            dx_m, dy_m = float(ego.dx_m), float(ego.dy_m)
            for track in tracks:
                track.move(cos, sin, dx_m, dy_m)
        noise = _process_noise(p, dt_s)
        width_growth_m2 = p.width_walk_m2ps * dt_s
        for track in tracks:
            track.predict(dt_s, noise[track.kind], width_growth_m2)

    def predicted(self, kind: Kind, ego: EgoMotion | None, dt_s: float) -> tuple[Track, ...]:
        """The confirmed tracks of `kind` as the next `update(..., ego, dt_s)` will have moved
        and predicted them (steps 1-2) before it associates any measurement: where this
        frame's detections of them are expected. The tracker itself does not change."""
        _require_kind("kind", kind)
        require_finite("dt_s", dt_s)
        ahead = [t.copied() for t in self._tracks if t.kind == kind and t.confirmed]
        self._move_and_predict(ahead, ego, max(dt_s, 0.0))
        return tuple(t.snapshot(self.params) for t in ahead)

    def update(
        self, measurements: Sequence[Measurement], ego: EgoMotion | None, dt_s: float
    ) -> TrackResult:
        """One frame: steps 1-5 of the module docstring.

        measurements: this frame's detections of every kind, in the current vehicle frame;
        ego: the car's motion since the previous frame (None: unknown); dt_s: time since the
        previous frame, s. ValueError naming dt_s when it is not finite or < 0, and naming
        measurements when a (kind, source_index) appears twice.
        """
        require_finite("dt_s", dt_s)
        if dt_s < 0:
            raise ValueError(f"dt_s: expected an interval >= 0, got {dt_s}")
        keys = [(m.kind, m.source_index) for m in measurements]
        if len(set(keys)) != len(keys):
            twice = next(k for i, k in enumerate(keys) if k in keys[:i])
            raise ValueError(f"measurements: (kind, source_index) {twice} appears twice")
        p = self.params
        tracks = self._tracks
        self._move_and_predict(tracks, ego, dt_s)  # 1-2
        # 3. association, per kind
        zs = [(float(m.x_m), float(m.y_m)) for m in measurements]
        rs = [_measurement_var(p, m) for m in measurements]
        taken: dict[int, int] = {}  # track position in tracks -> measurement position
        for kind in KINDS:
            rows = [i for i, t in enumerate(tracks) if t.kind == kind]
            cols = [j for j, m in enumerate(measurements) if m.kind == kind and m.for_track is None]
            if not rows or not cols:
                continue
            cost = [[tracks[i].gated_cost(*zs[j], rs[j], p) for j in cols] for i in rows]
            for r, c in _assign(cost):
                taken[rows[r]] = cols[c]
        # detections searched for a track: to that track, if still free and within its gates
        position = {t.id: i for i, t in enumerate(tracks)}
        for col, m in enumerate(measurements):
            at = None if m.for_track is None else position.get(m.for_track)
            if at is not None and at not in taken and tracks[at].kind == m.kind:
                if math.isfinite(tracks[at].gated_cost(*zs[col], rs[col], p)):
                    taken[at] = col
        # 4-5. update, misses and births
        live: list[_TrackState] = []
        ended: list[int] = []
        for i, track in enumerate(tracks):
            track.age += 1
            j = taken.get(i)
            if j is not None:
                track.correct(measurements[j], zs[j], rs[j], p)
            else:
                track.miss()
                if track.misses > track.misses_kept(p):
                    ended.append(track.id)
                    continue
            if track.kind == "pedestrian" and track.surely_faster_than(
                p.pedestrian_max_speed_mps, p.pedestrian_speed_gate_sigmas
            ):
                track.not_a_person()
            track.record(p)
            live.append(track)
        used = set(taken.values())
        for j, m in enumerate(measurements):
            if j not in used and m.for_track is None:
                live.append(_TrackState(self._next_id, m, rs[j], p))
                self._next_id += 1
        self._tracks = live  # ascending ids: survivors in order, then the newborn
        held = [(t.x, t.y) for t in live if t.kind == "vehicle" and t.confirmed]
        return TrackResult(tuple(t.snapshot(p, held) for t in live), tuple(sorted(ended)))
