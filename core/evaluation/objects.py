"""Pedestrians (paper 000), guard rails (paper 002), motion stereo's obstacle mask and the
pitch, scored frame by frame against ground truth.

- Pedestrians: a *visible* pedestrian is less than MAX_OCCLUSION hidden and within the
  detector's distance range (PedestrianParams min/max_distance_m). It is found when a box
  overlaps its true box by at least IOU_MATCH of their union; a box is a true positive when
  it overlaps any true pedestrian so (hidden ones included, which a box may rightly find).
  Recall = found / visible, precision = true boxes / boxes.
- Guard rails: a slow radar target (one the filter checked) is a *rail return* when it lies
  within NEAR_RAIL_M of a truth rail and on no vehicle. FN: a rail return not labelled;
  FP: a labelled target that is no rail return; vehicles labelled: labelled targets lying on
  a vehicle (paper 002: must be 0). Truth rails are image polylines along the beam
  (RAIL_HEIGHT_M above the road), taken to the road plane with the frame's true pitch. On
  frames whose truth does not label guard rails (real drives imported with their 3D
  labels) only the vehicles labelled count: rail returns, FN and FP need rail truth.
- Motion stereo: the expected obstacles are truth objects on its grid, less than
  MAX_OCCLUSION hidden, at least MIN_BOX_HEIGHT_PX tall, and moving when the car stands
  still (background subtraction sees only what moves). On the camera image's row window:
  object recall = expected obstacles with a marked pixel in their box; pixel recall = their
  box pixels marked; pixel precision = marked pixels inside any truth object's box (this
  frame's, widened by BOX_MARGIN_PX: the reprojected D lies on the obstacle's base). The
  same scores a baseline's image mask.
- Pitch: error = detected - true pitch, RMS and largest magnitude, in degrees.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.frame import RadarTarget
from core.io.groundtruth import FrameTruth, TruthObject
from core.params import MotionStereoParams
from core.search_area import iou

from .counts import add_fields
from .vehicles import VEHICLE_CLASSES, lies_on

Box = tuple[float, float, float, float]

IOU_MATCH = 0.3  # pedestrian boxes overlapping this much of their union match
MAX_OCCLUSION = 0.5
NEAR_RAIL_M = 1.0  # a slow target this close to a truth rail is a rail return
RAIL_HEIGHT_M = 0.61  # the truth polylines run along the beam's centre, this high
MIN_BOX_HEIGHT_PX = 8.0  # smaller obstacles are too far for motion stereo's grid
BOX_MARGIN_PX = 4  # a marked pixel this close to an object's box is explained by it
MOVING_MPS = 0.5  # an object faster than this over the ground moves


@dataclass(frozen=True)
class BoxScore:
    """Counts of one box detector over frames; missed_at / false_at: (frame index, truth id)
    of each visible person not found and (frame index, box index) of each false box."""

    visible: int = 0
    found: int = 0
    boxes: int = 0
    true_boxes: int = 0
    missed_at: tuple[tuple[int, int], ...] = ()
    false_at: tuple[tuple[int, int], ...] = ()

    @property
    def recall(self) -> float:
        return self.found / self.visible if self.visible else 0.0

    @property
    def precision(self) -> float:
        return self.true_boxes / self.boxes if self.boxes else 0.0

    def __add__(self, other: BoxScore) -> BoxScore:
        return add_fields(self, other)


def visible_person(o: TruthObject, min_distance_m: float, max_distance_m: float) -> bool:
    """A pedestrian the detector should find (module docstring)."""
    return (
        o.cls == "pedestrian"
        and o.occlusion < MAX_OCCLUSION
        and min_distance_m <= o.position_m[0] <= max_distance_m
    )


def score_pedestrians(
    index: int,
    boxes: Sequence[Box],
    objects: Sequence[TruthObject],
    min_distance_m: float,
    max_distance_m: float,
) -> BoxScore:
    """One frame's pedestrian boxes against the truth (module docstring)."""
    people = [o for o in objects if o.cls == "pedestrian"]
    visible = [o for o in people if visible_person(o, min_distance_m, max_distance_m)]
    missed = tuple(
        (index, o.id) for o in visible if not any(iou(b, o.box_px) >= IOU_MATCH for b in boxes)
    )
    false = tuple(
        (index, k)
        for k, b in enumerate(boxes)
        if not any(iou(b, o.box_px) >= IOU_MATCH for o in people)
    )
    return BoxScore(
        visible=len(visible),
        found=len(visible) - len(missed),
        boxes=len(boxes),
        true_boxes=len(boxes) - len(false),
        missed_at=missed,
        false_at=false,
    )


@dataclass(frozen=True)
class RailScore:
    """Guard-rail labels over frames (module docstring); *_at: (frame index, target index)."""

    slow_targets: int = 0
    rail_returns: int = 0
    labelled: int = 0
    fn_at: tuple[tuple[int, int], ...] = ()
    fp_at: tuple[tuple[int, int], ...] = ()
    vehicles_labelled_at: tuple[tuple[int, int], ...] = ()
    rail_truth_frames: int = 0  # frames whose truth labels guard rails: FN and FP count there

    @property
    def fn(self) -> int:
        return len(self.fn_at)

    @property
    def fp(self) -> int:
        return len(self.fp_at)

    @property
    def vehicles_labelled(self) -> int:
        return len(self.vehicles_labelled_at)

    def __add__(self, other: RailScore) -> RailScore:
        return add_fields(self, other)


def rails_on_road_m(truth: FrameTruth, camera: CameraModel) -> list[npt.NDArray[np.float64]]:
    """(N, 2) vehicle-frame (x, y) polylines of the frame's truth rails (camera: with the
    frame's true pitch)."""
    out = []
    for rail in truth.guard_rails:
        xyz = camera.point_at_height(np.array(rail.polyline_px, dtype=np.float64), RAIL_HEIGHT_M)
        xy = xyz[~np.isnan(xyz[:, 0]), :2]
        if len(xy) >= 2:
            out.append(xy)
    return out


def distance_to_polyline_m(x_m: float, y_m: float, polyline: npt.NDArray[np.float64]) -> float:
    a, b = polyline[:-1], polyline[1:]
    ab = b - a
    p = np.array([x_m, y_m])
    t = np.clip(((p - a) * ab).sum(axis=1) / np.maximum((ab * ab).sum(axis=1), 1e-12), 0, 1)
    return float(np.min(np.hypot(*(a + t[:, None] * ab - p).T)))


def score_rails(
    index: int,
    checked: Sequence[int],
    labelled: frozenset[int],
    radar: Sequence[RadarTarget],
    truth: FrameTruth,
    rails_m: Sequence[npt.NDArray[np.float64]],
) -> RailScore:
    """One frame: the targets the guard-rail filter checked and those it labelled. Without
    rail truth (truth.rails_labelled False) only the vehicles labelled guard rail count."""
    vehicles = [o for o in truth.objects if o.cls in VEHICLE_CLASSES]
    returns = 0
    fn_at, fp_at, vehicles_at = [], [], []
    for i in checked:
        t = radar[i]
        on_vehicle = any(lies_on(t.x_m, t.y_m, o) for o in vehicles)
        near = min((distance_to_polyline_m(t.x_m, t.y_m, r) for r in rails_m), default=math.inf)
        rail = near < NEAR_RAIL_M and not on_vehicle
        if i in labelled and on_vehicle:
            vehicles_at.append((index, i))
        if not truth.rails_labelled:
            continue
        returns += rail
        if rail and i not in labelled:
            fn_at.append((index, i))
        if i in labelled and not rail:
            fp_at.append((index, i))
    return RailScore(
        len(checked),
        returns,
        len(labelled),
        tuple(fn_at),
        tuple(fp_at),
        tuple(vehicles_at),
        int(truth.rails_labelled),
    )


@dataclass(frozen=True)
class MaskScore:
    """An obstacle mask over frames (module docstring)."""

    obstacles: int = 0
    obstacles_hit: int = 0
    truth_px: int = 0
    truth_marked_px: int = 0
    marked_px: int = 0
    marked_on_objects_px: int = 0
    missed_at: tuple[tuple[int, int], ...] = ()

    @property
    def object_recall(self) -> float:
        return self.obstacles_hit / self.obstacles if self.obstacles else 0.0

    @property
    def pixel_recall(self) -> float:
        return self.truth_marked_px / self.truth_px if self.truth_px else 0.0

    @property
    def pixel_precision(self) -> float:
        return self.marked_on_objects_px / self.marked_px if self.marked_px else 0.0

    def __add__(self, other: MaskScore) -> MaskScore:
        return add_fields(self, other)


def _on_grid(o: TruthObject, params: MotionStereoParams) -> bool:
    x, y, _ = o.position_m
    return params.x_min_m <= x <= params.x_max_m and abs(y) <= params.y_half_width_m


def _clip(box: Box, shape: tuple[int, int], first_row: int, margin: int) -> tuple[int, ...]:
    u0, v0, u1, v1 = box
    rows, cols = shape
    r0 = max(math.floor(v0 + 0.5) - margin - first_row, 0)
    r1 = min(math.ceil(v1 - 0.5) + 1 + margin - first_row, rows)
    c0 = max(math.floor(u0 + 0.5) - margin, 0)
    c1 = min(math.ceil(u1 - 0.5) + 1 + margin, cols)
    return r0, max(r1, r0), c0, max(c1, c0)


def score_mask(
    index: int,
    mask: npt.NDArray[np.uint8],
    first_row_px: int,
    truth: FrameTruth,
    params: MotionStereoParams,
    still: bool,
) -> MaskScore:
    """One frame's obstacle mask, (rows, W) uint8 (nonzero: obstacle) whose row 0 is image
    row first_row_px, against the truth (module docstring); still: the car stands still."""
    marked = mask != 0
    explained = np.zeros_like(marked)
    for o in truth.objects:
        r0, r1, c0, c1 = _clip(o.box_px, mask.shape, first_row_px, BOX_MARGIN_PX)
        explained[r0:r1, c0:c1] = True
    obstacles = hit = truth_px = truth_marked = 0
    missed = []
    for o in truth.objects:
        moving = math.hypot(*o.velocity_mps) > MOVING_MPS
        if not (
            _on_grid(o, params)
            and o.occlusion < MAX_OCCLUSION
            and o.box_px[3] - o.box_px[1] >= MIN_BOX_HEIGHT_PX
            and (moving or not still)
        ):
            continue
        r0, r1, c0, c1 = _clip(o.box_px, mask.shape, first_row_px, 0)
        if r1 <= r0 or c1 <= c0:
            continue
        obstacles += 1
        inside = int(np.count_nonzero(marked[r0:r1, c0:c1]))
        hit += inside > 0
        if inside == 0:
            missed.append((index, o.id))
        truth_px += (r1 - r0) * (c1 - c0)
        truth_marked += inside
    return MaskScore(
        obstacles=obstacles,
        obstacles_hit=hit,
        truth_px=truth_px,
        truth_marked_px=truth_marked,
        marked_px=int(np.count_nonzero(marked)),
        marked_on_objects_px=int(np.count_nonzero(marked & explained)),
        missed_at=tuple(missed),
    )


@dataclass(frozen=True)
class PitchScore:
    """Pitch errors over frames, degrees: detected - true; `calibration`: keeping the
    calibrated pitch instead."""

    errors_deg: tuple[float, ...] = ()
    calibration_errors_deg: tuple[float, ...] = ()

    @staticmethod
    def _rms(values: Sequence[float]) -> float:
        return math.sqrt(sum(v * v for v in values) / len(values)) if values else math.nan

    @property
    def rms_deg(self) -> float:
        return self._rms(self.errors_deg)

    @property
    def max_deg(self) -> float:
        return max((abs(v) for v in self.errors_deg), default=math.nan)

    @property
    def calibration_rms_deg(self) -> float:
        return self._rms(self.calibration_errors_deg)

    def __add__(self, other: PitchScore) -> PitchScore:
        return add_fields(self, other)


def score_pitch(pitch_rad: float, true_pitch_rad: float, calibrated_rad: float) -> PitchScore:
    """One frame's pitch errors; none when the truth has no pitch (NaN: an annotated real
    drive, `core.annotation.truth`)."""
    if math.isnan(true_pitch_rad):
        return PitchScore()
    return PitchScore(
        (math.degrees(pitch_rad - true_pitch_rad),),
        (math.degrees(calibrated_rad - true_pitch_rad),),
    )
