"""One rendered frame: its picture, panels and read-out come from the same frame and the
engine's result on it."""

from __future__ import annotations

import time

import numpy as np
import pytest
from app_fakes import HEIGHT_PX, FakeDrive

from app import draw, overlays
from app.engines import ClientEngines
from app.state import Layers, Panels, ViewState
from app.view import (
    AB_GAP_COLOUR,
    AB_GAP_PX,
    OVERLAY_OF_LAYER,
    SETTLING_NOTE,
    STAGE_GAP_PX,
    STAGE_TITLES,
    FrameView,
    can_series,
    can_window,
    median_timings,
    readout_text,
    render_view,
    stage_picture,
    stage_under,
    timings_markdown,
)
from core.cli import DEFAULT_RECORDINGS
from core.engine import FrameResult, FusionEngine, StageTimings, replay_window
from core.io.drive import Drive
from core.io.errors import RecordingError
from core.io.frame import FrameInput
from core.params import Params


def _view(drive: FakeDrive, state: ViewState) -> FrameView:
    result = ClientEngines(drive.camera).result("tab", drive, state.params, state.frame)
    return render_view(drive, state, result, drive.frame(state.frame))


def test_readout_gives_frame_time_speed_and_yaw_rate_in_display_units() -> None:
    text = readout_text(3, 10, 0.12, 25.0, np.radians(2.0))
    assert text == "frame 3 / 9 | t 0.12 s | 90.0 km/h | yaw +2.00 deg/s"


def test_readout_without_can_says_not_available() -> None:
    text = readout_text(0, 1, 0.0, float("nan"), float("nan"))
    assert text == "frame 0 / 0 | t 0.00 s | speed n/a | yaw n/a"


def test_view_of_a_frame_carries_that_frames_index_time_and_timings() -> None:
    drive = FakeDrive(frames=10)
    view = _view(drive, ViewState(frame=2))
    assert view.frame == 2
    assert view.readout.startswith("frame 2 / 9 | t 0.08 s")
    assert view.image.shape == (HEIGHT_PX + draw.STRIP_HEIGHT_PX, 640, 3)
    table = timings_markdown(view.timings)
    assert "| **total** |" in table and table.count("\n") == 8


def test_view_without_layers_shows_the_plain_frame() -> None:
    drive = FakeDrive()
    off = Layers(**dict.fromkeys(Layers.names(), False))
    view = _view(drive, ViewState(frame=1, layers=off))
    np.testing.assert_array_equal(view.image[:HEIGHT_PX], draw.grey_to_rgb(drive.frame(1).image))
    on = _view(drive, ViewState(frame=1))
    assert (on.image != view.image).any()


def test_every_layer_but_truth_is_an_overlay_and_every_stage_has_a_panel() -> None:
    assert set(OVERLAY_OF_LAYER) == set(Layers.names()) - {"truth"}
    assert set(OVERLAY_OF_LAYER.values()) == set(overlays.LAYERS)
    drive = FakeDrive(frames=3)
    result = ClientEngines(drive.camera).result("tab", drive, Params(), 2)
    for stage in ("motion_stereo", "symmetry", "pedestrians", "guard_rails"):
        image = stage_picture(result, ViewState(frame=2, panels=Panels(stage=stage)))
        assert stage in STAGE_TITLES and image is not None
        assert image.dtype == np.uint8 and image.shape[2] == 3


def test_a_result_of_another_frame_is_refused() -> None:
    drive = FakeDrive(frames=10)
    result = ClientEngines(drive.camera).result("tab", drive, Params(), 3)
    with pytest.raises(ValueError, match=r"expected frame 4, got \(3, 4\)"):
        render_view(drive, ViewState(frame=4), result, drive.frame(4))


def test_an_engine_per_client_and_the_last_result_again_for_a_redraw() -> None:
    drive = FakeDrive(frames=10)
    engines = ClientEngines(drive.camera, fill=False)
    first = engines.result("a", drive, Params(), 5)
    assert engines.result("a", drive, Params(), 5) is first  # a layer toggled: no rerun
    assert engines.result("a", drive, Params(), 6).replayed == 0  # the next frame
    # b's own engine: a seek, from the milestone a's engine left after frame 0
    assert engines.result("b", drive, Params(), 6).replayed == 5
    changed = Params().with_value("pitch.lines_kept", 3)
    again = engines.result("a", drive, changed, 6)
    assert again.replayed == 6 and again is not first  # new parameters: from the start
    assert again.from_start


def test_new_parameters_give_a_preview_then_the_exact_replay() -> None:
    drive = FakeDrive(frames=10)
    engines = ClientEngines(drive.camera, fill=False)
    engines.result("a", drive, Params(), 6)
    changed = Params().with_value("pitch.lines_kept", 3)
    preview = engines.result("a", drive, changed, 6, preview=True)
    assert preview.preview and preview.replayed == 0  # from the state after 5
    changed_again = Params().with_value("pitch.lines_kept", 4)  # before the exact one
    assert engines.result("a", drive, changed_again, 6, preview=True).preview
    exact = engines.result("a", drive, changed_again, 6, preview=True)
    assert not exact.preview and exact.replayed == 6
    assert engines.result("a", drive, changed_again, 6, preview=True) is exact
    # no kept state before the frame (the first frame), or no preview asked: the replay
    assert not engines.result("a", drive, changed, 0, preview=True).preview
    assert not engines.result("a", drive, Params(), 6).preview


def test_a_scrub_back_takes_up_the_state_the_engine_kept() -> None:
    drive = FakeDrive(frames=10)
    engines = ClientEngines(drive.camera, fill=False)
    assert engines.result("a", drive, Params(), 6).replayed == 6  # 0..5 on the way, kept
    assert engines.result("a", drive, Params(), 3).replayed == 0  # from 2's state
    plain = ClientEngines(drive.camera, keep_states=0, fill=False)
    plain.result("a", drive, Params(), 6)
    assert plain.result("a", drive, Params(), 3).replayed == 2  # from frame 0's milestone


def _once_from_start(engines: ClientEngines, drive: FakeDrive, index: int) -> FrameResult:
    """Client "a"'s result of frame `index` once the filler has played the drive from its
    start up to it (within a minute), the filler then stopped; the last result otherwise."""
    deadline = time.monotonic() + 60
    while True:
        result = engines.result("a", drive, Params(), index)
        if result.from_start or time.monotonic() > deadline:
            engines.close()
            return result
        time.sleep(0.05)


def test_a_far_frame_is_a_settling_replay_until_the_filler_reaches_it() -> None:
    drive = FakeDrive(frames=120)
    quiet = ClientEngines(drive.camera, catch_up_frames=10, fill=False)
    far = quiet.result("a", drive, Params(), 100)
    assert not far.from_start and far.replayed == replay_window(Params())
    assert quiet.result("a", drive, Params(), 100) is far  # nothing reaches it: kept
    view = render_view(drive, ViewState(frame=100), far, drive.frame(100))
    assert view.settling and SETTLING_NOTE in view.readout
    filled = ClientEngines(drive.camera, catch_up_frames=10)
    filled.result("a", drive, Params(), 100)
    exact = _once_from_start(filled, drive, 100)
    assert exact.from_start and exact.replayed <= 9  # from the milestone of frame 90 or 100
    played = FusionEngine(Params(), drive.camera, catch_up_frames=None).seek(drive, 100)
    assert [(t.id, t.x_m) for t in exact.tracking.tracks] == [
        (t.id, t.x_m) for t in played.tracking.tracks
    ]
    view = render_view(drive, ViewState(frame=100), exact, drive.frame(100))
    assert not view.settling and SETTLING_NOTE not in view.readout


def test_the_filler_plays_past_a_frame_that_cannot_be_read() -> None:
    class Damaged(FakeDrive):
        def frame(self, index: int) -> FrameInput:
            if index == 20:
                raise RecordingError("frame 20: damaged PNG")
            return super().frame(index)

    drive = Damaged(frames=60)
    engines = ClientEngines(drive.camera, catch_up_frames=5)
    engines.result("a", drive, Params(), 0)
    result = _once_from_start(engines, drive, 55)
    assert result.from_start and result.replayed == 4  # from the milestone of frame 50
    # the drive starts again after the damaged frame, as a playback does
    played = FusionEngine(Params(), drive.camera)
    for i in range(21, 56):
        expected = played.process(drive.frame(i))
    assert [(t.id, t.x_m) for t in result.tracking.tracks] == [
        (t.id, t.x_m) for t in expected.tracking.tracks
    ]


def test_a_frame_shows_the_same_track_ids_however_a_client_reached_it() -> None:
    def ids(result: FrameResult) -> list[tuple[str, int]]:
        return [(t.kind, t.id) for t in (*result.tracked_vehicles, *result.tracked_pedestrians)]

    with Drive(DEFAULT_RECORDINGS / "highway") as drive:
        engines = ClientEngines(drive.camera, fill=False)
        for i in range(121):  # tab a plays the drive to frame 120
            played = engines.result("a", drive, Params(), i)
        assert played.from_start and len(ids(played)) >= 2
        # tab b opens frame 120, then scrubs back and forth
        for i in (120, 40, 121, 120):
            seeked = engines.result("b", drive, Params(), i)
            assert seeked.from_start
        assert ids(seeked) == ids(played)
        # tab a changes a parameter (other tracks and ids), then takes it back
        changed = Params().with_value("vehicle.min_width_m", 1.2)
        assert engines.result("a", drive, changed, 120, preview=True).preview
        # no milestones of these yet (no filler here): a replay, settling
        assert not engines.result("a", drive, changed, 120, preview=True).from_start
        assert engines.result("a", drive, Params(), 120, preview=True).preview
        back = engines.result("a", drive, Params(), 120, preview=True)
        assert back.from_start and ids(back) == ids(played)
        # tab c comes after a switch to another recording (a new engine on this drive)
        assert ids(engines.result("c", drive, Params(), 120)) == ids(played)


def test_only_the_stage_picture_shown_is_drawn_and_it_goes_under_the_camera() -> None:
    drive = FakeDrive(frames=3)
    state = ViewState(frame=2, panels=Panels(stage="guard_rails"))
    view = _view(drive, state)
    result = ClientEngines(drive.camera).result("tab", drive, state.params, 2)
    stage = stage_picture(result, state)
    assert stage is not None
    np.testing.assert_array_equal(view.with_stage, stage_under(view.image, stage))
    for nothing in ("timings", "none"):
        state = ViewState(frame=2, panels=Panels(stage=nothing))
        assert stage_picture(result, state) is None
        alone = _view(drive, state)
        assert alone.with_stage is alone.image
    assert _view(drive, ViewState(frame=2, panels=Panels(bird_eye=False))).bird_eyes == ()
    with pytest.raises(ValueError, match="stage: expected one of motion_stereo"):
        Panels(stage="everything")


def test_a_narrower_stage_picture_goes_centred_under_the_camera_picture() -> None:
    camera = draw.filled(4, 10, (1, 2, 3))
    stage = draw.filled(3, 6, (200, 100, 50))
    out = stage_under(camera, stage)
    assert out.shape == (4 + STAGE_GAP_PX + 3, 10, 3)
    np.testing.assert_array_equal(out[:4], camera)
    np.testing.assert_array_equal(
        out[4 : 4 + STAGE_GAP_PX], draw.filled(STAGE_GAP_PX, 10, AB_GAP_COLOUR)
    )
    below = out[4 + STAGE_GAP_PX :]
    np.testing.assert_array_equal(below[:, 2:8], stage)  # (10 - 6) / 2 = 2 columns each side
    np.testing.assert_array_equal(below[:, :2], draw.filled(3, 2, AB_GAP_COLOUR))
    np.testing.assert_array_equal(below[:, 8:], draw.filled(3, 2, AB_GAP_COLOUR))


def test_a_wider_stage_picture_is_shrunk_to_the_camera_pictures_width() -> None:
    camera = draw.filled(5, 8, (0, 0, 0))
    stage = draw.filled(6, 16, (90, 90, 90))
    stage[:, 8:] = (30, 60, 120)  # its right half another colour
    out = stage_under(camera, stage)
    assert out.shape == (5 + STAGE_GAP_PX + 3, 8, 3)  # halved: 16 x 6 -> 8 x 3
    below = out[5 + STAGE_GAP_PX :]
    np.testing.assert_array_equal(below[:, :4], draw.filled(3, 4, (90, 90, 90)))
    np.testing.assert_array_equal(below[:, 4:], draw.filled(3, 4, (30, 60, 120)))


def test_a_one_pixel_line_stays_visible_in_a_stage_picture_shrunk_by_a_fifth() -> None:
    camera = draw.filled(1, 8, (0, 0, 0))
    stage = draw.filled(5, 10, (0, 0, 0))
    stage[:, 5] = (200, 200, 200)  # a 1 px line, as the marks on the symmetry matrices
    below = stage_under(camera, stage)[1 + STAGE_GAP_PX :]
    assert below.shape == (4, 8, 3)
    # bilinear: output column 4 samples input column 5.125, 7/8 of the way onto the line
    assert (below[:, 4] >= 150).all() and (below[:, :3] == 0).all() and (below[:, 6:] == 0).all()


def test_a_stage_picture_over_twice_as_wide_is_shrunk_by_area_averaging() -> None:
    camera = draw.filled(1, 6, (0, 0, 0))
    stage = draw.filled(4, 24, (0, 0, 0))
    stage[:, 3::4] = (200, 200, 200)  # one bright column in four
    below = stage_under(camera, stage)[1 + STAGE_GAP_PX :]
    assert below.shape == (1, 6, 3)
    # each output pixel averages four columns, one of them bright (bilinear would sample
    # between columns 4k + 1 and 4k + 2 and miss every bright one)
    np.testing.assert_array_equal(below, draw.filled(1, 6, (50, 50, 50)))


def test_a_picture_that_is_not_rgb_is_refused_by_name() -> None:
    camera = draw.filled(5, 8, (0, 0, 0))
    with pytest.raises(ValueError, match=r"^stage: expected an \(H, W, 3\)"):
        stage_under(camera, np.zeros((3, 4), np.uint8))
    with pytest.raises(ValueError, match=r"^picture: expected an \(H, W, 3\)"):
        stage_under(np.zeros((3, 4), np.uint8), camera)


def test_comparing_puts_a_and_b_side_by_side_and_lists_the_differences() -> None:
    drive = FakeDrive(frames=4)
    engines = ClientEngines(drive.camera)
    a = engines.result("a", drive, Params(), 3)
    b = engines.result("b", drive, Params(), 3)
    alone = render_view(drive, ViewState(frame=3), a, drive.frame(3))
    both = render_view(drive, ViewState(frame=3, params_b=Params()), a, drive.frame(3), b)
    height, width = alone.image.shape[:2]
    assert both.image.shape == (height, 2 * width + AB_GAP_PX, 3)
    # the same parameters draw the same picture on both sides (captions aside)
    picture_h = drive.frame(3).image.shape[0]
    np.testing.assert_array_equal(
        both.image[:picture_h, :width], both.image[:picture_h, width + AB_GAP_PX :]
    )
    assert alone.diff == ""
    assert "**A has, B lacks**\n- none" in both.diff and "**B has, A lacks**\n- none" in both.diff


def test_the_can_window_holds_the_frames_around_the_playhead_at_zero() -> None:
    drive = FakeDrive(frames=300)  # 25 Hz: 12 s
    series = can_series(drive)
    assert series is not None
    assert series.speed_kmh[0] == pytest.approx(90.0)
    assert series.yaw_rate_degps[0] == pytest.approx(np.degrees(0.01))
    dt, speed, yaw = can_window(series, 100, half_width_s=1.0)
    assert dt[0] == pytest.approx(-1.0) and dt[-1] == pytest.approx(1.0) and len(dt) == 51
    assert dt[25] == 0.0 and len(speed) == len(yaw) == 51
    dt, *_ = can_window(series, 0, half_width_s=1.0)  # at the start: only what follows
    assert dt[0] == 0.0 and len(dt) == 26


def test_a_drive_without_speed_or_yaw_rate_has_no_can_plot() -> None:
    class Silent(FakeDrive):
        def speed_at(self, t_ns: int) -> float:
            return float("nan")

        def yaw_rate_at(self, t_ns: int) -> float:
            return float("nan")

    assert can_series(Silent(frames=3)) is None


def test_the_running_median_is_taken_stage_by_stage() -> None:
    runs = [
        StageTimings(1, 2, 3, 4, 5, 6),
        StageTimings(3, 2, 1, 4, 9, 0),
        StageTimings(2, 2, 2, 2, 2, 2),
    ]
    assert median_timings(runs) == StageTimings(2, 2, 2, 4, 5, 2)
    table = timings_markdown(runs[0], median_timings(runs), 3)
    assert "| stage | ms | median of 3 |" in table and "| **total** | 21.00 | 17.00 |" in table
    with pytest.raises(ValueError, match="expected at least one"):
        median_timings([])
