"""CAN decoding: short frames are padded, real Toyota RAV4 data decodes to plausible values."""

from __future__ import annotations

import math
from pathlib import Path

import can
import numpy as np
import pytest

from core.io.canlog import (
    SPEED_UNITS_TO_MPS,
    YAW_RATE_UNITS_TO_RADPS,
    SignalMapping,
    read_vehicle_signals,
)
from core.io.writer import vehicle_dbc_path

SPEED = SignalMapping("SPEED", "SPEED", "km/h", SPEED_UNITS_TO_MPS["km/h"])
YAW_RATE = SignalMapping("KINEMATICS", "YAW_RATE", "deg/s", YAW_RATE_UNITS_TO_RADPS["deg/s"])


def test_short_frames_are_padded_and_unknown_ids_skipped(tmp_path: Path) -> None:
    log = tmp_path / "short.log"
    with can.CanutilsLogWriter(str(log), channel="can0") as w:
        # SPEED 0xB4: SPEED is bytes 5-6 big-endian; 0x2710 = 10000 -> 100.00 km/h.
        w.on_message_received(
            can.Message(
                timestamp=1.0,
                arbitration_id=0xB4,
                data=bytes([0, 0, 0, 0, 0, 0x27, 0x10]),
                is_extended_id=False,
            )
        )  # 7 of 8 bytes
        # KINEMATICS 0x24 with one byte: YAW_RATE bits all in byte 0 and 1 -> padded.
        w.on_message_received(
            can.Message(
                timestamp=1.5, arbitration_id=0x24, data=bytes([0x00]), is_extended_id=False
            )
        )
        w.on_message_received(
            can.Message(timestamp=2.0, arbitration_id=0x123, data=bytes(8), is_extended_id=False)
        )
    s = read_vehicle_signals(log, [vehicle_dbc_path()], SPEED, YAW_RATE)
    np.testing.assert_array_equal(s.speed_t_ns, [1_000_000_000])
    assert s.speed_mps[0] == pytest.approx(100.0 / 3.6)
    np.testing.assert_array_equal(s.yaw_rate_t_ns, [1_500_000_000])
    assert s.yaw_rate_radps[0] == 0.0


def test_sign_and_interpolation(tmp_path: Path) -> None:
    log = tmp_path / "v.log"
    kin = vehicle_dbc_path()
    import cantools

    db = cantools.database.load_file(str(kin))
    msg = db.get_message_by_name("KINEMATICS")  # type: ignore[union-attr]
    with can.CanutilsLogWriter(str(log), channel="can0") as w:
        for t, degs in ((0.0, 0.0), (1.0, 2.44)):
            w.on_message_received(
                can.Message(
                    timestamp=t,
                    arbitration_id=0x24,
                    data=msg.encode({"YAW_RATE": degs}),
                    is_extended_id=False,
                )
            )
    flipped = SignalMapping("KINEMATICS", "YAW_RATE", "deg/s", math.pi / 180, sign=-1)
    s = read_vehicle_signals(log, [kin], SPEED, flipped)
    assert s.yaw_rate_at(500_000_000) == pytest.approx(-math.radians(1.22))
    assert s.yaw_rate_at(5_000_000_000) == pytest.approx(-math.radians(2.44))  # held past the end
    assert np.isnan(s.speed_at(0))  # no SPEED frames


def test_real_rav4_log_decodes_to_plausible_values(realdata: Path) -> None:
    d = realdata / "comma2k19-rav4"
    s = read_vehicle_signals(
        d / "rav4_seg40.log.gz",
        [d / "toyota_rav4_powertrain.dbc"],
        SPEED,
        YAW_RATE,
        channel="can0",
    )
    duration_s = (s.speed_t_ns[-1] - s.speed_t_ns[0]) / 1e9
    assert 55.0 < duration_s < 61.0
    assert len(s.speed_t_ns) / duration_s == pytest.approx(41.0, abs=1.5)
    assert len(s.yaw_rate_t_ns) / duration_s == pytest.approx(83.0, abs=2.0)
    # I-280 traffic: between 25 and 80 km/h throughout, never backwards.
    assert 7.0 < s.speed_mps.min() and s.speed_mps.max() < 23.0
    # Yaw rate: the README's bias of about -0.4 deg/s, in 0.244 deg/s steps from -125 deg/s.
    assert np.degrees(np.median(s.yaw_rate_radps)) == pytest.approx(-0.4, abs=0.3)
    steps = (np.degrees(s.yaw_rate_radps) + 125.0) / 0.244
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
