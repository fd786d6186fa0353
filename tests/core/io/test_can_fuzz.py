"""Fuzzing: CAN logs with garbage read, or raise RecordingError; nothing else, no hang.

Text logs (candump -L, ASC, TRC, CSV) written by python-can keep all their good lines, amid
inserted garbage: mutated copies of good lines (characters replaced, deleted, inserted,
swapped, lines cut short), random text and binary junk. Every good line's frame must come
through, in order, and the decoders (speed and yaw rate, radar tracks) must take whatever
frames come. Binary logs (BLF, and gzip'd logs) get bytes flipped, overwritten, inserted,
deleted and cut; they must read or raise RecordingError, within a time limit.

FUZZ_EXAMPLES sets the number of examples per test (default: a short run for CI). Run
`pytest tests/core/io/test_can_fuzz.py --hypothesis-show-statistics` to see the outcomes.
"""

from __future__ import annotations

import gzip
import os
import re
import signal
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from types import FrameType

import can
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from core.io.can_radar import RadarCanDecoder
from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.canlog import (
    VehicleSignalDecoder,
    decode_frames,
    load_dbc,
)
from core.io.errors import RecordingError
from core.io.manifest import CanBus, CanSource, RadarCanSource, RadarField
from core.io.writer import SPEED_SIGNAL, YAW_RATE_SIGNAL, vehicle_dbc_path

pytestmark = pytest.mark.fuzz

FUZZ_EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "60"))
# A damaged log of a few dozen lines reads in milliseconds; this long means an endless loop.
HANG_S = 20
SETTINGS = settings(
    max_examples=FUZZ_EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)

RADAR_DBC = 'VERSION ""\n\nNS_ :\n\nBS_:\n\nBU_: XXX\n\n' + "\n".join(
    f"""BO_ {0x210 + i} TRACK_A_{i}: 8 XXX
 SG_ LONG_DIST : 15|13@0+ (0.04,0) [0|300] "m" XXX
 SG_ LAT_DIST : 31|11@0- (0.04,0) [-50|50] "m" XXX
 SG_ REL_SPEED : 47|12@0- (0.025,0) [-100|100] "m/s" XXX
 SG_ VALID : 48|1@0+ (1,0) [0|1] "" XXX
"""
    for i in range(4)
)
TEXT_SUFFIXES = (".log", ".asc", ".trc", ".csv")
WRITERS = {
    ".log": can.CanutilsLogWriter,
    ".asc": can.ASCWriter,
    ".trc": can.TRCWriter,
    ".csv": can.CSVWriter,
    ".blf": can.BLFWriter,
}
FOOTER_LINES = {".log": 0, ".asc": 1, ".trc": 0, ".csv": 0}


def _messages() -> list[can.Message]:
    """Speed and yaw rate (the bundled vehicle DBC) and four radar tracks, some frames short."""
    out = []
    for k in range(4):
        t = 46408.5 + 0.05 * k
        out.append(
            can.Message(
                timestamp=t,
                arbitration_id=0xB4,
                is_extended_id=False,
                data=bytes([0, 0, 0, 0, 0, 0x1D, 0x0B + k, 0x7A]),
                channel=0,
            )
        )
        out.append(
            can.Message(
                timestamp=t + 0.001,
                arbitration_id=0x24,
                is_extended_id=False,
                data=bytes([0x80 >> k, 3]),
                channel=0,
            )
        )
        for i in range(4):
            data = bytes([k, 0x02, 0x9A - i, 0x04 + i, 0x10, 0x7F, 0x80 * (i % 2), 0x11])
            out.append(
                can.Message(
                    timestamp=t + 0.002 + 1e-4 * i,
                    arbitration_id=0x210 + i,
                    is_extended_id=False,
                    data=data[: 8 - (i == 3) * 2],
                    channel=1,
                )
            )
    out.append(
        can.Message(
            timestamp=46409.0,
            arbitration_id=0x18FEF100,
            is_extended_id=True,
            data=b"\x01\x02\x03",
            channel=1,
        )
    )
    return out


MESSAGES = _messages()
EXPECTED = [(m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in MESSAGES]


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("can_fuzz")
    (path / "radar.dbc").write_text(RADAR_DBC)
    for suffix, writer in WRITERS.items():
        with writer(str(path / f"valid{suffix}")) as w:
            for m in MESSAGES:
                w.on_message_received(m)
    return path


@contextmanager
def _time_limit(what: str) -> Iterator[None]:
    def hang(signum: int, frame: FrameType | None) -> None:
        pytest.fail(f"{what}: still running after {HANG_S} s (an endless loop?)")

    previous = signal.signal(signal.SIGALRM, hang)
    signal.alarm(HANG_S)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _decode_all(frames: list[CanFrame], folder: Path) -> None:
    """Both decoders over the frames: they must not raise, whatever came."""
    vehicle = VehicleSignalDecoder(
        load_dbc([vehicle_dbc_path()]),
        CanSource(
            CanBus(("vehicle.dbc",), log="x.log"),
            SPEED_SIGNAL,
            YAW_RATE_SIGNAL,
            "standstill",
        ),
        "fuzz",
    )
    radar = RadarCanDecoder(
        load_dbc([folder / "radar.dbc"]),
        RadarCanSource(
            CanBus(("radar.dbc",), log="x.log"),
            "TRACK_A_*",
            RadarField("LONG_DIST", "m"),
            RadarField("LAT_DIST", "m", sign=-1),
            RadarField("REL_SPEED", "m/s"),
            RadarField("VALID"),
        ),
        "fuzz",
    )
    warnings: list[str] = []
    decode_frames(frames, [vehicle, radar])
    signals, scans = vehicle.result(warnings.append), radar.result(warnings.append)
    assert len(signals.speed_t_ns) == len(signals.speed_mps)
    assert scans.start[-1] == len(scans.range_m)


# --- text logs ------------------------------------------------------------------------------
CHARS = st.sampled_from(
    "0123456789ABCDEFabcdefxX#().,;:$ -+eEnNiIfF_RrTtd\t\x00\xff"
) | st.characters(
    exclude_categories=["Cs"]  # surrogates: not text a file can hold
)


@st.composite
def _mutated(draw: st.DrawFn, line: str) -> str:
    chars = list(line)
    for _ in range(draw(st.integers(1, 4))):
        if not chars:
            break
        i = draw(st.integers(0, len(chars) - 1))
        op = draw(st.sampled_from(["replace", "delete", "insert", "cut", "swap"]))
        if op == "replace":
            chars[i] = draw(CHARS)
        elif op == "delete":
            del chars[i]
        elif op == "insert":
            chars.insert(i, draw(CHARS))
        elif op == "cut":
            del chars[i:]
        else:
            j = draw(st.integers(0, len(chars) - 1))
            chars[i], chars[j] = chars[j], chars[i]
    return "".join(chars)


@st.composite
def _damaged_text_log(draw: st.DrawFn, suffix: str, folder: Path) -> tuple[bytes, bool]:
    """A valid log with garbage lines inserted; True when a garbage line could be a header
    line that changes how the rest reads (TRC `;$...`, ASC `base`)."""
    lines = (folder / f"valid{suffix}").read_text().splitlines()
    n_frames = len(MESSAGES)
    end = len(lines) - FOOTER_LINES[suffix]
    head, good, foot = lines[: end - n_frames], lines[end - n_frames : end], lines[end:]
    garbage = st.one_of(
        st.sampled_from(good).flatmap(_mutated).map(str.encode),
        st.text(max_size=60).map(str.encode),
        st.binary(max_size=60),
    )
    body: list[bytes] = []
    header_like = False
    for line in good:
        for junk in draw(st.lists(garbage, max_size=2)):
            body.append(junk)
            for piece in re.split(r"\r\n|\r|\n", junk.decode("utf-8", "replace")):
                words = piece.split()
                header_like |= piece.strip().startswith(";$") or (
                    bool(words) and words[0].lower() == "base"
                )
        body.append(line.encode())
    text = b"\n".join([*(x.encode() for x in head), *body, *(x.encode() for x in foot)]) + b"\n"
    return text, header_like


def _is_subsequence(wanted: list[object], got: list[object]) -> bool:
    it = iter(got)
    return all(any(w == g for g in it) for w in wanted)


@pytest.mark.parametrize("suffix", TEXT_SUFFIXES)
@SETTINGS
@given(data=st.data())
def test_text_log_with_garbage_keeps_every_good_line(
    folder: Path, suffix: str, data: st.DataObject
) -> None:
    path = folder / f"damaged{suffix}"
    text, header_like = data.draw(_damaged_text_log(suffix, folder))
    path.write_bytes(text)
    warnings: list[str] = []
    with _time_limit(f"{suffix} with garbage"):
        try:
            frames = list(iter_log_frames(path, warn=warnings.append))
        except RecordingError:
            event("RecordingError")
            assert header_like, "only a garbage header line may make the file unreadable"
            return
        got = [(f.arbitration_id, f.is_extended, f.data) for f in frames]
        assert _is_subsequence(list(EXPECTED), list(got))
        event(f"{len(got) - len(EXPECTED)} extra frames from garbage")
        event(f"{len(warnings)} warnings")
        assert len(warnings) <= 1
        _decode_all(frames, folder)


# --- binary logs ----------------------------------------------------------------------------
@st.composite
def _damaged_bytes(draw: st.DrawFn, data: bytes) -> bytes:
    b = bytearray(data)
    for _ in range(draw(st.integers(1, 6))):
        if not b:
            break
        i = draw(st.integers(0, len(b) - 1))
        op = draw(st.sampled_from(["flip", "overwrite", "insert", "delete", "cut"]))
        if op == "flip":
            b[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "overwrite":
            chunk = draw(st.binary(min_size=1, max_size=8))
            b[i : i + len(chunk)] = chunk
        elif op == "insert":
            b[i:i] = draw(st.binary(min_size=1, max_size=8))
        elif op == "delete":
            del b[i : i + draw(st.integers(1, 8))]
        else:
            del b[i:]
    return bytes(b)


@pytest.mark.parametrize("name", ["valid.blf", "valid.blf.gz", "valid.log.gz", "valid.asc.gz"])
@SETTINGS
@given(data=st.data())
def test_damaged_binary_log_reads_or_raises_recording_error(
    folder: Path, name: str, data: st.DataObject
) -> None:
    original = (folder / name.removesuffix(".gz")).read_bytes()
    if name.endswith(".gz"):
        original = gzip.compress(original, mtime=0)
    path = folder / f"damaged_{name}"
    path.write_bytes(data.draw(_damaged_bytes(original)))
    warnings: list[str] = []
    with _time_limit(name):
        try:
            frames = list(iter_log_frames(path, warn=warnings.append))
        except RecordingError as err:
            event("RecordingError")
            assert str(path) in str(err)
            return
        event(f"{len(frames)} of {len(MESSAGES)} frames, {len(warnings)} warnings")
        _decode_all(frames, folder)
