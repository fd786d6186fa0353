"""What the engine gets for one camera frame: the image, the radar targets, the car's motion."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from core.checks import require_grey_image
from core.ego import EgoMotion


@dataclass(frozen=True)
class RadarTarget:
    """One radar return or track, in the radar's polar frame and in the vehicle frame.

    range_m: distance from the radar; azimuth_rad: positive to the left (ROS REP 103);
    range_rate_mps: positive when the target recedes; x_m, y_m: vehicle frame (x forward,
    y left) after the radar's mounting offset; track_id: the sensor's track id, None for
    scan returns.
    """

    range_m: float
    azimuth_rad: float
    range_rate_mps: float
    amplitude: float
    x_m: float
    y_m: float
    track_id: int | None = None

    @classmethod
    def from_polar(
        cls,
        range_m: float,
        azimuth_rad: float,
        range_rate_mps: float,
        amplitude: float,
        mount_x_m: float,
        mount_y_m: float,
        mount_yaw_rad: float = 0.0,
        track_id: int | None = None,
    ) -> RadarTarget:
        """A target from the radar's own polar measurement and its mounting pose."""
        a = azimuth_rad + mount_yaw_rad
        return cls(
            range_m=range_m,
            azimuth_rad=azimuth_rad,
            range_rate_mps=range_rate_mps,
            amplitude=amplitude,
            x_m=mount_x_m + range_m * math.cos(a),
            y_m=mount_y_m + range_m * math.sin(a),
            track_id=track_id,
        )


def real_speed_mps(target: RadarTarget, ego_speed_mps: float) -> float:
    """Speed over ground along the line of sight (m/s, positive receding): the range rate
    plus the ego speed's component along the line of sight, so a static object reads 0.

    NaN when ego_speed_mps is NaN (unknown): such a target is never slow.
    """
    return target.range_rate_mps + ego_speed_mps * math.cos(target.azimuth_rad)


@dataclass(frozen=True, eq=False)
class FrameInput:
    """One camera frame with everything measured near its time.

    image: (H, W) uint8 grey, full camera frame, read-only; t_ns: camera time stamp (ns on
    the recording's clock); radar: targets of the radar scan nearest in time (radar_t_ns its
    time, None when no scan is near); speed_mps, yaw_rate_radps: the car's speed and yaw rate
    (positive turning left) at t_ns, from CAN (or the recording's stated assumptions; NaN
    when unknown); ego: the car's motion since the previous frame, None for the first frame
    or when speed is unknown.
    """

    index: int
    t_ns: int
    image: npt.NDArray[np.uint8]
    radar: tuple[RadarTarget, ...]
    radar_t_ns: int | None
    speed_mps: float
    yaw_rate_radps: float
    ego: EgoMotion | None = None

    def __post_init__(self) -> None:
        require_grey_image("image", self.image)
        self.image.flags.writeable = False
