"""`recording.yaml`: the manifest that names the parts of a recording.

Layout (format_version 1):

    format_version: 1
    name: highway
    description: free text
    generator: {scenario: highway, seed: 1}           # optional, free-form
    camera: {bag: bag, topic: /camera/image/compressed}   # topic optional: found by type
    #   mono16_bits: 12     optional: significant bits of mono16 images (default 16)
    radar: {bag: bag, topic: /radar/scan}                 # optional section; topic optional
    # or radar tracks sent over CAN (a family of messages, one track each):
    # radar:
    #   can:
    #     log: rav4.log.gz                 # a CAN log, or `bag:` (+ `topic:`) of can_msgs/Frame
    #     dbc: [toyota_adas_radar.dbc]
    #     channel: can1                    # optional: keep only this channel
    #     messages: TRACK_A_*              # DBC message names, shell pattern
    #     distance: {signal: LONG_DIST, unit: m}
    #     lateral: {signal: LAT_DIST, unit: m, sign: -1}     # engine: positive left
    #     range_rate: {signal: REL_SPEED, unit: m/s}        # optional; positive receding
    #     valid: {signal: VALID}                             # optional; kept when non-zero
    #     track_id: {signal: ID}          # optional; default: the message's place in the family
    can:                                                  # optional section
      log: vehicle.blf                                    # or `bag:` (+ `topic:`), as above
      dbc: [vehicle.dbc]
      channel: can0                                       # optional: keep only this channel
      speed: {message: SPEED, signal: SPEED, unit: km/h, sign: 1}         # m/s, km/h, mph
      yaw_rate: {message: KINEMATICS, signal: YAW_RATE, unit: deg/s, sign: 1}  # rad/s, deg/s
      yaw_rate_bias: standstill      # optional: subtract the mean yaw rate while standing still
    assumptions: {speed_mps: 27.0, yaw_rate_radps: 0.0}   # optional: constants used where
                                                          # nothing was recorded
    calibration: calibration.yaml
    groundtruth: groundtruth.json                         # optional
    time_offsets_ns: {camera: 0, radar: 0, can: 0}        # optional; added to each stream's stamps
    max_radar_skew_ms: 25        # optional; default half the radar's median scan period

Paths are relative to the recording folder and stay inside it. `sign` makes the value the
engine's convention: speed positive forward, yaw rate positive turning left, lateral positive
left, range rate positive receding.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from core.io.canlog import (
    SPEED_UNITS_TO_MPS,
    YAW_RATE_BIAS_MODES,
    YAW_RATE_UNITS_TO_RADPS,
    SignalMapping,
)
from core.io.errors import RecordingError
from core.io.yamlfile import Fields, load_yaml_mapping

MANIFEST_NAME = "recording.yaml"
MANIFEST_FORMAT_VERSION = 1


DISTANCE_UNITS_TO_M = {"m": 1.0, "cm": 0.01, "ft": 0.3048}
RANGE_RATE_UNITS_TO_MPS = {"m/s": 1.0, "km/h": 1.0 / 3.6}


@dataclass(frozen=True)
class BagStream:
    """A stream in a ROS bag: the bag (relative path) and the topic (None: find by type).

    mono16_bits: significant bits of mono16 camera images, scaled to 8 bits by 2**bits - 1.
    """

    bag: str
    topic: str | None = None
    mono16_bits: int = 16


@dataclass(frozen=True)
class CanBus:
    """Where CAN frames come from: a log file (`log`), or a can_msgs/Frame topic of a bag.

    Exactly one of `log` and `bag` is set; `topic` None finds the bag's CAN topic by type.
    dbc: the DBC files (relative paths) that decode it; channel: keep only frames of this
    channel (None keeps all).
    """

    dbc: tuple[str, ...]
    log: str | None = None
    bag: str | None = None
    topic: str | None = None
    channel: str | None = None

    def __post_init__(self) -> None:
        if (self.log is None) == (self.bag is None):
            raise ValueError(f"CanBus: expected exactly one of log and bag, got {self}")

    @property
    def file(self) -> str:
        """The log or the bag, whichever the frames come from (relative path)."""
        return self.log if self.log is not None else str(self.bag)


@dataclass(frozen=True)
class CanSource:
    """Speed and yaw rate from CAN; yaw_rate_bias 'standstill' subtracts the still-car mean."""

    bus: CanBus
    speed: SignalMapping
    yaw_rate: SignalMapping
    yaw_rate_bias: str = "none"


@dataclass(frozen=True)
class RadarField:
    """One signal of a radar track message: name, unit, factor to SI, sign to the engine's."""

    signal: str
    unit: str = ""
    to_si: float = 1.0
    sign: int = 1


@dataclass(frozen=True)
class RadarCanSource:
    """Radar tracks sent over CAN: one DBC message per track slot, `messages` a shell pattern.

    Track id: the `track_id` signal when given, else the message's place in the family
    (names sorted naturally: TRACK_A_2 before TRACK_A_10).
    """

    bus: CanBus
    messages: str
    distance: RadarField
    lateral: RadarField
    range_rate: RadarField | None = None
    valid: RadarField | None = None
    track_id: RadarField | None = None


@dataclass(frozen=True)
class Assumptions:
    """Constants used where the recording has no measurement (imported videos): m/s, rad/s."""

    speed_mps: float | None = None
    yaw_rate_radps: float | None = None

    def describe(self) -> tuple[str, ...]:
        """One plain sentence per assumption, for people reading results."""
        out = []
        if self.speed_mps is not None:
            out.append(f"speed {self.speed_mps:g} m/s is assumed, not measured")
        if self.yaw_rate_radps is not None:
            out.append(f"yaw rate {self.yaw_rate_radps:g} rad/s is assumed, not measured")
        return tuple(out)


@dataclass(frozen=True)
class TimeOffsets:
    """Nanoseconds added to each stream's time stamps to put them on the camera's clock."""

    camera_ns: int = 0
    radar_ns: int = 0
    can_ns: int = 0


@dataclass(frozen=True)
class Manifest:
    """A parsed `recording.yaml`; `folder` is the recording folder all paths are relative to."""

    folder: Path
    name: str
    camera: BagStream
    calibration: str
    description: str = ""
    radar: BagStream | RadarCanSource | None = None
    can: CanSource | None = None
    groundtruth: str | None = None
    time_offsets: TimeOffsets = TimeOffsets()
    assumptions: Assumptions = Assumptions()
    max_radar_skew_ms: float | None = None
    generator: Mapping[str, Any] = field(default_factory=dict)

    def resolve(self, relative: str) -> Path:
        """The path of a part, checked to exist inside the folder; RecordingError otherwise."""
        where = self.folder / MANIFEST_NAME
        path = self.folder / relative
        root = self.folder.resolve()
        if Path(relative).is_absolute() or not path.resolve().is_relative_to(root):
            raise RecordingError(
                f"{where}: names {relative!r}, which is outside the recording folder {root}; "
                "expected a path inside it"
            )
        if not path.exists():
            raise RecordingError(f"{where}: names {relative!r}, but {path} does not exist")
        return path


def _sign(f: Fields) -> int:
    sign = f.int_("sign") if "sign" in f.raw else 1
    if sign not in (1, -1):
        raise f.fail("sign", "1 or -1", sign)
    return sign


def _unit(f: Fields, units: Mapping[str, float]) -> tuple[str, float]:
    unit = f.str_("unit")
    if unit not in units:
        raise f.fail("unit", f"one of {', '.join(units)}", unit)
    return unit, units[unit]


def _signal(f: Fields, name: str, units: dict[str, float]) -> SignalMapping:
    s = f.sub(name)
    s.check_keys({"message", "signal", "unit"}, {"sign"})
    unit, to_si = _unit(s, units)
    return SignalMapping(s.str_("message"), s.str_("signal"), unit, to_si, _sign(s))


def _radar_field(f: Fields, name: str, units: Mapping[str, float] | None) -> RadarField:
    s = f.sub(name)
    if units is None:
        s.check_keys({"signal"})
        return RadarField(s.str_("signal"))
    s.check_keys({"signal", "unit"}, {"sign"})
    unit, to_si = _unit(s, units)
    return RadarField(s.str_("signal"), unit, to_si, _sign(s))


def _stream(f: Fields, name: str) -> BagStream:
    s = f.sub(name)
    s.check_keys({"bag"}, {"topic", "mono16_bits"})
    bits = s.int_("mono16_bits") if s.has("mono16_bits") else 16
    if not 1 <= bits <= 16:
        raise s.fail("mono16_bits", "an integer from 1 to 16", bits)
    return BagStream(s.str_("bag"), s.str_("topic") if s.has("topic") else None, bits)


BUS_KEYS = {"log", "bag", "topic", "dbc", "channel"}


def _bus(c: Fields) -> CanBus:
    """The CAN source fields of section `c` (its other keys are checked by the caller)."""
    dbc = c.raw.get("dbc")
    if isinstance(dbc, str):
        dbc = [dbc]
    if not isinstance(dbc, list) or not dbc or not all(isinstance(d, str) and d for d in dbc):
        raise c.fail("dbc", "a DBC file name or a list of them", c.raw.get("dbc"))
    if c.has("log") == c.has("bag"):
        raise RecordingError(
            f"{c.path}: {c.where}: expected exactly one of `log` (a CAN log file) and `bag` "
            f"(a bag with can_msgs/Frame), got {'both' if c.has('log') else 'neither'}"
        )
    if c.has("topic") and not c.has("bag"):
        raise RecordingError(f"{c.path}: {c.key('topic')}: only allowed with `bag`")
    return CanBus(
        dbc=tuple(dbc),
        log=c.str_("log") if c.has("log") else None,
        bag=c.str_("bag") if c.has("bag") else None,
        topic=c.str_("topic") if c.has("topic") else None,
        channel=str(c.raw["channel"]) if c.has("channel") else None,
    )


def _can(f: Fields) -> CanSource:
    c = f.sub("can")
    c.check_keys({"dbc", "speed", "yaw_rate"}, BUS_KEYS | {"yaw_rate_bias"})
    bias = c.raw.get("yaw_rate_bias") or "none"
    if bias not in YAW_RATE_BIAS_MODES:
        raise c.fail("yaw_rate_bias", " or ".join(YAW_RATE_BIAS_MODES), bias)
    return CanSource(
        bus=_bus(c),
        speed=_signal(c, "speed", SPEED_UNITS_TO_MPS),
        yaw_rate=_signal(c, "yaw_rate", YAW_RATE_UNITS_TO_RADPS),
        yaw_rate_bias=bias,
    )


def _radar(f: Fields) -> BagStream | RadarCanSource:
    r = f.sub("radar")
    if "can" not in r.raw:
        return _stream(f, "radar")
    r.check_keys({"can"})
    c = r.sub("can")
    c.check_keys(
        {"dbc", "messages", "distance", "lateral"},
        BUS_KEYS | {"range_rate", "valid", "track_id"},
    )
    return RadarCanSource(
        bus=_bus(c),
        messages=c.str_("messages"),
        distance=_radar_field(c, "distance", DISTANCE_UNITS_TO_M),
        lateral=_radar_field(c, "lateral", DISTANCE_UNITS_TO_M),
        range_rate=(
            _radar_field(c, "range_rate", RANGE_RATE_UNITS_TO_MPS) if c.has("range_rate") else None
        ),
        valid=_radar_field(c, "valid", None) if c.has("valid") else None,
        track_id=_radar_field(c, "track_id", None) if c.has("track_id") else None,
    )


def parse_manifest(raw: Mapping[str, Any], folder: Path) -> Manifest:
    """A Manifest from the mapping of `folder`/recording.yaml."""
    f = Fields(folder / MANIFEST_NAME, raw)
    f.check_keys(
        {"format_version", "name", "camera", "calibration"},
        {
            "description",
            "generator",
            "radar",
            "can",
            "groundtruth",
            "time_offsets_ns",
            "assumptions",
            "max_radar_skew_ms",
        },
    )
    if f.raw["format_version"] != MANIFEST_FORMAT_VERSION:
        raise f.fail("format_version", str(MANIFEST_FORMAT_VERSION), f.raw["format_version"])
    offsets = TimeOffsets()
    if f.has("time_offsets_ns"):
        o = f.sub("time_offsets_ns")
        o.check_keys(set(), {"camera", "radar", "can"})
        offsets = TimeOffsets(*(o.int_(k) if k in o.raw else 0 for k in ("camera", "radar", "can")))
    assumptions = Assumptions()
    if f.has("assumptions"):
        a = f.sub("assumptions")
        a.check_keys(set(), {"speed_mps", "yaw_rate_radps"})
        assumptions = Assumptions(
            *(a.float_(k) if a.has(k) else None for k in ("speed_mps", "yaw_rate_radps"))
        )
    skew = None
    if f.has("max_radar_skew_ms"):
        skew = f.float_("max_radar_skew_ms")
        if skew <= 0:
            raise f.fail("max_radar_skew_ms", "a positive number of milliseconds", skew)
    generator = f.raw.get("generator") or {}
    if not isinstance(generator, Mapping):
        raise f.fail("generator", "a mapping", generator)
    description = f.raw.get("description") or ""
    if not isinstance(description, str):
        raise f.fail("description", "a string", description)
    name = f.raw["name"]
    if not isinstance(name, (str, int, float)) or isinstance(name, bool) or name == "":
        raise f.fail("name", "a non-empty string", name)
    return Manifest(
        folder=folder,
        name=str(name),
        description=description,
        generator=dict(generator),
        camera=_stream(f, "camera"),
        radar=_radar(f) if f.has("radar") else None,
        can=_can(f) if f.has("can") else None,
        calibration=f.str_("calibration"),
        groundtruth=f.str_("groundtruth") if f.has("groundtruth") else None,
        time_offsets=offsets,
        assumptions=assumptions,
        max_radar_skew_ms=skew,
    )


def load_manifest(folder: Path | str) -> Manifest:
    """Read `folder`/recording.yaml (or the manifest file itself); RecordingError on bad input."""
    p = Path(folder)
    if p.is_file():
        p = p.parent
    if not p.is_dir():
        raise RecordingError(f"{p}: expected a recording folder, but it does not exist")
    return parse_manifest(load_yaml_mapping(p / MANIFEST_NAME, "recording manifest"), p)


def manifest_to_dict(m: Manifest) -> dict[str, Any]:
    """The YAML-ready mapping of `m` (layout in the module docstring)."""

    def stream(s: BagStream) -> dict[str, Any]:
        out: dict[str, Any] = {"bag": s.bag}
        if s.topic:
            out["topic"] = s.topic
        if s.mono16_bits != 16:
            out["mono16_bits"] = s.mono16_bits
        return out

    def bus(b: CanBus) -> dict[str, Any]:
        out: dict[str, Any] = {"log": b.log} if b.log is not None else {"bag": b.bag}
        if b.topic is not None:
            out["topic"] = b.topic
        out["dbc"] = list(b.dbc)
        if b.channel is not None:
            out["channel"] = b.channel
        return out

    def signal(s: SignalMapping) -> dict[str, Any]:
        return {"message": s.message, "signal": s.signal, "unit": s.unit, "sign": s.sign}

    def radar_field(r: RadarField) -> dict[str, Any]:
        return {"signal": r.signal, **({"unit": r.unit, "sign": r.sign} if r.unit else {})}

    out: dict[str, Any] = {
        "format_version": MANIFEST_FORMAT_VERSION,
        "name": m.name,
        "description": m.description,
    }
    if m.generator:
        out["generator"] = dict(m.generator)
    out["camera"] = stream(m.camera)
    if isinstance(m.radar, BagStream):
        out["radar"] = stream(m.radar)
    elif isinstance(m.radar, RadarCanSource):
        r = m.radar
        fields = {"distance": r.distance, "lateral": r.lateral, "range_rate": r.range_rate}
        fields |= {"valid": r.valid, "track_id": r.track_id}
        out["radar"] = {
            "can": {
                **bus(r.bus),
                "messages": r.messages,
                **{k: radar_field(v) for k, v in fields.items() if v is not None},
            }
        }
    if m.can is not None:
        out["can"] = {
            **bus(m.can.bus),
            "speed": signal(m.can.speed),
            "yaw_rate": signal(m.can.yaw_rate),
            **({"yaw_rate_bias": m.can.yaw_rate_bias} if m.can.yaw_rate_bias != "none" else {}),
        }
    a = m.assumptions
    if a.speed_mps is not None or a.yaw_rate_radps is not None:
        out["assumptions"] = {
            k: v
            for k, v in (("speed_mps", a.speed_mps), ("yaw_rate_radps", a.yaw_rate_radps))
            if v is not None
        }
    out["calibration"] = m.calibration
    if m.groundtruth is not None:
        out["groundtruth"] = m.groundtruth
    t = m.time_offsets
    out["time_offsets_ns"] = {"camera": t.camera_ns, "radar": t.radar_ns, "can": t.can_ns}
    if m.max_radar_skew_ms is not None:
        out["max_radar_skew_ms"] = m.max_radar_skew_ms
    return out


def save_manifest(m: Manifest, path: Path | str) -> None:
    Path(path).write_text(yaml.safe_dump(manifest_to_dict(m), sort_keys=False), encoding="utf-8")
