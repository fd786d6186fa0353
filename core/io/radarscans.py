"""Radar measurements of a whole drive, one row per return, grouped by scan."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

Int64Array = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]


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
