"""One frame's detections under two parameter sets, A and B: what each found that the other
did not (the inspector's A/B compare).

The detections of a frame (`detections`) are the papers' final per-frame outputs, untracked:

- the vehicles (`VehicleResult.vehicles`, after merging and the world-size filter);
- the pedestrians kept by both fusion filters (verdict "pedestrian"), with their box
  extended down to the feet, the box the evaluation scores;
- the radar targets the guard-rail filter labelled (searched or by overlap), with their
  search area's box.

`diff_detections(a, b)` pairs them one-to-one within a kind:

- vehicles with vehicles and pedestrians with pedestrians by image-box overlap: every pair
  whose IoU (`core.evaluation.objects.iou`, intersection over union) reaches `iou_min` is
  a candidate, and candidates are taken greedily, highest IoU first (equal IoUs in the
  order of A's then B's detections), each detection in at most one pair. Greedy can pair
  fewer than the most possible only when a box has two candidates; with `iou_min` above
  0.5 that needs two boxes of one set that overlap each other, which the vehicle merge and
  the pedestrian non-maximum suppression make rare, and greedy is how a person pairs boxes
  by eye;
- guard-rail labels by their radar target: both results are of one frame, so target k is
  the same return in both and a label of target k under A matches one under B.

Boxes are (u0, v0, u1, v1) full-image pixel edges, pixel centres at whole numbers, as
`core.vehicle.Vehicle.box_px`; distances are x ahead in the vehicle frame, metres.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

from core.engine import FrameResult
from core.evaluation.objects import iou
from core.search_area import SearchArea

Box = tuple[float, float, float, float]
Kind = Literal["vehicle", "pedestrian", "guard rail"]
KINDS: tuple[Kind, ...] = ("vehicle", "pedestrian", "guard rail")
# matched by their image boxes; guard-rail labels are matched by their radar target
BOX_KINDS: tuple[Kind, ...] = ("vehicle", "pedestrian")
DEFAULT_IOU_MIN = 0.5  # as CLEAR-MOT's match (core.evaluation.mot.IOU_MATCH)


@dataclass(frozen=True)
class Detection:
    """One detection of a frame.

    kind: "vehicle", "pedestrian" or "guard rail"; box_px: (u0, v0, u1, v1) image box in
    pixel edges (a guard rail's: its target's search area); distance_m: x ahead (a vehicle's
    and a guard rail's from the radar, a pedestrian's where its feet meet the road; NaN when
    unknown); label: a short text for people; target_index: the radar target of a
    guard-rail label (None for vehicles and pedestrians).
    """

    kind: Kind
    box_px: Box
    distance_m: float
    label: str
    target_index: int | None = None


@dataclass(frozen=True)
class DetectionDiff:
    """only_a / only_b: detections of A without a match in B and of B without one in A,
    each in `detections` order; matched: the number of pairs matched."""

    only_a: tuple[Detection, ...]
    only_b: tuple[Detection, ...]
    matched: int


def _metres(x: float, spec: str) -> str:
    """`x` formatted by `spec` (e.g. "+.1f"), never as "-0.0"; "?" when not finite."""
    return format(x, spec.replace(".", "z.", 1)) if math.isfinite(x) else "?"


def _area_box(area: SearchArea) -> Box:
    """The area's image box in pixel edges (its patch's corners mapped to the image)."""
    h, w = area.patch.shape
    (u0, u1), (v0, v1) = area.to_image_px([0, w], [0, h])
    return (float(u0), float(v0), float(u1), float(v1))


def detections(result: FrameResult) -> tuple[Detection, ...]:
    """The frame's vehicles, kept pedestrians and guard-rail labels (module docstring), in
    that order: vehicles and pedestrians as the results list them, guard rails by target."""
    out = [
        Detection(
            "vehicle",
            v.outline_px,
            v.distance_m,
            f"vehicle at {_metres(v.distance_m, '.1f')} m, "
            f"lateral {_metres(v.lateral_m, '+.1f')} m, {_metres(v.width_m, '.1f')} m wide",
        )
        for v in result.vehicle.vehicles
    ]
    out += [
        Detection(
            "pedestrian",
            p.extended_box_px,
            p.distance_m,
            f"pedestrian at col {round(p.axis_px)}, {_metres(p.distance_m, '.0f')} m",
        )
        for p in result.pedestrian.kept
    ]
    labelled = result.guardrail.guard_rail_targets
    out += [
        Detection(
            "guard rail",
            _area_box(a),
            a.x_m,
            f"guard rail: radar target {a.target_index} at {_metres(a.x_m, '.1f')} m",
            a.target_index,
        )
        for a in sorted(result.areas, key=lambda a: a.target_index)
        if a.target_index in labelled
    ]
    return tuple(out)


def _pairs_by_iou(a: Sequence[Box], b: Sequence[Box], iou_min: float) -> list[tuple[int, int]]:
    """Greedy one-to-one pairs (i, j) of boxes a[i], b[j] with IoU >= iou_min, highest
    first (module docstring)."""
    candidates = [
        (overlap, i, j)
        for i, box_a in enumerate(a)
        for j, box_b in enumerate(b)
        if (overlap := iou(box_a, box_b)) >= iou_min
    ]
    candidates.sort(key=lambda c: (-c[0], c[1], c[2]))
    used_a: set[int] = set()
    used_b: set[int] = set()
    pairs = []
    for _, i, j in candidates:
        if i not in used_a and j not in used_b:
            used_a.add(i)
            used_b.add(j)
            pairs.append((i, j))
    return pairs


def diff_detections(
    a: FrameResult, b: FrameResult, iou_min: float = DEFAULT_IOU_MIN
) -> DetectionDiff:
    """What frame result `a` detected that `b` did not, and the reverse (module docstring).

    a, b: the same frame (same index and time) under two parameter sets; iou_min: the
    least IoU, in (0, 1], of a vehicle or pedestrian pair. ValueError when the two are not
    of one frame or iou_min is out of range.
    """
    if not 0.0 < iou_min <= 1.0:
        raise ValueError(f"iou_min: expected an overlap in (0, 1], got {iou_min}")
    if a.index != b.index:
        raise ValueError(
            f"a, b: expected results of one frame, got frame {a.index} (a) and frame {b.index} (b)"
        )
    if a.t_ns != b.t_ns:
        raise ValueError(
            f"a, b: expected results of one frame, got frame {a.index} at {a.t_ns} ns (a) "
            f"and at {b.t_ns} ns (b): two recordings?"
        )
    found_a, found_b = detections(a), detections(b)
    matched_a: set[int] = set()
    matched_b: set[int] = set()
    for kind in BOX_KINDS:
        ia = [k for k, d in enumerate(found_a) if d.kind == kind]
        ib = [k for k, d in enumerate(found_b) if d.kind == kind]
        pairs = _pairs_by_iou(
            [found_a[k].box_px for k in ia], [found_b[k].box_px for k in ib], iou_min
        )
        matched_a.update(ia[i] for i, _ in pairs)
        matched_b.update(ib[j] for _, j in pairs)
    rails_a = {d.target_index: k for k, d in enumerate(found_a) if d.kind == "guard rail"}
    rails_b = {d.target_index: k for k, d in enumerate(found_b) if d.kind == "guard rail"}
    for target in rails_a.keys() & rails_b.keys():
        matched_a.add(rails_a[target])
        matched_b.add(rails_b[target])
    return DetectionDiff(
        only_a=tuple(d for k, d in enumerate(found_a) if k not in matched_a),
        only_b=tuple(d for k, d in enumerate(found_b) if k not in matched_b),
        matched=len(matched_a),
    )
