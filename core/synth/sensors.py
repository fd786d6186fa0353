"""The synthetic car's sensors: body pitch, the 77 GHz radar, CAN speed and yaw rate, camera noise.

Each takes the exact scene state and degrades it the way the papers describe real sensors:
radar points off-centre or off the vehicle (paper 001 fig. 2), one point for two vehicles
close together and misses in traffic (fig. 8), many slow returns along guard rails (paper
002 fig. 8), pedestrians rarely seen (paper 000); pitch from road roughness and braking
(paper 001 fig. 1); yaw rate with a bias and coarse steps like a real car's (see
../shared/realdata: the RAV4's 0.244 deg/s steps and -0.4 deg/s bias).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from core.io.calibration import RadarMount
from core.io.frame import RadarTarget
from core.synth.render import RadarView
from core.synth.scene import Scene

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class RadarModel:
    """A forward 77 GHz radar (paper 001: "obstacles up to 50 meters")."""

    max_range_m: float = 50.0
    half_fov_rad: float = math.radians(24.0)  # a little wider than the camera's 22.5 deg
    lateral_sigma_m: float = 0.4  # paper 001 fig. 2: points not centred on the object
    range_sigma_m: float = 0.12
    off_object_probability: float = 0.12  # a point beside the vehicle, not on it
    detect_probability: float = 0.92
    traffic_vehicles: int = 5  # more vehicles than this in range: more misses
    traffic_detect_factor: float = 0.8
    merge_probability: float = 0.7  # two vehicles close together give one point
    merge_range_m: float = 3.0
    merge_lateral_m: float = 4.5
    extra_point_probability: float = 0.6  # vans and trucks give more than one point
    pedestrian_probability: float = 0.08
    clutter_probability: float = 0.45  # poles and signs
    tree_probability: float = 0.15
    rail_point_probability: float = 0.09  # per metre of guard rail in view
    rail_lateral_sigma_m: float = 0.2
    false_alarms_per_scan: float = 0.3
    amplitude_offset_db: float = 55.0


def _amplitude(
    rcs_dbsm: float, range_m: float, model: RadarModel, rng: np.random.Generator
) -> float:
    return float(
        rcs_dbsm
        - 40.0 * math.log10(max(range_m, 1.0))
        + model.amplitude_offset_db
        + rng.normal(0, 1.5)
    )


def _target(
    p_xy: FloatArray,
    velocity_mps: FloatArray,
    ego_speed_mps: float,
    ego_yaw_rate_radps: float,
    rcs_dbsm: float,
    mount: RadarMount,
    model: RadarModel,
    rng: np.random.Generator,
) -> RadarTarget | None:
    """A return from vehicle-frame point p_xy moving at velocity_mps over ground (ego axes)."""
    rel = p_xy - np.array([mount.x_m, mount.y_m])
    rng_m = float(np.hypot(*rel)) + float(rng.normal(0, model.range_sigma_m))
    az = math.atan2(rel[1], rel[0]) - mount.yaw_rad
    if not (1.0 < rng_m <= model.max_range_m and abs(az) <= model.half_fov_rad):
        return None
    # relative velocity of the point as the moving, turning radar sees it
    v_rel = np.array(
        [
            velocity_mps[0] - ego_speed_mps + ego_yaw_rate_radps * p_xy[1],
            velocity_mps[1] - ego_yaw_rate_radps * p_xy[0],
        ]
    )
    range_rate = float(np.dot(v_rel, rel) / max(float(np.hypot(*rel)), 1e-6))
    return RadarTarget.from_polar(
        rng_m,
        az,
        range_rate,
        _amplitude(rcs_dbsm, rng_m, model, rng),
        mount.x_m,
        mount.y_m,
        mount.yaw_rad,
    )


def radar_scan(
    scene: Scene,
    views: dict[int, RadarView],
    rail_points: list[tuple[int, FloatArray]],
    ego_speed_mps: float,
    ego_yaw_rate_radps: float,
    mount: RadarMount,
    rng: np.random.Generator,
    model: RadarModel = RadarModel(),
) -> tuple[list[RadarTarget], set[int]]:
    """One radar scan and the ids of the objects that produced a point in it."""
    targets: list[RadarTarget] = []
    seen: set[int] = set()
    args = (ego_speed_mps, ego_yaw_rate_radps)

    def emit(obj_id: int, p_xy: FloatArray, vel: FloatArray, rcs: float) -> None:
        t = _target(p_xy, vel, *args, rcs, mount, model, rng)
        if t is not None:
            targets.append(t)
            if obj_id:
                seen.add(obj_id)

    in_range = {
        v.id: views[v.id]
        for v in scene.vehicles
        if v.id in views
        and 0 < views[v.id].near_m[0]
        and float(np.hypot(*views[v.id].near_m[:2])) < model.max_range_m + 5
    }
    p_detect = model.detect_probability * (
        model.traffic_detect_factor if len(in_range) > model.traffic_vehicles else 1.0
    )
    detected = []
    for v in scene.vehicles:
        view = in_range.get(v.id)
        if view is None:
            continue
        frac = view.visible_fraction
        prob = p_detect if frac > 0.5 else (0.45 * p_detect if frac > 0.2 else 0.05)
        if rng.uniform() < prob:
            detected.append(v)
    # one point for two vehicles close together (paper 001 fig. 8a)
    merged: set[int] = set()
    for va in detected:
        for vb in detected:
            if va.id >= vb.id or va.id in merged or vb.id in merged:
                continue
            pa, pb = in_range[va.id].near_m[:2], in_range[vb.id].near_m[:2]
            if (
                abs(pa[0] - pb[0]) < model.merge_range_m
                and abs(pa[1] - pb[1]) < model.merge_lateral_m
                and rng.uniform() < model.merge_probability
            ):
                merged |= {va.id, vb.id}
                vel = 0.5 * (in_range[va.id].velocity_mps + in_range[vb.id].velocity_mps)
                emit(va.id, 0.5 * (pa + pb), vel, max(va.radar_rcs_dbsm, vb.radar_rcs_dbsm))
                seen.add(vb.id)
    for v in detected:
        if v.id in merged:
            continue
        view = in_range[v.id]
        near = view.near_m[:2]
        # unit vector to the left of the line of sight
        across = np.array([-near[1], near[0]]) / max(float(np.hypot(*near)), 1e-6)
        points = (
            1
            + int(v.cls != "car" and rng.uniform() < model.extra_point_probability)
            + int(v.cls == "truck" and rng.uniform() < 0.4)
        )
        for _ in range(points):
            if rng.uniform() < model.off_object_probability:
                offset = float(rng.choice([-1.0, 1.0])) * (v.width_m / 2 + rng.uniform(0.2, 0.8))
            else:
                offset = float(
                    np.clip(rng.normal(0, model.lateral_sigma_m), -v.width_m / 2, v.width_m / 2)
                )
            emit(v.id, near + offset * across, view.velocity_mps, v.radar_rcs_dbsm)
    for p in scene.pedestrians:
        view = views.get(p.id)
        if (
            view is not None
            and view.visible_fraction > 0.3
            and rng.uniform() < model.pedestrian_probability
        ):
            emit(p.id, view.near_m[:2], view.velocity_mps, p.radar_rcs_dbsm)
    for o in scene.statics:
        view = views.get(o.id)
        prob = model.tree_probability if o.cls == "tree" else model.clutter_probability
        if view is not None and view.visible_fraction > 0.3 and rng.uniform() < prob:
            emit(o.id, view.near_m[:2], np.zeros(2), o.radar_rcs_dbsm)
    # many slow returns along guard rails (paper 002 fig. 8)
    for _, xy in rail_points:
        if rng.uniform() < model.rail_point_probability:
            across = np.array([-xy[1], xy[0]]) / max(float(np.hypot(*xy)), 1e-6)
            emit(0, xy + rng.normal(0, model.rail_lateral_sigma_m) * across, np.zeros(2), 8.0)
    for _ in range(rng.poisson(model.false_alarms_per_scan)):
        r = rng.uniform(5.0, model.max_range_m)
        a = rng.uniform(-model.half_fov_rad, model.half_fov_rad)
        emit(
            0,
            np.array([mount.x_m + r * math.cos(a), mount.y_m + r * math.sin(a)]),
            np.zeros(2),
            -5.0,
        )
    return targets, seen


# --- body pitch ------------------------------------------------------------------------------

SUSPENSION_TIME_S = 0.25  # the body's pitch follows braking with this lag
ROUGHNESS_FULL_SPEED_MPS = 15.0  # road roughness reaches full amplitude at this speed


def pitch_profile(
    scene: Scene, calibrated_pitch_rad: float, t_s: FloatArray, rng: np.random.Generator
) -> FloatArray:
    """True camera pitch (rad, positive nose down) at t_s: calibration, roughness, braking."""
    fine_t = np.arange(0.0, float(t_s.max()) + 1.0, 0.01)
    speed = np.array([scene.ego_speed_mps(float(t)) for t in fine_t])
    accel = np.gradient(speed, fine_t)
    brake = np.zeros_like(accel)
    alpha = 0.01 / SUSPENSION_TIME_S
    for k in range(1, len(accel)):
        brake[k] = brake[k - 1] + alpha * (-accel[k] - brake[k - 1])
    f1, f2 = rng.uniform(1.0, 1.4), rng.uniform(1.5, 2.0)
    ph1, ph2 = rng.uniform(0, 2 * math.pi, size=2)
    rough = 0.65 * np.sin(2 * math.pi * f1 * fine_t + ph1) + 0.35 * np.sin(
        2 * math.pi * f2 * fine_t + ph2
    )
    amp = scene.pitch_roughness_rad * np.clip(speed / ROUGHNESS_FULL_SPEED_MPS, 0.0, 1.0)
    pitch = calibrated_pitch_rad + amp * rough + scene.pitch_per_decel_rad_per_mps2 * brake
    return np.interp(t_s, fine_t, pitch)


# --- CAN -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class CanModel:
    rate_hz: float = 50.0
    speed_sigma_mps: float = 0.03
    yaw_bias_radps: float = math.radians(-0.4)  # like the real RAV4
    yaw_sigma_radps: float = math.radians(0.12)


def vehicle_states(
    scene: Scene, rng: np.random.Generator, model: CanModel = CanModel()
) -> list[tuple[float, float, float]]:
    """(t_s, speed_mps, yaw_rate_radps) as the car's sensors report them; standing still reads
    exactly 0 m/s (wheel pulses stop) while the gyro keeps its bias and noise."""
    out = []
    for t in np.arange(0.0, scene.seconds, 1.0 / model.rate_hz):
        t = float(t)
        speed = scene.ego_speed_mps(t)
        yaw = scene.ego_yaw_rate_radps(t)
        measured_speed = (
            max(speed + rng.normal(0, model.speed_sigma_mps), 0.0) if speed > 0.05 else 0.0
        )
        out.append(
            (
                t,
                measured_speed,
                yaw + model.yaw_bias_radps + float(rng.normal(0, model.yaw_sigma_radps)),
            )
        )
    return out


# --- camera ----------------------------------------------------------------------------------

OPTICS_BLUR_SIGMA_PX = 0.6
# About 0.42 DN with rounding: small, because PNG pays for every bit of noise and the
# bundled drives must stay small.
NOISE_SIGMA_GREY = 0.3


def camera_noise(image: npt.NDArray[np.uint8], rng: np.random.Generator) -> npt.NDArray[np.uint8]:
    """Lens blur and sensor noise."""
    blurred = cv2.GaussianBlur(image.astype(np.float32), (0, 0), OPTICS_BLUR_SIGMA_PX)
    noisy = blurred + rng.normal(0, NOISE_SIGMA_GREY, size=image.shape).astype(np.float32)
    return np.clip(np.rint(noisy), 0, 255).astype(np.uint8)
