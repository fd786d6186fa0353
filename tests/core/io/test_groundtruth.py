"""groundtruth.json (format_version 1): a round trip, truth without pitch or guard rails (null),
and damaged files named with the frame and field."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from core.io.errors import RecordingError
from core.io.groundtruth import (
    FrameTruth,
    TruthGuardRail,
    TruthObject,
    read_groundtruth,
    write_groundtruth,
)

CAR = TruthObject(3, "car", (10.5, 20.5, 40.5, 44.5), (25.0, -1.5, 0.0), (4.5, 1.8, 1.5),
                  (20.0, 0.0), True, 0.25)  # fmt: skip


def test_a_round_trip_keeps_objects_rails_and_pitch(tmp_path: Path) -> None:
    rail = TruthGuardRail(7, "right", ((600.0, 400.0), (400.0, 250.0)))
    frames = [FrameTruth(0, 0, 0.01, (CAR,), (rail,)), FrameTruth(2, 200, -0.02, (), ())]
    write_groundtruth(frames, tmp_path / "gt.json")
    assert read_groundtruth(tmp_path / "gt.json") == frames


def test_truth_without_pitch_or_rail_labels_is_written_null_and_read_back(tmp_path: Path) -> None:
    frames = [FrameTruth(5, 500, math.nan, (CAR,), (), rails_labelled=False)]
    write_groundtruth(frames, tmp_path / "gt.json")
    raw = json.loads((tmp_path / "gt.json").read_text())["frames"][0]
    assert raw["pitch_rad"] is None and raw["guard_rails"] is None
    (back,) = read_groundtruth(tmp_path / "gt.json")
    assert math.isnan(back.pitch_rad) and not back.rails_labelled
    assert back.guard_rails == () and back.objects == (CAR,)
    # an empty list is "no rail here", labelled
    write_groundtruth([FrameTruth(0, 0, 0.0, (), ())], tmp_path / "gt.json")
    assert read_groundtruth(tmp_path / "gt.json")[0].rails_labelled


def test_a_damaged_frame_is_named(tmp_path: Path) -> None:
    write_groundtruth([FrameTruth(0, 0, 0.0, (CAR,), ())], tmp_path / "gt.json")
    data = json.loads((tmp_path / "gt.json").read_text())
    del data["frames"][0]["objects"][0]["box_px"]
    (tmp_path / "gt.json").write_text(json.dumps(data))
    with pytest.raises(RecordingError, match=r"gt\.json: frames\[0\]: missing field 'box_px'"):
        read_groundtruth(tmp_path / "gt.json")
