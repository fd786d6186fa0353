"""Radar measurements of a whole drive, one row per return, grouped by scan."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Int64Array = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]

# What no automotive radar reports: beyond 1 km (the longest-range units reach about 300 m),
# outside a half-turn of azimuth, faster than 300 m/s (1,080 km/h) along the line of sight.
# A return outside these (3e38 m from a garbled float) is damage, dropped like a NaN.
MAX_RANGE_M = 1_000.0
MAX_ABS_RANGE_RATE_MPS = 300.0
_PI_FLOAT32 = float(np.float32(math.pi))  # +-pi as a float32 message field holds it


def plausible(
    range_m: FloatArray, azimuth_rad: FloatArray, range_rate_mps: FloatArray
) -> npt.NDArray[np.bool_]:
    """(R,) bool: the returns whose finite values a radar could report (see MAX_RANGE_M);
    a NaN range rate counts as not measured and passes."""
    with np.errstate(invalid="ignore"):
        return (
            np.isfinite(range_m)
            & (range_m >= 0.0)
            & (range_m <= MAX_RANGE_M)
            & (np.abs(azimuth_rad) <= _PI_FLOAT32)
            & ~(np.abs(range_rate_mps) > MAX_ABS_RANGE_RATE_MPS)
            & ~np.isinf(range_rate_mps)
        )


@dataclass(frozen=True, eq=False)
class RadarScans:
    """All radar messages of a topic, one row per return, grouped by scan.

    t_ns: (S,) int64 scan time stamps, ascending; start: (S + 1,) int64, returns of scan k
    are rows start[k]:start[k + 1]; range_m, azimuth_rad (positive left), range_rate_mps
    (positive receding), amplitude: (R,) float64; track_id: (R,) int64, -1 for scan returns.
    """

    t_ns: Int64Array
    start: Int64Array
    range_m: FloatArray
    azimuth_rad: FloatArray
    range_rate_mps: FloatArray
    amplitude: FloatArray
    track_id: Int64Array

    @property
    def median_period_ns(self) -> float:
        """Median time between scans (ns); inf with fewer than two scans."""
        if len(self.t_ns) < 2:
            return math.inf
        return float(np.median(np.diff(self.t_ns)))
