"""The image area searched around each radar target (paper 001, section II), shared by the
guard-rail filter and the vehicle detector.

For a target at (x_m, y_m) in the vehicle frame:

1. the radar point is mapped into the image on the object's base (the road, z = 0) with the
   frame's camera model (its detected pitch);
2. the area is `search_width_m` wide in the world at that distance (`moving_search_width_m`
   for a target moving over ground faster than `moving_speed_mps` or within `track_gate_m`
   of where the tracker expects a vehicle it follows, beyond the papers),
   centred on the target (beyond the papers: a target within `track_gate_m` of a tracked
   vehicle on that vehicle's tracked lateral position, with `centre_on_track`; a still
   target on its lateral position smoothed over the last scans, `core.radar_smoothing`):
   its left and right columns are the images of (x_m, y_m +- W / 2, 0); its height is
   `search_height_ratio` of `search_width_m` (of its width, for the paper's areas), and its
   bottom lies `search_bottom_fraction` of its height below the radar point, so the vehicle
   stays inside under pitch error;
3. only targets whose radar point lands inside the image get an area; an area crossing the
   image border is cropped to the image (the paper's second approach);
4. the cropped area is resampled by `scale = min(1, resampled_width_px / W_px)`, with W_px
   the uncropped width: every area ends up at most `resampled_width_px` wide with its aspect
   ratio kept, and is never enlarged (paper 001).

Coordinates: image pixels with pixel centres at integers (u column, v row), as the camera
model; an area's bounds are pixel edges. A patch pixel (r, c) covers the image rectangle
`to_image_px` maps its edges to.

Notes:
    - The paper does not say how the area's height relates to pixels and metres; here the
      height is `search_height_ratio` times the area's image width, which is the same
      fraction of its world width for square pixels (fx = fy).
    - Step 4 resamples bilinearly (OpenCV's INTER_LINEAR), not by pixel-area averaging:
      INTER_AREA cost 12 to 35 us per area (a third of the vehicle detector's budget for 8
      targets), and the refined shares of the bundled drives' vehicles stayed the same
      (highway 44 of 53 both ways).
    - Step 2, beyond the papers: paper 001 names the limit of its 2.5 m area, a vehicle
      missed when the radar point is off its centre or the vehicle is wider than the area.
      A 2.15 m car fits only with the point within 0.18 m of its centre; real points lie
      0.32-0.36 m off-centre (median, nuScenes and aiMotive) and radar-seen vehicles were
      outside every area on 46-66 % of their frames on drives of new seeds. A target moving
      over ground (|`core.io.frame.real_speed_mps`| > `moving_speed_mps`, never with the
      ego speed unknown) is a vehicle's: its area is `moving_search_width_m` wide, the
      widest vehicle (3 m) with the point 0.5 m off-centre. Still targets keep the paper's
      width: widening theirs too doubled the false positives (posts, signs, parked
      clutter), widening only the moving ones left them as they were. Measured on drives
      of seeds 101 and 202 (20 s each), RD per drive, papers -> 4 m moving areas, at the
      same FP per frame within 0.05: highway 159 -> 312 and 138 -> 307, exurban 201 -> 281
      and 158 -> 235, stop_and_go 123 -> 159 and 115 -> 138; nuScenes scene-0523 14 -> 31.
      A radar-seen vehicle outside every area (RFN): 0.47-0.66 -> 0.17-0.39 of their
      frames. Widths 3.5 and 4.5 m did as well within 5 % on these drives, and a moving
      threshold of 3 m/s did better on stop_and_go than 1, 2 or 5 m/s. The wider area
      keeps the paper's height (1.25 m): grown with its width it took in the background
      above a car (the RAV4 still's car ahead then ended in "no symmetry"), and highway
      RD on seed 202 was 254 rather than 307.
    - Step 2, tracked targets, beyond the papers: a vehicle that stops (a queue in
      stop_and_go) becomes a still target and lost its wide area, so the area missed it
      again. The tracker knows better: a target within `track_gate_m` = 1.5 m of where a
      confirmed vehicle track is expected on this frame (`core.tracking.Tracker.predicted`)
      keeps the wide area, however slow. Parked clutter never confirmed as a vehicle keeps
      the paper's. Measured on drives of seeds 101 and 202 (tuning: gates 1.5 and 2.5 m)
      and 404 and 707 (checking), off -> on: stop_and_go RD 157 -> 177, 141 -> 164,
      112 -> 130 and 123 -> 141, RFN of radar-seen vehicles down 0.04-0.07, tracked MOTA
      of radar-seen vehicles 0.12 -> 0.13, -0.09 -> 0.16, 0.10 -> 0.17 and 0.07 -> 0.16;
      exurban RD +4 to +9, MOTA 0.20 -> 0.27, 0.26 -> 0.28, 0.31 -> 0.30; highway
      the same; vehicle FP per frame up by 0.02 at most (tracked FP by 0.05 at most, on
      stop_and_go seed 101). nuScenes (2 Hz): detections the same, tracked MOTA 0.14 ->
      0.11.
    - Step 2, centred on the track (`centre_on_track`), beyond the papers: such a target's
      area is centred on the tracked vehicle's lateral position, vision's filtered over its
      frames, not on the radar point, which lies anywhere across the vehicle's rear or
      beside it. Measured with `fusionscope evaluate` on drives of new seeds (20 s each),
      radar-seen MOTA, highway / exurban / stop_and_go, off -> on (still targets smoothed,
      `core.radar_smoothing`, both ways): seeds 1313 + 1414 0.608 / 0.493 / 0.330 -> 0.595 /
      0.552 / 0.352; seeds 1515 + 909 0.582 / 0.443 / 0.300 -> 0.642 / 0.426 / 0.351;
      RD / (RD + FN) up on five of the six (0.817 / 0.699 / 0.550 -> 0.833 / 0.725 / 0.545,
      0.821 / 0.698 / 0.512 -> 0.833 / 0.711 / 0.538); raw vehicle FP per frame up by
      0.01-0.04, track FP per frame by 0.005-0.043 (at most 0.048). nuScenes (2 Hz, where
      a track's prediction is half a second old): detections the same, tracked RD / (RD +
      FN) 0.585 -> 0.623, MOTA 0.207 -> 0.179.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.frame import RadarTarget, real_speed_mps
from core.params import VehicleParams

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class SearchArea:
    """The area of one radar target.

    target_index: the target's place in the frame's radar tuple; base_px: (u, v) of the area's
    centre on the object's base (the radar point, or its smoothed centre:
    `core.radar_smoothing`); full_px: (u0, v0, u1, v1) pixel-edge bounds before cropping;
    box_px: (col0, row0, col1, row1) integer pixel bounds after cropping (end exclusive), so
    the crop is `image[row0:row1, col0:col1]`; y_left_m, y_right_m: the area's sides in the
    world (vehicle frame), at the target's x_m; patch: (h, w) uint8 grey, the crop resampled;
    px_per_m: patch pixels per metre across at the target's distance; moving: the target
    moves over ground (`moves`); tracked: the target lies within `track_gate_m` of where a
    confirmed vehicle track is expected (`tracked_vehicle`), tracked_width_m that track's
    filtered width (NaN when not tracked, or its width is unknown);
    too_far: the area has fewer than `min_image_px_per_m` image pixels per metre across
    (`image_px_per_m`), too coarse for vision: neither checked for a guard rail nor searched
    for a vehicle. The patch is an array of its own (C-contiguous, writable), never a view of
    the image.
    """

    target_index: int
    target: RadarTarget
    base_px: tuple[float, float]
    full_px: tuple[float, float, float, float]
    box_px: tuple[int, int, int, int]
    y_left_m: float
    y_right_m: float
    patch: npt.NDArray[np.uint8]
    px_per_m: float
    moving: bool = False
    tracked: bool = False
    too_far: bool = False
    tracked_width_m: float = math.nan

    @property
    def x_m(self) -> float:
        """The target's distance ahead (vehicle frame)."""
        return self.target.x_m

    @property
    def image_px_per_m(self) -> float:
        """Image pixels per metre across at the target's distance, before resampling."""
        return (self.full_px[2] - self.full_px[0]) / (self.y_left_m - self.y_right_m)

    @property
    def cropped(self) -> bool:
        """True when part of the area lies outside the image."""
        return self.box_px != tuple(math.ceil(b) for b in self.full_px)

    def to_patch_px(self, u: float, v: float) -> tuple[float, float]:
        """Image coordinates (u, v) -> patch pixel-edge coordinates (col, row), the inverse
        of `to_image_px`."""
        c0, r0, c1, r1 = self.box_px
        h, w = self.patch.shape
        return (u - c0 + 0.5) * w / (c1 - c0), (v - r0 + 0.5) * h / (r1 - r0)

    def to_image_px(
        self, cols: npt.ArrayLike, rows: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """Patch pixel-edge coordinates (0 .. w, 0 .. h) -> image coordinates (u, v)."""
        c0, r0, c1, r1 = self.box_px
        h, w = self.patch.shape
        u = c0 - 0.5 + np.asarray(cols, dtype=np.float64) * (c1 - c0) / w
        v = r0 - 0.5 + np.asarray(rows, dtype=np.float64) * (r1 - r0) / h
        return u, v


Rect = tuple[float, float, float, float]


def rect_area(r: Rect) -> float:
    """Area of an image rectangle (left, top, right, bottom); 0 when empty."""
    return max(0.0, r[2] - r[0]) * max(0.0, r[3] - r[1])


def intersection_area(a: Rect, b: Rect) -> float:
    """Area two image rectangles (left, top, right, bottom) share."""
    return rect_area((max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3])))


def box_pixels(box_edges_px: Rect) -> tuple[int, int, int, int]:
    """(col0, row0, col1, row1) inclusive: the pixels holding the edges of a pixel-edge box
    (u0, v0, u1, v1), a pixel being inside up to half of it (pixel centres at integers)."""
    u0, v0, u1, v1 = box_edges_px
    c0, r0 = math.floor(u0 + 0.5), math.floor(v0 + 0.5)
    c1, r1 = math.ceil(u1 - 0.5), math.ceil(v1 - 0.5)
    return c0, r0, max(c0, c1), max(r0, r1)


def iou(a: Rect, b: Rect) -> float:
    """Intersection over union of two image rectangles (0 when both are empty)."""
    shared = intersection_area(a, b)
    union = rect_area(a) + rect_area(b) - shared
    return shared / union if union > 0 else 0.0


def overlap_fraction(a: SearchArea, b: SearchArea) -> float:
    """Share of area `b`'s cropped image rectangle that `a`'s covers (0 .. 1)."""
    return intersection_area(a.box_px, b.box_px) / max(1.0, rect_area(b.box_px))


def tracked_vehicle(
    target: RadarTarget,
    params: VehicleParams,
    tracked_m: Sequence[tuple[float, float, float]],
) -> tuple[float, float] | None:
    """(lateral position, width) of the tracked vehicle whose expected position (x_m, y_m)
    in `tracked_m` ((x_m, y_m, width_m) each) lies nearest the target, within
    `track_gate_m` (None: none does)."""
    nearest = min(
        ((math.hypot(target.x_m - x, target.y_m - y), y, w) for x, y, w in tracked_m),
        default=None,
    )
    return None if nearest is None or nearest[0] > params.track_gate_m else nearest[1:]


def moves(target: RadarTarget, ego_speed_mps: float, params: VehicleParams) -> bool:
    """The target moves over ground faster than `moving_speed_mps` (never with the ego
    speed unknown, NaN)."""
    return abs(real_speed_mps(target, ego_speed_mps)) > params.moving_speed_mps


def search_width_m(moving: bool, tracked: bool, params: VehicleParams) -> float:
    """The world width of a target's area (step 2): `moving_search_width_m` when it is
    `moving` (`moves`) or `tracked` (within `track_gate_m` of a tracked vehicle's expected
    position, `tracked_vehicle`), else `search_width_m`."""
    return params.moving_search_width_m if moving or tracked else params.search_width_m


def search_areas(
    image: npt.NDArray[np.uint8],
    camera: CameraModel,
    radar: tuple[RadarTarget, ...],
    params: VehicleParams,
    ego_speed_mps: float = math.nan,
    tracked_m: Sequence[tuple[float, float, float]] = (),
    centres_y_m: Sequence[float] | None = None,
) -> tuple[SearchArea, ...]:
    """The areas of the targets of `radar` whose base point lands inside `image`, in radar
    order.

    image: (H, W) uint8 grey, the full camera frame; camera: the frame's camera model (with
    the detected pitch); ego_speed_mps: the car's speed, which tells moving targets (NaN,
    unknown: every area is `search_width_m` wide, unless tracked); tracked_m: (x_m, y_m,
    width_m) where the tracker expects the vehicles it follows on this frame, and their
    widths (`moving_search_width_m`; with `centre_on_track`, their areas are centred on
    them); centres_y_m: the lateral centre of each other target's area
    (`core.radar_smoothing`; None: its radar point's y_m, the paper's). ValueError when
    centres_y_m is not one per target.
    """
    camera.check_image(image)
    if not radar:
        return ()
    h_img, w_img = image.shape
    if centres_y_m is None:
        centres_y_m = [t.y_m for t in radar]
    elif len(centres_y_m) != len(radar):
        raise ValueError(
            f"centres_y_m: expected one per radar target ({len(radar)}), got {len(centres_y_m)}"
        )
    tracks = [tracked_vehicle(t, params, tracked_m) for t in radar]
    on_track = [None if k is None else k[0] for k in tracks]
    track_widths_m = [math.nan if k is None else k[1] for k in tracks]
    if params.centre_on_track:
        centres_y_m = [c if y is None else y for c, y in zip(centres_y_m, on_track, strict=True)]
    moving = [moves(t, ego_speed_mps, params) for t in radar]
    widths_m = [
        search_width_m(m, y is not None, params) for m, y in zip(moving, on_track, strict=True)
    ]
    pts = np.array(
        [
            (t.x_m, y, 0.0)
            for t, w_m, c in zip(radar, widths_m, centres_y_m, strict=True)
            for y in (c, c + w_m / 2, c - w_m / 2)
        ]
    )
    uv, in_front = camera.project(pts)
    points = uv.reshape(len(radar), 3, 2).tolist()
    visible = np.all(in_front.reshape(len(radar), 3), axis=1).tolist()
    areas = []
    for i, t in enumerate(radar):
        (u, v), (u_left, _), (u_right, _) = points[i]
        if not (visible[i] and -0.5 <= u < w_img - 0.5 and -0.5 <= v < h_img - 0.5):
            continue
        width_px = u_right - u_left
        if not width_px > 0:
            continue
        # as high as the paper's area however wide: a wider area is for the radar's
        # lateral error, not for a taller vehicle
        height_px = params.search_height_ratio * width_px * params.search_width_m / widths_m[i]
        v1 = v + params.search_bottom_fraction * height_px
        full = (u_left, v1 - height_px, u_right, v1)
        cropped = _crop(image, full, params)
        if cropped is None:
            continue
        box, patch = cropped
        areas.append(
            SearchArea(
                target_index=i,
                target=t,
                base_px=(u, v),
                full_px=full,
                box_px=box,
                y_left_m=centres_y_m[i] + widths_m[i] / 2,
                y_right_m=centres_y_m[i] - widths_m[i] / 2,
                patch=patch,
                px_per_m=patch.shape[1] / (box[2] - box[0]) * width_px / widths_m[i],
                moving=moving[i],
                tracked=on_track[i] is not None,
                too_far=width_px / widths_m[i] < params.min_image_px_per_m,
                tracked_width_m=track_widths_m[i],
            )
        )
    return tuple(areas)


def _crop(
    image: npt.NDArray[np.uint8], full_px: Rect, params: VehicleParams
) -> tuple[tuple[int, int, int, int], npt.NDArray[np.uint8]] | None:
    """Steps 3-4 for an area of pixel-edge bounds full_px: its integer bounds cropped to the
    image and its patch resampled to at most `resampled_width_px` across (None when less
    than 2 pixels of it lie inside the image either way)."""
    h_img, w_img = image.shape
    c0, r0 = max(0, math.ceil(full_px[0])), max(0, math.ceil(full_px[1]))
    c1, r1 = min(w_img, math.ceil(full_px[2])), min(h_img, math.ceil(full_px[3]))
    if c1 - c0 < 2 or r1 - r0 < 2:
        return None
    scale = min(1.0, params.resampled_width_px / (full_px[2] - full_px[0]))
    size = (max(1, round((c1 - c0) * scale)), max(1, round((r1 - r0) * scale)))
    crop = image[r0:r1, c0:c1]
    # always a C-contiguous array of its own: the compiled searches then have one
    # signature, loaded once from numba's cache instead of twice
    patch: npt.NDArray[np.uint8] = (
        crop.copy()
        if scale == 1.0
        else np.asarray(cv2.resize(crop, size, interpolation=cv2.INTER_LINEAR))
    )
    return (c0, r0, c1, r1), patch


def taller(
    area: SearchArea, image: npt.NDArray[np.uint8], factor: float, params: VehicleParams
) -> SearchArea | None:
    """The same area `factor` times as high, its bottom and sides where they were (beyond
    the papers: `core.vehicle`, step 6, a tracked vehicle taller than the area); None when
    it has no pixel more than the area inside the image."""
    u0, v0, u1, v1 = area.full_px
    full = (u0, v1 - factor * (v1 - v0), u1, v1)
    cropped = _crop(image, full, params)
    if cropped is None or cropped[0] == area.box_px:
        return None
    box, patch = cropped
    return dataclasses.replace(area, full_px=full, box_px=box, patch=patch)
