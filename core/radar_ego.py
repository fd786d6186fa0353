"""Ego speed from the radar itself: the stationary world's radial speeds (beyond the papers).

A radar on a car moving forward at v (yaw rate ignored, see Notes) sees every stationary
return approach at its radial speed

    range_rate = -v * cos(a),    a = azimuth + the radar's mounting yaw (vehicle frame),

while moving returns (traffic) do not fit that line. Per scan the fit is a one-point
consensus (RANSAC with every return as a hypothesis, exhaustively, since scans hold tens
of returns): each return with cos(a) >= `min_cos` proposes v = -range_rate / cos(a); the
proposal that the most distinct positions agree with (|range_rate + v cos a| <=
`tolerance_mps`; returns closer than `same_position_m` to an earlier agreeing one count
once, see Notes) wins, and v is refitted by least squares over all its agreeing returns. A
scan with fewer than `min_stationary` agreeing positions gives no speed (NaN). Over a
drive, the per-scan speeds are then cleaned by a running median over `median_scans` scans,
which removes the scans where a platoon of traffic outvoted the roadside.

Used for drives without CAN speed: `fusionscope import bag --ego-from-radar`
(core/io/importers/finish.py write_ego_from_radar) and `fusionscope import aimotive` (the
sample has no ego-motion file).

Notes:
    The yaw rate is not estimated: it would be the lateral velocity of the radar
    (omega * the radar's x offset) fitted beside v, about 0.08 m/s at 0.02 rad/s for a
    radar 3.8 m ahead, below the range-rate noise of a single scan. Importers write a yaw
    rate of 0 and say so.

    Support is counted in distinct positions, not returns: one vehicle gives several
    returns at one place (a truck's rear, a point beside it), and in sparse scans (the
    synthetic stop_and_go drive: 3-8 returns, mostly on vehicles) those outvoted the
    roadside. Measured against the bundled drives' CAN speed, over the scans with a speed
    after the running median (error median / p95 / max, m/s), counting returns -> counting
    positions 1 m apart:
        highway      100 % of scans  0.022 / 0.17 / 0.75  ->  100 %  0.024 / 0.18 / 0.51
        exurban       76 %           0.033 / 0.09 / 0.13  ->   76 %  0.032 / 0.10 / 0.13
        stop_and_go   40 %           0.078 / 6.1  / 9.0   ->   20 %  0.019 / 0.48 / 0.70
    and the aiMotive night-motorway sample (../shared/realdata, 26-55 returns a scan, the
    car at ~30 m/s) keeps a speed on all 50 scans, 29.89-30.13 m/s either way. stop_and_go
    loses its wrong fits (a truck's returns and a platoon outvoting two roadside posts) at
    the price of half its fits: most of its scans still have no speed, as they hold fewer
    than four stationary positions, and its 0.5 m/s errors are the running median carrying
    a lone fit over the scans beside it while the car brakes. A platoon of vehicles at one
    speed, each at its own position, still looks like a stationary world to a single scan;
    nothing in one scan tells them apart.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from core.checks import require_finite

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class RadarEgoParams:
    """min_cos: returns further off-axis than acos(min_cos) propose no speed (their
    -range_rate / cos(a) blows up); tolerance_mps: a return agrees with a speed when its
    range rate is within this of -v cos(a); min_stationary: distinct positions of agreeing
    returns a scan needs; same_position_m: an agreeing return closer than this to an
    earlier one (in the scan's order) adds no support: one vehicle's returns lie within
    about a metre of each other (core/synth/sensors.py: 0.4 m lateral spread), guard-rail
    and roadside returns further apart (1.5 m gives the same speeds as 1 m on the bundled
    drives but one exurban fit fewer, 2 m merges guard-rail returns: 72 % of exurban's
    scans fitted; Notes);
    median_scans: the running median's length over scans (odd); min_speed_mps: proposals
    below it are no hypothesis (a car does not reverse on a drive; the margin takes the
    noise of a standing car), so traffic pulling away from a standing car, which recedes
    with no stationary return to outvote it, gives no speed rather than a negative one."""

    min_cos: float = 0.5
    tolerance_mps: float = 0.5
    min_stationary: int = 4
    same_position_m: float = 1.0
    median_scans: int = 5
    min_speed_mps: float = -0.5

    def __post_init__(self) -> None:
        if not 0.0 < self.min_cos <= 1.0:
            raise ValueError(f"min_cos: expected a cosine in (0, 1], got {self.min_cos}")
        if not (math.isfinite(self.tolerance_mps) and self.tolerance_mps > 0):
            raise ValueError(f"tolerance_mps: expected > 0 m/s, got {self.tolerance_mps}")
        if self.min_stationary < 2:
            raise ValueError(f"min_stationary: expected >= 2 positions, got {self.min_stationary}")
        if not (math.isfinite(self.same_position_m) and self.same_position_m >= 0):
            raise ValueError(f"same_position_m: expected >= 0 m, got {self.same_position_m}")
        if self.median_scans < 1 or self.median_scans % 2 == 0:
            raise ValueError(f"median_scans: expected an odd count >= 1, got {self.median_scans}")
        require_finite("min_speed_mps", self.min_speed_mps)


@dataclass(frozen=True)
class ScanSpeed:
    """One scan's fit: speed_mps (NaN: too few stationary positions), the (N,) mask of the
    returns taken as stationary, and support: the distinct positions among them."""

    speed_mps: float
    stationary: npt.NDArray[np.bool_]
    support: int


def _returns(
    range_rate_mps: npt.ArrayLike,
    azimuth_rad: npt.ArrayLike,
    range_m: npt.ArrayLike | None,
    mount_yaw_rad: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(N,) float64 range rates, azimuths and ranges (NaN when None), checked."""
    rr = np.asarray(range_rate_mps, dtype=np.float64).ravel()
    az = np.asarray(azimuth_rad, dtype=np.float64).ravel()
    rg = np.full(rr.size, np.nan) if range_m is None else np.asarray(range_m, np.float64).ravel()
    if not rr.shape == az.shape == rg.shape:
        raise ValueError(
            "range_rate_mps, azimuth_rad, range_m: expected as many of each, got "
            f"{rr.size}, {az.size} and {rg.size}"
        )
    require_finite("mount_yaw_rad", mount_yaw_rad)
    return rr, az, rg


def speed_from_scan(
    range_rate_mps: npt.ArrayLike,
    azimuth_rad: npt.ArrayLike,
    mount_yaw_rad: float = 0.0,
    params: RadarEgoParams = RadarEgoParams(),
    *,
    range_m: npt.ArrayLike | None = None,
) -> ScanSpeed:
    """The car's forward speed (m/s) from one scan's (N,) range rates (positive receding),
    azimuths (rad, positive left, in the radar's frame) and ranges (m; None: every return is
    a position of its own); see the module docstring."""
    rr, az, rg = _returns(range_rate_mps, azimuth_rad, range_m, mount_yaw_rad)
    cos_a = np.cos(az + mount_yaw_rad)
    usable = np.isfinite(rr) & np.isfinite(cos_a)
    proposing = usable & (cos_a >= params.min_cos)
    none = ScanSpeed(math.nan, np.zeros(rr.size, dtype=bool), 0)
    if int(proposing.sum()) < params.min_stationary:
        return none
    proposals = -rr[proposing] / cos_a[proposing]  # (P,)
    proposals = proposals[proposals >= params.min_speed_mps]
    if proposals.size == 0:
        return none
    rr_u, cos_u = np.where(usable, rr, np.inf), np.where(usable, cos_a, 0.0)
    residual = np.abs(rr_u[None, :] + proposals[:, None] * cos_u[None, :])  # (P, N)
    agree = residual <= params.tolerance_mps
    # a return repeats a position when an earlier agreeing return lies within same_position_m
    xy = rg[:, None] * np.stack([np.cos(az), np.sin(az)], axis=1)  # (N, 2), radar frame
    gap = np.linalg.norm(xy[:, None, :] - xy[None, :, :], axis=2)  # (N, N); NaN: no range
    near_earlier = (gap < params.same_position_m) & np.tri(rr.size, k=-1, dtype=bool)
    repeats = (agree.astype(np.int64) @ near_earlier.T.astype(np.int64)) > 0  # (P, N)
    counts = (agree & ~repeats).sum(axis=1)
    best = int(counts.max())
    if best < params.min_stationary:
        return none
    # among the proposals with the most support, the one with the smallest summed residual
    tied = np.flatnonzero(counts == best)
    spread = np.where(agree[tied], residual[tied], 0.0).sum(axis=1)
    inliers = agree[tied[int(np.argmin(spread))]]
    c = cos_a[inliers]
    speed = float(-(rr[inliers] @ c) / (c @ c))
    return ScanSpeed(speed, inliers, best)


def running_median(values: npt.ArrayLike, length: int) -> FloatArray:
    """(N,) the median of each value's `length` neighbours (odd; fewer at the ends),
    NaN-ignoring; NaN only where every neighbour is NaN."""
    v = np.asarray(values, dtype=np.float64).ravel()
    half = length // 2
    out = np.full(v.size, np.nan)
    for k in range(v.size):
        window = v[max(0, k - half) : k + half + 1]
        window = window[np.isfinite(window)]
        if window.size:
            out[k] = float(np.median(window))
    return out


def speeds_from_scans(
    range_rate_mps: npt.ArrayLike,
    azimuth_rad: npt.ArrayLike,
    scan_start: npt.ArrayLike,
    mount_yaw_rad: float = 0.0,
    params: RadarEgoParams = RadarEgoParams(),
    *,
    range_m: npt.ArrayLike | None = None,
) -> FloatArray:
    """(S,) speed (m/s) per scan, cleaned by the running median (module docstring).

    range_rate_mps, azimuth_rad, range_m: (R,) all returns (range_m None: every return is a
    position of its own); scan_start: (S + 1,) returns of scan k are rows
    scan_start[k]:scan_start[k + 1] (as core.io.radarscans.RadarScans). NaN for scans with
    no fit and none near.
    """
    rr, az, rg = _returns(range_rate_mps, azimuth_rad, range_m, mount_yaw_rad)
    start = np.asarray(scan_start, dtype=np.int64).ravel()
    if start.size < 1 or start[0] != 0 or start[-1] != rr.size or np.any(np.diff(start) < 0):
        raise ValueError(
            f"scan_start: expected ascending row offsets from 0 to {rr.size}, got {start.size} "
            "offsets that are not"
        )
    raw = np.array(
        [
            speed_from_scan(rr[a:b], az[a:b], mount_yaw_rad, params, range_m=rg[a:b]).speed_mps
            for a, b in itertools.pairwise(start)
        ]
    )
    return running_median(raw, params.median_scans)
