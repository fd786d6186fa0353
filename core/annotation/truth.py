"""Annotations as the evaluation's ground truth: a `FrameTruth` for every frame marked
annotated, none for the others (the evaluation does not count them at all).

An annotator draws boxes; what the evaluation also reads of a truth object is estimated
with the drive's calibrated camera on a flat road, the papers' own assumption:

- position_m: the box's bottom-centre pixel on the road (z = 0); when a radar distance was
  snapped to the keyframe, the point of that pixel's ray whose x is that distance, at road
  level. A box whose bottom is at or above the horizon has no position (NaN) and is not a
  framed vehicle.
- size_m: width and height from the box's size in pixels at that depth in front of the
  camera (depth / fx and depth / fy metres per pixel, the camera looking ahead); length
  the class's typical length (TYPICAL_LENGTH_M).
- velocity_mps: unknown (NaN): motion stereo's scoring with the car standing still counts
  only moving objects, so it counts no annotated one then.
- occlusion: OCCLUDED_FRACTION when the occluded attribute is on, else 0; radar_seen: the
  attribute.
- pitch_rad: NaN, there is no true pitch; the evaluation scores no pitch on such frames.
- a guard_rail box becomes a guard rail whose polyline is the box's diagonal from its near
  corner at the bottom (the corner on the image's outer side) to its far corner at the top;
  other_obstacle becomes class "other". Interpolated boxes count like drawn ones.
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt

from core.annotation.model import Annotations, Box, Shown
from core.annotation.store import EXACT_TRUTH_VERSION, GROUNDTRUTH_NAME, read_annotations
from core.camera import CameraModel
from core.io.errors import RecordingError
from core.io.groundtruth import FrameTruth, TruthGuardRail, TruthObject, read_groundtruth

# typical lengths of the classes (m), for the footprint behind a box's near face
TYPICAL_LENGTH_M = {
    "car": 4.5,
    "van": 5.0,
    "truck": 10.0,
    "pedestrian": 0.5,
    "cyclist": 1.8,
    "other_obstacle": 1.0,
}
OCCLUDED_FRACTION = 0.5  # an occluded object: hidden as much as the evaluation's cut-off
TRUTH_CLASS = {"other_obstacle": "other"}  # annotation class -> core.io.groundtruth class


def _position_m(camera: CameraModel, box: Box, distance_m: float | None) -> np.ndarray:
    """(3,) vehicle-frame point under the box's bottom centre (module docstring)."""
    u0, _, u1, v1 = box
    pixel = np.array([[(u0 + u1) / 2, v1]])
    if distance_m is None:
        return camera.ground_point(pixel)[0]
    ray = camera.rays_vehicle(pixel)[0]
    origin = camera.position_vehicle_m
    if ray[0] <= 0:
        return np.full(3, np.nan)
    point = origin + (distance_m - origin[0]) / ray[0] * ray
    return np.array([point[0], point[1], 0.0])


def truth_object(camera: CameraModel, shown: Shown) -> TruthObject:
    """One annotated box as a truth object (module docstring); not for guard rails."""
    x, y, _ = _position_m(camera, shown.box_px, shown.distance_m)
    u0, v0, u1, v1 = shown.box_px
    i = camera.intrinsics
    depth_m = x - camera.position_vehicle_m[0]
    ok = math.isfinite(depth_m) and depth_m > 0
    width_m = (u1 - u0) * depth_m / i.fx_px if ok else math.nan
    height_m = (v1 - v0) * depth_m / i.fy_px if ok else math.nan
    return TruthObject(
        id=shown.track_id,
        cls=TRUTH_CLASS.get(shown.cls, shown.cls),
        box_px=shown.box_px,
        position_m=(float(x), float(y), 0.0),
        size_m=(TYPICAL_LENGTH_M[shown.cls], float(width_m), float(height_m)),
        velocity_mps=(math.nan, math.nan),
        radar_seen=shown.attributes["radar_seen"],
        occlusion=OCCLUDED_FRACTION if shown.attributes["occluded"] else 0.0,
    )


def guard_rail(camera: CameraModel, shown: Shown) -> TruthGuardRail:
    """A guard_rail box as a truth rail along its diagonal (module docstring)."""
    u0, v0, u1, v1 = shown.box_px
    right = (u0 + u1) / 2 >= camera.intrinsics.cx_px
    near, far = ((u1, v1), (u0, v0)) if right else ((u0, v1), (u1, v0))
    return TruthGuardRail(shown.track_id, "right" if right else "left", (near, far))


def frame_truths(
    annotations: Annotations, camera: CameraModel, times_ns: Sequence[int] | npt.NDArray[np.int64]
) -> dict[int, FrameTruth]:
    """The FrameTruth of every annotated frame of a drive with these frame times (ns),
    by frame index; frames marked annotated beyond the drive are left out."""
    out = {}
    for first, last in annotations.annotated:
        for index in range(first, min(last, len(times_ns) - 1) + 1):
            shown = annotations.shown_at(index)
            out[index] = FrameTruth(
                index=index,
                t_ns=int(times_ns[index]),
                pitch_rad=math.nan,
                objects=tuple(truth_object(camera, s) for s in shown if s.cls != "guard_rail"),
                guard_rails=tuple(guard_rail(camera, s) for s in shown if s.cls == "guard_rail"),
            )
    return out


def recording_truth(
    folder: Path,
    named: Path | None,
    camera: CameraModel,
    times_ns: Sequence[int] | npt.NDArray[np.int64],
) -> tuple[dict[int, FrameTruth], str | None]:
    """A recording's ground truth by frame index, and why there is none when its file could
    not be used (None when it could, or there is none).

    named: the file the manifest names (the generator's exact truth, format_version 1;
    RecordingError when it is bad, as `core.io.groundtruth.read_groundtruth`); without one,
    the annotations in `folder`/groundtruth.json when present (format_version 2, read
    without the journal, which the store empties after each saved edit). A file that
    cannot be used is not, and the reason is returned: annotations that cannot be read
    (the recording still opens, and the annotation store says the same when it opens them
    read-only), or a generated truth the manifest does not name (copied from another
    drive, its frames would not be this drive's).
    """
    if named is not None:
        return {f.index: f for f in read_groundtruth(named)}, None
    path = folder / GROUNDTRUTH_NAME
    if not path.exists():
        return {}, None
    if _format_version(path) == EXACT_TRUTH_VERSION:
        return {}, (
            f"ground truth not used: {path} holds a generated drive's exact truth "
            "(format_version 1), which only a recording.yaml naming it says is this drive's"
        )
    try:
        annotations, _ = read_annotations(path)
    except RecordingError as err:
        return {}, f"ground truth not used: {err}"
    return frame_truths(annotations, camera, times_ns), None


def _format_version(path: Path) -> object:
    """The file's format_version (None when it is not a JSON object with one)."""
    try:
        data = json.loads(path.read_bytes())
    except (OSError, ValueError):
        return None
    return data.get("format_version") if isinstance(data, dict) else None
