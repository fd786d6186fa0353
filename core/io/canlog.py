"""The car's speed and yaw rate decoded with a DBC from CAN frames, one pass over a source.

    frames = iter_log_frames(path, warn=warn)            # core.io.canfiles, or a bag's topic
    vehicle = VehicleSignalDecoder(db, source, where)     # one decoder per quantity family
    radar = RadarCanDecoder(db, radar_source, where)      # core.io.can_radar
    decode_frames(frames, [vehicle, radar])               # one pass over the log
    signals, scans = vehicle.result(warn), radar.result(warn)

Notes:
    Frames shorter than the DBC says are padded with zero bytes: some loggers strip trailing
    zero bytes (the comma2k19 logs do), and a strict decoder would reject them.
"""

from __future__ import annotations

import difflib
import math
import warnings
from collections import Counter
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import cantools
import numpy as np
import numpy.typing as npt
from cantools.database.can import Database, Message

from core.ego import STANDSTILL_SPEED_MPS, samples_around
from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.errors import RecordingError
from core.io.timeline import DEFAULT_MAX_GAP_NS, main_block

if TYPE_CHECKING:  # manifest imports this module for SignalMapping
    from core.io.manifest import CanBus, CanSource

Int64Array = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]
Warn = Callable[[str], None]

# How the yaw-rate bias is estimated: not at all, or from the stretches standing still.
YAW_RATE_BIAS_MODES = ("none", "standstill")
SPEED_UNITS_TO_MPS = {"m/s": 1.0, "km/h": 1.0 / 3.6, "mph": 0.44704}
YAW_RATE_UNITS_TO_RADPS = {"rad/s": 1.0, "deg/s": math.pi / 180.0}
NS_PER_S = 1_000_000_000

# Standing still for less than this gives too few yaw-rate samples for a bias estimate.
MIN_STANDSTILL_S = 1.0


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
    if t.size == 0:
        return np.zeros(t.shape)
    # Only the samples around t (a frame's lookup in an hour of CAN stays cheap), relative to
    # the first of them so that float64 keeps nanosecond resolution.
    ts, vs = samples_around(ts_ns, values, int(t.min()), int(t.max()))
    return np.interp((t - ts[0]).astype(np.float64), (ts - ts[0]).astype(np.float64), vs)


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


# --- decoding -----------------------------------------------------------------------------
Traffic = Mapping[tuple[str | None, int, bool], int]
"""Frames seen per (channel, arbitration id, extended flag)."""


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
        backwards = int(np.count_nonzero(np.diff(t[keep]) < 0))
        if backwards:
            warn(f"{where}: {backwards} {what} frames stamped earlier than the one before; sorted")
        order = np.argsort(t[keep], kind="stable")
        return t[keep][order], which[keep][order], values[keep][order]


class FrameDecoder:
    """What `decode_frames` feeds: the frames of some DBC messages on one bus, in a FrameLog.

    This part decides which frames to take (the bus's channel, the messages' ids) and keeps
    the traffic decode_frames counted, for the warning when none came; subclasses turn the
    log into their result.
    """

    def __init__(self, bus: CanBus, log: FrameLog) -> None:
        self._bus = bus
        self._log = log
        self._traffic: Traffic = {}

    @property
    def bus(self) -> CanBus:
        return self._bus

    @property
    def ids(self) -> frozenset[tuple[int, bool]]:
        """(arbitration id, extended) of the messages decoded."""
        return frozenset(self._log.keys)

    def wants(self, frame: CanFrame) -> bool:
        """Whether to feed `frame`; a function of its channel, id and extended flag only."""
        channel = self._bus.channel
        key = (frame.arbitration_id, frame.is_extended)
        return (channel is None or frame.channel == channel) and key in self._log.keys

    def feed(self, frame: CanFrame) -> None:
        self._log.feed(frame)

    def note_traffic(self, traffic: Traffic) -> None:
        """The frames the log carried, per (channel, id, extended)."""
        self._traffic = traffic


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


class VehicleSignalDecoder(FrameDecoder):
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
        if source.yaw_rate_bias not in YAW_RATE_BIAS_MODES:
            expected = " or ".join(repr(m) for m in YAW_RATE_BIAS_MODES)
            raise ValueError(f"yaw_rate_bias: expected {expected}, got {source.yaw_rate_bias!r}")
        self.source = source
        self.where = where
        self.offset_ns = offset_ns
        self.standstill_speed_mps = standstill_speed_mps
        self.min_standstill_s = min_standstill_s
        speed = find_signal(db, source.speed, where)
        yaw = find_signal(db, source.yaw_rate, where)
        messages = [speed] if yaw.frame_id == speed.frame_id else [speed, yaw]
        super().__init__(
            source.bus, FrameLog(messages, (source.speed.signal, source.yaw_rate.signal))
        )
        self._speed_i, self._yaw_i = 0, len(messages) - 1

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
