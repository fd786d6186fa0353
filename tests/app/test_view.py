"""The camera panel of one frame: its picture and read-out come from the same frame."""

from __future__ import annotations

import numpy as np
import pytest
from app_fakes import HEIGHT_PX, FakeDrive

from app import draw
from app.state import Layers, ViewState
from app.view import readout_text, render_view


def test_readout_gives_frame_time_speed_and_yaw_rate_in_display_units() -> None:
    text = readout_text(3, 10, 0.12, 25.0, np.radians(2.0))
    assert text == "frame 3 / 9 | t 0.12 s | 90.0 km/h | yaw +2.00 deg/s"


def test_readout_without_can_says_not_available() -> None:
    text = readout_text(0, 1, 0.0, float("nan"), float("nan"))
    assert text == "frame 0 / 0 | t 0.00 s | speed n/a | yaw n/a"


def test_view_of_a_frame_carries_that_frames_index_and_time() -> None:
    drive = FakeDrive(frames=10)
    view = render_view(drive, ViewState(frame=2))
    assert view.frame == 2
    assert view.readout.startswith("frame 2 / 9 | t 0.08 s")
    assert view.image.shape == (HEIGHT_PX + draw.STRIP_HEIGHT_PX, 640, 3)


def test_view_without_layers_shows_the_plain_frame() -> None:
    drive = FakeDrive()
    off = Layers(radar=False, truth=False, horizon=False)
    view = render_view(drive, ViewState(frame=1, layers=off))
    np.testing.assert_array_equal(view.image[:HEIGHT_PX], draw.grey_to_rgb(drive.frame(1).image))
    on = render_view(drive, ViewState(frame=1))
    assert (on.image != view.image).any()


def test_view_of_a_frame_outside_the_drive_is_refused() -> None:
    with pytest.raises(IndexError, match=r"frame: expected an index in \[0, 10\), got 10"):
        render_view(FakeDrive(frames=10), ViewState(frame=10))
