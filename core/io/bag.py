"""Camera images and radar scans from a ROS bag (ROS 1 `.bag`, ROS 2 sqlite3 or MCAP).

`BagReader` opens one bag with rosbags' AnyReader (radar_msgs registered), finds topics by
name or by message type, indexes the camera topic's time stamps once and decodes one image
on demand; radar messages are small and all decoded on open.

Notes:
    Time stamps are the bag's receive (log) times, not the header stamps: they are known
    without deserialising a message, which keeps opening a long drive cheap and random access
    exact. The writer of this project stores header stamp = log time.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.interfaces import Connection

from core.io import radar_msgs
from core.io.errors import RecordingError
from core.io.radarscans import RadarScans

Int64Array = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]

CAMERA_TYPES = (radar_msgs.COMPRESSED_IMAGE, radar_msgs.IMAGE)
RADAR_TYPES = (radar_msgs.RADAR_SCAN, radar_msgs.RADAR_TRACKS)

# Raw sensor_msgs/Image encodings we convert to grey, with their channel count.
RAW_ENCODINGS = {"mono8": 1, "8uc1": 1, "bgr8": 3, "rgb8": 3, "bgra8": 4, "rgba8": 4}


def _stamp(msg: Any) -> str:
    return f"{msg.header.stamp.sec}.{msg.header.stamp.nanosec:09d} s"


def decode_image(msg: Any, msgtype: str, where: str) -> npt.NDArray[np.uint8]:
    """(H, W) uint8 grey image from a CompressedImage (PNG/JPEG) or a raw 8-bit Image.

    `where` names the topic and time stamp in errors.
    """
    if msgtype == radar_msgs.COMPRESSED_IMAGE:
        buf = np.asarray(msg.data, dtype=np.uint8)
        try:
            img = cv2.imdecode(buf, cv2.IMREAD_UNCHANGED) if buf.size else None
        except cv2.error as err:
            raise RecordingError(f"{where}: cannot decode image ({msg.format!r}): {err}") from err
        if img is None:
            raise RecordingError(
                f"{where}: cannot decode image: expected PNG or JPEG data, format {msg.format!r}, "
                f"{buf.size} bytes"
            )
    else:
        encoding = str(msg.encoding).lower()
        if encoding not in RAW_ENCODINGS:
            raise RecordingError(
                f"{where}: image encoding {msg.encoding!r} not supported; "
                f"expected one of {', '.join(RAW_ENCODINGS)}"
            )
        channels = RAW_ENCODINGS[encoding]
        data = np.asarray(msg.data, dtype=np.uint8)
        if msg.step < msg.width * channels or data.size < msg.step * msg.height:
            raise RecordingError(
                f"{where}: image of {msg.width}x{msg.height} {encoding} needs "
                f"{msg.step * msg.height} bytes with step {msg.step}, got {data.size}"
            )
        rows = data[: msg.step * msg.height].reshape(msg.height, msg.step)
        img = rows[:, : msg.width * channels].reshape(msg.height, msg.width, channels)
        if encoding.startswith("rgb"):
            img = img[:, :, [2, 1, 0, 3][:channels]]
        if channels == 1:
            img = img[:, :, 0]
    if img.dtype != np.uint8:
        raise RecordingError(f"{where}: expected an 8-bit image, got {img.dtype}")
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[:, :, 0]
    elif img.ndim == 3:
        code = cv2.COLOR_BGRA2GRAY if img.shape[2] == 4 else cv2.COLOR_BGR2GRAY
        img = cv2.cvtColor(img, code)
    return np.ascontiguousarray(img)


class BagReader:
    """One open bag. Not thread-safe: callers that share it guard it with a lock."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self._reader = AnyReader([path], default_typestore=radar_msgs.typestore())
        try:
            self._reader.open()
        except (AnyReaderError, OSError) as err:
            raise RecordingError(f"{path}: cannot open ROS bag: {err}") from err

    def close(self) -> None:
        self._reader.close()

    @property
    def topics(self) -> dict[str, str]:
        """Topic name -> message type of every connection in the bag."""
        return {c.topic: c.msgtype for c in self._reader.connections}

    def _listing(self) -> str:
        return ", ".join(f"{t} ({m})" for t, m in sorted(self.topics.items())) or "none"

    def connection(self, topic: str | None, msgtypes: Sequence[str], role: str) -> Connection:
        """The connection of `topic`, or the only topic of one of `msgtypes` when None."""
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
            return found[0]
        candidates = sorted({c.topic for c in conns if c.msgtype in msgtypes})
        if len(candidates) != 1:
            what = "several" if candidates else "no"
            raise RecordingError(
                f"{self.path}: {what} {role} topics of type {' or '.join(msgtypes)} "
                f"({', '.join(candidates) or 'none'}); name one in recording.yaml. "
                f"Topics in the bag: {self._listing()}"
            )
        return next(c for c in conns if c.topic == candidates[0])

    def log_times_ns(self, conn: Connection) -> Int64Array:
        """(N,) int64 receive times of every message of `conn`, in bag order."""
        try:
            return np.fromiter((t for _, t, _ in self._reader.messages([conn])), dtype=np.int64)
        except (AnyReaderError, OSError) as err:
            raise RecordingError(f"{self.path}: cannot read topic {conn.topic}: {err}") from err

    def read_at(self, conn: Connection, t_ns: int, occurrence: int = 0) -> Any:
        """The `occurrence`-th message of `conn` received at exactly `t_ns`, deserialised."""
        try:
            found = [raw for _, _, raw in self._reader.messages([conn], start=t_ns, stop=t_ns + 1)]
            if len(found) <= occurrence:
                raise RecordingError(f"{self.path}: {conn.topic}: no message at t={t_ns} ns")
            return self._reader.deserialize(found[occurrence], conn.msgtype)
        except (AnyReaderError, OSError, ValueError) as err:
            raise RecordingError(
                f"{self.path}: {conn.topic}: message at t={t_ns} ns cannot be read: {err}"
            ) from err

    def read_radar(self, conn: Connection, offset_ns: int = 0) -> RadarScans:
        """Every RadarScan or RadarTracks message of `conn`; `offset_ns` added to stamps."""
        times: list[int] = []
        starts = [0]
        cols: dict[str, list[float]] = {"r": [], "a": [], "rr": [], "amp": []}
        ids: list[int] = []
        try:
            for _, t_ns, raw in self._reader.messages([conn]):
                msg: Any = self._reader.deserialize(raw, conn.msgtype)
                if conn.msgtype == radar_msgs.RADAR_SCAN:
                    for ret in msg.returns:
                        cols["r"].append(ret.range)
                        cols["a"].append(ret.azimuth)
                        cols["rr"].append(ret.doppler_velocity)
                        cols["amp"].append(ret.amplitude)
                        ids.append(-1)
                else:
                    for trk in msg.tracks:
                        x, y = trk.position.x, trk.position.y
                        r = math.hypot(x, y)
                        cols["r"].append(r)
                        cols["a"].append(math.atan2(y, x))
                        rr = (x * trk.velocity.x + y * trk.velocity.y) / r if r > 0 else 0.0
                        cols["rr"].append(rr)
                        cols["amp"].append(0.0)
                        ids.append(int.from_bytes(bytes(trk.uuid.uuid[:8]), "little") & (2**63 - 1))
                times.append(t_ns + offset_ns)
                starts.append(len(ids))
        except (AnyReaderError, OSError, ValueError) as err:
            raise RecordingError(
                f"{self.path}: cannot read radar topic {conn.topic}: {err}"
            ) from err
        order = np.argsort(np.asarray(times, dtype=np.int64), kind="stable")
        if np.any(order != np.arange(len(order))):
            raise RecordingError(
                f"{self.path}: radar topic {conn.topic}: scans are not in time order"
            )
        f64 = np.float64
        return RadarScans(
            t_ns=np.asarray(times, dtype=np.int64),
            start=np.asarray(starts, dtype=np.int64),
            range_m=np.asarray(cols["r"], dtype=f64),
            azimuth_rad=np.asarray(cols["a"], dtype=f64),
            range_rate_mps=np.asarray(cols["rr"], dtype=f64),
            amplitude=np.asarray(cols["amp"], dtype=f64),
            track_id=np.asarray(ids, dtype=np.int64),
        )


class CameraStream:
    """Random access to the images of one camera topic (indexed once, decoded on demand).

    times_ns: (N,) int64 camera stamps (log times + offset), in bag order.
    """

    def __init__(self, bag: BagReader, topic: str | None, offset_ns: int = 0) -> None:
        self.bag = bag
        self.conn = bag.connection(topic, CAMERA_TYPES, "camera")
        log_ns = bag.log_times_ns(self.conn)
        if len(log_ns) == 0:
            raise RecordingError(
                f"{bag.path}: camera topic {self.conn.topic}: expected images, the stream is empty"
            )
        if np.any(np.diff(log_ns) < 0):
            raise RecordingError(
                f"{bag.path}: camera topic {self.conn.topic}: stamps not in time order"
            )
        self._log_ns = log_ns
        # The k-th message at the same stamp, for exact random access.
        first = np.searchsorted(log_ns, log_ns, side="left")
        self._occurrence = np.arange(len(log_ns)) - first
        self.times_ns: Int64Array = log_ns + offset_ns

    def __len__(self) -> int:
        return len(self._log_ns)

    def image(self, i: int) -> npt.NDArray[np.uint8]:
        """(H, W) uint8 grey image of frame `i`."""
        t = int(self._log_ns[i])
        msg = self.bag.read_at(self.conn, t, int(self._occurrence[i]))
        where = f"{self.bag.path}: {self.conn.topic} at {_stamp(msg)} (log t={t} ns)"
        return decode_image(msg, self.conn.msgtype, where)
