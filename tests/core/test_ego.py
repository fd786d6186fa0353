"""Ego motion (paper 000 eq. 3-5): straight line, circle in closed form, gamma -> 0, chaining."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from core.ego import EgoMotion, chord_length_m, integrate, step

S = 1_000_000_000


def test_straight_line() -> None:
    m = step(20.0, 0.0, 0.1)
    assert (m.dx_m, m.dy_m, m.dyaw_rad) == pytest.approx((2.0, 0.0, 0.0))


@given(
    v=st.floats(0.5, 40.0),
    w=st.floats(-0.5, 0.5).filter(lambda w: abs(w) > 1e-3),
    t=st.floats(0.01, 2.0),
)
def test_circle_in_closed_form(v: float, w: float, t: float) -> None:
    # On a circle of radius R = v / w the car ends at (R sin wT, R (1 - cos wT)).
    r = v / w
    m = step(v, w, t)
    assert m.dx_m == pytest.approx(r * math.sin(w * t), abs=1e-9)
    assert m.dy_m == pytest.approx(r * (1 - math.cos(w * t)), abs=1e-9)
    assert m.dyaw_rad == pytest.approx(w * t)


def test_chord_is_continuous_through_zero_yaw_rate() -> None:
    near = [chord_length_m(25.0, w, 0.1) for w in (-1e-12, 0.0, 1e-12, 1e-6)]
    assert near == pytest.approx([2.5] * 4, rel=1e-9)
    assert all(math.isfinite(c) for c in near)


def test_pieces_of_a_circle_chain_to_the_whole_circle() -> None:
    # Constant signals sampled every 10 ms: chaining eq. (4) over the pieces is exact.
    t = np.arange(0, 2 * S, S // 100, dtype=np.int64)
    v, w = np.full(len(t), 15.0), np.full(len(t), 0.3)
    m = integrate(0, S, t, v, t, w)
    whole = step(15.0, 0.3, 1.0)
    assert m.pieces == 100
    assert (m.dx_m, m.dy_m, m.dyaw_rad) == pytest.approx(
        (whole.dx_m, whole.dy_m, whole.dyaw_rad), abs=1e-9
    )


def test_braking_between_frames_is_followed() -> None:
    # Speed falls linearly 20 -> 10 m/s over the frame interval, straight: 15 m, not 20 or 10.
    t = np.array([0, S // 2, S], dtype=np.int64)
    m = integrate(0, S, t, np.array([20.0, 15.0, 10.0]), t, np.zeros(3))
    assert m.dx_m == pytest.approx(15.0)
    # The paper's single interval with the start value would say 20 m.
    assert step(20.0, 0.0, 1.0).dx_m == pytest.approx(20.0)


def test_turn_starting_between_frames() -> None:
    # Straight for 0.5 s at 10 m/s, then a 0.2 rad/s turn: the yaw is that of the last half.
    t = np.array([0, S // 2 - 1, S // 2, S], dtype=np.int64)
    yaw = np.array([0.0, 0.0, 0.2, 0.2])
    m = integrate(0, S, t, np.full(4, 10.0), t, yaw)
    assert m.dyaw_rad == pytest.approx(0.1, abs=1e-6)
    first = step(10.0, 0.0, 0.5)
    second = step(10.0, 0.2, 0.5, heading0_rad=0.0)
    assert m.dx_m == pytest.approx(first.dx_m + second.dx_m, abs=1e-6)
    assert m.dy_m == pytest.approx(second.dy_m, abs=1e-6)


def test_signals_held_past_their_ends_and_degenerate_inputs() -> None:
    one = np.array([5 * S], dtype=np.int64)
    m = integrate(0, S, one, np.array([10.0]), one, np.array([0.0]))
    assert m.dx_m == pytest.approx(10.0)
    assert integrate(S, S, one, np.array([10.0]), one, np.array([0.0])) == EgoMotion.still()
    with pytest.raises(ValueError, match="t1_ns"):
        integrate(S, 0, one, np.array([1.0]), one, np.array([0.0]))
    empty = np.zeros(0, dtype=np.int64)
    with pytest.raises(ValueError, match="at least one sample"):
        integrate(0, S, empty, np.zeros(0), one, np.array([0.0]))


@pytest.mark.parametrize("bad", ["speed_mps", "yaw_rate_radps", "dt_s"])
def test_a_missing_signal_is_a_clear_error(bad: str) -> None:
    args = {"speed_mps": 10.0, "yaw_rate_radps": 0.1, "dt_s": 0.1, bad: math.nan}
    with pytest.raises(ValueError, match=f"{bad}: expected a finite number, got nan"):
        step(**args)
    with pytest.raises(ValueError, match="dyaw_rad: expected a finite number"):
        EgoMotion(1.0, 0.0, math.nan, 0.1)
