"""The Metrics panel's content: the evaluation's tables of hand-made reports whose figures the
tests work out, one error mark per frame with an error, slider labels thinned evenly, and the
marks of real evaluations (a bundled drive's, and the small synthetic drive's with the
evaluation's progress callback)."""

from __future__ import annotations

import dataclasses
from typing import Any

import pytest
from app_fakes import Recordings

from app.metrics import ERROR_KINDS, ErrorMark, error_marks, metrics_markdown, slider_marks
from core.evaluation.codec import empty
from core.evaluation.evaluate import (
    FINAL_PEDESTRIAN_STAGE,
    PEDESTRIAN_STAGES,
    RecordingReport,
    error_listings,
    evaluate_recording,
)
from core.evaluation.objects import BoxScore, RailScore
from core.evaluation.vehicles import FrameStats
from core.io.drive import Drive
from core.io.frame import FrameInput
from core.params import Params
from core.sweep import errors_at


def made(**changes: Any) -> RecordingReport:
    """An empty report of a drive named "drive", with `changes`."""
    base = dataclasses.replace(
        empty(RecordingReport),
        name="drive",
        pedestrians={k: empty(BoxScore) for k in PEDESTRIAN_STAGES},
    )
    return dataclasses.replace(base, **changes)


def errors() -> RecordingReport:
    """Errors on frames 12, 37, 40 and 61; right answers and listings that are not marked
    on frames 50, 70 and 80."""
    r = made(
        vehicles=dataclasses.replace(
            empty(FrameStats),
            fn_at=((37, 5), (37, 3), (40, 2)),
            rfn_at=((12, 8),),
            fp_at=((37, 4),),
            nvo_at=((50, 1),),  # a right answer
        ),
        guardrails=dataclasses.replace(
            empty(RailScore),
            fn_at=((12, 2),),
            fp_at=((61, 6), (61, 4)),
            vehicles_labelled_at=((61, 4),),  # among the FP
        ),
    )
    return dataclasses.replace(
        r,
        pedestrians={
            **r.pedestrians,
            "symmetry": BoxScore(missed_at=((70, 1),)),  # before the fusion filters
            "vehicles": BoxScore(missed_at=((70, 1),)),  # before the radar filter
            "radar": BoxScore(missed_at=((70, 1),)),  # before the HOG verification
            "hog": BoxScore(missed_at=((40, 7),), false_at=((37, 0), (61, 0), (37, 1))),
        },
        tracking=dataclasses.replace(
            r.tracking, vehicles=dataclasses.replace(empty(FrameStats), fn_at=((80, 3),))
        ),
    )


def marks(*frames: int) -> tuple[ErrorMark, ...]:
    return tuple(ErrorMark(f, ("vehicle FN",), f"frame {f}: FN vehicle 1") for f in frames)


# --- the tables -----------------------------------------------------------------------------


def test_the_markdown_holds_the_vehicle_table_of_the_drive_without_listings() -> None:
    r = made(
        frames=20,
        vehicles=dataclasses.replace(empty(FrameStats), rd=6, fn=3, rfn=1, fp=2, nvo=4),
    )
    text = metrics_markdown(r)
    assert text.startswith("**Vehicles, frame by frame (paper 001, section III)**\n")
    # framed = RD + FN + RFN = 10; shares of it; no box IoU, distance error, class or
    # distance of a vehicle in this made-up report
    row = "| drive | 20 | 10 | 6 (60%) | 3 (30%) | 1 (10%) | 2 | 4 | - | - | - | - / - / - | - |"
    assert row in text.splitlines()
    assert "**Guard rails (paper 002): slow radar targets (-: no guard-rail truth)**" in text
    assert "Where the errors are" not in metrics_markdown(errors())


# --- the marks ------------------------------------------------------------------------------


def test_each_frame_with_errors_gets_one_mark_in_frame_order() -> None:
    assert error_marks(errors()) == (
        ErrorMark(
            12,
            ("vehicle RFN", "guard-rail FN"),
            "frame 12: RFN vehicle 8; FN guard rail at radar target 2",
        ),
        ErrorMark(
            37,
            ("vehicle FN", "vehicle FP", "pedestrian FP"),
            "frame 37: FN vehicles 3, 5; FP vehicle from radar target 4; 2 FP pedestrians",
        ),
        ErrorMark(40, ("vehicle FN", "pedestrian FN"), "frame 40: FN vehicle 2; FN pedestrian 7"),
        ErrorMark(
            61,
            ("guard-rail FP", "pedestrian FP"),
            "frame 61: FP guard rail at radar targets 4, 6; FP pedestrian",
        ),
    )


def test_a_marks_label_names_its_codes_in_order() -> None:
    assert [m.label for m in error_marks(errors())] == ["FN+RFN", "FN+FP", "FN", "FP"]
    every = ErrorMark(0, ERROR_KINDS, "")
    assert every.label == "FN+RFN+FP"


def test_marks_can_be_of_chosen_kinds_only() -> None:
    found = error_marks(errors(), kinds=("pedestrian FN", "guard-rail FN"))
    assert found == (
        ErrorMark(12, ("guard-rail FN",), "frame 12: FN guard rail at radar target 2"),
        ErrorMark(40, ("pedestrian FN",), "frame 40: FN pedestrian 7"),
    )
    assert error_marks(errors(), kinds=()) == ()


def test_an_unknown_kind_is_refused_by_name() -> None:
    with pytest.raises(ValueError, match=r"kinds: expected some of vehicle FN, .*; got 'FN'"):
        error_marks(errors(), kinds=("vehicle FN", "FN"))


def test_a_drive_without_errors_has_no_marks() -> None:
    r = made(vehicles=dataclasses.replace(empty(FrameStats), rd=5, nvo_at=((3, 1),)))
    assert error_marks(r) == ()
    assert slider_marks(error_marks(r)) == ()


# --- the slider -----------------------------------------------------------------------------


def test_up_to_the_limit_every_mark_is_labelled() -> None:
    found = error_marks(errors())
    assert slider_marks(found, limit=4) == ((12, "FN+RFN"), (37, "FN+FP"), (40, "FN"), (61, "FP"))


@pytest.mark.parametrize(
    ("n", "limit", "labelled"),
    [
        (10, 5, [1, 3, 5, 7, 9]),  # parts of 2 marks: their middles 1, 3, ...
        (7, 3, [1, 3, 5]),  # parts of 7/3: middles 1.17, 3.5, 5.83
        (5, 1, [2]),
        (5, 0, []),
    ],
)
def test_beyond_the_limit_every_frame_stays_and_labels_are_spread_evenly(
    n: int, limit: int, labelled: list[int]
) -> None:
    frames = [10 * k for k in range(n)]
    out = slider_marks(marks(*frames), limit=limit)
    assert [m if isinstance(m, int) else m[0] for m in out] == frames
    assert [k for k, m in enumerate(out) if isinstance(m, tuple)] == labelled
    assert all(m[1] == "FN" for m in out if isinstance(m, tuple))


def test_a_negative_label_limit_is_refused() -> None:
    with pytest.raises(ValueError, match="limit: expected a number of labels >= 0, got -1"):
        slider_marks(marks(1, 2), limit=-1)


# --- real evaluations -----------------------------------------------------------------------


def listed(r: RecordingReport) -> dict[str, set[int]]:
    """The frames of each kind of error, read from the report's fields."""
    after_filters = r.pedestrians[FINAL_PEDESTRIAN_STAGE]
    at = {
        "vehicle FN": r.vehicles.fn_at,
        "vehicle RFN": r.vehicles.rfn_at,
        "vehicle FP": r.vehicles.fp_at,
        "guard-rail FN": r.guardrails.fn_at,
        "guard-rail FP": r.guardrails.fp_at,
        "pedestrian FN": after_filters.missed_at,
        "pedestrian FP": after_filters.false_at,
    }
    return {kind: {frame for frame, _ in at[kind]} for kind in ERROR_KINDS}


def check_marks(r: RecordingReport) -> None:
    found = error_marks(r)
    assert tuple(e.kind for e in error_listings(r)) == ERROR_KINDS
    # core.sweep counts the errors the evaluation lists, frame by frame
    assert [m.frame for m in found] == sorted(set(errors_at(r))), r.name
    for kind, frames in listed(r).items():
        assert {m.frame for m in found if kind in m.kinds} == frames, (r.name, kind)
    assert all(m.text.startswith(f"frame {m.frame}: ") for m in found)


def test_bundled_drives_are_marked_on_exactly_the_frames_they_list(
    bundled_reports: list[RecordingReport],
) -> None:
    for r in bundled_reports:
        check_marks(r)


def test_evaluation_reports_progress_once_per_frame(recordings: Recordings) -> None:
    path = recordings.root / recordings.name
    calls: list[tuple[int, int]] = []
    r = evaluate_recording(path, Params(), lambda done, n: calls.append((done, n)), timing=False)
    with Drive(path) as drive:
        n = len(drive)
    assert calls == [(done, n) for done in range(1, n + 1)]
    check_marks(r)


def test_evaluation_reads_the_frames_of_an_open_drive_when_given(recordings: Recordings) -> None:
    path = recordings.root / recordings.name

    class Counting(Drive):
        reads = 0

        def frame(self, i: int) -> FrameInput:
            Counting.reads += 1
            return super().frame(i)

    with Counting(path) as drive:
        opened = Counting.reads  # the drive reads a frame on open
        r = evaluate_recording(path, Params(), timing=False, frames=drive)
        assert Counting.reads - opened == len(drive)
        assert r == evaluate_recording(path, Params(), timing=False)

        class Short(Counting):
            def __len__(self) -> int:
                return 2

        with Short(path) as short, pytest.raises(ValueError) as err:
            evaluate_recording(path, Params(), timing=False, frames=short)
        assert str(err.value) == f"frames: expected the {len(drive)} frames of {path}, got 2"
