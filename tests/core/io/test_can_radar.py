"""Radar tracks over CAN: scans from repeated slots, the polar frame, signs, track ids, padding,
bad values, missing frames, and the real RAV4 radar."""

from __future__ import annotations

import math
import struct
import time
from pathlib import Path

import can
import numpy as np
import pytest
from cantools.database.can import Database

from core.io.can_radar import RadarCanDecoder, natural_key
from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.canlog import (
    VehicleSignalDecoder,
    decode_frames,
    load_dbc,
)
from core.io.errors import RecordingError
from core.io.frame import RadarTarget
from core.io.manifest import CanBus, CanSource, RadarCanSource, RadarField
from core.io.radarscans import RadarScans
from core.io.writer import SPEED_SIGNAL, YAW_RATE_SIGNAL

NS = 1_000_000_000
N_SLOTS = 12
# The RAV4 TRACK_A layout plus a track id; ids run backwards so that id order, name order
# (TRK_10 before TRK_2) and natural order all differ.
TRACK = """BO_ {id} TRK_{i}: 8 XXX
 SG_ LONG_DIST : 15|13@0+ (0.04,0) [0|300] "m" XXX
 SG_ LAT_DIST : 31|11@0- (0.04,0) [-50|50] "m" XXX
 SG_ REL_SPEED : 47|12@0- (0.025,0) [-100|100] "m/s" XXX
 SG_ VALID : 48|1@0+ (1,0) [0|1] "" XXX
 SG_ TRACK_ID : 63|8@0+ (1,0) [0|255] "" XXX
"""
FLOAT_TRACK = """BO_ {id} FTRK_{i}: 8 XXX
 SG_ LONG : 7|32@0- (1,0) [0|0] "m" XXX
 SG_ LAT : 39|32@0- (1,0) [0|0] "m" XXX
"""
SPEED_DBC = """BO_ 180 SPEED: 8 XXX
 SG_ SPEED : 47|16@0+ (0.01,0) [0|655.35] "km/h" XXX

BO_ 36 KINEMATICS: 8 XXX
 SG_ YAW_RATE : 7|16@0- (0.01,0) [-327.68|327.67] "deg/s" XXX
"""
TEST_DBC = (
    'VERSION ""\n\nNS_ :\n\nBS_:\n\nBU_: XXX\n\n'
    + "\n".join(TRACK.format(id=0x300 + N_SLOTS - 1 - i, i=i) for i in range(N_SLOTS))
    + "\n"
    + "\n".join(FLOAT_TRACK.format(id=0x400 + i, i=i) for i in range(2))
    + "\n"
    + SPEED_DBC
    + "\n"
    + "\n".join(f"SIG_VALTYPE_ {0x400 + i} {s} : 1;" for i in range(2) for s in ("LONG", "LAT"))
    + "\n"
)

M = RadarField("LONG_DIST", "m", 1.0, 1)
RIGHT_M = RadarField("LAT_DIST", "m", 1.0, -1)  # positive right on the bus, left in the engine
RANGE_RATE = RadarField("REL_SPEED", "m/s", 1.0, 1)
VALID = RadarField("VALID")


@pytest.fixture(scope="module")
def db(tmp_path_factory: pytest.TempPathFactory) -> Database:
    path = tmp_path_factory.mktemp("dbc") / "radar.dbc"
    path.write_text(TEST_DBC)
    return load_dbc([path])


def _source(
    messages: str = "TRK_*",
    channel: str | None = "can1",
    track_id: RadarField | None = None,
    valid: RadarField | None = VALID,
    distance: RadarField = M,
) -> RadarCanSource:
    bus = CanBus(("radar.dbc",), log="x.log", channel=channel)
    return RadarCanSource(bus, messages, distance, RIGHT_M, RANGE_RATE, valid, track_id)


def _track(
    db: Database, t_s: float, slot: int, long_m: float, right_m: float, rel_mps: float, valid: int
) -> CanFrame:
    message = db.get_message_by_name(f"TRK_{slot}")
    data = message.encode(
        {
            "LONG_DIST": long_m,
            "LAT_DIST": right_m,
            "REL_SPEED": rel_mps,
            "VALID": valid,
            "TRACK_ID": 100 + slot,
        }
    )
    return CanFrame(round(t_s * NS), message.frame_id, False, data, "can1")


def _truth(slot: int, cycle: int) -> tuple[float, float, float, int]:
    """Slot's target in a cycle: long (m), right (m), relative speed (m/s), valid."""
    valid = 0 if (slot == 3 and cycle == 1) or slot == 7 else 1
    return 10.0 + slot + cycle, 0.4 * slot - 2.0, -1.0 + 0.1 * slot, valid


CYCLE_S = 0.05
T0_S = 46408.0  # the RAV4 log's clock
# Arrival order within a cycle, as unordered as the RAV4's.
ORDER = [[0, 1, 2, 3, 4, 5, 6, 7, 11, 10, 9, 8], [4, 2, 3, 1, 0, 5, 6, 11, 10, 7, 9, 8]]


def _cycles(db: Database, n: int = 3) -> list[CanFrame]:
    frames = []
    for c in range(n):
        for k, slot in enumerate(ORDER[c % 2]):
            frames.append(_track(db, T0_S + c * CYCLE_S + k * 1e-4, slot, *_truth(slot, c)))
    return frames


def _run(decoder: RadarCanDecoder, frames: list[CanFrame]) -> tuple[RadarScans, list[str]]:
    warnings: list[str] = []
    decode_frames(frames, [decoder])
    return decoder.result(warnings.append), warnings


def test_natural_order() -> None:
    names = ["TRACK_A_10", "TRACK_A_2", "TRACK_A_1", "TRACK_B_0"]
    assert sorted(names, key=natural_key) == ["TRACK_A_1", "TRACK_A_2", "TRACK_A_10", "TRACK_B_0"]


def test_scans_from_repeated_slots_with_targets_in_the_polar_frame(db: Database) -> None:
    decoder = RadarCanDecoder(db, _source(), "radar.log", offset_ns=-round(T0_S * NS))
    assert [m.name for m in decoder.messages] == [f"TRK_{i}" for i in range(N_SLOTS)]
    scans, warnings = _run(decoder, _cycles(db))
    assert warnings == []
    # Each scan stamped with its first message, offset applied.
    np.testing.assert_array_equal(scans.t_ns, [0, 50_000_000, 100_000_000])
    for c in range(3):
        rows = slice(scans.start[c], scans.start[c + 1])
        got = sorted(
            zip(
                scans.track_id[rows].tolist(),
                scans.range_m[rows],
                scans.azimuth_rad[rows],
                scans.range_rate_mps[rows],
                strict=True,
            )
        )
        want = []
        for slot in range(N_SLOTS):
            long_m, right_m, rel, valid = _truth(slot, c)
            if valid:
                left_m = -right_m
                want.append((slot, math.hypot(long_m, left_m), math.atan2(left_m, long_m), rel))
        assert [g[0] for g in got] == [w[0] for w in want]  # the slot's place in the family
        np.testing.assert_allclose([g[1:] for g in got], [w[1:] for w in want], atol=1e-9)
    assert np.all(np.isnan(scans.amplitude))
    # Slot 0, first in: LAT_DIST -2 m is 2 m to the left, so a positive azimuth.
    assert scans.azimuth_rad[0] == pytest.approx(math.atan2(2.0, 10.0))


def test_track_id_signal_when_mapped_and_all_targets_without_valid(db: Database) -> None:
    decoder = RadarCanDecoder(db, _source(track_id=RadarField("TRACK_ID"), valid=None), "radar.log")
    scans, _ = _run(decoder, _cycles(db, 1))
    assert sorted(scans.track_id.tolist()) == [100 + s for s in range(N_SLOTS)]


def test_short_frames_are_padded(db: Database) -> None:
    """Six of eight bytes: LONG_DIST, LAT_DIST and REL_SPEED sit in bytes 0 to 5."""
    frames = [
        CanFrame(f.t_ns, f.arbitration_id, False, f.data[:6], f.channel) for f in _cycles(db, 1)
    ]
    scans, warnings = _run(RadarCanDecoder(db, _source(valid=None), "radar.log"), frames)
    assert warnings == []
    assert len(scans.t_ns) == 1
    first = int(np.argmin(scans.track_id))
    assert scans.range_m[first] == pytest.approx(math.hypot(10.0, 2.0))


def test_no_message_matches_the_pattern(db: Database) -> None:
    with pytest.raises(
        RecordingError, match=r"^radar\.log: no DBC message matches 'TRACK_\*' .* close names: "
    ):
        RadarCanDecoder(db, _source("TRACK_*"), "radar.log")


def test_family_message_without_a_mapped_signal(db: Database) -> None:
    with pytest.raises(
        RecordingError,
        match=r"^radar\.log: message 'TRK_0' has no signal 'LONG_DST'; close names: LONG_DIST",
    ):
        RadarCanDecoder(db, _source(distance=RadarField("LONG_DST", "m")), "radar.log")


def test_non_finite_targets_are_dropped_and_reported(db: Database) -> None:
    source = RadarCanSource(
        CanBus(("radar.dbc",), log="x.log"),
        "FTRK_*",
        RadarField("LONG", "m"),
        RadarField("LAT", "m"),
    )
    frames = [
        CanFrame(NS, 0x400, False, struct.pack(">ff", 20.0, 1.0)),
        CanFrame(NS + 1000, 0x401, False, struct.pack(">ff", math.nan, 1.0)),
        CanFrame(2 * NS, 0x400, False, struct.pack(">ff", 30.0, math.inf)),
        CanFrame(2 * NS + 1000, 0x401, False, struct.pack(">ff", 40.0, 0.0)),
        CanFrame(3 * NS, 0x400, False, struct.pack(">ff", 3e38, 0.0)),  # finite, but no radar's
    ]
    scans, warnings = _run(RadarCanDecoder(db, source, "radar.log"), frames)
    np.testing.assert_array_equal(scans.start, [0, 1, 2, 2])
    np.testing.assert_allclose(scans.range_m, [math.hypot(20.0, 1.0), 40.0])
    assert np.all(np.isnan(scans.range_rate_mps))  # not mapped
    assert warnings == [
        "radar.log: dropped 2 radar targets with non-finite values (first: FTRK_1 at t=1.000001 s)",
        "radar.log: dropped 1 radar targets no radar reports (range over 1000 m or range rate "
        "over 300 m/s; first at t=3.000000 s)",
    ]


def test_stamp_outside_the_main_block_is_dropped_and_reported(db: Database) -> None:
    frames = _cycles(db, 3)
    frames.insert(15, _track(db, 0.25, 5, 50.0, 0.0, 0.0, 1))  # a 1970 stamp
    scans, warnings = _run(RadarCanDecoder(db, _source(), "radar.log"), frames)
    assert len(scans.t_ns) == 3
    assert warnings == [
        "radar.log: dropped 1 radar track frames stamped outside the log's main block "
        "46408.000 s to 46408.101 s (gaps over 120 s end a block): first at t=0.250000 s"
    ]


def test_no_frame_names_the_family_its_ids_and_the_channel(db: Database) -> None:
    frames = [CanFrame(i, 0x2E4, False, bytes(5), "can1") for i in range(3)]
    scans, warnings = _run(RadarCanDecoder(db, _source(), "rav4.log"), frames)
    assert len(scans.t_ns) == 0
    np.testing.assert_array_equal(scans.start, [0])
    assert warnings == [
        "rav4.log: no frame of TRK_* (12 messages), id 0x30B to 0x300, on channel can1; the "
        "most frequent ids there: 0x2E4 (3) (is the DBC the log's?)"
    ]


def test_one_pass_over_a_log_feeds_speed_on_can0_and_radar_on_can1(
    db: Database, tmp_path: Path
) -> None:
    log = tmp_path / "both.log"
    speed = db.get_message_by_name("SPEED")
    with can.CanutilsLogWriter(str(log)) as w:
        for f in _cycles(db, 2):
            w.on_message_received(
                can.Message(
                    timestamp=f.t_ns / NS,
                    arbitration_id=f.arbitration_id,
                    data=f.data,
                    is_extended_id=False,
                    channel=1,
                )
            )
            w.on_message_received(  # the same ids on can0 must not reach the radar
                can.Message(
                    timestamp=f.t_ns / NS,
                    arbitration_id=f.arbitration_id,
                    data=f.data,
                    is_extended_id=False,
                    channel=0,
                )
            )
        w.on_message_received(
            can.Message(
                timestamp=T0_S + 0.2,
                arbitration_id=0xB4,
                data=speed.encode({"SPEED": 72.0}),
                is_extended_id=False,
                channel=0,
            )
        )
    vehicle_source = CanSource(
        CanBus(("radar.dbc",), log=log.name, channel="can0"),
        SPEED_SIGNAL,
        YAW_RATE_SIGNAL,
    )
    vehicle = VehicleSignalDecoder(db, vehicle_source, str(log))
    radar = RadarCanDecoder(db, _source(), str(log))
    warnings: list[str] = []
    decode_frames(iter_log_frames(log, warn=warnings.append), [vehicle, radar])
    np.testing.assert_allclose(vehicle.result(warnings.append).speed_mps, [20.0])
    scans = radar.result(warnings.append)
    assert len(scans.t_ns) == 2
    assert len(scans.range_m) == 2 * N_SLOTS - 3  # slot 7 invalid twice, slot 3 once
    assert [w.split(";")[0] for w in warnings] == [
        f"{log}: no frame of KINEMATICS (signal YAW_RATE), id 0x024, on channel can0"
    ]


# --- the real RAV4 radar --------------------------------------------------------------------
RAV4_RADAR_X_M = 2.7  # README: the radar sits about 2.7 m ahead of the car's reference point


@pytest.fixture(scope="module")
def rav4(realdata: Path) -> tuple[RadarScans, list[str]]:
    d = realdata / "comma2k19-rav4"
    log = d / "rav4_seg40.log.gz"
    source = RadarCanSource(
        CanBus(("toyota_adas_radar.dbc",), log=log.name, channel="can1"),
        "TRACK_A_*",
        RadarField("LONG_DIST", "m"),
        RadarField("LAT_DIST", "m", sign=-1),  # positive right on the RAV4's bus
        RadarField("REL_SPEED", "m/s"),
        RadarField("VALID"),
    )
    decoder = RadarCanDecoder(load_dbc([d / "toyota_adas_radar.dbc"]), source, str(log))
    warnings: list[str] = []
    start = time.perf_counter()
    decode_frames(iter_log_frames(log, warn=warnings.append), [decoder])
    scans = decoder.result(warnings.append)
    print(f"RAV4 radar tracks from 135k frames: {time.perf_counter() - start:.2f} s")
    return scans, warnings


def test_real_rav4_radar_scans_at_20_hz(rav4: tuple[RadarScans, list[str]]) -> None:
    scans, warnings = rav4
    assert warnings == []
    assert 1e9 / scans.median_period_ns == pytest.approx(20.0, abs=0.2)
    assert len(scans.t_ns) == 1200  # 1200 frames of each of the 16 TRACK_A messages
    per_scan = np.diff(scans.start)
    assert per_scan.max() <= 16
    assert 5 < per_scan.mean() < 12  # about half the slots hold a valid track


def test_real_rav4_radar_sees_the_cars_of_the_first_camera_frame(
    rav4: tuple[RadarScans, list[str]],
) -> None:
    scans, _ = rav4
    k = int(np.argmin(np.abs(scans.t_ns - 46408_547_000_000)))
    rows = range(scans.start[k], scans.start[k + 1])
    targets = [
        RadarTarget.from_polar(
            scans.range_m[r],
            scans.azimuth_rad[r],
            scans.range_rate_mps[r],
            0.0,
            RAV4_RADAR_X_M,
            0.0,
        )
        for r in rows
    ]
    xy = np.array([(t.x_m, t.y_m) for t in targets])
    # The silver car in the ego lane: 29.3 m ahead of the car, straight on.
    assert np.min(np.hypot(xy[:, 0] - 29.3, xy[:, 1])) < 0.1
    # 18.3 m ahead, 2.9 m to the RIGHT: lateral -2.9 m with positive left.
    assert np.min(np.hypot(xy[:, 0] - 18.3, xy[:, 1] + 2.9)) < 0.1


def test_real_rav4_rel_speed_is_positive_receding(rav4: tuple[RadarScans, list[str]]) -> None:
    """REL_SPEED agrees with the change of distance of the same track between scans: positive
    when the target draws away, so a car being approached has negative range rate."""
    scans, _ = rav4
    scan_of = np.repeat(np.arange(len(scans.t_ns)), np.diff(scans.start))
    t_s = scans.t_ns[scan_of] / 1e9
    x = scans.range_m * np.cos(scans.azimuth_rad)
    rate, rr = [], []
    for slot in range(16):
        mine = np.flatnonzero(scans.track_id == slot)
        dt = np.diff(t_s[mine])
        next_scan = (dt > 0.03) & (dt < 0.07)
        rate.append((np.diff(x[mine]) / np.where(next_scan, dt, 1.0))[next_scan])
        rr.append(scans.range_rate_mps[mine][1:][next_scan])
    d_rate, range_rate = np.concatenate(rate), np.concatenate(rr)
    same_track = np.abs(d_rate) < 30  # a slot handed to another target jumps
    assert np.count_nonzero(same_track) > 5000
    slope = np.polyfit(range_rate[same_track], d_rate[same_track], 1)[0]
    assert slope == pytest.approx(1.0, abs=0.05)
    assert np.corrcoef(range_rate[same_track], d_rate[same_track])[0, 1] > 0.9
