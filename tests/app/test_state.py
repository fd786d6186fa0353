from __future__ import annotations

import pytest

from app.state import ViewState


def test_state_starts_at_frame_zero_paused_with_all_layers() -> None:
    state = ViewState()
    assert (state.frame, state.playing) == (0, False)
    assert state.layers.radar and state.layers.truth and state.layers.horizon


def test_negative_frame_is_refused() -> None:
    with pytest.raises(ValueError, match="frame: expected an index >= 0, got -1"):
        ViewState(frame=-1)
