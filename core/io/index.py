"""The index of a recording: everything but the images, built once and cached on disk.

Opening a drive needs the camera's time stamps (not its images), the radar scans and the CAN
signals. `build_index` reads them from the recording's files; `load_index` returns the cached
copy when none of those files changed, so an hour-long drive reopens in a fraction of a
second. The cache lives under `$FUSIONSCOPE_CACHE_DIR` (default `$XDG_CACHE_HOME/fusionscope`
or `~/.cache/fusionscope`), one `.npz` per recording, keyed by the name (relative to the
recording folder), size and modification time of each file it is built from, and
`INDEX_VERSION`; not by the folder's path, so a recording moved or renamed keeps its index.
A cache that cannot be written (read-only home) is skipped silently: it only saves time.

Camera stamps are the bag's log times, put in time order by `CameraStream`; stamps outside
the main body of the stream (a 1970 stamp in the middle of a drive, see `core.io.timeline`)
are skipped and reported as a warning.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import os
import time
import zipfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt
from cantools.database.can import Database

from core.io.bag import CAN_TYPES, RADAR_TYPES, BagReader, CameraStream
from core.io.can_radar import RadarCanDecoder
from core.io.canfiles import iter_log_frames
from core.io.canframe import CanFrame
from core.io.canlog import (
    FrameDecoder,
    VehicleSignalDecoder,
    VehicleSignals,
    decode_frames,
    load_dbc,
)
from core.io.manifest import MANIFEST_NAME, CanBus, Manifest, RadarCanSource
from core.io.radarscans import RadarScans

INDEX_VERSION = 1
NS_PER_S = 1_000_000_000
Int64Array = npt.NDArray[np.int64]


@dataclass(frozen=True, eq=False)
class DriveIndex:
    """Time stamps and small streams of a recording, in time order.

    camera_log_ns: (N,) bag log time of each frame (what the bag is searched by);
    camera_occurrence: (N,) which of the messages at that same log time it is (bag order);
    camera_t_ns: (N,) frame stamps on the recording clock (camera offset applied);
    camera_skipped: frames skipped because their stamps are outliers;
    radar: all scans (None without radar); vehicle: speed and yaw rate;
    warnings: what was skipped or repaired while building, in plain words; build_s: seconds
    the build took (not the load).
    """

    camera_log_ns: Int64Array
    camera_occurrence: Int64Array
    camera_t_ns: Int64Array
    camera_skipped: int
    radar: RadarScans | None
    vehicle: VehicleSignals
    warnings: tuple[str, ...]
    build_s: float


# --- building -------------------------------------------------------------------------------
class _Bags:
    """The recording's bags, each opened once."""

    def __init__(self, manifest: Manifest) -> None:
        self.manifest = manifest
        self.open: dict[Path, BagReader] = {}

    def get(self, relative: str) -> BagReader:
        path = self.manifest.resolve(relative)
        if path not in self.open:
            self.open[path] = BagReader(path)
        return self.open[path]

    def close(self) -> None:
        for bag in self.open.values():
            bag.close()
        self.open.clear()


def _can_frames(bags: _Bags, bus: CanBus, warn: Callable[[str], None]) -> Iterable[CanFrame]:
    m = bags.manifest
    if bus.log is not None:
        return iter_log_frames(m.resolve(bus.log), warn=warn)
    assert bus.bag is not None
    bag = bags.get(bus.bag)
    return bag.can_frames(bag.connection(bus.topic, CAN_TYPES, "CAN"))


def _decode_can(
    bags: _Bags, warn: Callable[[str], None]
) -> tuple[VehicleSignals, RadarScans | None]:
    """Vehicle signals and radar-over-CAN, one pass over each CAN source."""
    m = bags.manifest
    by_bus: dict[tuple[str | None, str | None, str | None], list[FrameDecoder]] = {}
    vehicle: VehicleSignalDecoder | None = None
    radar: RadarCanDecoder | None = None

    def database(bus: CanBus) -> Database:
        return load_dbc([m.resolve(d) for d in bus.dbc])

    def where(section: str, bus: CanBus) -> str:
        kind = "log" if bus.log is not None else "bag"
        return (
            f"{m.folder / MANIFEST_NAME}: {section} ({kind} {bus.file}, DBC {', '.join(bus.dbc)})"
        )

    if m.can is not None:
        vehicle = VehicleSignalDecoder(
            database(m.can.bus), m.can, where("can", m.can.bus), offset_ns=m.time_offsets.can_ns
        )
        by_bus.setdefault((m.can.bus.log, m.can.bus.bag, m.can.bus.topic), []).append(vehicle)
    if isinstance(m.radar, RadarCanSource):
        bus = m.radar.bus
        radar = RadarCanDecoder(
            database(bus), m.radar, where("radar.can", bus), offset_ns=m.time_offsets.radar_ns
        )
        by_bus.setdefault((bus.log, bus.bag, bus.topic), []).append(radar)
    for decoders in by_bus.values():
        decode_frames(_can_frames(bags, decoders[0].bus, warn), decoders)
    signals = vehicle.result(warn) if vehicle is not None else VehicleSignals.empty()
    return signals, (radar.result(warn) if radar is not None else None)


def build_index(manifest: Manifest) -> DriveIndex:
    """Read the recording's stamps, radar and CAN; RecordingError naming the file on bad input."""
    started = time.perf_counter()
    m = manifest
    warnings: list[str] = []
    bags = _Bags(m)
    try:
        camera = CameraStream(
            bags.get(m.camera.bag), m.camera.topic, m.time_offsets.camera_ns, m.camera.mono16_bits
        )
        log_ns, skipped = camera.log_ns, camera.skipped
        where = f"{camera.bag.path}: camera topic {camera.conn.topic}"
        if skipped:
            warnings.append(
                f"{where}: skipped {skipped} frame(s) whose stamps lie outside the drive's "
                f"main time span (first kept {log_ns[0] / NS_PER_S:.3f} s, "
                f"last {log_ns[-1] / NS_PER_S:.3f} s)"
            )
        if camera.backwards:
            warnings.append(
                f"{where}: {camera.backwards} frame(s) stamped earlier than the one before "
                "in the bag; put in time order"
            )
        radar: RadarScans | None = None
        if m.radar is not None and not isinstance(m.radar, RadarCanSource):
            rbag = bags.get(m.radar.bag)
            rconn = rbag.connection(m.radar.topic, RADAR_TYPES, "radar")
            radar = rbag.read_radar(rconn, m.time_offsets.radar_ns, warn=warnings.append)
        vehicle, can_radar = _decode_can(bags, warnings.append)
        radar = can_radar if can_radar is not None else radar
    finally:
        bags.close()
    return DriveIndex(
        camera_log_ns=log_ns,
        camera_occurrence=camera.occurrence,
        camera_t_ns=camera.times_ns,
        camera_skipped=skipped,
        radar=radar,
        vehicle=vehicle,
        warnings=tuple(warnings),
        build_s=time.perf_counter() - started,
    )


# --- the cache ------------------------------------------------------------------------------
def cache_dir() -> Path:
    env = os.environ.get("FUSIONSCOPE_CACHE_DIR")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "fusionscope"


def _files(manifest: Manifest) -> list[Path]:
    """Every file the index is built from (the manifest first), sorted within each part.

    RecordingError when a part is missing or outside the folder (Manifest.resolve).
    """
    m = manifest
    parts = [MANIFEST_NAME, m.camera.bag]
    buses = [m.can.bus] if m.can is not None else []
    if isinstance(m.radar, RadarCanSource):
        buses.append(m.radar.bus)
    elif m.radar is not None:
        parts.append(m.radar.bag)
    for bus in buses:
        parts += [*bus.dbc, bus.file]
    files: list[Path] = []
    for part in parts:
        path = m.resolve(part)
        files += sorted(p for p in path.rglob("*") if p.is_file()) if path.is_dir() else [path]
    return files


def index_key(manifest: Manifest) -> str:
    """A hash of the recording's files (relative names, sizes, times) and INDEX_VERSION."""
    h = hashlib.sha256(f"{INDEX_VERSION}\n".encode())
    for path in _files(manifest):
        st = path.stat()
        name = path.relative_to(manifest.folder).as_posix()
        h.update(f"{name}\t{st.st_size}\t{st.st_mtime_ns}\n".encode())
    return h.hexdigest()[:32]


def _flatten(prefix: str, obj: Any, arrays: dict[str, Any], meta: dict[str, Any]) -> None:
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if isinstance(value, np.ndarray):
            arrays[f"{prefix}{f.name}"] = value
        else:
            meta[f"{prefix}{f.name}"] = value


def _unflatten(cls: Any, prefix: str, arrays: Any, meta: dict[str, Any]) -> Any:
    values = {}
    for f in dataclasses.fields(cls):
        key = f"{prefix}{f.name}"
        values[f.name] = arrays[key] if key in arrays.files else meta[key]
    return cls(**values)


def save_index(index: DriveIndex, path: Path) -> None:
    arrays: dict[str, Any] = {}
    meta: dict[str, Any] = {"version": INDEX_VERSION, "has_radar": index.radar is not None}
    _flatten("", index, arrays, meta)
    _flatten("vehicle.", index.vehicle, arrays, meta)
    if index.radar is not None:
        _flatten("radar.", index.radar, arrays, meta)
    for key in ("radar", "vehicle"):
        meta.pop(key)
    meta["warnings"] = list(index.warnings)
    arrays["meta"] = np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npz")
    np.savez(tmp, **arrays)
    tmp.replace(path)


def read_index(path: Path) -> DriveIndex:
    with np.load(path) as arrays:
        meta = json.loads(bytes(arrays["meta"]).decode())
        if meta.get("version") != INDEX_VERSION:
            raise ValueError(f"index version {meta.get('version')}, expected {INDEX_VERSION}")
        vehicle = _unflatten(VehicleSignals, "vehicle.", arrays, meta)
        radar = _unflatten(RadarScans, "radar.", arrays, meta) if meta["has_radar"] else None
        meta = {**meta, "radar": radar, "vehicle": vehicle, "warnings": tuple(meta["warnings"])}
        return _unflatten(DriveIndex, "", arrays, meta)


def load_index(manifest: Manifest, use_cache: bool = True) -> tuple[DriveIndex, bool]:
    """The recording's index and whether it came from the cache.

    use_cache False builds it from the files even when the cache holds a valid copy. A
    built index is saved to the cache either way.
    """
    path = cache_dir() / "index" / f"{index_key(manifest)}.npz"
    if use_cache and path.is_file():
        try:
            return read_index(path), True
        except (OSError, ValueError, KeyError, TypeError, zipfile.BadZipFile):
            pass  # a stale or damaged cache entry is rebuilt
    index = build_index(manifest)
    try:
        save_index(index, path)
    except OSError:
        pass  # see the module docstring
    return index, False
