"""The bundled drives open cleanly; the one where the car stands still has its gyro bias removed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS
from core.io import Drive
from core.synth.sensors import CanModel

RECORDINGS = DEFAULT_RECORDINGS


@pytest.mark.parametrize("name", ["highway", "exurban", "stop_and_go"])
def test_bundled_drive_opens_without_warnings(name: str) -> None:
    with Drive(RECORDINGS / name) as drive:
        assert drive.warnings == ()
        assert len(drive) == 150
        assert drive.frame(149).ego is not None


def test_gyro_bias_estimated_while_standing_still() -> None:
    with Drive(RECORDINGS / "stop_and_go") as drive:
        v = drive.vehicle_signals
        assert drive.manifest.can is not None
        assert drive.manifest.can.yaw_rate_bias == "standstill"
    assert v.standstill_s >= 1.0
    # The synthetic gyro reads its bias in 0.244 deg/s steps with noise: within a tenth of one.
    assert v.yaw_rate_bias_radps == pytest.approx(
        CanModel().yaw_bias_radps, abs=math.radians(0.0244)
    )
    still = drive.vehicle_signals.speed_at(v.yaw_rate_t_ns) < 0.05
    assert abs(np.mean(v.yaw_rate_radps[still])) < 1e-9
