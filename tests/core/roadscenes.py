"""Small synthetic road scenes for known-answer tests of the vision stages.

A straight, flat road with lane markings and a textured surface, rendered by the same
renderer as the bundled drives (core.synth.render) through the synthetic camera. The tests
place objects and choose the ego motion and the pitch, so they know every answer.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.synth.generate import synthetic_calibration
from core.synth.render import Renderer
from core.synth.road import Road, Segment
from core.synth.scene import (
    Marking,
    Pedestrian,
    Scene,
    StaticObject,
    Surface,
    Trajectory,
    Vehicle,
)
from core.synth.sensors import camera_noise

LANE_M = 3.6


def camera() -> CameraModel:
    """The bundled drives' camera: 640x480, 45 deg, 1.3 m high, pitch 0.01 rad, 640x300 used."""
    return synthetic_calibration().camera


def straight_road(
    *,
    seconds: float = 3.0,
    speed_mps: float = 15.0,
    markings: bool = True,
    texture: float = 0.12,
    vehicles: Sequence[Vehicle] = (),
    pedestrians: Sequence[Pedestrian] = (),
    statics: Sequence[StaticObject] = (),
) -> Scene:
    """A straight two-lane road, the ego car at constant speed in the right lane's centre line
    d = 0 (speed 0: standing still at s = 0)."""
    road = Road.from_segments([Segment(speed_mps * seconds + 800.0, 0.0)])
    ego = Trajectory.from_speed(road, 0.0, 0.0, [(0.0, speed_mps)], seconds)
    lines = (
        (
            Marking(-LANE_M / 2, "solid"),
            Marking(LANE_M / 2, "dashed"),
            Marking(3 * LANE_M / 2, "solid"),
        )
        if markings
        else ()
    )
    return Scene(
        name="test-road",
        seconds=seconds,
        road=road,
        ego=ego,
        surfaces=(
            Surface(-60.0, -LANE_M / 2 - 0.5, 90, 0.3),
            Surface(-LANE_M / 2 - 0.5, 3 * LANE_M / 2 + 0.5, 110, texture),
            Surface(3 * LANE_M / 2 + 0.5, 60.0, 90, 0.3),
        ),
        markings=lines,
        crosswalks_s_m=(),
        patches=(),
        vehicles=tuple(vehicles),
        pedestrians=tuple(pedestrians),
        statics=tuple(statics),
        guard_rails=(),
        pitch_roughness_rad=0.0,
        pitch_per_decel_rad_per_mps2=0.0,
    )


class RoadRenderer:
    """Renders frames of one scene; build once per scene (making the road texture is slow).

    The same seed gives the same road texture and the same sensor noise sequence.
    """

    def __init__(self, scene: Scene, seed: int = 0) -> None:
        self._rng = np.random.default_rng(seed)
        self._renderer = Renderer(scene, camera(), self._rng)

    def __call__(
        self, t_s: float, pitch_rad: float, noise: bool = True
    ) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint16]]:
        """(480, 640) uint8 grey image and uint16 object-label image (0 = no object) at t_s
        with the camera at `pitch_rad`."""
        frame, _, _ = self._renderer.render(t_s, pitch_rad, 1.0)
        image = camera_noise(frame.image, self._rng) if noise else frame.image
        return image, frame.labels


def standing_person(
    s_m: float, d_m: float, person_id: int = 7, height_m: float = 1.75
) -> tuple[npt.NDArray[np.uint8], tuple[float, float, float, float]]:
    """A standing car's noise-free view of a person standing s_m ahead, d_m to the left, on
    a road without markings, and the person's true box (u0, v0, u1, v1) from the labels."""
    standing = Trajectory.from_waypoints([(0.0, s_m, d_m), (10.0, s_m, d_m)])
    person = Pedestrian(person_id, height_m, 150, 40, standing)
    scene = straight_road(speed_mps=0.0, markings=False, pedestrians=(person,))
    image, labels = RoadRenderer(scene)(0.0, camera().extrinsics.pitch_rad, noise=False)
    rows, cols = np.nonzero(labels == person_id)
    box = (float(cols.min()), float(rows.min()), float(cols.max() + 1), float(rows.max() + 1))
    return image, box


def two_frames(
    ego_speed_mps: float,
    person_speed_mps: float,
    ahead_m: float = 12.0,
    left_m: float = 3.0,
    dt_s: float = 0.1,
    person_id: int = 7,
) -> tuple[npt.NDArray[np.uint8], npt.NDArray[np.uint8], tuple[float, float, float, float]]:
    """(previous frame, this frame, the person's true box on this frame) of a person who
    walks along the road at person_speed_mps while the car drives at ego_speed_mps."""
    start = (0.0, ahead_m, left_m)
    end = (3.0, ahead_m + 3.0 * person_speed_mps, left_m)
    person = Pedestrian(person_id, 1.75, 150, 40, Trajectory.from_waypoints([start, end]))
    scene = straight_road(speed_mps=ego_speed_mps, markings=False, pedestrians=(person,))
    render = RoadRenderer(scene)
    pitch = camera().extrinsics.pitch_rad
    previous, _ = render(0.0, pitch, noise=False)
    image, labels = render(dt_s, pitch, noise=False)
    rows, cols = np.nonzero(labels == person_id)
    box = (float(cols.min()), float(rows.min()), float(cols.max() + 1), float(rows.max() + 1))
    return previous, image, box
