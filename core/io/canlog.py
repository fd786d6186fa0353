"""Speed and yaw rate of the car from a CAN log decoded with one or more DBC files.

Any log python-can's `LogReader` reads (.blf, .asc, .log (candump -L), .trc, .csv, also
gzip'd) is decoded with cantools. Only the two messages that carry the mapped signals are
decoded; frames of other ids, error frames and remote frames are skipped.

Notes:
    Frames shorter than the DBC says are padded with zero bytes: some loggers strip trailing
    zero bytes (the comma2k19 logs do), and a strict decoder would reject them.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import can
import cantools
import numpy as np
import numpy.typing as npt
from cantools.database.can import Database, Message

from core.io.errors import RecordingError

Int64Array = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]

SPEED_UNITS_TO_MPS = {"m/s": 1.0, "km/h": 1.0 / 3.6, "mph": 0.44704}
YAW_RATE_UNITS_TO_RADPS = {"rad/s": 1.0, "deg/s": math.pi / 180.0}
NS_PER_S = 1_000_000_000


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
    turning left.
    """

    speed_t_ns: Int64Array
    speed_mps: FloatArray
    yaw_rate_t_ns: Int64Array
    yaw_rate_radps: FloatArray

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


def find_signal(db: Database, mapping: SignalMapping, dbc_names: str) -> Message:
    """The DBC message carrying `mapping`; RecordingError with close names when missing."""
    names = [m.name for m in db.messages]
    try:
        message = db.get_message_by_name(mapping.message)
    except KeyError as err:
        close = difflib.get_close_matches(mapping.message, names, n=5, cutoff=0.4)
        raise RecordingError(
            f"{dbc_names}: no message {mapping.message!r} in the DBC; "
            f"close names: {', '.join(close) or 'none'}"
        ) from err
    signals = [s.name for s in message.signals]
    if mapping.signal not in signals:
        close = difflib.get_close_matches(mapping.signal, signals, n=5, cutoff=0.4)
        raise RecordingError(
            f"{dbc_names}: message {mapping.message!r} has no signal {mapping.signal!r}; "
            f"close names: {', '.join(close) or 'none'}; all: {', '.join(signals)}"
        )
    return message


def read_vehicle_signals(
    log_path: Path,
    dbc_paths: Sequence[Path],
    speed: SignalMapping,
    yaw_rate: SignalMapping,
    channel: str | None = None,
    offset_ns: int = 0,
) -> VehicleSignals:
    """Decode speed and yaw rate from a CAN log.

    `channel`: keep only frames of this channel (e.g. "can0"; None keeps all); `offset_ns`
    is added to every time stamp (the recording's time offset for CAN).
    """
    db = load_dbc(dbc_paths)
    dbc_names = ", ".join(str(p) for p in dbc_paths)
    wanted = {
        "speed": (speed, find_signal(db, speed, dbc_names)),
        "yaw_rate": (yaw_rate, find_signal(db, yaw_rate, dbc_names)),
    }
    by_id: dict[tuple[int, bool], list[str]] = {}
    for key, (_, message) in wanted.items():
        by_id.setdefault((message.frame_id, message.is_extended_frame), []).append(key)
    samples: dict[str, tuple[list[int], list[float]]] = {k: ([], []) for k in wanted}

    if not log_path.is_file():
        raise RecordingError(f"{log_path}: CAN log not found")
    try:
        reader = can.LogReader(str(log_path))
    except (ValueError, OSError) as err:
        raise RecordingError(f"{log_path}: cannot open CAN log: {err}") from err
    try:
        for frame in reader:
            if frame.is_error_frame or frame.is_remote_frame:
                continue
            keys = by_id.get((frame.arbitration_id, frame.is_extended_id))
            if keys is None or (channel is not None and str(frame.channel) != channel):
                continue
            t_ns = round(frame.timestamp * NS_PER_S) + offset_ns
            message = wanted[keys[0]][1]
            data = bytes(frame.data).ljust(message.length, b"\x00")
            try:
                decoded = cast(Mapping[str, float], message.decode(data, decode_choices=False))
            except cantools.database.DecodeError as err:
                raise RecordingError(
                    f"{log_path}: frame {message.name} (0x{message.frame_id:X}) at "
                    f"t={frame.timestamp:.6f} s cannot be decoded: {err}"
                ) from err
            for key in keys:
                mapping = wanted[key][0]
                ts, vs = samples[key]
                ts.append(t_ns)
                vs.append(float(decoded[mapping.signal]) * mapping.to_si * mapping.sign)
    except (ValueError, OSError, EOFError, can.CanError) as err:
        raise RecordingError(f"{log_path}: cannot read CAN log: {err}") from err
    finally:
        reader.stop()

    def arrays(key: str) -> tuple[Int64Array, FloatArray]:
        ts, vs = samples[key]
        t = np.asarray(ts, dtype=np.int64)
        order = np.argsort(t, kind="stable")
        return t[order], np.asarray(vs, dtype=np.float64)[order]

    speed_t, speed_v = arrays("speed")
    yaw_t, yaw_v = arrays("yaw_rate")
    return VehicleSignals(speed_t, speed_v, yaw_t, yaw_v)
