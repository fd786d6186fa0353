"""A road as a centre line of piecewise-constant curvature, with curvilinear coordinates.

Road coordinates: s (m) along the centre line, d (m) to the left of it. World: a flat plane,
X/Y metres, heading psi (rad) counter-clockwise from X. The centre line is tabulated every
`STEP_M` and interpolated, which is exact enough for rendering at camera resolution.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

STEP_M = 0.25  # tabulation step of the centre line
PROJECTION_ITERATIONS = 3  # Newton steps from an along-track guess to the foot point


@dataclass(frozen=True)
class Segment:
    """A stretch of road of constant curvature (1/m, positive turning left)."""

    length_m: float
    curvature_1pm: float


@dataclass(frozen=True, eq=False)
class Road:
    """Centre line from s_start_m over the given segments; lanes and edges in d."""

    s_m: FloatArray
    x_m: FloatArray
    y_m: FloatArray
    heading_rad: FloatArray
    curvature_1pm: FloatArray

    @classmethod
    def from_segments(cls, segments: Sequence[Segment], s_start_m: float = -100.0) -> Road:
        total = sum(seg.length_m for seg in segments)
        s = np.arange(s_start_m, s_start_m + total + STEP_M, STEP_M)
        kappa = np.empty_like(s)
        edge = s_start_m
        for seg in segments:
            kappa[(s >= edge) & (s < edge + seg.length_m + 1e-9)] = seg.curvature_1pm
            edge += seg.length_m
        kappa[s >= edge] = segments[-1].curvature_1pm
        heading = np.concatenate([[0.0], np.cumsum(0.5 * (kappa[1:] + kappa[:-1]) * STEP_M)])
        heading -= np.interp(0.0, s, heading)  # heading 0 at s = 0
        x = np.concatenate([[0.0], np.cumsum(STEP_M * np.cos(0.5 * (heading[1:] + heading[:-1])))])
        y = np.concatenate([[0.0], np.cumsum(STEP_M * np.sin(0.5 * (heading[1:] + heading[:-1])))])
        x -= np.interp(0.0, s, x)
        y -= np.interp(0.0, s, y)
        return cls(s, x, y, heading, kappa)

    def curvature(self, s_m: npt.ArrayLike) -> FloatArray:
        return np.interp(np.asarray(s_m, dtype=np.float64), self.s_m, self.curvature_1pm)

    def heading(self, s_m: npt.ArrayLike) -> FloatArray:
        return np.interp(np.asarray(s_m, dtype=np.float64), self.s_m, self.heading_rad)

    def to_world(self, s_m: npt.ArrayLike, d_m: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Road (s, d) -> world (X, Y)."""
        s = np.asarray(s_m, dtype=np.float64)
        d = np.asarray(d_m, dtype=np.float64)
        psi = self.heading(s)
        X = np.interp(s, self.s_m, self.x_m) - d * np.sin(psi)
        Y = np.interp(s, self.s_m, self.y_m) + d * np.cos(psi)
        return X, Y

    def to_road(
        self, X: FloatArray, Y: FloatArray, s_guess_m: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """World (X, Y) -> road (s, d), refining an along-track guess (valid within a few
        tens of metres of the foot point, which holds for everything a camera sees)."""
        s = np.asarray(s_guess_m, dtype=np.float64).copy()
        d = np.zeros_like(s)
        for _ in range(PROJECTION_ITERATIONS):
            psi = self.heading(s)
            ex = X - np.interp(s, self.s_m, self.x_m)
            ey = Y - np.interp(s, self.s_m, self.y_m)
            c, sn = np.cos(psi), np.sin(psi)
            s = s + ex * c + ey * sn
            d = -ex * sn + ey * c
        return s, d

    def advance(self, s_m: float, d_m: float, distance_m: float) -> float:
        """Centre-line s after driving `distance_m` along the lane at offset d_m (exact for
        constant curvature over the step)."""
        kappa = float(self.curvature(s_m))
        return s_m + distance_m / max(1.0 - kappa * d_m, 1e-3)
