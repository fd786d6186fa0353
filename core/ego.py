"""The car's motion between two instants from speed and yaw rate (paper 000, eq. 3-5).

The car is a point at its rotation centre moving with speed v along its heading Gamma, which
turns at the yaw rate gamma. With v and gamma constant over an interval of length T,

    S      = 2 v / gamma * sin(gamma T / 2)      (-> v T as gamma -> 0)      eq. (5)
    dx     = S cos(Gamma0 + gamma T / 2)
    dy     = S sin(Gamma0 + gamma T / 2)                                     eq. (4)
    Gamma  = Gamma0 + gamma T

`step` is one such interval. `integrate` goes further than the paper, which holds v and gamma
constant between two camera frames: it cuts the frame interval at every CAN sample in between
and chains eq. (4) over the pieces, each piece with the mean of the linearly interpolated
signals over it, so a car braking or entering a curve between two frames is followed.

Frame: the vehicle frame at the start instant (x forward, y left, yaw positive to the left).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
import numpy.typing as npt

from core.checks import require_finite

NS_PER_S = 1_000_000_000
XY = TypeVar("XY", float, npt.NDArray[np.float64])
# A car whose speed reads below this stands still (wheel-speed sensors read 0 below ~0.1 m/s).
STANDSTILL_SPEED_MPS = 0.05


@dataclass(frozen=True)
class EgoMotion:
    """Where the car went between two instants, in the vehicle frame at the first.

    dx_m forward, dy_m left, dyaw_rad positive turning left; dt_s the interval; pieces the
    number of constant-velocity pieces integrated (1: the paper's single interval).
    """

    dx_m: float
    dy_m: float
    dyaw_rad: float
    dt_s: float
    pieces: int = 1

    def __post_init__(self) -> None:
        for name in ("dx_m", "dy_m", "dyaw_rad", "dt_s"):
            require_finite(name, getattr(self, name))
        if self.dt_s < 0:
            raise ValueError(f"dt_s: expected an interval >= 0, got {self.dt_s}")

    @classmethod
    def still(cls, dt_s: float = 0.0) -> EgoMotion:
        return cls(0.0, 0.0, 0.0, dt_s, 1)

    def carry(self, x_m: XY, y_m: XY) -> tuple[XY, XY]:
        """Points standing still in the world (floats or arrays), from the vehicle frame at
        the first instant into the one at the second: R(-dyaw) (p - (dx, dy))."""
        cos, sin = math.cos(-self.dyaw_rad), math.sin(-self.dyaw_rad)
        dx, dy = x_m - self.dx_m, y_m - self.dy_m
        return cos * dx - sin * dy, sin * dx + cos * dy


def chord_length_m(speed_mps: float, yaw_rate_radps: float, dt_s: float) -> float:
    """Eq. (5): S = 2 v / gamma * sin(gamma T / 2), written as v T sinc(gamma T / 2).

    The sinc form has no division, so it is exact and continuous through gamma = 0.
    ValueError naming the argument when one is not finite (an unknown yaw rate is NaN).
    """
    for name, value in (
        ("speed_mps", speed_mps),
        ("yaw_rate_radps", yaw_rate_radps),
        ("dt_s", dt_s),
    ):
        require_finite(name, value)
    half_turn_rad = yaw_rate_radps * dt_s / 2.0
    return speed_mps * dt_s * float(np.sinc(half_turn_rad / math.pi))


def step(
    speed_mps: float, yaw_rate_radps: float, dt_s: float, heading0_rad: float = 0.0
) -> EgoMotion:
    """Eq. (4)-(5) over one interval with constant speed and yaw rate.

    heading0_rad: Gamma0, the heading at the start relative to the frame the result is in.
    The result's dyaw_rad is the turn over the interval (Gamma - Gamma0).
    """
    s_m = chord_length_m(speed_mps, yaw_rate_radps, dt_s)
    mid_rad = heading0_rad + yaw_rate_radps * dt_s / 2.0
    return EgoMotion(
        s_m * math.cos(mid_rad), s_m * math.sin(mid_rad), yaw_rate_radps * dt_s, dt_s, 1
    )


def _piecewise_mean(
    edges_ns: npt.NDArray[np.int64], t_ns: npt.NDArray[np.int64], values: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """Mean over each [edges[k], edges[k+1]] of the linear interpolation of (t_ns, values).

    The pieces are cut at every sample, so the interpolation is linear inside each piece and
    its mean is the value at the piece's midpoint. Held constant past the ends.
    """
    origin = edges_ns[0]
    mid = ((edges_ns[:-1] - origin) + (edges_ns[1:] - origin)) / 2.0
    return np.interp(mid, (t_ns - origin).astype(np.float64), values)


def samples_around(
    t_ns: npt.NDArray[np.int64], values: npt.NDArray[np.float64], t0_ns: int, t1_ns: int
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """The samples inside (t0, t1) and the one on each side: all interpolation there needs.

    Keeps a long drive's per-frame cost independent of its length.
    """
    lo = max(int(np.searchsorted(t_ns, t0_ns, side="right")) - 1, 0)
    hi = min(int(np.searchsorted(t_ns, t1_ns, side="left")) + 1, len(t_ns))
    return t_ns[lo:hi], values[lo:hi]


def integrate(
    t0_ns: int,
    t1_ns: int,
    speed_t_ns: npt.NDArray[np.int64],
    speed_mps: npt.NDArray[np.float64],
    yaw_rate_t_ns: npt.NDArray[np.int64],
    yaw_rate_radps: npt.NDArray[np.float64],
) -> EgoMotion:
    """Motion from t0_ns to t1_ns, eq. (4) chained over every speed or yaw-rate sample between.

    Each signal is interpolated linearly between its samples and held past its ends; the
    stamps must be ascending. ValueError when t1_ns < t0_ns or a signal has no samples.
    """
    if t1_ns < t0_ns:
        raise ValueError(f"t1_ns: expected >= t0_ns = {t0_ns}, got {t1_ns}")
    if len(speed_t_ns) == 0 or len(yaw_rate_t_ns) == 0:
        raise ValueError("speed and yaw rate: expected at least one sample each, got none")
    speed_t_ns, speed_mps = samples_around(speed_t_ns, speed_mps, t0_ns, t1_ns)
    yaw_rate_t_ns, yaw_rate_radps = samples_around(yaw_rate_t_ns, yaw_rate_radps, t0_ns, t1_ns)
    inner = np.concatenate((speed_t_ns, yaw_rate_t_ns))
    inner = np.unique(inner[(inner > t0_ns) & (inner < t1_ns)])
    edges = np.concatenate(([t0_ns], inner, [t1_ns])).astype(np.int64)
    if len(edges) == 2 and t0_ns == t1_ns:
        return EgoMotion.still()
    v = _piecewise_mean(edges, speed_t_ns, speed_mps)
    w = _piecewise_mean(edges, yaw_rate_t_ns, yaw_rate_radps)
    dt = np.diff(edges) / NS_PER_S
    x = y = heading = 0.0
    for v_k, w_k, dt_k in zip(v, w, dt, strict=True):
        piece = step(float(v_k), float(w_k), float(dt_k), heading)
        x += piece.dx_m
        y += piece.dy_m
        heading += piece.dyaw_rad
    return EgoMotion(x, y, heading, (t1_ns - t0_ns) / NS_PER_S, len(dt))
