"""`fusionscope import nuscenes`: one scene of a nuScenes version folder as a recording.

    fusionscope import nuscenes ../shared/realdata/nuscenes-mini-scene-0523 nuscenes-0523 \\
        --scene scene-0523

Reads DATAROOT/VERSION/*.json (scene, sample, sample_data, ego_pose, calibrated_sensor,
sensor, sample_annotation, instance, category) and the files `sample_data` names, from a
full install as from a cut-down folder: rows of `sample_data` whose file is absent (sweeps,
other sensors) are skipped and counted. With the camera's sweeps present the recording
runs at its 12 Hz, without them at the keyframes' 2 Hz.

- camera: the named camera's images, grey, resized to `width_px`; intrinsics from its
  `calibrated_sensor` (scaled), pose (height, x, y, pitch, yaw, roll) from its rotation and
  translation (nuScenes' ego frame: x forward, y left, z up, on the road under the rear
  axle, the recording's vehicle frame).
- radar: per camera frame, each named radar's sweep nearest in time (within
  MAX_RADAR_GAP_MS), its points kept by nuScenes' default filter (RADAR_FILTER) and brought
  to the camera's time with both ego poses (radar -> ego at the radar's time -> global,
  moved on by its ego-compensated velocity over the time between, -> ego at the camera's
  time); range rate is the radial part of its velocity relative to the ego car. They are
  written as one scan at the camera's time, seen from a virtual radar at the first named
  radar's position, looking ahead.
- speed and yaw rate: from the ego poses (every `ego_pose` row in the scene's span),
  central differences over +-EGO_HALF_WINDOW_S, every EGO_STEP_S, as CAN frames.
- ground truth: on keyframes only (frames between count neither way), each annotation
  whose 3D box is in the image (core.io.importers.truth3d); classes by NUSCENES_CLASSES,
  the others left out and counted; hidden fraction from the visibility level; velocity
  from the annotation's neighbours (as nuscenes-devkit's box_velocity); track id from the
  instance. No true pitch and no guard-rail polylines: nuScenes has neither.

Time stamps: nuScenes' microseconds, less the first camera frame's (the recording clock
starts at 0; the offset is in the manifest's generator section).

Libraries: nuscenes-devkit is not used: its `NuScenes` needs the log, map, attribute and
visibility tables, which a cut-down folder lacks, and it depends on opencv-python, whose
`cv2` would replace the build this project uses (opencv-contrib-python-headless). The
tables are plain JSON, read here. PCD files are read with pypcd4 (BSD-3, maintained,
numpy only besides pydantic and lzf): it reads every PCD encoding (ascii, binary,
binary_compressed) with named fields; its errors are wrapped in RecordingError.

Notes:
    nuScenes' default radar filter (nuscenes-devkit RadarPointCloud.default_filters)
    keeps invalid_state 0, dyn_prop 0-6 (`range(7)`: 7, "stopped", is not kept) and
    ambig_state 3.
"""

from __future__ import annotations

import json
import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

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

FloatArray = npt.NDArray[np.float64]

DEFAULT_VERSION = "v1.0-mini"
DEFAULT_CAMERA = "CAM_FRONT"
DEFAULT_RADARS = ("RADAR_FRONT", "RADAR_FRONT_LEFT", "RADAR_FRONT_RIGHT")
TABLES = (
    "scene",
    "sample",
    "sample_data",
    "ego_pose",
    "calibrated_sensor",
    "sensor",
    "sample_annotation",
    "instance",
    "category",
)
MAX_RADAR_GAP_MS = 100.0  # over the radars' 13 Hz period: a keyframe's own sweep is up to 75 ms off
EGO_HALF_WINDOW_S = 0.1  # speed and yaw rate: central differences over +- this
EGO_STEP_S = 0.02  # and written every this
US_PER_NS = 1e-3
NS_PER_US = 1000
# nuScenes' default radar filter (module Notes)
RADAR_FILTER = {"invalid_state": (0,), "dyn_prop": tuple(range(7)), "ambig_state": (3,)}
# category name prefix -> the evaluation's class; categories matching none are left out
NUSCENES_CLASSES = (
    ("vehicle.car", "car"),
    ("vehicle.emergency", "car"),
    ("vehicle.truck", "truck"),
    ("vehicle.bus", "truck"),
    ("vehicle.trailer", "truck"),
    ("vehicle.construction", "truck"),
    ("human.pedestrian", "pedestrian"),
)
# visibility_token -> hidden fraction: the middle of its band (1: 0-40 % visible, 2: 40-60 %,
# 3: 60-80 %, 4: 80-100 %)
HIDDEN_BY_VISIBILITY = {"1": 0.8, "2": 0.5, "3": 0.3, "4": 0.1}


def _table(folder: Path, name: str) -> list[dict[str, Any]]:
    path = folder / f"{name}.json"
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError as err:
        raise RecordingError(
            f"{path}: table not found; a nuScenes version folder needs {', '.join(TABLES)}"
        ) from err
    except OSError as err:
        raise RecordingError(f"{path}: cannot read the table: {err.strerror}") from err
    except ValueError as err:
        raise RecordingError(f"{path}: not valid JSON: {err}") from err
    if not isinstance(data, list) or not all(isinstance(r, dict) for r in data):
        raise RecordingError(f"{path}: expected a JSON list of records, got {type(data).__name__}")
    return data


class _Tables:
    """The tables of a version folder, with look-ups by token built once."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.rows = {name: _table(folder, name) for name in TABLES}
        self._by_token: dict[str, dict[str, dict[str, Any]]] = {}
        self.annotations_of: dict[str, list[dict[str, Any]]] = {}
        for a in self.rows["sample_annotation"]:
            self.annotations_of.setdefault(str(a.get("sample_token")), []).append(a)

    def by_token(self, name: str) -> dict[str, dict[str, Any]]:
        if name not in self._by_token:
            where = self.folder / f"{name}.json"
            try:
                self._by_token[name] = {r["token"]: r for r in self.rows[name]}
            except KeyError as err:
                raise RecordingError(f"{where}: a record without a token") from err
        return self._by_token[name]


def _field(row: Mapping[str, Any], key: str, where: str) -> Any:
    if key not in row:
        raise RecordingError(f"{where}: missing field {key!r}")
    return row[key]


def read_pcd_radar(path: Path) -> npt.NDArray[Any]:
    """(N,) structured array of a radar PCD's fields (x, y, z, vx, vy, vx_comp, vy_comp, rcs,
    dyn_prop, ambig_state, invalid_state), all points; RecordingError naming the file."""
    from pypcd4 import PointCloud  # pydantic at import: only when a PCD is read

    wanted = ("x", "y", "z", "vx", "vy", "vx_comp", "vy_comp", "rcs")
    states = ("dyn_prop", "ambig_state", "invalid_state")
    try:
        cloud = PointCloud.from_path(path)
        fields = cloud.fields
        missing = [f for f in (*wanted, *states) if f not in fields]
        if missing:
            raise RecordingError(
                f"{path}: expected a nuScenes radar PCD with fields {', '.join(wanted + states)}; "
                f"missing {', '.join(missing)}"
            )
        values = cloud.numpy((*wanted, *states))
    except RecordingError:
        raise
    except FileNotFoundError as err:
        raise RecordingError(f"{path}: radar file not found") from err
    except Exception as err:  # pypcd4 raises pydantic, Value, Runtime, Unicode, Index errors
        raise RecordingError(f"{path}: damaged PCD file: {err}") from err
    dtype = [(f, np.float64) for f in (*wanted, *states)]
    out = np.empty(len(values), dtype=dtype)
    for k, f in enumerate((*wanted, *states)):
        out[f] = values[:, k]
    return out


def radar_filter(points: npt.NDArray[Any]) -> npt.NDArray[np.bool_]:
    """(N,) nuScenes' default filter (RADAR_FILTER), and finite positions and velocities."""
    keep = np.ones(len(points), dtype=bool)
    for name, allowed in RADAR_FILTER.items():
        keep &= np.isin(points[name], allowed)
    for name in ("x", "y", "vx", "vy", "vx_comp", "vy_comp"):
        keep &= np.isfinite(points[name])
    return keep


@dataclass(frozen=True)
class _Pose:
    """A rigid pose: R (3, 3), t (3,) mapping its frame's points into the parent frame."""

    R: FloatArray
    t: FloatArray

    @classmethod
    def of(cls, row: Mapping[str, Any], where: str) -> _Pose:
        try:
            R = quaternion_matrix(_field(row, "rotation", where))
            t = np.asarray(_field(row, "translation", where), dtype=np.float64)
        except ValueError as err:
            raise RecordingError(f"{where}: {err}") from err
        if t.shape != (3,) or not np.all(np.isfinite(t)):
            raise RecordingError(f"{where}: translation: expected 3 finite numbers, got {t}")
        return cls(R, t)

    def apply(self, p: FloatArray) -> FloatArray:
        out: FloatArray = p @ self.R.T + self.t
        return out

    def inverse_apply(self, p: FloatArray) -> FloatArray:
        out: FloatArray = (p - self.t) @ self.R
        return out


@dataclass(frozen=True)
class _Row:
    """A sample_data row with its file present."""

    token: str
    t_us: int
    path: Path
    sample_token: str
    is_key_frame: bool
    ego: _Pose
    sensor: _Pose
    calibrated_token: str


@dataclass
class _Skipped:
    """Counts of what was not used, for the notes."""

    missing_files: Counter[str] = field(default_factory=Counter)
    classes: Counter[str] = field(default_factory=Counter)
    bad_annotations: list[str] = field(default_factory=list)
    radar_frames_without: Counter[str] = field(default_factory=Counter)


def _scene(t: _Tables, name: str) -> dict[str, Any]:
    scenes = t.rows["scene"]
    for s in scenes:
        if s.get("name") == name:
            return s
    names = ", ".join(sorted(str(s.get("name")) for s in scenes)) or "none"
    raise RecordingError(f"{t.folder / 'scene.json'}: no scene {name!r}; the scenes there: {names}")


def _channel_rows(
    t: _Tables, dataroot: Path, sample_tokens: set[str], channels: Sequence[str], skipped: _Skipped
) -> dict[str, list[_Row]]:
    """The scene's sample_data rows of each channel whose file exists, by time."""
    sensors = {s["token"]: s.get("channel") for s in t.rows["sensor"]}
    calibrated = t.by_token("calibrated_sensor")
    poses = t.by_token("ego_pose")
    present = set(sensors.values())
    for c in channels:
        if c not in present:
            raise RecordingError(
                f"{t.folder / 'sensor.json'}: no sensor {c!r}; the sensors there: "
                f"{', '.join(sorted(str(s) for s in present))}"
            )
    out: dict[str, list[_Row]] = {c: [] for c in channels}
    where = t.folder / "sample_data.json"
    for r in t.rows["sample_data"]:
        if r.get("sample_token") not in sample_tokens:
            continue
        cal = calibrated.get(r.get("calibrated_sensor_token", ""))
        if cal is None:
            raise RecordingError(
                f"{where}: row {r.get('token')}: its calibrated_sensor_token is not in "
                "calibrated_sensor.json"
            )
        channel = sensors.get(cal.get("sensor_token"))
        if channel not in out:
            continue
        path = dataroot / str(_field(r, "filename", f"{where}: row {r.get('token')}"))
        if not path.is_file():
            skipped.missing_files[str(channel)] += 1
            continue
        pose = poses.get(r.get("ego_pose_token", ""))
        if pose is None:
            raise RecordingError(f"{where}: row {r['token']}: its ego pose is not in ego_pose.json")
        out[str(channel)].append(
            _Row(
                token=r["token"],
                t_us=int(r["timestamp"]),
                path=path,
                sample_token=r["sample_token"],
                is_key_frame=bool(r.get("is_key_frame")),
                ego=_Pose.of(pose, f"{t.folder / 'ego_pose.json'}: {pose['token']}"),
                sensor=_Pose.of(cal, f"{t.folder / 'calibrated_sensor.json'}: {cal['token']}"),
                calibrated_token=cal["token"],
            )
        )
    for rows in out.values():
        rows.sort(key=lambda row: row.t_us)
    return out


def ego_signals(
    t_us: npt.ArrayLike, xy_m: npt.ArrayLike, heading_rad: npt.ArrayLike
) -> tuple[npt.NDArray[np.int64], FloatArray, FloatArray]:
    """(times (us), speed (m/s, forward), yaw rate (rad/s, left positive)) every EGO_STEP_S
    from poses at (N,) times (us, any order, duplicates allowed), (N, 2) positions and (N,)
    headings: central differences over +-EGO_HALF_WINDOW_S of the poses interpolated."""
    t = np.asarray(t_us, dtype=np.float64) * 1e-6
    order = np.argsort(t, kind="stable")
    t, keep = np.unique(t[order], return_index=True)
    xy = np.asarray(xy_m, dtype=np.float64)[order][keep]
    heading = np.unwrap(np.asarray(heading_rad, dtype=np.float64)[order][keep])
    if len(t) < 2:
        raise RecordingError("ego_pose.json: expected at least two poses in the scene's span")
    grid = np.arange(t[0], t[-1] + 1e-9, EGO_STEP_S)
    lo = np.clip(grid - EGO_HALF_WINDOW_S, t[0], t[-1])
    hi = np.clip(grid + EGO_HALF_WINDOW_S, t[0], t[-1])
    dt = np.maximum(hi - lo, 1e-6)

    def at(s: FloatArray, values: FloatArray) -> FloatArray:
        return np.asarray(np.interp(s, t, values), dtype=np.float64)

    dx = (at(hi, xy[:, 0]) - at(lo, xy[:, 0])) / dt
    dy = (at(hi, xy[:, 1]) - at(lo, xy[:, 1])) / dt
    h = at(grid, heading)
    speed = dx * np.cos(h) + dy * np.sin(h)
    yaw_rate = (at(hi, heading) - at(lo, heading)) / dt
    return np.round(grid * 1e6).astype(np.int64), speed, yaw_rate


def _ego_in_span(
    t: _Tables, span_us: tuple[int, int]
) -> tuple[npt.NDArray[np.int64], FloatArray, FloatArray]:
    """ego_signals of every ego pose within `span_us`; RecordingError naming ego_pose.json and
    the pose when one cannot be read."""
    times, xy, heading = [], [], []
    where = t.folder / "ego_pose.json"
    for row in t.rows["ego_pose"]:
        try:
            t_us = int(row["timestamp"])
        except (KeyError, TypeError, ValueError) as err:
            raise RecordingError(f"{where}: {row.get('token')}: no integer timestamp") from err
        if span_us[0] <= t_us <= span_us[1]:
            pose = _Pose.of(row, f"{where}: {row.get('token')}")
            times.append(t_us)
            xy.append(pose.t[:2])
            heading.append(yaw_rad(pose.R))
    return ego_signals(times, np.reshape(xy, (-1, 2)), heading)


def _nearest(rows: Sequence[_Row], t_us: int) -> _Row | None:
    """The row nearest `t_us` within MAX_RADAR_GAP_MS, None when none is."""
    best = min(rows, key=lambda r: abs(r.t_us - t_us), default=None)
    if best is None or abs(best.t_us - t_us) > MAX_RADAR_GAP_MS * 1000:
        return None
    return best


def _radar_targets(
    camera_row: _Row, sweeps: Sequence[_Row], mount: RadarMount
) -> tuple[RadarTarget, ...]:
    """The sweeps' filtered points at the camera's time, seen from `mount` (module docstring)."""
    targets: list[RadarTarget] = []
    for sweep in sweeps:
        pts = read_pcd_radar(sweep.path)
        pts = pts[radar_filter(pts)]
        if len(pts) == 0:
            continue
        p_radar = np.stack([pts["x"], pts["y"], pts["z"]], axis=1)
        p_global = sweep.ego.apply(sweep.sensor.apply(p_radar))
        # moved on by the velocity over ground (compensated), in the radar's frame -> global
        v_comp = np.stack([pts["vx_comp"], pts["vy_comp"], np.zeros(len(pts))], axis=1)
        dt_s = (camera_row.t_us - sweep.t_us) * 1e-6
        p_global = p_global + dt_s * (v_comp @ (sweep.ego.R @ sweep.sensor.R).T)
        p_ego = camera_row.ego.inverse_apply(p_global)
        # relative velocity (raw), radar frame -> ego frame at the camera's time
        v_rel = np.stack([pts["vx"], pts["vy"], np.zeros(len(pts))], axis=1)
        R = camera_row.ego.R.T @ sweep.ego.R @ sweep.sensor.R
        v_ego = v_rel @ R.T
        dx, dy = p_ego[:, 0] - mount.x_m, p_ego[:, 1] - mount.y_m
        rng = np.hypot(dx, dy)
        rate = (dx * v_ego[:, 0] + dy * v_ego[:, 1]) / np.maximum(rng, 1e-6)
        for k in range(len(pts)):
            targets.append(
                RadarTarget.from_polar(
                    float(rng[k]),
                    math.atan2(float(dy[k]), float(dx[k])) - mount.yaw_rad,
                    float(rate[k]),
                    float(pts["rcs"][k]),
                    mount.x_m,
                    mount.y_m,
                    mount.yaw_rad,
                )
            )
    return tuple(targets)


def _class_of(category: str) -> str | None:
    for prefix, cls in NUSCENES_CLASSES:
        if category.startswith(prefix):
            return cls
    return None


def _annotation_boxes(
    t: _Tables, sample_token: str, camera_row: _Row, track_ids: dict[str, int], skipped: _Skipped
) -> list[Box3D]:
    """The sample's annotations as boxes in the ego frame at the camera's time."""
    anns = t.by_token("sample_annotation")
    samples = t.by_token("sample")
    instances = t.by_token("instance")
    categories = t.by_token("category")
    where = t.folder / "sample_annotation.json"
    out: list[Box3D] = []
    for a in t.annotations_of.get(sample_token, []):
        instance = instances.get(a.get("instance_token", ""), {})
        category = str(categories.get(instance.get("category_token", ""), {}).get("name", ""))
        cls = _class_of(category)
        if cls is None:
            skipped.classes[category or "(no category)"] += 1
            continue
        try:
            pose = _Pose.of(a, f"{where}: {a.get('token')}")
            size = [float(v) for v in _field(a, "size", f"{where}: {a.get('token')}")]
            velocity = _annotation_velocity(a, anns, samples)
            w, length, h = size
            centre = camera_row.ego.inverse_apply(pose.t[None, :])[0]
            R = camera_row.ego.R.T @ pose.R
            v_ego = camera_row.ego.R.T @ np.array([velocity[0], velocity[1], 0.0])
            token = str(a["instance_token"])
            box = Box3D(
                id=track_ids.setdefault(token, len(track_ids) + 1),
                cls=cls,
                centre_m=(float(centre[0]), float(centre[1]), float(centre[2])),
                size_m=(length, w, h),
                yaw_rad=yaw_rad(R),
                velocity_mps=(float(v_ego[0]), float(v_ego[1])),
                hidden=HIDDEN_BY_VISIBILITY.get(str(a.get("visibility_token")), 0.0),
            )
        except (RecordingError, ValueError, TypeError, KeyError) as err:
            skipped.bad_annotations.append(str(err))
            continue
        out.append(box)
    return out


def _annotation_velocity(
    a: Mapping[str, Any], anns: Mapping[str, Any], samples: Mapping[str, Any]
) -> tuple[float, float]:
    """Global (vx, vy) m/s from the annotation's neighbours (nuscenes-devkit box_velocity);
    (0, 0) for an annotation without neighbours."""
    prev, nxt = anns.get(a.get("prev") or ""), anns.get(a.get("next") or "")
    first, last = prev or a, nxt or a
    if first is last:
        return 0.0, 0.0
    dt_s = (
        int(samples[last["sample_token"]]["timestamp"])
        - int(samples[first["sample_token"]]["timestamp"])
    ) * 1e-6
    dp = np.asarray(last["translation"], dtype=np.float64) - np.asarray(first["translation"])
    if dt_s <= 0 or not np.all(np.isfinite(dp)):
        return 0.0, 0.0
    return float(dp[0] / dt_s), float(dp[1] / dt_s)


def _notes(skipped: _Skipped, frames: int, labelled: int, radars: Sequence[str]) -> list[str]:
    notes: list[str] = []
    if skipped.missing_files:
        counts = ", ".join(f"{n} {c}" for c, n in sorted(skipped.missing_files.items()))
        notes.append(f"sample_data rows without their file, skipped: {counts}")
    if skipped.classes:
        counts = ", ".join(f"{n} {c}" for c, n in sorted(skipped.classes.items()))
        notes.append(f"annotations of classes the evaluation does not score, left out: {counts}")
    if skipped.bad_annotations:
        notes.append(
            f"{len(skipped.bad_annotations)} annotations that cannot be used, left out: "
            + "; ".join(skipped.bad_annotations[:3])
        )
    for radar in radars:
        if skipped.radar_frames_without[radar]:
            notes.append(
                f"{skipped.radar_frames_without[radar]} of {frames} frames have no {radar} sweep "
                f"within {MAX_RADAR_GAP_MS:g} ms"
            )
    notes.append(
        f"ground truth on the {labelled} keyframes of {frames} frames (no true pitch, no "
        "guard-rail polylines: nuScenes labels neither)"
    )
    return notes


def import_nuscenes(
    dataroot: Path,
    out_dir: Path,
    scene: str,
    version: str = DEFAULT_VERSION,
    camera: str = DEFAULT_CAMERA,
    radars: Sequence[str] = DEFAULT_RADARS,
    width_px: int = DEFAULT_WIDTH_PX,
    options: ImportOptions = ImportOptions(),
    progress: Progress | None = None,
) -> ImportResult:
    """Write scene `scene` of DATAROOT/VERSION into `out_dir` (new or empty); see the module
    docstring. RecordingError or ValueError naming the file or option on bad input."""
    check_out_dir(out_dir)
    if width_px < 1:
        raise ValueError(f"--width: expected a width >= 1 px, got {width_px}")
    if not radars:
        raise ValueError("--radars: expected at least one radar channel")
    folder = dataroot / version
    if not folder.is_dir():
        raise RecordingError(f"{folder}: no nuScenes version folder {version!r} in {dataroot}")
    tables = _Tables(folder)
    s = _scene(tables, scene)
    sample_tokens = {
        r["token"] for r in tables.rows["sample"] if r.get("scene_token") == s["token"]
    }
    skipped = _Skipped()
    rows = _channel_rows(tables, dataroot, sample_tokens, (camera, *radars), skipped)
    cameras = rows[camera]
    if not cameras:
        raise RecordingError(
            f"{dataroot}: no {camera} image of {scene} is there "
            f"({skipped.missing_files[camera]} rows of sample_data name files that are absent)"
        )
    cal_row = tables.by_token("calibrated_sensor")[cameras[0].calibrated_token]
    K = np.asarray(cal_row.get("camera_intrinsic") or [], dtype=np.float64)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)):
        raise RecordingError(
            f"{folder / 'calibrated_sensor.json'}: {cal_row['token']}: camera_intrinsic: "
            f"expected a 3x3 matrix for {camera}, got {cal_row.get('camera_intrinsic')}"
        )
    first = read_grey(cameras[0].path)
    source_size = (first.shape[1], first.shape[0])
    size = output_size(width_px, source_size)
    at_source = Intrinsics(
        fx_px=float(K[0, 0]),
        fy_px=float(K[1, 1]),
        cx_px=float(K[0, 2]),
        cy_px=float(K[1, 2]),
        width_px=source_size[0],
        height_px=source_size[1],
    )
    extrinsics = camera_extrinsics(cameras[0].sensor.R, cameras[0].sensor.t)
    first_radar = rows[radars[0]]  # the virtual radar's place (yaw 0: it looks ahead)
    x_m, y_m, z_m = (float(v) for v in first_radar[0].sensor.t) if first_radar else (0, 0, 0)
    mount = RadarMount(x_m, y_m, z_m)
    model = CameraModel(scale_intrinsics(at_source, *size), extrinsics)
    calibration = Calibration(model, mount)

    t0_us = cameras[0].t_us
    span = (cameras[0].t_us - 1_000_000, cameras[-1].t_us + 1_000_000)
    ego_t, speed, yaw_rate = _ego_in_span(tables, span)
    track_ids: dict[str, int] = {}
    truths: list[FrameTruth] = []
    hz = 1e6 / float(np.median(np.diff([c.t_us for c in cameras]))) if len(cameras) > 1 else 0.0
    description = (
        f"nuScenes {version} {scene} (CC BY-NC-SA 4.0, non-commercial; not to be copied into "
        f"another repository): {camera} at {hz:.1f} Hz, grey, resized to {size[0]}x{size[1]}; "
        f"radar {', '.join(radars)} (nuScenes' default filter) brought to the camera's time, "
        f"from a virtual radar at {radars[0]}; speed and yaw rate from the ego poses; ground "
        "truth from the keyframes' 3D boxes."
    )
    with staging(out_dir) as tmp:
        with RecordingWriter(
            tmp,
            name=options.name or f"nuscenes-{scene}",
            calibration=calibration,
            description=description,
            generator={
                "importer": "nuscenes",
                "dataset": f"nuScenes {version}",
                "scene": scene,
                "camera": camera,
                "clock_origin_us": t0_us,
            },
        ) as w:
            for t_us, v, r in zip(ego_t, speed, yaw_rate, strict=True):
                if t_us >= t0_us:
                    w.add_vehicle_state((int(t_us) - t0_us) * NS_PER_US, float(v), float(r))
            for k, cam in enumerate(cameras):
                t_ns = (cam.t_us - t0_us) * NS_PER_US
                image = read_grey(cam.path, source_size, "the scene's first image's size")
                w.add_image(t_ns, to_grey(image, size))
                sweeps = []
                for radar in radars:
                    near = _nearest(rows[radar], cam.t_us)
                    if near is None:
                        skipped.radar_frames_without[radar] += 1
                    else:
                        sweeps.append(near)
                targets = _radar_targets(cam, sweeps, mount)
                w.add_radar_scan(t_ns, targets)
                if cam.is_key_frame:
                    xy = np.array([[tg.x_m, tg.y_m] for tg in targets]).reshape(-1, 2)
                    boxes = _annotation_boxes(tables, cam.sample_token, cam, track_ids, skipped)
                    objects: list[TruthObject] = []
                    for box in boxes:
                        o = truth_object(model, box, xy)
                        if o is not None:
                            objects.append(o)
                    truths.append(
                        FrameTruth(k, t_ns, math.nan, tuple(objects), (), rails_labelled=False)
                    )
                if progress is not None:
                    progress(k + 1, len(cameras))
            w.set_groundtruth(truths)
    notes = _notes(skipped, len(cameras), len(truths), radars)
    stamps = [(c.t_us - t0_us) * NS_PER_US for c in cameras]
    return result(out_dir, stamps, size, calibration, load_manifest(out_dir), notes)
