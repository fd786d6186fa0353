"""What a synthetic drive contains: the road, the ego car's motion, and every other actor.

Everything is placed in road coordinates (s along the reference line, d to its left, see
`road.py`) and moves along tabulated trajectories, so positions at any time are exact and
the renderer, the radar and the ground truth read the same numbers.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from core.synth.road import Road

FloatArray = npt.NDArray[np.float64]

TRAJECTORY_STEP_S = 0.01  # integration step of speed profiles

VehicleClass = str  # "car" | "van" | "truck"
StaticClass = str  # "pole" | "tree" | "sign"


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Road position (s, d) tabulated over time t_s (seconds from the drive's start)."""

    t_s: FloatArray
    s_m: FloatArray
    d_m: FloatArray

    def at(self, t_s: float) -> tuple[float, float]:
        return float(np.interp(t_s, self.t_s, self.s_m)), float(np.interp(t_s, self.t_s, self.d_m))

    @classmethod
    def from_speed(
        cls,
        road: Road,
        s0_m: float,
        d_m: float,
        speed_keys: Sequence[tuple[float, float]],
        seconds: float,
    ) -> Trajectory:
        """Drive along the lane at offset d_m; speed (m/s, negative = against s) linear
        between (t_s, speed_mps) keys, held outside them."""
        t = np.arange(0.0, seconds + 1.0, TRAJECTORY_STEP_S)
        kt, kv = zip(*speed_keys, strict=True)
        v = np.interp(t, kt, kv)
        s = np.empty_like(t)
        s[0] = s0_m
        for k in range(1, len(t)):
            step = 0.5 * (v[k] + v[k - 1]) * TRAJECTORY_STEP_S
            s[k] = road.advance(float(s[k - 1]), d_m, step)
        return cls(t, s, np.full_like(t, d_m))

    @classmethod
    def from_waypoints(cls, keys: Sequence[tuple[float, float, float]]) -> Trajectory:
        """Straight walking between (t_s, s_m, d_m) waypoints."""
        t, s, d = (np.asarray(col, dtype=np.float64) for col in zip(*keys, strict=True))
        return cls(t, s, d)


@dataclass(frozen=True)
class Vehicle:
    id: int
    cls: VehicleClass
    length_m: float
    width_m: float
    height_m: float
    body_grey: int  # 0..255, the paint under the scene's light
    trajectory: Trajectory
    facing_back: bool = False  # True: its front faces decreasing s (oncoming, or parked that way)
    radar_rcs_dbsm: float = 10.0


@dataclass(frozen=True)
class Pedestrian:
    id: int
    height_m: float
    shirt_grey: int
    trousers_grey: int
    trajectory: Trajectory
    radar_rcs_dbsm: float = -8.0


@dataclass(frozen=True)
class StaticObject:
    id: int
    cls: StaticClass
    s_m: float
    d_m: float
    width_m: float
    height_m: float
    grey: int
    radar_rcs_dbsm: float = 0.0


@dataclass(frozen=True)
class GuardRail:
    """A metal W-beam on posts at lateral offset d_m, present over the (s0, s1) pieces."""

    id: int
    side: str  # "left" | "right"
    d_m: float
    pieces_m: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class Marking:
    d_m: float
    kind: str  # "solid" | "dashed"
    width_m: float = 0.15


@dataclass(frozen=True)
class Surface:
    """A strip of ground between d0 and d1 with a base grey and texture strength."""

    d0_m: float
    d1_m: float
    grey: int
    texture: float  # relative amplitude of the grain


@dataclass(frozen=True)
class Patch:
    """A world-fixed dark or bright patch on the ground (tree shadow, bridge shadow, repair)."""

    s_m: float
    d_m: float
    length_m: float
    width_m: float
    factor: float  # multiplies the ground brightness
    round_shape: bool = True


@dataclass(frozen=True)
class Scene:
    """A whole synthetic drive before rendering."""

    name: str
    seconds: float
    road: Road
    ego: Trajectory
    surfaces: tuple[Surface, ...]
    markings: tuple[Marking, ...]
    crosswalks_s_m: tuple[float, ...]
    patches: tuple[Patch, ...]
    vehicles: tuple[Vehicle, ...]
    pedestrians: tuple[Pedestrian, ...]
    statics: tuple[StaticObject, ...]
    guard_rails: tuple[GuardRail, ...]
    illumination_keys: tuple[tuple[float, float], ...] = ((0.0, 1.0),)
    pitch_roughness_rad: float = 0.0087  # about 0.5 deg, paper 001 fig. 1
    pitch_per_decel_rad_per_mps2: float = 0.0035  # nose dips ~0.2 deg per m/s^2 of braking
    sun_shadow_offset_m: tuple[float, float] = (0.6, -0.4)  # shadow displacement (ds, dd)

    def illumination(self, t_s: float) -> float:
        kt, kg = zip(*self.illumination_keys, strict=True)
        return float(np.interp(t_s, kt, kg))

    def ego_speed_mps(self, t_s: float) -> float:
        dt = 0.05
        s0, _ = self.ego.at(max(t_s - dt, 0.0))
        s1, d = self.ego.at(t_s + dt)
        span = (t_s + dt) - max(t_s - dt, 0.0)
        kappa = float(self.road.curvature(0.5 * (s0 + s1)))
        return (s1 - s0) * (1.0 - kappa * d) / span

    def ego_yaw_rate_radps(self, t_s: float) -> float:
        """True yaw rate (rad/s, positive turning left): the heading change of the ego lane."""
        dt = 0.02
        t0 = max(t_s - dt, 0.0)
        s0, _ = self.ego.at(t0)
        s1, _ = self.ego.at(t_s + dt)
        return (float(self.road.heading(s1)) - float(self.road.heading(s0))) / (t_s + dt - t0)
