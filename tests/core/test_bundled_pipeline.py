"""The whole engine on the bundled drives against their exact ground truth: pedestrians
before and after each fusion filter and after tracking, and the vehicle tracks' id switches,
reported in the test output.

Pedestrians are scored by `core.evaluation.objects.score_pedestrians` (its docstring has
the rules; `fusionscope evaluate` prints the same figures). The floors sit under what the
engine reaches today, so a regression fails.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pytest

from core.engine import FrameResult
from core.evaluation.evaluate import PEDESTRIAN_STAGES
from core.evaluation.objects import BoxScore, score_pedestrians
from core.io.groundtruth import FrameTruth, TruthObject
from core.params import Params
from tests.core.playback import playback

MAX_OCCLUSION = 0.5
VEHICLES = ("car", "van", "truck")
# a confirmed vehicle track this close to a radar-seen vehicle's rear (metres) follows it
TRACK_DISTANCE_M, TRACK_LATERAL_M = 3.0, 1.5

# the pedestrian outputs compared (core.evaluation.evaluate.PEDESTRIAN_STAGES), then tracked
STAGES = {
    "symmetry": PEDESTRIAN_STAGES["symmetry"],
    "+motion stereo": PEDESTRIAN_STAGES["motion_stereo"],
    "+vehicles": PEDESTRIAN_STAGES["vehicles"],
    "+radar": PEDESTRIAN_STAGES["radar"],
    "+image motion": PEDESTRIAN_STAGES["image_motion"],
    "+HOG": PEDESTRIAN_STAGES["hog"],
}


def _pedestrian_scores(name: str) -> dict[str, BoxScore]:
    p = Params().pedestrian
    scores = {stage: BoxScore() for stage in (*STAGES, "tracked")}
    for result, truth in playback(name):
        assert truth is not None
        outputs = {
            stage: [
                c.extended_box_px for c in result.pedestrian.candidates if c.verdict in verdicts
            ]
            for stage, verdicts in STAGES.items()
        }
        outputs["tracked"] = [t.box_px for t in result.tracked_pedestrians]
        for stage, boxes in outputs.items():
            scores[stage] += score_pedestrians(
                result.index, boxes, truth.objects, p.min_distance_m, p.max_distance_m
            )
    return scores


def _follows(track_x_m: float, track_y_m: float, o: TruthObject) -> bool:
    x, y, _ = o.position_m
    return abs(track_x_m - x) < TRACK_DISTANCE_M and abs(track_y_m - y) < TRACK_LATERAL_M


def _id_switches(frames: Sequence[tuple[FrameResult, FrameTruth | None]]) -> tuple[int, int, int]:
    """(id switches, frames a radar-seen vehicle was followed by a confirmed track, radar-seen
    vehicle frames): a switch is a vehicle followed by another track id than last time."""
    last: dict[int, int] = {}
    switches = followed = seen = 0
    for result, truth in frames:
        assert truth is not None
        for o in truth.objects:
            if o.cls not in VEHICLES or not o.radar_seen or o.occlusion >= MAX_OCCLUSION:
                continue
            seen += 1
            near = [t for t in result.tracked_vehicles if _follows(t.x_m, t.y_m, o)]
            if not near:
                continue
            track = min(
                near, key=lambda t: np.hypot(t.x_m - o.position_m[0], t.y_m - o.position_m[1])
            )
            followed += 1
            switches += o.id in last and last[o.id] != track.id
            last[o.id] = track.id
    return switches, followed, seen


# floors under today's figures (README): (recall, precision) per stage
PEDESTRIAN_FLOORS = {
    "exurban": {
        "symmetry": (0.33, 0.06),
        # 0.19 today; 0.26 before the pitch region narrowed to 14 px (core/pitch.py Notes):
        # the pitch is right on more frames, and motion stereo marks 6 fewer people's feet
        "+motion stereo": (0.17, 0.06),
        "+vehicles": (0.17, 0.06),
        "+radar": (0.17, 0.08),
        # 0.12 / 0.85 today: the SVM scores exurban's far, small people low
        "+HOG": (0.10, 0.70),
        "tracked": (0.03, 0.40),
    },
    "stop_and_go": {
        # 0.78 / 0.19 today: boxes off their band's distance are kept when a person's size
        # there (`keep_off_band_boxes`), and the scan's threshold is 0.4 (core/pedestrian.py
        # Notes), more boxes of every kind for the SVM to decide on
        "symmetry": (0.45, 0.15),
        "+motion stereo": (0.40, 0.32),
        "+vehicles": (0.38, 0.33),
        "+radar": (0.38, 0.40),
        "+HOG": (0.30, 0.90),  # 0.47 / 1.00 today
        "tracked": (0.35, 0.85),  # 0.46 / 0.98 today
    },
}


@pytest.mark.parametrize("name", sorted(PEDESTRIAN_FLOORS))
def test_pedestrians_before_and_after_the_fusion_filters(
    name: str, report: Callable[[str], None]
) -> None:
    scores = _pedestrian_scores(name)
    for stage, s in scores.items():
        report(
            f"{name} pedestrians {stage:<15} recall {s.found}/{s.visible} = {s.recall:.0%}, "
            f"precision {s.true_boxes}/{s.boxes} = {s.precision:.0%}"
        )
    for stage, (recall, precision) in PEDESTRIAN_FLOORS[name].items():
        assert scores[stage].recall >= recall, stage
        assert scores[stage].precision >= precision, stage
    # each filter only removes boxes: precision may rise, recall never
    assert scores["+motion stereo"].found <= scores["symmetry"].found
    assert scores["+vehicles"].found <= scores["+motion stereo"].found
    assert scores["+radar"].found <= scores["+vehicles"].found
    assert scores["+image motion"].found <= scores["+radar"].found
    assert scores["+HOG"].found <= scores["+image motion"].found


def test_the_hog_verification_leaves_few_false_boxes_on_the_highway(
    report: Callable[[str], None],
) -> None:
    """The highway has no people: every box is false (guard-rail posts, wheels, shadows)."""
    scores = _pedestrian_scores("highway")
    before, after = scores["+radar"].boxes, scores["+HOG"].boxes
    frames = len(playback("highway"))
    report(f"highway false pedestrian boxes: {before} -> {after} over {frames} frames")
    assert after <= 0.1 * before  # today 212 -> 10
    assert after / frames <= 0.1


def _filter_effect(
    name: str, before_stage: str, after_stage: str, what: str, report: Callable[[str], None]
) -> tuple[BoxScore, BoxScore, int, int]:
    """The scores before and after one filter, and the false boxes before and after (reported)."""
    scores = _pedestrian_scores(name)
    before, after = scores[before_stage], scores[after_stage]
    false_before, false_after = before.boxes - before.true_boxes, after.boxes - after.true_boxes
    report(f"{name} {what}: false boxes {false_before} -> {false_after}")
    return before, after, false_before, false_after


@pytest.mark.parametrize("name", ["highway", "exurban", "stop_and_go"])
def test_the_radar_filter_removes_false_boxes_and_no_true_one(
    name: str, report: Callable[[str], None]
) -> None:
    before, after, false_before, false_after = _filter_effect(
        name, "+vehicles", "+radar", "radar filter", report
    )
    # people move slower than a jog: today no true box is lost on highway and exurban,
    # 1 of 98 on stop_and_go (a person beside a car pulling away, since the pitch region
    # narrowed to 14 px)
    assert after.true_boxes >= before.true_boxes - 1
    assert false_after <= 0.9 * false_before  # today 17-33 % fewer


@pytest.mark.parametrize("name", ["highway", "exurban", "stop_and_go"])
def test_the_image_motion_filter_removes_vehicle_parts_and_few_people(
    name: str, report: Callable[[str], None]
) -> None:
    before, after, false_before, false_after = _filter_effect(
        name, "+radar", "+image motion", "image-motion filter", report
    )
    # people walk: today 1 true box of 44 is lost on exurban, none on the others; highway
    # 201 -> 102 false boxes, exurban 220 -> 154, stop_and_go 216 -> 213 (it crawls, and the
    # two places lie too close to tell)
    assert after.true_boxes >= before.true_boxes - 1
    if name == "highway":
        assert false_after <= 0.7 * false_before


# today 8, 12, 5 switches over 334, 269, 133 followed frames; with the papers' 2.5 m areas for
# moving targets too, 3, 7, 2 over 81, 159, 50: more vehicles followed, fewer switches each
SWITCH_CEILINGS = {"highway": 10, "exurban": 14, "stop_and_go": 8}
FOLLOWED_FLOORS = {"highway": 290, "exurban": 235, "stop_and_go": 115}


@pytest.mark.parametrize("name", sorted(SWITCH_CEILINGS))
def test_vehicle_tracks_keep_their_ids(name: str, report: Callable[[str], None]) -> None:
    switches, followed, seen = _id_switches(playback(name))
    report(
        f"{name} vehicle tracks: {switches} id switches over {followed} followed frames "
        f"({followed}/{seen} radar-seen vehicle frames followed by a confirmed track)"
    )
    assert switches <= SWITCH_CEILINGS[name]
    assert followed >= FOLLOWED_FLOORS[name]
