"""`calibration.yaml`: the camera (ROS camera_info style intrinsics + pose) and the radar mount;
and ROS camera_info files themselves (`fusionscope calibrate` writes them, import reads them).

Layout (format_version 1):

    format_version: 1
    camera:                       # as ROS camera_info / camera_calibration_parsers
      image_width: 640
      image_height: 480
      camera_matrix: {rows: 3, cols: 3, data: [fx, 0, cx, 0, fy, cy, 0, 0, 1]}
      distortion_model: plumb_bob
      distortion_coefficients: {rows: 1, cols: 5, data: [k1, k2, p1, p2, k3]}   # data may be []
    extrinsics: {height_m: 1.2, x_m: 1.5, y_m: 0.0, pitch_rad: 0.01, yaw_rad: 0.0, roll_rad: 0.0}
    rows_used_px: [90, 390]       # [first, stop) rows the engine processes; null: all
    radar_mount: {x_m: 3.6, y_m: 0.0, z_m: 0.5, yaw_rad: 0.0}

Vehicle frame: x forward, y left, z up, metres, origin on the road under the reference point.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.checks import require_finite
from core.io.errors import RecordingError
from core.io.yamlfile import Fields, load_yaml_mapping

CALIBRATION_FORMAT_VERSION = 1
PLUMB_BOB = "plumb_bob"
RATIONAL_POLYNOMIAL = "rational_polynomial"
# Coefficient counts each distortion model may have (0: no distortion).
DISTORTION_MODELS = {PLUMB_BOB: (0, 4, 5), RATIONAL_POLYNOMIAL: (8,)}


@dataclass(frozen=True)
class RadarMount:
    """Radar position (m) and yaw (rad, positive to the left) in the vehicle frame."""

    x_m: float
    y_m: float
    z_m: float = 0.0
    yaw_rad: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x_m", "y_m", "z_m", "yaw_rad"):
            require_finite(name, getattr(self, name))


@dataclass(frozen=True)
class Calibration:
    camera: CameraModel
    radar_mount: RadarMount


def calibration_to_dict(cal: Calibration) -> dict[str, Any]:
    """The YAML-ready mapping of `cal` (layout in the module docstring)."""
    i, e = cal.camera.intrinsics, cal.camera.extrinsics
    rows = cal.camera.rows_used_px
    return {
        "format_version": CALIBRATION_FORMAT_VERSION,
        "camera": {
            "image_width": i.width_px,
            "image_height": i.height_px,
            "camera_matrix": {"rows": 3, "cols": 3, "data": [float(v) for v in i.K.ravel()]},
            "distortion_model": "plumb_bob" if len(i.distortion) <= 5 else "rational_polynomial",
            "distortion_coefficients": {
                "rows": 1,
                "cols": len(i.distortion),
                "data": [float(v) for v in i.distortion],
            },
        },
        "extrinsics": {
            "height_m": e.height_m,
            "x_m": e.x_m,
            "y_m": e.y_m,
            "pitch_rad": e.pitch_rad,
            "yaw_rad": e.yaw_rad,
            "roll_rad": e.roll_rad,
        },
        "rows_used_px": None if rows is None else [int(rows[0]), int(rows[1])],
        "radar_mount": {
            "x_m": cal.radar_mount.x_m,
            "y_m": cal.radar_mount.y_m,
            "z_m": cal.radar_mount.z_m,
            "yaw_rad": cal.radar_mount.yaw_rad,
        },
    }


def save_calibration(cal: Calibration, path: Path | str) -> None:
    Path(path).write_text(
        yaml.safe_dump(calibration_to_dict(cal), sort_keys=False), encoding="utf-8"
    )


def load_calibration(path: Path | str) -> Calibration:
    """Read `calibration.yaml`; RecordingError names the file and the key on bad input."""
    p = Path(path)
    f = Fields(p, load_yaml_mapping(p, "calibration"))
    f.check_keys({"camera", "extrinsics", "radar_mount"}, {"format_version", "rows_used_px"})
    if f.raw.get("format_version", CALIBRATION_FORMAT_VERSION) != CALIBRATION_FORMAT_VERSION:
        raise f.fail("format_version", str(CALIBRATION_FORMAT_VERSION), f.raw["format_version"])

    intrinsics = intrinsics_from_camera_info(f.sub("camera"))
    e = f.sub("extrinsics")
    e.check_keys({"height_m"}, {"x_m", "y_m", "pitch_rad", "yaw_rad", "roll_rad"})
    r = f.sub("radar_mount")
    r.check_keys({"x_m", "y_m"}, {"z_m", "yaw_rad"})
    rows: tuple[int, int] | None = None
    if f.has("rows_used_px"):
        first_stop = f.floats("rows_used_px", 2)
        if not all(v.is_integer() for v in first_stop):
            raise f.fail("rows_used_px", "two integer rows [first, stop]", f.raw["rows_used_px"])
        rows = (int(first_stop[0]), int(first_stop[1]))

    def opt(fields: Fields, name: str) -> float:
        return fields.float_(name) if name in fields.raw else 0.0

    try:
        extrinsics = Extrinsics(
            height_m=e.float_("height_m"),
            x_m=opt(e, "x_m"),
            y_m=opt(e, "y_m"),
            pitch_rad=opt(e, "pitch_rad"),
            yaw_rad=opt(e, "yaw_rad"),
            roll_rad=opt(e, "roll_rad"),
        )
        camera = CameraModel(intrinsics, extrinsics, rows)
        mount = RadarMount(r.float_("x_m"), r.float_("y_m"), opt(r, "z_m"), opt(r, "yaw_rad"))
    except ValueError as err:
        raise RecordingError(f"{p}: {err}") from err
    return Calibration(camera, mount)


# --- ROS camera_info files ---------------------------------------------------------------
def camera_info_to_dict(intrinsics: Intrinsics, camera_name: str) -> dict[str, Any]:
    """The YAML-ready mapping of a ROS camera_info file (layout in the module docstring)."""
    i = intrinsics
    model = RATIONAL_POLYNOMIAL if len(i.distortion) == 8 else PLUMB_BOB
    distortion = list(i.distortion) if i.distortion else [0.0] * 5
    return {
        "image_width": i.width_px,
        "image_height": i.height_px,
        "camera_name": camera_name,
        "camera_matrix": {"rows": 3, "cols": 3, "data": [float(v) for v in i.K.ravel()]},
        "distortion_model": model,
        "distortion_coefficients": {
            "rows": 1,
            "cols": len(distortion),
            "data": [float(v) for v in distortion],
        },
        "rectification_matrix": {
            "rows": 3,
            "cols": 3,
            "data": [float(v) for v in np.eye(3).ravel()],
        },
        "projection_matrix": {
            "rows": 3,
            "cols": 4,
            "data": [float(v) for v in np.hstack([i.K, np.zeros((3, 1))]).ravel()],
        },
    }


def save_camera_info(intrinsics: Intrinsics, path: Path, camera_name: str = "camera") -> None:
    path.write_text(
        yaml.safe_dump(
            camera_info_to_dict(intrinsics, camera_name), sort_keys=False, default_flow_style=None
        ),
        encoding="utf-8",
    )


def load_camera_info(path: Path) -> Intrinsics:
    """Intrinsics (size, camera matrix, distortion) of a ROS camera_info YAML file."""
    return intrinsics_from_camera_info(Fields(path, load_yaml_mapping(path, "camera_info file")))


def intrinsics_from_camera_info(f: Fields) -> Intrinsics:
    """Intrinsics of a ROS camera_info mapping (a file, or calibration.yaml's `camera`).

    RecordingError naming the file and the key on bad input; distortion models other than
    plumb_bob and rational_polynomial are refused (the engine's camera model has no others).
    """
    f.check_keys(
        {"image_width", "image_height", "camera_matrix"},
        {
            "camera_name",
            "distortion_model",
            "distortion_coefficients",
            "rectification_matrix",
            "projection_matrix",
        },
    )
    m = f.sub("camera_matrix")
    m.check_keys({"data"}, {"rows", "cols"})
    K = m.floats("data", 9)
    distortion: tuple[float, ...] = ()
    if f.has("distortion_coefficients"):
        d = f.sub("distortion_coefficients")
        d.check_keys({"data"}, {"rows", "cols"})
        distortion = d.floats("data")
    model = f.raw.get("distortion_model") or PLUMB_BOB
    if model not in DISTORTION_MODELS:
        raise f.fail("distortion_model", " or ".join(DISTORTION_MODELS), model)
    if all(v == 0.0 for v in distortion):
        distortion = ()
    if len(distortion) not in DISTORTION_MODELS[model]:
        expected = " or ".join(str(n) for n in DISTORTION_MODELS[model] if n)
        raise f.fail(
            "distortion_coefficients.data", f"{expected} coefficients for {model}", distortion
        )
    if K[1] != 0.0 or K[3] != 0.0 or K[6:] != (0.0, 0.0, 1.0):
        raise f.fail("camera_matrix.data", "[fx, 0, cx, 0, fy, cy, 0, 0, 1]", list(K))
    try:
        return Intrinsics(
            fx_px=K[0],
            fy_px=K[4],
            cx_px=K[2],
            cy_px=K[5],
            width_px=f.int_("image_width"),
            height_px=f.int_("image_height"),
            distortion=distortion,
        )
    except ValueError as err:
        raise RecordingError(f"{f.path}: {f.where or 'camera_info'}: {err}") from err
