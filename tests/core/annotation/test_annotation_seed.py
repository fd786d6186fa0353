"""A track of the engine accepted over a clip: found again by its box, stored sparse."""

from __future__ import annotations

import pytest

from core.annotation.model import DEFAULT_TOLERANCE_PX
from core.annotation.seed import engine_track
from core.cli import DEFAULT_RECORDINGS
from core.engine import FusionEngine
from core.io.drive import Drive
from core.params import Params

EXURBAN = DEFAULT_RECORDINGS / "exurban"  # a car tracked from frame 42 to past 60
FIRST, FRAME, LAST = 45, 55, 75


def test_an_engine_track_over_a_clip_becomes_sparse_keyframes() -> None:
    with Drive(EXURBAN) as drive:
        engine = FusionEngine(Params(), drive.camera)
        played = {i: engine.seek(drive, i) for i in range(FIRST, LAST + 1)}  # as engine_track
    chosen = played[FRAME].tracked_vehicles[0]
    boxes = {
        i: t.box_px for i, r in played.items() for t in r.tracked_vehicles if t.id == chosen.id
    }
    seen = []
    track = engine_track(
        EXURBAN,
        Params(),
        FIRST,
        LAST,
        FRAME,
        chosen.box_px,
        "vehicle",
        7,
        progress=lambda done, total: seen.append((done, total)),
    )
    assert track.id == 7 and track.cls == "car"
    assert seen[-1] == (LAST - FIRST + 1, LAST - FIRST + 1)
    assert (track.first_frame, track.last_frame) == (min(boxes), max(boxes))
    for i, box in boxes.items():  # every box of the engine's track, within the tolerance
        shown = track.box_at(i)
        assert shown is not None
        assert max(abs(a - b) for a, b in zip(shown[0], box, strict=True)) <= DEFAULT_TOLERANCE_PX
    assert len(track.keyframes) < len(boxes)  # sparse: not one keyframe per frame


def test_bad_clips_and_boxes_are_refused_by_name() -> None:
    with pytest.raises(ValueError, match=r"first, frame, last: expected 0 <= first <= frame"):
        engine_track(EXURBAN, Params(), 10, 5, 20, (0, 0, 1, 1), "vehicle", 1)
    with pytest.raises(ValueError, match=r"box_px: expected a confirmed vehicle track"):
        engine_track(EXURBAN, Params(), 0, 2, 1, (0, 0, 3, 3), "vehicle", 1)
    with pytest.raises(ValueError, match=r"kind: expected one of"):
        engine_track(EXURBAN, Params(), 0, 2, 1, (0, 0, 3, 3), "guard_rail", 1)  # type: ignore[arg-type]
