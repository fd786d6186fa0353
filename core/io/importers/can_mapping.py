"""An import's CAN input: the mapping file checked against the DBC files and the frames, and
the camera's stamps against the CAN log's span.

CAN mapping file (`--mapping`): the `can:` and/or `radar:` sections of recording.yaml without
`log`, `bag`, `topic` and `dbc`, which come from the command line (`--can LOG` or the bag's
CAN topic, `--dbc`). Each section keeps its own `channel`, and gets the DBC files that define
its messages (DBCs of different buses may reuse frame ids). MAPPING_EXAMPLE below is the one
of the Toyota RAV4 of comma2k19.

Notes:
    A camera frame a little outside the CAN log's span (up to CAN_SPAN_TOLERANCE_S) is
    accepted: comma2k19's first camera frame is 38 ms before the log's first CAN frame.
"""

from __future__ import annotations

import difflib
import fnmatch
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from cantools.database.can import Database, Message

from core.io.can_radar import natural_key
from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.canlog import (
    NS_PER_S,
    SignalMapping,
    check_signals,
    find_signal,
    id_text,
    load_dbc,
)
from core.io.errors import RecordingError
from core.io.manifest import MANIFEST_NAME, CanSource, RadarCanSource, parse_manifest
from core.io.writer import BAG_DIR, CALIBRATION_NAME
from core.io.yamlfile import Fields, load_yaml_mapping

MAPPING_EXAMPLE = """\
# Toyota RAV4 (comma2k19): speed and yaw rate on can0, the forward radar's tracks on can1.
can:                                   # optional section: speed and yaw rate
  channel: can0                        # optional: keep only frames of this channel
  speed: {message: SPEED, signal: SPEED, unit: km/h}              # units: m/s, km/h, mph
  yaw_rate: {message: KINEMATICS, signal: YAW_RATE, unit: deg/s}  # units: rad/s, deg/s
  # yaw_rate_bias: standstill          # optional: subtract the yaw rate of a standing car
radar:                                 # optional section: radar tracks over CAN
  can:
    channel: can1
    messages: TRACK_A_*                # one DBC message per track slot; a shell pattern
    distance: {signal: LONG_DIST, unit: m}
    lateral: {signal: LAT_DIST, unit: m, sign: -1}   # the bus says positive right
    range_rate: {signal: REL_SPEED, unit: m/s}       # optional
    valid: {signal: VALID}                           # optional: kept when non-zero
    # track_id: {signal: ID}           # optional; default: the message's place in the family
# sign: -1 flips a signal into the engine's convention: speed forward, yaw rate left,
# lateral left, range rate receding positive.
"""

CAN_SPAN_TOLERANCE_S = 1.0  # see the module Notes
# Names the importer writes; copied CAN files must not take them.
RESERVED_NAMES = frozenset({MANIFEST_NAME, CALIBRATION_NAME, BAG_DIR})
# Keys of a mapping section that come from the command line, not the mapping file.
SOURCE_KEYS = ("log", "bag", "topic", "dbc")


@dataclass(frozen=True)
class CanSpec:
    """CAN input: DBC files, the mapping file, and where the frames are.

    log: a CAN log file (copied into the recording); None in a bag import takes the bag's
    can_msgs/Frame topic `bag_topic` (None: found by type).
    """

    dbc: tuple[Path, ...]
    mapping: Path
    log: Path | None = None
    bag_topic: str | None = None

    def __post_init__(self) -> None:
        if not self.dbc:
            raise ValueError("--dbc: expected at least one DBC file with the CAN input")
        if self.log is not None and self.bag_topic is not None:
            raise ValueError(
                f"--can {self.log}, --can-topic {self.bag_topic}: expected one CAN source"
            )


@dataclass(frozen=True)
class PreparedCan:
    """A checked mapping: the manifest sections and the files to copy (name -> source)."""

    can: CanSource | None
    radar: RadarCanSource | None
    files: Mapping[str, Path]
    span_ns: tuple[int, int] | None  # first and last CAN frame; None when not scanned
    radar_times_ns: npt.NDArray[np.int64]  # frames of the first radar message, ascending
    description: str
    notes: tuple[str, ...]


def _mapping_sections(path: Path) -> tuple[dict[str, Any] | None, dict[str, Any] | None]:
    """The `can:` section and the `radar: can:` section of a mapping file, checked for keys."""
    f = Fields(path, load_yaml_mapping(path, "CAN mapping"))
    f.check_keys(set(), {"can", "radar"})
    if not f.has("can") and not f.has("radar"):
        raise RecordingError(
            f"{path}: expected a `can:` section (speed, yaw rate), a `radar:` section "
            "(radar tracks over CAN) or both; see `fusionscope import video --help`"
        )
    can_raw = None
    if f.has("can"):
        can_raw = dict(f.sub("can").raw)
    radar_raw = None
    if f.has("radar"):
        r = f.sub("radar")
        if set(r.raw) != {"can"}:
            raise RecordingError(
                f"{path}: radar: expected one key `can:` holding the radar's CAN fields "
                f"(messages, distance, lateral, ...) as in recording.yaml, got "
                f"{', '.join(sorted(map(str, r.raw))) or 'nothing'}"
            )
        radar_raw = dict(r.sub("can").raw)
    for where, raw in (("can", can_raw), ("radar.can", radar_raw)):
        for key in SOURCE_KEYS:
            if raw is not None and key in raw:
                raise RecordingError(
                    f"{path}: {where}.{key}: not allowed in a mapping file; the CAN source "
                    "and the DBC files come from the command line (--can or --can-topic, --dbc)"
                )
    return can_raw, radar_raw


def _copy_names(spec: CanSpec, reserved: frozenset[str]) -> dict[str, Path]:
    """Recording-relative names of the CAN files copied in: the files' own names."""
    names: dict[str, Path] = {}
    for path in ([spec.log] if spec.log is not None else []) + list(spec.dbc):
        if not path.is_file():
            flag = "--can" if path == spec.log else "--dbc"
            raise ValueError(f"{flag} {path}: file not found")
        if path.name in reserved or path.name in names:
            raise ValueError(
                f"{path}: its name {path.name!r} is taken in the recording folder "
                f"(by {names.get(path.name, 'the importer')}); rename the file"
            )
        names[path.name] = path
    return names


@dataclass(frozen=True)
class _FrameScan:
    first_ns: int
    last_ns: int
    counts: Mapping[tuple[int, bool, str | None], int]  # (id, extended, channel) -> frames
    times_ns: Mapping[tuple[int, bool], npt.NDArray[np.int64]]  # of the ids asked for


def _scan(frames: Iterable[CanFrame], where: str, keep_times: set[tuple[int, bool]]) -> _FrameScan:
    """Span, frame counts per id and channel, and the times of the `keep_times` ids."""
    counts: dict[tuple[int, bool, str | None], int] = {}
    times: dict[tuple[int, bool], list[int]] = {k: [] for k in keep_times}
    first = last = None
    for frame in frames:
        first = frame.t_ns if first is None else min(first, frame.t_ns)
        last = frame.t_ns if last is None else max(last, frame.t_ns)
        key = (frame.arbitration_id, frame.is_extended, frame.channel)
        counts[key] = counts.get(key, 0) + 1
        if key[:2] in times:
            times[key[:2]].append(frame.t_ns)
    if first is None or last is None:
        raise RecordingError(f"{where}: expected CAN data frames, there are none")
    return _FrameScan(
        first,
        last,
        counts,
        {k: np.sort(np.asarray(v, dtype=np.int64)) for k, v in times.items()},
    )


def _parse_mapping(
    spec: CanSpec, source: Mapping[str, str]
) -> tuple[CanSource | None, RadarCanSource | None]:
    """The mapping's sections, with `source` (log, or bag and topic) and all DBCs filled in,
    parsed as recording.yaml parses them; errors name the mapping file."""
    can_raw, radar_raw = _mapping_sections(spec.mapping)
    dbc_names = [p.name for p in spec.dbc]
    raw: dict[str, Any] = {
        "format_version": 1,
        "name": "mapping",
        "camera": {"bag": BAG_DIR},
        "calibration": CALIBRATION_NAME,
    }
    if can_raw is not None:
        raw["can"] = {**source, "dbc": dbc_names, **can_raw}
    if radar_raw is not None:
        raw["radar"] = {"can": {**source, "dbc": dbc_names, **radar_raw}}
    manifest_path = f"{spec.mapping.parent / MANIFEST_NAME}: "
    try:
        parsed = parse_manifest(raw, spec.mapping.parent)
    except RecordingError as err:
        text = str(err)
        if text.startswith(manifest_path):
            text = f"{spec.mapping}: " + text[len(manifest_path) :]
        raise RecordingError(text) from err
    radar = parsed.radar if isinstance(parsed.radar, RadarCanSource) else None
    return parsed.can, radar


def _find_message(dbs: Mapping[str, Database], spec: CanSpec, mapping: SignalMapping) -> Message:
    """The message carrying `mapping` in the first DBC that defines it; RecordingError else.

    Each DBC is searched on its own: DBCs of different buses may reuse frame ids.
    """
    paths = {p.name: p for p in spec.dbc}
    for name, db in dbs.items():
        if any(m.name == mapping.message for m in db.messages):
            return find_signal(db, mapping, str(paths[name]))
    names = sorted({m.name for db in dbs.values() for m in db.messages})
    close = difflib.get_close_matches(mapping.message, names, n=5, cutoff=0.4)
    raise RecordingError(
        f"{spec.mapping}: message {mapping.message!r} is in none of the DBC files "
        f"{', '.join(str(p) for p in spec.dbc)}; close names: {', '.join(close) or 'none'}"
    )


# (message name, frame id, extended) of the messages a section reads.
MessageIds = list[tuple[str, int, bool]]


def _assign_dbcs(
    spec: CanSpec, can_src: CanSource | None, radar_src: RadarCanSource | None
) -> tuple[CanSource | None, RadarCanSource | None, dict[str, MessageIds], list[str]]:
    """Each section with only the DBCs that define its messages, the messages, notes.

    RecordingError naming the mapping when a message or signal is in none of the DBCs.
    """
    dbs = {p.name: load_dbc([p]) for p in spec.dbc}
    listing = ", ".join(str(p) for p in spec.dbc)

    def defining(names: set[str]) -> tuple[str, ...]:
        return tuple(n for n, db in dbs.items() if names & {m.name for m in db.messages})

    ids: dict[str, MessageIds] = {}
    if can_src is not None:
        messages = [_find_message(dbs, spec, m) for m in (can_src.speed, can_src.yaw_rate)]
        bus = replace(can_src.bus, dbc=defining({m.name for m in messages}))
        can_src = replace(can_src, bus=bus)
        ids["can"] = [(m.name, m.frame_id, m.is_extended_frame) for m in messages]
    if radar_src is not None:
        pattern = radar_src.messages
        family = [
            m for db in dbs.values() for m in db.messages if fnmatch.fnmatchcase(m.name, pattern)
        ]
        if not family:
            raise RecordingError(
                f"{spec.mapping}: radar.can.messages: the pattern {pattern!r} matches no "
                f"message of {listing}"
            )
        family.sort(key=lambda m: natural_key(m.name))
        r = radar_src
        fields = (r.distance, r.lateral, r.range_rate, r.valid, r.track_id)
        for message in family:
            check_signals(message, [f.signal for f in fields if f is not None], str(spec.mapping))
        bus = replace(radar_src.bus, dbc=defining({m.name for m in family}))
        radar_src = replace(radar_src, bus=bus)
        ids["radar"] = [(m.name, m.frame_id, m.is_extended_frame) for m in family]
    used = {d for src in (can_src, radar_src) if src is not None for d in src.bus.dbc}
    notes = [
        f"{name}: defines none of the mapped messages (copied all the same)"
        for name in dbs
        if name not in used
    ]
    return can_src, radar_src, ids, notes


def _check_traffic(
    scan: _FrameScan,
    sections: Mapping[str, CanSource | RadarCanSource],
    ids: Mapping[str, MessageIds],
    source_name: str,
    mapping: Path,
) -> list[str]:
    """Notes on mapped messages missing from the frames; RecordingError when speed or yaw
    rate is missing, or every radar message (a radar may leave track slots unused)."""
    notes = []
    for section, src in sections.items():
        channel = src.bus.channel
        missing = []
        for name, frame_id, ext in ids[section]:
            on = {ch for (i, e, ch) in scan.counts if (i, e) == (frame_id, ext)}
            if (channel is None and not on) or (channel is not None and channel not in on):
                elsewhere = ", ".join(sorted(str(ch) for ch in on)) or "none"
                missing.append(f"{name} ({id_text(frame_id, ext)}; channels with it: {elsewhere})")
        if missing and (section == "can" or len(missing) == len(ids[section])):
            where = f"on channel {channel}, " if channel is not None else ""
            raise RecordingError(
                f"{source_name}: {where}no frames of {', '.join(missing)}; the mapping's "
                f"{section} section names them ({mapping})"
            )
        if missing:
            notes.append(f"{source_name}: no frames of {', '.join(missing)}")
    return notes


def prepare_can(
    spec: CanSpec,
    bag_name: str | None = None,
    bag_topic: str | None = None,
    bag_frames: Callable[[], Iterable[CanFrame]] | None = None,
) -> PreparedCan:
    """Check the mapping against the DBCs and the frames; ValueError/RecordingError naming them.

    bag_name, bag_topic, bag_frames: the copied bag, its CAN topic and that topic's frames
    when the frames come from a bag, not from `spec.log`.
    """
    reserved = RESERVED_NAMES if bag_name is None else RESERVED_NAMES | {bag_name}
    files = _copy_names(spec, reserved)
    source: dict[str, str] = {}
    if spec.log is not None:
        source["log"] = spec.log.name
    else:
        source["bag"] = str(bag_name)
        if bag_topic:
            source["topic"] = bag_topic
    can_src, radar_src = _parse_mapping(spec, source)
    can_src, radar_src, ids, notes = _assign_dbcs(spec, can_src, radar_src)

    # The frames hold the mapped messages on the mapped channels.
    span = None
    radar_times = np.zeros(0, dtype=np.int64)
    source_name = str(spec.log) if spec.log is not None else f"{bag_name}: {bag_topic}"
    frames: Iterable[CanFrame] | None = None
    if spec.log is not None:
        frames = iter_log_frames(spec.log, warn=notes.append)
    elif bag_frames is not None:
        frames = bag_frames()
    if frames is not None:
        first_radar = ids["radar"][0][1:] if "radar" in ids else None
        scan = _scan(frames, source_name, {first_radar} if first_radar else set())
        span = (scan.first_ns, scan.last_ns)
        sections = {k: v for k, v in (("can", can_src), ("radar", radar_src)) if v is not None}
        notes += _check_traffic(scan, sections, ids, source_name, spec.mapping)
        if first_radar is not None:
            radar_times = scan.times_ns[first_radar]
    text = ""
    if can_src is not None:
        sp, yr = can_src.speed, can_src.yaw_rate
        text += (
            f" Speed from CAN {sp.message}.{sp.signal} ({sp.unit}), yaw rate from "
            f"{yr.message}.{yr.signal} ({yr.unit})."
        )
    if radar_src is not None:
        text += f" Radar tracks over CAN: {radar_src.messages}."
    return PreparedCan(can_src, radar_src, files, span, radar_times, text.strip(), tuple(notes))


def _span_text(span_ns: tuple[int, int]) -> str:
    first, last = (t / NS_PER_S for t in span_ns)
    return f"{first:.3f} s" if span_ns[0] == span_ns[1] else f"{first:.3f}-{last:.3f} s"


def check_can_times(
    prepared: PreparedCan, times_ns: Sequence[int], what: str, skew_ms: float | None
) -> list[str]:
    """Notes on how the camera stamps meet the CAN log; RecordingError when they miss it."""
    notes: list[str] = []
    if prepared.span_ns is None or not times_ns:
        return notes
    first, last = prepared.span_ns
    tol = round(CAN_SPAN_TOLERANCE_S * NS_PER_S)
    t0, t1 = int(times_ns[0]), int(times_ns[-1])
    if t1 < first - tol or t0 > last + tol:
        raise RecordingError(
            f"{what}: {_span_text((t0, t1))} on the CAN clock is outside the CAN log's span "
            f"{_span_text(prepared.span_ns)}; expected a time within it"
        )
    outside = sum(1 for t in times_ns if not first <= t <= last)
    if outside:
        notes.append(
            f"{outside} of {len(times_ns)} camera frames lie outside the CAN log's span "
            f"{_span_text(prepared.span_ns)}: speed there is held from the nearest sample"
        )
    radar = prepared.radar_times_ns
    if len(radar) >= 2:
        period_ms = float(np.median(np.diff(radar))) / 1e6
        k = np.searchsorted(radar, t0)
        gap_ms = min(abs(int(radar[j]) - t0) for j in (k - 1, k) if 0 <= j < len(radar)) / 1e6
        limit = skew_ms if skew_ms is not None else period_ms / 2
        if gap_ms > limit:
            notes.append(
                f"the first camera frame is {gap_ms:.0f} ms from the nearest radar frame, more "
                f"than the {limit:.0f} ms within which a scan is paired with it; give "
                f"--max-radar-skew-ms {math.ceil(gap_ms)} or more to pair them"
            )
    return notes
