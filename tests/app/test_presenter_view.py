"""The presenter's layers and figures (app.presenter_view), its enlarged picture (app.draw),
and the playback clock, pacer and rest both kinds of tab use (app.player)."""

from __future__ import annotations

import dataclasses
import threading
import time

import numpy as np
import pytest
from engine_frames import engine_result

from app.draw import TEXT_COLOUR, scaled_to_width
from app.legend import BANNER_COLOUR, MARGIN_PX, legend_items
from app.player import Pacer, Player, Rest
from app.presenter_view import (
    COUNTS_BASELINE_PX,
    FIGURES_HEIGHT_PX,
    TIME_BASELINE_PX,
    HeadlineFigures,
    figures_lines,
    figures_strip,
    headline_figures,
    with_figures,
)
from app.state import DEMO_LAYERS, Layers


def test_the_presenter_draws_what_was_confirmed_and_its_legend_says_it_in_plain_words() -> None:
    words = {item.words for item in legend_items(DEMO_LAYERS)}
    assert "vehicle, confirmed over several frames" in words
    assert "pedestrian, confirmed over several frames" in words
    assert "the same object followed over time" in words
    # no single frame's proposals: raw boxes, radar verdicts, guard-rail lines, how it works
    assert DEMO_LAYERS.confirmed
    on = {name for name in Layers.names() if getattr(DEMO_LAYERS, name)}
    assert on == {"confirmed"}


def test_the_figures_count_the_confirmed_tracks_measured_this_frame() -> None:
    result = engine_result()
    figures = headline_figures(result)
    vehicles = [t for t in result.tracked_vehicles if t.misses == 0]
    assert figures.vehicles == len(vehicles) > 0
    assert figures.nearest_vehicle_m == min(t.x_m for t in vehicles)
    pedestrians = [t for t in result.tracked_pedestrians if t.misses == 0]
    assert figures.pedestrians == len(pedestrians)
    assert figures.processing_ms == result.timings.total_ms
    # a track missed this frame, or one not yet confirmed, is not counted
    measured = vehicles[0]
    for other in (
        dataclasses.replace(measured, misses=1),
        dataclasses.replace(measured, confirmed=False),
    ):
        tracking = dataclasses.replace(result.tracking, tracks=(measured, other))
        assert headline_figures(dataclasses.replace(result, tracking=tracking)).vehicles == 1
    empty = dataclasses.replace(result, tracking=dataclasses.replace(result.tracking, tracks=()))
    assert headline_figures(empty).nearest_vehicle_m is None
    assert headline_figures(empty).vehicles == 0 < len(result.vehicle.vehicles)


def test_the_figures_read_as_words() -> None:
    counts, time_text = figures_lines(HeadlineFigures(1, 2, 23.4, 4.25))
    assert counts == "1 vehicle   |   2 pedestrians   |   nearest vehicle 23 m"
    assert time_text == "4.2 ms to process this frame"
    assert figures_lines(HeadlineFigures(0, 0, None, 1.0))[0] == "0 vehicles   |   0 pedestrians"


def test_the_figures_are_drawn_over_the_picture_in_the_same_image() -> None:
    picture = np.full((100, 740, 3), 77, np.uint8)
    figures = HeadlineFigures(12, 10, 123.4, 123.45)  # the widest counts a frame gives
    out = with_figures(picture, figures)
    assert out.shape == (FIGURES_HEIGHT_PX + 100, 740, 3) and out.flags.c_contiguous
    np.testing.assert_array_equal(out[FIGURES_HEIGHT_PX:], picture)
    strip = out[:FIGURES_HEIGHT_PX]
    np.testing.assert_array_equal(strip, figures_strip(figures, 740))
    white = np.all(strip == TEXT_COLOUR, axis=2)
    background = np.all(strip == BANNER_COLOUR, axis=2)
    assert white.any() and np.count_nonzero(background) > strip.shape[0] * strip.shape[1] // 2
    rows = np.flatnonzero(white.any(axis=1))
    assert rows.min() < COUNTS_BASELINE_PX < TIME_BASELINE_PX <= rows.max() + 1
    # both lines fit: the text ends before the strip's right margin, and the counts line is
    # wider than the time line under it
    columns = np.flatnonzero(white.any(axis=0))
    assert columns.max() < 740 - MARGIN_PX
    counts_end = np.flatnonzero(white[: COUNTS_BASELINE_PX + 2].any(axis=0)).max()
    time_end = np.flatnonzero(white[COUNTS_BASELINE_PX + 10 :].any(axis=0)).max()
    assert counts_end > time_end
    with pytest.raises(ValueError, match="picture"):
        with_figures(np.zeros((10, 10), np.uint8), figures)


def test_an_enlarged_picture_keeps_its_aspect() -> None:
    rgb = np.zeros((300, 640, 3), np.uint8)
    rgb[:, 320:] = 200
    big = scaled_to_width(rgb, 960)
    assert big.shape == (450, 960, 3) and big.dtype == np.uint8
    assert big[:, :470].max() == 0 and big[:, 490:].min() == 200


def test_the_player_steps_until_a_step_says_no_more_and_stops_on_request() -> None:
    steps: list[int] = []
    done = threading.Event()

    def step() -> bool:
        steps.append(len(steps))
        if len(steps) == 3:
            done.set()
            return False
        return True

    player = Player("test")
    assert not player.playing
    player.start(lambda: 0.001, step)
    assert done.wait(5.0)
    player._stop.wait(5.0)
    assert steps == [0, 1, 2] and not player.playing

    again = threading.Event()
    player.start(lambda: 0.001, lambda: again.set() or True)
    assert again.wait(5.0) and player.playing
    player.stop()
    assert not player.playing


def test_the_pacer_says_yes_at_most_once_a_period(monkeypatch: pytest.MonkeyPatch) -> None:
    now_s = [100.0]
    monkeypatch.setattr("app.player.time.monotonic", lambda: now_s[0])
    pace = Pacer(0.2)
    answers = []
    for t_s in (100.0, 100.1, 100.19, 100.2, 100.35, 100.41, 105.0):
        now_s[0] = t_s
        answers.append(pace.due())
    # yes at 100.0; then 0.2 s after each yes: 100.2 and 100.41 (100.35 is 0.15 s after 100.2)
    assert answers == [True, False, False, True, False, True, True]


def test_a_burst_of_pokes_ends_in_one_call_a_rest_after_the_last() -> None:
    calls: list[float] = []
    called = threading.Event()

    def action() -> None:
        calls.append(time.monotonic())
        called.set()

    rest = Rest(0.05, action, "test-rest")
    for _ in range(5):
        before_poke = time.monotonic()
        rest.poke()
        time.sleep(0.01)
    assert called.wait(5.0)
    time.sleep(0.2)  # no second call comes
    assert len(calls) == 1 and calls[0] >= before_poke + 0.05

    called.clear()
    rest.poke()
    rest.cancel()
    assert not called.wait(0.2) and len(calls) == 1
