"""Vehicles the tracker follows, found again by their appearance when neither a radar
target's symmetry search nor the track search (`core.track_search`) framed them on this
frame (beyond the papers).

Symmetry needs both of a vehicle's borders and its shadow on every frame; in a queue or
against dark trees they come and go, and a track is lost after `max_missed_frames` frames
without them although the vehicle looks as it did. So:

1. template: a confirmed vehicle track measured on this frame by a radar target's vehicle
   (`core.vehicle`, not one searched for without radar) keeps that vehicle's box as an
   image patch, with its distance. The template is kept `appearance_max_age_frames` frames
   after it was taken and replaced whenever such a detection comes again;
2. search: a confirmed track as the tracker predicts it on this frame
   (`core.tracking.Tracker.predicted`) with a template and with no vehicle of the frame
   overlapping its expected box (`core.tracking.expected_boxes`) by more than
   DETECTED_OVERLAP of the smaller box: its template, scaled by template distance
   / predicted distance, is matched by normalised cross-correlation (OpenCV's
   TM_CCOEFF_NORMED) over the expected box widened by half the scaled template's width on
   either side and by 30 % of its height above and below (SEARCH_MARGIN_*), plus
   MARGIN_PX;
3. the best match is kept when its correlation reaches `appearance_min_ncc`, its lateral
   position and width on the predicted distance's vertical plane agree with the track's
   within `track_search_agreement_m`, that width is a vehicle's (`min_width_m` ..
   `max_width_m`) and it overlaps no vehicle of the frame (nor an earlier match) by more
   than `merge_overlap_fraction` of the smaller box;
4. a match is a measurement for its track alone (`core.tracking.Measurement.for_track`):
   box, lateral position and width measured, the distance the prediction. It is no
   detection: the frame's vehicles, and the figures scored on them (RD, FP per frame), do
   not hold it; the tracks do.

Coordinates: full-image pixels, boxes (u0, v0, u1, v1) as `core.vehicle` gives them (pixel
centres at integers); distances in the vehicle frame (x forward, y left), metres.

Notes:
    - All of it goes beyond the papers; `appearance_max_age_frames` 0 (the papers' preset)
      turns it off.
    - Measured on drives of new seeds (20 s each), radar-seen MOTA, highway / exurban /
      stop_and_go, off -> on: held out 1818-2525 0.679 / 0.581 / 0.499 -> 0.719 / 0.562 /
      0.524; seeds 1313-1717 + 2727 0.716 / 0.634 / 0.427 -> 0.727 / 0.629 / 0.496; seeds
      2929-3333 0.687 / 0.585 / 0.399 -> 0.683 / 0.597 / 0.460; seeds 3434-3636 (3636 made
      after the change) 0.704 / 0.688 / 0.519 -> 0.743 / 0.697 / 0.529. The misses fall
      (stop_and_go held out 668 -> 581), the tracks' false boxes rise (100 -> 158). On
      exurban the tracks kept include that of a van 41 m ahead whose symmetry box lies half
      a width off (seed 2020 MOTA 0.603 -> 0.572): it lives on, and its boxes count as
      false as they did while it lived before. Raw vehicle FP per frame moved by -0.005 ..
      +0.004 (the tracks' areas), RD / (RD + FN) by -0.003 .. +0.013. nuScenes 0.21 ->
      0.22, aiMotive the same. No cost above the bench's noise (whole frame 5.1-5.3 ms on
      against 5.3-5.4 ms off, the same run).
    - Measured on the held-out seeds with a first version: step 3, 0.8: 0.85 kept fewer
      tracks alive (stop_and_go 0.518 at an age of 3); step 1, 5 frames: 3 gained less on
      stop_and_go (0.514), 8 frames lost on exurban (0.562).
    - Step 4: taking the match's distance from a nearby radar target, or as the
      measurement of a new detection, raised the raw RD on stop_and_go by 0.03 but its FP
      per frame over 0.05 (a prediction 0.5-1 m short of a vehicle pulling away in a
      queue); a distance from the best of five template scales (0.96-1.04) was worse (FP
      0.07-0.10 per frame). The distance stays the prediction, as the track search's.
    - Steps 1-2 cut templates and search windows on the pixels holding a box's edges
      (`core.search_area.box_pixels`, as the inspector draws boxes); the first version
      rounded each edge to the nearest pixel border. Held out, radar-seen MOTA 0.719 /
      0.562 / 0.524 -> 0.718 / 0.560 / 0.525; seeds 1313-1717 + 2727 0.727 / 0.629 / 0.496
      -> 0.736 / 0.631 / 0.485.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.params import VehicleParams
from core.search_area import box_pixels
from core.tracking import Track, expected_boxes
from core.vehicle import Vehicle, overlap_of_smaller, world_extents

Box = tuple[float, float, float, float]
U8Array = npt.NDArray[np.uint8]

# Step 2: the search reaches this share of the scaled template's width beyond either side of
# the expected box, and this share of its height above and below, plus MARGIN_PX.
SEARCH_MARGIN_WIDTH = 0.5
SEARCH_MARGIN_HEIGHT = 0.3
MARGIN_PX = 2
# Step 2: a track whose expected box a vehicle of the frame overlaps by more than this share
# of the smaller box was detected.
DETECTED_OVERLAP = 0.3
# Templates or scaled templates narrower or lower than this are not matched.
MIN_TEMPLATE_PX = 8


@dataclass(frozen=True, eq=False)
class Template:
    """A track's look: patch, (h, w) uint8 grey, read-only, the pixels of its last radar
    vehicle's box; distance_m: that vehicle's distance; age_frames: frames since it was
    taken (0 on that frame)."""

    patch: U8Array
    distance_m: float
    age_frames: int


@dataclass(frozen=True)
class AppearanceMatch:
    """A tracked vehicle found by its template: track_id; vehicle: its box (the matched
    patch), the predicted distance, lateral position and width from vision, no radar
    target; ncc: the normalised cross-correlation of the match."""

    track_id: int
    vehicle: Vehicle
    ncc: float


def _pixels(box: Box, shape: tuple[int, ...]) -> tuple[int, int, int, int]:
    """The pixels (col0, row0, col1, row1), end exclusive, holding a pixel-edge box
    (`core.search_area.box_pixels`), cut at the image border."""
    c0, r0, c1, r1 = box_pixels(box)
    return max(c0, 0), max(r0, 0), min(c1 + 1, shape[1]), min(r1 + 1, shape[0])


def remember(
    templates: Mapping[int, Template],
    tracks: Sequence[Track],
    image: U8Array,
    vehicles: Sequence[Vehicle],
    radar_vehicles: int,
    params: VehicleParams,
) -> dict[int, Template]:
    """Step 1 after the tracker's update: the templates of the live confirmed vehicle tracks.

    tracks: every track after the update; vehicles: the frame's vehicles, the first
    `radar_vehicles` from radar targets (source_index of a track's measurement indexes
    them); templates: those kept after the last frame. None when the search is off
    (`appearance_max_age_frames` 0)."""
    kept: dict[int, Template] = {}
    if params.appearance_max_age_frames == 0:
        return kept
    for t in tracks:
        if t.kind != "vehicle" or not t.confirmed:
            continue
        if t.misses == 0 and t.source_index is not None and t.source_index < radar_vehicles:
            v = vehicles[t.source_index]
            c0, r0, c1, r1 = _pixels(v.box_px, image.shape)
            if c1 - c0 >= MIN_TEMPLATE_PX and r1 - r0 >= MIN_TEMPLATE_PX:
                patch = image[r0:r1, c0:c1].copy()
                patch.flags.writeable = False
                kept[t.id] = Template(patch, v.distance_m, 0)
                continue
        old = templates.get(t.id)
        if old is not None and old.age_frames < params.appearance_max_age_frames:
            kept[t.id] = Template(old.patch, old.distance_m, old.age_frames + 1)
    return kept


def _match(image: U8Array, template: U8Array, expected: Box) -> tuple[float, Box] | None:
    """Step 2: (correlation, box) of the template's best match around the expected box;
    None when the search window does not hold the template."""
    h, w = template.shape
    u0, _, u1, v1 = expected
    margin_u = SEARCH_MARGIN_WIDTH * w + MARGIN_PX
    margin_v = SEARCH_MARGIN_HEIGHT * h + MARGIN_PX
    centre = (u0 + u1) / 2
    c0, r0, c1, r1 = _pixels(
        (centre - w / 2 - margin_u, v1 - h - margin_v, centre + w / 2 + margin_u, v1 + margin_v),
        image.shape,
    )
    if c1 - c0 < w or r1 - r0 < h:
        return None
    scores = cv2.matchTemplate(image[r0:r1, c0:c1], template, cv2.TM_CCOEFF_NORMED)
    _, best, _, (col, row) = cv2.minMaxLoc(scores)
    left, top = c0 + col - 0.5, r0 + row - 0.5  # pixel edges
    return float(best), (left, top, left + w, top + h)


def find_by_appearance(
    image: U8Array,
    camera: CameraModel,
    predicted: Sequence[Track],
    templates: Mapping[int, Template],
    vehicles: Sequence[Vehicle],
    params: VehicleParams,
) -> tuple[AppearanceMatch, ...]:
    """Steps 2-3: the predicted confirmed vehicle tracks found by their templates.

    image: the frame's (H, W) uint8 grey image; camera: this frame's; predicted:
    `Tracker.predicted("vehicle", ...)` for this frame; vehicles: every vehicle of the frame
    (radar targets' and the track search's)."""
    if params.appearance_max_age_frames == 0 or not predicted or not templates:
        return ()
    found: list[AppearanceMatch] = []
    taken = [v.box_px for v in vehicles]
    looked_for = [t for t in predicted if t.id in templates and t.x_m > 0]
    for t, expected in zip(looked_for, expected_boxes(looked_for, camera), strict=True):
        if expected is None:
            continue
        template = templates[t.id]
        if any(overlap_of_smaller(expected, b) > DETECTED_OVERLAP for b in taken):
            continue
        scale = template.distance_m / t.x_m
        h, w = template.patch.shape
        size = (round(w * scale), round(h * scale))
        if min(size) < MIN_TEMPLATE_PX:
            continue
        shrink = cv2.INTER_AREA if scale < 1 else cv2.INTER_LINEAR
        scaled = np.asarray(cv2.resize(template.patch, size, interpolation=shrink), np.uint8)
        match = _match(image, scaled, expected)
        if match is None or not match[0] >= params.appearance_min_ncc:
            continue
        ncc, box = match
        (lateral_m,), (width_m,), (vision_m,) = world_extents([box], [t.x_m], camera)
        agree = params.track_search_agreement_m
        if not (
            abs(lateral_m - t.y_m) <= agree
            and abs(width_m - t.width_m) <= agree
            and params.min_width_m <= width_m <= params.max_width_m
            and not any(overlap_of_smaller(box, b) > params.merge_overlap_fraction for b in taken)
        ):
            continue
        vehicle = Vehicle(box, t.x_m, lateral_m, width_m, vision_m, ())
        found.append(AppearanceMatch(t.id, vehicle, ncc))
        taken.append(box)
    return tuple(found)
