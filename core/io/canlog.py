"""CAN logs: their frames, and the car's speed and yaw rate decoded from them with a DBC.

    frames = iter_log_frames(path, warn=warn)            # CanFrame, in file order
    vehicle = VehicleSignalDecoder(db, source, where)     # one decoder per quantity family
    radar = RadarCanDecoder(db, radar_source, where)      # core.io.can_radar
    decode_frames(frames, [vehicle, radar])               # one pass over the log
    signals, scans = vehicle.result(warn), radar.result(warn)

Notes:
    Frames shorter than the DBC says are padded with zero bytes: some loggers strip trailing
    zero bytes (the comma2k19 logs do), and a strict decoder would reject them.
"""

from __future__ import annotations

import base64
import difflib
import gzip
import math
import re
import string
import struct
import warnings
import zlib
from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO, Protocol, TextIO, cast

import can
import cantools
import numpy as np
import numpy.typing as npt
from can.io import blf
from can.io.blf import BLFParseError
from cantools.database.can import Database, Message

from core.io.canframe import CanFrame
from core.io.errors import RecordingError
from core.io.timeline import DEFAULT_MAX_GAP_NS, main_block

if TYPE_CHECKING:  # manifest imports this module for SignalMapping
    from core.io.manifest import CanBus, CanSource

Int64Array = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]
Warn = Callable[[str], None]

SPEED_UNITS_TO_MPS = {"m/s": 1.0, "km/h": 1.0 / 3.6, "mph": 0.44704}
YAW_RATE_UNITS_TO_RADPS = {"rad/s": 1.0, "deg/s": math.pi / 180.0}
NS_PER_S = 1_000_000_000

# A car whose speed reads below this stands still (wheel-speed sensors read 0 below ~0.1 m/s).
STANDSTILL_SPEED_MPS = 0.05
# Standing still for less than this gives too few yaw-rate samples for a bias estimate.
MIN_STANDSTILL_S = 1.0

MAX_STANDARD_ID = 0x7FF
MAX_EXTENDED_ID = 0x1FFF_FFFF
MAX_DATA_BYTES = 64  # CAN FD
CAN_ERR_FLAG = 0x2000_0000  # linux/can.h: set in the id of error frames (candump prints it)
# Seconds whose nanoseconds still fit int64 (year 2262).
MAX_ABS_TIME_S = 9.2e9
# Days from the TRC epoch (1899-12-30, OLE automation date) to the Unix epoch.
TRC_EPOCH_TO_UNIX_DAYS = 25569.0
SECONDS_PER_DAY = 86400.0
BAD_LINES_SHOWN = 3
LINE_TEXT_CHARS = 60


# --- quantities ---------------------------------------------------------------------------
@dataclass(frozen=True)
class SignalMapping:
    """Where a quantity sits on the bus: DBC message and signal, the signal's unit, a sign.

    `sign` (+1 or -1) turns the signal into the engine's convention (speed forward positive,
    yaw rate positive turning left); `to_si` is the factor from `unit` to m/s or rad/s.
    """

    message: str
    signal: str
    unit: str
    to_si: float
    sign: int = 1

    def __post_init__(self) -> None:
        if self.sign not in (1, -1):
            raise ValueError(f"sign: expected 1 or -1, got {self.sign!r}")


@dataclass(frozen=True, eq=False)
class VehicleSignals:
    """Speed and yaw rate as decoded, each with its own time stamps.

    speed_t_ns: (N,) int64 ns, ascending; speed_mps: (N,) float64 m/s;
    yaw_rate_t_ns: (M,) int64 ns, ascending; yaw_rate_radps: (M,) float64 rad/s, positive
    turning left, with `yaw_rate_bias_radps` already subtracted (0.0 when none was);
    standstill_s: how long the car stood still (speed below STANDSTILL_SPEED_MPS at
    consecutive yaw-rate samples), whether or not a bias was estimated from it.
    """

    speed_t_ns: Int64Array
    speed_mps: FloatArray
    yaw_rate_t_ns: Int64Array
    yaw_rate_radps: FloatArray
    yaw_rate_bias_radps: float = 0.0
    standstill_s: float = 0.0

    @classmethod
    def empty(cls) -> VehicleSignals:
        i, f = np.zeros(0, np.int64), np.zeros(0, np.float64)
        return cls(i, f, i, f)

    def speed_at(self, t_ns: npt.ArrayLike) -> FloatArray:
        """Speed (m/s) at `t_ns` (any shape, ns), linear between samples, held past the ends.

        NaN when there are no speed samples.
        """
        return _interp(t_ns, self.speed_t_ns, self.speed_mps)

    def yaw_rate_at(self, t_ns: npt.ArrayLike) -> FloatArray:
        """Yaw rate (rad/s) at `t_ns`, as `speed_at`."""
        return _interp(t_ns, self.yaw_rate_t_ns, self.yaw_rate_radps)


def _interp(t_ns: npt.ArrayLike, ts_ns: Int64Array, values: FloatArray) -> FloatArray:
    t = np.asarray(t_ns, dtype=np.int64)
    if len(ts_ns) == 0:
        return np.full(t.shape, np.nan)
    # Relative to the first sample so that float64 keeps nanosecond resolution.
    return np.interp(
        (t - ts_ns[0]).astype(np.float64), (ts_ns - ts_ns[0]).astype(np.float64), values
    )


# --- DBC ----------------------------------------------------------------------------------
def load_dbc(paths: Sequence[Path]) -> Database:
    """One cantools database from one or more DBC files."""
    db = Database(strict=False)  # real DBCs (opendbc's) have overlapping signals elsewhere
    for path in paths:
        try:
            db.add_dbc_file(str(path))
        except FileNotFoundError as err:
            raise RecordingError(f"{path}: DBC file not found") from err
        except (OSError, UnicodeDecodeError, cantools.database.Error) as err:
            raise RecordingError(f"{path}: not a readable DBC file: {err}") from err
    return db


def find_signal(db: Database, mapping: SignalMapping, where: str) -> Message:
    """The DBC message carrying `mapping`; RecordingError with close names when missing."""
    names = [m.name for m in db.messages]
    try:
        message = db.get_message_by_name(mapping.message)
    except KeyError as err:
        close = difflib.get_close_matches(mapping.message, names, n=5, cutoff=0.4)
        raise RecordingError(
            f"{where}: no message {mapping.message!r} in the DBC; "
            f"close names: {', '.join(close) or 'none'}"
        ) from err
    check_signals(message, [mapping.signal], where)
    return message


def check_signals(message: Message, signals: Iterable[str], where: str) -> None:
    """RecordingError naming the first of `signals` that `message` lacks, with close names."""
    have = [s.name for s in message.signals]
    for signal in signals:
        if signal not in have:
            close = difflib.get_close_matches(signal, have, n=5, cutoff=0.4)
            raise RecordingError(
                f"{where}: message {message.name!r} has no signal {signal!r}; "
                f"close names: {', '.join(close) or 'none'}; all: {', '.join(have)}"
            )


def id_text(arbitration_id: int, is_extended: bool) -> str:
    """0x0B4 for a standard id, 0x18FEF100 (extended) for an extended one."""
    return f"0x{arbitration_id:08X} (extended)" if is_extended else f"0x{arbitration_id:03X}"


# --- log files ----------------------------------------------------------------------------
def iter_log_frames(path: Path, *, warn: Warn) -> Iterator[CanFrame]:
    """The data frames of a CAN log, in file order; error and remote frames are skipped.

    Formats, by suffix (each also gzip'd, `.log.gz` etc.): `.blf` (Vector binary), `.asc`
    (Vector text), `.log` (candump -L), `.trc` (PEAK, versions 1.0, 1.1, 1.3, 2.0, 2.1), `.csv`
    (python-can's CSVWriter layout). t_ns = round(time stamp (s) * 1e9) on the log's clock
    (.asc: seconds since the trigger block start, as python-can reads it; .trc: `$STARTTIME`
    plus the offset). channel: as the file names it: candump's interface ("can0"), the 1-based
    channel number of .asc, .blf and .trc ("1": CANoe's CAN 1, PCAN's bus 1), None where
    the file has none (.csv, .trc 1.0 and 1.1).

    Bad input: a missing file, an unknown suffix, a file that is not the format at all (BLF
    garbage, bad gzip) or an unsupported TRC version raise RecordingError naming the file. A
    text line that is not a frame (a corrupted line amid good ones) is skipped; the skipped
    lines are reported in one `warn` call at the end: their count and the first few, by line
    number, text and reason. A file that breaks off (a truncated gzip or BLF) after some
    frames were read is reported with `warn` and the frames before the break are kept; one
    that breaks before any frame raises.

    Notes:
        python-can's text readers cannot skip a bad line: `CanutilsLogReader`, `CSVReader`
        and `TRCReader` raise ValueError from inside their generator, which ends it (the rest
        of the file is lost), and `ASCReader` drops any line its regex does not match without
        a word, but raises on one it matches and cannot parse. So the four text formats are
        parsed here, one small parser per format, a line at a time, following python-can's
        readers (same fields, same rules for extended ids); BLF, a binary format with no
        lines, goes through python-can's `BLFReader`. The file is returned as an iterator
        whose checks (file present, format known) run at call time, its reading lazily.
    """
    suffixes = [s.lower() for s in path.suffixes]
    gz = suffixes[-1:] == [".gz"]
    kind = "".join(suffixes[-2:-1] if gz else suffixes[-1:])
    if kind not in LOG_SUFFIXES:
        raise RecordingError(
            f"{path}: unknown CAN log format {''.join(path.suffixes)!r}; expected one of "
            f"{', '.join(LOG_SUFFIXES)}, optionally gzip'd (.gz)"
        )
    if not path.is_file():
        raise RecordingError(f"{path}: CAN log not found")
    if kind == ".blf":
        return _blf_frames(path, gz, warn)
    return _text_frames(path, gz, TEXT_FORMATS[kind](), warn)


class _LineParser(Protocol):
    name: str

    def parse(self, line: str) -> CanFrame | None:
        """The frame of `line`, None for a line that is no data frame (header, comment,
        event, error or remote frame); ValueError for a line that is none of these."""
        ...


class _BadHeaderError(Exception):
    """A header line that makes the whole file unreadable (unsupported version...)."""


def _text_frames(path: Path, gz: bool, parser: _LineParser, warn: Warn) -> Iterator[CanFrame]:
    bad: list[str] = []
    n_bad = n_frames = line_no = 0
    try:
        with _open_text(path, gz) as lines:
            for line_no, line in enumerate(lines, 1):
                try:
                    frame = parser.parse(line)
                except ValueError as err:
                    n_bad += 1
                    if len(bad) < BAD_LINES_SHOWN:
                        bad.append(f"line {line_no} {_clip(line)} ({err})")
                    continue
                if frame is not None:
                    n_frames += 1
                    yield frame
    except _BadHeaderError as err:
        raise RecordingError(f"{path}: line {line_no}: {err}") from err
    except (OSError, EOFError, zlib.error) as err:
        where = f"{path}: {'gzip ' if gz else ''}read failed at line {line_no + 1}: {err}"
        if n_frames == 0:
            raise RecordingError(f"{where}; expected a {parser.name} CAN log") from err
        warn(f"{where}; kept the {n_frames} frames before it, the rest is lost")
    if n_bad:
        more = f"; and {n_bad - len(bad)} more" if n_bad > len(bad) else ""
        warn(
            f"{path}: skipped {n_bad} of {line_no} lines that are not {parser.name} CAN frames: "
            + "; ".join(bad)
            + more
        )


def _open_text(path: Path, gz: bool) -> TextIO:
    # errors="replace": binary junk in a text log is a bad line, not a failed file.
    if gz:
        return gzip.open(path, "rt", encoding="utf-8", errors="replace")
    return path.open(encoding="utf-8", errors="replace")


def _clip(line: str) -> str:
    text = line.rstrip("\r\n")
    if len(text) > LINE_TEXT_CHARS:
        text = text[: LINE_TEXT_CHARS - 3] + "..."
    return repr(text)


def _frame(t_s: float, can_id: int, extended: bool, data: bytes, channel: str | None) -> CanFrame:
    """A CanFrame, checked: a finite time, an id within its range, at most 64 data bytes."""
    if not math.isfinite(t_s) or abs(t_s) > MAX_ABS_TIME_S:
        raise ValueError(f"time stamp {t_s!r} s is not a time")
    limit = MAX_EXTENDED_ID if extended else MAX_STANDARD_ID
    if not 0 <= can_id <= limit:
        kind = "an extended" if extended else "a standard"
        raise ValueError(f"id 0x{can_id:X} is not {kind} id (0 to 0x{limit:X})")
    if len(data) > MAX_DATA_BYTES:
        raise ValueError(f"{len(data)} data bytes, at most {MAX_DATA_BYTES} expected")
    return CanFrame(round(t_s * NS_PER_S), can_id, extended, data, channel)


def _data_bytes(tokens: Sequence[str], count: int, base: int) -> bytes:
    """`count` bytes from `count` tokens of one byte each in `base` (16 or 10)."""
    if not 0 <= count <= MAX_DATA_BYTES:
        raise ValueError(f"data length {count}: expected 0 to {MAX_DATA_BYTES}")
    if len(tokens) < count:
        raise ValueError(f"{count} data bytes expected, {len(tokens)} found")
    if base == 16:
        return bytes.fromhex(" ".join(tokens[:count]))  # rejects tokens that are not 2 digits
    return bytes(int(t, 10) for t in tokens[:count])  # ValueError outside 0..255


def _classic_length(dlc: int) -> int:
    if not 0 <= dlc <= 15:
        raise ValueError(f"DLC {dlc} is not 0 to 15")
    return min(dlc, 8)  # classic CAN: DLC 9..15 mean 8 bytes


class _Candump:
    """`(1436509052.249713) can0 0B4#00000000001D0B7A5E`, optionally ` R`/` T` at the end."""

    name = "candump -L"

    def parse(self, line: str) -> CanFrame | None:
        parts = line.split()
        if not parts:
            return None
        if len(parts) == 4 and parts[3] in ("R", "T", "r", "t"):  # direction, newer candump
            parts = parts[:3]
        if len(parts) != 3:
            raise ValueError("expected '(time) channel id#data'")
        stamp, channel, frame = parts
        if not (stamp.startswith("(") and stamp.endswith(")")):
            raise ValueError("expected the time stamp in parentheses")
        can_id_text, sep, data_text = frame.partition("#")
        if not sep:
            raise ValueError("expected '#' between id and data")
        extended = len(can_id_text) > 3  # candump: 3 hex digits standard, 8 extended
        can_id = int(can_id_text, 16)
        if extended and can_id & CAN_ERR_FLAG:
            return None
        if data_text[:1] in ("R", "r"):
            return None
        if data_text.startswith("#"):  # CAN FD: '##', one flags digit, the data
            if len(data_text) < 2 or data_text[1] not in string.hexdigits:
                raise ValueError("expected a flags digit after '##'")
            data_text = data_text[2:]
        return _frame(float(stamp[1:-1]), can_id, extended, bytes.fromhex(data_text), channel)


_ASC_ID = re.compile(r"[0-9A-Fa-f]+[xX]?\Z")


class _Asc:
    """Vector ASC: `0.012300 1  0B4  Rx   d 8 00 00 00 00 00 1D 0B 7A` and CANFD lines.

    Header lines (date, base, internal events, Begin/End Triggerblock), comments and events
    (a time stamp and a channel followed by a word that is no CAN id: Statistic:, ErrorFrame,
    J1939TP; and CANoe's TxRq transmit requests) are no frames. A line of time stamp,
    channel and CAN id is a frame and must parse as one.
    """

    name = "ASC"
    HEADER_WORDS = frozenset({"date", "base", "internal", "no", "begin", "end"})

    def __init__(self) -> None:
        self.base = 16

    def parse(self, line: str) -> CanFrame | None:
        parts = line.split()
        if not parts or parts[0].startswith("//"):
            return None
        head = parts[0].lower()
        if head in self.HEADER_WORDS:
            if head == "base" and len(parts) > 1:
                if parts[1].lower() not in ("hex", "dec"):
                    raise ValueError(f"base {parts[1]!r}: expected hex or dec")
                self.base = 16 if parts[1].lower() == "hex" else 10
            return None
        try:
            t_s = float(parts[0])
        except ValueError:
            raise ValueError("expected a time stamp or a header line") from None
        if len(parts) < 3:
            raise ValueError("expected a channel and an event after the time stamp")
        if parts[1].upper() == "CANFD":
            return self._fd(t_s, parts)
        if not parts[1].isdigit() or not _ASC_ID.match(parts[2]):
            return None  # ErrorFrame, statistics, chip status, other events
        can_id, extended = self._id(parts[2])
        if _at(parts, 3) == "TxRq":
            return None
        if _at(parts, 3) not in ("Rx", "Tx"):
            raise ValueError(f"direction {_at(parts, 3)!r}: expected Rx or Tx")
        if len(parts) < 6:
            raise ValueError("expected 'd <dlc> <data>' after the direction")
        if parts[4] in ("r", "R"):
            return None
        if parts[4] not in ("d", "D"):
            raise ValueError(f"frame type {parts[4]!r}: expected d or r")
        length = _classic_length(int(parts[5], self.base))
        data = _data_bytes(parts[6:], length, self.base)
        return _frame(t_s, can_id, extended, data, parts[1])

    def _id(self, text: str) -> tuple[int, bool]:
        if text[-1:] in ("x", "X"):
            return int(text[:-1], self.base), True
        return int(text, self.base), False

    def _fd(self, t_s: float, parts: list[str]) -> CanFrame | None:
        # time CANFD channel dir id [symbolic name] brs esi dlc length data...
        if any(p.lower() == "errorframe" for p in parts[2:5]):
            return None
        rest = parts[5:]
        if rest and not rest[0].isdigit():
            rest = rest[1:]
        if len(parts) < 5 or len(rest) < 4:
            raise ValueError("expected 'channel dir id brs esi dlc length data' after CANFD")
        can_id, extended = self._id(parts[4])
        length = int(rest[3])
        if length == 0:
            return None  # remote frame
        return _frame(t_s, can_id, extended, _data_bytes(rest[4:], length, self.base), parts[2])


class _Trc:
    """PEAK TRC: `;$` header lines name version, start time and (2.x) the columns."""

    name = "TRC"
    VERSIONS = ("1.0", "1.1", "1.3", "2.0", "2.1")
    DATA_TYPES = frozenset({"DT", "FD", "FB", "FE", "BI"})
    OTHER_TYPES = frozenset({"RR", "ST", "EC", "ER", "EV"})  # remote, status, errors, events

    def __init__(self) -> None:
        self.version = "1.0"  # PEAK: files without $FILEVERSION are 1.0
        self.start_s = 0.0
        self.columns: list[str] = []

    def parse(self, line: str) -> CanFrame | None:
        text = line.strip()
        if not text:
            return None
        if text.startswith(";"):
            self._header(text)
            return None
        if self.version >= "2.0":
            return self._v2(text)
        parts = text.split()
        if not parts[0].endswith(")"):
            raise ValueError("expected a message number like '12)' first")
        if self.version == "1.0":  # N) time id dlc data
            bus, kind, rest = None, "Rx", parts[2:]
        elif self.version == "1.1":  # N) time type id dlc data
            bus, kind, rest = None, _at(parts, 2), parts[3:]
        else:  # 1.3: N) time bus type id - dlc data
            bus, kind, rest = _at(parts, 2), _at(parts, 3), parts[4:5] + parts[6:]
        if kind in ("Warng", "Error") or _at(rest, 0) == "FFFFFFFF":
            return None  # bus state and error lines
        if kind not in ("Rx", "Tx"):
            raise ValueError(f"message type {kind!r}: expected Rx or Tx")
        if len(rest) < 2:
            raise ValueError("expected id and DLC")
        if _at(rest, 2) in ("RTR", "ERROR"):
            return None
        can_id_text = rest[0]
        data = _data_bytes(rest[2:], _classic_length(int(rest[1])), 16)
        t_s = float(parts[1]) / 1000.0 + self.start_s
        return _frame(t_s, int(can_id_text, 16), len(can_id_text) > 4, data, bus)

    def _header(self, text: str) -> None:
        if not text.startswith(";$"):
            return
        key, _, value = text[2:].partition("=")
        value = value.strip()
        if key == "FILEVERSION":
            if value not in self.VERSIONS:
                raise _BadHeaderError(
                    f"TRC file version {value!r} is not supported; "
                    f"expected one of {', '.join(self.VERSIONS)}"
                )
            self.version = value
        elif key == "STARTTIME":
            try:
                days = float(value)
            except ValueError:
                raise _BadHeaderError(
                    f"$STARTTIME {value!r}: expected days since 1899-12-30"
                ) from None
            self.start_s = (days - TRC_EPOCH_TO_UNIX_DAYS) * SECONDS_PER_DAY
            if not math.isfinite(self.start_s):
                raise _BadHeaderError(f"$STARTTIME {value!r}: expected days since 1899-12-30")
        elif key == "COLUMNS":
            self.columns = value.split(",")
            missing = {"O", "T", "I", "D"} - set(self.columns)
            if missing or not {"L", "l"} & set(self.columns):
                raise _BadHeaderError(
                    f"$COLUMNS {value!r}: expected at least O, T, I, L (or l) and D"
                )

    def _v2(self, text: str) -> CanFrame | None:
        if not self.columns:
            raise _BadHeaderError(f"TRC {self.version} data before the $COLUMNS header line")
        row = dict(zip(self.columns, text.split(maxsplit=len(self.columns) - 1), strict=False))
        kind = row.get("T", "")
        if kind in self.OTHER_TYPES:
            return None
        if kind not in self.DATA_TYPES:
            raise ValueError(f"message type {kind!r}: expected one of DT, FD, FB, FE, BI, RR")
        length_column = "l" if "l" in self.columns else "L"
        if not {"O", "I", length_column} <= row.keys():
            raise ValueError(f"{len(row)} columns, the header names {len(self.columns)}")
        length = int(row["l"]) if length_column == "l" else _dlc_to_length(int(row["L"]))
        data = bytes.fromhex(row.get("D", ""))
        if len(data) != length:
            raise ValueError(f"{length} data bytes expected, {len(data)} found")
        t_s = float(row["O"]) / 1000.0 + self.start_s
        return _frame(t_s, int(row["I"], 16), len(row["I"]) > 4, data, row.get("B"))


def _at(parts: Sequence[str], i: int) -> str:
    return parts[i] if i < len(parts) else ""


def _dlc_to_length(dlc: int) -> int:
    if not 0 <= dlc <= 15:
        raise ValueError(f"DLC {dlc} is not 0 to 15")
    return can.util.dlc2len(dlc)


class _Csv:
    """python-can's CSV: `timestamp,arbitration_id,extended,remote,error,dlc,data` (base64)."""

    name = "CSV"

    def parse(self, line: str) -> CanFrame | None:
        text = line.strip()
        if not text or text.startswith("timestamp,"):
            return None
        fields = text.split(",")
        if len(fields) != 7:
            raise ValueError(f"expected 7 comma-separated fields, got {len(fields)}")
        t, can_id, extended, remote, error, dlc, data = fields
        for flag in (extended, remote, error):
            if flag not in ("0", "1"):
                raise ValueError(f"flag {flag!r}: expected 0 or 1")
        if remote == "1" or error == "1":
            return None
        payload = base64.b64decode(data, validate=True)  # binascii.Error is a ValueError
        if int(dlc) != len(payload):
            raise ValueError(f"dlc {dlc} but {len(payload)} data bytes")
        return _frame(float(t), int(can_id, 16), extended == "1", payload, None)


TEXT_FORMATS: dict[str, Callable[[], _LineParser]] = {
    ".asc": _Asc,
    ".log": _Candump,
    ".trc": _Trc,
    ".csv": _Csv,
}
LOG_SUFFIXES = (".blf", *TEXT_FORMATS)


class _CheckedBLFReader(can.BLFReader):
    """python-can's BLFReader, refusing objects too small to move past.

    python-can 4.6 reads an object of size 0 inside a container again and again, forever
    (hardbyte/python-can#1584, #1581, open): a corrupted BLF would hang the app. Each
    container's chain of objects is walked first, as python-can walks it, and one shorter
    than its own header raises BLFParseError.
    """

    def _parse_data(self, data: bytes) -> Iterator[can.Message]:
        header = blf.OBJ_HEADER_BASE_STRUCT  # "LOBJ", header size, version, object size, type
        pos = 0
        # As python-can: the next object starts within 8 bytes (padding) of the last one's end.
        while (found := data.find(b"LOBJ", pos, pos + 8)) >= 0 and found + header.size <= len(data):
            size = header.unpack_from(data, found)[3]
            if size < header.size:
                raise BLFParseError(f"an object of {size} bytes in a container")
            pos = found + size
        return super()._parse_data(data)


def _blf_frames(path: Path, gz: bool, warn: Warn) -> Iterator[CanFrame]:
    errors = (BLFParseError, struct.error, zlib.error, ValueError, OSError, EOFError)
    try:
        stream = cast(BinaryIO, gzip.open(path, "rb")) if gz else path.open("rb")
    except OSError as err:
        raise RecordingError(f"{path}: cannot open: {err}") from err
    try:
        reader = _CheckedBLFReader(stream)
    except errors as err:
        stream.close()
        raise RecordingError(f"{path}: not a readable BLF file: {err}") from err
    n_frames = n_bad = 0
    first_bad = ""
    try:
        for msg in reader:
            if msg.is_error_frame or msg.is_remote_frame:
                continue
            # python-can numbers BLF channels from 0; the file (and CANoe) from 1.
            channel = None if msg.channel is None else str(cast(int, msg.channel) + 1)
            try:
                frame = _frame(
                    msg.timestamp, msg.arbitration_id, msg.is_extended_id, bytes(msg.data), channel
                )
            except ValueError as err:
                n_bad += 1
                first_bad = first_bad or f"at t={msg.timestamp!r} s: {err}"
                continue
            n_frames += 1
            yield frame
    except errors as err:
        if n_frames == 0:
            raise RecordingError(f"{path}: not a readable BLF file: {err}") from err
        warn(f"{path}: BLF read failed after {n_frames} frames: {err}; the rest is lost")
    else:
        # python-can ends a file cut short without a word; its header knows the full size.
        size = path.stat().st_size
        if not gz and reader.file_size > size:
            cut = f"{path}: the BLF header gives {reader.file_size} bytes, the file has {size}"
            if n_frames == 0:
                raise RecordingError(f"{cut}: it was cut short before its first CAN frame")
            warn(f"{cut}: it was cut short; kept the {n_frames} frames before the cut")
        elif n_frames == 0 and reader.object_count > 0:
            warn(
                f"{path}: the BLF header counts {reader.object_count} objects, but none is a "
                "CAN data frame (other buses, or a damaged file)"
            )
    finally:
        reader.stop()
    if n_bad:
        warn(f"{path}: skipped {n_bad} BLF frames that are not CAN frames (first {first_bad})")


# --- decoding -----------------------------------------------------------------------------
Traffic = Mapping[tuple[str | None, int, bool], int]
"""Frames seen per (channel, arbitration id, extended flag)."""


class FrameDecoder(Protocol):
    """What `decode_frames` feeds: a decoder of some messages on one bus."""

    @property
    def bus(self) -> CanBus: ...

    def wants(self, frame: CanFrame) -> bool:
        """Whether to feed `frame`; a function of its channel, id and extended flag only."""
        ...

    def feed(self, frame: CanFrame) -> None: ...

    def note_traffic(self, traffic: Traffic) -> None:
        """The frames the log carried, for a helpful warning when none was wanted."""
        ...


@dataclass(slots=True)
class _Route:
    decoders: tuple[FrameDecoder, ...]
    count: int = 0


def decode_frames(frames: Iterable[CanFrame], decoders: Iterable[FrameDecoder]) -> None:
    """Feed each frame to the decoders that want it, in one pass; then tell them the traffic.

    One dict lookup per frame: which decoders want a (channel, id, extended) key is asked
    once per key, and the frames of each key are counted.
    """
    decoders = tuple(decoders)
    routes: dict[tuple[str | None, int, bool], _Route] = {}
    for frame in frames:
        key = (frame.channel, frame.arbitration_id, frame.is_extended)
        route = routes.get(key)
        if route is None:
            route = routes[key] = _Route(tuple(d for d in decoders if d.wants(frame)))
        route.count += 1
        for decoder in route.decoders:
            decoder.feed(frame)
    traffic = {key: route.count for key, route in routes.items()}
    for decoder in decoders:
        decoder.note_traffic(traffic)


class FrameLog:
    """Stamps and decoded signal values of the frames of some DBC messages, as fed.

    `signals` are looked up in each message; a message without one gives NaN for it.
    """

    def __init__(self, messages: Sequence[Message], signals: Sequence[str]) -> None:
        self.messages = tuple(messages)
        self.signals = tuple(signals)
        self.keys = {(m.frame_id, m.is_extended_frame): i for i, m in enumerate(self.messages)}
        self.received = [0] * len(self.messages)
        self._t_ns: list[int] = []
        self._which: list[int] = []
        self._values: list[tuple[float, ...]] = []
        self._undecodable = 0
        self._first_undecodable = ""

    def feed(self, frame: CanFrame) -> None:
        i = self.keys[(frame.arbitration_id, frame.is_extended)]
        self.received[i] += 1
        message = self.messages[i]
        data = frame.data
        if len(data) < message.length:
            data = data.ljust(message.length, b"\x00")
        try:
            decoded = message.decode_simple(data, decode_choices=False)
        except (cantools.database.Error, ValueError) as err:
            self._undecodable += 1
            if not self._first_undecodable:
                at = f"{message.name} at t={frame.t_ns / NS_PER_S:.6f} s"
                self._first_undecodable = f"{at}: {err}"
            return
        self._t_ns.append(frame.t_ns)
        self._which.append(i)
        self._values.append(tuple(_number(decoded.get(s)) for s in self.signals))

    def table(
        self, warn: Warn, where: str, what: str
    ) -> tuple[Int64Array, npt.NDArray[np.intp], FloatArray]:
        """(t_ns (R,), message index (R,), values (R, len(signals))) sorted by time.

        t_ns on the log's clock. Frames that do not decode and stamps outside the log's main
        block (`timeline.main_block`) are dropped and reported with `warn`.
        """
        if self._undecodable:
            warn(
                f"{where}: skipped {self._undecodable} {what} frames the DBC cannot decode "
                f"(first: {self._first_undecodable})"
            )
        t = np.asarray(self._t_ns, dtype=np.int64)
        which = np.asarray(self._which, dtype=np.intp)
        values = np.asarray(self._values, dtype=np.float64).reshape(len(t), len(self.signals))
        keep = main_block(t)
        if not keep.all():
            lo, hi = t[keep].min() / NS_PER_S, t[keep].max() / NS_PER_S
            out = t[~keep] / NS_PER_S
            warn(
                f"{where}: dropped {len(out)} {what} frames stamped outside the log's main "
                f"block {lo:.3f} s to {hi:.3f} s (gaps over {DEFAULT_MAX_GAP_NS / NS_PER_S:.0f} "
                f"s end a block): first at t={out[0]:.6f} s"
            )
        order = np.argsort(t[keep], kind="stable")
        return t[keep][order], which[keep][order], values[keep][order]


def _number(value: object) -> float:
    return float(value) if isinstance(value, (int, float)) else math.nan


def missing_frames_warning(
    where: str, what: str, ids: str, channel: str | None, traffic: Traffic
) -> str:
    """The warning for a decoder that received no frame: what it wanted, what the log holds.

    what: the DBC message(s); ids: their ids as text; traffic: as decode_frames counted it.
    """
    on = f"on channel {channel}" if channel is not None else "on any channel"
    text = f"{where}: no frame of {what}, id {ids}, {on}"
    here: Counter[tuple[int, bool]] = Counter()
    channels: Counter[str | None] = Counter()
    for (c, i, e), n in traffic.items():
        channels[c] += n
        if channel is None or c == channel:
            here[(i, e)] += n
    if not channels:
        return text + "; the log holds no data frame at all"
    if not here:
        listing = ", ".join(f"{c} ({n} frames)" for c, n in channels.most_common())
        return text + f"; the log has no frame on that channel; its channels: {listing}"
    listing = ", ".join(f"{id_text(i, e)} ({n})" for (i, e), n in here.most_common(8))
    return text + f"; the most frequent ids there: {listing} (is the DBC the log's?)"


class VehicleSignalDecoder:
    """Speed and yaw rate of a `CanSource` from the frames of one pass (see decode_frames).

    where: names the source in messages (the log file, the manifest section); offset_ns:
    added to every stamp (the recording's CAN time offset).
    Yaw-rate bias (`source.yaw_rate_bias == "standstill"`): the mean yaw rate over the yaw
    samples taken while the car stands still (speed, interpolated at the yaw samples, below
    `standstill_speed_mps`), subtracted when the car stood still for `min_standstill_s` or
    more; otherwise a warning and no correction. A gyro at rest reads its bias; the RAV4's
    reads about -0.4 deg/s.
    """

    def __init__(
        self,
        db: Database,
        source: CanSource,
        where: str,
        offset_ns: int = 0,
        *,
        standstill_speed_mps: float = STANDSTILL_SPEED_MPS,
        min_standstill_s: float = MIN_STANDSTILL_S,
    ) -> None:
        if source.yaw_rate_bias not in ("none", "standstill"):
            raise ValueError(
                f"yaw_rate_bias: expected 'none' or 'standstill', got {source.yaw_rate_bias!r}"
            )
        self.source = source
        self.where = where
        self.offset_ns = offset_ns
        self.standstill_speed_mps = standstill_speed_mps
        self.min_standstill_s = min_standstill_s
        speed = find_signal(db, source.speed, where)
        yaw = find_signal(db, source.yaw_rate, where)
        messages = [speed] if yaw.frame_id == speed.frame_id else [speed, yaw]
        self._log = FrameLog(messages, (source.speed.signal, source.yaw_rate.signal))
        self._speed_i, self._yaw_i = 0, len(messages) - 1
        self._traffic: Traffic = {}

    @property
    def bus(self) -> CanBus:
        return self.source.bus

    @property
    def ids(self) -> frozenset[tuple[int, bool]]:
        """(arbitration id, extended) of the messages decoded."""
        return frozenset(self._log.keys)

    def wants(self, frame: CanFrame) -> bool:
        channel = self.source.bus.channel
        return (channel is None or frame.channel == channel) and (
            frame.arbitration_id,
            frame.is_extended,
        ) in self._log.keys

    def feed(self, frame: CanFrame) -> None:
        self._log.feed(frame)

    def note_traffic(self, traffic: Traffic) -> None:
        self._traffic = traffic

    def result(self, warn: Warn) -> VehicleSignals:
        """Samples of both quantities, sorted, SI units and the engine's signs, bias removed."""
        src, log = self.source, self._log
        for i, mapping in ((self._speed_i, src.speed), (self._yaw_i, src.yaw_rate)):
            message = log.messages[i]
            if log.received[i] == 0:
                what = f"{message.name} (signal {mapping.signal})"
                ids = id_text(message.frame_id, message.is_extended_frame)
                warn(missing_frames_warning(self.where, what, ids, src.bus.channel, self._traffic))
        t, which, values = log.table(warn, self.where, "speed and yaw-rate")
        speed_t, speed = self._samples(t, which, values, 0, self._speed_i, src.speed, warn)
        yaw_t, yaw = self._samples(t, which, values, 1, self._yaw_i, src.yaw_rate, warn)

        still = np.abs(_interp(yaw_t, speed_t, speed)) < self.standstill_speed_mps
        standstill_s = float(np.diff(yaw_t)[still[:-1] & still[1:]].sum()) / NS_PER_S
        bias = 0.0
        if src.yaw_rate_bias == "standstill":
            if standstill_s >= self.min_standstill_s:
                bias = float(yaw[still].mean())
            else:
                warn(
                    f"{self.where}: yaw_rate_bias standstill: the car stands still (speed below "
                    f"{self.standstill_speed_mps} m/s) for {standstill_s:.2f} s, "
                    f"{self.min_standstill_s} s needed; no yaw-rate bias subtracted"
                )
        return VehicleSignals(speed_t, speed, yaw_t, yaw - bias, bias, standstill_s)

    def _samples(
        self,
        t: Int64Array,
        which: npt.NDArray[np.intp],
        values: FloatArray,
        column: int,
        message: int,
        mapping: SignalMapping,
        warn: Warn,
    ) -> tuple[Int64Array, FloatArray]:
        rows = which == message
        ts, vs = t[rows], values[rows, column] * (mapping.to_si * mapping.sign)
        finite = np.isfinite(vs)
        if not finite.all():
            warn(
                f"{self.where}: dropped {np.count_nonzero(~finite)} non-finite "
                f"{mapping.message}.{mapping.signal} values (first at "
                f"t={ts[~finite][0] / NS_PER_S:.6f} s)"
            )
        return ts[finite] + self.offset_ns, vs[finite]


def _python_warning(message: str) -> None:
    warnings.warn(message, RuntimeWarning, stacklevel=2)


def read_vehicle_signals(
    log_path: Path,
    dbc_paths: Sequence[Path],
    speed: SignalMapping,
    yaw_rate: SignalMapping,
    channel: str | None = None,
    offset_ns: int = 0,
    *,
    yaw_rate_bias: str = "none",
    warn: Warn = _python_warning,
) -> VehicleSignals:
    """Speed and yaw rate from a CAN log file: iter_log_frames + one VehicleSignalDecoder.

    `channel`: keep only frames of this channel (e.g. "can0"; None keeps all); `offset_ns`
    is added to every time stamp (the recording's time offset for CAN); warnings go to
    `warn` (default: Python's `warnings.warn` with RuntimeWarning).
    """
    from core.io.manifest import CanBus, CanSource  # manifest imports this module

    bus = CanBus(dbc=tuple(str(p) for p in dbc_paths), log=str(log_path), channel=channel)
    decoder = VehicleSignalDecoder(
        load_dbc(dbc_paths),
        CanSource(bus, speed, yaw_rate, yaw_rate_bias),
        str(log_path),
        offset_ns,
    )
    decode_frames(iter_log_frames(log_path, warn=warn), [decoder])
    return decoder.result(warn)
