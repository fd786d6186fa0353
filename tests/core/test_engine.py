"""The fusion engine on the bundled drives: stage order, seeking, and `fusionscope run`.

Replay tolerance (core.engine): after a seek, a frame's per-frame detections (pitch,
vehicles, guard-rail labels, pedestrian verdicts) are those of a playback from the start,
and its motion-stereo obstacle mask differs only in cells at the threshold. Tracks are
rebuilt from the replayed window, so their ids restart and tracks kept alive by
intermittent detections may differ; most confirmed tracks still have a counterpart.
"""

from __future__ import annotations

import json
from collections.abc import Callable

import numpy as np
import pytest

from core.cli import DEFAULT_RECORDINGS, main
from core.engine import FrameResult, FusionEngine, Milestones, replay_window
from core.io.drive import Drive
from core.io.errors import RecordingError
from core.io.frame import FrameInput
from core.params import Params, params_from
from core.vehicle import body_box
from tests.core.playback import playback

SEEK_DRIVE = "stop_and_go"  # the car brakes, stands and drives on: every mode of the stages
SEEK_STEP = 15  # frames between the seeks compared with the playback
MASK_AGREEMENT = 0.998  # share of obstacle cells a seek reproduces (today 0.9986)
TRACK_MATCH_M = 1.0  # a confirmed track of the playback has a seek counterpart this close
TRACK_AGREEMENT = 0.7  # share of the playback's confirmed tracks with such a counterpart
# share of seeks whose search areas differ from the playback's: a track confirmed before the
# replayed window widened an area there or was searched for without radar
# (`core.track_search`), or a replayed track, filtered from fewer frames, centres one a
# little elsewhere (`centre_on_track`; today 7 of 10: 6 before tracks lived on by their
# look, `core.appearance`, 4 without the track searches, 1 without centring either); a seek
# from the start is the playback exactly (the from-start tests below)
AREAS_APART = 0.7


def _playback(name: str) -> tuple[FrameResult, ...]:
    return tuple(result for result, _ in playback(name))


def _seek(name: str, index: int) -> FrameResult:
    with Drive(DEFAULT_RECORDINGS / name) as drive:
        return FusionEngine(Params(), drive.camera).seek(drive, index)


def test_played_frames_follow_each_other() -> None:
    played = _playback(SEEK_DRIVE)
    assert [r.index for r in played] == list(range(len(played)))
    assert all(r.replayed == 0 for r in played)
    assert played[0].motion_stereo.mode == "first_frame"
    assert played[1].motion_stereo.mode != "first_frame"
    for r in played:
        t = r.timings
        parts = (
            t.pitch_ms,
            t.motion_stereo_ms,
            t.guardrail_ms,
            t.vehicle_ms,
            t.pedestrian_ms,
            t.tracking_ms,
        )
        assert all(x >= 0 for x in parts)
        assert t.total_ms == pytest.approx(sum(parts))
        # the frame's camera carries the pitch found on it
        assert r.camera.extrinsics.pitch_rad == r.pitch.pitch_rad


def _searched_areas(r: FrameResult) -> list[tuple[float, float, float, float]]:
    searched = [t.area for t in r.track_search.search.targets if t.area is not None]
    return [a.full_px for a in (*r.areas, *searched)]


def test_a_seek_reproduces_the_playback_within_the_replay_tolerance(
    report: Callable[[str], None],
) -> None:
    played = _playback(SEEK_DRIVE)
    window = replay_window(Params())
    matched = total = seeks = widened_apart = 0
    for i in range(0, len(played), SEEK_STEP):
        a, b = played[i], _seek(SEEK_DRIVE, i)
        seeks += 1
        assert b.index == i and b.replayed == min(i, window)
        assert b.pitch.pitch_rad == a.pitch.pitch_rad
        same = np.mean(a.motion_stereo.obstacles == b.motion_stereo.obstacles)
        assert same >= MASK_AGREEMENT
        # the areas the tracker widens, and those it searches without radar, follow the
        # replayed tracks: where they differ, what was found in them may too
        if _searched_areas(b) != _searched_areas(a):
            widened_apart += 1
            continue
        assert [v.box_px for v in b.vehicle.vehicles] == [v.box_px for v in a.vehicle.vehicles]
        assert b.guardrail.guard_rail_targets == a.guardrail.guard_rail_targets
        assert [(c.extended_box_px, c.verdict) for c in b.pedestrian.candidates] == [
            (c.extended_box_px, c.verdict) for c in a.pedestrian.candidates
        ]
        for t in a.tracking.confirmed:
            total += 1
            matched += any(
                u.kind == t.kind and np.hypot(u.x_m - t.x_m, u.y_m - t.y_m) <= TRACK_MATCH_M
                for u in b.tracking.confirmed
            )
    report(
        f"engine seek on {SEEK_DRIVE} (window {window} frames): {matched}/{total} confirmed "
        f"tracks of the playback rebuilt; {widened_apart}/{seeks} seeks with areas widened "
        "otherwise"
    )
    assert matched >= TRACK_AGREEMENT * total
    assert widened_apart <= AREAS_APART * seeks


def test_seeking_the_next_frame_processes_just_it() -> None:
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera)
        assert engine.seek(drive, 40).replayed == replay_window(Params())
        nxt = engine.seek(drive, 41)
        assert nxt.replayed == 0 and nxt.motion_stereo.mode != "first_frame"
        assert engine.seek(drive, 0).replayed == 0
        # a frame out of order starts over
        jumped = engine.process(drive.frame(90))
        assert jumped.motion_stereo.mode == "first_frame"
        assert jumped.tracking.tracks == () or all(t.age == 1 for t in jumped.tracking.tracks)
        with pytest.raises(ValueError, match="index"):
            engine.seek(drive, len(drive))


def test_a_seek_a_little_ahead_plays_the_frames_in_between() -> None:
    played = _playback(SEEK_DRIVE)
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera)
        engine.seek(drive, 0)
        ahead = engine.seek(drive, 5)  # frames 1..4 processed on the way, as played
        assert ahead.replayed == 4
        assert np.array_equal(ahead.motion_stereo.obstacles, played[5].motion_stereo.obstacles)
        assert [t.id for t in ahead.tracking.tracks] == [t.id for t in played[5].tracking.tracks]
        far = engine.seek(drive, 5 + replay_window(Params()) + 1)  # beyond the window: replay
        assert far.replayed == replay_window(Params())
        back = engine.seek(drive, 10)  # backwards: replay
        assert back.replayed == 10


class _Damaged:
    """A drive whose frame `bad` cannot be read."""

    def __init__(self, drive: Drive, bad: int) -> None:
        self.drive, self.bad = drive, bad

    def __len__(self) -> int:
        return len(self.drive)

    def frame(self, i: int) -> FrameInput:
        if i == self.bad:
            raise RecordingError(f"frame {i} is not a PNG")
        return self.drive.frame(i)


def test_a_seek_past_a_frame_that_cannot_be_read_replays_from_after_it() -> None:
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        damaged = _Damaged(drive, 35)
        engine = FusionEngine(Params(), drive.camera)
        result = engine.seek(damaged, 40)
        clean = FusionEngine(Params(), drive.camera)
        for i in range(36, 41):  # what the replay amounts to: a start after the damaged frame
            expected = clean.process(drive.frame(i))
        assert result.index == 40 and result.replayed == replay_window(Params())
        assert np.array_equal(result.motion_stereo.obstacles, expected.motion_stereo.obstacles)
        assert result.pitch.pitch_rad == expected.pitch.pitch_rad
        with pytest.raises(RecordingError, match="frame 35"):
            engine.seek(damaged, 35)


# --- kept states --------------------------------------------------------------------------
KEEP = 256  # states kept by the engines below: more than any of them processes


def _assert_same(a: FrameResult, b: FrameResult) -> None:
    """Two results of one frame are the same, bit for bit where it matters downstream."""
    assert a.index == b.index
    assert a.pitch.pitch_rad == b.pitch.pitch_rad
    for name in ("obstacles", "image_mask", "next_background"):
        assert np.array_equal(getattr(a.motion_stereo, name), getattr(b.motion_stereo, name))
    assert [v.box_px for v in a.vehicle.vehicles] == [v.box_px for v in b.vehicle.vehicles]
    assert [(t.id, t.x_m, t.y_m) for t in a.tracking.tracks] == [
        (t.id, t.x_m, t.y_m) for t in b.tracking.tracks
    ]
    assert a.tracking == b.tracking


def test_a_seek_back_takes_up_the_state_kept_after_the_frame_before() -> None:
    played = _playback(SEEK_DRIVE)
    window = replay_window(Params())
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera, keep_states=KEEP)
        for i in range(41):  # keeping states changes no result
            _assert_same(engine.seek(drive, i), played[i])
        assert engine.kept_states == tuple(range(41))
        assert engine.seek(drive, 80).replayed == window  # nothing kept near 80: a replay
        back = engine.seek(drive, 30)  # from the state after 29
        assert back.replayed == 0
        _assert_same(back, played[30])
        on = engine.seek(drive, 35)  # from the state after 34, kept by the first playback
        assert on.replayed == 0
        _assert_same(on, played[35])
        ahead = engine.seek(drive, 45)  # the latest state kept before 45 is 40's
        assert ahead.replayed == 4
        _assert_same(ahead, played[45])
        # the states the replay of 80 kept give what that replay's path gives (it started
        # over at 80 - window), not what a playback from the start gives
        clean = FusionEngine(Params(), drive.camera)
        for i in range(80 - window, 71):
            expected = clean.process(drive.frame(i))
        replayed = engine.seek(drive, 70)
        assert replayed.replayed == 0
        _assert_same(replayed, expected)


def test_kept_states_are_the_last_used() -> None:
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera, keep_states=5)
        for i in range(41):
            engine.seek(drive, i)
        assert engine.kept_states == (36, 37, 38, 39, 40)
        assert engine.seek(drive, 38).replayed == 0  # from 37's state
        assert engine.kept_states == (36, 39, 40, 37, 38)  # least recently used first
        assert engine.seek(drive, 41).replayed == 0  # from 40's
        assert engine.kept_states == (39, 37, 38, 40, 41)  # 36, used longest ago, dropped
        assert engine.seek(drive, 10).replayed == 10  # nothing kept near 10: a replay
        assert engine.kept_states == (6, 7, 8, 9, 10)


def test_an_engine_keeps_no_state_by_default() -> None:
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera)
        for i in range(41):
            engine.seek(drive, i)
        assert engine.kept_states == ()
        assert engine.seek(drive, 30).replayed == replay_window(Params())


def test_reset_drops_the_kept_states_and_a_jump_keeps_them() -> None:
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera, keep_states=KEEP)
        for i in range(11):
            engine.seek(drive, i)
        jumped = engine.process(drive.frame(90))  # a frame out of order starts over...
        assert jumped.motion_stereo.mode == "first_frame"
        assert engine.kept_states == (*range(11), 90)  # ...and keeps the states
        assert engine.seek(drive, 6).replayed == 0
        engine.reset()
        assert engine.kept_states == () and engine.last_index is None
        assert engine.seek(drive, 6).replayed == 6


def test_a_state_kept_before_the_window_is_not_used() -> None:
    played = _playback(SEEK_DRIVE)
    window = replay_window(Params())
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera, keep_states=KEEP)
        for i in range(11):
            engine.seek(drive, i)
        # 10's state is window frames back: the engine plays on from 10 as it would without
        ahead = engine.seek(drive, 10 + window)
        assert ahead.replayed == window - 1
        _assert_same(ahead, played[10 + window])
        # the latest kept is more than window frames back: a replay
        far = 10 + 3 * window
        assert engine.seek(drive, far).replayed == window


def test_a_preview_runs_this_frame_on_the_state_other_parameters_kept() -> None:
    played = _playback(SEEK_DRIVE)
    wider = Params().with_value("vehicle.min_width_m", 2.9)  # wider than any car here
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera, keep_states=KEEP)
        for i in range(31):
            engine.seek(drive, i)
        state = engine.kept_state(29)
        assert state is not None and engine.kept_state(31) is None
        # under the same parameters a preview is the frame played from that state
        same = FusionEngine(Params(), drive.camera, keep_states=KEEP)
        preview = same.preview(state, drive.frame(30))
        assert preview.preview and not played[30].preview
        _assert_same(preview, played[30])
        assert same.last_index is None and same.kept_states == ()  # nothing of it is kept
        # under other parameters this frame's stages use them
        assert played[30].vehicle.vehicles
        assert all(v.width_m < 2.9 for v in played[30].vehicle.vehicles)
        other = FusionEngine(wider, drive.camera).preview(state, drive.frame(30))
        assert other.vehicle.vehicles == ()
        assert other.pitch.pitch_rad == played[30].pitch.pitch_rad
        assert engine.seek(drive, 30).replayed == 0  # the state is still kept, unchanged
        with pytest.raises(ValueError, match="expected frame 30, which follows the state, got"):
            FusionEngine(Params(), drive.camera).preview(state, drive.frame(31))
        coarser = Params().with_value("motion_stereo.cell_m", 2 * Params().motion_stereo.cell_m)
        with pytest.raises(ValueError, match=r"state\.background"):  # another grid
            FusionEngine(coarser, drive.camera).preview(state, drive.frame(30))


# --- from the start ---------------------------------------------------------------------


def test_a_seek_from_the_start_gives_the_playbacks_tracks_and_ids_however_it_is_reached() -> None:
    played = _playback(SEEK_DRIVE)
    assert all(r.from_start for r in played)
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera, catch_up_frames=None)
        for i in (80, 30, 120, 31, 0, 149, 60):  # forwards, back, next, the ends
            result = engine.seek(drive, i)
            assert result.from_start
            _assert_same(result, played[i])
        assert any(t.id > 1 for t in played[120].tracked_vehicles)  # ids worth comparing
        # a replay (the default engine, far from any from-start state) is not from the start
        assert not FusionEngine(Params(), drive.camera).seek(drive, 80).from_start


def test_engines_sharing_milestones_seek_from_the_nearest_within_their_catch_up() -> None:
    played = _playback(SEEK_DRIVE)
    window = replay_window(Params())
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        milestones = Milestones(Params(), every=10)
        first = FusionEngine(Params(), drive.camera, milestones=milestones)
        for i in range(61):  # a playback keeps the states of frames 0, 10, .. 60
            first.seek(drive, i)
        assert milestones.reach == 60
        other = FusionEngine(Params(), drive.camera, catch_up_frames=15, milestones=milestones)
        near = other.seek(drive, 57)  # from 50's milestone
        assert near.from_start and near.replayed == 6
        _assert_same(near, played[57])
        reach = other.seek(drive, 76)  # 60's is 15 frames back
        assert reach.from_start and reach.replayed == 15
        _assert_same(reach, played[76])
        assert milestones.reach == 70  # the engine kept 70's on the way
        far = other.seek(drive, 120)  # beyond its catch-up: a replay
        assert not far.from_start and far.replayed == window
        assert milestones.reach == 70  # nothing from the start in a replay
        # an engine keeping the states of a replay over frames 78..100 ...
        keeper = FusionEngine(
            Params(), drive.camera, keep_states=KEEP, catch_up_frames=15, milestones=milestones
        )
        assert not keeper.seek(drive, 100).from_start
        filler = FusionEngine(Params(), drive.camera, catch_up_frames=None, milestones=milestones)
        filler.seek(drive, 90)
        assert milestones.reach == 90
        # ... takes up 90's milestone, not its own state of 90 from the replay
        exact = keeper.seek(drive, 100)
        assert exact.from_start and exact.replayed == 9
        _assert_same(exact, played[100])


def test_a_from_start_seek_past_a_frame_that_cannot_be_read_starts_the_drive_again_after_it() -> (
    None
):
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(Params(), drive.camera, catch_up_frames=None)
        for bad in (0, 35):
            engine.reset()
            result = engine.seek(_Damaged(drive, bad), 40)
            clean = FusionEngine(Params(), drive.camera)
            for i in range(bad + 1, 41):  # as a playback does: the drive starts again
                expected = clean.process(drive.frame(i))
            assert result.from_start and result.replayed == 40
            _assert_same(result, expected)


def test_bad_milestones_and_catch_up_are_refused_by_name() -> None:
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        with pytest.raises(ValueError, match="catch_up_frames: expected an integer >= 0"):
            FusionEngine(Params(), drive.camera, catch_up_frames=-1)
        other = Params().with_value("vehicle.min_width_m", 1.2)
        with pytest.raises(ValueError, match="milestones: expected those of the engine's"):
            FusionEngine(Params(), drive.camera, milestones=Milestones(other))
    for every in (0, 2.5, True):
        with pytest.raises(ValueError, match="every: expected an integer >= 1"):
            Milestones(Params(), every=every)  # type: ignore[arg-type]


@pytest.mark.parametrize("keep", [-1, 1.5, True])
def test_bad_keep_states_is_refused_by_name(keep: object) -> None:
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        with pytest.raises(ValueError, match="keep_states: expected an integer >= 0"):
            FusionEngine(Params(), drive.camera, keep_states=keep)  # type: ignore[arg-type]


def test_vehicle_tracks_show_their_bodies_and_the_papers_their_faces() -> None:
    """Step 12 of `core.vehicle` on the tracks: a vehicle track's outline is the body around
    its box at its distance; a pedestrian's is its box; the papers' preset has no body."""
    played = _playback(SEEK_DRIVE)
    length_m = Params().vehicle.body_length_m
    vehicles = [(r, t) for r in played for t in r.tracked_vehicles]
    assert vehicles
    for r, t in vehicles:
        assert t.outline_px == body_box(t.box_px, t.x_m, r.camera, length_m)
    assert any(t.outline_px != t.box_px for _, t in vehicles)  # the side of one in another lane
    assert all(t.outline_px == t.box_px for r in played for t in r.tracked_pedestrians)
    with Drive(DEFAULT_RECORDINGS / SEEK_DRIVE) as drive:
        engine = FusionEngine(params_from("papers"), drive.camera)
        papers = [engine.process(drive.frame(i)) for i in range(20)]
    assert all(t.outline_px == t.box_px for r in papers for t in r.tracked_vehicles)
    assert all(v.outline_px == v.box_px for r in papers for v in r.vehicle.vehicles)


def test_fusionscope_run_writes_a_line_per_frame(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    out = tmp_path / "results.jsonl"
    assert main(["run", str(DEFAULT_RECORDINGS / SEEK_DRIVE), "--out", str(out)]) == 0
    lines = out.read_text().splitlines()
    played = _playback(SEEK_DRIVE)
    assert len(lines) == len(played)
    for line, r in zip(lines, played, strict=True):
        record = json.loads(line)
        assert record["frame"] == r.index and record["t_ns"] == r.t_ns
        assert record["pitch_rad"] == pytest.approx(r.pitch.pitch_rad, abs=1e-6)
        assert len(record["vehicles"]) == len(r.vehicle.vehicles)
        for v, written in zip(r.vehicle.vehicles, record["vehicles"], strict=True):
            assert written["box_px"] == pytest.approx(v.box_px, abs=0.051)
            assert written["body_px"] == pytest.approx(v.outline_px, abs=0.051)
        assert [p["verdict"] for p in record["pedestrians"]] == [
            c.verdict for c in r.pedestrian.candidates
        ]
        assert {t["id"] for t in record["tracks"]} == {t.id for t in r.tracking.shown}
        assert set(record["timings_ms"]) >= {"pitch", "pedestrian", "tracking", "total"}
    assert not (tmp_path / "results.jsonl.partial").exists()


def test_fusionscope_run_says_what_is_wrong(tmp_path, capsys) -> None:  # type: ignore[no-untyped-def]
    assert main(["run", str(tmp_path / "nowhere")]) == 2
    assert "nowhere" in capsys.readouterr().err
    out = tmp_path / "missing" / "results.jsonl"
    assert main(["run", str(DEFAULT_RECORDINGS / SEEK_DRIVE), "--out", str(out)]) == 2
    assert "missing" in capsys.readouterr().err
    bad = tmp_path / "params.yaml"
    bad.write_text("pedestrian:\n  gap_fraction: 3.0\n")
    assert main(["run", str(DEFAULT_RECORDINGS / SEEK_DRIVE), "--params", str(bad)]) == 2
    assert "gap_fraction" in capsys.readouterr().err


def test_the_engine_runs_the_real_rav4_frame(rav4) -> None:  # type: ignore[no-untyped-def]
    with Drive(rav4) as drive:
        result = FusionEngine(Params(), drive.camera).seek(drive, 0)
    # the silver car ahead (test_bundled_vehicles) is a vehicle, no pedestrian is near it
    (car,) = [v for v in result.vehicle.vehicles if abs(v.lateral_m) < 1.5]
    for c in result.pedestrian.kept:
        assert not (car.box_px[0] <= c.axis_px <= car.box_px[2]), c
    width = drive.camera.intrinsics.width_px
    for c in result.pedestrian.candidates:
        assert 0 <= c.axis_px < width
    assert result.tracking.confirmed == ()  # one frame confirms nothing
