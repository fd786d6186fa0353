"""`fusionscope import bag`: a recording folder from a ROS 1 `.bag` file or a ROS 2 bag
folder (metadata.yaml + .db3/.mcap), copied as is; camera, radar and CAN topics named or found
by message type.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from core.io.bag import CAN_TYPES, RADAR_TYPES, BagReader, CameraStream
from core.io.errors import RecordingError
from core.io.importers.calibration_spec import CalibrationSpec, build_calibration
from core.io.importers.can_mapping import CanSpec, check_can_times, prepare_can
from core.io.importers.finish import (
    ImportOptions,
    ImportResult,
    Progress,
    assumption_notes,
    check_ego_from_radar,
    check_out_dir,
    result,
    staging,
    write_manifest,
)
from core.io.manifest import BagStream, RadarCanSource


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
    bag's images are used at their own size: the calibration must be for that size. With
    `options.ego_from_radar` the speed is estimated from the radar (finish.write_ego_from_radar).
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
            prepared = prepare_can(can_spec, bag_name, conn.topic, lambda: reader.can_frames(conn))
        elif can_spec is not None:
            prepared = prepare_can(can_spec)
        mapped_radar = prepared is not None and prepared.radar is not None
        radar_found, radar_note = _radar_topic(reader, radar_topic, mapped_radar)
    notes.extend([radar_note] if radar_note else [])
    assumptions, assumption_text, more = assumption_notes(options, prepared)
    notes.extend(more)
    notes.extend(prepared.notes if prepared is not None else ())
    size = (first.shape[1], first.shape[0])
    radar: BagStream | RadarCanSource | None = (
        BagStream(bag_name, radar_found) if radar_found is not None else None
    )
    if prepared is not None and prepared.radar is not None:
        radar = prepared.radar
    check_ego_from_radar(options, prepared, radar is not None, bag_path)
    built = build_calibration(calibration, size, size, radar is not None, "the bag's images are")
    notes.extend(built.notes)
    if prepared is not None:
        what = f"{bag_path}: the camera's stamps"
        notes.extend(check_can_times(prepared, times_ns, what, options.max_radar_skew_ms))
    with staging(out_dir) as tmp:
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
        manifest = write_manifest(
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
            notes=notes,
        )
    return result(out_dir, times_ns, size, built.calibration, manifest, notes)
