"""core.io.importers.nuscenes: `fusionscope import nuscenes` on the real scene-0523 and on a
small synthetic version folder whose answers this file derives.

The real scene (../shared/realdata, nuScenes v1.0-mini, CC BY-NC-SA 4.0) is read where it is
and imported into tmp_path only; nothing derived from it enters the repository.

The synthetic folder is written in nuScenes' own layout with the libraries nuScenes files
are made of (json tables, JPEG images by cv2, radar PCDs by pypcd4): scene "scene-synth",
3 keyframes 0.5 s apart, the camera at 12 Hz with its sweeps present, one radar at 13 Hz.
The ego car drives straight along the global heading HEADING_RAD at EGO_SPEED_MPS; one car
drives ahead of it in the same direction at CAR_SPEED_MPS, CAR_GAP_M ahead (centre to the
ego's reference point) at the first camera frame. So, at time t (s after the first camera
frame), in the ego frame of time t:

    car centre x = CAR_GAP_M + (CAR_SPEED_MPS - EGO_SPEED_MPS) t,  y = 0,  yaw 0,

and its near face (the rear) is half its length (CAR_SIZE_WLH_M[1] / 2) nearer. Each radar
sweep holds one point on the car's rear face at the sweep's own time, with the car's velocity
over ground as vx_comp/vy_comp: brought to a camera frame's time it must sit on the rear face
at that time.
"""

from __future__ import annotations

import contextlib
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
import pytest
from pypcd4 import PointCloud

from core.cli import main
from core.io.drive import Drive

REAL_SCENE = "nuscenes-mini-scene-0523"
VEHICLES = ("car", "van", "truck")
RADAR_POINT_HEIGHT_M = 0.5  # radar points are drawn this high when projected onto the image

# --- the synthetic scene's facts ---------------------------------------------------------
SCENE = "scene-synth"
OTHER_SCENE = "scene-other"  # in scene.json, without samples
VERSION = "v1.0-synth"
LOG = "n000-2024-01-01-00-00-00-0000"
T0_US = 1_700_000_000_000_000  # the first camera frame
CAMERA_PERIOD_US = 83_333  # 12 Hz
CAMERA_ROWS = 13  # 1 s of camera: keyframes at rows 0, 6 and 12
KEY_EVERY = 6
RADAR_PERIOD_US = 76_923  # 13 Hz
RADAR_FIRST_US = T0_US - 31_000
RADAR_ROWS = 15
SAMPLE_AFTER_CAMERA_US = 20_000  # a sample's (the lidar's) time is 20 ms after its camera's
HEADING_RAD = 0.6  # the road's heading in the global frame
EGO_START_M = (410.0, 1170.0)
EGO_SPEED_MPS = 10.0  # 36 km/h: a whole number of the CAN speed's 0.01 km/h steps
CAR_SPEED_MPS = 6.0
CAR_GAP_M = 22.0
CAR_SIZE_WLH_M = (1.9, 4.5, 1.6)  # nuScenes' order: width, length, height
IMAGE_SIZE_PX = (320, 180)
IMAGE_SCALE = 0.2  # of nuScenes' 1600x900 CAM_FRONT
# the real CAM_FRONT and RADAR_FRONT of scene-0523's car (calibrated_sensor.json)
CAM_TRANSLATION_M = [1.72200568478, 0.00475453292289, 1.49491291905]
CAM_ROTATION_WXYZ = [
    0.5077241387638071,
    -0.4973392230703816,
    0.49837167536166627,
    -0.4964832014373754,
]
CAM_K = [[1252.8131021185304, 0.0, 826.588114781398], [0.0, 1252.8131021185304, 469.9846626224581]]
RADAR_TRANSLATION_M = [3.412, 0.0, 0.5]
RADAR_YAW_RAD = 2 * math.atan2(-0.0022689260808398757, 0.9999974259839071)
FILTERED_POINT_M = (15.0, 4.0)  # a point nuScenes' default filter drops (invalid_state 1)
RADAR_FIELDS = (
    ("x", np.float32),
    ("y", np.float32),
    ("z", np.float32),
    ("dyn_prop", np.int8),
    ("id", np.int16),
    ("rcs", np.float32),
    ("vx", np.float32),
    ("vy", np.float32),
    ("vx_comp", np.float32),
    ("vy_comp", np.float32),
    ("is_quality_valid", np.int8),
    ("ambig_state", np.int8),
    ("x_rms", np.int8),
    ("y_rms", np.int8),
    ("invalid_state", np.int8),
    ("pdh0", np.int8),
    ("vx_rms", np.int8),
    ("vy_rms", np.int8),
)


def _direction() -> npt.NDArray[np.float64]:
    return np.array([math.cos(HEADING_RAD), math.sin(HEADING_RAD)])


def _ego_xy(t_us: int) -> npt.NDArray[np.float64]:
    return np.asarray(EGO_START_M) + EGO_SPEED_MPS * (t_us - T0_US) * 1e-6 * _direction()


def _car_centre_xy(t_us: int) -> npt.NDArray[np.float64]:
    t_s = (t_us - T0_US) * 1e-6
    return np.asarray(EGO_START_M) + (CAR_GAP_M + CAR_SPEED_MPS * t_s) * _direction()


def _yaw_quaternion(yaw_rad: float) -> list[float]:
    return [math.cos(yaw_rad / 2), 0.0, 0.0, math.sin(yaw_rad / 2)]


def _rotate(xy: npt.NDArray[np.float64], angle_rad: float) -> npt.NDArray[np.float64]:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    return np.array([c * xy[0] - s * xy[1], s * xy[0] + c * xy[1]])


def _radar_points(t_us: int) -> npt.NDArray[np.float64]:
    """(2, 18) the sweep's points: one on the car's rear face, one the filter drops."""
    # the rear face's centre, global -> ego at the sweep's time -> radar frame
    rear = _car_centre_xy(t_us) - CAR_SIZE_WLH_M[1] / 2 * _direction()
    in_ego = _rotate(rear - _ego_xy(t_us), -HEADING_RAD)
    in_radar = _rotate(in_ego - np.asarray(RADAR_TRANSLATION_M[:2]), -RADAR_YAW_RAD)
    over_ground = _rotate(CAR_SPEED_MPS * _direction(), -(HEADING_RAD + RADAR_YAW_RAD))
    relative = _rotate((CAR_SPEED_MPS - EGO_SPEED_MPS) * _direction(), -HEADING_RAD - RADAR_YAW_RAD)
    # x y z dyn_prop id rcs vx vy vx_comp vy_comp is_quality_valid ambig_state x_rms y_rms
    # invalid_state pdh0 vx_rms vy_rms
    on_car = [*in_radar, 0.0, 0, 1, 12.0, *relative, *over_ground, 1, 3, 19, 19, 0, 1, 19, 3]
    dropped = [*FILTERED_POINT_M, 0.0, 1, 2, 5.0, -10.0, 0.0, 0.0, 0.0, 1, 3, 19, 19, 1, 1, 19, 3]
    return np.array([on_car, dropped], dtype=np.float64)


@dataclass(frozen=True)
class Synthetic:
    """The synthetic DATAROOT and what a test needs to damage it."""

    dataroot: Path
    tables: Path
    camera_files: list[Path]
    radar_files: list[Path]
    camera_t_us: list[int]
    radar_t_us: list[int]
    car_annotations: list[str]


def _token(kind: str, k: int) -> str:
    return f"{kind}{k:04d}".ljust(32, "0")


def build_synthetic(root: Path) -> Synthetic:
    """Write the module docstring's scene into `root` (DATAROOT) and say where its parts are."""
    tables = root / VERSION
    tables.mkdir(parents=True)
    rng = np.random.default_rng(523)
    sensor = [
        {"token": _token("sensorcam", 0), "channel": "CAM_FRONT", "modality": "camera"},
        {"token": _token("sensorrad", 0), "channel": "RADAR_FRONT", "modality": "radar"},
    ]
    K = (np.vstack([np.asarray(CAM_K) * IMAGE_SCALE, [0.0, 0.0, 1.0]])).tolist()
    calibrated = [
        {
            "token": _token("calcam", 0),
            "sensor_token": sensor[0]["token"],
            "translation": CAM_TRANSLATION_M,
            "rotation": CAM_ROTATION_WXYZ,
            "camera_intrinsic": K,
        },
        {
            "token": _token("calrad", 0),
            "sensor_token": sensor[1]["token"],
            "translation": RADAR_TRANSLATION_M,
            "rotation": _yaw_quaternion(RADAR_YAW_RAD),
            "camera_intrinsic": [],
        },
    ]
    camera_t = [T0_US + k * CAMERA_PERIOD_US for k in range(CAMERA_ROWS)]
    radar_t = [RADAR_FIRST_US + k * RADAR_PERIOD_US for k in range(RADAR_ROWS)]
    keys = camera_t[::KEY_EVERY]
    samples: list[dict[str, Any]] = [
        {
            "token": _token("sample", k),
            "timestamp": t + SAMPLE_AFTER_CAMERA_US,
            "prev": _token("sample", k - 1) if k else "",
            "next": _token("sample", k + 1) if k + 1 < len(keys) else "",
            "scene_token": _token("scene", 0),
        }
        for k, t in enumerate(keys)
    ]
    scenes = [
        {
            "token": _token("scene", 0),
            "log_token": _token("log", 0),
            "nbr_samples": len(samples),
            "first_sample_token": samples[0]["token"],
            "last_sample_token": samples[-1]["token"],
            "name": SCENE,
            "description": "synthetic: straight road, one car ahead",
        },
        {
            "token": _token("scene", 1),
            "log_token": _token("log", 0),
            "nbr_samples": 0,
            "first_sample_token": "",
            "last_sample_token": "",
            "name": OTHER_SCENE,
            "description": "synthetic: no samples",
        },
    ]

    def nearest_sample(t_us: int) -> str:
        k = int(np.argmin([abs(t_us - s["timestamp"]) for s in samples]))
        return str(samples[k]["token"])

    sample_data: list[dict[str, Any]] = []
    ego_pose: list[dict[str, Any]] = []
    camera_files: list[Path] = []
    radar_files: list[Path] = []
    for kind, times, channel, ext, cal in (
        ("cam", camera_t, "CAM_FRONT", "jpg", calibrated[0]),
        ("rad", radar_t, "RADAR_FRONT", "pcd", calibrated[1]),
    ):
        for k, t in enumerate(times):
            key = kind == "cam" and k % KEY_EVERY == 0
            folder = "samples" if key else "sweeps"
            filename = f"{folder}/{channel}/{LOG}__{channel}__{t}.{ext}"
            path = root / filename
            path.parent.mkdir(parents=True, exist_ok=True)
            if kind == "cam":
                w, h = IMAGE_SIZE_PX
                ramp = np.linspace(40, 200, w, dtype=np.float64)[None, :, None]
                image = ramp + rng.normal(0.0, 12.0, (h, w, 3))
                assert cv2.imwrite(str(path), np.clip(image, 0, 255).astype(np.uint8))
                camera_files.append(path)
            else:
                cloud = PointCloud.from_points(
                    _radar_points(t), [f for f, _ in RADAR_FIELDS], [d for _, d in RADAR_FIELDS]
                )
                cloud.save(path)
                radar_files.append(path)
            token = _token(f"sd{kind}", k)
            ego_pose.append(
                {
                    "token": token,
                    "timestamp": t,
                    "rotation": _yaw_quaternion(HEADING_RAD),
                    "translation": [*_ego_xy(t).tolist(), 0.0],
                }
            )
            sample_data.append(
                {
                    "token": token,
                    "sample_token": nearest_sample(t),
                    "ego_pose_token": token,
                    "calibrated_sensor_token": cal["token"],
                    "timestamp": t,
                    "fileformat": ext,
                    "is_key_frame": key,
                    "height": IMAGE_SIZE_PX[1] if kind == "cam" else 0,
                    "width": IMAGE_SIZE_PX[0] if kind == "cam" else 0,
                    "filename": filename,
                    "prev": _token(f"sd{kind}", k - 1) if k else "",
                    "next": _token(f"sd{kind}", k + 1) if k + 1 < len(times) else "",
                }
            )
    annotations = []
    for k, s in enumerate(samples):
        centre = _car_centre_xy(int(s["timestamp"]))
        annotations.append(
            {
                "token": _token("ann", k),
                "sample_token": s["token"],
                "instance_token": _token("instance", 0),
                "visibility_token": "4",
                "attribute_tokens": [],
                "translation": [*centre.tolist(), CAR_SIZE_WLH_M[2] / 2],
                "size": list(CAR_SIZE_WLH_M),
                "rotation": _yaw_quaternion(HEADING_RAD),
                "prev": _token("ann", k - 1) if k else "",
                "next": _token("ann", k + 1) if k + 1 < len(samples) else "",
                "num_lidar_pts": 100,
                "num_radar_pts": 1,
            }
        )
    barrier = {
        **annotations[0],
        "token": _token("annbarrier", 0),
        "instance_token": _token("instance", 1),
        "translation": [*(_ego_xy(T0_US) + _rotate(np.array([12.0, -5.0]), HEADING_RAD)), 0.5],
        "size": [0.5, 2.0, 1.0],
        "prev": "",
        "next": "",
    }
    instances = [
        {
            "token": _token("instance", 0),
            "category_token": _token("catcar", 0),
            "nbr_annotations": len(annotations),
            "first_annotation_token": annotations[0]["token"],
            "last_annotation_token": annotations[-1]["token"],
        },
        {
            "token": _token("instance", 1),
            "category_token": _token("catbarrier", 0),
            "nbr_annotations": 1,
            "first_annotation_token": barrier["token"],
            "last_annotation_token": barrier["token"],
        },
    ]
    categories = [
        {"token": _token("catcar", 0), "name": "vehicle.car", "description": "car", "index": 17},
        {
            "token": _token("catbarrier", 0),
            "name": "movable_object.barrier",
            "description": "barrier",
            "index": 9,
        },
    ]
    for name, rows in (
        ("scene", scenes),
        ("sample", samples),
        ("sample_data", sample_data),
        ("ego_pose", ego_pose),
        ("calibrated_sensor", calibrated),
        ("sensor", sensor),
        ("sample_annotation", [*annotations, barrier]),
        ("instance", instances),
        ("category", categories),
    ):
        (tables / f"{name}.json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    return Synthetic(
        root,
        tables,
        camera_files,
        radar_files,
        camera_t,
        radar_t,
        [str(a["token"]) for a in annotations],
    )


def _synthetic_args(
    s: Synthetic, out: Path, scene: str = SCENE, camera: str = "CAM_FRONT"
) -> list[str]:
    args = ["import", "nuscenes", str(s.dataroot), str(out), "--scene", scene]
    args += ["--version", VERSION, "--camera", camera, "--radars", "RADAR_FRONT"]
    return [*args, "--width", str(IMAGE_SIZE_PX[0])]


@pytest.fixture
def synthetic(tmp_path: Path) -> Synthetic:
    """A fresh synthetic DATAROOT, for a test to damage."""
    return build_synthetic(tmp_path / "dataroot")


def _main_printing(args: list[str], where: Path) -> tuple[int, str]:
    """core.cli.main's exit code and what it printed (for module-scoped fixtures, which
    capsys cannot serve)."""
    with where.open("w") as f, contextlib.redirect_stdout(f):
        code = main(args)
    return code, where.read_text()


@dataclass(frozen=True)
class Imported:
    scene: Synthetic
    out: Path
    printed: str


@pytest.fixture(scope="module")
def imported(tmp_path_factory: pytest.TempPathFactory) -> Imported:
    """The synthetic scene, imported once through the CLI."""
    root = tmp_path_factory.mktemp("synthetic")
    scene = build_synthetic(root / "dataroot")
    out = root / "out" / "synth"
    code, printed = _main_printing(_synthetic_args(scene, out), root / "stdout.txt")
    assert code == 0
    return Imported(scene, out, printed)


def _out_is_clean(out: Path) -> None:
    """A failed import leaves neither OUT_DIR nor a partial folder beside it."""
    assert not out.exists()
    assert not out.parent.exists() or list(out.parent.iterdir()) == []


# --- the real scene ----------------------------------------------------------------------
@pytest.fixture(scope="module")
def real_scene(realdata: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """scene-0523 imported through the CLI: the folder and what the CLI printed."""
    root = tmp_path_factory.mktemp("nuscenes")
    out = root / "scene-0523"
    args = ["import", "nuscenes", str(realdata / REAL_SCENE), str(out), "--scene", "scene-0523"]
    code, printed = _main_printing(args, root / "stdout.txt")
    assert code == 0
    return out, printed


def test_real_scene_frames_speed_radar_and_truth(real_scene: tuple[Path, str]) -> None:
    out, _ = real_scene
    with Drive(out) as drive:
        assert len(drive) == 40
        assert drive.frame_rate_hz == pytest.approx(2.0, abs=0.1)  # keyframes only
        classes: set[str] = set()
        for i in range(len(drive)):
            frame = drive.frame(i)
            # the README: the ego car drives at 3.8-8.8 m/s
            assert 3.0 <= frame.speed_mps <= 9.5, (i, frame.speed_mps)
            assert frame.radar, f"frame {i}: no radar targets"
            truth = drive.truth(i)
            assert truth is not None, f"frame {i}: no truth"
            assert math.isnan(truth.pitch_rad) and not truth.rails_labelled
            classes |= {o.cls for o in truth.objects}
        assert {"car", "truck", "pedestrian"} <= classes


def test_real_scene_radar_points_fall_in_the_vehicles_boxes(
    real_scene: tuple[Path, str], report: Callable[[str], None]
) -> None:
    """Radar-seen vehicles (not hidden, 0-50 m ahead) have a radar point, projected 0.5 m
    above the road, inside their truth box: the radar, the camera and the labels agree."""
    out, _ = real_scene
    seen = hit = 0
    with Drive(out) as drive:
        for i in range(len(drive)):
            truth = drive.truth(i)
            assert truth is not None
            pts = [(t.x_m, t.y_m, RADAR_POINT_HEIGHT_M) for t in drive.frame(i).radar]
            uv, in_front = drive.camera.project(np.array(pts))
            for o in truth.objects:
                if not (
                    o.cls in VEHICLES
                    and o.radar_seen
                    and o.occlusion < 0.5
                    and 0 < o.position_m[0] <= 50
                ):
                    continue
                u0, v0, u1, v1 = o.box_px
                inside = in_front & (uv[:, 0] >= u0) & (uv[:, 0] <= u1)
                inside &= (uv[:, 1] >= v0) & (uv[:, 1] <= v1)
                seen += 1
                hit += bool(inside.any())
    report(
        f"nuScenes scene-0523: {hit} of {seen} radar-seen vehicles within 50 m have a radar "
        "point in their box"
    )
    assert seen >= 100  # measured: 121
    assert hit >= 0.8 * seen  # measured: 119


def test_real_scene_notes_count_the_rows_without_files(
    real_scene: tuple[Path, str], realdata: Path
) -> None:
    """Only the keyframes have files here (README): every other row of the four channels is
    skipped, and the notes say how many of each."""
    _, printed = real_scene
    tables = realdata / REAL_SCENE / "v1.0-mini"
    channel = {
        c["token"]: s_by[c["sensor_token"]]
        for s_by in [
            {s["token"]: s["channel"] for s in json.loads((tables / "sensor.json").read_text())}
        ]
        for c in json.loads((tables / "calibrated_sensor.json").read_text())
    }
    sweeps: dict[str, int] = {}
    for row in json.loads((tables / "sample_data.json").read_text()):
        if not row["is_key_frame"]:
            name = channel[row["calibrated_sensor_token"]]
            sweeps[name] = sweeps.get(name, 0) + 1
    wanted = ("CAM_FRONT", "RADAR_FRONT", "RADAR_FRONT_LEFT", "RADAR_FRONT_RIGHT")
    counts = ", ".join(f"{sweeps[c]} {c}" for c in wanted)
    assert f"note: sample_data rows without their file, skipped: {counts}" in printed
    assert "ground truth on the 40 keyframes of 40 frames" in printed


# --- a scene it has never seen -------------------------------------------------------------
def test_synthetic_scene_runs_at_the_cameras_12_hz_with_truth_on_keyframes(
    imported: Imported,
) -> None:
    out, printed = imported.out, imported.printed
    assert (
        "annotations of classes the evaluation does not score, left out: 1 movable_object.barrier"
        in printed
    )
    assert "ground truth on the 3 keyframes of 13 frames" in printed
    assert "without their file" not in printed
    with Drive(out) as drive:
        assert len(drive) == CAMERA_ROWS
        assert drive.frame_rate_hz == pytest.approx(1e6 / CAMERA_PERIOD_US, rel=1e-4)
        keyframes = [i for i in range(len(drive)) if drive.truth(i) is not None]
        assert keyframes == list(range(0, CAMERA_ROWS, KEY_EVERY))
        size = drive.camera.intrinsics
        assert (size.width_px, size.height_px) == IMAGE_SIZE_PX


def test_synthetic_speed_and_yaw_rate_come_from_the_poses(imported: Imported) -> None:
    with Drive(imported.out) as drive:
        for i in range(len(drive)):
            frame = drive.frame(i)
            # CAN carries speed in 0.01 km/h steps (core/io/data/vehicle.dbc)
            assert frame.speed_mps == pytest.approx(EGO_SPEED_MPS, abs=0.01 / 3.6)
            assert frame.yaw_rate_radps == 0.0


def test_synthetic_car_truth_is_its_near_face_in_the_ego_frame_of_the_camera_time(
    imported: Imported,
) -> None:
    """The annotation holds the car at the sample's time; the box is placed in the ego frame
    of the keyframe camera's time (as nuscenes-devkit's get_sample_data does), so its centre
    lies CAR_GAP + CAR_SPEED t_sample - EGO_SPEED t_camera ahead, the near face
    CAR_LENGTH / 2 nearer."""
    out, synthetic = imported.out, imported.scene
    length = CAR_SIZE_WLH_M[1]
    with Drive(out) as drive:
        for i in range(0, CAMERA_ROWS, KEY_EVERY):
            truth = drive.truth(i)
            assert truth is not None
            (car,) = truth.objects
            t_camera_s = (synthetic.camera_t_us[i] - T0_US) * 1e-6
            t_sample_s = t_camera_s + SAMPLE_AFTER_CAMERA_US * 1e-6
            centre_x = CAR_GAP_M + CAR_SPEED_MPS * t_sample_s - EGO_SPEED_MPS * t_camera_s
            assert car.cls == "car"
            assert car.position_m[0] == pytest.approx(centre_x - length / 2, abs=1e-3)
            assert car.position_m[1] == pytest.approx(0.0, abs=1e-3)
            assert car.size_m == pytest.approx(
                (length, CAR_SIZE_WLH_M[0], CAR_SIZE_WLH_M[2]), abs=1e-3
            )
            assert car.velocity_mps == pytest.approx((CAR_SPEED_MPS, 0.0), abs=1e-3)
            assert car.occlusion == pytest.approx(0.1)  # visibility "4": 80-100 % visible
            assert car.radar_seen
            # the box straddles the image's centre column: the car is dead ahead
            u0, _, u1, _ = car.box_px
            assert u0 < IMAGE_SIZE_PX[0] / 2 < u1


def test_synthetic_radar_point_is_brought_to_the_cameras_time(imported: Imported) -> None:
    """Each frame's radar point on the car is the nearest sweep's, moved on by the car's
    velocity over ground (vx_comp, vy_comp) to the camera's time and seen from the ego frame
    of that time: on the car's rear face then, closing at CAR_SPEED - EGO_SPEED."""
    out, synthetic = imported.out, imported.scene
    shift_m = []
    with Drive(out) as drive:
        for i in range(len(drive)):
            targets = drive.frame(i).radar
            t_us = synthetic.camera_t_us[i]
            t_s = (t_us - T0_US) * 1e-6
            rear_x = CAR_GAP_M + (CAR_SPEED_MPS - EGO_SPEED_MPS) * t_s - CAR_SIZE_WLH_M[1] / 2
            (target,) = targets  # the other point is dropped by nuScenes' default filter
            assert (target.x_m, target.y_m) == pytest.approx((rear_x, 0.0), abs=0.005)
            assert target.range_rate_mps == pytest.approx(CAR_SPEED_MPS - EGO_SPEED_MPS, abs=1e-3)
            sweep_us = min(synthetic.radar_t_us, key=lambda r: abs(r - t_us))
            shift_m.append(abs(CAR_SPEED_MPS * (t_us - sweep_us) * 1e-6))
    # the scene tells a moved point from an unmoved one: some sweeps lie far enough off
    assert max(shift_m) > 0.1


# --- bad inputs ------------------------------------------------------------------------------
def _fails(s: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str], **kwargs: str) -> str:
    """Import `s` expecting failure: the CLI's message, after checking nothing was left."""
    out = tmp_path / "out" / "synth"
    assert main(_synthetic_args(s, out, **kwargs)) == 2
    _out_is_clean(out)
    err = capsys.readouterr().err
    assert err.startswith("fusionscope import nuscenes: ")
    return err


def test_missing_table(
    synthetic: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (synthetic.tables / "sample.json").unlink()
    err = _fails(synthetic, tmp_path, capsys)
    assert f"{synthetic.tables / 'sample.json'}: table not found" in err
    assert "needs scene, sample, sample_data" in err


def test_scene_not_there_lists_the_scenes(
    synthetic: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    err = _fails(synthetic, tmp_path, capsys, scene="scene-0523")
    assert f"{synthetic.tables / 'scene.json'}: no scene 'scene-0523'" in err
    assert f"the scenes there: {OTHER_SCENE}, {SCENE}" in err


def test_camera_not_there_lists_the_sensors(
    synthetic: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    err = _fails(synthetic, tmp_path, capsys, camera="CAM_NOPE")
    assert f"{synthetic.tables / 'sensor.json'}: no sensor 'CAM_NOPE'" in err
    assert "the sensors there: CAM_FRONT, RADAR_FRONT" in err


@pytest.mark.parametrize(
    ("field", "value", "problem"),
    [
        ("rotation", [0, 0, 0, 0], "rotation: expected a quaternion"),
        ("timestamp", None, "no integer"),
    ],
)
def test_an_unreadable_ego_pose_is_named(
    synthetic: Synthetic,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    field: str,
    value: object,
    problem: str,
) -> None:
    # a pose of a sweep whose file is absent: read only for the speed and yaw rate
    path = synthetic.tables / "ego_pose.json"
    rows = json.loads(path.read_text())
    rows[1][field] = value
    path.write_text(json.dumps(rows))
    err = _fails(synthetic, tmp_path, capsys)
    assert f"{path}: {rows[1]['token']}: {problem}" in err


def test_damaged_pcd_header(
    synthetic: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # the sweep the first frame uses (31 ms before it)
    pcd = synthetic.radar_files[0]
    data = pcd.read_bytes()
    assert b"\nWIDTH 2\n" in data
    pcd.write_bytes(data.replace(b"\nWIDTH 2\n", b"\nWIDTH two\n", 1))
    err = _fails(synthetic, tmp_path, capsys)
    assert f"{pcd}: damaged PCD file" in err


def test_label_with_nan_is_left_out_and_noted(
    synthetic: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = synthetic.tables / "sample_annotation.json"
    rows = json.loads(path.read_text())
    bad = synthetic.car_annotations[1]
    for row in rows:
        if row["token"] == bad:
            row["translation"][0] = math.nan
    path.write_text(json.dumps(rows))  # Python's json writes NaN, and reads it back
    out = tmp_path / "out" / "synth"
    assert main(_synthetic_args(synthetic, out)) == 0
    printed = capsys.readouterr().out
    assert "note: 1 annotations that cannot be used, left out: " in printed
    assert f"left out: {path}: {bad}: translation: expected 3 finite numbers" in printed
    with Drive(out) as drive:
        objects = [len(t.objects) if (t := drive.truth(i)) else None for i in range(len(drive))]
    assert [objects[i] for i in range(0, CAMERA_ROWS, KEY_EVERY)] == [1, 0, 1]
    assert list(out.parent.iterdir()) == [out]


def test_all_camera_images_missing(
    synthetic: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for path in synthetic.camera_files:
        path.unlink()
    err = _fails(synthetic, tmp_path, capsys)
    assert f"{synthetic.dataroot}: no CAM_FRONT image of {SCENE} is there" in err
    assert f"({CAMERA_ROWS} rows of sample_data name files that are absent)" in err


def test_one_missing_image_is_skipped_and_counted(
    synthetic: Synthetic, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    synthetic.camera_files[3].unlink()  # a sweep between the first two keyframes
    out = tmp_path / "out" / "synth"
    assert main(_synthetic_args(synthetic, out)) == 0
    assert (
        "note: sample_data rows without their file, skipped: 1 CAM_FRONT" in capsys.readouterr().out
    )
    with Drive(out) as drive:
        assert len(drive) == CAMERA_ROWS - 1
        gone = synthetic.camera_t_us[3] - T0_US
        assert gone * 1000 not in drive.times_ns.tolist()
    assert list(out.parent.iterdir()) == [out]
