from __future__ import annotations

import pytest

from app.state import Layers, ViewState
from core.params import Params


def test_state_starts_at_frame_zero_paused_with_the_papers_parameters() -> None:
    state = ViewState()
    assert (state.frame, state.playing) == (0, False)
    assert state.layers.radar and state.layers.vehicles and state.layers.horizon
    assert not state.layers.truth  # the engine's output first; truth on request
    assert not state.layers.confirmed  # the demo's picture; the frame's own detections first
    assert state.params == Params()
    assert Layers.names()[0] == "radar" and len(Layers.names()) == 13


def test_negative_frame_is_refused() -> None:
    with pytest.raises(ValueError, match="frame: expected an index >= 0, got -1"):
        ViewState(frame=-1)
