"""Annotation tracks: interpolation worked out by hand, edits, attributes from a frame on,
keyframe simplification, and bad input named."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from core.annotation.model import (
    Annotations,
    AttributeChange,
    Keyframe,
    Track,
    interpolate,
    simplify,
)

A = (10.0, 20.0, 30.0, 60.0)
B = (20.0, 30.0, 60.0, 100.0)


def car(*keyframes: Keyframe, end: int | None = None) -> Track:
    return Track(1, "car", keyframes, end_frame=end)


def test_interpolation_between_keyframes_by_hand() -> None:
    track = car(Keyframe(10, A), Keyframe(20, B))
    # frame 14 is 4/10 of the way: u0 = 10 + 0.4 * 10, v0 = 20 + 0.4 * 10, u1 = 30 + 0.4 * 30,
    # v1 = 60 + 0.4 * 40
    assert track.box_at(14) == ((14.0, 24.0, 42.0, 76.0), False, None)
    assert track.box_at(10) == (A, True, None) and track.box_at(20) == (B, True, None)
    assert track.box_at(9) is None and track.box_at(21) is None
    assert interpolate(Keyframe(0, A), Keyframe(2, B), 1) == (15.0, 25.0, 45.0, 80.0)


def test_a_gap_has_no_box_and_an_end_holds_the_last_box() -> None:
    track = car(Keyframe(10, A, interpolate=False), Keyframe(20, B), end=25)
    assert track.box_at(15) is None  # occluded: switched off
    assert track.box_at(25) == (B, False, None) and track.box_at(26) is None
    assert track.with_interpolation(12, True).box_at(15) is not None
    with pytest.raises(ValueError, match=r"frame: expected a frame between .*\(10\.\.19\), got 20"):
        track.with_interpolation(20, True)


def test_drawing_on_an_interpolated_frame_makes_a_keyframe_there() -> None:
    track = car(Keyframe(10, A), Keyframe(20, B)).with_box(15, (0, 0, 5, 5), distance_m=12.0)
    assert [k.frame for k in track.keyframes] == [10, 15, 20]
    assert track.box_at(15) == ((0.0, 0.0, 5.0, 5.0), True, 12.0)
    expected = interpolate(Keyframe(10, A), Keyframe(15, (0, 0, 5, 5)), 12)
    assert track.box_at(12) == (expected, False, None)
    # a box drawn inside a gap keeps the gap on both sides
    gap = car(Keyframe(10, A, interpolate=False), Keyframe(20, B)).with_box(15, A)
    assert gap.box_at(12) is None and gap.box_at(17) is None
    # beyond the end: the track is extended to it and the end goes
    assert car(Keyframe(10, A), end=30).with_box(40, B).last_frame == 40
    assert car(Keyframe(10, A), end=30).with_box(20, B).last_frame == 30


def test_ending_a_track() -> None:
    track = car(Keyframe(10, A), Keyframe(20, B), Keyframe(30, A))
    ended = track.ended_at(14)  # between keyframes: the box shown there becomes the last
    assert [k.frame for k in ended.keyframes] == [10, 14] and ended.last_frame == 14
    assert ended.box_at(14) == ((14.0, 24.0, 42.0, 76.0), True, None)
    assert track.ended_at(35).last_frame == 35 and track.ended_at(35).box_at(33) == (A, False, None)
    assert track.ended_at(20).keyframes[-1].frame == 20 and track.ended_at(20).end_frame is None
    with pytest.raises(ValueError, match="track 1 starts on frame 10, cannot end on 9"):
        track.ended_at(9)
    # in a gap, where the object is hidden: the track ends where it was last seen
    gap = car(Keyframe(10, A, interpolate=False), Keyframe(20, B)).ended_at(15)
    assert gap.keyframes == (Keyframe(10, A),) and gap.last_frame == 10


def test_the_last_keyframe_never_keeps_a_gap_flag() -> None:
    # deleting the keyframe after a gap leaves the keyframe before it last; a box drawn
    # later must not make a gap nobody asked for
    track = car(Keyframe(0, A, interpolate=False), Keyframe(10, B)).without_keyframe(10)
    assert track is not None and track.keyframes == (Keyframe(0, A),)
    assert track.with_box(8, B).box_at(4) is not None


def test_an_attribute_changes_from_its_frame_on_only() -> None:
    track = car(Keyframe(0, A), Keyframe(40, B))
    track = track.with_attribute(20, "occluded", True)
    assert [track.attributes_at(f)["occluded"] for f in (0, 19, 20, 40)] == [
        False,
        False,
        True,
        True,
    ]
    track = track.with_attribute(30, "occluded", False).with_attribute(25, "occluded", True)
    assert track.changes == (
        AttributeChange(20, "occluded", True),
        AttributeChange(30, "occluded", False),
    )
    # an earlier change does not rewrite a later one
    track = track.with_attribute(10, "occluded", True)
    assert [track.attributes_at(f)["occluded"] for f in (9, 10, 29, 30)] == [
        False,
        True,
        True,
        False,
    ]
    assert track.changes == (
        AttributeChange(10, "occluded", True),
        AttributeChange(30, "occluded", False),
    )
    assert track.attributes_at(35) == {"occluded": False, "truncated": False, "radar_seen": False}


def test_deleting_keyframes() -> None:
    track = car(Keyframe(10, A), Keyframe(20, B))
    assert track.without_keyframe(20) == car(Keyframe(10, A))
    assert car(Keyframe(10, A)).without_keyframe(10) is None
    with pytest.raises(ValueError, match="track 1 has no keyframe on frame 15"):
        track.without_keyframe(15)


def test_simplify_keeps_only_the_keyframes_interpolation_needs() -> None:
    # a box moving linearly from frame 0 to 10, then back to where it started by frame 20
    dense = [(f, interpolate(Keyframe(0, A), Keyframe(10, B), f)) for f in range(11)]
    dense += [(f, interpolate(Keyframe(10, B), Keyframe(20, A), f)) for f in range(11, 21)]
    keys = simplify(dense, tolerance_px=0.01)
    assert [k.frame for k in keys] == [0, 10, 20]
    track = Track(1, "car", keys)
    for f, box in dense:
        shown = track.box_at(f)
        assert shown is not None
        assert max(abs(a - b) for a, b in zip(shown[0], box, strict=True)) <= 0.01
    # frames 21..24 missing: a gap, then the box again
    keys = simplify([*dense, (25, A), (26, A)], tolerance_px=0.01)
    assert [(k.frame, k.interpolate) for k in keys] == [
        (0, True),
        (10, True),
        (20, False),
        (25, True),
        (26, True),
    ]
    assert simplify([]) == ()


@given(
    st.lists(
        st.tuples(st.floats(0, 600), st.floats(0, 400), st.floats(1, 40), st.floats(1, 40)),
        min_size=1,
        max_size=30,
    ),
    st.floats(0, 5),
)
def test_simplified_tracks_reproduce_every_box_within_the_tolerance(
    raw: list[tuple[float, float, float, float]], tolerance_px: float
) -> None:
    dense = [(f, (u, v, u + w, v + h)) for f, (u, v, w, h) in enumerate(raw)]
    track = Track(1, "car", simplify(dense, tolerance_px))
    for f, box in dense:
        shown = track.box_at(f)
        assert shown is not None
        assert max(abs(a - b) for a, b in zip(shown[0], box, strict=True)) <= tolerance_px + 1e-9


def test_annotations_edits_and_annotated_frames() -> None:
    ann = (
        Annotations()
        .with_track(car(Keyframe(5, A)))
        .with_track(Track(3, "pedestrian", (Keyframe(5, B),)))
    )
    assert [t.id for t in ann.tracks] == [1, 3] and ann.next_id() == 4
    assert [s.track_id for s in ann.shown_at(5)] == [1, 3] and ann.shown_at(6) == ()
    assert ann.without_track(1).next_id() == 4
    ann = ann.with_annotated(0, 9).with_annotated(20, 29).with_annotated(10, 19)
    assert ann.annotated == ((0, 29),)
    ann = ann.with_annotated(5, 7, on=False)
    assert ann.annotated == ((0, 4), (8, 29))
    assert ann.is_annotated(4) and not ann.is_annotated(5) and not ann.is_annotated(30)


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (lambda: Keyframe(0, (10, 10, 5, 20)), r"box_px: expected u0 < u1 and v0 < v1"),
        (lambda: Keyframe(0, (0, 0, float("nan"), 1)), r"box_px: expected four finite numbers"),
        (lambda: Keyframe(-1, A), r"frame: expected a frame index >= 0, got -1"),
        (lambda: Keyframe(0, A, distance_m=0.0), r"distance_m: expected a distance > 0"),
        (lambda: Keyframe(0, A, distance_m="far"), r"distance_m: expected a distance > 0"),  # type: ignore[arg-type]
        (lambda: Keyframe(0, A, interpolate=1), r"interpolate: expected true or false, got 1"),  # type: ignore[arg-type]
        (lambda: Keyframe(0, (0, 0, 10**400, 1)), r"box_px: expected four finite numbers"),
        (lambda: Track(1, "bus", (Keyframe(0, A),)), r"cls: expected one of .*got 'bus'"),
        (lambda: Track(0, "car", (Keyframe(0, A),)), r"id: expected a track id >= 1, got 0"),
        (lambda: Track(1, "car", ()), r"keyframes: expected one or more"),
        (
            lambda: Track(1, "car", (Keyframe(5, A), Keyframe(5, B))),
            r"keyframes: expected .*increasing frames, got frames \[5, 5\]",
        ),
        (
            lambda: Track(1, "car", (Keyframe(5, A),), end_frame=5),
            r"end_frame: expected a frame after the last keyframe 5, got 5",
        ),
        (lambda: AttributeChange(0, "parked", True), r"name: expected one of"),
        (
            lambda: Annotations((car(Keyframe(0, A)), car(Keyframe(1, A)))),
            r"tracks: expected unique ids",
        ),
        (lambda: Annotations(annotated=((5, 3),)), r"annotated: expected sorted, disjoint"),
        (lambda: simplify([(1, A), (0, A)]), r"boxes: expected increasing frames, got \[1, 0\]"),
    ],
)
def test_bad_values_are_refused_by_name(make: object, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        make()  # type: ignore[operator]
