"""`fusionscope import aimotive`: one sequence of the aiMotive Multimodal Dataset as a recording.

    fusionscope import aimotive ../shared/realdata/aimotive-night-motorway aimotive-night

A sequence folder holds `sensor/camera/CAM/CAM_<id>.jpg`, `sensor/radar/RADAR/RADAR_<id>.json`
(detection lists), `sensor/calibration/calibration.json` and `dynamic/box/3d_body/
frame_<id>.json` (3D boxes with the keyframe's time stamp); one frame id is one
synchronised keyframe.

- vehicle frame: the data set's body frame (x forward, y left, z up) lowered to the road:
  the road's height in the body frame is the median bottom of the labelled boxes 0-60 m
  ahead (-0.14 m on the night motorway; 0 when no box is there, with a note).
- camera: undistorted at import (cv2.undistort, same K), then grey and resized to
  `width_px`; pose from `RT_body_from_sensor` (OpenCV optical frame -> body).
- radar: range, azimuth and radial speed of each detection, elevation ignored (Notes),
  from the radar's mount (`RT_body_from_sensor`: position and yaw).
- speed: from the radar itself (core.radar_ego; the sample has no ego-motion file); yaw
  rate 0, written as CAN frames like a recorded car's.
- ground truth on every frame with a label file: ObjectType by AIMOTIVE_CLASSES (others
  left out and counted), the 3D box through core.io.importers.truth3d, velocity over ground
  = the label's relative velocity + the ego speed, hidden OCCLUDED_FRACTION when
  `Occluded` is set (truncation is measured from the projection), track id `ObjectId`. No
  true pitch, no guard-rail polylines: the labels have neither.

Time stamps: the labels' `Timestamp` (ns) less the first frame's; frames without a label
file are placed by their id on the line through the labelled ones.

Notes:
    Undistort, or carry the distortion in the camera model? The stages work on a pinhole
    image: motion stereo warps by road-plane homographies, the vehicle and pedestrian
    detectors look for vertical symmetry, the guard-rail filter for straight lines
    (core/camera.py: homographies take undistorted pixels). With k1 = -0.30 the front
    camera bends a vertical edge at u = 1100 of 1280 by 10 px over 400 rows and moves the
    image's side edges by 56 px (78 px in the corners), so it is undistorted at import;
    the recording's camera is the undistorted pinhole, and the 3D boxes project onto it.
    The radar's elevation is ignored. On the night motorway's radar-seen vehicles (119,
    193 points on them; tests/core/io/importers/test_aimotive.py measures it): turned into
    the body frame by the radar's full mount rotation (it looks 0.85 deg down), the points
    lie a median 0.95 m below the box bottoms and project a median 16 px below them
    (10-90 %: -1 to 36 px, in the camera's 1280 px), inside the box for 18 vehicles;
    taken as the mount's height + range * sin(elevation), they lie a median 0.21 m below
    the bottoms, scattered -15 to +22 px about the bottom edge, inside for 64. Range and
    azimuth on a flat road, drawn 0.5 m up, put a point inside the box for 115 of 119.
"""

from __future__ import annotations

import json
import math
import re
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel, Intrinsics
from core.io.calibration import Calibration, RadarMount
from core.io.errors import RecordingError
from core.io.frame import RadarTarget
from core.io.groundtruth import FrameTruth, TruthObject
from core.io.importers.calibration_spec import scale_intrinsics
from core.io.importers.finish import (
    DEFAULT_WIDTH_PX,
    ImportOptions,
    ImportResult,
    Progress,
    check_out_dir,
    output_size,
    read_grey,
    result,
    staging,
    to_grey,
)
from core.io.importers.pose import camera_extrinsics, quaternion_matrix, yaw_rad
from core.io.importers.truth3d import Box3D, truth_object
from core.io.manifest import load_manifest
from core.io.writer import RecordingWriter
from core.radar_ego import speeds_from_scans

FloatArray = npt.NDArray[np.float64]

DEFAULT_CAMERA = "F_MIDLONGRANGECAM_CL"
DEFAULT_RADAR = "F_LRR_C"
AIMOTIVE_CLASSES = {
    "CAR": "car",
    "VAN": "van",
    "TRUCK": "truck",
    "BUS": "truck",
    "PEDESTRIAN": "pedestrian",
}
OCCLUDED_FRACTION = 0.5  # hidden fraction of an object labelled Occluded (the evaluation's cut)
GROUND_FROM_BOXES_M = (0.0, 60.0)  # boxes this far ahead give the road's height
BOX = "BoundingBox3D "
_ID = re.compile(r"_(\d+)\.(jpg|json)$")


def _json(path: Path, what: str) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError as err:
        raise RecordingError(f"{path}: {what} not found") from err
    except OSError as err:
        raise RecordingError(f"{path}: cannot read {what}: {err.strerror}") from err
    except ValueError as err:
        raise RecordingError(f"{path}: {what} is not valid JSON: {err}") from err


def _matrix(sensor: Mapping[str, Any], where: str) -> FloatArray:
    M = np.asarray(sensor.get("RT_body_from_sensor"), dtype=np.float64)
    if M.shape != (4, 4) or not np.all(np.isfinite(M)):
        raise RecordingError(f"{where}: RT_body_from_sensor: expected a finite 4x4 matrix")
    return M


def _sensor(calibration: Mapping[str, Any], name: str, path: Path) -> Mapping[str, Any]:
    if name not in calibration or not isinstance(calibration[name], dict):
        raise RecordingError(
            f"{path}: no sensor {name!r}; the sensors there: {', '.join(sorted(calibration))}"
        )
    return calibration[name]


def _intrinsics(cam: Mapping[str, Any], where: str) -> tuple[Intrinsics, FloatArray]:
    """The camera's pinhole intrinsics at its own size, and its distortion (k1 k2 p1 p2 k3)."""
    try:
        fx, fy = (float(v) for v in cam["focal_length_px"])
        cx, cy = (float(v) for v in cam["principal_point_px"])
        w, h = (int(v) for v in cam["image_resolution_px"])
        dist = np.asarray(cam.get("distortion_coeffs") or [], dtype=np.float64)
        return Intrinsics(fx, fy, cx, cy, w, h), dist
    except (KeyError, TypeError, ValueError) as err:
        raise RecordingError(f"{where}: camera intrinsics: {err}") from err


@dataclass(frozen=True)
class _Frame:
    frame_id: int
    image: Path
    labels: Path | None  # None: no label file
    radar: Path | None


def _frames(sequence: Path, camera: str, radar: str) -> list[_Frame]:
    folder = sequence / "sensor" / "camera" / camera
    images = sorted(folder.glob(f"{camera}_*.jpg")) if folder.is_dir() else []
    if not images:
        raise RecordingError(f"{folder}: no {camera}_<id>.jpg images")
    out = []
    for image in images:
        m = _ID.search(image.name)
        if m is None:
            continue
        fid = m.group(1)
        labels = sequence / "dynamic" / "box" / "3d_body" / f"frame_{fid}.json"
        scan = sequence / "sensor" / "radar" / radar / f"{radar}_{fid}.json"
        out.append(
            _Frame(
                int(fid),
                image,
                labels if labels.is_file() else None,
                scan if scan.is_file() else None,
            )
        )
    return out


def _objects(path: Path, data: Any) -> list[dict[str, Any]]:
    objects = data.get("CapturedObjects") if isinstance(data, dict) else None
    if not isinstance(objects, list):
        raise RecordingError(f"{path}: expected an object with a CapturedObjects list")
    return [o for o in objects if isinstance(o, dict)]


def _box(o: Mapping[str, Any], ground_z_m: float, ego_speed_mps: float) -> Box3D:
    """One label as a box in the vehicle frame; KeyError/TypeError/ValueError on bad fields."""
    centre = [float(o[f"{BOX}Origin {a}"]) for a in "XYZ"]
    size = tuple(float(o[f"{BOX}Extent {a}"]) for a in "XYZ")
    R = quaternion_matrix([float(o[f"{BOX}Orientation Quat {a}"]) for a in "WXYZ"])
    vx, vy = float(o["Relative Velocity X"]), float(o["Relative Velocity Y"])
    return Box3D(
        id=int(o["ObjectId"]),
        cls=AIMOTIVE_CLASSES[str(o["ObjectType"])],
        centre_m=(centre[0], centre[1], centre[2] - ground_z_m),
        size_m=(size[0], size[1], size[2]),
        yaw_rad=yaw_rad(R),
        velocity_mps=(vx + ego_speed_mps, vy),
        hidden=OCCLUDED_FRACTION if o.get("Occluded") else 0.0,
    )


def _ground_z_m(labels: Mapping[int, list[dict[str, Any]]]) -> float | None:
    """The road's height in the body frame: the median box bottom 0-60 m ahead."""
    lo, hi = GROUND_FROM_BOXES_M
    bottoms = []
    for objects in labels.values():
        for o in objects:
            try:
                x = float(o[f"{BOX}Origin X"])
                bottom = float(o[f"{BOX}Origin Z"]) - float(o[f"{BOX}Extent Z"]) / 2
            except (KeyError, TypeError, ValueError):
                continue
            if lo < x <= hi and math.isfinite(bottom):
                bottoms.append(bottom)
    return float(np.median(bottoms)) if bottoms else None


def _scan(path: Path | None) -> list[tuple[float, float, float, float]]:
    """(range m, azimuth rad, range rate m/s, rcs) of each finite detection."""
    if path is None:
        return []
    data = _json(path, "radar detection list")
    targets = data.get("targets") if isinstance(data, dict) else None
    if not isinstance(targets, list):
        raise RecordingError(f"{path}: expected an object with a targets list")
    out = []
    for t in targets:
        try:
            values = (float(t["range"]), float(t["azimuth"]), float(t["speed"]), float(t["rcs"]))
        except (KeyError, TypeError, ValueError) as err:
            raise RecordingError(
                f"{path}: a target without range/azimuth/speed/rcs: {err}"
            ) from err
        if all(math.isfinite(v) for v in values) and values[0] > 0:
            out.append(values)
    return out


def import_aimotive(
    sequence: Path,
    out_dir: Path,
    camera: str = DEFAULT_CAMERA,
    radar: str = DEFAULT_RADAR,
    width_px: int = DEFAULT_WIDTH_PX,
    options: ImportOptions = ImportOptions(),
    progress: Progress | None = None,
) -> ImportResult:
    """Write the aiMotive sequence folder `sequence` into `out_dir` (new or empty); see the
    module docstring. RecordingError or ValueError naming the file or option on bad input."""
    check_out_dir(out_dir)
    if width_px < 1:
        raise ValueError(f"--width: expected a width >= 1 px, got {width_px}")
    cal_path = sequence / "sensor" / "calibration" / "calibration.json"
    cal = _json(cal_path, "calibration")
    if not isinstance(cal, dict):
        raise RecordingError(f"{cal_path}: expected an object of sensors")
    cam, rad = _sensor(cal, camera, cal_path), _sensor(cal, radar, cal_path)
    K_source, dist = _intrinsics(cam, f"{cal_path}: {camera}")
    frames = _frames(sequence, camera, radar)
    notes: list[str] = []

    # --- labels and the clock -------------------------------------------------------------
    labels: dict[int, list[dict[str, Any]]] = {}
    stamps: dict[int, int] = {}
    for f in frames:
        if f.labels is None:
            continue
        data = _json(f.labels, "label file")
        try:
            stamps[f.frame_id] = int(data["Timestamp"])
        except (KeyError, TypeError, ValueError) as err:
            raise RecordingError(f"{f.labels}: expected an integer Timestamp (ns)") from err
        labels[f.frame_id] = _objects(f.labels, data)
    if not stamps:
        raise RecordingError(
            f"{sequence / 'dynamic' / 'box' / '3d_body'}: no frame_<id>.json: their Timestamp is "
            "the sequence's only clock"
        )
    ids = np.array(sorted(stamps), dtype=np.float64)
    if len(ids) >= 2:
        slope, offset = np.polyfit(ids, [stamps[int(i)] for i in ids], 1)
    else:
        slope, offset = 1e9 / 15, stamps[int(ids[0])] - 1e9 / 15 * ids[0]
    times = {f.frame_id: stamps.get(f.frame_id, round(slope * f.frame_id + offset)) for f in frames}
    t0 = min(times.values())
    unlabelled = sum(f.labels is None for f in frames)
    if unlabelled:
        notes.append(f"{unlabelled} of {len(frames)} frames have no label file: no truth there")
    ground = _ground_z_m(labels)
    if ground is None:
        notes.append("no labelled box 0-60 m ahead: the road taken at the body frame's z = 0")
        ground = 0.0

    # --- calibration ---------------------------------------------------------------------
    M_cam, M_rad = _matrix(cam, f"{cal_path}: {camera}"), _matrix(rad, f"{cal_path}: {radar}")
    position = M_cam[:3, 3] - (0.0, 0.0, ground)
    source_size = (K_source.width_px, K_source.height_px)
    read_grey(frames[0].image, source_size, f"{camera}'s size in {cal_path}")
    size = output_size(width_px, source_size)
    model = CameraModel(
        scale_intrinsics(K_source, *size), camera_extrinsics(M_cam[:3, :3], position)
    )
    mount = RadarMount(
        float(M_rad[0, 3]), float(M_rad[1, 3]), float(M_rad[2, 3] - ground), yaw_rad(M_rad[:3, :3])
    )
    calibration = Calibration(model, mount)

    # --- radar and the speed from it ------------------------------------------------------
    scans = [_scan(f.radar) for f in frames]
    no_radar = sum(f.radar is None for f in frames)
    if no_radar:
        notes.append(f"{no_radar} of {len(frames)} frames have no {radar} file: no radar there")
    counts = np.array([0] + [len(s) for s in scans], dtype=np.int64)
    rows = [t for s in scans for t in s]
    speeds = speeds_from_scans(
        [r[2] for r in rows],
        [r[1] for r in rows],
        np.cumsum(counts),
        mount.yaw_rad,
        range_m=[r[0] for r in rows],
    )
    fitted = np.isfinite(speeds)
    if not fitted.any():
        raise RecordingError(
            f"{sequence / 'sensor' / 'radar' / radar}: no scan has enough stationary returns "
            "to give the ego speed (core.radar_ego), and the sequence has no other"
        )
    notes.append(
        f"speed from the radar's stationary returns on {int(fitted.sum())} of {len(frames)} "
        f"frames ({float(np.nanmin(speeds)):.1f}-{float(np.nanmax(speeds)):.1f} m/s); yaw "
        "rate not recorded: 0"
    )

    # --- write ---------------------------------------------------------------------------
    K = K_source.K
    description = (
        f"aiMotive Multimodal Dataset sequence {sequence.name} (CC BY-NC-SA 4.0, "
        f"non-commercial; not to be copied into another repository): {camera} undistorted, "
        f"grey, resized to {size[0]}x{size[1]}; radar {radar} detections (elevation ignored); "
        "speed estimated from the radar's stationary returns, yaw rate 0; ground truth from "
        "the 3D boxes."
    )
    skipped: Counter[str] = Counter()
    bad: list[str] = []
    truths: list[FrameTruth] = []
    with staging(out_dir) as tmp:
        with RecordingWriter(
            tmp,
            name=options.name or f"aimotive-{sequence.name}",
            calibration=calibration,
            description=description,
            generator={
                "importer": "aimotive",
                "sequence": sequence.name,
                "camera": camera,
                "radar": radar,
                "clock_origin_ns": t0,
            },
        ) as w:
            for k, f in enumerate(frames):
                t_ns = times[f.frame_id] - t0
                grey = read_grey(f.image, source_size, f"{camera}'s size in {cal_path}")
                w.add_image(t_ns, to_grey(cv2.undistort(grey, K, dist), size))
                targets = tuple(
                    RadarTarget.from_polar(r, a, rr, rcs, mount.x_m, mount.y_m, mount.yaw_rad)
                    for r, a, rr, rcs in scans[k]
                )
                w.add_radar_scan(t_ns, targets)
                if np.isfinite(speeds[k]):
                    w.add_vehicle_state(t_ns, float(speeds[k]), 0.0)
                if f.frame_id in labels:
                    xy = np.array([[t.x_m, t.y_m] for t in targets]).reshape(-1, 2)
                    objects: list[TruthObject] = []
                    for o in labels[f.frame_id]:
                        if str(o.get("ObjectType")) not in AIMOTIVE_CLASSES:
                            skipped[str(o.get("ObjectType"))] += 1
                            continue
                        try:
                            box = _box(o, ground, float(np.nan_to_num(speeds[k])))
                        except (KeyError, TypeError, ValueError) as err:
                            bad.append(f"{f.labels}: object {o.get('ObjectId')}: {err}")
                            continue
                        seen = truth_object(model, box, xy)
                        if seen is not None:
                            objects.append(seen)
                    truths.append(
                        FrameTruth(k, t_ns, math.nan, tuple(objects), (), rails_labelled=False)
                    )
                if progress is not None:
                    progress(k + 1, len(frames))
            w.set_groundtruth(truths)
    if skipped:
        counts_text = ", ".join(f"{n} {c}" for c, n in sorted(skipped.items()))
        notes.append(f"labels of types the evaluation does not score, left out: {counts_text}")
    if bad:
        notes.append(f"{len(bad)} labels that cannot be used, left out: " + "; ".join(bad[:3]))
    notes.append(
        f"ground truth on {len(truths)} of {len(frames)} frames (no true pitch, no guard-rail "
        "polylines: the labels have neither)"
    )
    frame_t_ns = [times[f.frame_id] - t0 for f in frames]
    return result(out_dir, frame_t_ns, size, calibration, load_manifest(out_dir), notes)
