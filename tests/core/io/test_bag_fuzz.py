"""Fuzzing: a damaged bag of any kind reads, or raises RecordingError; nothing else, no hang.

Hypothesis flips, inserts, deletes and truncates bytes of small valid bags (ROS 1, ROS 2
sqlite3, ROS 2 MCAP; for ROS 2, of the storage file in its folder, of metadata.yaml, or of the
storage file opened alone), uncompressed and in every compression rosbags writes, then opens
each, indexes and decodes both camera topics, reads both radar topics and the CAN topic.

FUZZ_EXAMPLES sets the number of damaged bags per kind, and for the compressed variants
together (default: a short run for CI, some 10 s in all). Run
`pytest tests/core/io/test_bag_fuzz.py --hypothesis-show-statistics` to see where they failed.
"""

from __future__ import annotations

import os
import signal
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from functools import cache
from pathlib import Path
from types import FrameType

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
    write_bag,
)
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from core.io.bag import CAN_TYPES, RADAR_TYPES, BagReader, CameraStream
from core.io.errors import RecordingError
from core.io.radar_msgs import CAN_FRAME, COMPRESSED_IMAGE, IMAGE, RADAR_SCAN, RADAR_TRACKS

FUZZ_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "200"))
# One damaged bag reads in milliseconds; this long means a loop that does not end.
HANG_S = 20
T0_NS = 1_700_000_000_000_000_000
PERIOD_NS = 100_000_000
METADATA = "metadata.yaml"


def _messages() -> list[Message]:
    """Three frames on two camera topics (PNG and raw mono16), radar scans, tracks, CAN."""
    messages: list[Message] = []
    for k in range(3):
        t = T0_NS + k * PERIOD_NS
        img = (np.arange(48, dtype=np.uint8).reshape(6, 8) * 5 + k).astype(np.uint8)
        ok, png = cv2.imencode(".png", img)
        assert ok
        messages += [
            ("/cam", COMPRESSED_IMAGE, t, compressed_image(t, png.tobytes(), "png")),
            ("/raw", IMAGE, t + 1, raw_image(t + 1, img.astype(np.uint16) * 200, "mono16")),
            ("/radar", RADAR_SCAN, t + 2, radar_scan(t + 2, [(10.0 + k, 0.1, -1.0, 5.0)] * k)),
            (
                "/tracks",
                RADAR_TRACKS,
                t + 3,
                radar_tracks(t + 3, [(bytes(range(16)), (10.0, 2.0 * k), (1.0, 0.5))]),
            ),
            ("/can", CAN_FRAME, t + 4, can_frame(t + 4, 0x100 + k, bytes(range(k + 1)))),
        ]
    return messages


@cache
def _valid_bag(kind: Kind, compression: Compression) -> dict[str, bytes]:
    """The files of a valid bag of `kind`: name -> content ("" is the .bag file itself)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = write_bag(bag_path(Path(tmp), kind), kind, _messages(), compression=compression)
        if path.is_file():
            return {"": path.read_bytes()}
        return {p.name: p.read_bytes() for p in sorted(path.iterdir())}


Edit = tuple[str, int, bytes]


def _damage(data: bytes, edits: list[Edit]) -> bytes:
    """Apply edits: (what, position as a fraction of 2**16 of the length, bytes)."""
    buf = bytearray(data)
    for what, where, payload in edits:
        pos = where * len(buf) // 2**16
        if what == "flip":
            buf[pos : pos + len(payload)] = bytes(
                b ^ (p or 1) for b, p in zip(buf[pos : pos + len(payload)], payload, strict=False)
            )
        elif what == "insert":
            buf[pos:pos] = payload
        elif what == "delete":
            del buf[pos : pos + len(payload)]
        else:
            del buf[pos:]
    return bytes(buf)


EDITS = st.lists(
    st.tuples(
        st.sampled_from(["flip", "flip", "insert", "delete", "truncate"]),
        st.integers(0, 2**16 - 1),
        st.binary(min_size=1, max_size=8),
    ),
    min_size=1,
    max_size=4,
)


class HangError(Exception):
    """A damaged bag kept the reader busy past HANG_S."""


@contextmanager
def _time_limit(seconds: int) -> Iterator[None]:
    def alarm(signum: int, frame: FrameType | None) -> None:
        raise HangError(f"reading took longer than {seconds} s")

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _step(name: str, read: Callable[[], object]) -> None:
    """Run one reading step; a RecordingError is a fine outcome, anything else fails."""
    try:
        read()
    except RecordingError:
        event(f"{name}: RecordingError")
    else:
        event(f"{name}: read")


def _read_everything(path: Path) -> None:
    try:
        bag = BagReader(path)
    except RecordingError:
        event("open: RecordingError")
        return
    with bag:
        for topic in ("/cam", "/raw"):

            def camera(topic: str = topic) -> None:
                stream = CameraStream(bag, topic, mono16_bits=12)
                for k in range(len(stream)):
                    image = stream.image(k)
                    assert image.dtype == np.uint8 and image.ndim == 2

            _step(f"camera {topic}", camera)
        for topic in ("/radar", "/tracks"):

            def radar(topic: str = topic) -> None:
                conn = bag.connection(topic, RADAR_TYPES, "radar")
                scans = bag.read_radar(conn, warn=lambda _: None)
                assert np.all(np.diff(scans.t_ns) >= 0)
                assert np.all(np.diff(scans.start) >= 0)
                assert scans.start[0] == 0 and scans.start[-1] == len(scans.range_m)
                assert np.all(np.isfinite(scans.range_m) & np.isfinite(scans.range_rate_mps))

            _step(f"radar {topic}", radar)
        _step("can", lambda: list(bag.can_frames(bag.connection("/can", CAN_TYPES, "CAN"))))


# What of a ROS 2 bag is damaged (a ROS 1 bag is one file).
PARTS = ("storage file", "metadata.yaml", "storage file alone")


def _write_damaged(
    folder: Path, kind: Kind, compression: Compression, part: str, edits: list[Edit]
) -> Path:
    files = dict(_valid_bag(kind, compression))
    if "" in files:
        path = bag_path(folder, kind)
        path.write_bytes(_damage(files[""], edits))
        return path
    (storage,) = [name for name in files if name != METADATA]
    if part == "storage file alone" and compression != "zstd-file":  # needs metadata.yaml
        path = folder / storage
        path.write_bytes(_damage(files[storage], edits))
        return path
    damaged = METADATA if part == METADATA else storage
    files[damaged] = _damage(files[damaged], edits)
    path = bag_path(folder, kind)
    path.mkdir()
    for name, content in files.items():
        (path / name).write_bytes(content)
    return path


@pytest.mark.fuzz
@pytest.mark.parametrize("kind", KINDS)
@settings(
    max_examples=FUZZ_EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(edits=EDITS, part=st.sampled_from(PARTS))
def test_damaged_bags_read_or_raise_recording_error(
    kind: Kind, edits: list[Edit], part: str
) -> None:
    event(f"damaged: {'the .bag file' if kind == 'ros1' else part}")
    with tempfile.TemporaryDirectory() as tmp:
        path = _write_damaged(Path(tmp), kind, "none", part, edits)
        with _time_limit(HANG_S):
            _read_everything(path)


COMPRESSED = [(k, c) for k in KINDS for c in COMPRESSIONS[k] if c != "none"]


@pytest.mark.fuzz
@settings(
    max_examples=FUZZ_EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(variant=st.sampled_from(COMPRESSED), edits=EDITS, part=st.sampled_from(PARTS))
def test_damaged_compressed_bags_read_or_raise_recording_error(
    variant: tuple[Kind, Compression], edits: list[Edit], part: str
) -> None:
    kind, compression = variant
    event(f"compression: {kind} {compression}")
    with tempfile.TemporaryDirectory() as tmp:
        path = _write_damaged(Path(tmp), kind, compression, part, edits)
        with _time_limit(HANG_S):
            _read_everything(path)


def test_the_valid_bags_read_whole() -> None:
    """The fuzzing starts from bags that read without error (else it tests nothing)."""
    for kind, compression in [(k, "none") for k in KINDS] + COMPRESSED:
        with tempfile.TemporaryDirectory() as tmp:
            path = _write_damaged(Path(tmp), kind, compression, "storage file", [])
            with BagReader(path) as bag:
                assert len(CameraStream(bag, "/cam")) == 3
                assert CameraStream(bag, "/raw").image(2).shape == (6, 8)
                tracks = bag.read_radar(
                    bag.connection("/tracks", RADAR_TYPES, "radar"), warn=pytest.fail
                )
                assert len(tracks.t_ns) == 3
                assert len(list(bag.can_frames(bag.connection(None, CAN_TYPES, "CAN")))) == 3
