"""Speed and yaw rate from CAN: dispatch, padding, signs, time order, outliers, yaw-rate bias,
warnings that name what is missing, and the real Toyota RAV4 log."""

from __future__ import annotations

import math
import struct
import time
from pathlib import Path

import can
import numpy as np
import pytest
from cantools.database.can import Database

from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.canlog import (
    SPEED_UNITS_TO_MPS,
    YAW_RATE_UNITS_TO_RADPS,
    SignalMapping,
    VehicleSignalDecoder,
    VehicleSignals,
    decode_frames,
    load_dbc,
    read_vehicle_signals,
)
from core.io.errors import RecordingError
from core.io.manifest import CanBus, CanSource
from core.io.writer import SPEED_SIGNAL, YAW_RATE_SIGNAL, vehicle_dbc_path

SPEED = SPEED_SIGNAL
YAW_RATE = YAW_RATE_SIGNAL
NS = 1_000_000_000

# Speed as in the RAV4 (0.01 km/h), yaw rate finer than the RAV4's 0.244 deg/s so that a
# -0.4 deg/s bias is exact; a float signal (for NaN) and a multiplexed message.
TEST_DBC = """VERSION ""

NS_ :

BS_:

BU_: XXX

BO_ 180 SPEED: 8 XXX
 SG_ SPEED : 47|16@0+ (0.01,0) [0|655.35] "km/h" XXX

BO_ 36 KINEMATICS: 8 XXX
 SG_ YAW_RATE : 7|16@0- (0.01,0) [-327.68|327.67] "deg/s" XXX

BO_ 37 GYRO_F: 4 XXX
 SG_ YAW_F : 7|32@0- (1,0) [0|0] "deg/s" XXX

BO_ 38 MUXED: 8 XXX
 SG_ MUX M : 7|8@0+ (1,0) [0|255] "" XXX
 SG_ A m1 : 15|8@0+ (1,0) [0|255] "km/h" XXX

SIG_VALTYPE_ 37 YAW_F : 1;
"""


@pytest.fixture(scope="module")
def db(tmp_path_factory: pytest.TempPathFactory) -> Database:
    path = tmp_path_factory.mktemp("dbc") / "test.dbc"
    path.write_text(TEST_DBC)
    return load_dbc([path])


def _source(
    channel: str | None = None,
    bias: str = "none",
    speed: SignalMapping = SPEED,
    yaw_rate: SignalMapping = YAW_RATE,
) -> CanSource:
    return CanSource(CanBus(("test.dbc",), log="x.log", channel=channel), speed, yaw_rate, bias)


def _speed(db: Database, t_s: float, kmh: float, channel: str | None = "can0") -> CanFrame:
    data = db.get_message_by_name("SPEED").encode({"SPEED": kmh})
    return CanFrame(round(t_s * NS), 0xB4, False, data, channel)


def _yaw(db: Database, t_s: float, degps: float, channel: str | None = "can0") -> CanFrame:
    data = db.get_message_by_name("KINEMATICS").encode({"YAW_RATE": degps})
    return CanFrame(round(t_s * NS), 0x24, False, data, channel)


def _decode(
    decoder: VehicleSignalDecoder, frames: list[CanFrame]
) -> tuple[VehicleSignals, list[str]]:
    warnings: list[str] = []
    decode_frames(frames, [decoder])
    return decoder.result(warnings.append), warnings


# --- the file wrapper -----------------------------------------------------------------------
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
    s = read_vehicle_signals(log, [vehicle_dbc_path()], SPEED, YAW_RATE, warn=pytest.fail)
    np.testing.assert_array_equal(s.speed_t_ns, [1_000_000_000])
    assert s.speed_mps[0] == pytest.approx(100.0 / 3.6)
    np.testing.assert_array_equal(s.yaw_rate_t_ns, [1_500_000_000])
    assert s.yaw_rate_radps[0] == 0.0


def test_sign_and_interpolation(tmp_path: Path) -> None:
    log = tmp_path / "v.log"
    kin = vehicle_dbc_path()
    msg = load_dbc([kin]).get_message_by_name("KINEMATICS")
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
    warnings: list[str] = []
    s = read_vehicle_signals(log, [kin], SPEED, flipped, warn=warnings.append)
    assert s.yaw_rate_at(500_000_000) == pytest.approx(-math.radians(1.22))
    assert s.yaw_rate_at(5_000_000_000) == pytest.approx(-math.radians(2.44))  # held past the end
    assert np.isnan(s.speed_at(0))  # no SPEED frames, and a warning that says so
    assert warnings == [
        f"{log}: no frame of SPEED (signal SPEED), id 0x0B4, on any channel; the most "
        "frequent ids there: 0x024 (2) (is the DBC the log's?)"
    ]


def test_wrapper_warns_through_python_warnings_by_default(tmp_path: Path) -> None:
    log = tmp_path / "empty.log"
    log.write_text("")
    with pytest.warns(RuntimeWarning) as record:
        read_vehicle_signals(log, [vehicle_dbc_path()], SPEED, YAW_RATE)
    assert [str(w.message) for w in record] == [
        f"{log}: no frame of {name}, id {ids}, on any channel; the log holds no data frame at all"
        for name, ids in (
            ("SPEED (signal SPEED)", "0x0B4"),
            ("KINEMATICS (signal YAW_RATE)", "0x024"),
        )
    ]


# --- dispatch -------------------------------------------------------------------------------
def test_decode_frames_routes_by_channel_id_and_extended_flag(db: Database) -> None:
    on0 = VehicleSignalDecoder(db, _source("can0"), "log")
    on1 = VehicleSignalDecoder(db, _source("can1"), "log")
    anywhere = VehicleSignalDecoder(db, _source(None), "log")
    frames = [
        _speed(db, 1.0, 36.0, "can0"),
        _speed(db, 1.1, 72.0, "can1"),
        CanFrame(1_200_000_000, 0xB4, True, _speed(db, 0, 90.0).data, "can0"),  # extended 0xB4
        _yaw(db, 1.3, 1.0, "can1"),
        CanFrame(1_400_000_000, 0x300, False, bytes(8), "can0"),
    ]
    assert [on0.wants(f) for f in frames] == [True, False, False, False, False]
    assert on0.ids == {(0xB4, False), (0x24, False)}
    decode_frames(frames, [on0, on1, anywhere])
    s0, s1, s_any = (d.result(lambda _: None) for d in (on0, on1, anywhere))
    np.testing.assert_allclose(s0.speed_mps, [10.0])
    np.testing.assert_allclose(s1.speed_mps, [20.0])
    np.testing.assert_allclose(s_any.speed_mps, [10.0, 20.0])
    np.testing.assert_array_equal(s1.yaw_rate_t_ns, [1_300_000_000])
    assert len(s0.yaw_rate_t_ns) == 0


def test_samples_sorted_by_time_in_si_units_with_offset(db: Database) -> None:
    decoder = VehicleSignalDecoder(db, _source(), "log", offset_ns=-500_000_000)
    frames = [_speed(db, 2.0, 36.0), _speed(db, 1.0, 18.0), _yaw(db, 1.5, 90.0)]
    s, warnings = _decode(decoder, frames)
    assert warnings == [
        "log: 1 speed and yaw-rate frames stamped earlier than the one before; sorted"
    ]
    np.testing.assert_array_equal(s.speed_t_ns, [500_000_000, 1_500_000_000])
    np.testing.assert_allclose(s.speed_mps, [5.0, 10.0])
    np.testing.assert_allclose(s.yaw_rate_radps, [math.pi / 2])


def test_stamp_outside_the_main_block_is_dropped_and_reported(db: Database) -> None:
    frames = [_speed(db, 46408.0 + 0.025 * i, 36.0) for i in range(40)]
    frames.insert(20, _speed(db, 0.5, 99.0))  # a 1970 stamp amid 2018's
    s, warnings = _decode(VehicleSignalDecoder(db, _source(), "log.gz"), frames)
    assert len(s.speed_t_ns) == 40
    np.testing.assert_allclose(s.speed_mps, 10.0)
    assert warnings[-1] == (
        "log.gz: dropped 1 speed and yaw-rate frames stamped outside the log's main block "
        "46408.000 s to 46408.975 s (gaps over 120 s end a block): first at t=0.500000 s"
    )


def test_no_frame_names_the_message_and_what_the_channel_carries(db: Database) -> None:
    frames = [CanFrame(i, 0x2C1, False, bytes(8), "can0") for i in range(5)]
    frames += [CanFrame(i, 0x18DAF110, True, bytes(8), "can0") for i in range(3)]
    frames += [CanFrame(i, 0xB4, False, bytes(8), "can1") for i in range(2)]
    decoder = VehicleSignalDecoder(db, _source("can0"), "rav4.log")
    _, warnings = _decode(decoder, frames)
    assert warnings == [
        "rav4.log: no frame of SPEED (signal SPEED), id 0x0B4, on channel can0; the most "
        "frequent ids there: 0x2C1 (5), 0x18DAF110 (extended) (3) (is the DBC the log's?)",
        "rav4.log: no frame of KINEMATICS (signal YAW_RATE), id 0x024, on channel can0; the "
        "most frequent ids there: 0x2C1 (5), 0x18DAF110 (extended) (3) (is the DBC the log's?)",
    ]
    _, warnings = _decode(VehicleSignalDecoder(db, _source("can7"), "rav4.log"), frames)
    assert warnings[0].endswith(
        "on channel can7; the log has no frame on that channel; its channels: can0 (8 frames), "
        "can1 (2 frames)"
    )


# --- yaw-rate bias --------------------------------------------------------------------------
def _standing_then_turning(db: Database, stand_s: float) -> list[CanFrame]:
    """Speed at 40 Hz: 0 while standing, then 10 m/s; yaw rate at 80 Hz with a -0.4 deg/s
    bias: -0.4 deg/s while standing, 5.0 - 0.4 deg/s while turning, for 3 s."""
    speed = [_speed(db, k / 40, 0.0 if k / 40 < stand_s else 36.0) for k in range(40 * 6)]
    yaw = [_yaw(db, k / 80, -0.4 + (5.0 if k / 80 >= stand_s else 0.0)) for k in range(80 * 6)]
    return sorted(speed + yaw, key=lambda f: f.t_ns)


def test_yaw_rate_bias_is_the_standstill_mean(db: Database) -> None:
    decoder = VehicleSignalDecoder(db, _source(bias="standstill"), "log")
    s, warnings = _decode(decoder, _standing_then_turning(db, stand_s=3.0))
    assert warnings == []
    assert s.yaw_rate_bias_radps == pytest.approx(math.radians(-0.4))
    # Still: yaw samples up to the last zero-speed sample at 2.975 s (interpolated speed
    # rises above 0.05 m/s right after it).
    assert s.standstill_s == pytest.approx(2.975)
    standing, turning = s.yaw_rate_t_ns < 3 * NS, s.yaw_rate_t_ns >= 3 * NS
    np.testing.assert_allclose(s.yaw_rate_radps[standing], 0.0, atol=1e-12)
    np.testing.assert_allclose(s.yaw_rate_radps[turning], math.radians(5.0))


def test_yaw_rate_bias_needs_a_second_of_standstill(db: Database) -> None:
    decoder = VehicleSignalDecoder(db, _source(bias="standstill"), "log")
    s, warnings = _decode(decoder, _standing_then_turning(db, stand_s=0.5))
    assert s.yaw_rate_bias_radps == 0.0
    assert s.standstill_s == pytest.approx(0.475)
    assert warnings == [
        "log: yaw_rate_bias standstill: the car stands still (speed below 0.05 m/s) for "
        "0.47 s, 1.0 s needed; no yaw-rate bias subtracted"
    ]
    np.testing.assert_allclose(s.yaw_rate_radps[:10], math.radians(-0.4))


def test_without_bias_mode_standstill_is_measured_but_nothing_subtracted(db: Database) -> None:
    s, warnings = _decode(
        VehicleSignalDecoder(db, _source(), "log"), _standing_then_turning(db, 3.0)
    )
    assert warnings == []
    assert (s.yaw_rate_bias_radps, s.standstill_s) == (0.0, pytest.approx(2.975))
    np.testing.assert_allclose(s.yaw_rate_radps[:10], math.radians(-0.4))


# --- bad values and bad input ---------------------------------------------------------------
def test_non_finite_and_undecodable_frames_are_dropped_and_reported(db: Database) -> None:
    gyro = SignalMapping("GYRO_F", "YAW_F", "deg/s", YAW_RATE_UNITS_TO_RADPS["deg/s"])
    muxed = SignalMapping("MUXED", "A", "km/h", SPEED_UNITS_TO_MPS["km/h"])
    decoder = VehicleSignalDecoder(db, _source(speed=muxed, yaw_rate=gyro), "log")
    frames = [
        CanFrame(1 * NS, 0x25, False, struct.pack(">f", 2.0)),
        CanFrame(1 * NS, 0x26, False, bytes([1, 36])),
        CanFrame(2 * NS, 0x25, False, struct.pack(">f", math.nan)),
        CanFrame(2 * NS, 0x26, False, bytes([5, 36])),  # no signals for multiplexer value 5
        CanFrame(3 * NS, 0x25, False, struct.pack(">f", math.inf)),
    ]
    s, warnings = _decode(decoder, frames)
    np.testing.assert_allclose(s.yaw_rate_radps, [math.radians(2.0)])
    np.testing.assert_allclose(s.speed_mps, [10.0])
    assert warnings == [
        "log: skipped 1 speed and yaw-rate frames the DBC cannot decode (first: MUXED at "
        "t=2.000000 s: expected multiplexer id 1, but got 5)",
        "log: dropped 2 non-finite GYRO_F.YAW_F values (first at t=2.000000 s)",
    ]


def test_unknown_message_or_signal_raises_with_close_names(db: Database) -> None:
    typo = SignalMapping("KINEMATIK", "YAW_RATE", "deg/s", 1.0)
    with pytest.raises(RecordingError, match=r"^log: no message 'KINEMATIK' in the DBC; close "):
        VehicleSignalDecoder(db, _source(yaw_rate=typo), "log")
    typo = SignalMapping("KINEMATICS", "YAWRATE", "deg/s", 1.0)
    with pytest.raises(
        RecordingError, match=r"^log: message 'KINEMATICS' has no signal 'YAWRATE'; close names: "
    ):
        VehicleSignalDecoder(db, _source(yaw_rate=typo), "log")
    with pytest.raises(ValueError, match=r"yaw_rate_bias: expected 'none' or 'standstill'"):
        VehicleSignalDecoder(db, _source(bias="always"), "log")


# --- the real RAV4 log ----------------------------------------------------------------------
def test_real_rav4_log_decodes_to_plausible_values(realdata: Path) -> None:
    d = realdata / "comma2k19-rav4"
    log = d / "rav4_seg40.log.gz"
    db = load_dbc([d / "toyota_rav4_powertrain.dbc"])
    source = CanSource(
        CanBus(("p.dbc",), log=log.name, channel="can0"), SPEED, YAW_RATE, "standstill"
    )
    decoder = VehicleSignalDecoder(db, source, str(log))
    warnings: list[str] = []
    start = time.perf_counter()
    decode_frames(iter_log_frames(log, warn=warnings.append), [decoder])
    s = decoder.result(warnings.append)
    print(f"RAV4 speed and yaw rate from 135k frames: {time.perf_counter() - start:.2f} s")

    duration_s = (s.speed_t_ns[-1] - s.speed_t_ns[0]) / 1e9
    assert 55.0 < duration_s < 61.0
    assert len(s.speed_t_ns) / duration_s == pytest.approx(41.0, abs=1.5)
    assert len(s.yaw_rate_t_ns) / duration_s == pytest.approx(83.0, abs=2.0)
    # I-280 in traffic, not free-flowing: 29 to 73 km/h, never standing, never backwards.
    assert s.speed_mps.min() == pytest.approx(8.16, abs=0.01)
    assert s.speed_mps.max() == pytest.approx(20.29, abs=0.01)
    assert s.standstill_s == 0.0
    assert warnings == [
        f"{log}: yaw_rate_bias standstill: the car stands still (speed below 0.05 m/s) for "
        "0.00 s, 1.0 s needed; no yaw-rate bias subtracted"
    ]
    # Yaw rate: the README's bias of about -0.4 deg/s, in 0.244 deg/s steps from -125 deg/s.
    assert s.yaw_rate_bias_radps == 0.0
    assert np.degrees(np.mean(s.yaw_rate_radps)) == pytest.approx(-0.42, abs=0.01)
    steps = (np.degrees(s.yaw_rate_radps) + 125.0) / 0.244
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
