"""`recording.yaml`: the manifest that names the parts of a recording.

Layout (format_version 1):

    format_version: 1
    name: highway
    description: free text
    generator: {scenario: highway, seed: 1}           # optional, free-form
    camera: {bag: bag, topic: /camera/image/compressed}   # topic optional: found by type
    radar: {bag: bag, topic: /radar/scan}                 # optional section; topic optional
    can:                                                  # optional section
      log: vehicle.blf
      dbc: [vehicle.dbc]
      channel: can0                                       # optional: keep only this channel
      speed: {message: SPEED, signal: SPEED, unit: km/h, sign: 1}         # m/s, km/h, mph
      yaw_rate: {message: KINEMATICS, signal: YAW_RATE, unit: deg/s, sign: 1}  # rad/s, deg/s
    calibration: calibration.yaml
    groundtruth: groundtruth.json                         # optional
    time_offsets_ns: {camera: 0, radar: 0, can: 0}        # optional; added to each stream's stamps

Paths are relative to the recording folder. `sign` makes the value the engine's convention:
speed positive forward, yaw rate positive turning left.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from core.io.canlog import SPEED_UNITS_TO_MPS, YAW_RATE_UNITS_TO_RADPS, SignalMapping
from core.io.errors import RecordingError
from core.io.yamlfile import Fields, load_yaml_mapping

MANIFEST_NAME = "recording.yaml"
MANIFEST_FORMAT_VERSION = 1


@dataclass(frozen=True)
class BagStream:
    """A stream in a ROS bag: the bag (relative path) and the topic (None: find by type)."""

    bag: str
    topic: str | None = None


@dataclass(frozen=True)
class CanSource:
    log: str
    dbc: tuple[str, ...]
    speed: SignalMapping
    yaw_rate: SignalMapping
    channel: str | None = None


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
    radar: BagStream | None = None
    can: CanSource | None = None
    groundtruth: str | None = None
    time_offsets: TimeOffsets = TimeOffsets()
    generator: Mapping[str, Any] = field(default_factory=dict)

    def resolve(self, relative: str) -> Path:
        """The path of a part, checked to exist; RecordingError naming the manifest otherwise."""
        path = self.folder / relative
        if not path.exists():
            raise RecordingError(
                f"{self.folder / MANIFEST_NAME}: names {relative!r}, but {path} does not exist"
            )
        return path


def _signal(f: Fields, name: str, units: dict[str, float]) -> SignalMapping:
    s = f.sub(name)
    s.check_keys({"message", "signal", "unit"}, {"sign"})
    unit = s.str_("unit")
    if unit not in units:
        raise s.fail("unit", f"one of {', '.join(units)}", unit)
    sign = s.int_("sign") if "sign" in s.raw else 1
    if sign not in (1, -1):
        raise s.fail("sign", "1 or -1", sign)
    return SignalMapping(s.str_("message"), s.str_("signal"), unit, units[unit], sign)


def _stream(f: Fields, name: str) -> BagStream:
    s = f.sub(name)
    s.check_keys({"bag"}, {"topic"})
    return BagStream(s.str_("bag"), s.str_("topic") if s.has("topic") else None)


def parse_manifest(raw: Mapping[str, Any], folder: Path) -> Manifest:
    """A Manifest from the mapping of `folder`/recording.yaml."""
    f = Fields(folder / MANIFEST_NAME, raw)
    f.check_keys(
        {"format_version", "name", "camera", "calibration"},
        {"description", "generator", "radar", "can", "groundtruth", "time_offsets_ns"},
    )
    if f.raw["format_version"] != MANIFEST_FORMAT_VERSION:
        raise f.fail("format_version", str(MANIFEST_FORMAT_VERSION), f.raw["format_version"])
    can: CanSource | None = None
    if f.has("can"):
        c = f.sub("can")
        c.check_keys({"log", "dbc", "speed", "yaw_rate"}, {"channel"})
        dbc = c.raw["dbc"]
        if isinstance(dbc, str):
            dbc = [dbc]
        if not isinstance(dbc, list) or not dbc or not all(isinstance(d, str) for d in dbc):
            raise c.fail("dbc", "a DBC file name or a list of them", c.raw["dbc"])
        can = CanSource(
            log=c.str_("log"),
            dbc=tuple(dbc),
            speed=_signal(c, "speed", SPEED_UNITS_TO_MPS),
            yaw_rate=_signal(c, "yaw_rate", YAW_RATE_UNITS_TO_RADPS),
            channel=str(c.raw["channel"]) if c.has("channel") else None,
        )
    offsets = TimeOffsets()
    if f.has("time_offsets_ns"):
        o = f.sub("time_offsets_ns")
        o.check_keys(set(), {"camera", "radar", "can"})
        offsets = TimeOffsets(*(o.int_(k) if k in o.raw else 0 for k in ("camera", "radar", "can")))
    generator = f.raw.get("generator") or {}
    if not isinstance(generator, Mapping):
        raise f.fail("generator", "a mapping", generator)
    description = f.raw.get("description") or ""
    if not isinstance(description, str):
        raise f.fail("description", "a string", description)
    return Manifest(
        folder=folder,
        name=str(f.raw["name"]),
        description=description,
        generator=dict(generator),
        camera=_stream(f, "camera"),
        radar=_stream(f, "radar") if f.has("radar") else None,
        can=can,
        calibration=f.str_("calibration"),
        groundtruth=f.str_("groundtruth") if f.has("groundtruth") else None,
        time_offsets=offsets,
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
        return {"bag": s.bag, **({"topic": s.topic} if s.topic else {})}

    def signal(s: SignalMapping) -> dict[str, Any]:
        return {"message": s.message, "signal": s.signal, "unit": s.unit, "sign": s.sign}

    out: dict[str, Any] = {
        "format_version": MANIFEST_FORMAT_VERSION,
        "name": m.name,
        "description": m.description,
    }
    if m.generator:
        out["generator"] = dict(m.generator)
    out["camera"] = stream(m.camera)
    if m.radar is not None:
        out["radar"] = stream(m.radar)
    if m.can is not None:
        out["can"] = {
            "log": m.can.log,
            "dbc": list(m.can.dbc),
            **({"channel": m.can.channel} if m.can.channel else {}),
            "speed": signal(m.can.speed),
            "yaw_rate": signal(m.can.yaw_rate),
        }
    out["calibration"] = m.calibration
    if m.groundtruth is not None:
        out["groundtruth"] = m.groundtruth
    t = m.time_offsets
    out["time_offsets_ns"] = {"camera": t.camera_ns, "radar": t.radar_ns, "can": t.can_ns}
    return out


def save_manifest(m: Manifest, path: Path | str) -> None:
    Path(path).write_text(yaml.safe_dump(manifest_to_dict(m), sort_keys=False), encoding="utf-8")
