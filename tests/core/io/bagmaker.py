"""Small ROS bags of every kind for tests: ROS 1 `.bag`, ROS 2 sqlite3 and ROS 2 MCAP.

    path = write_bag(tmp_path / "drive.bag", "ros1", [
        ("/camera", IMAGE, 1_000, raw_image(1_000, pixels, "mono8")),
        ("/radar", RADAR_SCAN, 2_000, radar_scan(2_000, [(20.0, 0.1, -1.5, 10.0)])),
        ("/can", CAN_FRAME, 3_000, can_frame(3_000, 0x123, b"\\x01\\x02")),
    ])

A message is (topic, message type, log time ns, fields): fields a dict of the message's
fields (nested dicts for nested messages, lists of dicts for message arrays, bytes or lists
for number arrays); fields left out are zero. Bytes in place of the dict are written as the
serialised message, unchecked (a message that does not deserialise). The helpers below give
the fields of the messages the project reads, with header stamp = log time.

ROS 1 bags are serialised with the ROS 1 Noetic store plus radar_msgs (noetic flavour: track
ids are uuid_msgs/UniqueID) and can_msgs; ROS 2 bags with core.io.radar_msgs.typestore().
"""

from __future__ import annotations

import shutil
from collections.abc import Sequence
from functools import cache
from pathlib import Path
from typing import Any, Literal, get_args

import numpy as np
import yaml
from rosbags import rosbag1, rosbag2
from rosbags.interfaces import Nodetype
from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore

from core.io import radar_msgs

Kind = Literal["ros1", "sqlite3", "mcap"]
KINDS: tuple[Kind, ...] = get_args(Kind)
# ROS 1: chunks compressed with lz4 or bz2; ROS 2: zstd of the whole file, of each message,
# or (MCAP only) of each chunk.
Compression = Literal["none", "lz4", "bz2", "zstd-file", "zstd-message", "zstd-chunk"]
COMPRESSIONS: dict[Kind, tuple[Compression, ...]] = {
    "ros1": ("none", "lz4", "bz2"),
    "sqlite3": ("none", "zstd-file", "zstd-message"),
    "mcap": ("none", "zstd-file", "zstd-message", "zstd-chunk"),
}
ROS1_COMPRESSION = {
    "lz4": rosbag1.Writer.CompressionFormat.LZ4,
    "bz2": rosbag1.Writer.CompressionFormat.BZ2,
}
ROS2_COMPRESSION = {
    "zstd-file": CompressionMode.FILE,
    "zstd-message": CompressionMode.MESSAGE,
    "zstd-chunk": CompressionMode.STORAGE,
}
Message = tuple[str, str, int, "dict[str, Any] | bytes"]
NS_PER_S = 1_000_000_000
PLUGINS = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}
METADATA = "metadata.yaml"
METADATA_KEY = "rosbag2_bagfile_information"

UNIQUE_ID = "uuid_msgs/msg/UniqueID"
ROS1_EXTRA_DEFINITIONS = {
    UNIQUE_ID: "uint8[16] uuid",
    **{
        name: text.replace("unique_identifier_msgs/UUID uuid", "uuid_msgs/UniqueID uuid")
        for name, text in radar_msgs.RADAR_MSG_DEFINITIONS.items()
    },
}


@cache
def ros1_typestore() -> Typestore:
    """ROS 1 Noetic with radar_msgs (uuid_msgs/UniqueID track ids) and can_msgs/Frame."""
    store = get_typestore(Stores.ROS1_NOETIC)
    types = {}
    for name, text in ROS1_EXTRA_DEFINITIONS.items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def typestore(kind: Kind) -> Typestore:
    return ros1_typestore() if kind == "ros1" else radar_msgs.typestore()


def bag_path(folder: Path, kind: Kind, name: str = "bag") -> Path:
    """Where a bag of `kind` goes in `folder`: `name.bag` for ROS 1, a folder `name` else."""
    return folder / (f"{name}.bag" if kind == "ros1" else name)


# --- messages ----------------------------------------------------------------------------
def _zero(store: Typestore, desc: Any) -> Any:
    node, spec = desc
    if node == Nodetype.NAME:
        return build(store, spec, {})
    if node == Nodetype.BASE:
        return {"string": "", "bool": False}.get(spec[0], 0)
    (inner, count) = spec
    if inner[0] == Nodetype.BASE and inner[1][0] != "string":
        return np.zeros(count if node == Nodetype.ARRAY else 0, dtype=inner[1][0])
    return [_zero(store, inner) for _ in range(count if node == Nodetype.ARRAY else 0)]


def _value(store: Typestore, desc: Any, value: Any) -> Any:
    node, spec = desc
    if node == Nodetype.NAME:
        return build(store, spec, value) if isinstance(value, dict) else value
    if node == Nodetype.BASE:
        return value
    inner = spec[0]
    if inner[0] == Nodetype.BASE and inner[1][0] != "string":
        if isinstance(value, bytes):
            return np.frombuffer(value, dtype=inner[1][0]).copy()
        return np.asarray(value, dtype=inner[1][0])
    return [_value(store, inner, v) for v in value]


def build(store: Typestore, msgtype: str, fields: dict[str, Any]) -> Any:
    """A message of `msgtype` from a dict of its fields; fields left out are zero."""
    defs = dict(store.fielddefs[msgtype][1])
    if unknown := set(fields) - set(defs):
        raise ValueError(f"{msgtype} has no fields {sorted(unknown)}; it has {list(defs)}")
    return store.types[msgtype](
        **{
            name: _value(store, desc, fields[name]) if name in fields else _zero(store, desc)
            for name, desc in defs.items()
        }
    )


def serialize(
    kind: Kind, msgtype: str, fields: dict[str, Any] | bytes, store: Typestore | None = None
) -> bytes:
    """The message as a bag of `kind` stores it (bytes pass through)."""
    if isinstance(fields, bytes):
        return fields
    store = store or typestore(kind)
    msg = build(store, msgtype, fields)
    if kind == "ros1":
        return bytes(store.serialize_ros1(msg, msgtype))
    return bytes(store.serialize_cdr(msg, msgtype))


def header(t_ns: int, frame_id: str = "") -> dict[str, Any]:
    sec, nanosec = divmod(t_ns, NS_PER_S)
    return {"stamp": {"sec": sec, "nanosec": nanosec}, "frame_id": frame_id}


def raw_image(
    t_ns: int, pixels: np.ndarray, encoding: str, big_endian: bool = False, pad: int = 0
) -> dict[str, Any]:
    """sensor_msgs/Image fields: (H, W) or (H, W, C) pixels, rows padded by `pad` bytes."""
    height, width = pixels.shape[:2]
    dtype = pixels.dtype.newbyteorder(">" if big_endian else "<")
    rows = pixels.astype(dtype).reshape(height, -1).view(np.uint8)
    rows = np.concatenate([rows, np.full((height, pad), 0xEE, np.uint8)], axis=1)
    return {
        "header": header(t_ns, "camera"),
        "height": height,
        "width": width,
        "encoding": encoding,
        "is_bigendian": int(big_endian),
        "step": rows.shape[1],
        "data": rows.ravel(),
    }


def compressed_image(t_ns: int, data: bytes, fmt: str) -> dict[str, Any]:
    """sensor_msgs/CompressedImage fields."""
    return {"header": header(t_ns, "camera"), "format": fmt, "data": data}


def radar_scan(t_ns: int, returns: Sequence[tuple[float, float, float, float]]) -> dict[str, Any]:
    """radar_msgs/RadarScan fields: returns as (range, azimuth, doppler_velocity, amplitude)."""
    names = ("range", "azimuth", "doppler_velocity", "amplitude")
    return {
        "header": header(t_ns, "radar"),
        "returns": [dict(zip(names, r, strict=True)) for r in returns],
    }


def radar_tracks(
    t_ns: int, tracks: Sequence[tuple[bytes, tuple[float, float], tuple[float, float]]]
) -> dict[str, Any]:
    """radar_msgs/RadarTracks fields: tracks as (16-byte uuid, (x, y) m, (vx, vy) m/s)."""
    return {
        "header": header(t_ns, "radar"),
        "tracks": [
            {
                "uuid": {"uuid": uuid},
                "position": {"x": x, "y": y, "z": 0.0},
                "velocity": {"x": vx, "y": vy, "z": 0.0},
            }
            for uuid, (x, y), (vx, vy) in tracks
        ],
    }


def can_frame(
    t_ns: int,
    arbitration_id: int,
    data: bytes,
    *,
    channel: str = "",
    dlc: int | None = None,
    is_extended: bool = False,
    is_rtr: bool = False,
    is_error: bool = False,
) -> dict[str, Any]:
    """can_msgs/Frame fields: data padded to 8 bytes, dlc len(data) unless given."""
    return {
        "header": header(t_ns, channel),
        "id": arbitration_id,
        "is_rtr": is_rtr,
        "is_extended": is_extended,
        "is_error": is_error,
        "dlc": len(data) if dlc is None else dlc,
        "data": data.ljust(8, b"\0"),
    }


# --- bags --------------------------------------------------------------------------------
def write_bag(
    path: Path,
    kind: Kind,
    messages: Sequence[Message],
    store: Typestore | None = None,
    compression: Compression = "none",
) -> Path:
    """Write `messages` into a new bag of `kind` at `path` (ROS 1: a .bag file); returns path.

    One connection per (topic, message type), in order of first appearance. `store` defines
    the message types (default: `typestore(kind)`); `compression` is one of COMPRESSIONS[kind].
    """
    if kind not in KINDS:
        raise ValueError(f"kind: expected one of {KINDS}, got {kind!r}")
    if compression not in COMPRESSIONS[kind]:
        raise ValueError(f"compression: expected one of {COMPRESSIONS[kind]}, got {compression!r}")
    if (kind == "ros1") != (path.suffix == ".bag"):
        raise ValueError(f"path: a ROS 1 bag and only it ends in .bag, got {path} for {kind}")
    store = store or typestore(kind)
    streams = list(dict.fromkeys((topic, msgtype) for topic, msgtype, _, _ in messages))
    writer: rosbag1.Writer | rosbag2.Writer
    if kind == "ros1":
        writer = rosbag1.Writer(path)
        if compression != "none":
            writer.set_compression(ROS1_COMPRESSION[compression])
    else:
        writer = rosbag2.Writer(path, version=9, storage_plugin=PLUGINS[kind])
        if compression != "none":
            writer.set_compression(ROS2_COMPRESSION[compression], CompressionFormat.ZSTD)
    with writer:
        conns = {
            stream: writer.add_connection(stream[0], stream[1], typestore=store)
            for stream in streams
        }
        for topic, msgtype, t_ns, fields in messages:
            writer.write(conns[topic, msgtype], t_ns, serialize(kind, msgtype, fields, store))
    return path


def write_multifile_bag(path: Path, kind: Kind, files: Sequence[Sequence[Message]]) -> Path:
    """A ROS 2 bag folder of several storage files, each holding one of `files`, listed in
    metadata.yaml in the given order (as a split or merged recording has them).

    Every file must hold the same topics, first met in the same order (metadata.yaml lists
    the first file's).
    """
    if kind == "ros1":
        raise ValueError("kind: a ROS 1 bag is one file; expected sqlite3 or mcap")
    streams = [list(dict.fromkeys((m[0], m[1]) for m in part)) for part in files]
    if any(s != streams[0] for s in streams):
        raise ValueError(f"files: expected the same topics in each, got {streams}")
    infos = []
    path.mkdir()
    for k, part in enumerate(files):
        scratch = path / f".part{k}"
        write_bag(scratch, kind, part)
        info = yaml.safe_load((scratch / METADATA).read_text())[METADATA_KEY]
        infos.append(info)
        (name,) = info["relative_file_paths"]
        shutil.move(scratch / name, path / f"part{k}_{name}")
        shutil.rmtree(scratch)
    merged = dict(infos[0])
    merged["relative_file_paths"] = [
        f"part{k}_{n}" for k, i in enumerate(infos) for n in i["relative_file_paths"]
    ]
    merged["files"] = [
        {**f, "path": f"part{k}_{f['path']}"} for k, i in enumerate(infos) for f in i["files"]
    ]
    merged["message_count"] = sum(i["message_count"] for i in infos)
    (path / METADATA).write_text(yaml.safe_dump({METADATA_KEY: merged}, sort_keys=False))
    return path
