"""A ROS 2 MCAP bag written in files of bounded size, as rosbag2's `max_bagfile_size` does.

rosbags writes one file per bag. This writer rolls over to a new part when the current one
passes `max_file_bytes`, each part a complete bag written by rosbags, and on close moves the
parts' files into one folder with one `metadata.yaml` listing them all (rosbag2's layout for a
split bag, which rosbags and ROS 2 read as one bag):

    bag/metadata.yaml  bag/bag_0.mcap  bag/bag_1.mcap  ...

Notes:
    A part rolls over between messages, so a file can exceed the limit by one message.
"""

from __future__ import annotations

import shutil
from pathlib import Path
from typing import Any, Literal

import yaml
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.rosbag2.writer import Connection
from rosbags.typesys.store import Typestore

METADATA_NAME = "metadata.yaml"
METADATA_KEY = "rosbag2_bagfile_information"
PARTS_DIR = ".parts"


class SplitBagWriter:
    """Write messages on fixed topics into `path`, starting a new file past `max_file_bytes`."""

    def __init__(
        self,
        path: Path,
        topics: dict[str, str],
        typestore: Typestore,
        max_file_bytes: int,
        version: Literal[8, 9] = 9,
    ) -> None:
        if max_file_bytes <= 0:
            raise ValueError(f"max_file_bytes: expected > 0, got {max_file_bytes}")
        self.path = path
        self.topics = dict(topics)  # topic -> message type
        self.typestore = typestore
        self.max_file_bytes = max_file_bytes
        self.version = version
        self._parts: list[Path] = []
        self._writer: Writer | None = None
        self._connections: dict[str, Connection] = {}
        self._bytes = 0
        self.path.mkdir(parents=True, exist_ok=False)

    def _open_part(self) -> None:
        part = self.path / PARTS_DIR / f"bag_{len(self._parts)}"
        part.parent.mkdir(exist_ok=True)
        writer = Writer(part, version=self.version, storage_plugin=StoragePlugin.MCAP)
        writer.open()
        self._connections = {
            topic: writer.add_connection(topic, msgtype, typestore=self.typestore)
            for topic, msgtype in self.topics.items()
        }
        self._parts.append(part)
        self._writer = writer
        self._bytes = 0

    def write(self, topic: str, t_ns: int, data: bytes | memoryview) -> None:
        """Write one serialized message on one of the topics."""
        if self._writer is None or self._bytes >= self.max_file_bytes:
            if self._writer is not None:
                self._writer.close()
            self._open_part()
        assert self._writer is not None
        self._writer.write(self._connections[topic], t_ns, data)
        self._bytes += len(data)

    def close(self) -> None:
        """Finish the last part and assemble the folder: the files and one metadata.yaml."""
        if self._writer is None:
            self._open_part()  # an empty bag is still a bag
        assert self._writer is not None
        self._writer.close()
        infos = []
        for part in self._parts:
            info = yaml.safe_load((part / METADATA_NAME).read_text(encoding="utf-8"))[METADATA_KEY]
            (name,) = info["relative_file_paths"]
            shutil.move(part / name, self.path / name)
            infos.append(info)
        shutil.rmtree(self.path / PARTS_DIR)
        (self.path / METADATA_NAME).write_text(
            yaml.safe_dump({METADATA_KEY: _merge(infos)}, sort_keys=False), encoding="utf-8"
        )


def _merge(infos: list[dict[str, Any]]) -> dict[str, Any]:
    """One bag's metadata from its parts': files listed in order, counts and times summed."""
    merged = dict(infos[0])
    starts = [i["starting_time"]["nanoseconds_since_epoch"] for i in infos]
    ends = [s + i["duration"]["nanoseconds"] for s, i in zip(starts, infos, strict=True)]
    merged["starting_time"] = {"nanoseconds_since_epoch": min(starts)}
    merged["duration"] = {"nanoseconds": max(ends) - min(starts)}
    merged["message_count"] = sum(i["message_count"] for i in infos)
    merged["relative_file_paths"] = [p for i in infos for p in i["relative_file_paths"]]
    merged["files"] = [f for i in infos for f in i["files"]]
    counts: dict[str, int] = {}
    for info in infos:
        for entry in info["topics_with_message_count"]:
            name = entry["topic_metadata"]["name"]
            counts[name] = counts.get(name, 0) + entry["message_count"]
    merged["topics_with_message_count"] = [
        {**entry, "message_count": counts[entry["topic_metadata"]["name"]]}
        for entry in infos[0]["topics_with_message_count"]
    ]
    return merged
