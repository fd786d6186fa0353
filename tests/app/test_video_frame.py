"""One frame of an exported video: the inspector's camera picture, untouched, over a banner
that names the recording, time, frame and parameter sets, and a legend drawn in the
overlays' own colours."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from app_fakes import HEIGHT_PX, WIDTH_PX, FakeDrive

from app import legend, overlays, video_frame
from app.state import Layers, ViewState
from app.view import AB_GAP_PX, camera_picture, side_by_side
from core.engine import FrameResult, FusionEngine
from core.params import Params

HASH_A = "a1b2c3d4e5"
HASH_B = "f6e5d4c3b2"
NO_LAYERS = Layers(**dict.fromkeys(Layers.names(), False))


def _result(drive: FakeDrive, index: int, params: Params | None = None) -> FrameResult:
    return FusionEngine(params or Params(), drive.camera).seek(drive, index)


def test_title_names_recording_time_frame_and_the_parameter_set() -> None:
    stamp = video_frame.Stamp("highway", 90, 150, 9.0, (HASH_A,))
    assert video_frame.title_text(stamp) == (
        f"highway  |  t 9.00 s  |  frame 90 / 149  |  params {HASH_A}"
    )


def test_title_of_a_comparison_labels_both_hashes_a_and_b() -> None:
    text = video_frame.title_text(video_frame.Stamp("x", 3, 10, 0.3, (HASH_A, HASH_B)))
    assert f"A (left) params {HASH_A}" in text and f"B (right) params {HASH_B}" in text
    assert text.index(HASH_A) < text.index(HASH_B)


def test_stamp_counts_time_from_the_drives_first_frame() -> None:
    drive = FakeDrive(frames=10)
    stamp = video_frame.stamp_of(drive, drive.frame(3), [HASH_A])
    period_s = (drive.times_ns[1] - drive.times_ns[0]) / 1e9
    assert (stamp.recording, stamp.frame, stamp.frame_count) == ("fake", 3, 10)
    assert stamp.t_s == pytest.approx(3 * period_s)


def test_stamp_needs_one_or_two_hashes() -> None:
    with pytest.raises(ValueError, match="params_hashes: expected the hash of set A"):
        video_frame.Stamp("x", 0, 1, 0.0, (HASH_A, HASH_B, HASH_A))


def test_video_frame_is_the_inspectors_picture_over_its_banner() -> None:
    drive = FakeDrive(frames=5)
    result = _result(drive, 2)
    out = video_frame.video_frame(drive, Layers(), drive.frame(2), [result], [HASH_A])
    picture = camera_picture(drive, ViewState(frame=2), result, drive.frame(2))
    strip = legend.legend_strip(Layers(), WIDTH_PX)
    assert out.shape == (HEIGHT_PX + video_frame.TITLE_HEIGHT_PX + strip.shape[0], WIDTH_PX, 3)
    np.testing.assert_array_equal(out[:HEIGHT_PX], picture)
    title = out[HEIGHT_PX : HEIGHT_PX + video_frame.TITLE_HEIGHT_PX]
    stamp = video_frame.stamp_of(drive, drive.frame(2), [HASH_A])
    expected = video_frame.title_strip(video_frame.title_text(stamp), WIDTH_PX)
    np.testing.assert_array_equal(title, expected)
    np.testing.assert_array_equal(out[HEIGHT_PX + video_frame.TITLE_HEIGHT_PX :], strip)


def test_a_and_b_side_by_side_over_one_banner_as_wide() -> None:
    drive = FakeDrive(frames=5)
    b_params = dataclasses.replace(
        Params(), tracking=dataclasses.replace(Params().tracking, confirm_frames=1)
    )
    a, b = _result(drive, 4), _result(drive, 4, b_params)
    out = video_frame.video_frame(drive, Layers(), drive.frame(4), [a, b], [HASH_A, HASH_B])
    state = ViewState(frame=4)
    pictures = [camera_picture(drive, state, r, drive.frame(4)) for r in (a, b)]
    assert out.shape[1] == 2 * WIDTH_PX + AB_GAP_PX
    np.testing.assert_array_equal(out[:HEIGHT_PX], side_by_side(*pictures))
    assert (
        out.shape[0]
        == HEIGHT_PX
        + video_frame.TITLE_HEIGHT_PX
        + (legend.legend_strip(Layers(), out.shape[1]).shape[0])
    )


def test_scaled_frame_has_the_width_asked_and_its_banner_drawn_at_it() -> None:
    drive = FakeDrive(frames=3)
    result = _result(drive, 1)
    out = video_frame.video_frame(drive, Layers(), drive.frame(1), [result], [HASH_A], 320)
    picture_h = round(HEIGHT_PX * 320 / WIDTH_PX)
    legend_h = legend.legend_strip(Layers(), 320).shape[0]
    assert out.shape == (picture_h + video_frame.TITLE_HEIGHT_PX + legend_h, 320, 3)


def test_every_layer_has_its_legend_and_each_mark_is_drawn_in_its_colour() -> None:
    assert set(legend.LEGEND) == set(Layers.names())
    every = Layers(**dict.fromkeys(Layers.names(), True))
    items = legend.legend_items(every)
    strip = legend.legend_strip(every, WIDTH_PX)
    colours = {tuple(int(c) for c in px) for px in strip.reshape(-1, 3)}
    for item in items:
        assert item.colour in colours, item


def test_legend_lists_only_the_layers_switched_on() -> None:
    only = dataclasses.replace(NO_LAYERS, vehicles=True, radar=True)
    items = legend.legend_items(only)
    assert items == legend.LEGEND["vehicles"] + legend.LEGEND["radar"]
    assert items[0].colour == overlays.VEHICLE_COLOUR
    assert legend.legend_items(NO_LAYERS) == ()
    assert legend.legend_strip(NO_LAYERS, WIDTH_PX).shape == (0, WIDTH_PX, 3)


@pytest.mark.parametrize("width_px", [200, 640, 1288])
def test_legend_lines_fit_the_width(width_px: int) -> None:
    items = legend.legend_items(Layers(**dict.fromkeys(Layers.names(), True)))
    lines = legend.legend_lines(items, width_px)
    assert [i for line in lines for i in line] == list(items)
    for line in lines:
        used = sum(legend._item_width_px(i) for i in line)
        used += legend.ITEM_GAP_PX * (len(line) - 1) + legend.MARGIN_PX
        assert used <= width_px or len(line) == 1
    assert len(legend.legend_strip(Layers(), width_px)) == (
        len(legend.legend_lines(legend.legend_items(Layers()), width_px)) * legend.LEGEND_LINE_PX
        + legend.LEGEND_BOTTOM_PX
    )


def test_video_frame_refuses_results_of_another_frame_or_unmatched_hashes() -> None:
    drive = FakeDrive(frames=3)
    result = _result(drive, 1)
    with pytest.raises(
        ValueError, match=r"results: expected results of frame 2, got frame\(s\) \[1\]"
    ):
        video_frame.video_frame(drive, Layers(), drive.frame(2), [result], [HASH_A])
    with pytest.raises(ValueError, match="results, params_hashes: expected one of each"):
        video_frame.video_frame(drive, Layers(), drive.frame(1), [result], [HASH_A, HASH_B])
    with pytest.raises(ValueError, match="width_px: expected at least"):
        video_frame.video_frame(drive, Layers(), drive.frame(1), [result], [HASH_A], 4)
