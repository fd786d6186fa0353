"""Annotation export and import: round trips in every format checked on every frame, one
exported record per format worked out by hand, tracks rebuilt from hand-written files,
bad files named, and random input to the COCO reader."""

from __future__ import annotations

import copy
import json
import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from core.annotation.formats import (
    DECIMALS,
    FORMATS,
    IMPORT_TOLERANCE_PX,
    AnnotationFormatError,
    export_annotations,
    export_command,
    import_annotations,
    import_command,
)
from core.annotation.model import (
    ATTRIBUTES,
    CLASSES,
    Annotations,
    AttributeChange,
    Keyframe,
    Track,
)
from core.io.errors import RecordingError
from tests.core.arbitrary import values

FRAMES = 40
SIZE = (640, 480)
# a corner read back is within one written step of the exported one, and the rebuilt
# keyframes reproduce every read box within IMPORT_TOLERANCE_PX (formats.py)
ROUND_TRIP_PX = 10.0**-DECIMALS + IMPORT_TOLERANCE_PX + 1e-9
CARRIED = {
    "mot": ("occluded",),
    "kitti": ("occluded", "truncated"),
    "coco": ATTRIBUTES,
    "cvat": ATTRIBUTES,
}
SUFFIX = {"mot": "txt", "kitti": "txt", "coco": "json", "cvat": "xml"}


def change(frame: int, name: str, value: bool = True) -> AttributeChange:
    return AttributeChange(frame, name, value)


def scene() -> Annotations:
    """Every class; keyframes at fractional edges, a gap, ends held (one to the last frame),
    a single-frame track on the last frame, attribute changes on and between keyframes and
    one inside a gap."""
    tracks = (
        Track(
            1,
            "car",
            (
                Keyframe(0, (9.5, 19.5, 19.5, 39.5)),
                Keyframe(10, (20.25, 20.0, 40.0, 50.0), distance_m=23.5),
                Keyframe(20, (30.0, 30.0, 50.0, 60.0), interpolate=False),
                Keyframe(26, (100.0, 100.0, 130.0, 140.0)),
            ),
            (
                change(3, "radar_seen"),
                change(5, "occluded"),
                change(15, "occluded", False),
                change(27, "truncated"),
            ),
            end_frame=32,
        ),
        Track(
            2,
            "truck",
            (
                Keyframe(5, (200.125, 150.3, 260.7, 210.9)),
                Keyframe(15, (180.0, 140.0, 250.0, 215.0)),
            ),
            (change(8, "radar_seen"),),
        ),
        Track(3, "van", (Keyframe(39, (300.0, 100.0, 340.0, 130.0)),)),
        Track(
            4,
            "pedestrian",
            (Keyframe(0, (400.0, 200.0, 420.0, 260.0)), Keyframe(39, (430.0, 190.0, 455.0, 265.0))),
            (change(20, "occluded"), change(20, "truncated")),
        ),
        Track(
            5, "cyclist", (Keyframe(12, (50.0, 60.0, 70.0, 100.0)), Keyframe(18, (60, 60, 80, 99)))
        ),
        Track(
            7,
            "guard_rail",
            (Keyframe(0, (-0.5, 200.0, 300.0, 260.0)), Keyframe(30, (-0.5, 210.0, 320.0, 270.0))),
            end_frame=FRAMES - 1,
        ),
        Track(
            9,
            "other_obstacle",
            (
                Keyframe(2, (500.0, 300.0, 520.0, 320.0), interpolate=False),
                Keyframe(3, (501.0, 300.0, 521.0, 320.0)),
                Keyframe(6, (504.0, 301.0, 524.0, 321.0), interpolate=False),
                Keyframe(9, (510.0, 302.0, 530.0, 322.0)),
                Keyframe(12, (512.0, 303.0, 532.0, 323.0)),
            ),
            (change(7, "truncated"),),  # inside the gap 7..8: shown from frame 9
        ),
    )
    return Annotations(tracks, ((0, 19), (25, 39)))


def test_the_scene_has_every_class() -> None:
    assert sorted(t.cls for t in scene().tracks) == sorted(CLASSES)


def assert_same_on_every_frame(
    before: Annotations, after: Annotations, fmt: str, keyframe_flags: bool
) -> None:
    for frame in range(FRAMES):
        old, new = before.shown_at(frame), after.shown_at(frame)
        assert [(s.track_id, s.cls) for s in new] == [(s.track_id, s.cls) for s in old], frame
        for o, n in zip(old, new, strict=True):
            error = max(abs(a - b) for a, b in zip(o.box_px, n.box_px, strict=True))
            assert error <= ROUND_TRIP_PX, (frame, o.track_id, o.box_px, n.box_px)
            expected = {k: (v and k in CARRIED[fmt]) for k, v in o.attributes.items()}
            assert n.attributes == expected, (frame, o.track_id)
            if keyframe_flags:
                track = before.track(o.track_id)
                assert track is not None
                # CVAT makes a frame where an attribute changes a keyframe (formats.py)
                changed = fmt == "cvat" and frame in {c.frame for c in track.changes}
                assert n.keyframe == (o.keyframe or changed), (frame, o.track_id)


@pytest.mark.parametrize("fmt", FORMATS)
def test_round_trip_shows_the_same_boxes_on_every_frame(fmt: str, tmp_path: Path) -> None:
    original = scene()
    path = tmp_path / f"scene.{SUFFIX[fmt]}"
    export_annotations(original, path, fmt, frame_count=FRAMES, image_size_px=SIZE)
    again = import_annotations(path, fmt, frame_count=FRAMES)
    assert_same_on_every_frame(original, again, fmt, keyframe_flags=fmt in ("coco", "cvat"))
    assert [t.id for t in again.tracks] == [t.id for t in original.tracks]
    # the held ends come back as ends
    ends = {t.id: t.end_frame for t in again.tracks}
    assert (ends[1], ends[7]) == (32, FRAMES - 1)
    if fmt in ("coco", "cvat"):
        assert again.annotated == original.annotated
    else:
        assert again.annotated == ((0, FRAMES - 1),)  # mot and kitti cannot say


def test_cvat_keyframes_only_round_trips_too(tmp_path: Path) -> None:
    original = scene()
    path = tmp_path / "scene.xml"
    export_annotations(
        original, path, "cvat", frame_count=FRAMES, image_size_px=SIZE, keyframes_only=True
    )
    boxes = ET.parse(path).getroot().findall("track/box")
    assert all(b.get("keyframe") == "1" for b in boxes)
    again = import_annotations(path, "cvat")  # the task's size from the file
    assert_same_on_every_frame(original, again, "cvat", keyframe_flags=True)
    assert again.annotated == original.annotated


@pytest.mark.parametrize("fmt", ["mot", "kitti", "coco"])
def test_keyframes_only_writes_the_keyframes_alone(fmt: str, tmp_path: Path) -> None:
    original = scene()
    path = tmp_path / f"keys.{SUFFIX[fmt]}"
    export_annotations(
        original, path, fmt, frame_count=FRAMES, image_size_px=SIZE, keyframes_only=True
    )
    keyframes = sum(len(t.keyframes) for t in original.tracks)
    if fmt == "coco":
        records = json.loads(path.read_text())["annotations"]
        assert len(records) == keyframes
        assert all(r["attributes"]["keyframe"] for r in records)
    else:
        assert len(path.read_text().splitlines()) == keyframes
    # read back, the frames between keyframes are gaps: the pedestrian's 0 and 39 only
    pedestrian = import_annotations(path, fmt).track(4)
    assert pedestrian is not None
    assert [f for f in range(FRAMES) if pedestrian.box_at(f) is not None] == [0, 39]


# --- one record per format, worked out by hand ------------------------------------------

# columns 10..19 and rows 20..39: edges u0 = 9.5, u1 = 19.5, v0 = 19.5, v1 = 39.5
COLUMNS_10_TO_19 = (9.5, 19.5, 19.5, 39.5)
TWO_TO_THE_RIGHT = (11.5, 19.5, 21.5, 39.5)


def small() -> Annotations:
    """One car, keyframes on frames 0 and 2 (moving 2 px right), occluded from frame 1, in a
    recording of 4 frames of which 0..2 are annotated."""
    car = Track(
        1,
        "car",
        (Keyframe(0, COLUMNS_10_TO_19), Keyframe(2, TWO_TO_THE_RIGHT)),
        (change(1, "occluded"),),
    )
    return Annotations((car,), ((0, 2),))


def test_mot_lines_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "gt.txt"
    export_annotations(small(), path, "mot", frame_count=4, image_size_px=SIZE)
    # frame 1-based; bb_left = u0 + 0.5 (image from 0); width = 10 columns; class 3 = Car;
    # frame 1 (written 2) is halfway: u0 = 10.5 -> bb_left 11; occluded -> visibility 0.5
    assert path.read_text().splitlines() == [
        "1,1,10.000,20.000,10.000,20.000,1,3,1.000",
        "2,1,11.000,20.000,10.000,20.000,1,3,0.500",
        "3,1,12.000,20.000,10.000,20.000,1,3,0.500",
    ]


def test_kitti_line_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "0000.txt"
    export_annotations(small(), path, "kitti", frame_count=4, image_size_px=SIZE)
    # KITTI's x1..x2 are the first and last pixel columns, 10 and 19; track ids from 0;
    # alpha and rotation_y -10, dimensions -1, location -1000 (unknown)
    first, second, _ = path.read_text().splitlines()
    assert first == "0 0 Car 0 0 -10 10.000 20.000 19.000 39.000 -1 -1 -1 -1000 -1000 -1000 -10"
    assert second == "1 0 Car 0 1 -10 11.000 20.000 20.000 39.000 -1 -1 -1 -1000 -1000 -1000 -10"


def test_coco_records_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "coco.json"
    export_annotations(
        small(), path, "coco", frame_count=4, image_size_px=SIZE, frame_names=list("abcd")
    )
    document = json.loads(path.read_text())
    assert document["annotations"][1] == {
        "id": 2,
        "image_id": 2,
        "category_id": 1,
        "bbox": [11.0, 20.0, 10.0, 20.0],  # halfway: u0 = 10.5 -> x = 11
        "area": 200.0,
        "iscrowd": 0,
        "track_id": 1,
        "attributes": {
            "occluded": True,
            "truncated": False,
            "radar_seen": False,
            "keyframe": False,
        },
    }
    assert document["images"][3] == {
        "id": 4,
        "file_name": "d",
        "width": 640,
        "height": 480,
        "frame_index": 3,
        "annotated": False,
    }
    assert [c["name"] for c in document["categories"]] == list(CLASSES)
    assert document["categories"][0] == {"id": 1, "name": "car", "supercategory": "obstacle"}


def test_cvat_boxes_by_hand(tmp_path: Path) -> None:
    path = tmp_path / "annotations.xml"
    export_annotations(small(), path, "cvat", frame_count=4, image_size_px=SIZE)
    root = ET.parse(path).getroot()
    assert root.findtext("version") == "1.1"
    assert root.findtext("meta/task/size") == "4"
    assert root.findtext("meta/task/original_size/width") == "640"
    assert "fusionscope annotated frames: 0-2" in path.read_text()
    track = root.find("track")
    assert track is not None and track.attrib == {"id": "0", "label": "car", "source": "manual"}
    boxes = track.findall("box")
    # corners with the image from 0: xtl = u0 + 0.5 = 10, xbr = u1 + 0.5 = 20
    assert boxes[0].attrib == {
        "frame": "0",
        "outside": "0",
        "occluded": "0",
        "keyframe": "1",
        "xtl": "10.000",
        "ytl": "20.000",
        "xbr": "20.000",
        "ybr": "40.000",
        "z_order": "0",
    }
    # frame 1: interpolated, but occluded changes there, so a keyframe for CVAT
    assert [boxes[1].get(k) for k in ("frame", "occluded", "keyframe", "xtl", "xbr")] == [
        "1",
        "1",
        "1",
        "11.000",
        "21.000",
    ]
    # after the last keyframe: an outside keyframe holding its box
    assert [boxes[3].get(k) for k in ("frame", "outside", "keyframe", "xtl")] == [
        "3",
        "1",
        "1",
        "12.000",
    ]
    assert {a.get("name"): a.text for a in boxes[0].findall("attribute")} == {
        "truncated": "false",
        "radar_seen": "false",
    }


# --- tracks rebuilt from hand-written files ------------------------------------------------


def test_mot_rebuilds_keyframes_gaps_and_ends(tmp_path: Path) -> None:
    path = tmp_path / "gt.txt"
    # frames 0..2 moving 1 px a frame, frame 3 missing, frames 4..5 standing still
    path.write_text(
        "1,5,10,20,10,20,1,3,1\n"
        "2,5,11,20,10,20,1,3,1\n"
        "3,5,12,20,10,20,1,3,1\n"
        "5,5,12,20,10,20,1,3,1\n"
        "6,5,12,20,10,20,1,3,1\n"
    )
    got = import_annotations(path, "mot")
    assert got == Annotations(
        (
            Track(
                5,
                "car",
                (
                    Keyframe(0, COLUMNS_10_TO_19),
                    Keyframe(2, TWO_TO_THE_RIGHT, interpolate=False),
                    Keyframe(4, TWO_TO_THE_RIGHT),
                ),
                end_frame=5,
            ),
        ),
        ((0, 5),),  # the frames up to the last line: a MOT file is annotated throughout
    )


def test_cvat_shapes_read_as_cvat_shows_them(tmp_path: Path) -> None:
    path = tmp_path / "annotations.xml"
    path.write_text(
        "<annotations><version>1.1</version><meta><task><size>10</size></task></meta>"
        '<track id="2" label="truck">'
        '<box frame="0" outside="0" occluded="0" keyframe="1" xtl="10" ytl="20" xbr="20"'
        ' ybr="40"><attribute name="radar_seen">true</attribute>'
        '<attribute name="colour">red</attribute></box>'
        '<box frame="4" outside="0" occluded="1" keyframe="1" xtl="14" ytl="20" xbr="24"'
        ' ybr="40"/>'
        '<box frame="6" outside="1" occluded="0" keyframe="1" xtl="14" ytl="20" xbr="24"'
        ' ybr="40"/>'
        "</track>"
        '<track id="0" label="pedestrian">'
        '<box frame="7" outside="0" occluded="0" keyframe="1" xtl="0" ytl="0" xbr="5" ybr="9"/>'
        "</track></annotations>"
    )
    got = import_annotations(path, "cvat")
    # frame 5 is interpolated toward the outside box (the same): held, so an end; radar_seen
    # left out on frame 4 keeps its value; the pedestrian holds to the task's end (frame 9)
    truck = Track(
        3,
        "truck",
        (Keyframe(0, COLUMNS_10_TO_19), Keyframe(4, (13.5, 19.5, 23.5, 39.5))),
        (change(0, "radar_seen"), change(4, "occluded")),
        end_frame=5,
    )
    pedestrian = Track(1, "pedestrian", (Keyframe(7, (-0.5, -0.5, 4.5, 8.5)),), end_frame=9)
    assert got == Annotations((pedestrian, truck), ((0, 9),))


def test_kitti_skips_dont_care_and_reads_kitti_types(tmp_path: Path) -> None:
    path = tmp_path / "0001.txt"
    path.write_text(
        "0 -1 DontCare -1 -1 -10 5 5 50 50 -1 -1 -1 -1000 -1000 -1000 -10\n"
        "0 3 Person_sitting 0.3 2 1.2 10 20 19 39 1.7 0.6 0.9 1 1.5 12 0.4\n"
        "3 -1 DontCare -1 -1 -10 5 5 50 50 -1 -1 -1 -1000 -1000 -1000 -10\n"
    )
    got = import_annotations(path, "kitti")
    sitting = Track(
        4,
        "pedestrian",
        (Keyframe(0, COLUMNS_10_TO_19),),
        (change(0, "occluded"), change(0, "truncated")),
    )
    assert got == Annotations((sitting,), ((0, 3),))


# --- bad files ---------------------------------------------------------------------------

MOT_LINE = "1,1,10,20,10,20,1,3,1"
KITTI_LINE = "0 0 Car 0 0 -10 10 20 19 39 -1 -1 -1 -1000 -1000 -1000 -10"


def coco(**changes: Any) -> str:
    document: dict[str, Any] = {
        "images": [{"id": 1, "frame_index": 0, "file_name": "a", "width": 9, "height": 9}],
        "annotations": [
            {"id": 1, "image_id": 1, "category_id": 1, "bbox": [10, 20, 10, 20], "track_id": 1}
        ],
        "categories": [{"id": 1, "name": "car"}],
    }
    for key, value in changes.items():
        section, _, field = key.partition("__")
        if field:
            document[section][0][field] = value
        else:
            document[section] = value
    return json.dumps(document)


def cvat(track: str, size: int = 10) -> str:
    return f"<annotations><meta><task><size>{size}</size></task></meta>{track}</annotations>"


BOX = 'outside="0" occluded="0" keyframe="1" xtl="10" ytl="20" xbr="20" ybr="40"'

BAD = [
    ("mot", "1,1,10,20,10,20,1,3\n", r"line 1: expected 9 comma-separated values .*, got 8"),
    ("mot", "1,1,ten,20,10,20,1,3,1", r"line 1: expected bb_left \(a finite number\), got 'ten'"),
    (
        "mot",
        "1,1,10,20,10,20,1,7,1",
        r"line 1: expected a class id of 1 pedestrian, 2 cyclist, 3 car, 101 truck, .*, got 7",
    ),
    ("mot", "1,1,10,20,0,20,1,3,1", r"line 1: expected a box of positive size"),
    ("mot", "0,1,10,20,10,20,1,3,1", r"line 1: expected a frame >= 1 \(MOT counts from 1\), got 0"),
    ("mot", "1,1,10,20,10,20,0,3,1", r"line 1: expected considered flag 1 .*, got 0"),
    ("mot", "1,1,10,20,10,20,1,3,1.5", r"line 1: expected a visibility in \[0, 1\], got 1.5"),
    (
        "mot",
        f"{MOT_LINE}\n\n{MOT_LINE}\n",
        r"line 3: expected one box per track and frame: track 1 already has one on frame 0 at "
        r"line 1",
    ),
    (
        "mot",
        f"{MOT_LINE}\n2,1,10,20,10,20,1,101,1\n",
        r"line 2: expected one class per track: track 1 is car at line 1, got truck",
    ),
    (
        "mot",
        "4,1,10,20,10,20,1,3,1",
        r"line 1: expected a frame before the recording's end \(2 frames, last 1\), got frame 3",
    ),
    ("kitti", "0 0 Car 0 0 -10 10 20 19 39", r"line 1: expected 17 space-separated values"),
    ("kitti", KITTI_LINE.replace("Car", "Bus"), r"line 1: expected a type of .*, got 'Bus'"),
    ("kitti", KITTI_LINE.replace("Car 0 0", "Car 0 5"), r"line 1: expected occluded 0, 1, 2 or 3"),
    ("kitti", KITTI_LINE.replace(" 19 ", " 8 "), r"line 1: expected a box of positive size"),
    ("kitti", KITTI_LINE.replace("0 0 Car", "0 x Car"), r"line 1: expected track_id .*, got 'x'"),
    ("coco", '{"images": [', r"line 1 column 13: expected JSON"),
    ("coco", "[]", r"top level: expected an object, got list"),
    ("coco", coco(annotations=None), r'top level: expected "annotations" a list, got NoneType'),
    ("coco", coco(categories__name="bus"), r'categories\[0\]: expected "name" one of \(.*\), got'),
    ("coco", coco(annotations__bbox=[1, 2, 3]), r'annotations\[0\]: expected "bbox" \[x, y, '),
    ("coco", coco(annotations__image_id=9), r'annotations\[0\]: expected "image_id" of an image'),
    ("coco", coco(annotations__track_id=0), r'"track_id" a whole number >= 1, got 0'),
    ("coco", coco(images__frame_index=-1), r'images\[0\]: expected "frame_index" a whole number'),
    ("coco", coco(annotations__bbox=[1, 2, "3", 4]), r"annotations\[0\] bbox: expected a number"),
    ("coco", coco(images=[{"id": 1}]), r'images\[0\]: expected the field "frame_index"'),
    ("coco", b"\xff\xfe\x00{".decode("latin-1"), r"expected JSON"),
    ("cvat", "<annotations><track", r"line 1 column 14: expected XML, got unclosed token"),
    ("cvat", "<tasks/>", r"<tasks>: expected the root element <annotations>"),
    (
        "cvat",
        '<?xml version="1.0" encoding="utf.-8"?><annotations/>',
        r"the XML declaration: expected a known encoding",
    ),
    ("cvat", cvat('<track id="0" label="bus"/>'), r'<track id="0">: expected a label of'),
    (
        "cvat",
        cvat('<track id="0" label="car"><box frame="0" outside="0"/></track>'),
        r'<track id="0"> <box frame="0">: expected xtl a finite number, got None',
    ),
    (
        "cvat",
        cvat(
            f'<track id="0" label="car"><box frame="1" {BOX}><attribute name="truncated">yes'
            "</attribute></box></track>"
        ),
        r'<box frame="1">: expected attribute truncated "true" or "false", got \'yes\'',
    ),
    ("cvat", cvat('<image id="0"/>'), r"<image>: expected CVAT for video <track> elements \(a "),
    ("cvat", cvat("", size=5), r"<meta><task><size>: expected the recording's 2 frames, got 5"),
    (
        "cvat",
        cvat(f'<track id="0" label="car"><box frame="0" {BOX}/><box frame="0" {BOX}/></track>'),
        r"expected one box per frame, got frame 0 again",
    ),
    ("cvat", "<annotations/>", r"<meta>: expected <task><size>"),
]


@pytest.mark.parametrize(("fmt", "text", "message"), BAD)
def test_a_bad_file_is_named_with_where_and_what(
    fmt: str, text: str, message: str, tmp_path: Path
) -> None:
    path = tmp_path / f"bad.{SUFFIX[fmt]}"
    path.write_text(text, encoding="latin-1")
    frame_count = 2 if "recording" in message else None
    with pytest.raises(AnnotationFormatError, match=message) as caught:
        import_annotations(path, fmt, frame_count=frame_count)
    assert str(caught.value).startswith(f"{path}: ")
    assert isinstance(caught.value, RecordingError)


def test_a_missing_file_and_bad_arguments(tmp_path: Path) -> None:
    with pytest.raises(AnnotationFormatError, match=r"nothing\.txt: cannot read the file"):
        import_annotations(tmp_path / "nothing.txt", "mot")
    with pytest.raises(ValueError, match=r"fmt: expected one of \('mot', .*\), got 'yolo'"):
        import_annotations(tmp_path / "x", "yolo")
    with pytest.raises(ValueError, match=r"frame_count: expected a number of frames >= 1"):
        import_annotations(tmp_path / "x", "mot", frame_count=0)
    out = tmp_path / "out.txt"
    with pytest.raises(ValueError, match=r"fmt: expected one of .*, got 'yolo'"):
        export_annotations(scene(), out, "yolo", frame_count=FRAMES, image_size_px=SIZE)
    with pytest.raises(
        ValueError,
        match=r"frame_count: expected more frames than the last one annotated \(frame 39, "
        r"track 3\), got 39",
    ):
        export_annotations(scene(), out, "mot", frame_count=39, image_size_px=SIZE)
    with pytest.raises(ValueError, match=r"image_size_px: expected \(width, height\).*\(0, 480\)"):
        export_annotations(scene(), out, "coco", frame_count=FRAMES, image_size_px=(0, 480))
    with pytest.raises(ValueError, match=r"frame_names: expected 40 non-empty names .*, got 2"):
        export_annotations(
            scene(), out, "coco", frame_count=FRAMES, image_size_px=SIZE, frame_names=["a", "b"]
        )
    assert not out.exists()


def test_empty_annotations_round_trip(tmp_path: Path) -> None:
    for fmt in FORMATS:
        path = tmp_path / f"empty.{SUFFIX[fmt]}"
        export_annotations(Annotations(), path, fmt, frame_count=3, image_size_px=SIZE)
        got = import_annotations(path, fmt, frame_count=3)
        assert got.tracks == ()
        assert got.annotated == (() if fmt in ("coco", "cvat") else ((0, 2),))


# --- what the command prints ---------------------------------------------------------------


def test_the_command_says_what_the_format_leaves_out(tmp_path: Path) -> None:
    out = tmp_path / "gt.txt"
    text = export_command(scene(), out, "mot", frame_count=FRAMES, image_size_px=SIZE)
    lines = text.splitlines()
    boxes = len(out.read_text().splitlines())
    assert lines[0] == f"wrote 7 tracks, {boxes} boxes to {out} (mot)"
    assert lines[1:] == [
        "not in mot: the radar distances snapped to keyframes",
        "not in mot: the attributes radar_seen, truncated",
        "not in mot: the annotated frames (0-19, 25-39): an import marks all 40 frames annotated",
    ]
    annotations, said = import_command(out, "mot", frame_count=FRAMES)
    assert said.startswith(f"read 7 tracks ({sum(len(t.keyframes) for t in annotations.tracks)}")
    assert said.endswith("(mot); annotated frames: 0-39")


# --- random input to the COCO reader ------------------------------------------------------

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "200"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)


def valid_coco(tmp: Path) -> dict[str, Any]:
    path = tmp / "valid.json"
    export_annotations(small(), path, "coco", frame_count=4, image_size_px=SIZE)
    document: dict[str, Any] = json.loads(path.read_text())
    return document


def key_paths(tree: Any, prefix: tuple[Any, ...] = ()) -> list[tuple[Any, ...]]:
    """Every key path of a nested JSON value (lists indexed), the root excluded."""
    if isinstance(tree, dict):
        items = list(tree.items())
    elif isinstance(tree, list):
        items = list(enumerate(tree))
    else:
        items = []
    out = []
    for key, value in items:
        out.append((*prefix, key))
        out += key_paths(value, (*prefix, key))
    return out


def read_coco_or_fail_clearly(path: Path) -> None:
    try:
        import_annotations(path, "coco")
        event("read")
    except AnnotationFormatError as err:
        event("AnnotationFormatError")
        assert str(err).startswith(f"{path}: ")


@pytest.mark.fuzz
@FUZZ
@given(data=st.binary(max_size=400) | values.map(lambda v: json.dumps(v).encode()))
def test_any_bytes_to_the_coco_importer(
    data: bytes, tmp_path_factory: pytest.TempPathFactory
) -> None:
    path = tmp_path_factory.mktemp("coco") / "any.json"
    path.write_bytes(data)
    read_coco_or_fail_clearly(path)


@pytest.mark.fuzz
@FUZZ
@given(seed=st.data(), value=values, drop=st.booleans())
def test_one_part_of_a_coco_file_replaced_by_anything(
    seed: st.DataObject, value: Any, drop: bool, tmp_path_factory: pytest.TempPathFactory
) -> None:
    folder = tmp_path_factory.mktemp("coco")
    document = valid_coco(folder)
    where = seed.draw(st.sampled_from(key_paths(document)))
    raw = copy.deepcopy(document)
    parent = raw
    for key in where[:-1]:
        parent = parent[key]
    if drop and isinstance(parent, dict):
        del parent[where[-1]]
    else:
        parent[where[-1]] = value
    path = folder / "changed.json"
    path.write_text(json.dumps(raw))
    read_coco_or_fail_clearly(path)
