"""CAN log files: every format python-can writes reads back; bad lines are skipped and reported.

Round trips write the same frames with python-can's writers (and gzip'd) and compare ids,
extended flags, data, channels and time stamps within each format's precision. Hand-written
excerpts cover what the writers do not write (TRC 1.x, ASC in decimal, CAN FD, events).
"""

from __future__ import annotations

import gzip
import shutil
import signal
import struct
import zlib
from collections.abc import Callable
from pathlib import Path
from types import FrameType

import can
import pytest
from can.io import blf
from can.io.trc import TRCFileVersion

from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.errors import RecordingError

T0_S = 1_700_000_000.123456
STEP_S = 0.0137


def _messages() -> list[can.Message]:
    """Six data frames (standard and extended, 0 to 8 bytes, channels 0 and 1), an error
    frame and a remote frame."""
    out = [
        can.Message(
            timestamp=T0_S + i * STEP_S,
            arbitration_id=(0x18FEF100 + i) if i % 2 else (0x0B4 + i),
            is_extended_id=bool(i % 2),
            data=bytes(range(10 * i, 10 * i + [8, 3, 0, 8, 1, 5][i])),
            channel=i % 2,
        )
        for i in range(6)
    ]
    t_end = T0_S + 6 * STEP_S
    out.append(can.Message(timestamp=t_end, is_error_frame=True, channel=0))
    out.append(
        can.Message(
            timestamp=t_end + STEP_S,
            arbitration_id=0x123,
            is_extended_id=False,
            is_remote_frame=True,
            dlc=2,
            channel=0,
        )
    )
    return out


DATA = [m for m in _messages() if not (m.is_error_frame or m.is_remote_frame)]

# suffix: writer, channel as read for python-can channel c, time precision (s), relative times
FORMATS: dict[
    str,
    tuple[Callable[..., can.io.generic.MessageWriter], Callable[[int], str | None], float, bool],
] = {
    ".log": (can.CanutilsLogWriter, lambda c: f"can{c}", 1e-6, False),
    ".asc": (can.ASCWriter, lambda c: str(c + 1), 1e-6, True),
    ".trc": (can.TRCWriter, lambda c: str(c + 1), 2e-6, False),
    ".csv": (can.CSVWriter, lambda c: None, 1e-9, False),
    ".blf": (can.BLFWriter, lambda c: str(c + 1), 1e-9, False),
}


def _write(path: Path, suffix: str, messages: list[can.Message]) -> None:
    writer = FORMATS[suffix][0]
    with writer(str(path)) as w:
        for m in messages:
            w.on_message_received(m)


def _read(path: Path) -> tuple[list[CanFrame], list[str]]:
    warnings: list[str] = []
    return list(iter_log_frames(path, warn=warnings.append)), warnings


def _check_round_trip(frames: list[CanFrame], suffix: str) -> None:
    _, channel_of, precision_s, relative = FORMATS[suffix]
    assert [(f.arbitration_id, f.is_extended, f.data) for f in frames] == [
        (m.arbitration_id, m.is_extended_id, bytes(m.data)) for m in DATA
    ]
    assert [f.channel for f in frames] == [channel_of(i % 2) for i in range(len(DATA))]
    t0_ns = frames[0].t_ns if relative else 0
    m0_s = DATA[0].timestamp if relative else 0.0
    for f, m in zip(frames, DATA, strict=True):
        assert (f.t_ns - t0_ns) / 1e9 == pytest.approx(m.timestamp - m0_s, abs=precision_s)


@pytest.mark.parametrize("suffix", list(FORMATS))
def test_round_trip_through_each_python_can_writer(tmp_path: Path, suffix: str) -> None:
    path = tmp_path / f"frames{suffix}"
    _write(path, suffix, _messages())
    frames, warnings = _read(path)
    _check_round_trip(frames, suffix)
    assert warnings == []


@pytest.mark.parametrize("suffix", [s for s in FORMATS if s != ".blf"])
def test_round_trip_gzip_written_by_python_can_logger(tmp_path: Path, suffix: str) -> None:
    path = tmp_path / f"frames{suffix}.gz"
    # can.Logger gzips text formats itself; it refuses .blf.gz (BLFWriter seeks back).
    with can.Logger(str(path)) as w:
        for m in _messages():
            w.on_message_received(m)
    assert path.read_bytes()[:2] == b"\x1f\x8b"
    frames, warnings = _read(path)
    _check_round_trip(frames, suffix)
    assert warnings == []


def test_round_trip_blf_gzipped_afterwards(tmp_path: Path) -> None:
    _write(tmp_path / "frames.blf", ".blf", _messages())
    with (tmp_path / "frames.blf").open("rb") as src, gzip.open(tmp_path / "f.blf.gz", "wb") as dst:
        shutil.copyfileobj(src, dst)
    frames, warnings = _read(tmp_path / "f.blf.gz")
    _check_round_trip(frames, ".blf")
    assert warnings == []


def test_trc_version_1_0_as_written_by_python_can(tmp_path: Path) -> None:
    path = tmp_path / "v10.trc"
    with can.TRCWriter(str(path)) as w:
        w.file_version = TRCFileVersion.V1_0
        for m in DATA:
            w.on_message_received(m)
    frames, warnings = _read(path)
    assert warnings == []
    assert [(f.arbitration_id, f.is_extended, f.data, f.channel) for f in frames] == [
        (m.arbitration_id, m.is_extended_id, bytes(m.data), None) for m in DATA
    ]
    # 1.0 has no start time: milliseconds since the first frame, rounded to 1 ms.
    for f, m in zip(frames, DATA, strict=True):
        assert f.t_ns / 1e9 == pytest.approx(m.timestamp - DATA[0].timestamp, abs=0.6e-3)


# --- hand-written excerpts -------------------------------------------------------------------
def _excerpt(tmp_path: Path, name: str, text: str) -> tuple[list[CanFrame], list[str]]:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return _read(path)


def test_trc_1_1_and_1_3_with_start_time(tmp_path: Path) -> None:
    # $STARTTIME 45000.5 days after 1899-12-30 = 2023-03-15 12:00:00 UTC = 1678881600 s.
    v11 = (
        ";$FILEVERSION=1.1\n;$STARTTIME=45000.5\n"
        "     1)      1059.9  Rx        0300  8  00 11 22 33 44 55 66 77\n"
        "     2)      1060.0  Warng FFFFFFFF  4  00 00 00 08  BUSHEAVY\n"
        "     3)      1061.5  Tx    18FEF100  2  AA BB\n"
        "     4)      1062.0  Rx        0100  3  RTR\n"
    )
    frames, warnings = _excerpt(tmp_path, "v11.trc", v11)
    assert warnings == []
    assert [(f.arbitration_id, f.is_extended, f.data, f.channel) for f in frames] == [
        (0x300, False, bytes.fromhex("0011223344556677"), None),
        (0x18FEF100, True, b"\xaa\xbb", None),
    ]
    # float seconds near 1.7e9 s resolve ~240 ns
    assert [f.t_ns for f in frames] == pytest.approx(
        [1678881601_059_900_000, 1678881601_061_500_000], abs=1000
    )
    v13 = (
        ";$FILEVERSION=1.3\n;$STARTTIME=45000.5\n"
        "     1)      1059.9 2  Rx        0300 -  2    01 02\n"
        "     2)      1060.0 1  Error     0000 -  0\n"
    )
    frames, warnings = _excerpt(tmp_path, "v13.trc", v13)
    assert warnings == []
    assert [(f.arbitration_id, f.data, f.channel) for f in frames] == [(0x300, b"\x01\x02", "2")]
    assert frames[0].t_ns == pytest.approx(1678881601_059_900_000, abs=1000)


def test_asc_decimal_base_events_and_can_fd(tmp_path: Path) -> None:
    asc = (
        "date Wed Mar 15 12:00:00.000 2023\n"
        "base dec  timestamps absolute\n"
        "no internal events logged\n"
        "// a comment\n"
        "Begin Triggerblock Wed Mar 15 12:00:00.000 2023\n"
        "   0.000000 Start of measurement\n"
        "   0.001000 1  Statistic: D 0 R 0 XD 0 XR 0 E 0 O 0 B 0.00%\n"
        "   0.002000 1  180             Rx   d 3 1 2 255\n"
        "   0.003000 2  ErrorFrame\n"
        "   0.004000 1  1000x           Tx   r 4\n"
        "   0.004500 1  180             TxRq d 3 1 2 255\n"
        "   0.005000 CANFD   2 Rx      291                                   1 0 9 12 "
        "1 2 3 4 5 6 7 8 9 10 11 12        0    0      3000        0        0        0        0"
        "        0\n"
        "End TriggerBlock\n"
    )
    frames, warnings = _excerpt(tmp_path, "dec.asc", asc)
    assert warnings == []
    assert [(f.t_ns, f.arbitration_id, f.is_extended, f.data, f.channel) for f in frames] == [
        (2_000_000, 180, False, bytes([1, 2, 255]), "1"),
        (5_000_000, 291, False, bytes(range(1, 13)), "2"),
    ]


def test_candump_fd_error_remote_and_direction(tmp_path: Path) -> None:
    log = (
        "(1.000000) can0 0B4##1001122\n"
        "(1.100000) can0 20000080#0000000000000000\n"
        "(1.200000) can1 123#R\n"
        "(1.300000) vcan0 00000123#AABB T\n"
        "\n"
    )
    frames, warnings = _excerpt(tmp_path, "fd.log", log)
    assert warnings == []
    assert frames == [
        CanFrame(1_000_000_000, 0x0B4, False, b"\x00\x11\x22", "can0"),
        CanFrame(1_300_000_000, 0x123, True, b"\xaa\xbb", "vcan0"),
    ]


# --- garbage amid good lines -----------------------------------------------------------------
GARBAGE = [
    b"this is not a frame",
    b"\x00\x01\x02\xff binary junk \x7f",
    b"1.0 2.0 3.0 4.0 5.0 6.0 7.0 8.0 9.0",
]


def _corrupt(line: str) -> str:
    """The line with its hex digits and decimal points garbled."""
    return line.replace("0", "Z").replace(".", ":")


# Each writer ends the file with one line per frame, ASC with one closing line more.
FOOTER_LINES = {".log": 0, ".asc": 1, ".trc": 0, ".csv": 0}


@pytest.mark.parametrize("suffix", list(FOOTER_LINES))
def test_bad_lines_are_skipped_and_reported_once(tmp_path: Path, suffix: str) -> None:
    clean = tmp_path / f"clean{suffix}"
    _write(clean, suffix, DATA)
    lines = clean.read_text().splitlines()
    k = len(lines) - FOOTER_LINES[suffix] - len(DATA) + 3  # the line of DATA[3]
    target = lines[k]
    bad = [*GARBAGE, _corrupt(target).encode(), target[: len(target) // 2].encode()]
    damaged = [*(x.encode() for x in lines[:k]), *bad, *(x.encode() for x in lines[k + 1 :])]
    path = tmp_path / f"damaged{suffix}"
    path.write_bytes(b"\n".join(damaged) + b"\n")

    frames, warnings = _read(path)

    expected = DATA[:3] + DATA[4:]
    assert [(f.arbitration_id, f.data) for f in frames] == [
        (m.arbitration_id, bytes(m.data)) for m in expected
    ]
    assert len(warnings) == 1
    # ASC reads a line of a time stamp and other words as an event (statistics...).
    n_bad = 4 if suffix == ".asc" else 5
    assert warnings[0].startswith(f"{path}: skipped {n_bad} of {len(damaged)} lines that are not")
    assert f"line {k + 1} 'this is not a frame'" in warnings[0]
    assert f"line {k + 2} '\\x00\\x01\\x02\ufffd binary junk \\x7f'" in warnings[0]
    assert f"; and {n_bad - 3} more" in warnings[0]


def test_python_can_would_stop_at_the_first_bad_candump_line(tmp_path: Path) -> None:
    """Why the text formats are parsed here: python-can's generator ends at a bad line."""
    path = tmp_path / "x.log"
    path.write_text("(1.0) can0 001#00\ngarbage\n(2.0) can0 002#00\n")
    got = []
    with pytest.raises(ValueError):
        for m in can.LogReader(str(path)):
            got.append(m.arbitration_id)
    assert got == [1]
    frames, warnings = _read(path)
    assert [f.arbitration_id for f in frames] == [1, 2]
    assert "line 2 'garbage'" in warnings[0]


def test_long_lines_are_shortened_in_the_warning(tmp_path: Path) -> None:
    frames, warnings = _excerpt(tmp_path, "long.log", "(1.0) can0 001#00\n" + "x" * 500 + "\n")
    assert len(frames) == 1
    assert "x" * 57 + "..." in warnings[0]
    assert "x" * 58 not in warnings[0]


def test_empty_file_gives_no_frames_and_no_warning(tmp_path: Path) -> None:
    for suffix in FORMATS:
        if suffix == ".blf":
            _write(tmp_path / "empty.blf", ".blf", [])
        else:
            (tmp_path / f"empty{suffix}").write_text("")
        assert _read(tmp_path / f"empty{suffix}") == ([], [])


# --- unreadable files ------------------------------------------------------------------------
def test_missing_file_and_unknown_format(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match=r"nope\.log: CAN log not found"):
        iter_log_frames(tmp_path / "nope.log", warn=print)
    (tmp_path / "x.mf4").write_bytes(b"")
    with pytest.raises(RecordingError, match=r"x\.mf4: unknown CAN log format '\.mf4'; expected"):
        iter_log_frames(tmp_path / "x.mf4", warn=print)
    (tmp_path / "x.gz").write_bytes(b"")
    with pytest.raises(RecordingError, match=r"x\.gz: unknown CAN log format '\.gz'"):
        iter_log_frames(tmp_path / "x.gz", warn=print)


def test_binary_garbage_blf_raises(tmp_path: Path) -> None:
    path = tmp_path / "junk.blf"
    path.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(RecordingError, match=r"junk\.blf: not a readable BLF file"):
        _read(path)
    path.write_bytes(b"LOGG")  # too short for the header
    with pytest.raises(RecordingError, match=r"junk\.blf: not a readable BLF file"):
        _read(path)


def test_bad_gzip_raises(tmp_path: Path) -> None:
    path = tmp_path / "plain.log.gz"
    path.write_text("(1.0) can0 001#00\n")  # not gzip'd at all
    with pytest.raises(RecordingError, match=r"plain\.log\.gz: gzip read failed at line 1: "):
        _read(path)


def test_truncated_gzip_keeps_the_frames_before_the_break(tmp_path: Path) -> None:
    path = tmp_path / "cut.log.gz"
    lines = "".join(f"({i}.0) can0 {i % 0x7FF:03X}#0011223344556677\n" for i in range(2000))
    path.write_bytes(gzip.compress(lines.encode())[:-2000])
    frames, warnings = _read(path)
    assert 0 < len(frames) < 2000
    assert [f.arbitration_id for f in frames] == list(range(len(frames)))
    assert len(warnings) == 1
    assert f"cut.log.gz: gzip read failed at line {len(frames) + 1}" in warnings[0]
    assert f"kept the {len(frames)} frames before it" in warnings[0]


@pytest.mark.parametrize("junk", [b"", b"\x00" * 64])
def test_truncated_blf_keeps_the_frames_before_the_break(tmp_path: Path, junk: bytes) -> None:
    path = tmp_path / "cut.blf"
    many = [
        can.Message(timestamp=T0_S + i * 1e-3, arbitration_id=i % 0x7FF, data=bytes(8))
        for i in range(5000)
    ]
    with can.BLFWriter(str(path), max_container_size=4096) as w:
        for m in many:
            w.on_message_received(m)
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2] + junk)
    frames, warnings = _read(path)
    assert 0 < len(frames) < 5000
    assert [f.arbitration_id for f in frames] == [i % 0x7FF for i in range(len(frames))]
    if junk:  # python-can stumbles over the junk (and makes a frame of part of it first)
        assert f"BLF read failed after {len(frames)} frames" in warnings[0]
        assert "skipped 1 BLF frames that are not CAN frames" in warnings[1]
    else:  # python-can stops quietly; the header's file size tells
        assert warnings == [
            f"{path}: the BLF header gives {len(data)} bytes, the file has {len(data) // 2}: "
            f"it was cut short; kept the {len(frames)} frames before the cut"
        ]


def test_blf_cut_before_its_first_frame_raises(tmp_path: Path) -> None:
    path = tmp_path / "stub.blf"
    _write(path, ".blf", DATA)
    full = path.stat().st_size
    path.write_bytes(path.read_bytes()[: blf.FILE_HEADER_SIZE + 40])
    with pytest.raises(
        RecordingError,
        match=rf"stub\.blf: the BLF header gives {full} bytes, the file has "
        rf"{blf.FILE_HEADER_SIZE + 40}: it was cut short before its first CAN frame",
    ):
        _read(path)


def test_blf_without_data_frames_says_so(tmp_path: Path) -> None:
    path = tmp_path / "errors.blf"
    _write(path, ".blf", [m for m in _messages() if m.is_error_frame])
    assert _read(path) == (
        [],
        [
            f"{path}: the BLF header counts 1 objects, but none is a CAN data frame "
            "(other buses, or a damaged file)"
        ],
    )


def test_unsupported_trc_version_and_missing_columns_raise(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match=r"v12\.trc: line 1: TRC file version '1\.2'"):
        _excerpt(tmp_path, "v12.trc", ";$FILEVERSION=1.2\n 1) 1.0 1 Rx 0100 1 00\n")
    with pytest.raises(RecordingError, match=r"v20\.trc: line 2: TRC 2\.0 data before"):
        _excerpt(tmp_path, "v20.trc", ";$FILEVERSION=2.0\n 1 1.0 DT 0100 Rx 1 00\n")
    with pytest.raises(RecordingError, match=r"st\.trc: line 2: \$STARTTIME 'soon'"):
        _excerpt(tmp_path, "st.trc", ";$FILEVERSION=2.1\n;$STARTTIME=soon\n")


def test_blf_object_of_size_zero_raises_instead_of_looping_forever(tmp_path: Path) -> None:
    """python-can 4.6 alone yields the same frame forever here (hardbyte/python-can#1584)."""
    ok = tmp_path / "ok.blf"
    _write(ok, ".blf", DATA[:2])
    data = ok.read_bytes()
    start = blf.FILE_HEADER_SIZE
    size = blf.OBJ_HEADER_BASE_STRUCT.unpack_from(data, start)[3]
    container = data[start + blf.OBJ_HEADER_BASE_STRUCT.size : start + size]
    inner = bytearray(zlib.decompress(container[blf.LOG_CONTAINER_STRUCT.size :]))
    assert inner[:4] == b"LOBJ"
    struct.pack_into("<L", inner, 8, 0)  # the first frame's object size
    body = blf.LOG_CONTAINER_STRUCT.pack(blf.NO_COMPRESSION, len(inner)) + inner
    obj = blf.OBJ_HEADER_BASE_STRUCT.pack(b"LOBJ", 16, 1, 16 + len(body), blf.LOG_CONTAINER)
    path = tmp_path / "zero.blf"
    path.write_bytes(data[:start] + obj + body)

    def hang(signum: int, frame: FrameType | None) -> None:
        pytest.fail("iter_log_frames loops forever on a BLF object of size 0")

    previous = signal.signal(signal.SIGALRM, hang)
    signal.alarm(10)
    try:
        with pytest.raises(RecordingError, match=r"zero\.blf: not a readable BLF file: an object"):
            _read(path)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
