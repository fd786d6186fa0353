"""The annotation store: edits saved at once and kept across crashes, conflicting edits of two
tabs refused, files it cannot read never overwritten.

FUZZ_EXAMPLES sets the number of examples of each fuzz test (default: a short run for CI).
"""

from __future__ import annotations

import copy
import errno
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st
from jsonschema import Draft202012Validator
from store_burst import burst_track

import core.annotation.store as store_module
from core.annotation.model import (
    ATTRIBUTES,
    CLASSES,
    Annotations,
    AttributeChange,
    Keyframe,
    Track,
)
from core.annotation.store import (
    GROUNDTRUTH_NAME,
    JOURNAL_NAME,
    AnnotationStore,
    Conflict,
    Edit,
    EditError,
    ReadOnlyError,
    annotations_to_json,
    read_annotations,
    schema,
)
from core.io.errors import RecordingError

REPO_ROOT = Path(__file__).resolve().parents[3]
HIGHWAY_TRUTH = REPO_ROOT / "recordings" / "highway" / GROUNDTRUTH_NAME
BURST = Path(__file__).with_name("store_burst.py")
BURST_TIMEOUT_S = 120.0  # the burst process is killed by then whatever happens

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "150"))
FUZZ = settings(
    max_examples=EXAMPLES,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)

CAR = Track(1, "car", (Keyframe(0, (10.0, 20.0, 50.0, 60.0), 21.5), Keyframe(4, (14, 20, 54, 60))))
VAN = Track(2, "van", (Keyframe(2, (100.0, 30.0, 140.0, 70.0)),))

# groundtruth.json with every field used: spelled out, as a person would read it
VALID: dict[str, Any] = {
    "format_version": 2,
    "kind": "annotations",
    "revision": 5,
    "annotated": [[0, 9], [20, 29]],
    "tracks": [
        {
            "id": 1,
            "class": "car",
            "keyframes": [
                {"frame": 0, "box_px": [10, 20, 50, 60], "distance_m": 21.5, "interpolate": False},
                {"frame": 4, "box_px": [14, 20, 54, 60], "distance_m": None, "interpolate": True},
            ],
            "changes": [{"frame": 2, "name": "occluded", "value": True}],
            "end_frame": 8,
        },
        {
            "id": 3,
            "class": "pedestrian",
            "keyframes": [
                {"frame": 5, "box_px": [1, 2, 3, 4.5], "distance_m": None, "interpolate": True}
            ],
            "changes": [],
            "end_frame": None,
        },
    ],
}
VALID_ANNOTATIONS = Annotations(
    (
        Track(
            1,
            "car",
            (Keyframe(0, (10, 20, 50, 60), 21.5, False), Keyframe(4, (14, 20, 54, 60))),
        )
        .with_attribute(2, "occluded", True)
        .ended_at(8),
        Track(3, "pedestrian", (Keyframe(5, (1, 2, 3, 4.5)),)),
    ),
    ((0, 9), (20, 29)),
)


def write_json(path: Path, value: Any) -> bytes:
    raw = json.dumps(value).encode()
    path.write_bytes(raw)
    return raw


def files(folder: Path) -> dict[str, bytes]:
    """Every file in `folder` with its bytes."""
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def assert_refuses_and_writes_nothing(folder: Path) -> str:
    """Opens `folder`'s store, which must be read-only; an edit is refused, no file changes.
    Returns the reason."""
    before = files(folder)
    with AnnotationStore(folder) as store:
        reason = store.read_only_reason
        assert reason is not None
        with pytest.raises(ReadOnlyError) as refused:
            store.apply(draw(store.revision, Track(9, "car", VAN.keyframes)))
        assert str(refused.value) == reason
    assert files(folder) == before
    return reason


def draw(base: int, track: Track, label: str = "draw") -> Edit:
    return Edit(base, {track.id: track}, (), label)


# --- the file format -------------------------------------------------------------------------
def test_the_schema_is_draft_2020_12_and_names_the_models_classes_and_attributes() -> None:
    Draft202012Validator.check_schema(schema())
    assert schema()["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    defs = schema()["$defs"]
    assert tuple(defs["track"]["properties"]["class"]["enum"]) == CLASSES
    assert tuple(defs["change"]["properties"]["name"]["enum"]) == ATTRIBUTES


def test_a_valid_file_reads_as_its_annotations(tmp_path: Path) -> None:
    write_json(tmp_path / GROUNDTRUTH_NAME, VALID)
    assert read_annotations(tmp_path / GROUNDTRUTH_NAME) == (VALID_ANNOTATIONS, 5)
    with AnnotationStore(tmp_path) as store:
        assert store.read_only_reason is None
        assert store.snapshot() == (VALID_ANNOTATIONS, 5)
    assert annotations_to_json(VALID_ANNOTATIONS, 5) == VALID


def test_an_empty_folder_opens_editable_at_revision_0_and_opening_writes_nothing(
    tmp_path: Path,
) -> None:
    with AnnotationStore(tmp_path) as store:
        assert store.snapshot() == (Annotations(), 0)
        assert store.read_only_reason is None and store.save_error is None
    assert files(tmp_path) == {}


def test_a_missing_folder_is_an_error_naming_it(tmp_path: Path) -> None:
    with pytest.raises(RecordingError, match=r"nowhere: expected a recording folder, got nothing"):
        AnnotationStore(tmp_path / "nowhere")


# --- edits persist ---------------------------------------------------------------------------
def test_edits_persist_across_reopening_and_the_file_follows_the_schema(tmp_path: Path) -> None:
    moved = CAR.with_box(2, (11, 21, 51, 61))
    car = Track(
        1,
        "car",
        (CAR.keyframes[0], Keyframe(2, (11, 21, 51, 61)), CAR.keyframes[1]),
        (AttributeChange(1, "truncated", True),),
    )
    with AnnotationStore(tmp_path) as store:
        assert store.apply(draw(0, CAR, "draw car")) == 1
        assert store.apply(draw(1, VAN, "draw van")) == 2
        assert store.apply(draw(2, moved, "move box")) == 3
        assert store.apply(draw(3, VAN.with_class("truck"), "class")) == 4
        assert store.apply(draw(4, moved.with_attribute(1, "truncated", True), "attribute")) == 5
        assert store.apply(Edit(5, annotated=((0, 9, True),), label="done")) == 6
        assert store.apply(Edit(6, annotated=((3, 4, False),), label="not done")) == 7
        assert store.apply(Edit(7, {2: None}, label="delete van")) == 8
        assert (tmp_path / JOURNAL_NAME).read_bytes() == b""  # every edit is in the file
    expected = Annotations((car,), ((0, 2), (5, 9)))
    with AnnotationStore(tmp_path) as store:
        assert store.snapshot() == (expected, 8)
        assert store.read_only_reason is None
    document = json.loads((tmp_path / GROUNDTRUTH_NAME).read_text())
    Draft202012Validator(schema()).validate(document)
    assert document["revision"] == 8 and document["annotated"] == [[0, 2], [5, 9]]
    assert [t["id"] for t in document["tracks"]] == [1]


def test_the_file_keeps_its_permission_bits(tmp_path: Path) -> None:
    path = tmp_path / GROUNDTRUTH_NAME
    write_json(path, VALID)
    path.chmod(0o640)
    with AnnotationStore(tmp_path) as store:
        store.apply(draw(5, VAN))
    assert path.stat().st_mode & 0o777 == 0o640


def test_edits_from_many_threads_all_land(tmp_path: Path) -> None:
    threads_n, edits_n = 4, 15

    with AnnotationStore(tmp_path) as store:

        def client(track_id: int) -> None:
            base = 0
            for k in range(edits_n):
                track = Track(track_id, "car", (Keyframe(k, (0, 0, 10, 10)),))
                base = store.apply(draw(base, track))

        workers = [threading.Thread(target=client, args=(i + 1,)) for i in range(threads_n)]
        for w in workers:
            w.start()
        for w in workers:
            w.join()
        assert store.revision == threads_n * edits_n
    with AnnotationStore(tmp_path) as store:
        assert store.revision == threads_n * edits_n
        assert [t.keyframes[0].frame for t in store.annotations.tracks] == [edits_n - 1] * threads_n


def test_a_second_store_on_the_same_recording_is_read_only_until_the_first_closes(
    tmp_path: Path,
) -> None:
    with AnnotationStore(tmp_path) as first:
        first.apply(draw(0, CAR))
        reason = assert_refuses_and_writes_nothing(tmp_path)
        assert "another window or program is editing" in reason
        with AnnotationStore(tmp_path, writable=False) as viewer:
            assert viewer.snapshot() == first.snapshot()
            assert viewer.read_only_reason == "opened for reading only"
    with AnnotationStore(tmp_path) as second:
        assert second.read_only_reason is None
        assert second.apply(draw(1, VAN)) == 2


# --- the journal -----------------------------------------------------------------------------
class _Crash(BaseException):
    """The process dies here (nothing after it runs, no except clause catches it)."""


class _CrashingOs:
    """The `os` module as core.annotation.store sees it, dying on its `crash_at`-th call
    that touches the disk (a write dies half done). calls: the names of those calls."""

    STEPS = ("open", "write", "fsync", "fchmod", "close", "replace", "ftruncate", "truncate")

    def __init__(self, crash_at: int | None) -> None:
        self.crash_at = crash_at
        self.calls: list[str] = []

    def __getattr__(self, name: str) -> Any:
        real = getattr(os, name)
        if name not in self.STEPS:
            return real

        def step(*args: Any) -> Any:
            self.calls.append(name)
            if len(self.calls) - 1 == self.crash_at:
                if name == "write":
                    fd, data = args
                    os.write(fd, bytes(data)[: len(data) // 2])
                raise _Crash(name)
            return real(*args)

        return step


def _with_os(monkeypatch: pytest.MonkeyPatch, fake: _CrashingOs) -> None:
    """core.annotation.store uses `fake` as its os module until monkeypatch.undo()."""
    monkeypatch.setattr(store_module, "os", fake)


def test_an_edit_journaled_but_not_saved_is_replayed_on_opening(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    with AnnotationStore(tmp_path) as store:
        store.apply(draw(0, CAR))
        fake = _CrashingOs(crash_at=7)
        _with_os(monkeypatch, fake)
        with pytest.raises(_Crash):
            store.apply(draw(1, VAN, "draw van"))
        monkeypatch.undo()
        # the journal line written and synced, the new file too, and the crash at its rename
        journal, temporary = ["write", "fsync"], ["open", "fchmod", "write", "fsync", "close"]
        assert fake.calls == [*journal, *temporary, "replace"]
    assert read_annotations(tmp_path / GROUNDTRUTH_NAME)[1] == 1  # the crash came before saving
    assert b'"label":"draw van"' in (tmp_path / JOURNAL_NAME).read_bytes()
    with AnnotationStore(tmp_path) as store:
        assert store.snapshot() == (Annotations((CAR, VAN)), 2)
        # replayed edits are known to the conflict check, with their labels
        with pytest.raises(Conflict, match=r"track 2 was changed in revision 2 by 'draw van'"):
            store.apply(draw(1, VAN.with_class("truck")))
    assert read_annotations(tmp_path / GROUNDTRUTH_NAME) == (Annotations((CAR, VAN)), 2)
    assert (tmp_path / JOURNAL_NAME).read_bytes() == b""


def test_a_journal_written_by_hand_is_replayed(tmp_path: Path) -> None:
    write_json(tmp_path / GROUNDTRUTH_NAME, VALID)
    lines = [
        # revision 5 is in the file already: skipped
        {"revision": 5, "base_revision": 4, "label": "old", "tracks": {"3": None}, "annotated": []},
        {
            "revision": 6,
            "base_revision": 5,
            "label": "draw",
            "tracks": {
                "7": {
                    "id": 7,
                    "class": "cyclist",
                    "keyframes": [
                        {"frame": 1, "box_px": [5, 6, 7, 8], "distance_m": 9, "interpolate": True}
                    ],
                    "changes": [],
                    "end_frame": None,
                }
            },
            "annotated": [[10, 19, True]],
        },
        {
            "revision": 7,
            "base_revision": 5,
            "label": "delete",
            "tracks": {"1": None},
            "annotated": [],
        },
    ]
    (tmp_path / JOURNAL_NAME).write_text("".join(json.dumps(e) + "\n" for e in lines))
    cyclist = Track(7, "cyclist", (Keyframe(1, (5, 6, 7, 8), 9.0),))
    expected = Annotations((VALID_ANNOTATIONS.tracks[1], cyclist), ((0, 29),))
    with AnnotationStore(tmp_path, writable=False) as viewer:
        assert viewer.snapshot() == (expected, 7)
    assert (tmp_path / JOURNAL_NAME).stat().st_size > 0  # a viewer writes nothing
    with AnnotationStore(tmp_path) as store:
        assert store.snapshot() == (expected, 7)
    assert read_annotations(tmp_path / GROUNDTRUTH_NAME) == (expected, 7)


def test_a_cut_short_last_journal_line_is_ignored_and_dropped(tmp_path: Path) -> None:
    with AnnotationStore(tmp_path) as store:
        store.apply(draw(0, CAR))
    saved = (tmp_path / GROUNDTRUTH_NAME).read_bytes()
    line = {"revision": 2, "base_revision": 1, "label": "x", "tracks": {"1": None}, "annotated": []}
    text = json.dumps(line) + "\n"
    for cut in (1, len(text) // 2, len(text) - 1):  # the newline is the last byte written
        (tmp_path / JOURNAL_NAME).write_text(text[:cut])
        with AnnotationStore(tmp_path) as store:
            assert store.snapshot() == (Annotations((CAR,)), 1)
            assert store.read_only_reason is None
        assert (tmp_path / JOURNAL_NAME).read_bytes() == b""
        assert (tmp_path / GROUNDTRUTH_NAME).read_bytes() == saved
    # a replayed line followed by a cut one: the cut one goes, the next edit follows
    (tmp_path / JOURNAL_NAME).write_text(text + text[:10])
    with AnnotationStore(tmp_path) as store:
        assert store.snapshot() == (Annotations(), 2)
        assert store.apply(draw(2, VAN)) == 3
    with AnnotationStore(tmp_path) as store:
        assert store.snapshot() == (Annotations((VAN,)), 3)


@pytest.mark.parametrize(
    ("journal", "message"),
    [
        ("not json\n{}\n", r"line 1: not valid JSON"),
        (
            '{"revision": 1, "base_revision": 0, "label": "", "tracks": {"1": {"id": 1}}, '
            '"annotated": []}\n',
            r'line 1: tracks\["1"\]: expected the field "class"',
        ),
        (
            '{"revision": 1, "base_revision": 0, "label": "", "tracks": {"2": null}, '
            '"annotated": []}\n',
            r"line 1: tracks\[2\]: expected a track to delete, there is none",
        ),
        (
            '{"revision": 3, "base_revision": 0, "label": "", "tracks": {}, '
            '"annotated": [[0, 1, true]]}\n',
            r"line 1: revision: expected 1 \(after groundtruth.json's 0",
        ),
    ],
    ids=["not-json", "schema", "model", "revision-gap"],
)
def test_a_damaged_journal_makes_the_store_read_only(
    tmp_path: Path, journal: str, message: str
) -> None:
    (tmp_path / JOURNAL_NAME).write_text(journal)
    reason = assert_refuses_and_writes_nothing(tmp_path)
    assert str(tmp_path / JOURNAL_NAME) in reason
    assert "neither groundtruth.json nor the journal is overwritten" in reason
    assert re.search(message, reason), reason


@pytest.mark.parametrize("first_edit", [True, False], ids=["first-edit", "second-edit"])
def test_a_crash_at_any_step_of_an_edit_leaves_it_all_there_or_not_at_all(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, first_edit: bool
) -> None:
    """Every disk step of an edit in turn dies; reopening shows the edit whole or not at
    all, whole whenever the journal had it on disk, and the store goes on editing. The
    first edit also creates the journal and the file."""
    done = [] if first_edit else [CAR]
    before = (Annotations(tuple(done)), len(done))
    after = (Annotations((*done, VAN)), len(done) + 1)

    def run(folder: Path, crash_at: int | None) -> _CrashingOs:
        folder.mkdir()
        with AnnotationStore(folder) as store:
            for track in done:
                store.apply(draw(store.revision, track))
            fake = _CrashingOs(crash_at)
            _with_os(monkeypatch, fake)
            try:
                store.apply(draw(store.revision, VAN))
            except _Crash:
                pass
            finally:
                monkeypatch.undo()
        return fake

    steps = run(tmp_path / "clean", None).calls
    journal_written = steps.index("write")
    journal_synced = journal_written + 1
    assert steps[journal_synced] == "fsync"
    assert steps[:journal_written] == (["open", "fsync"] if first_edit else [])
    for k in range(len(steps)):
        folder = tmp_path / f"crash-{k}"
        run(folder, k)
        with AnnotationStore(folder) as store:
            state = store.snapshot()
            assert state in (before, after), (k, steps[k])
            if k <= journal_written:  # the journal line not or half written: never acknowledged
                assert state == before, (k, steps[k])
            if k > journal_synced:
                assert state == after, (k, steps[k])
            assert store.read_only_reason is None
            store.apply(draw(state[1], VAN.with_class("truck")))
        with AnnotationStore(folder) as store:
            assert store.annotations.track(2) == VAN.with_class("truck")


def test_a_temporary_file_left_by_a_crash_is_never_read_and_goes(tmp_path: Path) -> None:
    write_json(tmp_path / GROUNDTRUTH_NAME, VALID)
    left = tmp_path / f".{GROUNDTRUTH_NAME}.4242.0.tmp"
    left.write_text('{"format_version": 2, "revi')
    with AnnotationStore(tmp_path) as store:
        assert store.snapshot() == (VALID_ANNOTATIONS, 5)
    assert not left.exists()


def test_a_failed_save_keeps_the_edit_in_the_journal_and_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    def full(*_: Any) -> None:
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    with AnnotationStore(tmp_path) as store:
        store.apply(draw(0, CAR))
        monkeypatch.setattr(store_module, "_replace_atomically", full)
        assert store.apply(draw(1, VAN)) == 2  # acknowledged: it is in the journal
        assert store.save_error is not None
        assert "No space left on device" in store.save_error
        assert "replayed when the recording is opened" in store.save_error
        assert read_annotations(tmp_path / GROUNDTRUTH_NAME)[1] == 1
        monkeypatch.undo()
        assert store.apply(draw(2, VAN.with_class("truck"))) == 3
        assert store.save_error is None
    assert read_annotations(tmp_path / GROUNDTRUTH_NAME) == (
        Annotations((CAR, VAN.with_class("truck"))),
        3,
    )


def test_a_journal_that_cannot_be_written_refuses_the_edit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    class _FullDisk:
        """`os` whose fsync finds the disk full."""

        def __getattr__(self, name: str) -> Any:
            if name == "fsync":

                def fsync(_fd: int) -> None:
                    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

                return fsync
            return getattr(os, name)

    with AnnotationStore(tmp_path) as store:
        store.apply(draw(0, CAR))
        saved = files(tmp_path)
        monkeypatch.setattr(store_module, "os", _FullDisk())
        with pytest.raises(
            EditError, match=r"cannot append the edit: No space .*nothing was saved"
        ):
            store.apply(draw(1, VAN))
        monkeypatch.undo()
        assert store.snapshot() == (Annotations((CAR,)), 1)
        assert files(tmp_path) == saved
        assert store.apply(draw(1, VAN)) == 2


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL")
@pytest.mark.parametrize("kill_after", [1, 12, 40])
def test_a_process_killed_in_a_burst_of_edits_keeps_every_acknowledged_one(
    tmp_path: Path, kill_after: int
) -> None:
    proc = subprocess.Popen(
        [sys.executable, str(BURST), str(tmp_path), "1000000"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    watchdog = threading.Timer(BURST_TIMEOUT_S, proc.kill)
    watchdog.start()
    acknowledged: list[int] = []
    try:
        assert proc.stdout is not None
        while len(acknowledged) < kill_after:
            line = proc.stdout.readline()
            if not line:  # it ended by itself: why
                break
            acknowledged.append(int(line))
        proc.send_signal(signal.SIGKILL)
        out, err = proc.communicate()
    finally:
        watchdog.cancel()
    assert proc.returncode == -signal.SIGKILL, err
    acknowledged += [int(line) for line in out.split("\n")[:-1]]  # after the last: cut short
    assert acknowledged == list(range(1, len(acknowledged) + 1))
    last = acknowledged[-1]
    # the file is whole and holds at least every acknowledged edit
    on_file, file_revision = read_annotations(tmp_path / GROUNDTRUTH_NAME)
    assert file_revision >= last
    assert on_file.tracks == tuple(burst_track(k) for k in range(1, file_revision + 1))
    with AnnotationStore(tmp_path) as store:
        annotations, revision = store.snapshot()
        assert store.read_only_reason is None
    assert file_revision <= revision <= file_revision + 1  # at most one journaled, unsaved
    assert annotations.tracks == tuple(burst_track(k) for k in range(1, revision + 1))
    assert annotations.annotated == ((1, revision),)


# --- two tabs --------------------------------------------------------------------------------
def test_two_tabs_editing_one_track_the_second_is_refused(tmp_path: Path) -> None:
    with AnnotationStore(tmp_path) as store:
        store.apply(draw(0, CAR))
        seen = store.revision  # both tabs show revision 1
        assert store.apply(draw(seen, CAR.with_box(1, (0, 0, 9, 9)), "move box")) == 2
        saved = files(tmp_path)
        with pytest.raises(Conflict) as refused:
            store.apply(draw(seen, CAR.with_class("truck"), "change class"))
        assert str(refused.value) == (
            "track 1 was changed in revision 2 by 'move box', after revision 1 which this edit "
            "(change class) is based on; nothing was saved: reload and redo it"
        )
        assert (refused.value.track_id, refused.value.revision) == (1, 2)
        assert (refused.value.label, refused.value.base_revision) == ("move box", 1)
        assert files(tmp_path) == saved
        assert store.snapshot() == (Annotations((CAR.with_box(1, (0, 0, 9, 9)),)), 2)
        # deleting it from the stale tab is refused too; a tab that saw revision 2 may
        with pytest.raises(Conflict, match="track 1 was changed in revision 2"):
            store.apply(Edit(seen, {1: None}, label="delete"))
        assert store.apply(Edit(2, {1: None}, label="delete")) == 3


def test_two_tabs_editing_different_tracks_both_succeed(tmp_path: Path) -> None:
    with AnnotationStore(tmp_path) as store:
        store.apply(Edit(0, {1: CAR, 2: VAN}, label="draw both"))
        assert store.apply(draw(1, CAR.with_class("truck"), "tab A")) == 2
        assert store.apply(draw(1, VAN.with_class("car"), "tab B")) == 3
        assert store.apply(draw(1, Track(3, "cyclist", VAN.keyframes), "tab B")) == 4
        # a new track id another tab took meanwhile is a conflict
        with pytest.raises(Conflict, match="track 3 was changed in revision 4 by 'tab B'"):
            store.apply(draw(1, Track(3, "pedestrian", VAN.keyframes), "tab A"))
    with AnnotationStore(tmp_path) as store:
        assert [t.cls for t in store.annotations.tracks] == ["truck", "car", "cyclist"]


def test_frames_marked_the_other_way_by_another_tab_conflict(tmp_path: Path) -> None:
    with AnnotationStore(tmp_path) as store:
        store.apply(Edit(0, annotated=((0, 9, True),), label="done 0-9"))
        with pytest.raises(
            Conflict, match=r"frames 0..9 were marked annotated in revision 1 by 'done 0-9'"
        ):
            store.apply(Edit(0, annotated=((5, 5, False),), label="not done 5"))
        assert store.apply(Edit(0, annotated=((5, 12, True),))) == 2  # the same way: fine
        assert store.apply(Edit(0, annotated=((20, 20, False),))) == 3  # elsewhere: fine
        assert store.annotations.annotated == ((0, 12),)


def test_edits_based_on_a_revision_before_the_open_or_after_now_are_refused(
    tmp_path: Path,
) -> None:
    write_json(tmp_path / GROUNDTRUTH_NAME, VALID)
    with AnnotationStore(tmp_path) as store:
        with pytest.raises(Conflict, match=r"based on revision 4, older than revision 5 of"):
            store.apply(draw(4, VAN))
        with pytest.raises(ValueError, match=r"edit.base_revision: expected a revision <= 5 "):
            store.apply(draw(6, VAN))
        with pytest.raises(ValueError, match=r"tracks\[2\]: expected a track to delete"):
            store.apply(Edit(5, {2: None}))
        assert store.revision == 5


# --- edits -----------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"base_revision": -1, "tracks": {1: CAR}}, r"base_revision: expected a revision >= 0"),
        ({"base_revision": 0, "tracks": {2: CAR}}, r"tracks\[2\]: expected the track with id 2"),
        ({"base_revision": 0, "tracks": {1: "car"}}, r"tracks\[1\]: expected a Track or None"),
        ({"base_revision": 0, "annotated": ((5, 4, True),)}, r"annotated\[0\]: expected \(first"),
        ({"base_revision": 0}, r"expected a track or a frame range to change, got none"),
    ],
)
def test_a_bad_edit_is_a_value_error_naming_the_field(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        Edit(**kwargs)


def test_the_inverse_of_an_edit_undoes_it(tmp_path: Path) -> None:
    before = Annotations((CAR,), ((0, 3), (8, 9)))
    edit = Edit(1, {1: None, 2: VAN}, ((2, 8, True),), "delete car, draw van")
    done = edit.applied_to(before)
    assert done == Annotations((VAN,), ((0, 9),))
    undo = edit.inverse(before, 2)
    assert undo.label == "undo delete car, draw van"
    assert dict(undo.tracks) == {1: CAR, 2: None}
    assert undo.applied_to(done) == before
    with AnnotationStore(tmp_path) as store:
        store.apply(Edit(0, {1: CAR}, ((0, 3, True), (8, 9, True))))
        assert store.apply(edit) == 2
        assert store.apply(undo) == 3
        assert store.annotations == before


# --- read-only -------------------------------------------------------------------------------
def _future(path: Path) -> None:
    write_json(path, {**VALID, "format_version": 99, "something": "new"})


def _not_json(path: Path) -> None:
    path.write_text('{"format_version": 2, "kind": "annotations", "revision": ')


def _short_box(path: Path) -> None:
    document = copy.deepcopy(VALID)
    document["tracks"][1]["keyframes"][0]["box_px"] = [1, 2, 3]
    write_json(path, document)


def _huge_box(path: Path) -> None:
    document = copy.deepcopy(VALID)
    document["tracks"][0]["keyframes"][0]["box_px"][2] = 10**400
    write_json(path, document)


def _upside_down_box(path: Path) -> None:
    document = copy.deepcopy(VALID)
    document["tracks"][0]["keyframes"][1]["box_px"] = [14, 60, 54, 20]
    write_json(path, document)


@pytest.mark.parametrize(
    ("write", "message"),
    [
        (
            lambda p: shutil.copy(HIGHWAY_TRUTH, p),
            "holds the generator's exact ground truth (format_version 1, core.io.groundtruth), "
            "not annotations",
        ),
        (
            _future,
            "format_version 99 is newer than this fusionscope reads (2): "
            "update fusionscope to edit it",
        ),
        (_not_json, "not valid JSON: Expecting value: line 1 column 58 (char 57)"),
        (
            _short_box,
            "tracks[1].keyframes[0].box_px: expected exactly 4 items ([u0, v0, u1, v1]: the box "
            "edges, full-image pixels, pixel centres at integers), got 3: [1, 2, 3]",
        ),
        (
            _huge_box,
            "tracks[0].keyframes[0].box_px: expected four finite numbers (u0, v0, u1, v1), "
            "got (10, 20, 1000000",
        ),
        (
            _upside_down_box,
            "tracks[0].keyframes[1].box_px: expected u0 < u1 and v0 < v1, got (14, 60, 54, 20)",
        ),
    ],
    ids=["exact-truth", "future-version", "not-json", "schema", "huge-number", "model"],
)
def test_a_file_that_is_not_editable_annotations_opens_read_only_and_stays(
    tmp_path: Path, write: Callable[[Path], Any], message: str
) -> None:
    path = tmp_path / GROUNDTRUTH_NAME
    write(path)
    reason = assert_refuses_and_writes_nothing(tmp_path)
    assert reason.startswith(f"{path}: {message}")  # a huge number is quoted in full
    assert reason.endswith("; opened read-only: it is never overwritten")
    with AnnotationStore(tmp_path) as store:
        assert store.annotations == Annotations()


def test_the_bundled_recordings_exact_truth_is_never_overwritten() -> None:
    raw = HIGHWAY_TRUTH.read_bytes()
    with tempfile.TemporaryDirectory() as folder:
        shutil.copy(HIGHWAY_TRUTH, Path(folder) / GROUNDTRUTH_NAME)
        assert_refuses_and_writes_nothing(Path(folder))
    assert HIGHWAY_TRUTH.read_bytes() == raw


# --- fuzz ------------------------------------------------------------------------------------
json_values = st.recursive(
    st.none()
    | st.booleans()
    | st.integers(-(2**70), 2**70)
    | st.sampled_from([10**400, -(10**400)])  # JSON integers no float holds
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=12),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=10), inner, max_size=4)
    ),
    max_leaves=16,
)


def _paths(value: Any, at: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    """Every place in a JSON value, as the keys and indexes leading there."""
    yield at
    items = (
        value.items()
        if isinstance(value, dict)
        else enumerate(value)
        if isinstance(value, list)
        else ()
    )
    for key, inner in items:
        yield from _paths(inner, (*at, key))


PLACES = list(_paths(VALID))[1:]
TRACK = VALID["tracks"][0]
TRACK_PLACES = list(_paths(TRACK))[1:]


def _mutated(document: Any, place: tuple[Any, ...], delete: bool, value: Any) -> Any:
    """A copy of `document` with the part at `place` deleted or replaced by `value`."""
    document = copy.deepcopy(document)
    parent = document
    for key in place[:-1]:
        parent = parent[key]
    if delete:
        del parent[place[-1]]
    else:
        parent[place[-1]] = value
    return document


def _opens_or_refuses(raw: bytes, journal: bytes | None = None) -> None:
    """groundtruth.json `raw` (and a journal) opens as annotations, or read-only with a reason
    naming the file, and then is never overwritten."""
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        (folder / GROUNDTRUTH_NAME).write_bytes(raw)
        if journal is not None:
            (folder / JOURNAL_NAME).write_bytes(journal)
        with AnnotationStore(folder) as store:
            read_only = store.read_only_reason is not None
        event("read-only" if read_only else "opens")
        if read_only:
            reason = assert_refuses_and_writes_nothing(folder)
            assert str(folder) in reason
        else:
            with AnnotationStore(folder) as store:
                reread = json.dumps(annotations_to_json(store.annotations, store.revision))
                assert store.snapshot() == store_module.parse_annotations(reread.encode(), "x")


@pytest.mark.fuzz
@FUZZ
@given(json_values)
def test_any_json_as_the_file_opens_or_is_refused_never_overwritten(value: Any) -> None:
    _opens_or_refuses(json.dumps(value).encode())


@pytest.mark.fuzz
@FUZZ
@given(st.sampled_from(PLACES), st.booleans(), json_values)
def test_a_valid_file_with_one_part_changed_opens_or_is_refused(
    place: tuple[Any, ...], delete: bool, value: Any
) -> None:
    _opens_or_refuses(json.dumps(_mutated(VALID, place, delete, value)).encode())


@pytest.mark.fuzz
@FUZZ
@given(st.data())
def test_a_valid_file_cut_or_with_bytes_changed_opens_or_is_refused(data: st.DataObject) -> None:
    raw = bytearray(json.dumps(VALID).encode())
    at = data.draw(st.integers(0, len(raw)))
    if data.draw(st.booleans()):
        del raw[at:]
    else:
        raw[at:at] = data.draw(st.binary(min_size=1, max_size=4))
    _opens_or_refuses(bytes(raw))


@pytest.mark.fuzz
@FUZZ
@given(st.sampled_from(TRACK_PLACES), st.booleans(), json_values)
def test_a_journal_line_with_one_part_changed_replays_or_is_refused(
    place: tuple[Any, ...], delete: bool, value: Any
) -> None:
    """A line putting VALID's first track with one part changed, then a good line."""
    track = _mutated(TRACK, place, delete, value)
    entry = {
        "revision": 6,
        "base_revision": 5,
        "label": "",
        "tracks": {"1": track},
        "annotated": [],
    }
    good = {"revision": 7, "base_revision": 6, "label": "", "tracks": {"3": None}, "annotated": []}
    journal = f"{json.dumps(entry)}\n{json.dumps(good)}\n".encode()
    _opens_or_refuses(json.dumps(VALID).encode(), journal)
