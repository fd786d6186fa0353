"""`fusionscope annotations export|import` on the Udacity vehicles video as `fusionscope
import` makes it: every format exported and imported into a fresh copy shows the same boxes
on every frame; export reads the store without writing; import refuses to overwrite without
--replace, refuses the generator's truth and names a bad file; and `fusionscope evaluate`
scores the frames marked annotated, and only those."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from core.annotation.formats import DECIMALS, FORMATS, IMPORT_TOLERANCE_PX, export_annotations
from core.annotation.model import Annotations, AttributeChange, Keyframe, Track
from core.annotation.store import (
    GROUNDTRUTH_NAME,
    JOURNAL_NAME,
    AnnotationStore,
    Edit,
    track_to_json,
)
from core.cli import DEFAULT_RECORDINGS, main

FRAMES = 38  # the 1.5 s video at 25 frames/s
SIZE_PX = (640, 360)  # 1280x720 resized to the default width
ANNOTATED = ((0, 19),)
# a corner read back is within one written step, the rebuilt keyframes within
# IMPORT_TOLERANCE_PX of every read box (core/annotation/formats.py)
ROUND_TRIP_PX = 10.0**-DECIMALS + IMPORT_TOLERANCE_PX + 1e-9
SUFFIX = {"mot": "txt", "kitti": "txt", "coco": "json", "cvat": "xml"}
# a file each reader refuses, and a word of its message
MALFORMED = {
    "mot": ("1,1,10.5,20.5,wide,30,1,3,1\n", "line 1"),
    "kitti": ("0 0 Car 0 0\n", "line 1"),
    "coco": ('{"images": [', "JSON"),
    "cvat": ("<annotations><track id='0'>", "XML"),
}


def run(capsys: pytest.CaptureFixture[str], *argv: str | Path) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


@pytest.fixture(scope="module")
def imported(realdata: Path, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The Udacity vehicles video imported at 25 frames/s, never annotated (copied by each
    test that changes it)."""
    out = tmp_path_factory.mktemp("annotations-cli") / "cars"
    video = realdata / "udacity-highway" / "vehicles_1280x720.mp4"
    args = ["import", "video", str(video), str(out), "--fps", "25"]
    args += ["--fx", "579", "--cx", "320", "--cy", "180", "--camera-height-m", "1.3"]
    args += ["--assume-speed-mps", "26"]
    assert main(args) == 0
    return out


def copy_of(imported: Path, folder: Path) -> Path:
    out = folder / "cars"
    shutil.copytree(imported, out)
    return out


@pytest.fixture
def cars(imported: Path, tmp_path: Path) -> Path:
    return copy_of(imported, tmp_path / "a")


@pytest.fixture
def blank(imported: Path, tmp_path: Path) -> Path:
    """A second copy, without annotations."""
    return copy_of(imported, tmp_path / "b")


def scene() -> Annotations:
    """Three tracks on frames 0..19 marked annotated: interpolated between keyframes, a gap
    and an end held after the last keyframe, an occluded change between keyframes (occluded
    is the attribute every format carries)."""
    tracks = (
        Track(
            1,
            "car",
            (
                Keyframe(0, (200.5, 150.5, 260.5, 190.5)),
                Keyframe(10, (190.25, 148.5, 262.75, 195.5)),
                Keyframe(19, (150.5, 140.5, 240.5, 210.5)),
            ),
        ),
        Track(
            2,
            "truck",
            (
                Keyframe(3, (400.5, 120.5, 520.5, 220.5), interpolate=False),
                Keyframe(9, (410.5, 118.5, 530.5, 224.5)),
            ),
            end_frame=14,
        ),
        Track(
            3,
            "pedestrian",
            (Keyframe(5, (30.5, 160.5, 50.5, 220.5)), Keyframe(12, (40.5, 158.5, 62.5, 224.5))),
            (AttributeChange(8, "occluded", True),),
        ),
    )
    return Annotations(tracks, ANNOTATED)


def annotate(recording: Path, annotations: Annotations) -> int:
    """`annotations` put into the recording's store as one edit; the revision it got."""
    with AnnotationStore(recording) as store:
        assert store.read_only_reason is None
        _, revision = store.snapshot()
        tracks: dict[int, Track | None] = {t.id: t for t in annotations.tracks}
        ranges = tuple((a, b, True) for a, b in annotations.annotated)
        return store.apply(Edit(revision, tracks, ranges, "annotate"))


def stored(recording: Path) -> tuple[Annotations, int]:
    with AnnotationStore(recording, writable=False) as store:
        return store.snapshot()


def files(recording: Path) -> dict[str, bytes]:
    """Every file directly in the recording folder, by name, with its bytes."""
    return {p.name: p.read_bytes() for p in sorted(recording.iterdir()) if p.is_file()}


def assert_same_on_every_frame(before: Annotations, after: Annotations) -> None:
    for frame in range(FRAMES):
        old, new = before.shown_at(frame), after.shown_at(frame)
        assert [(s.track_id, s.cls) for s in new] == [(s.track_id, s.cls) for s in old], frame
        for o, n in zip(old, new, strict=True):
            error = max(abs(a - b) for a, b in zip(o.box_px, n.box_px, strict=True))
            assert error <= ROUND_TRIP_PX, (frame, o.track_id, o.box_px, n.box_px)
            assert n.attributes["occluded"] == o.attributes["occluded"], (frame, o.track_id)


# --- export and import --------------------------------------------------------------------


@pytest.mark.parametrize("fmt", FORMATS)
def test_export_then_import_into_a_fresh_copy_shows_the_same_boxes_on_every_frame(
    fmt: str, cars: Path, blank: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    annotate(cars, scene())
    before = files(cars)
    out = tmp_path / f"gt.{SUFFIX[fmt]}"
    code, exported, err = run(capsys, "annotations", "export", cars, out, "--format", fmt)
    assert code == 0, err
    # boxes on frames 0..19, on 3 and 9..14, on 5..12
    assert exported.startswith(f"wrote 3 tracks, {20 + 7 + 8} boxes to {out} ({fmt})\n")
    assert f"from {cars / GROUNDTRUTH_NAME} (revision 1)" in exported
    assert files(cars) == before  # read-only: neither groundtruth.json nor a journal written

    code, printed, err = run(capsys, "annotations", "import", blank, out, "--format", fmt)
    assert code == 0, err
    assert f"{blank / GROUNDTRUTH_NAME}: revision 1: 3 tracks" in printed
    after, revision = stored(blank)
    assert revision == 1  # one edit
    assert_same_on_every_frame(scene(), after)
    if fmt in ("coco", "cvat"):
        assert after.annotated == ANNOTATED
    else:  # these cannot say which frames were annotated: an import marks them all
        assert after.annotated == ((0, FRAMES - 1),)
        assert f"not in {fmt}: the annotated frames (0-19)" in exported


def test_export_replays_the_journal_and_writes_nothing(
    cars: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    annotate(cars, scene())
    van = Track(4, "van", (Keyframe(15, (300.5, 150.5, 340.5, 180.5)),))
    # an edit journaled, groundtruth.json not yet rewritten (a crash in the store's step 3)
    entry = {"revision": 2, "base_revision": 1, "label": "draw", "annotated": []}
    entry["tracks"] = {"4": track_to_json(van)}
    (cars / JOURNAL_NAME).write_text(json.dumps(entry) + "\n")
    before = files(cars)
    out = tmp_path / "gt.xml"
    code, printed, err = run(capsys, "annotations", "export", cars, out, "--format", "cvat")
    assert code == 0, err
    assert printed.startswith(f"wrote 4 tracks, {20 + 7 + 8 + 1} boxes to {out} (cvat)\n")
    assert f"from {cars / GROUNDTRUTH_NAME} (revision 2)" in printed
    assert files(cars) == before


def test_import_with_replace_puts_only_the_files_tracks_and_frames_in_one_edit(
    cars: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    annotate(cars, scene())
    van = Track(
        7,
        "van",
        (Keyframe(30, (300.5, 150.5, 340.5, 180.5)), Keyframe(37, (310.5, 150.5, 352.5, 184.5))),
    )
    new = Annotations((van,), ((30, 37),))
    path = tmp_path / "van.xml"
    export_annotations(new, path, "cvat", frame_count=FRAMES, image_size_px=SIZE_PX)
    code, printed, err = run(
        capsys, "annotations", "import", cars, path, "--format", "cvat", "--replace"
    )
    assert code == 0, err
    assert printed.endswith(
        f"{cars / GROUNDTRUTH_NAME}: revision 2: 1 tracks, 2 keyframes, 8 (30-37) frames marked "
        "annotated; replaced 3 tracks and 20 (0-19) frames marked annotated\n"
    )
    after, revision = stored(cars)
    assert revision == 2
    assert after.annotated == ((30, 37),)
    assert [t.id for t in after.tracks] == [7]
    assert_same_on_every_frame(new, after)
    journal = cars / JOURNAL_NAME
    assert not journal.exists() or journal.read_bytes() == b""  # saved into groundtruth.json


def test_import_into_an_annotated_recording_without_replace_exits_2_naming_replace(
    cars: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    annotate(cars, scene())
    path = tmp_path / "gt.txt"
    export_annotations(scene(), path, "mot", frame_count=FRAMES, image_size_px=SIZE_PX)
    before = files(cars)
    code, printed, err = run(capsys, "annotations", "import", cars, path, "--format", "mot")
    assert code == 2
    assert printed == ""
    assert err.startswith("fusionscope annotations import: --replace: ")
    assert "already holds 3 tracks and 20 (0-19) frames marked annotated" in err
    assert "nothing was imported" in err
    assert files(cars) == before


def test_import_into_the_generators_exact_truth_exits_2_with_the_read_only_reason(
    cars: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shutil.copyfile(DEFAULT_RECORDINGS / "highway" / GROUNDTRUTH_NAME, cars / GROUNDTRUTH_NAME)
    path = tmp_path / "gt.json"
    export_annotations(scene(), path, "coco", frame_count=FRAMES, image_size_px=SIZE_PX)
    before = files(cars)
    for replace in ((), ("--replace",)):
        code, _, err = run(
            capsys, "annotations", "import", cars, path, "--format", "coco", *replace
        )
        assert code == 2
        with AnnotationStore(cars) as store:
            reason = store.read_only_reason
        assert reason is not None and "generator's exact ground truth" in reason
        assert err == f"fusionscope annotations import: {reason}; nothing was imported\n"
        assert files(cars) == before  # the same bytes, no journal


def test_export_of_the_generators_exact_truth_exits_2(
    cars: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    shutil.copyfile(DEFAULT_RECORDINGS / "highway" / GROUNDTRUTH_NAME, cars / GROUNDTRUTH_NAME)
    out = tmp_path / "gt.txt"
    code, _, err = run(capsys, "annotations", "export", cars, out, "--format", "mot")
    assert code == 2
    assert f"{cars / GROUNDTRUTH_NAME}: holds the generator's exact ground truth" in err
    assert err.endswith("; nothing was exported\n")
    assert not out.exists()


@pytest.mark.parametrize("fmt", FORMATS)
def test_a_malformed_import_file_exits_2_naming_the_file(
    fmt: str, cars: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    text, word = MALFORMED[fmt]
    path = tmp_path / f"bad.{SUFFIX[fmt]}"
    path.write_text(text)
    before = files(cars)
    code, printed, err = run(capsys, "annotations", "import", cars, path, "--format", fmt)
    assert code == 2
    assert printed == ""
    assert err.startswith(f"fusionscope annotations import: {path}: ")
    assert word in err
    assert files(cars) == before


def test_a_folder_that_is_not_a_recording_exits_2_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "gt.txt"
    export_annotations(scene(), path, "mot", frame_count=FRAMES, image_size_px=SIZE_PX)
    for action, file in (("export", tmp_path / "out.txt"), ("import", path)):
        code, _, err = run(capsys, "annotations", action, tmp_path, file, "--format", "mot")
        assert code == 2
        assert err.startswith(f"fusionscope annotations {action}: {tmp_path}")
        assert "recording manifest not found" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["gt.txt"]


def test_export_into_a_folder_that_does_not_exist_exits_2_naming_out(
    cars: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "nowhere" / "gt.txt"
    code, _, err = run(capsys, "annotations", "export", cars, out, "--format", "mot")
    assert code == 2
    assert err == (
        f"fusionscope annotations export: OUT {out}: the folder {out.parent} does not exist\n"
    )


# --- the evaluation of an annotated recording ----------------------------------------------


def cars_ahead(annotated: tuple[tuple[int, int], ...]) -> Annotations:
    """Two cars on frames 0..19."""
    tracks = (
        Track(
            1,
            "car",
            (Keyframe(0, (280.5, 170.5, 330.5, 205.5)), Keyframe(19, (275.5, 168.5, 330.5, 208.5))),
        ),
        Track(
            2,
            "car",
            (Keyframe(0, (400.5, 175.5, 470.5, 225.5)), Keyframe(19, (420.5, 176.5, 500.5, 235.5))),
        ),
    )
    return Annotations(tracks, annotated)


def test_evaluate_scores_the_frames_marked_annotated(
    cars: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    annotate(cars, cars_ahead(ANNOTATED))
    code, printed, err = run(capsys, "evaluate", cars, "--format", "json")
    assert code == 0, err
    report = json.loads(printed)
    assert [(r["name"], r["frames"]) for r in report["recordings"]] == [("cars", 20)]
    assert report["total"]["frames"] == 20
    code, printed, err = run(capsys, "evaluate", cars, "--format", "markdown")
    assert code == 0, err
    assert "| recording | frames |" in printed
    assert "\n| cars | 20 |" in printed


def test_evaluate_without_a_frame_marked_annotated_says_why(
    cars: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with AnnotationStore(cars) as store:
        tracks: dict[int, Track | None] = {t.id: t for t in cars_ahead(()).tracks}
        store.apply(Edit(0, tracks, (), "draw"))
    code, printed, err = run(capsys, "evaluate", cars)
    assert code == 2
    assert printed == ""
    assert err.startswith(f"fusionscope evaluate: {cars}: expected ground truth to evaluate")
    assert "annotations count only on frames marked fully annotated" in err
