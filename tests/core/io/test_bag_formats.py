"""BagReader on every bag kind engineers have: ROS 1, ROS 2 sqlite3 and MCAP.

Known answers: images whose grey value follows from the published luma weights
(0.299 R + 0.587 G + 0.114 B) or from the 16-bit scale v * 255 / (2**bits - 1); radar tracks at
positions whose range, azimuth and range rate are plain geometry; CAN frames spelled out.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import pytest
from bagmaker import (
    COMPRESSIONS,
    KINDS,
    Compression,
    Kind,
    Message,
    bag_path,
    can_frame,
    compressed_image,
    radar_scan,
    radar_tracks,
    raw_image,
    ros1_typestore,
    serialize,
    write_bag,
    write_multifile_bag,
)
from rosbags import rosbag1
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from core.io.bag import (
    CAMERA_TYPES,
    CAN_TYPES,
    RADAR_TYPES,
    BagReader,
    CameraStream,
    decode_image,
)
from core.io.canframe import CanFrame
from core.io.errors import RecordingError
from core.io.radar_msgs import CAN_FRAME, COMPRESSED_IMAGE, IMAGE, RADAR_SCAN, RADAR_TRACKS

T0_NS = 1_700_000_000_123_456_789  # a 2023 log time
PERIOD_NS = 50_000_000


def _t(k: int) -> int:
    return T0_NS + k * PERIOD_NS


def _write(tmp_path: Path, kind: Kind, messages: list[Message]) -> Path:
    return write_bag(bag_path(tmp_path, kind), kind, messages)


def _luma(rgb: tuple[int, int, int]) -> int:
    r, g, b = rgb
    return round(0.299 * r + 0.587 * g + 0.114 * b)


# Colours whose luma is not near .5, so the rounding of any exact implementation agrees.
RGB = np.array(
    [[(200, 100, 50), (0, 0, 255), (255, 0, 0)], [(0, 255, 0), (255, 255, 255), (10, 20, 30)]],
    dtype=np.uint8,
)
GREY_OF_RGB = np.array([[_luma(tuple(px)) for px in row] for row in RGB.tolist()], np.uint8)
ALPHA = np.array([[0, 50, 100], [150, 200, 255]], np.uint8)[..., None]
MONO8 = np.array([[0, 1, 2, 3], [127, 128, 254, 255]], np.uint8)
# 16-bit: 257 k scales to k exactly; 128 / 257 rounds down, 129 / 257 up.
MONO16 = np.array([[0, 128, 129, 25700], [65535, 257, 514, 32896]], np.uint16)
GREY_OF_MONO16 = np.array([[0, 0, 1, 100], [255, 1, 2, 128]], np.uint8)
# 12 significant bits: 4095 is white, 2048 -> 127.53, beyond 12 bits clips.
MONO12 = np.array([[0, 2048, 4095, 5000]], np.uint16)
GREY_OF_MONO12 = np.array([[0, 128, 255, 255]], np.uint8)


def _png(img: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".png", img)
    assert ok
    return buf.tobytes()


def _jpeg(img: np.ndarray) -> bytes:
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, 95])
    assert ok
    return buf.tobytes()


def _flat(value: Any, shape: tuple[int, ...]) -> np.ndarray:
    return np.broadcast_to(np.asarray(value, np.uint8), shape).copy()


# topic -> (fields at t, expected grey, tolerance, mono16_bits)
IMAGE_CASES: dict[str, tuple[str, Any, np.ndarray, int, int]] = {
    "/mono8": (IMAGE, lambda t: raw_image(t, MONO8, "mono8"), MONO8, 0, 16),
    "/mono8_padded": (IMAGE, lambda t: raw_image(t, MONO8, "mono8", pad=3), MONO8, 0, 16),
    "/8uc1": (IMAGE, lambda t: raw_image(t, MONO8, "8UC1"), MONO8, 0, 16),
    "/rgb8": (IMAGE, lambda t: raw_image(t, RGB, "rgb8"), GREY_OF_RGB, 0, 16),
    "/bgr8": (IMAGE, lambda t: raw_image(t, RGB[..., ::-1], "bgr8"), GREY_OF_RGB, 0, 16),
    "/rgba8": (
        IMAGE,
        lambda t: raw_image(t, np.concatenate([RGB, ALPHA], axis=2), "rgba8", pad=2),
        GREY_OF_RGB,
        0,
        16,
    ),
    "/bgra8": (
        IMAGE,
        lambda t: raw_image(t, np.concatenate([RGB[..., ::-1], ALPHA], axis=2), "bgra8"),
        GREY_OF_RGB,
        0,
        16,
    ),
    "/mono16_le": (IMAGE, lambda t: raw_image(t, MONO16, "mono16"), GREY_OF_MONO16, 0, 16),
    "/mono16_be": (
        IMAGE,
        lambda t: raw_image(t, MONO16, "mono16", big_endian=True, pad=1),
        GREY_OF_MONO16,
        0,
        16,
    ),
    "/16uc1_12bit": (IMAGE, lambda t: raw_image(t, MONO12, "16UC1"), GREY_OF_MONO12, 0, 12),
    "/png8_grey": (
        COMPRESSED_IMAGE,
        lambda t: compressed_image(t, _png(MONO8), "png"),
        MONO8,
        0,
        16,
    ),
    "/png8_colour": (
        COMPRESSED_IMAGE,
        lambda t: compressed_image(t, _png(RGB[..., ::-1]), "bgr8; png compressed bgr8"),
        GREY_OF_RGB,
        0,
        16,
    ),
    "/png16_grey": (
        COMPRESSED_IMAGE,
        lambda t: compressed_image(t, _png(MONO16), "mono16; png compressed mono16"),
        GREY_OF_MONO16,
        0,
        16,
    ),
    "/png16_12bit": (
        COMPRESSED_IMAGE,
        lambda t: compressed_image(t, _png(MONO12), "png"),
        GREY_OF_MONO12,
        0,
        12,
    ),
    "/png16_colour": (
        COMPRESSED_IMAGE,
        lambda t: compressed_image(t, _png(RGB[..., ::-1].astype(np.uint16) * 257), "png"),
        GREY_OF_RGB,
        0,
        16,
    ),
    "/jpeg_grey": (
        COMPRESSED_IMAGE,
        lambda t: compressed_image(t, _jpeg(_flat(93, (16, 16))), "jpeg"),
        _flat(93, (16, 16)),
        1,
        16,
    ),
    "/jpeg_colour": (
        COMPRESSED_IMAGE,
        lambda t: compressed_image(t, _jpeg(_flat((50, 100, 200), (16, 16, 3))), "bgr8; jpeg"),
        _flat(_luma((200, 100, 50)), (16, 16)),
        2,
        16,
    ),
}


@pytest.mark.parametrize("kind", KINDS)
def test_every_image_encoding_decodes_to_its_known_grey(tmp_path: Path, kind: Kind) -> None:
    messages: list[Message] = [
        (topic, msgtype, _t(k), fields(_t(k)))
        for k, (topic, (msgtype, fields, _, _, _)) in enumerate(IMAGE_CASES.items())
    ]
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        for k, (topic, (_, _, want, tol, bits)) in enumerate(IMAGE_CASES.items()):
            stream = CameraStream(bag, topic, mono16_bits=bits)
            assert stream.times_ns.tolist() == [_t(k)]
            got = stream.image(0)
            assert got.dtype == np.uint8 and got.shape == want.shape, topic
            assert np.abs(got.astype(int) - want).max() <= tol, (topic, got, want)


def _frames(n: int) -> list[np.ndarray]:
    """Frame k: a gradient with a bright bar at column 2 k (distinct per frame)."""
    frames = []
    for k in range(n):
        img = (np.arange(24, dtype=np.uint8)[None, :] * 7 + k).repeat(16, 0)
        img[4:8, 2 * k : 2 * k + 3] = 255
        frames.append(img)
    return frames


@pytest.mark.parametrize("kind", KINDS)
def test_camera_pixels_and_stamps_come_back_exactly(tmp_path: Path, kind: Kind) -> None:
    frames = _frames(5)
    # Two frames share a log time: random access must still tell them apart.
    stamps = [_t(0), _t(1), _t(1), _t(3), _t(4)]
    messages: list[Message] = [
        ("/cam", COMPRESSED_IMAGE, t, compressed_image(t, _png(img), "png"))
        for t, img in zip(stamps, frames, strict=True)
    ]
    messages.append(("/radar", RADAR_SCAN, _t(2), radar_scan(_t(2), [])))
    offset_ns = -7
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        assert bag.topics == {"/cam": COMPRESSED_IMAGE, "/radar": RADAR_SCAN}
        stream = CameraStream(bag, "/cam", offset_ns)
        assert len(stream) == 5
        assert stream.times_ns.tolist() == [t + offset_ns for t in stamps]
        for k in (4, 0, 2, 1, 3):
            np.testing.assert_array_equal(stream.image(k), frames[k])


@pytest.mark.parametrize("kind", KINDS)
def test_frames_read_in_any_order_a_player_reads_them_come_back_exactly(
    tmp_path: Path, kind: Kind
) -> None:
    # read_at continues from the last message read; whatever the order, the pixels are the
    # frame's: forward, skipping frames (within and beyond its look-ahead), backwards, the
    # same frame twice, two frames sharing a stamp, with another topic read in between
    frames = _frames(12)
    stamps = [_t(k) for k in range(6)] + [_t(5)] + [_t(k) for k in range(7, 12)]
    messages: list[Message] = [
        ("/cam", COMPRESSED_IMAGE, t, compressed_image(t, _png(img), "png"))
        for t, img in zip(stamps, frames, strict=True)
    ]
    messages += [("/radar", RADAR_SCAN, _t(k), radar_scan(_t(k), [])) for k in range(12)]
    orders = [
        list(range(12)),
        [0, 2, 4, 6, 8, 10],
        [0, 1, 9, 10, 11],
        list(range(11, -1, -1)),
        [3, 3, 4, 4, 5, 6, 5, 7],
    ]
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        stream = CameraStream(bag, "/cam")
        radar = bag.connection("/radar", RADAR_TYPES, "radar")
        for order in orders:
            for k in order:
                np.testing.assert_array_equal(stream.image(k), frames[k], err_msg=f"frame {k}")
                if k % 3 == 0:
                    assert bag.read_at(radar, _t(k)).header.stamp.sec == _t(k) // 10**9


@pytest.mark.parametrize(
    ("kind", "compression"), [(k, c) for k in KINDS for c in COMPRESSIONS[k] if c != "none"]
)
def test_compressed_bags_read_the_same(
    tmp_path: Path, kind: Kind, compression: Compression
) -> None:
    frames = _frames(3)
    messages: list[Message] = [
        ("/cam", COMPRESSED_IMAGE, _t(k), compressed_image(_t(k), _png(img), "png"))
        for k, img in enumerate(frames)
    ]
    messages += [
        ("/radar", RADAR_SCAN, _t(3), radar_scan(_t(3), [(12.5, 0.25, 1.0, 2.0)])),
        ("/can", CAN_FRAME, _t(4), can_frame(_t(4), 0x42, b"\x07")),
    ]
    path = write_bag(bag_path(tmp_path, kind), kind, messages, compression=compression)
    with BagReader(path) as bag:
        stream = CameraStream(bag, None)
        assert stream.times_ns.tolist() == [_t(0), _t(1), _t(2)]
        for k in (2, 0, 1):
            np.testing.assert_array_equal(stream.image(k), frames[k])
        radar = bag.read_radar(bag.connection(None, RADAR_TYPES, "radar"), warn=pytest.fail)
        assert radar.range_m.tolist() == [12.5]
        can = list(bag.can_frames(bag.connection(None, CAN_TYPES, "CAN")))
        assert can == [CanFrame(_t(4), 0x42, False, b"\x07", None)]


@pytest.mark.parametrize("kind", KINDS)
def test_radar_scans_come_back_grouped_with_offset(tmp_path: Path, kind: Kind) -> None:
    scans = [
        [(20.5, 0.25, -1.5, 10.0)],
        [],
        [(30.0, -0.5, 2.0, 7.5), (45.25, 0.125, 0.0, 3.0)],
    ]
    messages: list[Message] = [
        ("/radar", RADAR_SCAN, _t(k), radar_scan(_t(k), s)) for k, s in enumerate(scans)
    ]
    warnings: list[str] = []
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        conn = bag.connection(None, RADAR_TYPES, "radar")
        radar = bag.read_radar(conn, 1_000, warn=warnings.append)
    assert warnings == []
    assert radar.t_ns.tolist() == [_t(k) + 1_000 for k in range(3)]
    assert radar.start.tolist() == [0, 1, 1, 3]
    flat = [r for s in scans for r in s]  # values exact in float32
    assert radar.range_m.tolist() == [r[0] for r in flat]
    assert radar.azimuth_rad.tolist() == [r[1] for r in flat]
    assert radar.range_rate_mps.tolist() == [r[2] for r in flat]
    assert radar.amplitude.tolist() == [r[3] for r in flat]
    assert radar.track_id.tolist() == [-1, -1, -1]


@pytest.mark.parametrize("kind", KINDS)
def test_radar_tracks_become_range_azimuth_and_range_rate(tmp_path: Path, kind: Kind) -> None:
    tracks = [
        # straight ahead, moving away at 2 m/s
        ((7).to_bytes(8, "little") + bytes(8), (10.0, 0.0), (2.0, 0.0)),
        # 5 m to the left, approaching sideways at 1 m/s
        (bytes([1, 2, 3, 4, 5, 6, 7, 8]) + b"\xff" * 8, (0.0, 5.0), (0.0, -1.0)),
        # 3 m ahead and 4 m right, moving along x only
        (b"\xff" * 16, (3.0, -4.0), (5.0, 0.0)),
    ]
    messages: list[Message] = [("/tracks", RADAR_TRACKS, _t(0), radar_tracks(_t(0), tracks))]
    warnings: list[str] = []
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        radar = bag.read_radar(
            bag.connection("/tracks", RADAR_TYPES, "radar"), warn=warnings.append
        )
    assert warnings == []
    assert radar.start.tolist() == [0, 3]
    np.testing.assert_allclose(radar.range_m, [10.0, 5.0, 5.0])
    np.testing.assert_allclose(radar.azimuth_rad, [0.0, math.pi / 2, -math.atan2(4.0, 3.0)])
    # line of sight of (3, -4) is (0.6, -0.8): 5 m/s along x is 3 m/s away
    np.testing.assert_allclose(radar.range_rate_mps, [2.0, -1.0, 3.0])
    assert radar.track_id.tolist() == [7, 0x0807060504030201, 2**63 - 1]


@pytest.mark.parametrize("kind", KINDS)
def test_non_finite_returns_are_dropped_in_one_warning(tmp_path: Path, kind: Kind) -> None:
    nan, inf = math.nan, math.inf
    scans = [
        [(10.0, 0.0, 0.0, 1.0), (nan, 0.0, 0.0, 1.0)],
        [(inf, 0.0, 0.0, 1.0), (11.0, nan, 0.0, 1.0), (12.0, 0.0, -inf, 1.0)],
        [(13.0, 0.0, 0.0, 1.0), (14.0, 0.0, 0.0, nan), (15.0, 0.0, 0.0, inf)],
    ]
    messages: list[Message] = [
        ("/radar", RADAR_SCAN, _t(k), radar_scan(_t(k), s)) for k, s in enumerate(scans)
    ]
    warnings: list[str] = []
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        radar = bag.read_radar(bag.connection(None, RADAR_TYPES, "radar"), warn=warnings.append)
    assert radar.range_m.tolist() == [10.0, 13.0]
    assert radar.start.tolist() == [0, 1, 1, 2]
    assert len(warnings) == 1
    assert (
        "radar topic /radar: 6 return(s) with a non-finite range, azimuth, velocity or "
        "amplitude dropped" in warnings[0]
    )
    assert "1700000000.123456789 s, 1700000000.173456789 s" in warnings[0]


@pytest.mark.parametrize("kind", KINDS)
def test_returns_no_radar_reports_are_dropped_in_one_warning(tmp_path: Path, kind: Kind) -> None:
    returns = [
        (3e38, 0.0, 0.0, 1.0),  # a garbled float: finite, but no radar sees 3e38 m
        (-1.0, 0.0, 0.0, 1.0),
        (20.0, 4.0, 0.0, 1.0),  # beyond a half-turn
        (20.0, 0.0, 500.0, 1.0),
        (1000.0, -math.pi, -300.0, 1.0),  # at the edges: kept
    ]
    messages: list[Message] = [("/radar", RADAR_SCAN, _t(0), radar_scan(_t(0), returns))]
    warnings: list[str] = []
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        radar = bag.read_radar(bag.connection(None, RADAR_TYPES, "radar"), warn=warnings.append)
    assert radar.range_m.tolist() == [1000.0] and radar.start.tolist() == [0, 1]
    (warning,) = warnings
    assert (
        "radar topic /radar: 4 return(s) no radar reports (range outside 0-1000 m, azimuth "
        "beyond +-pi or range rate over 300 m/s) dropped, in scans at log t = 1700000000."
        in warning
    )


@pytest.mark.parametrize("kind", KINDS)
def test_a_scan_stamped_in_1970_amid_a_drive_is_dropped(tmp_path: Path, kind: Kind) -> None:
    stamps = [_t(0), _t(1), 5_000_000_000, _t(3), _t(4)]
    messages: list[Message] = [
        ("/radar", RADAR_SCAN, t, radar_scan(t, [(10.0 + k, 0.0, 0.0, 1.0)]))
        for k, t in enumerate(stamps)
    ]
    warnings: list[str] = []
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        radar = bag.read_radar(bag.connection(None, RADAR_TYPES, "radar"), warn=warnings.append)
    assert radar.t_ns.tolist() == [_t(0), _t(1), _t(3), _t(4)]
    assert radar.range_m.tolist() == [10.0, 11.0, 13.0, 14.0]
    assert warnings == [
        f"{bag.path}: radar topic /radar: 1 scan(s) stamped away from the rest of the stream "
        "dropped, at log t = 5.000000000 s"
    ]


@pytest.mark.parametrize("kind", ["sqlite3", "mcap"])
def test_scans_out_of_time_order_are_sorted_and_reported(tmp_path: Path, kind: Kind) -> None:
    # A bag of two files listed latest first: rosbags reads file by file.
    def scans(ks: range) -> list[Message]:
        return [
            ("/radar", RADAR_SCAN, _t(k), radar_scan(_t(k), [(10.0 + k, 0.0, 0.0, 1.0)]))
            for k in ks
        ]

    path = write_multifile_bag(tmp_path / "bag", kind, [scans(range(3, 6)), scans(range(3))])
    warnings: list[str] = []
    with BagReader(path) as bag:
        conn = bag.connection(None, RADAR_TYPES, "radar")
        assert bag.log_times_ns(conn).tolist() == [_t(k) for k in (3, 4, 5, 0, 1, 2)]
        radar = bag.read_radar(conn, warn=warnings.append)
    assert radar.t_ns.tolist() == [_t(k) for k in range(6)]
    assert radar.range_m.tolist() == [10.0 + k for k in range(6)]
    assert radar.start.tolist() == list(range(7))
    assert len(warnings) == 1
    assert "1 scan(s) stamped earlier than the scan before, sorted" in warnings[0]


@pytest.mark.parametrize("kind", ["sqlite3", "mcap"])
def test_camera_frames_of_a_bag_read_out_of_order_come_in_time_order(
    tmp_path: Path, kind: Kind
) -> None:
    def frames(ks: range) -> list[Message]:
        return [("/cam", IMAGE, _t(k), raw_image(_t(k), MONO8 + k, "mono8")) for k in ks]

    path = write_multifile_bag(tmp_path / "bag", kind, [frames(range(2, 4)), frames(range(2))])
    with BagReader(path) as bag:
        stream = CameraStream(bag, None)
        assert stream.backwards == 1
        assert stream.times_ns.tolist() == [_t(k) for k in range(4)]
        for k in (*range(4), 1, 2, 3):
            np.testing.assert_array_equal(stream.image(k), MONO8 + k)


def test_a_ros1_topic_from_two_publishers_reads_as_one_stream(tmp_path: Path) -> None:
    # rosbag record writes one connection per publisher of a topic
    path = tmp_path / "two.bag"
    with rosbag1.Writer(path) as writer:
        a, b = (
            writer.add_connection("/radar", RADAR_SCAN, typestore=ros1_typestore(), callerid=c)
            for c in ("/driver_a", "/driver_b")
        )
        for k, conn in enumerate([a, b, a, b]):
            scan = radar_scan(_t(k), [(10.0 + k, 0.0, 0.0, 1.0)])
            writer.write(conn, _t(k), serialize("ros1", RADAR_SCAN, scan))
    with BagReader(path) as bag:
        radar = bag.read_radar(bag.connection("/radar", RADAR_TYPES, "radar"), warn=pytest.fail)
    assert radar.range_m.tolist() == [10.0, 11.0, 12.0, 13.0]
    assert radar.t_ns.tolist() == [_t(k) for k in range(4)]


@pytest.mark.parametrize("kind", KINDS)
def test_can_frames_from_a_bag(tmp_path: Path, kind: Kind) -> None:
    frames = [
        can_frame(_t(0), 0x123, b"\x01\x02", channel="can0"),
        can_frame(_t(1), 0x1ABCDEF0, bytes(range(8)), is_extended=True),
        can_frame(_t(2), 0x200, b"", is_rtr=True, dlc=4),
        can_frame(_t(3), 0x20000080, b"\x00" * 8, is_error=True),
        can_frame(_t(4), 0x7FF, b"", channel="can1"),
        # padding beyond dlc is not data
        {**can_frame(_t(5), 0x300, b"\xaa\xbb\xcc"), "data": b"\xaa\xbb\xcc\x11\x22\x33\x44\x55"},
    ]
    messages: list[Message] = [("/can", CAN_FRAME, _t(k), f) for k, f in enumerate(frames)]
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        got = list(bag.can_frames(bag.connection(None, CAN_TYPES, "CAN")))
    assert got == [
        CanFrame(_t(0), 0x123, False, b"\x01\x02", "can0"),
        CanFrame(_t(1), 0x1ABCDEF0, True, bytes(range(8)), None),
        CanFrame(_t(4), 0x7FF, False, b"", "can1"),
        CanFrame(_t(5), 0x300, False, b"\xaa\xbb\xcc", None),
    ]


@pytest.mark.parametrize("kind", KINDS)
def test_a_can_frame_with_dlc_over_8_names_topic_and_stamp(tmp_path: Path, kind: Kind) -> None:
    messages: list[Message] = [
        ("/can", CAN_FRAME, _t(0), can_frame(_t(0), 0x10, b"\x01")),
        ("/can", CAN_FRAME, _t(1), can_frame(_t(1), 0x11, bytes(8), dlc=9)),
    ]
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        frames = bag.can_frames(bag.connection("/can", CAN_TYPES, "CAN"))
        assert next(frames).arbitration_id == 0x10
        with pytest.raises(
            RecordingError,
            match=rf"{bag.path}: /can at 1700000000\.173456789 s \(log t={_t(1)} ns\): CAN frame "
            r"with dlc 9; expected at most 8 data bytes",
        ):
            next(frames)


# --- topics found by type ----------------------------------------------------------------
def _one_of_each(t: int) -> list[Message]:
    return [
        ("/cam", IMAGE, t, raw_image(t, MONO8, "mono8")),
        ("/radar", RADAR_TRACKS, t, radar_tracks(t, [])),
        ("/can", CAN_FRAME, t, can_frame(t, 1, b"")),
        ("/other", "std_msgs/msg/String", t, {"data": "hello"}),
    ]


@pytest.mark.parametrize("kind", KINDS)
def test_topics_are_found_by_type(tmp_path: Path, kind: Kind) -> None:
    with BagReader(_write(tmp_path, kind, _one_of_each(_t(0)))) as bag:
        assert bag.connection(None, CAMERA_TYPES, "camera").topic == "/cam"
        assert bag.connection(None, RADAR_TYPES, "radar").topic == "/radar"
        assert bag.connection(None, CAN_TYPES, "CAN").topic == "/can"
        np.testing.assert_array_equal(CameraStream(bag, None).image(0), MONO8)


@pytest.mark.parametrize("kind", KINDS)
def test_several_candidates_are_listed(tmp_path: Path, kind: Kind) -> None:
    t = _t(0)
    messages = [
        *_one_of_each(t),
        ("/cam2", COMPRESSED_IMAGE, t, compressed_image(t, _png(MONO8), "png")),
        ("/radar2", RADAR_SCAN, t, radar_scan(t, [])),
        ("/can2", CAN_FRAME, t, can_frame(t, 2, b"")),
    ]
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        for types, role, listed in [
            (CAMERA_TYPES, "camera", "/cam, /cam2"),
            (RADAR_TYPES, "radar", "/radar, /radar2"),
            (CAN_TYPES, "CAN", "/can, /can2"),
        ]:
            with pytest.raises(
                RecordingError, match=rf"several {role} topics .* \({listed}\); name one"
            ):
                bag.connection(None, types, role)


@pytest.mark.parametrize("kind", KINDS)
def test_no_candidate_is_an_error_listing_the_topics(tmp_path: Path, kind: Kind) -> None:
    t = _t(0)
    messages: list[Message] = [("/other", "std_msgs/msg/String", t, {"data": "x"})]
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        for types, role in [(CAMERA_TYPES, "camera"), (RADAR_TYPES, "radar"), (CAN_TYPES, "CAN")]:
            with pytest.raises(
                RecordingError,
                match=rf"{bag.path}: no {role} topics of type .* \(none\).*"
                r"Topics in the bag: /other \(std_msgs/msg/String\)",
            ):
                bag.connection(None, types, role)
        with pytest.raises(
            RecordingError, match=r"no camera topic '/cam'; topics in the bag: /other"
        ):
            bag.connection("/cam", CAMERA_TYPES, "camera")
        with pytest.raises(
            RecordingError, match=r"radar topic '/other' has type std_msgs/msg/String"
        ):
            bag.connection("/other", RADAR_TYPES, "radar")


@pytest.mark.parametrize("kind", ["ros1", "mcap"])
def test_a_vendor_message_of_the_same_name_is_refused(tmp_path: Path, kind: Kind) -> None:
    store = get_typestore(Stores.ROS1_NOETIC if kind == "ros1" else Stores.ROS2_HUMBLE)
    vendor = "std_msgs/Header header\nfloat32[] ranges\nfloat32[] angles\n"
    store.register(get_types_from_msg(vendor, RADAR_SCAN))
    t = _t(0)
    fields = {"header": {"stamp": {"sec": 1, "nanosec": 0}}, "ranges": [1.0], "angles": [0.0]}
    path = write_bag(bag_path(tmp_path, kind), kind, [("/radar", RADAR_SCAN, t, fields)], store)
    with (
        BagReader(path) as bag,
        pytest.raises(
            RecordingError,
            match=rf"{bag.path}: radar topic /radar: the bag's {RADAR_SCAN} has no field returns$",
        ),
    ):
        bag.connection(None, RADAR_TYPES, "radar")


# --- bad input ---------------------------------------------------------------------------
def _storage_file(path: Path) -> Path:
    """The one file holding the messages: the .bag itself, or the folder's .db3 / .mcap."""
    if path.is_file():
        return path
    (found,) = [p for p in path.iterdir() if p.suffix in (".db3", ".mcap")]
    return found


def _drive_bag(tmp_path: Path, kind: Kind, n: int = 40) -> Path:
    """A bag of n camera frames (raw mono8, 32x24, so the file is some 40 KB) and radar."""
    messages: list[Message] = []
    for k in range(n):
        img = np.full((24, 32), k, np.uint8)
        messages.append(("/cam", IMAGE, _t(k), raw_image(_t(k), img, "mono8")))
        messages.append(
            ("/radar", RADAR_SCAN, _t(k) + 1, radar_scan(_t(k) + 1, [(10.0, 0.0, 0.0, 1.0)]))
        )
    return _write(tmp_path, kind, messages)


def _read_everything(path: Path) -> None:
    with BagReader(path) as bag:
        stream = CameraStream(bag, "/cam")
        for k in range(len(stream)):
            stream.image(k)
        bag.read_radar(bag.connection("/radar", RADAR_TYPES, "radar"), warn=lambda _: None)


@pytest.mark.parametrize("kind", KINDS)
def test_read_everything_works_on_the_intact_bag(tmp_path: Path, kind: Kind) -> None:
    _read_everything(_drive_bag(tmp_path, kind))  # the baseline of the damage tests below


@pytest.mark.parametrize("kind", KINDS)
def test_truncated_bag(tmp_path: Path, kind: Kind) -> None:
    path = _drive_bag(tmp_path, kind)
    storage = _storage_file(path)
    data = storage.read_bytes()
    storage.write_bytes(data[: len(data) // 2])
    with pytest.raises(RecordingError, match=rf"^{path}"):
        _read_everything(path)


def _mcap_records(data: bytes, start: int, end: int) -> list[tuple[int, int, int]]:
    """(offset, opcode, length) of the MCAP records between start and end."""
    records, pos = [], start
    while pos < end:
        op, length = struct.unpack_from("<BQ", data, pos)
        records.append((pos, op, length))
        pos += 9 + length
    return records


def test_corrupt_mcap_chunk(tmp_path: Path) -> None:
    path = _drive_bag(tmp_path, "mcap")
    storage = _storage_file(path)
    data = bytearray(storage.read_bytes())
    header_end = 8 + 9 + struct.unpack_from("<Q", data, 9)[0]
    (chunk, op, _) = _mcap_records(data, header_end, header_end + 1)[0]
    assert op == 0x06
    # chunk body: start, end, uncompressed size (8 bytes each), crc (4), compression (4 + 0)
    records_start = chunk + 9 + 8 * 3 + 4 + 4 + 8
    records_len = struct.unpack_from("<Q", data, records_start - 8)[0]
    messages = [
        r for r in _mcap_records(data, records_start, records_start + records_len) if r[1] == 0x05
    ]
    # The 5th message record claims to run past the end of its chunk (rosbags reads a chunk
    # whole before it yields any of its messages).
    struct.pack_into("<Q", data, messages[4][0] + 1, 2**40)
    storage.write_bytes(bytes(data))
    with pytest.raises(
        RecordingError,
        match=rf"^{path}: /cam: cannot read the first message: Truncated record",
    ):
        _read_everything(path)


def test_garbage_sqlite3_file(tmp_path: Path) -> None:
    path = _drive_bag(tmp_path, "sqlite3")
    storage = _storage_file(path)
    storage.write_bytes(np.random.default_rng(3).bytes(storage.stat().st_size))
    with pytest.raises(RecordingError, match=rf"^{path}: cannot open as a ROS bag .*database"):
        BagReader(path)


@pytest.mark.parametrize("name", ["empty.bag", "empty.db3", "empty.mcap", "empty.txt"])
def test_empty_file(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    path.write_bytes(b"")
    with pytest.raises(RecordingError, match=rf"^{path}: cannot open as a ROS bag \(expected"):
        BagReader(path)


def test_folder_without_metadata(tmp_path: Path) -> None:
    path = _drive_bag(tmp_path, "mcap")
    (path / "metadata.yaml").unlink()
    with pytest.raises(RecordingError, match=rf"^{path}: cannot open as a ROS bag .*metadata"):
        BagReader(path)


def test_missing_path(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match=rf"^{tmp_path / 'nothing'}: cannot open as a ROS bag"):
        BagReader(tmp_path / "nothing")


@pytest.mark.parametrize("kind", KINDS)
def test_a_message_that_fails_to_deserialise(tmp_path: Path, kind: Kind) -> None:
    garbage = b"\x00\x01\x00\x00" + b"\xff" * 7
    messages: list[Message] = [
        ("/cam", IMAGE, _t(0), raw_image(_t(0), MONO8, "mono8")),
        ("/cam", IMAGE, _t(1), garbage),
        ("/radar", RADAR_SCAN, _t(2), garbage),
    ]
    with BagReader(_write(tmp_path, kind, messages)) as bag:
        stream = CameraStream(bag, None)
        np.testing.assert_array_equal(stream.image(0), MONO8)
        with pytest.raises(
            RecordingError,
            match=rf"^{bag.path}: /cam: message at log t={_t(1)} ns is not a valid {IMAGE}",
        ):
            stream.image(1)
        with pytest.raises(
            RecordingError,
            match=rf"^{bag.path}: /radar: message at log t={_t(2)} ns is not a valid {RADAR_SCAN}",
        ):
            bag.read_radar(bag.connection(None, RADAR_TYPES, "radar"), warn=lambda _: None)


def test_a_log_time_beyond_int64_is_an_error(tmp_path: Path) -> None:
    t = 2**63 + 5
    messages: list[Message] = [("/cam", IMAGE, t, raw_image(0, MONO8, "mono8"))]
    with (
        BagReader(_write(tmp_path, "mcap", messages)) as bag,
        pytest.raises(
            RecordingError,
            match=rf"/cam: the first message has log time {t} ns; expected an integer",
        ),
    ):
        CameraStream(bag, None)


# --- decode_image on bad messages -------------------------------------------------------
def _raw_msg(**change: Any) -> Any:
    from bagmaker import build, typestore

    return build(typestore("mcap"), IMAGE, {**raw_image(0, MONO8, "mono8"), **change})


@pytest.mark.parametrize(
    ("change", "error"),
    [
        ({"encoding": "yuv422"}, r"where: image encoding 'yuv422' not supported; expected one of"),
        ({"step": 3}, r"where: expected a 4x2 mono8 image of rows of at least 4 bytes, got step 3"),
        ({"data": bytes(7)}, r"got step 4 and 7 bytes"),
        ({"width": 0}, r"expected a 0x2 mono8 image"),
        ({"encoding": "mono16"}, r"rows of at least 8 bytes, got step 4"),
    ],
)
def test_bad_raw_images(change: dict[str, Any], error: str) -> None:
    with pytest.raises(RecordingError, match=error):
        decode_image(_raw_msg(**change), IMAGE, "where")


def test_compressed_data_that_is_neither_png_nor_jpeg() -> None:
    from bagmaker import build, typestore

    gif = build(typestore("mcap"), COMPRESSED_IMAGE, compressed_image(0, b"GIF89a....", "gif"))
    with pytest.raises(RecordingError, match=r"where: cannot decode image: expected PNG or JPEG"):
        decode_image(gif, COMPRESSED_IMAGE, "where")
    broken = build(
        typestore("mcap"), COMPRESSED_IMAGE, compressed_image(0, _png(MONO8)[:30], "png")
    )
    with pytest.raises(RecordingError, match=r"that OpenCV cannot decode"):
        decode_image(broken, COMPRESSED_IMAGE, "where")


@pytest.mark.parametrize("bits", [0, 17])
def test_mono16_bits_out_of_range(bits: int) -> None:
    with pytest.raises(
        ValueError, match=rf"mono16_bits: expected 1 to 16 significant bits, got {bits}"
    ):
        decode_image(_raw_msg(), IMAGE, "where", bits)


def test_close_twice_is_harmless(tmp_path: Path) -> None:
    bag = BagReader(_write(tmp_path, "mcap", _one_of_each(_t(0))))
    bag.close()
    bag.close()
