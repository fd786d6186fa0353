"""`fusionscope import`: a recording folder from a video, a still image or a ROS bag.

The result is a folder `core.io.Drive` and the inspector open (layout in core/io/manifest.py),
self-contained: the CAN log, the DBC files and the bag are copied into it. The folder is
written beside OUT_DIR under a temporary name and renamed at the end, so an error leaves
nothing behind; OUT_DIR must be new or empty.

- video: any file OpenCV reads. Frames become grey, are resized to `width_px` (height by the
  video's aspect ratio) and resampled to `fps`: for each output time the source frame nearest
  in time is taken (source frame i is at i / the container's frame rate). The stamps are the
  output times on the video's clock (0 at its first frame) plus `start_ns`, the recording-clock
  time of the video's first frame -- with CAN, its time on the CAN log's clock.
- still: one image at a given time, resized as a video frame.
- bag: a ROS 1 `.bag` file or a ROS 2 bag folder (metadata.yaml + .db3/.mcap) copied as is;
  camera, radar and CAN topics named or found by message type.

CAN mapping file (`--mapping`): the `can:` and/or `radar:` sections of recording.yaml without
`log`, `bag`, `topic` and `dbc`, which come from the command line (`--can LOG` or the bag's
CAN topic, `--dbc`). Each section keeps its own `channel`, and gets the DBC files that define
its messages (DBCs of different buses may reuse frame ids). MAPPING_EXAMPLE below is the one
of the Toyota RAV4 of comma2k19.

Where nothing records the speed, `Assumptions` (a constant speed and yaw rate) go into the
manifest; without either, speed is NaN and the engine's motion stereo cannot work.

Notes:
    A camera frame a little outside the CAN log's span (up to CAN_SPAN_TOLERANCE_S) is
    accepted: comma2k19's first camera frame is 38 ms before the log's first CAN frame.
"""

from __future__ import annotations

import difflib
import fnmatch
import math
import os
import shutil
import uuid
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
from cantools.database.can import Database, Message

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.io import radar_msgs
from core.io.bag import CAN_TYPES, RADAR_TYPES, BagReader, CameraStream
from core.io.calibration import Calibration, RadarMount, load_camera_info, save_calibration
from core.io.can_radar import natural_key
from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.canlog import (
    SignalMapping,
    check_signals,
    find_signal,
    id_text,
    load_dbc,
)
from core.io.drive import Drive
from core.io.errors import RecordingError
from core.io.manifest import (
    MANIFEST_NAME,
    Assumptions,
    BagStream,
    CanSource,
    Manifest,
    RadarCanSource,
    parse_manifest,
    save_manifest,
)
from core.io.split_bag import SplitBagWriter
from core.io.writer import (
    BAG_DIR,
    CALIBRATION_NAME,
    CAMERA_TOPIC,
    MAX_BAG_FILE_BYTES,
    png_image_message,
)
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

GreyImage = npt.NDArray[np.uint8]
Progress = Callable[[int, int], None]

DEFAULT_WIDTH_PX = 640  # paper 001: the engine works on 640-pixel-wide images
DEFAULT_FPS = 10.0  # paper 002: "sampled at 10 fps"
DEFAULT_CAMERA_HEIGHT_M = 1.2  # a car's windscreen camera
DEFAULT_CAMERA_X_M = 1.5  # behind the windscreen, ahead of the rear axle
CAN_SPAN_TOLERANCE_S = 1.0  # see the module Notes
ASPECT_TOLERANCE = 0.01  # relative: a camera_info for another resolution of the same sensor
NS_PER_S = 1_000_000_000
# Names the importer writes; copied CAN files must not take them.
RESERVED_NAMES = frozenset({MANIFEST_NAME, CALIBRATION_NAME, BAG_DIR})
# Keys of a mapping section that come from the command line, not the mapping file.
SOURCE_KEYS = ("log", "bag", "topic", "dbc")


# --- calibration -------------------------------------------------------------------------


@dataclass(frozen=True)
class CameraInfoFile:
    """Intrinsics from a ROS camera_info YAML (as `fusionscope calibrate` writes)."""

    path: Path


@dataclass(frozen=True)
class FieldOfView:
    """Pinhole intrinsics from a horizontal field of view: square pixels, centred."""

    hfov_deg: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.hfov_deg) and 0.0 < self.hfov_deg < 180.0):
            raise ValueError(
                f"--hfov-deg: expected a field of view in (0, 180) degrees, got {self.hfov_deg}"
            )


@dataclass(frozen=True)
class Pinhole:
    """Pinhole intrinsics in pixels of the source image (a video's, a still's, a bag's).

    fy_px None: equal to fx_px; cx_px, cy_px None: the image centre.
    """

    fx_px: float
    fy_px: float | None = None
    cx_px: float | None = None
    cy_px: float | None = None


IntrinsicsSpec = CameraInfoFile | FieldOfView | Pinhole


@dataclass(frozen=True)
class CalibrationSpec:
    """How to calibrate the imported camera and radar.

    camera_height_m, camera_x_m, pitch_rad (down positive), yaw_rad (left positive): the
    camera's pose in the vehicle frame (x forward, origin on the road under the reference
    point); radar_mount: needed when the recording has
    radar. `rows_used_px` is left None (the engine uses all rows).
    """

    intrinsics: IntrinsicsSpec
    camera_height_m: float = DEFAULT_CAMERA_HEIGHT_M
    camera_x_m: float = DEFAULT_CAMERA_X_M
    pitch_rad: float = 0.0
    yaw_rad: float = 0.0
    radar_mount: RadarMount | None = None


def scale_intrinsics(i: Intrinsics, width_px: int, height_px: int) -> Intrinsics:
    """`i` for the image resized to `width_px` x `height_px`; distortion unchanged.

    Pixel centres sit at integer coordinates (core/camera.py), so a resize by s maps
    u -> (u + 0.5) * s - 0.5, as cv2.resize samples; focal lengths scale by s.
    """
    sx, sy = width_px / i.width_px, height_px / i.height_px
    return Intrinsics(
        fx_px=i.fx_px * sx,
        fy_px=i.fy_px * sy,
        cx_px=(i.cx_px + 0.5) * sx - 0.5,
        cy_px=(i.cy_px + 0.5) * sy - 0.5,
        width_px=width_px,
        height_px=height_px,
        distortion=i.distortion,
    )


@dataclass(frozen=True)
class _BuiltCalibration:
    calibration: Calibration
    description: str
    notes: tuple[str, ...]


def _build_calibration(
    spec: CalibrationSpec,
    source_size: tuple[int, int],
    out_size: tuple[int, int],
    has_radar: bool,
    what: str,
) -> _BuiltCalibration:
    """The calibration of the output images (`out_size`) from `spec` about the source images.

    what: the source and its verb, for messages ("the video is", "the bag's images are").
    """
    (sw, sh), (ow, oh) = source_size, out_size
    notes: list[str] = []
    intr = spec.intrinsics
    if isinstance(intr, CameraInfoFile):
        info = load_camera_info(intr.path)
        if (info.width_px, info.height_px) != (sw, sh):
            ratio = (info.width_px / info.height_px) / (sw / sh)
            if (sw, sh) == (ow, oh) or abs(ratio - 1.0) > ASPECT_TOLERANCE:
                raise ValueError(
                    f"--camera-info {intr.path}: calibrated at {info.width_px}x{info.height_px}, "
                    f"but {what} {sw}x{sh}; give a camera_info (or --fx/--fy/--cx/--cy) "
                    f"at {sw}x{sh}"
                )
            notes.append(
                f"{intr.path} is for {info.width_px}x{info.height_px}, but {what} {sw}x{sh}: "
                "taken as the same sensor at another resolution"
            )
        intrinsics = scale_intrinsics(info, ow, oh)
        source = f"from {intr.path.name}"
    elif isinstance(intr, FieldOfView):
        intrinsics = Intrinsics.from_fov(ow, oh, math.radians(intr.hfov_deg))
        source = f"pinhole from a horizontal field of view of {intr.hfov_deg:g} deg, centred"
    else:
        at_source = Intrinsics(
            fx_px=intr.fx_px,
            fy_px=intr.fy_px if intr.fy_px is not None else intr.fx_px,
            cx_px=intr.cx_px if intr.cx_px is not None else (sw - 1) / 2.0,
            cy_px=intr.cy_px if intr.cy_px is not None else (sh - 1) / 2.0,
            width_px=sw,
            height_px=sh,
        )
        intrinsics = scale_intrinsics(at_source, ow, oh)
        source = (
            f"pinhole fx {at_source.fx_px:g}, fy {at_source.fy_px:g}, cx {at_source.cx_px:g}, "
            f"cy {at_source.cy_px:g} px at {sw}x{sh}"
        )
    if source_size != out_size and not isinstance(intr, FieldOfView):
        source += f", scaled to {ow}x{oh}"
    if has_radar and spec.radar_mount is None:
        raise ValueError(
            "--radar-x-m: the recording has radar, so its mount is needed: give --radar-x-m "
            "(and --radar-y-m, --radar-z-m, --radar-yaw-rad when not 0)"
        )
    mount = spec.radar_mount if spec.radar_mount is not None else RadarMount(0.0, 0.0)
    extrinsics = Extrinsics(
        height_m=spec.camera_height_m,
        x_m=spec.camera_x_m,
        pitch_rad=spec.pitch_rad,
        yaw_rad=spec.yaw_rad,
    )
    calibration = Calibration(CameraModel(intrinsics, extrinsics, None), mount)
    text = (
        f"Intrinsics: {source}. Camera {spec.camera_height_m:g} m above the road, "
        f"{spec.camera_x_m:g} m ahead of the reference point, pitch {spec.pitch_rad:g} rad, "
        f"yaw {spec.yaw_rad:g} rad."
    )
    if has_radar:
        text += (
            f" Radar at x {mount.x_m:g} m, y {mount.y_m:g} m, z {mount.z_m:g} m, "
            f"yaw {mount.yaw_rad:g} rad."
        )
    return _BuiltCalibration(calibration, text, tuple(notes))


# --- CAN ---------------------------------------------------------------------------------


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
class _PreparedCan:
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


def _prepare_can(
    spec: CanSpec,
    bag_name: str | None = None,
    bag_topic: str | None = None,
    bag_frames: Callable[[], Iterable[CanFrame]] | None = None,
) -> _PreparedCan:
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
    return _PreparedCan(can_src, radar_src, files, span, radar_times, text.strip(), tuple(notes))


def _span_text(span_ns: tuple[int, int]) -> str:
    first, last = (t / NS_PER_S for t in span_ns)
    return f"{first:.3f} s" if span_ns[0] == span_ns[1] else f"{first:.3f}-{last:.3f} s"


def _check_can_times(
    prepared: _PreparedCan, times_ns: Sequence[int], what: str, skew_ms: float | None
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


# --- the folder --------------------------------------------------------------------------


@dataclass(frozen=True)
class ImportOptions:
    """What every import takes besides its source.

    name: the recording's name (None: the source file's stem); assumptions: constants where
    nothing records the speed or yaw rate; max_radar_skew_ms: how far (ms) a radar scan may
    lie from a camera frame and still be paired with it (None: the Drive's default).
    """

    name: str | None = None
    assumptions: Assumptions = field(default_factory=Assumptions)
    max_radar_skew_ms: float | None = None

    def __post_init__(self) -> None:
        a = self.assumptions
        for flag, value in (
            ("--assume-speed-mps", a.speed_mps),
            ("--assume-yaw-rate-radps", a.yaw_rate_radps),
        ):
            if value is not None and not math.isfinite(value):
                raise ValueError(f"{flag}: expected a finite number, got {value}")
        if a.speed_mps is not None and a.speed_mps < 0:
            raise ValueError(f"--assume-speed-mps: expected a speed >= 0 m/s, got {a.speed_mps}")
        skew = self.max_radar_skew_ms
        if skew is not None and not (math.isfinite(skew) and skew > 0):
            raise ValueError(f"--max-radar-skew-ms: expected a time > 0 ms, got {skew}")
        if self.name is not None and not self.name.strip():
            raise ValueError("--name: expected a non-empty name")


@dataclass(frozen=True)
class ImportResult:
    """What was written: the folder, its frames (count, size, first and last stamp, ns),
    the calibration and manifest as written, and notes for the person importing."""

    out_dir: Path
    frames: int
    width_px: int
    height_px: int
    first_t_ns: int
    last_t_ns: int
    calibration: Calibration
    manifest: Manifest
    notes: tuple[str, ...] = field(default_factory=tuple)


def check_out_dir(out_dir: Path) -> None:
    """RecordingError unless `out_dir` is new or an empty folder."""
    if out_dir.exists() and not out_dir.is_dir():
        raise RecordingError(
            f"{out_dir}: expected a new or empty folder for the recording, it is a file"
        )
    if out_dir.is_dir() and any(out_dir.iterdir()):
        raise RecordingError(
            f"{out_dir}: expected a new or empty folder for the recording, it is not empty"
        )


@contextmanager
def _staging(out_dir: Path) -> Iterator[Path]:
    """A temporary folder beside `out_dir`, renamed to it on success, removed on error.

    Success: the recording opens with Drive (RecordingError otherwise).
    """
    check_out_dir(out_dir)
    out_dir.parent.mkdir(parents=True, exist_ok=True)
    # mkdir, not tempfile.mkdtemp: the folder gets the user's usual permissions, not 0700.
    tmp = out_dir.parent / f".{out_dir.name}.{uuid.uuid4().hex[:12]}.partial"
    tmp.mkdir()
    try:
        yield tmp
        Drive(tmp).close()  # it must open; this also caches its index (moves keep it)
        check_out_dir(out_dir)
        if out_dir.exists():
            out_dir.rmdir()
        os.replace(tmp, out_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _assumption_notes(
    options: ImportOptions, prepared: _PreparedCan | None
) -> tuple[Assumptions, str, list[str]]:
    """The assumptions to write (yaw rate 0 with an assumed speed), their text, notes."""
    a = options.assumptions
    if prepared is not None and prepared.can is not None and a != Assumptions():
        raise ValueError(
            "--assume-speed-mps/--assume-yaw-rate-radps: the mapping's `can:` section records "
            "speed and yaw rate; assumptions are for recordings without them"
        )
    if a.speed_mps is not None and a.yaw_rate_radps is None:
        a = Assumptions(a.speed_mps, 0.0)
    text, notes = "", []
    if a.speed_mps is not None:
        text = f"Speed not recorded: assumed {a.speed_mps:g} m/s"
    if a.yaw_rate_radps is not None:
        text += ("; yaw rate" if text else "Yaw rate not recorded: assumed") + (
            f" {a.yaw_rate_radps:g} rad/s"
        )
    if text:
        text += "."
    if a.speed_mps is None and (prepared is None or prepared.can is None):
        notes.append(
            "no speed: nothing records it and --assume-speed-mps is not given, so speed is NaN "
            "and the engine's motion stereo cannot work"
        )
    return a, text, notes


def _finish(
    tmp: Path,
    *,
    kind: str,
    source: Path,
    source_text: str,
    camera: BagStream,
    built: _BuiltCalibration,
    radar: BagStream | RadarCanSource | None,
    prepared: _PreparedCan | None,
    assumptions: Assumptions,
    assumption_text: str,
    options: ImportOptions,
) -> Manifest:
    """Copy the CAN files, write calibration and manifest (checked by _staging's open).

    The description: "Imported by `fusionscope import KIND` from NAME" + source_text, then
    the calibration's, the CAN mapping's and the assumptions' descriptions.
    """
    if prepared is not None:
        for rel, src in prepared.files.items():
            shutil.copyfile(src, tmp / rel)
    save_calibration(built.calibration, tmp / CALIBRATION_NAME)
    description = _join(
        f"Imported by `fusionscope import {kind}` from {source.name}{source_text}",
        built.description,
        prepared.description if prepared is not None else "",
        assumption_text,
    )
    manifest = Manifest(
        folder=tmp,
        name=_name(options, source),
        description=description,
        generator={"importer": kind, "source": source.name},
        camera=camera,
        radar=radar,
        can=prepared.can if prepared is not None else None,
        calibration=CALIBRATION_NAME,
        assumptions=assumptions,
        max_radar_skew_ms=options.max_radar_skew_ms,
    )
    save_manifest(manifest, tmp / MANIFEST_NAME)
    return manifest


def _result(
    out_dir: Path,
    stamps: Sequence[int],
    size: tuple[int, int],
    built: _BuiltCalibration,
    manifest: Manifest,
    notes: Sequence[str],
) -> ImportResult:
    """What an import wrote into `out_dir`: `stamps` of frames of `size` (width, height)."""
    return ImportResult(
        out_dir,
        len(stamps),
        size[0],
        size[1],
        stamps[0],
        stamps[-1],
        built.calibration,
        replace(manifest, folder=out_dir),
        tuple(notes),
    )


def output_size(width_px: int, source_size: tuple[int, int]) -> tuple[int, int]:
    """(width, height) of the resized image: `width_px` wide, the source's aspect ratio."""
    sw, sh = source_size
    return width_px, max(1, round(width_px * sh / sw))


def to_grey(frame: npt.NDArray[Any], size: tuple[int, int]) -> GreyImage:
    """(H, W) uint8 grey of a decoded 8-bit frame (grey, BGR or BGRA), resized to `size` (W, H).

    Shrinking averages pixel areas (cv2.INTER_AREA); enlarging interpolates linearly.
    """
    if frame.dtype != np.uint8 or frame.ndim not in (2, 3):
        raise ValueError(f"frame: expected an 8-bit image, got {frame.dtype} {frame.shape}")
    grey: npt.NDArray[Any] = frame
    if frame.ndim == 3 and frame.shape[2] == 4:
        grey = cv2.cvtColor(frame, cv2.COLOR_BGRA2GRAY)
    elif frame.ndim == 3 and frame.shape[2] == 3:
        grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    elif frame.ndim == 3:
        grey = frame[:, :, 0]
    if (grey.shape[1], grey.shape[0]) != size:
        shrink = size[0] < grey.shape[1]
        grey = cv2.resize(grey, size, interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
    return np.ascontiguousarray(grey, dtype=np.uint8)


def _camera_bag(tmp: Path) -> SplitBagWriter:
    return SplitBagWriter(
        tmp / BAG_DIR,
        {CAMERA_TOPIC: radar_msgs.COMPRESSED_IMAGE},
        radar_msgs.typestore(),
        MAX_BAG_FILE_BYTES,
    )


@dataclass(frozen=True)
class VideoSampling:
    """How video frames become recording frames.

    width_px: output width (height by the aspect ratio); fps: output frame rate; start_ns:
    the recording-clock time of the video's first frame (the CAN clock's, with CAN);
    from_s, to_s: the clip on the video's clock (to_s None: to the end).
    """

    width_px: int = DEFAULT_WIDTH_PX
    fps: float = DEFAULT_FPS
    start_ns: int = 0
    from_s: float = 0.0
    to_s: float | None = None

    def __post_init__(self) -> None:
        if self.width_px < 1:
            raise ValueError(f"--width: expected a width >= 1 px, got {self.width_px}")
        if not (math.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"--fps: expected a frame rate > 0, got {self.fps}")
        if self.start_ns < 0:
            raise ValueError(f"start time: expected >= 0 ns, got {self.start_ns}")
        if not (math.isfinite(self.from_s) and self.from_s >= 0):
            raise ValueError(f"--from-s: expected a time >= 0 s, got {self.from_s}")
        if self.to_s is not None and not (math.isfinite(self.to_s) and self.to_s > self.from_s):
            raise ValueError(
                f"--to-s: expected a time after --from-s {self.from_s}, got {self.to_s}"
            )


@dataclass(frozen=True)
class _Video:
    capture: cv2.VideoCapture
    fps: float
    frame_count: int | None  # None when the container does not say
    width_px: int
    height_px: int


def _open_video(path: Path) -> _Video:
    if not path.is_file():
        raise RecordingError(f"{path}: video not found")
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise RecordingError(
            f"{path}: cannot open as a video; expected a file OpenCV reads (mp4, avi, mkv, ...)"
        )
    fps = float(capture.get(cv2.CAP_PROP_FPS))
    count = capture.get(cv2.CAP_PROP_FRAME_COUNT)
    width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH))
    height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))
    if not (math.isfinite(fps) and fps > 0):
        capture.release()
        raise RecordingError(f"{path}: the video does not say its frame rate (got {fps})")
    if width <= 0 or height <= 0:
        capture.release()
        raise RecordingError(f"{path}: the video does not say its frame size ({width}x{height})")
    frame_count = int(count) if 0 < count < 2**31 else None
    return _Video(capture, fps, frame_count, width, height)


def _name(options: ImportOptions, source: Path) -> str:
    return options.name if options.name is not None else source.stem or source.name


def _output_ns(sampling: VideoSampling, k: int) -> int:
    """Output time k (ns) on the video's clock; each rounded on its own, so no drift builds up."""
    return round(sampling.from_s * NS_PER_S) + round(k * NS_PER_S / sampling.fps)


def _planned_count(v: _Video, sampling: VideoSampling) -> int:
    """How many output frames the clip gives, from the container's frame count (0: unknown)."""
    if v.frame_count is None:
        return 0
    end_s = (v.frame_count - 1) / v.fps
    end_ns = round((end_s if sampling.to_s is None else min(end_s, sampling.to_s)) * NS_PER_S)
    count = 0
    while _output_ns(sampling, count) <= end_ns:
        count += 1
    return count


def _sampled_frames(
    v: _Video, sampling: VideoSampling, out_size: tuple[int, int], where: Path
) -> Iterator[tuple[int, GreyImage]]:
    """(output time on the video's clock (ns), grey resized image) per output frame.

    Output time k takes source frame round(t_k * fps); source frames are grabbed in order and
    only the wanted ones decoded. Ends at --to-s or past the last source frame.
    """
    to_ns = None if sampling.to_s is None else round(sampling.to_s * NS_PER_S)
    grabbed = -1  # index of the last source frame grabbed
    image: GreyImage | None = None
    k = 0
    while True:
        t_ns = _output_ns(sampling, k)
        if to_ns is not None and t_ns > to_ns:
            return
        wanted = math.floor(t_ns * v.fps / NS_PER_S + 0.5)
        if wanted > grabbed:
            while grabbed < wanted and v.capture.grab():
                grabbed += 1
            if grabbed < wanted:
                return  # past the end
            ok, frame = v.capture.retrieve()
            if not ok or frame is None:
                raise RecordingError(f"{where}: frame {grabbed} cannot be decoded")
            image = to_grey(frame, out_size)
        assert image is not None  # wanted >= 0 = the first grab
        yield t_ns, image
        k += 1


def import_video(
    video: Path,
    out_dir: Path,
    calibration: CalibrationSpec,
    sampling: VideoSampling = VideoSampling(),
    can_spec: CanSpec | None = None,
    options: ImportOptions = ImportOptions(),
    progress: Progress | None = None,
) -> ImportResult:
    """Write the recording of `video` into `out_dir` (new or empty); see the module docstring.

    RecordingError or ValueError naming the file or the option on bad input; nothing is left
    behind then.
    """
    check_out_dir(out_dir)
    prepared = _prepare_can(can_spec) if can_spec is not None else None
    assumptions, assumption_text, notes = _assumption_notes(options, prepared)
    notes.extend(prepared.notes if prepared is not None else ())
    v = _open_video(video)
    try:
        source_size = (v.width_px, v.height_px)
        out_size = output_size(sampling.width_px, source_size)
        has_radar = prepared is not None and prepared.radar is not None
        built = _build_calibration(calibration, source_size, out_size, has_radar, "the video is")
        notes.extend(built.notes)
        total = _planned_count(v, sampling)
        if prepared is not None:
            planned = [sampling.start_ns + _output_ns(sampling, k) for k in range(max(total, 1))]
            what = f"{video}: the video's frames (--video-start-s)"
            notes.extend(_check_can_times(prepared, planned, what, options.max_radar_skew_ms))
        with _staging(out_dir) as tmp:
            bag = _camera_bag(tmp)
            stamps: list[int] = []
            for t_ns, image in _sampled_frames(v, sampling, out_size, video):
                stamp = sampling.start_ns + t_ns
                bag.write(
                    CAMERA_TOPIC, stamp, png_image_message(radar_msgs.typestore(), stamp, image)
                )
                stamps.append(stamp)
                if progress is not None:
                    progress(len(stamps), max(total, len(stamps)))
            bag.close()
            if not stamps:
                end = "the end" if sampling.to_s is None else f"--to-s {sampling.to_s:g}"
                lasts = (
                    f"; the video lasts {(v.frame_count - 1) / v.fps:g} s" if v.frame_count else ""
                )
                raise RecordingError(
                    f"{video}: no frames between --from-s {sampling.from_s:g} and {end}{lasts}"
                )
            if progress is not None and len(stamps) < total:
                progress(len(stamps), len(stamps))
            clip_end_s = (stamps[-1] - sampling.start_ns) / NS_PER_S
            manifest = _finish(
                tmp,
                kind="video",
                source=video,
                source_text=(
                    f" ({v.width_px}x{v.height_px}, {v.fps:g} fps): grey, resized to "
                    f"{out_size[0]}x{out_size[1]}, resampled to {sampling.fps:g} fps (the source "
                    f"frame nearest each output time), video time {sampling.from_s:g}-"
                    f"{clip_end_s:g} s; stamps are the output times plus {sampling.start_ns} ns."
                ),
                camera=BagStream(BAG_DIR, CAMERA_TOPIC),
                built=built,
                radar=prepared.radar if prepared is not None else None,
                prepared=prepared,
                assumptions=assumptions,
                assumption_text=assumption_text,
                options=options,
            )
    finally:
        v.capture.release()
    return _result(out_dir, stamps, out_size, built, manifest, notes)


def _join(*parts: str) -> str:
    return " ".join(p.strip() for p in parts if p.strip())


def import_still(
    image_path: Path,
    out_dir: Path,
    t_ns: int,
    calibration: CalibrationSpec,
    width_px: int = DEFAULT_WIDTH_PX,
    can_spec: CanSpec | None = None,
    options: ImportOptions = ImportOptions(),
) -> ImportResult:
    """Write a one-frame recording of `image_path` stamped `t_ns` (ns on the CAN log's clock
    when `can_spec` is given) into `out_dir` (new or empty).

    The image is made grey and resized as a video frame; RecordingError or ValueError naming
    the file or the option on bad input, and nothing is left behind then.
    """
    check_out_dir(out_dir)
    if width_px < 1:
        raise ValueError(f"--width: expected a width >= 1 px, got {width_px}")
    if t_ns < 0:
        raise ValueError(f"--time-s: expected a time >= 0 s, got {t_ns / NS_PER_S:g}")
    if not image_path.is_file():
        raise RecordingError(f"{image_path}: image not found")
    frame = cv2.imread(str(image_path), cv2.IMREAD_COLOR)
    if frame is None:
        raise RecordingError(
            f"{image_path}: cannot decode the image; expected a file OpenCV reads (png, jpg, ...)"
        )
    prepared = _prepare_can(can_spec) if can_spec is not None else None
    assumptions, assumption_text, notes = _assumption_notes(options, prepared)
    notes.extend(prepared.notes if prepared is not None else ())
    source_size = (frame.shape[1], frame.shape[0])
    out_size = output_size(width_px, source_size)
    has_radar = prepared is not None and prepared.radar is not None
    built = _build_calibration(calibration, source_size, out_size, has_radar, "the image is")
    notes.extend(built.notes)
    if prepared is not None:
        what = f"--time-s {t_ns / NS_PER_S:.3f}"
        notes.extend(_check_can_times(prepared, [t_ns], what, options.max_radar_skew_ms))
    image = to_grey(frame, out_size)
    with _staging(out_dir) as tmp:
        bag = _camera_bag(tmp)
        bag.write(CAMERA_TOPIC, t_ns, png_image_message(radar_msgs.typestore(), t_ns, image))
        bag.close()
        manifest = _finish(
            tmp,
            kind="still",
            source=image_path,
            source_text=(
                f" ({source_size[0]}x{source_size[1]}): one frame at {t_ns / NS_PER_S:.3f} s, "
                f"grey, resized to {out_size[0]}x{out_size[1]}."
            ),
            camera=BagStream(BAG_DIR, CAMERA_TOPIC),
            built=built,
            radar=prepared.radar if prepared is not None else None,
            prepared=prepared,
            assumptions=assumptions,
            assumption_text=assumption_text,
            options=options,
        )
    return _result(out_dir, [t_ns], out_size, built, manifest, notes)


def _radar_topic(reader: BagReader, topic: str | None, mapped: bool) -> tuple[str | None, str]:
    """The bag's radar topic (named, or the only one of a radar type), a note; None: none."""
    if topic is not None:
        if mapped:
            raise ValueError(
                f"--radar-topic {topic}: the mapping's `radar:` section also gives radar; "
                "expected one radar source"
            )
        return reader.connection(topic, RADAR_TYPES, "radar").topic, ""
    found = sorted(t for t, m in reader.topics.items() if m in RADAR_TYPES)
    if mapped:
        note = f"radar topics of the bag not used (radar from CAN): {', '.join(found)}"
        return None, note if found else ""
    if len(found) > 1:
        raise RecordingError(
            f"{reader.path}: several radar topics ({', '.join(found)}); name one with --radar-topic"
        )
    return (found[0] if found else None), ""


def import_bag(
    bag_path: Path,
    out_dir: Path,
    calibration: CalibrationSpec,
    camera_topic: str | None = None,
    radar_topic: str | None = None,
    can_spec: CanSpec | None = None,
    options: ImportOptions = ImportOptions(),
    progress: Progress | None = None,
) -> ImportResult:
    """Copy a ROS bag (a ROS 1 `.bag` file or a ROS 2 bag folder) into a recording folder.

    Topics not named are found by message type (camera: Image or CompressedImage; radar:
    RadarScan or RadarTracks, optional; CAN: can_msgs/Frame when `can_spec` has no log). The
    bag's images are used at their own size: the calibration must be for that size.
    """
    check_out_dir(out_dir)
    if not bag_path.exists():
        raise RecordingError(f"{bag_path}: bag not found")
    bag_name = bag_path.name
    notes: list[str] = []
    prepared = None
    with BagReader(bag_path) as reader:
        stream = CameraStream(reader, camera_topic)
        first = stream.image(0)
        times_ns = [int(t) for t in stream.times_ns]
        if can_spec is not None and can_spec.log is None:
            conn = reader.connection(can_spec.bag_topic, CAN_TYPES, "CAN")
            prepared = _prepare_can(can_spec, bag_name, conn.topic, lambda: reader.can_frames(conn))
        elif can_spec is not None:
            prepared = _prepare_can(can_spec)
        mapped_radar = prepared is not None and prepared.radar is not None
        radar_found, radar_note = _radar_topic(reader, radar_topic, mapped_radar)
    notes.extend([radar_note] if radar_note else [])
    assumptions, assumption_text, more = _assumption_notes(options, prepared)
    notes.extend(more)
    notes.extend(prepared.notes if prepared is not None else ())
    size = (first.shape[1], first.shape[0])
    radar: BagStream | RadarCanSource | None = (
        BagStream(bag_name, radar_found) if radar_found is not None else None
    )
    if prepared is not None and prepared.radar is not None:
        radar = prepared.radar
    built = _build_calibration(calibration, size, size, radar is not None, "the bag's images are")
    notes.extend(built.notes)
    if prepared is not None:
        what = f"{bag_path}: the camera's stamps"
        notes.extend(_check_can_times(prepared, times_ns, what, options.max_radar_skew_ms))
    with _staging(out_dir) as tmp:
        if bag_path.is_dir():
            files = sorted(p for p in bag_path.rglob("*") if p.is_file())
            for k, src in enumerate(files):
                dst = tmp / bag_name / src.relative_to(bag_path)
                dst.parent.mkdir(parents=True, exist_ok=True)
                shutil.copyfile(src, dst)
                if progress is not None:
                    progress(k + 1, len(files))
        else:
            shutil.copyfile(bag_path, tmp / bag_name)
            if progress is not None:
                progress(1, 1)
        radar_text = f" Radar from topic {radar_found}." if isinstance(radar, BagStream) else ""
        manifest = _finish(
            tmp,
            kind="bag",
            source=bag_path,
            source_text=(
                f": camera topic {stream.conn.topic} ({len(times_ns)} frames, "
                f"{size[0]}x{size[1]}), copied as is.{radar_text}"
            ),
            camera=BagStream(bag_name, stream.conn.topic),
            built=built,
            radar=radar,
            prepared=prepared,
            assumptions=assumptions,
            assumption_text=assumption_text,
            options=options,
        )
    return _result(out_dir, times_ns, size, built, manifest, notes)
