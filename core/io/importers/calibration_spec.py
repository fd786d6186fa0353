"""How an import calibrates its camera and radar: the intrinsics as given (a camera_info
file, a horizontal field of view or a pinhole), the camera's pose and the radar's mount, built
into the calibration of the output images.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.io.calibration import Calibration, RadarMount, load_camera_info

DEFAULT_CAMERA_HEIGHT_M = 1.2  # a car's windscreen camera
DEFAULT_CAMERA_X_M = 1.5  # behind the windscreen, ahead of the rear axle
ASPECT_TOLERANCE = 0.01  # relative: a camera_info for another resolution of the same sensor


@dataclass(frozen=True)
class CameraInfoFile:
    """Intrinsics from a ROS camera_info YAML (as `fusionscope calibrate` writes)."""

    path: Path


@dataclass(frozen=True)
class FieldOfView:
    """Pinhole intrinsics from a horizontal field of view: square pixels, centred."""

    hfov_deg: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.hfov_deg) and 0.0 < self.hfov_deg < 180.0):
            raise ValueError(
                f"--hfov-deg: expected a field of view in (0, 180) degrees, got {self.hfov_deg}"
            )


@dataclass(frozen=True)
class Pinhole:
    """Pinhole intrinsics in pixels of the source image (a video's, a still's, a bag's).

    fy_px None: equal to fx_px; cx_px, cy_px None: the image centre.
    """

    fx_px: float
    fy_px: float | None = None
    cx_px: float | None = None
    cy_px: float | None = None


IntrinsicsSpec = CameraInfoFile | FieldOfView | Pinhole


@dataclass(frozen=True)
class CalibrationSpec:
    """How to calibrate the imported camera and radar.

    camera_height_m, camera_x_m, pitch_rad (down positive), yaw_rad (left positive): the
    camera's pose in the vehicle frame (x forward, origin on the road under the reference
    point); radar_mount: needed when the recording has
    radar. `rows_used_px` is left None (the engine uses all rows).
    """

    intrinsics: IntrinsicsSpec
    camera_height_m: float = DEFAULT_CAMERA_HEIGHT_M
    camera_x_m: float = DEFAULT_CAMERA_X_M
    pitch_rad: float = 0.0
    yaw_rad: float = 0.0
    radar_mount: RadarMount | None = None


def scale_intrinsics(i: Intrinsics, width_px: int, height_px: int) -> Intrinsics:
    """`i` for the image resized to `width_px` x `height_px`; distortion unchanged.

    Pixel centres sit at integer coordinates (core/camera.py), so a resize by s maps
    u -> (u + 0.5) * s - 0.5, as cv2.resize samples; focal lengths scale by s.
    """
    sx, sy = width_px / i.width_px, height_px / i.height_px
    return Intrinsics(
        fx_px=i.fx_px * sx,
        fy_px=i.fy_px * sy,
        cx_px=(i.cx_px + 0.5) * sx - 0.5,
        cy_px=(i.cy_px + 0.5) * sy - 0.5,
        width_px=width_px,
        height_px=height_px,
        distortion=i.distortion,
    )


@dataclass(frozen=True)
class BuiltCalibration:
    """The calibration of the output images, its description for the manifest, notes."""

    calibration: Calibration
    description: str
    notes: tuple[str, ...]


def build_calibration(
    spec: CalibrationSpec,
    source_size: tuple[int, int],
    out_size: tuple[int, int],
    has_radar: bool,
    what: str,
) -> BuiltCalibration:
    """The calibration of the output images (`out_size`) from `spec` about the source images.

    what: the source and its verb, for messages ("the video is", "the bag's images are").
    """
    (sw, sh), (ow, oh) = source_size, out_size
    notes: list[str] = []
    intr = spec.intrinsics
    if isinstance(intr, CameraInfoFile):
        info = load_camera_info(intr.path)
        if (info.width_px, info.height_px) != (sw, sh):
            ratio = (info.width_px / info.height_px) / (sw / sh)
            if (sw, sh) == (ow, oh) or abs(ratio - 1.0) > ASPECT_TOLERANCE:
                raise ValueError(
                    f"--camera-info {intr.path}: calibrated at {info.width_px}x{info.height_px}, "
                    f"but {what} {sw}x{sh}; give a camera_info (or --fx/--fy/--cx/--cy) "
                    f"at {sw}x{sh}"
                )
            notes.append(
                f"{intr.path} is for {info.width_px}x{info.height_px}, but {what} {sw}x{sh}: "
                "taken as the same sensor at another resolution"
            )
        intrinsics = scale_intrinsics(info, ow, oh)
        source = f"from {intr.path.name}"
    elif isinstance(intr, FieldOfView):
        intrinsics = Intrinsics.from_fov(ow, oh, math.radians(intr.hfov_deg))
        source = f"pinhole from a horizontal field of view of {intr.hfov_deg:g} deg, centred"
    else:
        at_source = Intrinsics(
            fx_px=intr.fx_px,
            fy_px=intr.fy_px if intr.fy_px is not None else intr.fx_px,
            cx_px=intr.cx_px if intr.cx_px is not None else (sw - 1) / 2.0,
            cy_px=intr.cy_px if intr.cy_px is not None else (sh - 1) / 2.0,
            width_px=sw,
            height_px=sh,
        )
        intrinsics = scale_intrinsics(at_source, ow, oh)
        source = (
            f"pinhole fx {at_source.fx_px:g}, fy {at_source.fy_px:g}, cx {at_source.cx_px:g}, "
            f"cy {at_source.cy_px:g} px at {sw}x{sh}"
        )
    if source_size != out_size and not isinstance(intr, FieldOfView):
        source += f", scaled to {ow}x{oh}"
    if has_radar and spec.radar_mount is None:
        raise ValueError(
            "--radar-x-m: the recording has radar, so its mount is needed: give --radar-x-m "
            "(and --radar-y-m, --radar-z-m, --radar-yaw-rad when not 0)"
        )
    mount = spec.radar_mount if spec.radar_mount is not None else RadarMount(0.0, 0.0)
    extrinsics = Extrinsics(
        height_m=spec.camera_height_m,
        x_m=spec.camera_x_m,
        pitch_rad=spec.pitch_rad,
        yaw_rad=spec.yaw_rad,
    )
    calibration = Calibration(CameraModel(intrinsics, extrinsics, None), mount)
    text = (
        f"Intrinsics: {source}. Camera {spec.camera_height_m:g} m above the road, "
        f"{spec.camera_x_m:g} m ahead of the reference point, pitch {spec.pitch_rad:g} rad, "
        f"yaw {spec.yaw_rad:g} rad."
    )
    if has_radar:
        text += (
            f" Radar at x {mount.x_m:g} m, y {mount.y_m:g} m, z {mount.z_m:g} m, "
            f"yaw {mount.yaw_rad:g} rad."
        )
    return BuiltCalibration(calibration, text, tuple(notes))
