"""`fusionscope synth`: build a scenario, render it, simulate the sensors, write a recording.

The camera is the papers' (paper 001: grey, 45 deg aperture, 640x480 of which 640x300 are
processed; paper 002: 10 fps), mounted behind the windscreen; the radar sits above the front
bumper. One seed gives the same bytes: every random draw comes from generators spawned from
it, one per concern, in a fixed order.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.io.calibration import Calibration, RadarMount
from core.io.canlog import MIN_STANDSTILL_S, STANDSTILL_SPEED_MPS
from core.io.groundtruth import FrameTruth
from core.io.writer import RecordingWriter
from core.synth.render import Renderer
from core.synth.scenarios import SCENARIOS
from core.synth.sensors import camera_noise, pitch_profile, radar_scan, vehicle_states

FRAME_RATE_HZ = 10.0  # paper 002: "sampled at 10 fps"
IMAGE_SIZE_PX = (640, 480)  # paper 001
HORIZONTAL_FOV_RAD = math.radians(45.0)  # paper 001: "the camera aperture is 45 deg"
ROWS_USED_PX = (130, 430)  # 640x300 of 640x480, horizon near the top third of the window
CAMERA_HEIGHT_M = 1.3
CAMERA_X_M = 1.4  # behind the windscreen, ahead of the rear axle (the vehicle-frame origin)
CAMERA_PITCH_RAD = 0.01  # calibrated: slightly nose down
RADAR_MOUNT = RadarMount(x_m=3.6, y_m=0.0, z_m=0.5)  # above the front bumper
START_NS = 1_767_225_600_000_000_000  # 2026-01-01T00:00:00Z: a fixed, realistic epoch
MAX_SECONDS = 600.0

Progress = Callable[[int, int], None]


def synthetic_calibration() -> Calibration:
    intrinsics = Intrinsics.from_fov(*IMAGE_SIZE_PX, HORIZONTAL_FOV_RAD)
    extrinsics = Extrinsics(height_m=CAMERA_HEIGHT_M, x_m=CAMERA_X_M, pitch_rad=CAMERA_PITCH_RAD)
    return Calibration(
        camera=CameraModel(intrinsics, extrinsics, ROWS_USED_PX), radar_mount=RADAR_MOUNT
    )


def generate(
    scenario: str,
    seconds: float,
    seed: int,
    out_dir: Path | str,
    progress: Progress | None = None,
) -> Path:
    """Write the recording of `scenario` lasting `seconds` into `out_dir` (new or empty)."""
    if scenario not in SCENARIOS:
        raise ValueError(f"scenario: expected one of {', '.join(SCENARIOS)}, got {scenario!r}")
    if not (0 < seconds <= MAX_SECONDS) or not math.isfinite(seconds):
        raise ValueError(f"seconds: expected a duration in (0, {MAX_SECONDS:g}], got {seconds}")
    if seed < 0:
        raise ValueError(f"seed: expected an integer >= 0, got {seed}")
    scene_rng, texture_rng, pitch_rng, radar_rng, can_rng, noise_rng = np.random.default_rng(
        seed
    ).spawn(6)
    scene = SCENARIOS[scenario](seconds, scene_rng)
    calibration = synthetic_calibration()
    renderer = Renderer(scene, calibration.camera, texture_rng)
    n_frames = max(round(seconds * FRAME_RATE_HZ), 1)
    t_s = np.arange(n_frames) / FRAME_RATE_HZ
    pitch = pitch_profile(scene, CAMERA_PITCH_RAD, t_s, pitch_rng)
    can_states = vehicle_states(scene, can_rng)
    truths: list[FrameTruth] = []
    out = Path(out_dir)
    generator = {"scenario": scenario, "seconds": float(seconds), "seed": int(seed)}
    description = (SCENARIOS[scenario].__doc__ or scenario).strip()
    # Where the car stands still long enough, the manifest asks for the gyro's bias to be
    # estimated there (core.io.canlog), as an engineer would for a real drive.
    can_period_s = can_states[1][0] - can_states[0][0] if len(can_states) > 1 else 0.0
    still_s = sum(can_period_s for _, speed, _ in can_states if speed < STANDSTILL_SPEED_MPS)
    with RecordingWriter(
        out,
        name=out.name,
        calibration=calibration,
        description=description,
        generator=generator,
        yaw_rate_bias="standstill" if still_s >= MIN_STANDSTILL_S else "none",
    ) as writer:
        for k, t in enumerate(t_s):
            t = float(t)
            t_ns = START_NS + round(t * 1e9)
            frame, rail_points, views = renderer.render(t, float(pitch[k]), scene.illumination(t))
            writer.add_image(t_ns, camera_noise(frame.image, noise_rng))
            speed = scene.ego_speed_mps(t)
            yaw_rate = scene.ego_yaw_rate_radps(t)
            targets, seen = radar_scan(
                scene, views, rail_points, speed, yaw_rate, calibration.radar_mount, radar_rng
            )
            writer.add_radar_scan(t_ns, targets)
            objects = tuple(
                o if o.id not in seen else replace(o, radar_seen=True) for o in frame.objects
            )
            truths.append(FrameTruth(k, t_ns, float(pitch[k]), objects, frame.guard_rails))
            if progress is not None:
                progress(k + 1, n_frames)
        for t, speed, yaw_rate in can_states:
            writer.add_vehicle_state(START_NS + round(t * 1e9), speed, yaw_rate)
        writer.set_groundtruth(truths)
    return out
