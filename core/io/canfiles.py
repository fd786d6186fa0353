"""CAN log files read frame by frame: BLF, ASC, candump, TRC and CSV, plain or gzip'd.

`iter_log_frames(path, warn=...)` is the one entry point; its docstring says how each format
is read and what happens to bad lines and broken files.
"""

from __future__ import annotations

import base64
import gzip
import math
import re
import string
import struct
import zlib
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import BinaryIO, Protocol, TextIO, cast

import can
from can.io import blf
from can.io.blf import BLFParseError

from core.io.canframe import CanFrame
from core.io.errors import RecordingError

Warn = Callable[[str], None]
NS_PER_S = 1_000_000_000
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
