"""Every tunable number of the engine: nested frozen dataclasses, one per stage, saved as YAML.

Defaults cite the paper and section they come from. Change a value with
`dataclasses.replace` (or `Params.with_value("vehicle.search_width_m", 3.0)`); every class
validates itself in `__post_init__` and names the field it rejects.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TypeVar

import yaml

from core.ego import STANDSTILL_SPEED_MPS

PARAMS_FORMAT_VERSION = 1


class ParamsError(ValueError):
    """A parameter file or value that cannot be used; the message names the field."""


def _check(ok: bool, name: str, expected: str, got: object) -> None:
    if not ok:
        raise ParamsError(f"{name}: expected {expected}, got {got!r}")


def _positive(obj: object, *names: str) -> None:
    for name in names:
        value = getattr(obj, name)
        _check(math.isfinite(value) and value > 0, name, "a number > 0", value)


def _fraction(obj: object, *names: str) -> None:
    for name in names:
        value = getattr(obj, name)
        _check(0.0 <= value <= 1.0, name, "a fraction in [0, 1]", value)


@dataclass(frozen=True)
class PitchParams:
    """Vanishing-point pitch detector and horizon tracking (paper 000, II-A)."""

    # |vertical Sobel| above this is an edge (paper: "a given threshold")
    sobel_threshold: float = 60.0
    # edges are read from this many rows above the calibrated vanishing point down (the
    # paper starts "from the bottom part of the image"; the sky above holds no road lines)
    rows_above_vp_px: int = 10
    # the row histogram of horizon tracking starts this far above it (far things, which
    # do not move as the car drives, make the steadiest reference)
    tracking_rows_above_vp_px: int = 40
    # edges are clustered on every row_step_px-th row (1: every row, as the paper)
    row_step_px: int = 3
    min_cluster_px: int = 40  # paper 000: "40 pixels in the current setup"
    merge_angle_rad: float = 0.02  # paper 000: "a 0.02 radians threshold"
    # lines closer than this to the image vertical are poles, trunks, vehicle sides: no vote
    min_tilt_rad: float = 0.05
    lines_kept: int = 7  # paper 000: "only the 7 lines with the highest confidence"
    # half-size of the region around the calibrated vanishing point where intersections
    # count: 1.0 deg of pitch on the bundled drives (fy 773 px), 1.6 deg at fy 500 px (the
    # papers' preset: 40, core/pitch.py Notes)
    vp_region_px: float = 14.0
    # intersection weight also x sin(crossing angle) (False: the paper's min confidence alone)
    weight_by_crossing_angle: bool = True
    # an intersection may lie this far inside a segment's rows and still be a vanishing point
    segment_margin_px: float = 5.0
    min_confidence: float = 200.0  # below this summed weight, horizon tracking takes over
    # ... and above this weighted RMS distance of the intersections from their mean (curves)
    max_spread_px: float = 6.0
    # beyond the paper: a vanishing point whose horizon lies more than this many rows from
    # the previous frame's is taken for a curve's stray lines, and horizon tracking takes
    # over (11: 0.8 deg at fy 773 px; 0: no such check, the papers' preset; core/pitch.py)
    max_vp_jump_px: float = 11.0
    # largest row shift per frame searched by horizon tracking (~0.3 deg at 10 fps)
    max_tracking_offset_px: int = 4
    # share of the way back to the calibrated horizon taken on each tracked frame
    tracking_pull: float = 0.2
    # beyond the paper: leave out edges inside the previous frame's vehicle boxes (off by
    # default since moving targets' wider areas boxed more road, core/pitch.py Notes; the
    # papers' preset: on, as it stood)
    leave_out_vehicles: bool = False

    def __post_init__(self) -> None:
        _positive(
            self,
            "sobel_threshold",
            "merge_angle_rad",
            "vp_region_px",
            "min_confidence",
            "max_spread_px",
        )
        _check(
            0 <= self.min_tilt_rad < math.pi / 2, "min_tilt_rad", "in [0, pi/2)", self.min_tilt_rad
        )
        _check(self.segment_margin_px >= 0, "segment_margin_px", ">= 0", self.segment_margin_px)
        _check(self.min_cluster_px >= 2, "min_cluster_px", "an integer >= 2", self.min_cluster_px)
        _check(self.lines_kept >= 2, "lines_kept", "an integer >= 2", self.lines_kept)
        _check(self.row_step_px >= 1, "row_step_px", "an integer >= 1", self.row_step_px)
        _check(self.rows_above_vp_px >= 0, "rows_above_vp_px", ">= 0", self.rows_above_vp_px)
        _check(
            self.tracking_rows_above_vp_px >= self.rows_above_vp_px,
            "tracking_rows_above_vp_px",
            f">= rows_above_vp_px={self.rows_above_vp_px}",
            self.tracking_rows_above_vp_px,
        )
        _fraction(self, "tracking_pull")
        _check(
            math.isfinite(self.max_vp_jump_px) and self.max_vp_jump_px >= 0,
            "max_vp_jump_px",
            "a finite number of rows >= 0",
            self.max_vp_jump_px,
        )
        _check(
            self.max_tracking_offset_px >= 0,
            "max_tracking_offset_px",
            ">= 0",
            self.max_tracking_offset_px,
        )


@dataclass(frozen=True)
class MotionStereoParams:
    """Bird's-eye motion stereo (paper 000, II-B)."""

    x_min_m: float = 4.0
    x_max_m: float = 40.0  # the radars of paper 000 reach 40 m
    y_half_width_m: float = 10.0
    cell_m: float = 0.1  # "chosen considering odometry accuracy"
    mean_window_px: int = 3  # paper 000: "a square area (3x3)"
    threshold_xi: float = 20.0  # paper 000: threshold xi on the local mean m_i (grey levels)
    weight_obstacle: float = 0.25  # paper 000 eq. 7, w_i when m_i > xi
    weight_free: float = 1.0  # paper 000 eq. 7, w_i when m_i < xi
    # beyond the paper: D's connected regions smaller than this are not obstacle regions
    min_region_m2: float = 0.1
    # beyond the paper: slower than this over a frame interval the ego car stands still and
    # motion stereo is background subtraction
    standstill_speed_mps: float = STANDSTILL_SPEED_MPS

    def __post_init__(self) -> None:
        _positive(self, "x_max_m", "y_half_width_m", "cell_m", "threshold_xi")
        _check(
            math.isfinite(self.min_region_m2) and self.min_region_m2 >= 0,
            "min_region_m2",
            "an area >= 0",
            self.min_region_m2,
        )
        _check(
            math.isfinite(self.standstill_speed_mps) and self.standstill_speed_mps >= 0,
            "standstill_speed_mps",
            "a speed >= 0",
            self.standstill_speed_mps,
        )
        _check(
            0 <= self.x_min_m < self.x_max_m,
            "x_min_m",
            f"0 <= x_min_m < x_max_m={self.x_max_m}",
            self.x_min_m,
        )
        _check(
            self.mean_window_px >= 1 and self.mean_window_px % 2 == 1,
            "mean_window_px",
            "an odd integer >= 1",
            self.mean_window_px,
        )
        _fraction(self, "weight_obstacle", "weight_free")


@dataclass(frozen=True)
class VehicleParams:
    """Radar-guided vehicle detection by vertical symmetry (paper 001, II)."""

    search_width_m: float = 2.5  # paper 001: "the chosen interest area width is 2.5 meters"
    # beyond the papers (core/search_area.py Notes): a target moving over ground faster than
    # moving_speed_mps is a vehicle's, and its area is moving_search_width_m wide, the widest
    # vehicle (max_width_m) with its radar point up to 0.5 m off its centre, as high as a
    # search_width_m area (the papers' preset: search_width_m for every target)
    moving_search_width_m: float = 4.0
    moving_speed_mps: float = 3.0
    # beyond the papers (core/search_area.py Notes): a target within track_gate_m of where
    # the tracker expects a confirmed vehicle track on this frame is that vehicle's, and gets
    # the moving targets' area however slow it is (0: off, the papers' preset)
    track_gate_m: float = 1.5
    # beyond the papers (core/search_area.py Notes): such a target's area is centred on the
    # tracked vehicle's lateral position (vision's, filtered), not on the radar point
    centre_on_track: bool = True
    # beyond the papers (core/track_search.py): a confirmed vehicle track no radar target
    # returned on this frame is searched for by vision in an area on its prediction, on at
    # most track_search_frames consecutive frames without radar (0: off, the papers'
    # preset), unless nearer vehicles hide more than track_search_hidden_fraction of its
    # expected box; the box found must agree with the track's lateral position and width
    # within track_search_agreement_m
    track_search_frames: int = 2
    track_search_hidden_fraction: float = 0.2
    track_search_agreement_m: float = 0.3
    # beyond the papers (core/appearance.py): a confirmed vehicle track that neither a radar
    # target's vehicle nor the track search framed on this frame is looked for by its look,
    # the patch of its last radar vehicle's box (kept appearance_max_age_frames frames; 0:
    # off, the papers' preset), matched by normalised cross-correlation of at least
    # appearance_min_ncc; the match must agree with the track as the track search's does
    appearance_max_age_frames: int = 5
    appearance_min_ncc: float = 0.8
    # beyond the papers (core/radar_smoothing.py): each area is centred on its radar point's
    # lateral position averaged over about lateral_smoothing_s of scans, a point pairing with
    # the last scans' within lateral_smoothing_gate_m across (the papers' preset: 0, every
    # area on its own point)
    lateral_smoothing_s: float = 0.2
    lateral_smoothing_gate_m: float = 1.0
    search_height_ratio: float = 0.5  # paper 001: "area height is ... half of its width"
    # paper 001: bottom at 30% of area height below the radar point
    search_bottom_fraction: float = 0.3
    resampled_width_px: int = 64  # fixed size of the resampled area (paper: "a fixed size")
    max_half_width_px: int = 32  # largest symmetry half-width
    # |horizontal Sobel| (3x3) above this is a binarised vertical edge (paper: "binarized")
    edge_threshold: float = 30.0
    # chi = s^2 / n a vehicle's axis reaches, per row of the resampled area
    symmetry_threshold: float = 0.35
    # beyond the papers (core/vehicle.py Notes, step 6): the threshold times this for a
    # target that neither moves over ground (moving_speed_mps) nor lies where a confirmed
    # vehicle track is expected (track_gate_m): posts, trunks and signs are still, and
    # their boxes pass with less symmetry than vehicles' (the papers' preset: 1)
    still_symmetry_factor: float = 1.2
    # beyond the papers (core/vehicle.py Notes, step 6): a target where a confirmed vehicle
    # track is expected (track_gate_m) whose area holds no candidate axis is searched again
    # in an area this many times as high, bottom and sides kept: a van or truck taller than
    # the area, its symmetric doors and windows above it (the papers' preset: 1, no search)
    tracked_taller_area_factor: float = 2.5
    # chi stays below the threshold for windows narrower than this (paper 001: "low for
    # narrow area widths"): poles, posts and gaps are not vehicles
    narrow_width_m: float = 0.4
    # beyond the papers (core/vehicle.py Notes, step 6): mirrored pairs at the vehicle's
    # half-width (give or take a column) per row of the area, at least; a vehicle's borders
    # pair up about twice a row (a step is two Sobel columns), a box centred on a tree trunk
    # or a post has borders only where the background happens to pair (0: off, the papers'
    # preset)
    min_border_pairs_per_row: float = 0.3
    # beyond the papers (core/vehicle.py Notes, step 6): an axis that qualifies in the area of
    # a tracked vehicle takes its half-width within this much of the track's width when one
    # there reaches the threshold with the border pairs (0: off, the papers' preset)
    track_width_tolerance_m: float = 0.4
    # share of a box's columns with a shadow-to-road edge for its bottom (paper: "shadow";
    # no figure). A vehicle's shadow and wheels end on the road across its whole width; at
    # 0.5 (the papers' preset) rail posts, clutter and parts of vehicles passed too
    # (core/vehicle.py Notes, step 7)
    bottom_edge_fraction: float = 0.8
    # beyond the papers (core/vehicle.py Notes, step 7): a box's base lies at most this high
    # above the road at its target's distance (the papers' preset: 1000, anywhere in the area)
    max_base_height_m: float = 0.3
    # share of a box's columns with a horizontal edge for its top
    top_edge_fraction: float = 0.5
    min_height_ratio: float = 0.5  # a top lies at least this x width above the bottom
    refined_error_m: float = 0.40  # paper 001, III: "an error lower than 40 centimeters"
    # world-size filter: narrowest vehicle. The papers give no figure; 1.2 (their preset) let
    # a dark car's pair of rear lights, 1.2-1.3 m apart, pass for the car; the narrowest
    # cars sold are about 1.55 m wide (core/vehicle.py Notes, step 6)
    min_width_m: float = 1.5
    max_width_m: float = 3.0  # world-size filter: widest vehicle
    # box height / width when the top is not found (paper 001, fig. 7.b)
    default_height_ratio: float = 0.8
    # beyond the papers (core/vehicle.py, step 11): a box's top rises to where both of its
    # side borders' vertical edges end, looked for up to top_search_ratio x its width above
    # its base, a border ending at a gap of more than top_gap_ratio x its width (the papers'
    # preset: top_search_ratio 0, off)
    top_search_ratio: float = 2.0
    top_gap_ratio: float = 0.2
    # beyond the papers (core/vehicle.py, step 12): the box shown and scored for a vehicle
    # holds its rear face and the same face this far behind, as the camera sees a vehicle
    # that long: its side and roof (0: the rear face alone, the papers' preset)
    body_length_m: float = 4.0
    # beyond the papers (core/vehicle.py, step 11): a box at least truck_width_m wide (a truck
    # or a bus: cars are 1.55-2.0 m wide, vans up to 2.1 m, trucks 2.45-2.6 m) rises to
    # truck_height_ratio x its width where one of its side borders goes on up to there (0:
    # off, the papers' preset)
    truck_width_m: float = 2.3
    truck_height_ratio: float = 1.4
    # boxes from several targets overlapping by more than this share of the smaller one are
    # one vehicle (paper 001: "overlapping results")
    merge_overlap_fraction: float = 0.5
    similar_size_ratio: float = 0.8  # narrower / wider width of boxes "of similar size"
    # bases "at the same height": within this share of the box height
    same_base_fraction: float = 0.1
    # beyond the papers (core/vehicle.py Notes): boxes are one vehicle only when their
    # targets lie within this distance of each other, a chain of them for a long truck
    # (the papers' preset: 1000 m, beyond any radar's range: overlap alone decides)
    merge_max_gap_m: float = 5.0
    # beyond the papers (core/vehicle.py, step 10): a vehicle whose box ends on a nearer
    # vehicle's on one side, which hides it there, is this wide (or as wide as seen, when
    # wider), its lateral position taken from its other side (chosen: a passenger car's or
    # van's width, 1.6-2.1 m, within refined_error_m; 0: off, the papers' preset)
    hidden_side_width_m: float = 1.85
    # beyond the papers: a vehicle is as far as its nearest target, the one nearest its near
    # face (the papers' preset: False, the mean of its targets)
    distance_of_nearest_target: bool = True
    # beyond the papers (core/vehicle.py Notes): a target whose area has fewer image pixels
    # per metre across than this is too far for vision: neither checked for a guard rail nor
    # searched for a vehicle (0: every target is, the papers' preset)
    min_image_px_per_m: float = 10.0

    def __post_init__(self) -> None:
        _check(
            math.isfinite(self.min_border_pairs_per_row) and self.min_border_pairs_per_row >= 0,
            "min_border_pairs_per_row",
            "a number of pairs per row >= 0 (0: off)",
            self.min_border_pairs_per_row,
        )
        _check(
            math.isfinite(self.track_width_tolerance_m) and self.track_width_tolerance_m >= 0,
            "track_width_tolerance_m",
            "a width >= 0 (0: off)",
            self.track_width_tolerance_m,
        )
        _check(
            math.isfinite(self.body_length_m) and self.body_length_m >= 0,
            "body_length_m",
            "a length in metres >= 0 (0: the rear face alone)",
            self.body_length_m,
        )
        _check(
            math.isfinite(self.hidden_side_width_m) and self.hidden_side_width_m >= 0,
            "hidden_side_width_m",
            "a width in metres >= 0 (0: off)",
            self.hidden_side_width_m,
        )
        _check(
            math.isfinite(self.truck_height_ratio) and self.truck_height_ratio >= 0,
            "truck_height_ratio",
            "a ratio >= 0 (0: off)",
            self.truck_height_ratio,
        )
        _check(
            math.isfinite(self.min_image_px_per_m) and self.min_image_px_per_m >= 0,
            "min_image_px_per_m",
            "a resolution >= 0 (0: off)",
            self.min_image_px_per_m,
        )
        _positive(
            self,
            "truck_width_m",
            "max_base_height_m",
            "search_width_m",
            "moving_search_width_m",
            "moving_speed_mps",
            "search_height_ratio",
            "symmetry_threshold",
            "still_symmetry_factor",
            "refined_error_m",
            "default_height_ratio",
            "top_gap_ratio",
            "edge_threshold",
            "min_height_ratio",
            "narrow_width_m",
            "merge_max_gap_m",
            "lateral_smoothing_gate_m",
            "track_search_agreement_m",
        )
        _check(
            math.isfinite(self.tracked_taller_area_factor) and self.tracked_taller_area_factor >= 1,
            "tracked_taller_area_factor",
            "a factor >= 1 (1: no second search)",
            self.tracked_taller_area_factor,
        )
        _check(
            self.track_search_frames >= 0,
            "track_search_frames",
            "a whole number of frames >= 0 (0: off)",
            self.track_search_frames,
        )
        _check(
            self.appearance_max_age_frames >= 0,
            "appearance_max_age_frames",
            "a whole number of frames >= 0 (0: off)",
            self.appearance_max_age_frames,
        )
        _check(
            math.isfinite(self.appearance_min_ncc) and -1 <= self.appearance_min_ncc <= 1,
            "appearance_min_ncc",
            "a correlation in -1 .. 1",
            self.appearance_min_ncc,
        )
        _check(
            math.isfinite(self.lateral_smoothing_s) and self.lateral_smoothing_s >= 0,
            "lateral_smoothing_s",
            "a time >= 0 (0: off)",
            self.lateral_smoothing_s,
        )
        _check(
            math.isfinite(self.track_gate_m) and self.track_gate_m >= 0,
            "track_gate_m",
            "a distance >= 0 (0: off)",
            self.track_gate_m,
        )
        _fraction(
            self,
            "search_bottom_fraction",
            "bottom_edge_fraction",
            "top_edge_fraction",
            "merge_overlap_fraction",
            "similar_size_ratio",
            "same_base_fraction",
            "track_search_hidden_fraction",
        )
        _check(
            math.isfinite(self.top_search_ratio) and self.top_search_ratio >= 0,
            "top_search_ratio",
            "a ratio >= 0 (0: the top is not searched above the area)",
            self.top_search_ratio,
        )
        _check(
            self.resampled_width_px >= 8,
            "resampled_width_px",
            "an integer >= 8",
            self.resampled_width_px,
        )
        _check(
            1 <= self.max_half_width_px <= self.resampled_width_px,
            "max_half_width_px",
            f"1..resampled_width_px={self.resampled_width_px}",
            self.max_half_width_px,
        )
        _check(
            0 < self.min_width_m < self.max_width_m,
            "min_width_m",
            f"0 < min_width_m < max_width_m={self.max_width_m}",
            self.min_width_m,
        )


@dataclass(frozen=True)
class GuardRailParams:
    """Guard-rail filter for slow radar objects and overlapping boxes (paper 002)."""

    # paper 002: "lower than 5 m/s"; a rail stands still, and cars crawling in a queue at
    # 2-5 m/s were labelled guard rail (core/guardrail.py, Notes)
    max_speed_mps: float = 1.5
    # |3x3 Sobel| (Euclidean, 4 per grey level of a step) above this is an edge. Paper 002:
    # "a very low threshold on module"; 40 (a 10-grey step) rather than 20 because at 20 the
    # road texture and lane-marking edges of the bundled stop_and_go drive carried a line
    # across the areas of 8 of 74 slow vehicle targets, at 40 none (highway rails: 76 -> 71
    # of 175 found).
    sobel_threshold: float = 40.0
    max_holes: int = 5  # paper 002: "a maximum of 5 holes is allowed"
    min_length_fraction: float = 0.5  # paper 002: "longer than 50% of the searching area"
    overlap_fraction: float = 0.5  # paper 002: "overlapped ... more than a threshold"
    # edge orientations kept: the line's angle from the image horizontal, rising towards the
    # vanishing point (paper 002 fig. 1 "approximatively" that of a guard rail)
    min_angle_rad: float = math.radians(2.0)
    max_angle_rad: float = math.radians(45.0)
    # overlapping boxes management (paper 002, III); False: every slow area is searched
    manage_overlaps: bool = True
    # beyond the paper (core/guardrail.py, step 6): an area the rail's area covers is labelled
    # by overlap only when its target lies within overlap_gate_m across of the rail's target,
    # and searched otherwise (a parked car or a sign beside the rail); 0: no gate, the
    # default and the papers' preset (1 m was measured and not adopted: Notes)
    overlap_gate_m: float = 0.0
    # beyond the paper (core/guardrail.py, step 5): the line must pass the target at least
    # this high above the road, not along it (kerbs, lane edges, shadows, a parked car's
    # sill, a trailer's chassis); the papers' preset: -100 (no test)
    min_line_height_m: float = 0.15
    # beyond the paper: a slow target where the tracker expects a vehicle
    # (SearchArea.tracked) is not checked; the papers' preset: False
    skip_tracked_vehicles: bool = True
    # beyond the paper (core/rail_lines.py): a slow target along the line of the returns
    # found on a rail over the last line_memory_s, within line_gate_m across, is guard rail
    # too (0 s: off, the papers' preset); 0.5 m since the lines leave out wrong returns
    # (core/rail_lines.py Notes; 0.4 before)
    line_memory_s: float = 2.0
    line_gate_m: float = 0.5
    # beyond the paper (core/rail_lines.py, step 4): a target labelled guard rail by its
    # search or by overlap is not a rail return where its side's remembered returns trace
    # no line, even loosely (rail_returns_required), or where it lies along its side's line
    # but more than line_veto_m across from it (a pole, a sign, a car beside the rail);
    # False and 0: off, the papers' preset
    rail_returns_required: bool = True
    line_veto_m: float = 1.0

    def __post_init__(self) -> None:
        _positive(self, "max_speed_mps", "sobel_threshold", "line_gate_m")
        _check(
            math.isfinite(self.line_memory_s) and self.line_memory_s >= 0,
            "line_memory_s",
            "a time >= 0 (0: off)",
            self.line_memory_s,
        )
        _check(self.max_holes >= 0, "max_holes", "an integer >= 0", self.max_holes)
        _check(
            math.isfinite(self.line_veto_m) and self.line_veto_m >= 0,
            "line_veto_m",
            "a distance >= 0 (0: off)",
            self.line_veto_m,
        )
        _check(
            math.isfinite(self.overlap_gate_m) and self.overlap_gate_m >= 0,
            "overlap_gate_m",
            "a distance >= 0 (0: no gate)",
            self.overlap_gate_m,
        )
        _fraction(self, "min_length_fraction", "overlap_fraction")
        _check(
            math.isfinite(self.min_line_height_m),
            "min_line_height_m",
            "a finite height in metres",
            self.min_line_height_m,
        )
        _check(
            0.0 <= self.min_angle_rad < math.pi / 2,
            "min_angle_rad",
            "an angle in [0, pi/2)",
            self.min_angle_rad,
        )
        _check(
            self.min_angle_rad < self.max_angle_rad < math.pi / 2,
            "max_angle_rad",
            f"an angle in (min_angle_rad={self.min_angle_rad}, pi/2)",
            self.max_angle_rad,
        )


@dataclass(frozen=True)
class PedestrianParams:
    """Symmetry pedestrian detection and its fusion filters (paper 000, II-D, after its
    reference [3], Bertozzi et al. 2000)."""

    # the people searched for (issue 6: 0.9-2.1 m tall, 3-40 m away)
    min_height_m: float = 0.9
    max_height_m: float = 2.1
    min_distance_m: float = 3.0
    max_distance_m: float = 40.0
    aspect_min: float = 0.2  # width / height of a human box (paper: "a specific aspect ratio")
    aspect_max: float = 0.6
    # each distance band scans a box as tall as a person of this height standing there
    scan_height_m: float = 1.7
    distance_step_ratio: float = 1.12  # distance of a band / that of the next nearer one
    # columns are summed in bins so that a band's box is about this many bins tall: near
    # bands scan coarser, as far ones (their people are as many bins tall)
    scan_bins: int = 32
    # |horizontal Sobel| (3x3) above this is a vertical edge
    edge_threshold: float = 40.0
    # a column whose edges cover this share of the box height is a border column; the body's
    # half-width is the outermost pair of border columns mirrored about the axis
    border_column_fraction: float = 0.15
    # edge pixels / box pixels a candidate reaches (paper: "strong presence of edges")
    min_edge_density: float = 0.04
    # mean of edge and grey-level symmetry (0..1) a candidate reaches (core/pedestrian.py
    # Notes: with the SVM's verification, 0.4 lets more people reach it; the papers' preset
    # keeps 0.6)
    symmetry_threshold: float = 0.4
    # share of a row's edges with a mirrored partner (of opposite sign, within 1 px) for the
    # row to be symmetric
    row_symmetry_fraction: float = 0.5
    # rows (a share of the band's box height) that end a run: non-symmetric rows end the
    # body upwards and the symmetric area downwards, rows without edges end the legs (0.08
    # stopped at the waist of people whose shirt is the background's grey)
    gap_fraction: float = 0.15
    max_candidates: int = 24  # candidates reported per frame, strongest first
    # two refined boxes sharing more than this share of the smaller one frame one person
    nms_overlap_fraction: float = 0.5
    # share of a box marked by motion stereo to keep it: on the bundled drives half the
    # symmetric boxes on a pedestrian reach 0.15-0.2, half of the others stay under 0.1
    min_obstacle_fraction: float = 0.1
    # share of a box inside a detected vehicle's box that removes it (paper: "areas detected
    # where also a vehicle has been detected")
    vehicle_overlap_fraction: float = 0.5
    # beyond the papers (core/pedestrian.py, step 5): a box standing where radar sees a target
    # moving over ground faster than radar_min_speed_mps (a jog; paper 000: radar does not see
    # people, "the human shape generally does not reflect enough energy") is removed when the
    # target is within radar_gate_lateral_m sideways and radar_gate_distance_fraction of the
    # box's distance ahead or behind (the box's base is where the ground plane puts it; on the
    # bundled drives these gates removed a quarter of the false boxes and no true one);
    # radar_gate_lateral_m 0 switches the filter off (the paper's fusion)
    radar_min_speed_mps: float = 3.0
    radar_gate_lateral_m: float = 1.5
    radar_gate_distance_fraction: float = 0.2
    # beyond the papers (core/pedestrian.py, step 5; core/image_motion.py): a box whose pixels
    # match the previous frame where they were, in the image, better by more than this
    # normalised cross-correlation than where a still object would have been under the car's
    # motion moves with the car (a truck's wheel beside it, outside the radar's view) and is
    # removed; 2 or more switches the filter off (an NCC lies in -1 .. 1; the papers' preset)
    image_motion_margin: float = 0.2
    # beyond the papers (core/pedestrian.py, step 6): a box that passed every filter is kept
    # only when OpenCV's HOG people SVM scores its window at least hog_min_score (the SVM's
    # own threshold is 0; core/hog.py); a box motion stereo did not mark, but that passed
    # the other filters, is kept when the SVM scores it at least
    # hog_without_motion_min_score (a score no window reaches, such as 100, keeps the
    # paper's motion-stereo filter as it is); verify_with_hog False keeps every box that
    # passed the filters and scores none (the papers' preset)
    verify_with_hog: bool = True
    hog_min_score: float = 0.3
    hog_without_motion_min_score: float = 0.5
    # beyond the papers (core/pedestrian.py, step 6): a person's box that ends rejected is
    # replaced by the first of up to this many other boxes framing the same person (those
    # the one-box-per-person choice left out, in its order) that passes steps 5-6; 0 keeps
    # the one box chosen (the papers' preset)
    hog_alternatives: int = 5
    # beyond the papers (core/pedestrian.py, step 6): a box the SVM scores below its floor is
    # scored again as a person of scan_height_m standing on its base (the symmetric area
    # often holds only the legs), and takes that box when it reaches the floor (False: the
    # box as found, the papers' preset)
    hog_person_at_base: bool = True
    # beyond the papers (core/pedestrian.py, step 4): a box whose base stands off its band's
    # distance (the scan seeded it in a farther or nearer band) is kept when its height and
    # width are a person's there, ranking after the boxes that stand at their band's distance
    # when one box per person is chosen (False: the "perspective" constraint rejects it,
    # the papers' preset)
    keep_off_band_boxes: bool = True
    # beyond the papers (core/pedestrian.py, step 4): a body still going on at the head row of
    # the tallest person standing where the box's base is has no top (False: at that of the
    # tallest person standing at its band's distance, the papers' preset)
    head_row_at_base: bool = True

    @property
    def image_motion_filter(self) -> bool:
        """Is the image-motion filter on (`image_motion_margin` below 2)?"""
        return self.image_motion_margin < 2

    def __post_init__(self) -> None:
        _positive(
            self,
            "radar_min_speed_mps",
            "min_height_m",
            "min_distance_m",
            "aspect_min",
            "scan_height_m",
            "edge_threshold",
            "symmetry_threshold",
        )
        _check(
            self.max_height_m > self.min_height_m,
            "max_height_m",
            f"> min_height_m={self.min_height_m}",
            self.max_height_m,
        )
        _check(
            self.max_distance_m > self.min_distance_m,
            "max_distance_m",
            f"> min_distance_m={self.min_distance_m}",
            self.max_distance_m,
        )
        _check(
            self.aspect_max > self.aspect_min,
            "aspect_max",
            f"> aspect_min={self.aspect_min}",
            self.aspect_max,
        )
        _check(
            1.0 < self.distance_step_ratio <= 2.0,
            "distance_step_ratio",
            "a ratio in (1, 2]",
            self.distance_step_ratio,
        )
        _check(self.scan_bins >= 8, "scan_bins", "an integer >= 8", self.scan_bins)
        _check(self.max_candidates >= 1, "max_candidates", "an integer >= 1", self.max_candidates)
        _check(
            self.hog_alternatives >= 0,
            "hog_alternatives",
            "an integer >= 0",
            self.hog_alternatives,
        )
        _fraction(
            self,
            "border_column_fraction",
            "min_edge_density",
            "row_symmetry_fraction",
            "gap_fraction",
            "nms_overlap_fraction",
            "min_obstacle_fraction",
            "vehicle_overlap_fraction",
            "radar_gate_distance_fraction",
        )
        _check(
            math.isfinite(self.radar_gate_lateral_m) and self.radar_gate_lateral_m >= 0,
            "radar_gate_lateral_m",
            "a distance >= 0 (0: no radar filter)",
            self.radar_gate_lateral_m,
        )
        _check(
            math.isfinite(self.image_motion_margin) and self.image_motion_margin >= 0,
            "image_motion_margin",
            "an NCC margin >= 0 (2 or more: no image-motion filter)",
            self.image_motion_margin,
        )
        for name in ("hog_min_score", "hog_without_motion_min_score"):
            _check(math.isfinite(getattr(self, name)), name, "a finite number", getattr(self, name))


@dataclass(frozen=True)
class TrackingParams:
    """Temporal confirmation (beyond the papers: paper 002's "simple time correlation").

    The papers give no tracker, so every default here is chosen, not quoted (core/tracking.py).
    """

    # a track is confirmed after this many frames with a detection (chosen)
    confirm_frames: int = 3
    # a pedestrian track after this many (chosen: the HOG-verified detections are rarely
    # false; the papers' preset 3, as every kind; core/tracking.py, step 5)
    pedestrian_confirm_frames: int = 2
    # beyond the papers: a vehicle track not yet confirmed is shown (`Track.shown`) on each
    # frame it is measured once it has this many hits, while its life goes on as a
    # tentative track's (chosen; 0: shown once confirmed, the papers' preset;
    # core/tracking.py, step 5)
    show_vehicles_after_hits: int = 2
    # ... but not within this distance ahead and across of a confirmed vehicle track, where
    # it is most often a second track on that vehicle (chosen; core/tracking.py, step 5)
    early_clearance_ahead_m: float = 4.0
    early_clearance_across_m: float = 2.0
    # a confirmed track is kept through this many consecutive missed frames (chosen)
    max_missed_frames: int = 3
    # a tentative track is kept through this many consecutive missed frames (chosen; the
    # papers' preset 0: dropped at its first miss, so a vehicle detected every other frame
    # was never confirmed; 1 before 2026-11-29; core/tracking.py, step 5)
    tentative_max_missed_frames: int = 2
    # hard cap on the distance between a track's prediction and a detection it may take,
    # whatever the covariance (chosen: a 30 m/s car seen again 0.1 s after its birth, with
    # speed 0, is 3 m from its prediction; 2 m lost such tracks on the second frame)
    gate_m: float = 5.0
    # gate on the squared Mahalanobis distance of the position innovation (chosen: the 99 %
    # quantile of a chi-square with 2 degrees of freedom)
    gate_chi2: float = 9.21
    # association cost of a gated pair: nu^T S^-1 nu + ln det S, the negative log-likelihood
    # of the innovation, instead of nu^T S^-1 nu alone (chosen; false: the Mahalanobis
    # distance alone, which lets a newborn track, whose speed is unknown and S large, take a
    # confirmed track's detection; README, "Tracker association")
    likelihood_cost: bool = True
    # white-acceleration spectral density of the constant-velocity model, per kind (chosen;
    # guard rails are static ground points, so almost none)
    vehicle_accel_psd_m2ps3: float = 4.0
    pedestrian_accel_psd_m2ps3: float = 1.0
    guard_rail_accel_psd_m2ps3: float = 0.01
    # measurement noise (chosen): radar distance of vehicles and guard rails, vision lateral
    # position of vehicles and pedestrians, radar lateral position of guard rails. 0.5 and
    # 0.3 (the papers' preset) smoothed a braking or turning car's track behind it and let
    # tracks take wrong detections; 0.3 and 0.2, radar-seen MOTA on seeds 101-303 (three
    # scenarios each): highway 0.48 -> 0.51, exurban 0.36 -> 0.39, stop_and_go 0.14 -> 0.25,
    # track FP per frame 0.05 -> 0.02-0.03; seeds 404-606: 0.36 -> 0.35, 0.37 -> 0.39,
    # 0.11 -> 0.15, FP 0.04-0.07 -> 0.02-0.05; seed 909 0.65 -> 0.64, 0.43 -> 0.44,
    # 0.10 -> 0.06; nuScenes 0.10 -> 0.15 (README, "Tracker noise")
    radar_sigma_x_m: float = 0.3
    vision_sigma_y_m: float = 0.2
    guard_rail_sigma_y_m: float = 0.5
    # a pedestrian's distance comes from its foot row: its sigma is this share of the
    # distance, but not below pedestrian_min_sigma_x_m (chosen)
    pedestrian_sigma_x_fraction: float = 0.1
    pedestrian_min_sigma_x_m: float = 0.3
    # vision width: measurement sigma and random-walk density of the width filter (chosen)
    width_sigma_m: float = 0.2
    width_walk_m2ps: float = 0.01
    # a new track starts with speed 0 and this sigma on each velocity axis (chosen: a 30 m/s
    # car lies within 2 sigma)
    initial_velocity_sigma_mps: float = 15.0
    # position sigma added on each axis when the ego motion of a frame is unknown (chosen)
    unknown_ego_sigma_m: float = 2.0
    # filtered positions kept per track, this frame's included (chosen: 3 s at 10 fps)
    history_length: int = 30
    # a pedestrian track is no longer confirmed once its speed over the ground is above this
    # by more than pedestrian_speed_gate_sigmas of the speed's sigma: a "person" moving with
    # the traffic is a part of a vehicle (chosen: a jog, as pedestrian.radar_min_speed_mps;
    # the margin keeps a person seen far away, whose distance is noisy, from seeming to run)
    pedestrian_max_speed_mps: float = 3.0
    pedestrian_speed_gate_sigmas: float = 2.0
    # a confirmed track missed on this frame shows its last box moved to where the track
    # expects its object, sized for that distance (chosen; false: the last box stays where it
    # was measured, as in the papers' preset; core/tracking.py, `coasting_boxes`)
    coasting_boxes_follow: bool = True
    # there, a pedestrian's box stands at most this fast from where its track was at its last
    # hit (chosen: a walking pace; the velocity of a track of a few hits is mostly the noise
    # of distances read from foot rows; core/tracking.py, step 6)
    pedestrian_coasting_speed_mps: float = 1.5

    def __post_init__(self) -> None:
        _check(self.confirm_frames >= 1, "confirm_frames", "an integer >= 1", self.confirm_frames)
        _check(
            self.pedestrian_confirm_frames >= 1,
            "pedestrian_confirm_frames",
            "an integer >= 1",
            self.pedestrian_confirm_frames,
        )
        _check(
            self.show_vehicles_after_hits >= 0,
            "show_vehicles_after_hits",
            "an integer >= 0",
            self.show_vehicles_after_hits,
        )
        for name in ("early_clearance_ahead_m", "early_clearance_across_m"):
            value = getattr(self, name)
            _check(math.isfinite(value) and value >= 0, name, "a distance >= 0", value)
        _check(
            self.max_missed_frames >= 0,
            "max_missed_frames",
            "an integer >= 0",
            self.max_missed_frames,
        )
        _check(
            self.tentative_max_missed_frames >= 0,
            "tentative_max_missed_frames",
            "an integer >= 0",
            self.tentative_max_missed_frames,
        )
        _positive(
            self,
            "gate_m",
            "gate_chi2",
            "vehicle_accel_psd_m2ps3",
            "pedestrian_accel_psd_m2ps3",
            "radar_sigma_x_m",
            "vision_sigma_y_m",
            "guard_rail_sigma_y_m",
            "pedestrian_sigma_x_fraction",
            "pedestrian_min_sigma_x_m",
            "width_sigma_m",
            "initial_velocity_sigma_mps",
            "pedestrian_max_speed_mps",
            "pedestrian_coasting_speed_mps",
        )
        for name in (
            "guard_rail_accel_psd_m2ps3",
            "width_walk_m2ps",
            "unknown_ego_sigma_m",
            "pedestrian_speed_gate_sigmas",
        ):
            value = getattr(self, name)
            _check(math.isfinite(value) and value >= 0, name, "a number >= 0", value)
        _check(self.history_length >= 1, "history_length", "an integer >= 1", self.history_length)


@dataclass(frozen=True)
class Params:
    """The whole configuration: one value per stage."""

    pitch: PitchParams = field(default_factory=PitchParams)
    motion_stereo: MotionStereoParams = field(default_factory=MotionStereoParams)
    vehicle: VehicleParams = field(default_factory=VehicleParams)
    guardrail: GuardRailParams = field(default_factory=GuardRailParams)
    pedestrian: PedestrianParams = field(default_factory=PedestrianParams)
    tracking: TrackingParams = field(default_factory=TrackingParams)

    def with_value(self, dotted: str, value: object) -> Params:
        """A copy with one leaf replaced, e.g. `with_value("pitch.merge_angle_rad", 0.03)`."""
        return self.with_values({dotted: value})

    def with_values(self, values: Mapping[str, object]) -> Params:
        """A copy with several leaves replaced at once, so that values checked against each
        other (min_distance_m < max_distance_m) may change together. ParamsError names an
        unknown leaf or a value refused."""
        data = to_dict(self)
        for dotted, value in values.items():
            node, leaf = _leaf_of(data, dotted)
            node[leaf] = value
        return from_dict(data)

    def value_of(self, dotted: str) -> object:
        """The value of one leaf, e.g. `value_of("pitch.lines_kept")`; ParamsError when there
        is none."""
        node, leaf = _leaf_of(to_dict(self), dotted)
        return node[leaf]


def _leaf_of(data: dict[str, Any], dotted: str) -> tuple[dict[str, Any], str]:
    """The dict holding the leaf `dotted` of nested parameter dicts, and the leaf's name;
    ParamsError naming what is known where the name goes wrong."""
    node = data
    parts = dotted.split(".")
    for part in parts[:-1]:
        if not isinstance(node.get(part), dict):
            groups = ", ".join(k for k, v in node.items() if isinstance(v, dict))
            raise ParamsError(f"{dotted}: no such parameter group {part!r}; known here: {groups}")
        node = node[part]
    leaf = parts[-1]
    if leaf not in node:
        raise ParamsError(f"{dotted}: no such parameter; known here: {', '.join(node)}")
    if isinstance(node[leaf], dict):
        raise ParamsError(
            f"{dotted}: no such parameter; known here: {', '.join(node)} ({dotted} is a "
            f"group of parameters, not one; in it: {', '.join(node[leaf])})"
        )
    return node, leaf


T = TypeVar("T")


def to_dict(value: object) -> dict[str, Any]:
    """Nested plain dict of a parameter dataclass (YAML-ready)."""
    if not dataclasses.is_dataclass(value) or isinstance(value, type):
        raise TypeError(f"to_dict: expected a dataclass instance, got {type(value).__name__}")
    return dataclasses.asdict(value)


HASH_HEX_DIGITS = 10  # of a parameter set's SHA-256: 40 bits, no clash among thousands of sets


def params_hash(params: Params) -> str:
    """A short, stable name of a parameter set: the first `HASH_HEX_DIGITS` hex digits of the
    SHA-256 of its values as sorted JSON. Equal sets have equal hashes in any process; it
    names sweep sets, is burned into exported videos and keys shared views."""
    text = json.dumps(to_dict(params), sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:HASH_HEX_DIGITS]


def _coerce(path: str, tp: Any, raw: object) -> object:
    if dataclasses.is_dataclass(tp) and isinstance(tp, type):
        if not isinstance(raw, dict):
            raise ParamsError(f"{path}: expected a mapping of parameters, got {raw!r}")
        return _build(tp, raw, path)
    if tp is bool:
        _check(isinstance(raw, bool), path, "true or false", raw)
        return raw
    if tp is int:
        _check(isinstance(raw, int) and not isinstance(raw, bool), path, "an integer", raw)
        return raw
    if tp is float:
        _check(isinstance(raw, (int, float)) and not isinstance(raw, bool), path, "a number", raw)
        try:
            return float(typing.cast(float, raw))
        except OverflowError:
            raise ParamsError(f"{path}: expected a number in float range, got {raw!r}") from None
    if tp is str:
        _check(isinstance(raw, str), path, "a string", raw)
        return raw
    if typing.get_origin(tp) in (typing.Union, types.UnionType):
        for option in typing.get_args(tp):
            if option is type(None) and raw is None:
                return None
        options = [a for a in typing.get_args(tp) if a is not type(None)]
        return _coerce(path, options[0], raw)
    raise ParamsError(f"{path}: unsupported parameter type {tp!r}")


def _build(cls: type[T], raw: dict[str, Any], prefix: str = "") -> T:
    hints = typing.get_type_hints(cls)
    fields = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
    unknown = sorted(set(raw) - fields, key=str)
    if unknown:
        where = f"{prefix}." if prefix else ""
        raise ParamsError(
            f"{where}{unknown[0]}: unknown parameter; known here: {', '.join(sorted(fields))}"
        )
    kwargs = {
        name: _coerce(f"{prefix}.{name}" if prefix else name, hints[name], value)
        for name, value in raw.items()
    }
    try:
        return cls(**kwargs)
    except ParamsError as err:
        raise ParamsError(f"{prefix}.{err}" if prefix else str(err)) from None


def from_dict(raw: dict[str, Any]) -> Params:
    """Params from a nested dict; missing keys take their defaults."""
    return _build(Params, raw)


def save_params(params: Params, path: Path | str) -> None:
    """Write `params` as YAML, with a format version."""
    data = {"format_version": PARAMS_FORMAT_VERSION, **to_dict(params)}
    Path(path).write_text(yaml.safe_dump(data, sort_keys=False), encoding="utf-8")


# Built-in parameter sets by name, each a YAML file in core/presets/: "papers", the papers'
# pipeline pinned before the defaults departed from it (its header says what it holds).
PRESETS_DIR = Path(__file__).with_name("presets")
BUILTIN_PRESETS = ("papers",)


def params_from(spec: str | Path | None) -> Params:
    """The parameters `--params` names: None the defaults; a built-in preset's name
    (BUILTIN_PRESETS; give a file of that name as ./NAME.yaml or by another path); else a
    parameter file. ParamsError naming the file or the field."""
    if spec is None:
        return Params()
    if str(spec) in BUILTIN_PRESETS:
        return load_params(PRESETS_DIR / f"{spec}.yaml")
    return load_params(spec)


def load_params(path: Path | str) -> Params:
    """Read a YAML parameter file; raises ParamsError naming the file and the field."""
    p = Path(path)
    try:
        raw = yaml.safe_load(p.read_text(encoding="utf-8"))
    except OSError as err:
        raise ParamsError(f"{p}: cannot read parameter file: {err.strerror}") from err
    except UnicodeDecodeError as err:
        raise ParamsError(f"{p}: not a UTF-8 text file: {err}") from err
    except yaml.YAMLError as err:
        raise ParamsError(f"{p}: not valid YAML: {err}") from err
    if raw is None:
        raw = {}
    if not isinstance(raw, dict):
        raise ParamsError(f"{p}: expected a mapping of parameter groups, got {type(raw).__name__}")
    version = raw.pop("format_version", PARAMS_FORMAT_VERSION)
    if isinstance(version, bool) or version != PARAMS_FORMAT_VERSION:
        raise ParamsError(f"{p}: format_version: expected {PARAMS_FORMAT_VERSION}, got {version!r}")
    try:
        return from_dict(raw)
    except ParamsError as err:
        raise ParamsError(f"{p}: {err}") from None
