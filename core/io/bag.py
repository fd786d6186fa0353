"""Camera images, radar scans and CAN frames from a ROS bag (ROS 1 `.bag`, ROS 2 sqlite3, MCAP).

`BagReader` opens one bag with rosbags' AnyReader, finds topics by name or by message type,
checks that the bag's definition of a topic's message type has the fields read here, indexes
the camera topic's time stamps once and decodes one image on demand; radar and CAN messages
are small and read whole.

A bag is a ROS 1 `.bag` file, a ROS 2 bag folder (metadata.yaml and its .db3 or .mcap files),
or a single `.db3` or `.mcap` file. Any damage to it (truncation, a corrupt chunk, a garbage
database, a message that does not deserialise) raises RecordingError naming the file, and the
topic and time stamp when known: on open, or when the damaged message is read. rosbags wraps
some of its errors in its own types and lets others through; `BAG_ERRORS` lists both.

Notes:
    Time stamps are the bag's receive (log) times, not the header stamps: they are known
    without deserialising a message, which keeps opening a long drive cheap and random access
    exact. The writer of this project stores header stamp = log time.
    A topic recorded through several connections (ROS 1 records one per publisher) is read as
    one stream.
"""

from __future__ import annotations

import math
import struct
import sys
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, TypeAlias

import apsw
import cv2
import numpy as np
import numpy.typing as npt
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.interfaces import Connection, Nodetype
from rosbags.rosbag1 import ReaderError as Rosbag1Error
from rosbags.rosbag2 import ReaderError as Rosbag2Error
from rosbags.typesys.store import Typestore

if sys.version_info >= (3, 14):  # as rosbags imports it
    from compression.zstd import ZstdError
else:
    from backports.zstd import ZstdError

from core.io import radar_msgs
from core.io.canframe import CanFrame
from core.io.errors import RecordingError
from core.io.image_header import JPEG_MAGIC, image_size_px
from core.io.png import PNG_SIGNATURE, decode_unfiltered_grey
from core.io.radar_msgs import CAN_FRAME
from core.io.radarscans import MAX_ABS_RANGE_RATE_MPS, MAX_RANGE_M, RadarScans, plausible
from core.io.timeline import main_block

Int64Array = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]

CAMERA_TYPES = (radar_msgs.COMPRESSED_IMAGE, radar_msgs.IMAGE)
RADAR_TYPES = (radar_msgs.RADAR_SCAN, radar_msgs.RADAR_TRACKS)
CAN_TYPES = (CAN_FRAME,)

# What reading a damaged bag raises in rosbags 0.11.9, found by tests/core/io/test_bag_fuzz.py:
# its own errors, and what its readers, decompressors and QoS parser let through unwrapped.
BAG_ERRORS: tuple[type[BaseException], ...] = (
    AnyReaderError,  # open, deserialize
    Rosbag1Error,  # ROS 1 messages(): a damaged chunk or record
    Rosbag2Error,  # ROS 2 messages(): a damaged MCAP chunk or record
    OSError,  # a missing or unreadable path, a folder without metadata.yaml, a bad bz2 chunk
    apsw.Error,  # a damaged sqlite3 page met while reading messages
    struct.error,  # a record shorter than its fixed fields
    ValueError,  # UnicodeDecodeError of a name, type or metadata.yaml; a bad ROS 1 record type
    AssertionError,  # rosbag1 asserts on index records and message times
    KeyError,  # a connection id or definition encoding that the bag does not define
    TypeError,  # a damaged QoS profile (YAML of the wrong shape)
    AttributeError,  # ... a QoS enum given as a list
    MemoryError,  # an MCAP record whose length says terabytes (read() allocates that much)
    OverflowError,  # ... or more than an index can hold
    ZstdError,  # a damaged zstd-compressed file, message or MCAP chunk
    EOFError,  # ... or one cut short
    RuntimeError,  # a damaged lz4 ROS 1 chunk (lz4.frame raises RuntimeError)
)

# Raw sensor_msgs/Image encodings read here: channels, bytes per channel, cv2 code to grey.
RAW_ENCODINGS: dict[str, tuple[int, int, int | None]] = {
    "mono8": (1, 1, None),
    "8uc1": (1, 1, None),
    "mono16": (1, 2, None),
    "16uc1": (1, 2, None),
    "bgr8": (3, 1, cv2.COLOR_BGR2GRAY),
    "rgb8": (3, 1, cv2.COLOR_RGB2GRAY),
    "bgra8": (4, 1, cv2.COLOR_BGRA2GRAY),
    "rgba8": (4, 1, cv2.COLOR_RGBA2GRAY),
}
# cv2.imdecode gives BGR(A); grey conversion by channel count.
DECODED_TO_GREY = {3: cv2.COLOR_BGR2GRAY, 4: cv2.COLOR_BGRA2GRAY}
# ISO 11898-1: a classic CAN data frame carries at most 8 bytes.
CAN_MAX_DLC = 8
INT64_MAX = 2**63 - 1
NS_PER_S = 1_000_000_000
# read_at: messages of the stream a read may pass over after the last one before it asks by
# time (a playback that skips frames, other topics' messages do not count)
CURSOR_LOOKAHEAD = 4
# Stamps listed in a warning before "…".
WARN_STAMPS = 3

# --- the fields read from each message type, and what each must be ----------------------
NUMBER, TEXT, BYTES = "a number", "a string", "a uint8 array"
Fields: TypeAlias = dict[str, "str | Fields | list[Fields]"]
_TIME: Fields = {"sec": NUMBER, "nanosec": NUMBER}
_HEADER: Fields = {"stamp": _TIME, "frame_id": TEXT}
_XY: Fields = {"x": NUMBER, "y": NUMBER}
FIELDS_READ: dict[str, Fields] = {
    radar_msgs.IMAGE: {
        "header": _HEADER,
        "height": NUMBER,
        "width": NUMBER,
        "encoding": TEXT,
        "is_bigendian": NUMBER,
        "step": NUMBER,
        "data": BYTES,
    },
    radar_msgs.COMPRESSED_IMAGE: {"header": _HEADER, "format": TEXT, "data": BYTES},
    radar_msgs.RADAR_SCAN: {
        "header": _HEADER,
        "returns": [
            {"range": NUMBER, "azimuth": NUMBER, "doppler_velocity": NUMBER, "amplitude": NUMBER}
        ],
    },
    radar_msgs.RADAR_TRACKS: {
        "header": _HEADER,
        "tracks": [{"uuid": {"uuid": BYTES}, "position": _XY, "velocity": _XY}],
    },
    CAN_FRAME: {
        "header": _HEADER,
        "id": NUMBER,
        "is_rtr": NUMBER,
        "is_extended": NUMBER,
        "is_error": NUMBER,
        "dlc": NUMBER,
        "data": BYTES,
    },
}
NUMERIC_TYPES = {"bool", "byte", "char", "float32", "float64"} | {
    f"{sign}int{bits}" for sign in ("", "u") for bits in (8, 16, 32, 64)
}


def _type_name(desc: Any) -> str:
    node, spec = desc
    if node == Nodetype.BASE:
        return str(spec[0])
    if node == Nodetype.NAME:
        return str(spec)
    return _type_name(spec[0]) + "[]"


_EXPECTED = {dict: "a message", list: "a message array"}


def _is_message_array(node: Nodetype, spec: Any) -> bool:
    return node in (Nodetype.ARRAY, Nodetype.SEQUENCE) and spec[0][0] == Nodetype.NAME


def _is_kind(node: Nodetype, spec: Any, kind: str) -> bool:
    if kind == BYTES:
        return node in (Nodetype.ARRAY, Nodetype.SEQUENCE) and spec[0] == (
            Nodetype.BASE,
            ("uint8", 0),
        )
    if kind == TEXT:
        return node == Nodetype.BASE and spec[0] == "string"
    return node == Nodetype.BASE and spec[0] in NUMERIC_TYPES


def _fields_problem(store: Typestore, msgtype: str, want: Fields, prefix: str) -> str | None:
    """What keeps `msgtype`, as `store` defines it, from having the fields `want`; None if ok."""
    if msgtype not in store.fielddefs:
        return f"has no definition of {msgtype}"
    have: dict[str, Any] = dict(store.fielddefs[msgtype][1])
    for name, kind in want.items():
        path = prefix + name
        if name not in have:
            return f"has no field {path}"
        node, spec = have[name]
        if isinstance(kind, dict) and node == Nodetype.NAME:
            problem = _fields_problem(store, spec, kind, path + ".")
        elif isinstance(kind, list) and _is_message_array(node, spec):
            problem = _fields_problem(store, spec[0][1], kind[0], path + "[].")
        elif isinstance(kind, str) and _is_kind(node, spec, kind):
            problem = None
        else:
            expected = kind if isinstance(kind, str) else _EXPECTED[type(kind)]
            return f"has {path} of type {_type_name(have[name])}, expected {expected}"
        if problem is not None:
            return problem
    return None


def _seconds(t_ns: int) -> str:
    sign = "-" if t_ns < 0 else ""
    sec, ns = divmod(abs(int(t_ns)), NS_PER_S)
    return f"{sign}{sec}.{ns:09d} s"


def _stamp(msg: Any) -> str:
    return f"{msg.header.stamp.sec}.{msg.header.stamp.nanosec:09d} s"


def _stamps(t_ns: Sequence[int] | Int64Array) -> str:
    shown = ", ".join(_seconds(int(t)) for t in t_ns[:WARN_STAMPS])
    return shown + (", …" if len(t_ns) > WARN_STAMPS else "")


def _next_message(last_ns: int | None) -> str:
    """The message after the one at `last_ns` (None: before any), in words."""
    return "the first message" if last_ns is None else f"the message after log t={last_ns} ns"


def _reason(err: BaseException) -> str:
    return f"{err} ({type(err).__name__})"


def check_mono16_bits(mono16_bits: int) -> None:
    """Raise ValueError unless 1 <= mono16_bits <= 16."""
    if not 1 <= mono16_bits <= 16:
        raise ValueError(f"mono16_bits: expected 1 to 16 significant bits, got {mono16_bits}")


def _to_8bit(img: npt.NDArray[np.uint16], bits: int) -> npt.NDArray[np.uint8]:
    """value * 255 / (2**bits - 1), rounded and clipped to 0..255."""
    scaled = np.rint(img.astype(np.float64) * (255.0 / (2**bits - 1)))
    return np.clip(scaled, 0, 255).astype(np.uint8)


def _decode_compressed(msg: Any, where: str, size_px: tuple[int, int] | None) -> npt.NDArray[Any]:
    """(H, W) or (H, W, 3|4) BGR(A), uint8 or uint16, from PNG or JPEG data: this project's
    own PNG layout by `core.io.png`, anything else by OpenCV. `size_px`: the (width, height)
    its header must declare, checked before decoding (None: any)."""
    buf = np.asarray(msg.data, dtype=np.uint8)
    head = buf[:8].tobytes()
    if not (head.startswith(PNG_SIGNATURE) or head.startswith(JPEG_MAGIC)):
        raise RecordingError(
            f"{where}: cannot decode image: expected PNG or JPEG data, format {msg.format!r}, "
            f"{buf.size} bytes starting {head!r}"
        )
    kind = "PNG" if head.startswith(PNG_SIGNATURE) else "JPEG"
    declared = image_size_px(buf.data)
    if declared is None:
        raise RecordingError(
            f"{where}: damaged {kind} data ({buf.size} bytes): its header gives no image size"
        )
    if size_px is not None and declared != size_px:
        raise RecordingError(
            f"{where}: the {kind} image declares {declared[0]}x{declared[1]} pixels, the "
            f"calibration says {size_px[0]}x{size_px[1]}; not decoded"
        )
    plain = decode_unfiltered_grey(np.ascontiguousarray(buf).data)
    if plain is not None:
        return plain
    try:
        img = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED)
    except cv2.error as err:
        raise RecordingError(f"{where}: cannot decode image ({msg.format!r}): {err}") from err
    if img is None:
        raise RecordingError(
            f"{where}: damaged {kind} data: {buf.size} bytes (format {msg.format!r}) that "
            "OpenCV cannot decode"
        )
    if img.dtype not in (np.uint8, np.uint16) or (img.ndim == 3 and img.shape[2] not in (3, 4)):
        raise RecordingError(
            f"{where}: expected an 8- or 16-bit grey, BGR or BGRA image, got {img.dtype} "
            f"with shape {img.shape}"
        )
    if img.ndim == 3:
        img = cv2.cvtColor(img, DECODED_TO_GREY[img.shape[2]])
    return img


def _decode_raw(msg: Any, where: str, size_px: tuple[int, int] | None) -> npt.NDArray[Any]:
    """(H, W) uint8 or uint16 grey from a raw sensor_msgs/Image; `size_px` as in
    `_decode_compressed`."""
    encoding = str(msg.encoding).lower()
    if encoding not in RAW_ENCODINGS:
        raise RecordingError(
            f"{where}: image encoding {msg.encoding!r} not supported; "
            f"expected one of {', '.join(RAW_ENCODINGS)}"
        )
    channels, depth, to_grey = RAW_ENCODINGS[encoding]
    height, width, step = int(msg.height), int(msg.width), int(msg.step)
    if size_px is not None and (width, height) != size_px:
        raise RecordingError(
            f"{where}: the image message declares {width}x{height} pixels, the calibration "
            f"says {size_px[0]}x{size_px[1]}; not decoded"
        )
    data = np.asarray(msg.data, dtype=np.uint8)
    row_bytes = width * channels * depth
    if height == 0 or width == 0 or step < row_bytes or data.size < step * height:
        raise RecordingError(
            f"{where}: expected a {width}x{height} {encoding} image of rows of at least "
            f"{row_bytes} bytes, got step {step} and {data.size} bytes"
        )
    pixels = data[: step * height].reshape(height, step)[:, :row_bytes]
    if depth == 2:
        pairs = pixels.reshape(height, width, 2).astype(np.uint16)
        hi, lo = (
            (pairs[..., 0], pairs[..., 1]) if msg.is_bigendian else (pairs[..., 1], pairs[..., 0])
        )
        return (hi << 8) | lo
    img = pixels.reshape(height, width, channels)
    return img[:, :, 0] if to_grey is None else cv2.cvtColor(img, to_grey)


def decode_image(
    msg: Any,
    msgtype: str,
    where: str,
    mono16_bits: int = 16,
    size_px: tuple[int, int] | None = None,
) -> npt.NDArray[np.uint8]:
    """(H, W) uint8 grey image from a sensor_msgs Image or CompressedImage.

    Image encodings: mono8 (8UC1), mono16 (16UC1; `is_bigendian` honoured), bgr8, rgb8, bgra8,
    rgba8. CompressedImage: JPEG (grey or colour) or PNG (8- or 16-bit, grey or colour).
    Colour becomes grey with OpenCV's BGR2GRAY weights; 16-bit values v become
    round(v * 255 / (2**mono16_bits - 1)), clipped to 255. `where` names the topic and time
    stamp in errors. `size_px` (width, height): the size the image must have, checked against
    what the message or its PNG / JPEG header declares before anything is decoded, so that a
    small message declaring a huge image costs nothing (None: any size).
    """
    check_mono16_bits(mono16_bits)
    if msgtype == radar_msgs.COMPRESSED_IMAGE:
        img = _decode_compressed(msg, where, size_px)
    else:
        img = _decode_raw(msg, where, size_px)
    if img.dtype == np.uint16:
        img = _to_8bit(img, mono16_bits)
    return np.ascontiguousarray(img, dtype=np.uint8)


class BagReader:
    """One open bag; a context manager. Not thread-safe: callers that share it use a lock."""

    def __init__(self, path: Path | str) -> None:
        self.path = Path(path)
        try:
            self._reader = AnyReader([self.path], default_typestore=radar_msgs.typestore())
            self._reader.open()
        except BAG_ERRORS as err:
            raise RecordingError(
                f"{self.path}: cannot open as a ROS bag (expected a ROS 1 .bag file, a ROS 2 "
                f"bag folder with metadata.yaml, or a .db3 or .mcap file): {_reason(err)}"
            ) from err
        self._open = True
        # read_at's place in one stream: its connection and the messages after the last read
        self._cursor: tuple[Connection, Iterator[tuple[int, bytes]]] | None = None
        for c in self._reader.connections:
            if not (isinstance(c.topic, str) and isinstance(c.msgtype, str)):
                self.close()
                raise RecordingError(
                    f"{self.path}: connection {c.id} has topic {c.topic!r} of type {c.msgtype!r}; "
                    "expected a topic name and a message type name"
                )

    def close(self) -> None:
        if self._open:
            self._open = False
            self._cursor = None
            self._reader.close()

    def __enter__(self) -> BagReader:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()

    @property
    def topics(self) -> dict[str, str]:
        """Topic name -> message type of every connection in the bag."""
        return {c.topic: c.msgtype for c in self._reader.connections}

    def _listing(self) -> str:
        return ", ".join(f"{t} ({m})" for t, m in sorted(self.topics.items())) or "none"

    def connection(self, topic: str | None, msgtypes: Sequence[str], role: str) -> Connection:
        """The connection of `topic`, or the only topic of one of `msgtypes` when None.

        Checks that the bag defines the message type with the fields this module reads.
        """
        conns = self._reader.connections
        if topic is not None:
            found = [c for c in conns if c.topic == topic]
            if not found:
                raise RecordingError(
                    f"{self.path}: no {role} topic {topic!r}; topics in the bag: {self._listing()}"
                )
            if found[0].msgtype not in msgtypes:
                raise RecordingError(
                    f"{self.path}: {role} topic {topic!r} has type {found[0].msgtype}; "
                    f"expected {' or '.join(msgtypes)}"
                )
            conn = found[0]
        else:
            candidates = sorted({c.topic for c in conns if c.msgtype in msgtypes})
            if len(candidates) != 1:
                what = "several" if candidates else "no"
                raise RecordingError(
                    f"{self.path}: {what} {role} topics of type {' or '.join(msgtypes)} "
                    f"({', '.join(candidates) or 'none'}); name one in recording.yaml. "
                    f"Topics in the bag: {self._listing()}"
                )
            conn = next(c for c in conns if c.topic == candidates[0])
        if conn.msgtype in FIELDS_READ:
            problem = _fields_problem(
                self._reader.typestore, conn.msgtype, FIELDS_READ[conn.msgtype], ""
            )
            if problem is not None:
                raise RecordingError(
                    f"{self.path}: {role} topic {conn.topic}: the bag's {conn.msgtype} {problem}"
                )
        return conn

    # --- raw access, every library error made a RecordingError ----------------------------
    def _raw(
        self, conn: Connection, start: int | None = None, stop: int | None = None
    ) -> Iterator[tuple[int, bytes]]:
        """(log time ns, serialised message) of every message of `conn`'s topic, bag order."""
        stream = [
            c
            for c in self._reader.connections
            if (c.topic, c.msgtype) == (conn.topic, conn.msgtype)
        ]
        last: int | None = None
        try:
            for _, t_ns, raw in self._reader.messages(stream or [conn], start, stop):
                # sqlite3 columns hold whatever a damaged page says
                if not (isinstance(t_ns, int) and 0 <= t_ns <= INT64_MAX):
                    raise RecordingError(
                        f"{self.path}: {conn.topic}: {_next_message(last)} has log time "
                        f"{t_ns!r} ns; expected an integer from 0 to {INT64_MAX}"
                    )
                if not isinstance(raw, bytes | memoryview):
                    raise RecordingError(
                        f"{self.path}: {conn.topic}: message at log t={t_ns} ns has data of "
                        f"type {type(raw).__name__}; expected bytes"
                    )
                last = t_ns
                yield t_ns, raw
        except BAG_ERRORS as err:
            raise RecordingError(
                f"{self.path}: {conn.topic}: cannot read {_next_message(last)}: {_reason(err)}"
            ) from err

    def _deserialize(self, raw: bytes, conn: Connection, t_ns: int) -> Any:
        try:
            return self._reader.deserialize(raw, conn.msgtype)
        except BAG_ERRORS as err:
            raise RecordingError(
                f"{self.path}: {conn.topic}: message at log t={t_ns} ns is not a valid "
                f"{conn.msgtype}: {_reason(err)}"
            ) from err

    def _messages(self, conn: Connection) -> Iterator[tuple[int, Any]]:
        for t_ns, raw in self._raw(conn):
            yield t_ns, self._deserialize(raw, conn, t_ns)

    # --- public reading ----------------------------------------------------------------
    def log_times_ns(self, conn: Connection) -> Int64Array:
        """(N,) int64 receive times of every message of `conn`, in bag order."""
        return np.fromiter((t for t, _ in self._raw(conn)), dtype=np.int64)

    def read_at(self, conn: Connection, t_ns: int, occurrence: int = 0) -> Any:
        """The `occurrence`-th message of `conn` received at exactly `t_ns`, deserialised.

        Reading frame after frame, each message is taken from where the last one was read
        (`_next_at`): a query by time reads and parses the whole chunk of the file that
        holds the message (an MCAP chunk holds about a dozen camera images), a cursor each
        chunk once. Anything else (a seek, a repeated stamp) is a query by time, which starts
        the cursor again after the message it found."""
        raw = self._next_at(conn, t_ns) if occurrence == 0 else None
        if raw is None:
            found = [raw for _, raw in self._raw(conn, t_ns, t_ns + 1)]
            if len(found) <= occurrence:
                raise RecordingError(
                    f"{self.path}: {conn.topic}: no message at t={t_ns} ns "
                    f"(expected at least {occurrence + 1}, found {len(found)})"
                )
            raw = found[occurrence]
            self._cursor = (conn, self._raw(conn, t_ns + 1, None))
        return self._deserialize(raw, conn, t_ns)

    def _next_at(self, conn: Connection, t_ns: int) -> bytes | None:
        """The first message of `conn` at `t_ns` among the next `CURSOR_LOOKAHEAD` after the
        last one `read_at` returned, in bag order; None (and no cursor) when it is not there:
        the caller asks by time instead."""
        cursor, self._cursor = self._cursor, None
        if cursor is None or cursor[0] is not conn:
            return None
        messages = cursor[1]
        for _ in range(CURSOR_LOOKAHEAD):
            item = next(messages, None)
            if item is None or item[0] > t_ns:
                return None
            if item[0] == t_ns:
                self._cursor = cursor
                return item[1]
        return None

    def read_radar(
        self, conn: Connection, offset_ns: int = 0, *, warn: Callable[[str], None]
    ) -> RadarScans:
        """Every RadarScan or RadarTracks message of `conn`; `offset_ns` added to the stamps.

        Tracks become polar: range and azimuth (positive left) of the position, range rate
        (positive receding) the velocity along the line of sight, track id the first 8 bytes
        of the UUID (little-endian, sign bit cleared), amplitude 0.

        Repairs what real recordings get wrong, each kind reported once through `warn`: returns
        with a non-finite range, azimuth, velocity or amplitude, or values no radar reports
        (`radarscans.plausible`), are dropped; scans stamped outside the
        main body of the stream (`timeline.main_block`, e.g. 1970 amid a drive) are dropped;
        scans out of time order are sorted.
        """
        where = f"{self.path}: radar topic {conn.topic}"
        times: list[int] = []
        scan_of_row: list[int] = []
        rows: list[tuple[float, float, float, float]] = []
        ids: list[int] = []
        for t_ns, msg in self._messages(conn):
            if conn.msgtype == radar_msgs.RADAR_SCAN:
                for ret in msg.returns:
                    rows.append((ret.range, ret.azimuth, ret.doppler_velocity, ret.amplitude))
                    ids.append(-1)
            else:
                for trk in msg.tracks:
                    x, y = trk.position.x, trk.position.y
                    r = math.hypot(x, y)
                    rr = (x * trk.velocity.x + y * trk.velocity.y) / r if r > 0 else 0.0
                    rows.append((r, math.atan2(y, x), rr, 0.0))
                    ids.append(int.from_bytes(bytes(trk.uuid.uuid[:8]), "little") & INT64_MAX)
            scan_of_row.extend([len(times)] * (len(rows) - len(scan_of_row)))
            times.append(t_ns)
        t = np.asarray(times, dtype=np.int64)
        scan = np.asarray(scan_of_row, dtype=np.int64)
        values = np.asarray(rows, dtype=np.float64).reshape(-1, 4)

        finite = np.all(np.isfinite(values), axis=1)
        if not finite.all():
            bad_scans = t[np.unique(scan[~finite])]
            warn(
                f"{where}: {np.count_nonzero(~finite)} return(s) with a non-finite range, "
                f"azimuth, velocity or amplitude dropped, in scans at log t = "
                f"{_stamps(bad_scans)}"
            )
        implausible = finite & ~plausible(values[:, 0], values[:, 1], values[:, 2])
        if implausible.any():
            warn(
                f"{where}: {np.count_nonzero(implausible)} return(s) no radar reports (range "
                f"outside 0-{MAX_RANGE_M:g} m, azimuth beyond +-pi or range rate over "
                f"{MAX_ABS_RANGE_RATE_MPS:g} m/s) dropped, in scans at log t = "
                f"{_stamps(t[np.unique(scan[implausible])])}"
            )
            finite &= ~implausible
        in_block = main_block(t)
        if not in_block.all():
            warn(
                f"{where}: {np.count_nonzero(~in_block)} scan(s) stamped away from the rest of "
                f"the stream dropped, at log t = {_stamps(t[~in_block])}"
            )
        kept = np.flatnonzero(in_block)
        late = np.diff(t[kept]) < 0
        if late.any():
            warn(
                f"{where}: {np.count_nonzero(late)} scan(s) stamped earlier than the scan before, "
                f"sorted; at log t = {_stamps(t[kept][1:][late])}"
            )
        order = kept[np.argsort(t[kept], kind="stable")]
        rank = np.full(len(t), -1, dtype=np.int64)
        rank[order] = np.arange(len(order))
        row_idx = np.flatnonzero(finite & in_block[scan])
        row_idx = row_idx[np.argsort(rank[scan[row_idx]], kind="stable")]
        counts = np.bincount(rank[scan[row_idx]], minlength=len(order))
        return RadarScans(
            t_ns=t[order] + offset_ns,
            start=np.concatenate(([0], np.cumsum(counts))).astype(np.int64),
            range_m=values[row_idx, 0],
            azimuth_rad=values[row_idx, 1],
            range_rate_mps=values[row_idx, 2],
            amplitude=values[row_idx, 3],
            track_id=np.asarray(ids, dtype=np.int64)[row_idx],
        )

    def can_frames(self, conn: Connection) -> Iterator[CanFrame]:
        """The data frames of a can_msgs/Frame topic, in bag order.

        t_ns: the log time; data: the first `dlc` bytes; channel: the header's frame_id, None
        when empty. Remote (rtr) and error frames are skipped; dlc > 8 raises RecordingError.
        """
        for t_ns, msg in self._messages(conn):
            if msg.is_rtr or msg.is_error:
                continue
            dlc, data = int(msg.dlc), bytes(np.asarray(msg.data, dtype=np.uint8))
            if dlc > min(CAN_MAX_DLC, len(data)):
                raise RecordingError(
                    f"{self.path}: {conn.topic} at {_stamp(msg)} (log t={t_ns} ns): CAN frame "
                    f"with dlc {dlc}; expected at most {min(CAN_MAX_DLC, len(data))} data bytes"
                )
            yield CanFrame(
                t_ns=t_ns,
                arbitration_id=int(msg.id),
                is_extended=bool(msg.is_extended),
                data=data[:dlc],
                channel=str(msg.header.frame_id) or None,
            )


class CameraStream:
    """Random access to the images of one camera topic, in time order, decoded on demand.

    log_ns: (N,) bag log time of each frame, ascending; occurrence: (N,) which of the
    messages at that same log time it is (bag order), so (log_ns, occurrence) finds a message
    again exactly; times_ns: log_ns + offset_ns; skipped: frames left out because their
    stamps lie outside the stream's main span (timeline.main_block: a 1970 stamp mid-drive);
    backwards: how often the reader gave a stamp earlier than the one before (then sorted).
    mono16_bits: the significant bits of 16-bit images (see decode_image).

    Notes:
        rosbags reads a bag split over several files one file after another, so the log
        times it yields can go backwards between files: they are sorted here.
    """

    def __init__(
        self, bag: BagReader, topic: str | None, offset_ns: int = 0, mono16_bits: int = 16
    ) -> None:
        check_mono16_bits(mono16_bits)
        self.bag = bag
        self.mono16_bits = mono16_bits
        self.conn = bag.connection(topic, CAMERA_TYPES, "camera")
        raw_ns = bag.log_times_ns(self.conn)
        self.backwards = int(np.count_nonzero(np.diff(raw_ns) < 0))
        in_time = raw_ns[np.argsort(raw_ns, kind="stable")]
        occurrence = np.arange(len(in_time)) - np.searchsorted(in_time, in_time, side="left")
        keep = main_block(in_time)
        self.log_ns: Int64Array = in_time[keep]
        self.occurrence: Int64Array = occurrence[keep]
        self.skipped = int(np.count_nonzero(~keep))
        if len(self.log_ns) == 0:
            raise RecordingError(
                f"{bag.path}: camera topic {self.conn.topic}: expected images, the stream is empty"
            )
        self.times_ns: Int64Array = self.log_ns + offset_ns

    def __len__(self) -> int:
        return len(self.log_ns)

    def image(self, i: int) -> npt.NDArray[np.uint8]:
        """(H, W) uint8 grey image of frame `i`."""
        t = int(self.log_ns[i])
        msg = self.bag.read_at(self.conn, t, int(self.occurrence[i]))
        where = f"{self.bag.path}: {self.conn.topic} at {_stamp(msg)} (log t={t} ns)"
        return decode_image(msg, self.conn.msgtype, where, self.mono16_bits)
