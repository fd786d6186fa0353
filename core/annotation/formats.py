"""Export and import of a recording's annotations in four common formats.

    export_annotations(annotations, "gt.txt", "mot", frame_count=900, image_size_px=(640, 480))
    annotations = import_annotations("gt.txt", "mot", frame_count=900)

FORMATS:
    mot    MOT Challenge ground truth (MOT16/17 gt/gt.txt): one CSV line per box,
           `frame, id, bb_left, bb_top, bb_width, bb_height, considered, class, visibility`.
    kitti  KITTI tracking labels (label_02/NNNN.txt): one line per box, `frame track_id type
           truncated occluded alpha x1 y1 x2 y2 h w l x y z rotation_y`.
    coco   COCO JSON with track ids: one image per frame, one annotation per box.
    cvat   CVAT for video 1.1 XML: one <track> per track, <box> shapes with keyframe and
           outside flags (CVAT's own keyframe model, the closest to ours).

Boxes. Ours are (u0, v0, u1, v1), the pixel edges with pixel centres at integers: the image
spans -0.5 .. width - 0.5 and a box over columns 10..19 has u0 = 9.5, u1 = 19.5.
    coco, cvat, mot: the image spans 0 .. width (pixel c covers c .. c + 1: COCO's boxes of
        masks, CVAT's canvas; MOT's text does not fix an origin, and CVAT's and Datumaro's MOT
        converters write CVAT's numbers as they are, so this module does too). Columns
        10..19: bb_left = x = xtl = 10, width 10, xbr = 20; so left = u0 + 0.5.
    kitti: x1..x2 are the 0-based indices of the first and last pixel column (the "0-based
        index" of KITTI's readme; KITTI clips boxes to x2 <= width - 1). Columns 10..19:
        x1 = 10, x2 = 19; so x1 = u0 + 0.5 and x2 = u1 - 0.5.
Coordinates are written with DECIMALS digits after the point; a corner read back is within
10**-DECIMALS px of the one written (two roundings for the width-and-height formats).

Classes (ours -> the format's; every class round-trips):
    mot    pedestrian 1 (Pedestrian), cyclist 2 (Person on vehicle: MOT16 annotates the rider
           so, the bicycle apart), car 3 (Car). MOT has no truck, van, guard rail or other
           obstacle: those are written with class ids outside MOT's 1..13, truck 101, van 102,
           guard_rail 103, other_obstacle 104 (an evaluator that accepts only MOT's classes,
           e.g. TrackEval's MOT loader, must be given the file without them).
    kitti  car Car, truck Truck, van Van, pedestrian Pedestrian, cyclist Cyclist,
           other_obstacle Misc (KITTI's own catch-all); guard_rail GuardRail, a type outside
           KITTI's list (KITTI's devkit and TrackEval keep only the types they evaluate, so it
           is skipped like Misc). Import also reads KITTI's Person / Person_sitting as
           pedestrian and Tram as other_obstacle, and skips DontCare regions.
    coco, cvat  the category / label name is our class name.

Attributes:
    mot    occluded as visibility (0.5 when occluded, else 1); truncated and radar_seen are
           not carried (MOT's visibility mixes occlusion and cropping).
    kitti  truncated 0/1, occluded 0 (fully visible) / 1 (partly occluded); radar_seen not
           carried. Import: truncated > 0 is truncated; occluded 1 or 2 is occluded, 0 and
           3 (KITTI's "unknown") are not.
    coco   annotation["attributes"] = {occluded, truncated, radar_seen, keyframe}.
    cvat   occluded is CVAT's own box flag; truncated and radar_seen are <attribute>
           children ("true"/"false"), declared as mutable checkboxes in the labels.
Radar distances snapped to keyframes (Keyframe.distance_m) are carried by no format.

Ids: MOT and COCO write our track id; KITTI and CVAT count tracks from 0 and are written
our id - 1 (read back + 1). MOT frames are 1-based; KITTI, COCO (frame_index) and CVAT
frames are 0-based like ours.

Keyframes, gaps, ends. Every export writes the box on every frame a track is shown
(interpolated frames included); keyframes_only=True writes only the keyframes' frames, and
then mot, kitti and coco files read back with gaps between the keyframes (they cannot say
"interpolated"). coco marks keyframes (attributes.keyframe); cvat marks them keyframe="1",
and also a frame where an attribute changes (CVAT's interpolated shapes copy the attributes
of the shape before them, so a change exists only on a keyframe there). cvat writes an
outside="1" keyframe on the frame after each gap starts and after a track's end (none when
that is past the last frame: CVAT holds the last box to the task's end, as our end_frame
does), so its keyframes_only file is complete.

Import rebuilds sparse tracks: within each run of consecutive frames, `simplify` (model.py)
with IMPORT_TOLERANCE_PX keeps the fewest keyframes, splitting the run at the frames the
file marks as keyframes (coco, cvat) so those stay keyframes; a frame missing between two
boxes makes a gap; a run that ends on a frame not marked a keyframe with the same box as the
keyframe before it becomes an end (end_frame) held from that keyframe. CVAT's sparse shapes
are read with CVAT's semantics (interpolate toward the next shape unless outside, hold the
last one to the task's end) and thinned the same way. Attribute changes are rebuilt from the
values on the boxes, from the frame where a value changes.

Annotated frames (Annotations.annotated):
    coco   every image carries "annotated": true/false; import marks the images not marked
           false (a COCO file of other origin: all of its images).
    cvat   a comment in <meta>: "fusionscope annotated frames: 0-99, 150-199" (or "none");
           without it (a CVAT file of other origin) every frame of the task.
    mot, kitti  cannot carry them; a ground-truth sequence in these formats is annotated
           throughout, so import marks frames 0 .. frame_count - 1 (frame_count given) or
           0 .. the last frame with a line.

Bad files raise AnnotationFormatError (a core.io.errors.RecordingError) naming the file, the
line or record or element, what was expected and what came.

Notes:
    API: the brief's `export_annotations(annotations, path, fmt, *, frame_count,
    image_size_px, frame_names=None, keyframes_only=False)` and `import_annotations(path,
    fmt, *, frame_count=None)`. frame_names are used by coco only (image file_name, default
    "000000.png", ...). The section at the end (export_command, import_command and
    not_carried, which lists what a format leaves out) is what `fusionscope annotations
    export|import` (core/cli.py) runs once the recording and its annotation store are open.
    A file is written to NAME.partial and renamed: whole or not at all.
"""

from __future__ import annotations

import itertools
import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any
from xml.parsers import expat

from core.annotation.model import (
    ATTRIBUTES,
    CLASSES,
    Annotations,
    AttributeChange,
    Box,
    Keyframe,
    Track,
    check_box,
    douglas_peucker,
    interpolate,
    simplify,
)
from core.io.errors import RecordingError

FORMATS = ("mot", "kitti", "coco", "cvat")

# digits written after the point for pixel coordinates
DECIMALS = 3
_STEP_PX = 10.0**-DECIMALS
# A corner read back is within one step of the one written (two half-step roundings for
# left + width), so a read interpolated corner departs from the line through the read
# keyframes by at most two steps; four keep every keyframe the annotator drew apart from
# rounding noise. A box shown after import is within _STEP_PX + this of the exported one.
IMPORT_TOLERANCE_PX = 4 * _STEP_PX

# our image's left edge is at -0.5 (pixel centres at integers); COCO, CVAT and MOT put it
# at 0, KITTI puts the first pixel's centre at 0 (module docstring)
_HALF_PIXEL_PX = 0.5

_MOT_CLASS_IDS = {
    "pedestrian": 1,
    "cyclist": 2,
    "car": 3,
    "truck": 101,
    "van": 102,
    "guard_rail": 103,
    "other_obstacle": 104,
}
_MOT_CONSIDERED = 1  # MOT's 7th ground-truth column: 1 = evaluated, 0 = ignored
_MOT_VISIBILITY_OCCLUDED = 0.5  # visible fraction written for an occluded box
_MOT_VISIBILITY_FREE = 1.0
_MOT_COLUMNS = 9

_KITTI_TYPES = {
    "car": "Car",
    "truck": "Truck",
    "van": "Van",
    "pedestrian": "Pedestrian",
    "cyclist": "Cyclist",
    "guard_rail": "GuardRail",
    "other_obstacle": "Misc",
}
_KITTI_READ_ALSO = {
    "person": "pedestrian",
    "person_sitting": "pedestrian",
    "tram": "other_obstacle",
}
_KITTI_DONT_CARE = "dontcare"
# KITTI's values for what a 2D label does not know (its readme and DontCare lines):
# alpha and rotation_y -10, dimensions -1, location -1000
_KITTI_UNKNOWN_ANGLE = -10
_KITTI_UNKNOWN_SIZE_M = -1
_KITTI_UNKNOWN_LOCATION_M = -1000
_KITTI_OCCLUDED = 1  # "partly occluded" (0 fully visible, 2 largely occluded, 3 unknown)
_KITTI_OCCLUDED_READ = (1, 2)
_KITTI_OCCLUSION_LEVELS = (0, 1, 2, 3)
_KITTI_TRUNCATED = 1
_KITTI_COLUMNS = (17, 18)  # a results file adds a score

_COCO_SUPERCATEGORY = "obstacle"
_COCO_DEFAULT_FILE_NAME = "{frame:06d}.png"

_CVAT_VERSION = "1.1"
_CVAT_TASK_NAME = "fusionscope"
_CVAT_ANNOTATED_MARK = "fusionscope annotated frames:"
_CVAT_ATTRIBUTES = ("truncated", "radar_seen")  # occluded is CVAT's own box flag
_CVAT_TRUE, _CVAT_FALSE = "true", "false"


class AnnotationFormatError(RecordingError):
    """An annotation file that cannot be imported; the message names the file, the line,
    record or element, what was expected and what came."""


def _error(path: Path, where: str, message: str) -> AnnotationFormatError:
    return AnnotationFormatError(f"{path}: {where}: {message}")


# --- export ---------------------------------------------------------------------------


def export_annotations(
    annotations: Annotations,
    path: Path | str,
    fmt: str,
    *,
    frame_count: int,
    image_size_px: tuple[int, int],
    frame_names: Sequence[str] | None = None,
    keyframes_only: bool = False,
) -> None:
    """Write `annotations` to `path` in format `fmt` (one of FORMATS; module docstring).

    frame_count: the recording's number of frames (every track and annotated range lies
    before it); image_size_px: (width, height) of its images in pixels (coco, cvat);
    frame_names: one image file name per frame (coco; default "000000.png", ...);
    keyframes_only: write only keyframes (module docstring). ValueError naming the
    parameter on bad arguments; the file is written whole or not at all on such errors.
    """
    _check_export(annotations, fmt, frame_count, image_size_px, frame_names)
    if fmt == "mot":
        text = _mot_text(annotations, keyframes_only)
    elif fmt == "kitti":
        text = _kitti_text(annotations, keyframes_only)
    elif fmt == "coco":
        text = _coco_text(annotations, frame_count, image_size_px, frame_names, keyframes_only)
    else:
        text = _cvat_text(annotations, frame_count, image_size_px, keyframes_only)
    target = Path(path)
    partial = target.with_name(target.name + ".partial")
    partial.write_text(text, encoding="utf-8")
    partial.replace(target)  # a whole file or none


def _check_export(
    annotations: Annotations,
    fmt: str,
    frame_count: int,
    image_size_px: tuple[int, int],
    frame_names: Sequence[str] | None,
) -> None:
    if fmt not in FORMATS:
        raise ValueError(f"fmt: expected one of {FORMATS}, got {fmt!r}")
    if isinstance(frame_count, bool) or not isinstance(frame_count, int) or frame_count < 1:
        raise ValueError(f"frame_count: expected a number of frames >= 1, got {frame_count!r}")
    size = tuple(image_size_px)
    if len(size) != 2 or not all(
        isinstance(v, int) and not isinstance(v, bool) and v > 0 for v in size
    ):
        raise ValueError(
            f"image_size_px: expected (width, height), two whole numbers > 0, got {image_size_px!r}"
        )
    last = max(
        [(t.last_frame, f"track {t.id}") for t in annotations.tracks]
        + [(b, "the annotated frames") for _, b in annotations.annotated],
        default=None,
        key=lambda frame_what: frame_what[0],
    )
    if last is not None and last[0] >= frame_count:
        raise ValueError(
            f"frame_count: expected more frames than the last one annotated (frame {last[0]}, "
            f"{last[1]}), got {frame_count}"
        )
    if frame_names is not None and (
        len(frame_names) != frame_count or not all(isinstance(n, str) and n for n in frame_names)
    ):
        raise ValueError(
            f"frame_names: expected {frame_count} non-empty names (one per frame), "
            f"got {len(frame_names)} entries"
        )


@dataclass(frozen=True)
class _Row:
    """A track's box on one frame, as exported."""

    frame: int
    box_px: Box
    keyframe: bool
    attributes: dict[str, bool]


def _rows(track: Track, keyframes_only: bool) -> list[_Row]:
    out = []
    for frame in range(track.first_frame, track.last_frame + 1):
        shown = track.box_at(frame)
        if shown is None or (keyframes_only and not shown[1]):
            continue
        out.append(_Row(frame, shown[0], shown[1], track.attributes_at(frame)))
    return out


def _by_frame(annotations: Annotations, keyframes_only: bool) -> list[tuple[Track, _Row]]:
    """Every exported box, by frame then track id."""
    rows = [(t, r) for t in annotations.tracks for r in _rows(t, keyframes_only)]
    return sorted(rows, key=lambda tr: (tr[1].frame, tr[0].id))


def _num(value: float) -> str:
    return f"{value:.{DECIMALS}f}"


def _left_top_width_height(box: Box) -> tuple[float, float, float, float]:
    """(left, top, width, height) with the image spanning 0..width (coco, mot)."""
    u0, v0, u1, v1 = box
    return (u0 + _HALF_PIXEL_PX, v0 + _HALF_PIXEL_PX, u1 - u0, v1 - v0)


def _from_left_top_width_height(x: float, y: float, w: float, h: float) -> Box:
    u0, v0 = x - _HALF_PIXEL_PX, y - _HALF_PIXEL_PX
    return (u0, v0, u0 + w, v0 + h)


def _mot_text(annotations: Annotations, keyframes_only: bool) -> str:
    lines = []
    for track, row in _by_frame(annotations, keyframes_only):
        x, y, w, h = _left_top_width_height(row.box_px)
        visibility = (
            _MOT_VISIBILITY_OCCLUDED if row.attributes["occluded"] else _MOT_VISIBILITY_FREE
        )
        lines.append(
            f"{row.frame + 1},{track.id},{_num(x)},{_num(y)},{_num(w)},{_num(h)},"
            f"{_MOT_CONSIDERED},{_MOT_CLASS_IDS[track.cls]},{_num(visibility)}\n"
        )
    return "".join(lines)


def _kitti_text(annotations: Annotations, keyframes_only: bool) -> str:
    lines = []
    for track, row in _by_frame(annotations, keyframes_only):
        u0, v0, u1, v1 = row.box_px
        truncated = _KITTI_TRUNCATED if row.attributes["truncated"] else 0
        occluded = _KITTI_OCCLUDED if row.attributes["occluded"] else 0
        box = " ".join(
            _num(v)
            for v in (
                u0 + _HALF_PIXEL_PX,
                v0 + _HALF_PIXEL_PX,
                u1 - _HALF_PIXEL_PX,
                v1 - _HALF_PIXEL_PX,
            )
        )
        size = " ".join([str(_KITTI_UNKNOWN_SIZE_M)] * 3)
        location = " ".join([str(_KITTI_UNKNOWN_LOCATION_M)] * 3)
        lines.append(
            f"{row.frame} {track.id - 1} {_KITTI_TYPES[track.cls]} {truncated} {occluded} "
            f"{_KITTI_UNKNOWN_ANGLE} {box} {size} {location} {_KITTI_UNKNOWN_ANGLE}\n"
        )
    return "".join(lines)


def _coco_text(
    annotations: Annotations,
    frame_count: int,
    image_size_px: tuple[int, int],
    frame_names: Sequence[str] | None,
    keyframes_only: bool,
) -> str:
    width, height = image_size_px
    images = [
        {
            "id": frame + 1,
            "file_name": (
                frame_names[frame]
                if frame_names is not None
                else _COCO_DEFAULT_FILE_NAME.format(frame=frame)
            ),
            "width": width,
            "height": height,
            "frame_index": frame,
            "annotated": annotations.is_annotated(frame),
        }
        for frame in range(frame_count)
    ]
    records = []
    for number, (track, row) in enumerate(_by_frame(annotations, keyframes_only), start=1):
        x, y, w, h = (round(v, DECIMALS) for v in _left_top_width_height(row.box_px))
        records.append(
            {
                "id": number,
                "image_id": row.frame + 1,
                "category_id": CLASSES.index(track.cls) + 1,
                "bbox": [x, y, w, h],
                "area": round(w * h, DECIMALS),
                "iscrowd": 0,
                "track_id": track.id,
                "attributes": {**row.attributes, "keyframe": row.keyframe},
            }
        )
    categories = [
        {"id": i + 1, "name": cls, "supercategory": _COCO_SUPERCATEGORY}
        for i, cls in enumerate(CLASSES)
    ]
    document = {
        "info": {"description": "fusionscope annotations"},
        "images": images,
        "annotations": records,
        "categories": categories,
    }
    # one image, annotation or category a line: readable, and json's fast encoder (an
    # indent makes it use the slow one)
    parts = []
    for key, value in document.items():
        if isinstance(value, list):
            rows = ",\n".join(json.dumps(item) for item in value)
            parts.append(f"{json.dumps(key)}: [\n{rows}\n]" if value else f"{json.dumps(key)}: []")
        else:
            parts.append(f"{json.dumps(key)}: {json.dumps(value)}")
    return "{\n" + ",\n".join(parts) + "\n}\n"


def _ranges_text(ranges: Iterable[tuple[int, int]]) -> str:
    parts = [str(a) if a == b else f"{a}-{b}" for a, b in ranges]
    return ", ".join(parts) if parts else "none"


@dataclass(frozen=True)
class _Shape:
    """A CVAT <box>: a track's box on `frame`, or where it leaves the picture (outside)."""

    frame: int
    box_px: Box
    outside: bool
    keyframe: bool
    attributes: dict[str, bool]
    where: str = ""


def _cvat_shapes(track: Track, frame_count: int, keyframes_only: bool) -> list[_Shape]:
    change_frames = {c.frame for c in track.changes}
    out: list[_Shape] = []
    last_box: Box | None = None
    for frame in range(track.first_frame, min(track.last_frame + 2, frame_count)):
        shown = track.box_at(frame) if frame <= track.last_frame else None
        attributes = track.attributes_at(frame)
        if shown is None:
            if last_box is not None:  # it leaves here: an outside keyframe holding its box
                out.append(_Shape(frame, last_box, True, True, attributes))
            last_box = None
            continue
        box, is_keyframe, _ = shown
        keyframe = is_keyframe or frame in change_frames or last_box is None
        if keyframe or not keyframes_only:
            out.append(_Shape(frame, box, False, keyframe, attributes))
        last_box = box
    return out


def _flag(value: bool) -> str:
    return "1" if value else "0"


def _cvat_text(
    annotations: Annotations,
    frame_count: int,
    image_size_px: tuple[int, int],
    keyframes_only: bool,
) -> str:
    root = ET.Element("annotations")
    ET.SubElement(root, "version").text = _CVAT_VERSION
    meta = ET.SubElement(root, "meta")
    task = ET.SubElement(meta, "task")
    for tag, text in (
        ("id", "0"),
        ("name", _CVAT_TASK_NAME),
        ("size", str(frame_count)),
        ("mode", "interpolation"),
        ("overlap", "0"),
        ("flipped", "False"),
        ("start_frame", "0"),
        ("stop_frame", str(frame_count - 1)),
    ):
        ET.SubElement(task, tag).text = text
    labels = ET.SubElement(task, "labels")
    for cls in CLASSES:
        label = ET.SubElement(labels, "label")
        ET.SubElement(label, "name").text = cls
        specs = ET.SubElement(label, "attributes")
        for name in _CVAT_ATTRIBUTES:
            spec = ET.SubElement(specs, "attribute")
            for tag, text in (
                ("name", name),
                ("mutable", "True"),
                ("input_type", "checkbox"),
                ("default_value", _CVAT_FALSE),
                ("values", f"{_CVAT_FALSE}\n{_CVAT_TRUE}"),
            ):
                ET.SubElement(spec, tag).text = text
    size = ET.SubElement(task, "original_size")
    ET.SubElement(size, "width").text = str(image_size_px[0])
    ET.SubElement(size, "height").text = str(image_size_px[1])
    meta.append(ET.Comment(f" {_CVAT_ANNOTATED_MARK} {_ranges_text(annotations.annotated)} "))
    for track in annotations.tracks:
        element = ET.SubElement(
            root, "track", {"id": str(track.id - 1), "label": track.cls, "source": "manual"}
        )
        for shape in _cvat_shapes(track, frame_count, keyframes_only):
            # corners with the image spanning 0..width
            u0, v0, u1, v1 = (v + _HALF_PIXEL_PX for v in shape.box_px)
            box = ET.SubElement(
                element,
                "box",
                {
                    "frame": str(shape.frame),
                    "outside": _flag(shape.outside),
                    "occluded": _flag(shape.attributes["occluded"]),
                    "keyframe": _flag(shape.keyframe),
                    "xtl": _num(u0),
                    "ytl": _num(v0),
                    "xbr": _num(u1),
                    "ybr": _num(v1),
                    "z_order": "0",
                },
            )
            for name in _CVAT_ATTRIBUTES:
                value = shape.attributes[name]
                ET.SubElement(box, "attribute", {"name": name}).text = (
                    _CVAT_TRUE if value else _CVAT_FALSE
                )
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, "unicode") + "\n"


# --- import ---------------------------------------------------------------------------


def import_annotations(
    path: Path | str, fmt: str, *, frame_count: int | None = None
) -> Annotations:
    """The annotations in the file at `path`, format `fmt` (one of FORMATS; module
    docstring). frame_count: the recording's number of frames; a box on a later frame is
    an error, and it sets the frames marked annotated by mot and kitti and the end of
    cvat's last boxes (None: cvat's task size, and the last frame with a box).

    AnnotationFormatError naming the file, the line, record or element and what was
    expected; ValueError naming `fmt` or `frame_count` when those are wrong.
    """
    if fmt not in FORMATS:
        raise ValueError(f"fmt: expected one of {FORMATS}, got {fmt!r}")
    if frame_count is not None and (
        isinstance(frame_count, bool) or not isinstance(frame_count, int) or frame_count < 1
    ):
        raise ValueError(
            f"frame_count: expected a number of frames >= 1 or None, got {frame_count!r}"
        )
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as err:
        raise AnnotationFormatError(f"{path}: cannot read the file: {err.strerror}") from err
    if fmt == "mot":
        return _read_mot(path, data, frame_count)
    if fmt == "kitti":
        return _read_kitti(path, data, frame_count)
    if fmt == "coco":
        return _read_coco(path, data, frame_count)
    return _read_cvat(path, data, frame_count)


@dataclass(frozen=True)
class _Seen:
    """One box read from a file: `frame`, its attributes, whether the file marks it a
    keyframe (True), an interpolated frame (False) or cannot say (None); where: the line
    or record, for messages."""

    frame: int
    box_px: Box
    attributes: dict[str, bool]
    keyframe: bool | None
    where: str


class _Tracks:
    """Boxes read from a file, by track id: one class per track, one box per frame."""

    def __init__(self, path: Path, frame_count: int | None) -> None:
        self.path = path
        self.frame_count = frame_count
        self.classes: dict[int, tuple[str, str]] = {}  # id -> (class, where first seen)
        self.seen: dict[int, dict[int, _Seen]] = {}

    def check_frame(self, frame: int, where: str) -> None:
        if self.frame_count is not None and frame >= self.frame_count:
            raise _error(
                self.path,
                where,
                f"expected a frame before the recording's end ({self.frame_count} frames, "
                f"last {self.frame_count - 1}), got frame {frame}",
            )

    def add(self, track_id: int, cls: str, seen: _Seen) -> None:
        self.check_frame(seen.frame, seen.where)
        first = self.classes.setdefault(track_id, (cls, seen.where))
        if first[0] != cls:
            raise _error(
                self.path,
                seen.where,
                f"expected one class per track: track {track_id} is {first[0]} at "
                f"{first[1]}, got {cls}",
            )
        frames = self.seen.setdefault(track_id, {})
        if seen.frame in frames:
            raise _error(
                self.path,
                seen.where,
                f"expected one box per track and frame: track {track_id} already has one on "
                f"frame {seen.frame} at {frames[seen.frame].where}",
            )
        frames[seen.frame] = seen

    def last_frame(self) -> int | None:
        return max((f for frames in self.seen.values() for f in frames), default=None)

    def annotations(self, annotated: Sequence[tuple[int, int]]) -> Annotations:
        tracks = [
            _dense_track(track_id, self.classes[track_id][0], list(self.seen[track_id].values()))
            for track_id in sorted(self.seen)
        ]
        return Annotations(tuple(tracks), tuple(annotated))


def _runs(seen: Sequence[_Seen]) -> list[list[_Seen]]:
    """`seen` (increasing frames) cut into runs of consecutive frames."""
    runs: list[list[_Seen]] = []
    for s in seen:
        if runs and s.frame == runs[-1][-1].frame + 1:
            runs[-1].append(s)
        else:
            runs.append([s])
    return runs


def _dense_track(track_id: int, cls: str, seen: list[_Seen]) -> Track:
    """A sparse track for boxes on frames (module docstring): `simplify` per run of
    consecutive frames, split at the frames marked keyframes."""
    seen = sorted(seen, key=lambda s: s.frame)
    marked = {s.frame for s in seen if s.keyframe}
    runs = _runs(seen)
    keyframes: list[Keyframe] = []
    for number, run in enumerate(runs):
        cuts = sorted({0, len(run) - 1} | {i for i, s in enumerate(run) if s.keyframe})
        chosen = [Keyframe(run[0].frame, run[0].box_px)]
        for a, b in itertools.pairwise(cuts):
            part = simplify([(s.frame, s.box_px) for s in run[a : b + 1]], IMPORT_TOLERANCE_PX)
            chosen += part[1:]
        if number < len(runs) - 1:
            chosen[-1] = replace(chosen[-1], interpolate=False)  # a gap follows
        keyframes += chosen
    return _finished_track(
        track_id, cls, keyframes, marked, [(s.frame, s.attributes) for s in seen]
    )


def _finished_track(
    track_id: int,
    cls: str,
    keyframes: list[Keyframe],
    marked: set[int],
    attributes: Sequence[tuple[int, dict[str, bool]]],
) -> Track:
    """The track with `keyframes` (a last one not marked, with its predecessor's box and
    interpolated from it, becomes end_frame) and the attribute changes of `attributes`
    ((frame, values) on the frames shown, increasing)."""
    end_frame = None
    if len(keyframes) >= 2:
        before, last = keyframes[-2], keyframes[-1]
        if before.interpolate and last.frame not in marked and last.box_px == before.box_px:
            keyframes = keyframes[:-1]
            end_frame = last.frame
    # the last keyframe's flag is not shown; True as the model's edits expect it
    keyframes[-1] = replace(keyframes[-1], interpolate=True)
    changes = []
    current = dict.fromkeys(ATTRIBUTES, False)
    for frame, values in attributes:
        for name in ATTRIBUTES:
            if values[name] != current[name]:
                changes.append(AttributeChange(frame, name, values[name]))
                current[name] = values[name]
    changes.sort(key=lambda c: (c.frame, c.name))
    return Track(track_id, cls, tuple(keyframes), tuple(changes), end_frame)


def _all_frames(frame_count: int | None, last_frame: int | None) -> tuple[tuple[int, int], ...]:
    """Annotated frames of a file that cannot say (mot, kitti): all of the recording."""
    if frame_count is not None:
        return ((0, frame_count - 1),)
    return () if last_frame is None else ((0, last_frame),)


def _decoded(path: Path, data: bytes) -> str:
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as err:
        raise _error(
            path, f"byte {err.start}", "expected UTF-8 text, got bytes that are not"
        ) from err


def _lines(path: Path, data: bytes) -> Iterable[tuple[str, str]]:
    """(where, text) of each non-blank line."""
    for number, line in enumerate(_decoded(path, data).split("\n"), start=1):
        if line.strip():
            yield f"line {number}", line.strip()


def _int_text(path: Path, where: str, what: str, text: str) -> int:
    """A whole number written as such (or as a float with nothing after the point)."""
    try:
        return int(text)
    except ValueError:
        pass
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not value.is_integer():
        raise _error(path, where, f"expected {what} (a whole number), got {text!r}")
    return int(value)


def _float_text(path: Path, where: str, what: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise _error(path, where, f"expected {what} (a finite number), got {text!r}")
    return value


def _box(path: Path, where: str, box: Box) -> Box:
    try:
        return check_box("box", box)
    except ValueError as err:
        raise _error(path, where, f"expected a box of positive size: {err}") from err


def _read_mot(path: Path, data: bytes, frame_count: int | None) -> Annotations:
    classes = {v: k for k, v in _MOT_CLASS_IDS.items()}
    tracks = _Tracks(path, frame_count)
    for where, line in _lines(path, data):
        cells = [c.strip() for c in line.split(",")]
        if len(cells) != _MOT_COLUMNS:
            raise _error(
                path,
                where,
                f"expected {_MOT_COLUMNS} comma-separated values (frame, id, bb_left, bb_top, "
                f"bb_width, bb_height, considered, class, visibility), got {len(cells)}",
            )
        frame = _int_text(path, where, "frame (1-based)", cells[0]) - 1
        track_id = _int_text(path, where, "id", cells[1])
        x, y, w, h = (
            _float_text(path, where, name, text)
            for name, text in zip(
                ("bb_left", "bb_top", "bb_width", "bb_height"), cells[2:6], strict=True
            )
        )
        considered = _int_text(path, where, "considered flag", cells[6])
        class_id = _int_text(path, where, "class", cells[7])
        visibility = _float_text(path, where, "visibility", cells[8])
        if frame < 0:
            raise _error(path, where, f"expected a frame >= 1 (MOT counts from 1), got {cells[0]}")
        if track_id < 1:
            raise _error(path, where, f"expected an id >= 1, got {cells[1]}")
        if considered != _MOT_CONSIDERED:
            raise _error(
                path,
                where,
                f"expected considered flag {_MOT_CONSIDERED} (ignored boxes are not imported), "
                f"got {cells[6]}",
            )
        if class_id not in classes:
            known = ", ".join(f"{number} {cls}" for number, cls in sorted(classes.items()))
            raise _error(path, where, f"expected a class id of {known}, got {cells[7]}")
        if not 0.0 <= visibility <= 1.0:
            raise _error(path, where, f"expected a visibility in [0, 1], got {cells[8]}")
        box = _box(path, where, _from_left_top_width_height(x, y, w, h))
        attributes = {
            "occluded": visibility < _MOT_VISIBILITY_FREE,
            "truncated": False,
            "radar_seen": False,
        }
        tracks.add(track_id, classes[class_id], _Seen(frame, box, attributes, None, where))
    return tracks.annotations(_all_frames(frame_count, tracks.last_frame()))


def _read_kitti(path: Path, data: bytes, frame_count: int | None) -> Annotations:
    types = {v.lower(): k for k, v in _KITTI_TYPES.items()} | _KITTI_READ_ALSO
    tracks = _Tracks(path, frame_count)
    last_frame: int | None = None
    for where, line in _lines(path, data):
        cells = line.split()
        if len(cells) not in _KITTI_COLUMNS:
            raise _error(
                path,
                where,
                f"expected {_KITTI_COLUMNS[0]} space-separated values (frame track_id type "
                f"truncated occluded alpha x1 y1 x2 y2 h w l x y z rotation_y), "
                f"got {len(cells)}",
            )
        frame = _int_text(path, where, "frame", cells[0])
        track_id = _int_text(path, where, "track_id", cells[1]) + 1
        kind = cells[2].lower()
        truncated = _float_text(path, where, "truncated", cells[3])
        occluded = _int_text(path, where, "occluded", cells[4])
        numbers = [
            _float_text(path, where, name, text)
            for name, text in zip(
                ("alpha", "x1", "y1", "x2", "y2", "h", "w", "l", "x", "y", "z", "rotation_y"),
                cells[5:17],
                strict=True,
            )
        ]
        if frame < 0:
            raise _error(path, where, f"expected a frame >= 0, got {cells[0]}")
        tracks.check_frame(frame, where)
        last_frame = frame if last_frame is None else max(last_frame, frame)
        if kind == _KITTI_DONT_CARE:
            continue  # a region where objects were not labelled, not an object
        if kind not in types:
            raise _error(
                path,
                where,
                f"expected a type of {sorted(_KITTI_TYPES.values())} (or DontCare, Person, "
                f"Person_sitting, Tram), got {cells[2]!r}",
            )
        if track_id < 1:
            raise _error(path, where, f"expected a track_id >= 0, got {cells[1]}")
        if occluded not in _KITTI_OCCLUSION_LEVELS:
            raise _error(path, where, f"expected occluded 0, 1, 2 or 3, got {cells[4]}")
        x1, y1, x2, y2 = numbers[1:5]
        box = _box(
            path,
            where,
            (x1 - _HALF_PIXEL_PX, y1 - _HALF_PIXEL_PX, x2 + _HALF_PIXEL_PX, y2 + _HALF_PIXEL_PX),
        )
        attributes = {
            "occluded": occluded in _KITTI_OCCLUDED_READ,
            "truncated": truncated > 0,
            "radar_seen": False,
        }
        tracks.add(track_id, types[kind], _Seen(frame, box, attributes, None, where))
    return tracks.annotations(_all_frames(frame_count, last_frame))


# COCO: the JSON read with types checked field by field


def _field(path: Path, where: str, record: Any, key: str) -> Any:
    if not isinstance(record, dict):
        raise _error(path, where, f"expected an object, got {type(record).__name__}")
    if key not in record:
        raise _error(path, where, f'expected the field "{key}", got fields {sorted(record)[:8]}')
    return record[key]


def _json_int(path: Path, where: str, key: str, value: Any, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise _error(path, where, f'expected "{key}" a whole number >= {minimum}, got {value!r}')
    return value


def _json_list(path: Path, where: str, key: str, value: Any) -> list[Any]:
    if not isinstance(value, list):
        raise _error(path, where, f'expected "{key}" a list, got {type(value).__name__}')
    return value


def _json_number(path: Path, where: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise _error(path, where, f"expected a number, got {value!r}")
    try:
        number = float(value)
    except OverflowError:
        number = math.inf
    if not math.isfinite(number):
        raise _error(path, where, f"expected a finite number, got {value!r}")
    return number


def _read_coco(path: Path, data: bytes, frame_count: int | None) -> Annotations:
    try:
        document = json.loads(data)
    except json.JSONDecodeError as err:
        raise _error(
            path, f"line {err.lineno} column {err.colno}", f"expected JSON, got {err.msg}"
        ) from err
    except (ValueError, RecursionError) as err:  # not UTF-8; nested deeper than Python goes
        raise _error(path, "the whole file", f"expected JSON, got {err}") from err
    categories: dict[int, str] = {}
    for i, record in enumerate(
        _json_list(
            path, "top level", "categories", _field(path, "top level", document, "categories")
        )
    ):
        where = f"categories[{i}]"
        category_id = _json_int(path, where, "id", _field(path, where, record, "id"), 0)
        name = _field(path, where, record, "name")
        if name not in CLASSES:
            raise _error(path, where, f'expected "name" one of {CLASSES}, got {name!r}')
        if category_id in categories:
            raise _error(path, where, f"expected unique category ids, got {category_id} again")
        categories[category_id] = name
    frames: dict[int, int] = {}  # image id -> frame
    image_frames: set[int] = set()
    not_annotated: set[int] = set()
    tracks = _Tracks(path, frame_count)
    for i, record in enumerate(
        _json_list(path, "top level", "images", _field(path, "top level", document, "images"))
    ):
        where = f"images[{i}]"
        image_id = _json_int(path, where, "id", _field(path, where, record, "id"), 0)
        key = "frame_index"  # TAO's name; CocoVID (mmtracking) says frame_id
        if isinstance(record, dict) and key not in record and "frame_id" in record:
            key = "frame_id"
        frame = _json_int(path, where, key, _field(path, where, record, key), 0)
        if image_id in frames:
            raise _error(path, where, f"expected unique image ids, got {image_id} again")
        if frame in image_frames:
            raise _error(path, where, f"expected one image per frame, got frame {frame} again")
        image_frames.add(frame)
        tracks.check_frame(frame, where)
        annotated = record.get("annotated", True)
        if not isinstance(annotated, bool):
            raise _error(path, where, f'expected "annotated" true or false, got {annotated!r}')
        frames[image_id] = frame
        if not annotated:
            not_annotated.add(frame)
    for i, record in enumerate(
        _json_list(
            path, "top level", "annotations", _field(path, "top level", document, "annotations")
        )
    ):
        where = f"annotations[{i}]"
        image_id = _json_int(path, where, "image_id", _field(path, where, record, "image_id"), 0)
        if image_id not in frames:
            raise _error(path, where, f'expected "image_id" of an image, got {image_id!r}')
        category_id = _json_int(
            path, where, "category_id", _field(path, where, record, "category_id"), 0
        )
        if category_id not in categories:
            raise _error(path, where, f'expected "category_id" of a category, got {category_id!r}')
        track_id = _json_int(path, where, "track_id", _field(path, where, record, "track_id"), 1)
        bbox = _json_list(path, where, "bbox", _field(path, where, record, "bbox"))
        if len(bbox) != 4:
            raise _error(path, where, f'expected "bbox" [x, y, width, height], got {bbox!r}')
        x, y, w, h = (_json_number(path, f"{where} bbox", v) for v in bbox)
        if record.get("iscrowd", 0) not in (0, False):
            raise _error(path, where, f'expected "iscrowd" 0, got {record["iscrowd"]!r}')
        given = record.get("attributes", {})
        if not isinstance(given, dict):
            raise _error(path, where, f'expected "attributes" an object, got {given!r}')
        for name in (*ATTRIBUTES, "keyframe"):
            if not isinstance(given.get(name, False), bool):
                raise _error(
                    path, where, f'expected attribute "{name}" true or false, got {given[name]!r}'
                )
        attributes = {name: given.get(name, False) for name in ATTRIBUTES}
        box = _box(path, where, _from_left_top_width_height(x, y, w, h))
        seen = _Seen(frames[image_id], box, attributes, given.get("keyframe"), where)
        tracks.add(track_id, categories[category_id], seen)
    annotated = sorted(image_frames - not_annotated)
    return tracks.annotations(_ranges(annotated))


def _ranges(frames: Sequence[int]) -> tuple[tuple[int, int], ...]:
    """Sorted frames as inclusive (first, last) ranges."""
    out: list[tuple[int, int]] = []
    for f in frames:
        if out and f == out[-1][1] + 1:
            out[-1] = (out[-1][0], f)
        else:
            out.append((f, f))
    return tuple(out)


# CVAT: the XML read element by element, shapes with CVAT's semantics


def _xml_int(path: Path, where: str, name: str, text: str | None, minimum: int) -> int:
    try:
        value = int(text or "")
    except ValueError:
        value = minimum - 1
    if value < minimum:
        raise _error(path, where, f"expected {name} a whole number >= {minimum}, got {text!r}")
    return value


def _xml_float(path: Path, where: str, name: str, text: str | None) -> float:
    try:
        value = float(text or "")
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise _error(path, where, f"expected {name} a finite number, got {text!r}")
    return value


def _xml_flag(path: Path, where: str, name: str, text: str | None) -> bool:
    if text not in ("0", "1"):
        raise _error(path, where, f'expected {name} "0" or "1", got {text!r}')
    return text == "1"


def _is_comment(element: ET.Element) -> bool:
    return element.tag is ET.Comment


def _read_cvat(path: Path, data: bytes, frame_count: int | None) -> Annotations:
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    try:
        root = ET.fromstring(data, parser=parser)
    except ET.ParseError as err:
        line, column = err.position  # expat counts columns from 0
        reason = expat.ErrorString(err.code)
        raise _error(
            path, f"line {line} column {column + 1}", f"expected XML, got {reason}"
        ) from err
    except LookupError as err:  # the declaration names an encoding Python does not know
        raise _error(path, "the XML declaration", f"expected a known encoding, got {err}") from err
    if root.tag != "annotations":
        raise _error(path, f"<{root.tag}>", "expected the root element <annotations> of CVAT XML")
    size, annotated = _cvat_meta(path, root)
    if size is None and frame_count is None:
        raise _error(
            path,
            "<meta>",
            "expected <task><size> (the number of frames; or give frame_count), got none",
        )
    if size is not None and frame_count is not None and size != frame_count:
        raise _error(
            path,
            "<meta><task><size>",
            f"expected the recording's {frame_count} frames, got {size}",
        )
    count = frame_count if frame_count is not None else size
    assert count is not None  # one of the two is given (checked above)
    tracks: dict[int, Track | None] = {}
    for element in root:
        if _is_comment(element) or element.tag in ("version", "meta"):
            continue
        if element.tag != "track":
            kind = " (a CVAT for images file)" if element.tag == "image" else ""
            raise _error(
                path, f"<{element.tag}>", f"expected CVAT for video <track> elements{kind}"
            )
        track_id, track = _cvat_track(path, element, count)
        if track_id in tracks:
            raise _error(
                path, f'<track id="{track_id - 1}">', "expected unique track ids, got it again"
            )
        tracks[track_id] = track
    if annotated is None:
        annotated = ((0, count - 1),)  # a CVAT task of other origin: annotated throughout
    elif annotated and annotated[-1][1] >= count:
        raise _error(
            path,
            "<meta> comment",
            f"expected annotated frames before frame {count}, got {_ranges_text(annotated)}",
        )
    kept = tuple(t for _, t in sorted(tracks.items()) if t is not None)
    return Annotations(kept, annotated)


def _cvat_meta(
    path: Path, root: ET.Element
) -> tuple[int | None, tuple[tuple[int, int], ...] | None]:
    """(<task> or <job> <size>, the annotated frames of our comment), None where absent."""
    meta = root.find("meta")
    if meta is None:
        return None, None
    size = None
    for holder in ("task", "job"):
        element = meta.find(f"{holder}/size")
        if element is not None:
            size = _xml_int(path, f"<meta><{holder}><size>", "the size", element.text, 1)
            break
    for node in meta.iter():
        text = (node.text or "").strip()
        if _is_comment(node) and text.startswith(_CVAT_ANNOTATED_MARK):
            return size, _parse_ranges(path, text.removeprefix(_CVAT_ANNOTATED_MARK).strip())
    return size, None


def _parse_ranges(path: Path, text: str) -> tuple[tuple[int, int], ...]:
    where = "<meta> comment"
    if text == "none":
        return ()
    ranges = []
    for part in text.split(","):
        first, _, last = part.strip().partition("-")
        a = _xml_int(path, where, "a frame", first, 0)
        ranges.append((a, _xml_int(path, where, "a frame", last, 0) if last else a))
    try:
        return Annotations((), tuple(ranges)).annotated
    except ValueError as err:
        raise _error(path, where, f"expected sorted, disjoint frame ranges: {err}") from err


def _cvat_track(path: Path, element: ET.Element, count: int) -> tuple[int, Track | None]:
    """(our track id, the track; None when it is outside on every shape)."""
    where = f'<track id="{element.get("id")}">'
    track_id = _xml_int(path, where, "id", element.get("id"), 0) + 1
    label = element.get("label")
    if label not in CLASSES:
        raise _error(path, where, f"expected a label of {CLASSES}, got {label!r}")
    read: list[tuple[_Shape, dict[str, bool]]] = []
    for node in element:
        if _is_comment(node):
            continue
        box_where = f'{where} <{node.tag} frame="{node.get("frame")}">'
        if node.tag != "box":
            raise _error(path, box_where, "expected <box> shapes only")
        frame = _xml_int(path, box_where, "frame", node.get("frame"), 0)
        if frame >= count:
            raise _error(
                path, box_where, f"expected a frame before the end ({count} frames), got {frame}"
            )
        corners = [
            _xml_float(path, box_where, name, node.get(name)) - _HALF_PIXEL_PX
            for name in ("xtl", "ytl", "xbr", "ybr")
        ]
        given: dict[str, bool] = {}
        for child in node:
            if _is_comment(child):
                continue
            if child.tag != "attribute":
                raise _error(path, box_where, f"expected <attribute> children, got <{child.tag}>")
            name = child.get("name") or ""
            if name not in _CVAT_ATTRIBUTES:
                continue  # an attribute of a task of other origin
            value = (child.text or "").strip().lower()
            if value not in (_CVAT_TRUE, _CVAT_FALSE):
                raise _error(
                    path, box_where, f'expected attribute {name} "true" or "false", got {value!r}'
                )
            given[name] = value == _CVAT_TRUE
        shape = _Shape(
            frame,
            _box(path, box_where, (corners[0], corners[1], corners[2], corners[3])),
            _xml_flag(path, box_where, "outside", node.get("outside", "0")),
            _xml_flag(path, box_where, "keyframe", node.get("keyframe", "0")),
            {"occluded": _xml_flag(path, box_where, "occluded", node.get("occluded", "0"))},
            box_where,
        )
        read.append((shape, given))
    read.sort(key=lambda sg: sg[0].frame)
    shapes = []
    carried = dict.fromkeys(_CVAT_ATTRIBUTES, False)
    for i, (shape, given) in enumerate(read):
        if i > 0 and read[i - 1][0].frame == shape.frame:
            raise _error(
                path, shape.where, f"expected one box per frame, got frame {shape.frame} again"
            )
        carried = carried | given  # CVAT: an attribute a shape leaves out keeps its value
        shapes.append(replace(shape, attributes={**shape.attributes, **carried}))
    return track_id, _sparse_track(track_id, label, shapes, count)


def _sparse_track(track_id: int, cls: str, shapes: Sequence[_Shape], count: int) -> Track | None:
    """The track CVAT shows for `shapes` (increasing frames) in a task of `count` frames:
    interpolated from a shape toward the next unless it is outside, the last held to the
    task's end; then thinned (module docstring)."""
    keys: list[Keyframe] = []
    marked: set[int] = set()
    attributes = []
    for i, shape in enumerate(shapes):
        if shape.outside:
            continue
        after = shapes[i + 1] if i + 1 < len(shapes) else None
        here = Keyframe(shape.frame, shape.box_px)
        if shape.keyframe:
            marked.add(shape.frame)
        attributes.append((shape.frame, shape.attributes))
        if after is None:
            keys.append(here)
            if count - 1 > shape.frame:
                keys.append(Keyframe(count - 1, shape.box_px))  # held to the task's end
        elif not after.outside:
            keys.append(here)
        elif after.frame == shape.frame + 1:
            keys.append(replace(here, interpolate=False))
        else:  # shown up to the frame before the outside shape, moving toward its box
            last = after.frame - 1
            toward = interpolate(here, Keyframe(after.frame, after.box_px), last)
            keys += [here, Keyframe(last, toward, interpolate=False)]
    if not keys:
        return None
    return _finished_track(track_id, cls, _thinned(keys, marked), marked, attributes)


def _thinned(keys: list[Keyframe], marked: set[int]) -> list[Keyframe]:
    """`keys` without those that interpolation between the kept ones reproduces within
    IMPORT_TOLERANCE_PX: Douglas-Peucker over the given keyframes (`simplify` needs a box
    on every frame; the error between two piecewise-linear tracks peaks at their
    breakpoints, so checking the given keyframes is enough). Marked frames and the ends of
    each interpolated span stay."""
    keep: set[int] = set()
    start = 0
    for end, key in enumerate(keys):
        if key.interpolate and end < len(keys) - 1:
            continue
        span = keys[start : end + 1]
        cuts = sorted({0, len(span) - 1} | {i for i, k in enumerate(span) if k.frame in marked})
        for a, b in itertools.pairwise(cuts):
            keep |= {start + i for i in douglas_peucker(span, IMPORT_TOLERANCE_PX, a, b)}
        keep |= {start + c for c in cuts}
        start = end + 1
    return [keys[i] for i in sorted(keep)]


def not_carried(
    annotations: Annotations, fmt: str, *, frame_count: int, keyframes_only: bool = False
) -> tuple[str, ...]:
    """What an export of `annotations` to `fmt` leaves out, in words (empty: nothing)."""
    out = []
    if any(k.distance_m is not None for t in annotations.tracks for k in t.keyframes):
        out.append("the radar distances snapped to keyframes")
    carried = {"mot": ("occluded",), "kitti": ("occluded", "truncated")}.get(fmt, ATTRIBUTES)
    lost = sorted({c.name for t in annotations.tracks for c in t.changes if c.name not in carried})
    if lost:
        out.append(f"the attributes {', '.join(lost)}")
    if fmt in ("mot", "kitti") and annotations.annotated != ((0, frame_count - 1),):
        out.append(
            f"the annotated frames ({_ranges_text(annotations.annotated)}): an import marks "
            f"all {frame_count} frames annotated"
        )
    if keyframes_only and fmt != "cvat":
        out.append("the frames between keyframes: an import reads them as gaps")
    return tuple(out)


def export_command(
    annotations: Annotations,
    out: Path | str,
    fmt: str,
    *,
    frame_count: int,
    image_size_px: tuple[int, int],
    keyframes_only: bool = False,
) -> str:
    """`fusionscope annotations export`: export_annotations, and the lines it prints (what
    was written, what `fmt` leaves out)."""
    export_annotations(
        annotations,
        out,
        fmt,
        frame_count=frame_count,
        image_size_px=image_size_px,
        keyframes_only=keyframes_only,
    )
    boxes = sum(len(_rows(t, keyframes_only)) for t in annotations.tracks)
    text = f"wrote {len(annotations.tracks)} tracks, {boxes} boxes to {out} ({fmt})"
    lost = not_carried(annotations, fmt, frame_count=frame_count, keyframes_only=keyframes_only)
    return text + "".join(f"\nnot in {fmt}: {item}" for item in lost)


def import_command(path: Path | str, fmt: str, *, frame_count: int) -> tuple[Annotations, str]:
    """`fusionscope annotations import`: import_annotations for a recording of
    `frame_count` frames, and the line it prints."""
    annotations = import_annotations(path, fmt, frame_count=frame_count)
    keyframes = sum(len(t.keyframes) for t in annotations.tracks)
    text = (
        f"read {len(annotations.tracks)} tracks ({keyframes} keyframes) from {path} ({fmt}); "
        f"annotated frames: {_ranges_text(annotations.annotated)}"
    )
    return annotations, text
