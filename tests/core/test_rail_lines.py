"""Guard-rail lines from the returns found over the last seconds (core.rail_lines): known
answers on rails placed by hand, the car's motion, the gates, and the papers' preset."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from core.ego import EgoMotion
from core.guardrail import GuardRailCheck, GuardRailResult
from core.io.frame import RadarTarget
from core.params import GuardRailParams, Params, ParamsError, params_from
from core.rail_lines import (
    LINE_EXTEND_M,
    LINE_MAX_OUTLIER_FRACTION,
    LINE_MAX_RMS_M,
    RailReturns,
    along_rail_lines,
    fit_line,
    remember,
)

PARAMS = GuardRailParams()
# nothing remembered, after returns have been gathered long enough to judge a side by them
GATHERED = dataclasses.replace(RailReturns.none(), gathered_s=PARAMS.line_memory_s)
NO_PIXELS = np.zeros((0, 2), dtype=np.int32)


def target_at(x_m: float, y_m: float) -> RadarTarget:
    return RadarTarget.from_polar(math.hypot(x_m, y_m), math.atan2(y_m, x_m), 0.0, 0.0, 0.0, 0.0)


def check(index: int, verdict: str, side: str = "right") -> GuardRailCheck:
    return GuardRailCheck(
        target_index=index,
        side=side,
        real_speed_mps=0.0,
        edges=np.zeros((4, 8), dtype=np.uint8),
        line_px=NO_PIXELS,
        holes_px=NO_PIXELS,
        coverage=0.3 if verdict == "not_guard_rail" else 0.9,
        verdict=verdict,
        overlapped_by=None,
    )


def rail_y_m(x_m: float) -> float:
    """A right rail 7 m off, bending gently left: y = -7 + 0.002 x^2."""
    return -7.0 + 0.002 * x_m**2


def returns_at(
    xs: list[float], ys: list[float], side: str = "right", age_s: float = 0.0
) -> RailReturns:
    n = len(xs)
    return RailReturns(
        np.array(xs, dtype=np.float64),
        np.array(ys, dtype=np.float64),
        np.full(n, side == "left"),
        np.full(n, age_s),
    )


def returns_on_rail(xs: list[float], side: str = "right") -> RailReturns:
    return returns_at(xs, [rail_y_m(x) for x in xs], side)


def test_a_bending_rail_is_fitted_with_its_parabola() -> None:
    line = fit_line(returns_on_rail([10, 15, 20, 25, 30, 40]), "right")
    assert line is not None and line.returns == 6
    assert line.coefficients == pytest.approx((-7.0, 0.0, 0.002), abs=1e-9)
    assert line.rms_m == pytest.approx(0.0, abs=1e-9)
    assert (line.x_near_m, line.x_far_m) == (10 - LINE_EXTEND_M, 40 + LINE_EXTEND_M)
    assert line.y_m(50.0) == pytest.approx(rail_y_m(50.0))
    assert line.holds(50.0, rail_y_m(50.0) + 0.3, 0.4)
    assert not line.holds(50.0, rail_y_m(50.0) + 0.5, 0.4)  # beyond the gate across
    assert not line.holds(61.0, rail_y_m(61.0), 0.4)  # beyond the stretch


def test_four_returns_make_a_straight_line_and_fewer_none() -> None:
    straight = fit_line(returns_on_rail([10, 14, 18, 22]), "right")
    assert straight is not None and len(straight.coefficients) == 2
    assert fit_line(returns_on_rail([10, 14, 18]), "right") is None
    assert fit_line(returns_on_rail([10, 14, 18, 22]), "left") is None  # the other side's


def test_returns_close_together_or_scattered_make_no_line() -> None:
    assert fit_line(returns_on_rail([20, 22, 24, 26, 28]), "right") is None  # 8 m < 10 m
    xs = [10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0]
    zigzag = returns_at(xs, [-7.0 + (1.0 if k % 2 else -1.0) for k in range(len(xs))])

    assert fit_line(zigzag, "right") is None  # RMS 1 m > LINE_MAX_RMS_M
    assert LINE_MAX_RMS_M < 1.0


def test_a_few_wrong_returns_are_left_out_of_the_line() -> None:
    xs = [10.0, 14.0, 18.0, 22.0, 26.0, 30.0, 34.0, 38.0, 42.0]
    ys = [rail_y_m(x) for x in xs]
    ys[2] += 4.0  # a car's return labelled by mistake, inside the rail
    ys[6] -= 5.0  # clutter beyond it
    line = fit_line(returns_at(xs, ys), "right")
    assert line is not None and line.returns == 7
    assert line.coefficients == pytest.approx((-7.0, 0.0, 0.002), abs=1e-9)
    assert line.rms_m == pytest.approx(0.0, abs=1e-9)
    # more than LINE_MAX_OUTLIER_FRACTION wrong: no line rather than a line through them
    ys[4] += 3.0
    assert LINE_MAX_OUTLIER_FRACTION * len(xs) < 3
    assert fit_line(returns_at(xs, ys), "right") is None


def test_remembered_returns_move_with_the_car_and_age_out() -> None:
    old = RailReturns(
        np.array([20.0, 30.0]),
        np.array([-7.0, -7.0]),
        np.array([False, True]),
        np.array([0.5, 1.95]),
    )
    found = GuardRailResult(
        (check(0, "guard_rail", "left"), check(1, "overlap"), check(2, "not_guard_rail"))
    )
    radar = (target_at(40.0, 7.0), target_at(45.0, -7.0), target_at(50.0, -7.0))
    # the car drove 3 m ahead in 0.1 s, turning 0.01 rad left
    ego = EgoMotion(3.0, 0.0, 0.01, 0.1)
    kept = remember(old, found, radar, ego, 0.1, 2.0)
    # the second aged past 2 s; only the searched rail of this frame joins
    assert len(kept) == 2
    x, y = ego.carry(20.0, -7.0)
    np.testing.assert_allclose(kept.x_m, [x, 40.0])
    np.testing.assert_allclose(kept.y_m, [y, 7.0])
    np.testing.assert_array_equal(kept.left, [False, True])
    np.testing.assert_allclose(kept.age_s, [0.6, 0.0])
    assert kept.x_m[0] == pytest.approx(17.0, abs=0.1) and kept.y_m[0] < -7.0  # turned left
    # the car's motion unknown: nothing remembered can be placed
    alone = remember(old, found, radar, None, 0.1, 2.0)
    assert len(alone) == 1 and alone.x_m[0] == pytest.approx(40.0)
    # the time gathered grows frame by frame, with or without returns, until then
    assert kept.gathered_s == pytest.approx(0.1) and alone.gathered_s == 0.0
    nothing = GuardRailResult(())
    later = remember(remember(kept, nothing, radar, ego, 0.1, 2.0), nothing, radar, ego, 0.1, 2.0)
    assert later.gathered_s == pytest.approx(0.3)
    empty = remember(RailReturns.none(), nothing, radar, ego, 0.1, 2.0)
    assert len(empty) == 0 and empty.gathered_s == pytest.approx(0.1)


def test_a_target_along_the_line_is_labelled_and_others_are_not() -> None:
    xs = [10.0, 16.0, 22.0, 28.0, 34.0, 40.0]
    radar = [target_at(x, rail_y_m(x)) for x in xs]
    radar += [
        target_at(46.0, rail_y_m(46.0) + 0.3),  # 6: along the rail, missed by the search
        target_at(52.0, rail_y_m(52.0) + 1.5),  # 7: a parked car inside the rail
        target_at(30.0, 7.0),  # 8: the left side has no line
        target_at(90.0, rail_y_m(90.0)),  # 9: beyond the line's stretch
    ]
    checks = [check(i, "guard_rail") for i in range(6)]
    checks += [check(6, "not_guard_rail"), check(7, "not_guard_rail")]
    checks += [check(8, "not_guard_rail", "left"), check(9, "not_guard_rail")]
    result, lines, kept = along_rail_lines(
        GuardRailResult(tuple(checks)),
        radar,
        RailReturns.none(),
        EgoMotion.still(0.1),
        0.1,
        PARAMS,
    )
    assert [c.verdict for c in result.checks][6:] == ["line"] + ["not_guard_rail"] * 3
    assert result.guard_rail_targets == frozenset(range(7))
    assert [line.side for line in lines] == ["right"] and lines[0].returns == 6
    assert len(kept) == 6  # the found ones; one labelled along the line is not remembered
    # the next frame, nothing found by the search: the remembered returns still make the line
    again, _, _ = along_rail_lines(
        GuardRailResult((check(6, "not_guard_rail"),)),
        radar,
        kept,
        EgoMotion.still(0.1),
        0.1,
        PARAMS,
    )
    assert again.checks[0].verdict == "line"


def test_a_label_well_across_from_the_line_is_taken_back() -> None:
    xs = [10.0, 16.0, 22.0, 28.0, 34.0, 40.0]
    radar = [target_at(x, rail_y_m(x)) for x in xs]
    radar += [
        target_at(30.0, rail_y_m(30.0) - 1.5),  # 6: a pole 1.5 m behind the rail, searched
        target_at(35.0, rail_y_m(35.0) + 1.3),  # 7: a parked car inside it, by overlap
        target_at(25.0, rail_y_m(25.0) + 0.6),  # 8: a rail return scattered 0.6 m
        target_at(80.0, rail_y_m(80.0) + 2.0),  # 9: beyond the line's stretch (40 + 20 m)
        target_at(30.0, 7.0),  # 10: the left side has no other return
    ]
    overlap = [dataclasses.replace(check(i, "overlap"), overlapped_by=0) for i in (7, 9)]
    checks = [check(i, "guard_rail") for i in (0, 1, 2, 3, 4, 5, 6, 8)]
    checks += [*overlap, dataclasses.replace(check(10, "overlap", "left"), overlapped_by=0)]
    found = GuardRailResult(tuple(checks))
    still = EgoMotion.still(0.1)
    result, lines, kept = along_rail_lines(found, radar, GATHERED, still, 0.1, PARAMS)
    verdicts = {c.target_index: c.verdict for c in result.checks}
    assert PARAMS.line_veto_m == 1.0 and PARAMS.rail_returns_required
    assert [line.side for line in lines] == ["right"]
    assert lines[0].holds(30.0, rail_y_m(30.0), 0.2)
    assert [verdicts[i] for i in (6, 7, 8, 9, 10)] == [
        "off_line",
        "off_line",
        "guard_rail",
        "overlap",
        "off_line",
    ]
    assert result.guard_rail_targets == frozenset(range(11)) - {6, 7, 10}
    assert len(kept) == 8  # the pole's return stays remembered; the fit leaves it out
    assert lines[0].returns == 7
    no_veto = dataclasses.replace(PARAMS, line_veto_m=0.0)
    across, _, _ = along_rail_lines(found, radar, GATHERED, still, 0.1, no_veto)
    assert across.guard_rail_targets == frozenset(range(11)) - {10}
    any_side = dataclasses.replace(PARAMS, rail_returns_required=False)
    side, _, _ = along_rail_lines(found, radar, GATHERED, still, 0.1, any_side)
    assert side.guard_rail_targets == frozenset(range(11)) - {6, 7}


def test_a_side_with_two_barriers_keeps_its_labels_without_a_line() -> None:
    # the median's barrier 3 m left, six returns, and another 11 m left, three: a third of
    # the side's returns, too many for the line of step 2, few enough for step 4's
    radar = [target_at(x, 3.0) for x in (10.0, 20.0, 30.0, 40.0, 50.0, 60.0)]
    radar += [target_at(x, 11.0) for x in (15.0, 25.0, 35.0)]
    found = GuardRailResult(tuple(check(i, "guard_rail", "left") for i in range(9)))
    still = EgoMotion.still(0.1)
    result, lines, _ = along_rail_lines(found, radar, GATHERED, still, 0.1, PARAMS)
    assert lines == () and result.guard_rail_targets == frozenset(range(9))
    # returns scattered over 6 m across trace no rail, however many
    ys = [3.0, 9.0, 4.0, 9.0, 3.5, 8.0, 3.0, 9.5, 4.0]
    scattered = [target_at(6.0 * (k + 1), y) for k, y in enumerate(ys)]
    found = GuardRailResult(tuple(check(i, "guard_rail", "left") for i in range(9)))
    result, _, _ = along_rail_lines(found, scattered, GATHERED, still, 0.1, PARAMS)
    assert result.guard_rail_targets == frozenset()


def test_a_label_on_a_side_without_a_line_of_returns_is_taken_back() -> None:
    # one pole found on the left, three returns on the right: too few for a line either side
    radar = [target_at(20.0, 4.0), *(target_at(x, rail_y_m(x)) for x in (10.0, 16.0, 22.0))]
    checks = [check(0, "guard_rail", "left"), *(check(i, "guard_rail") for i in (1, 2, 3))]
    found = GuardRailResult(tuple(checks))
    still = EgoMotion.still(0.1)
    result, lines, kept = along_rail_lines(found, radar, GATHERED, still, 0.1, PARAMS)
    assert lines == () and len(kept) == 4
    assert result.guard_rail_targets == frozenset()
    assert {c.verdict for c in result.checks} == {"off_line"}
    # a fourth return on the right, found the next frame, makes the line there
    radar.append(target_at(28.0, rail_y_m(28.0)))
    found = GuardRailResult((*checks, check(4, "guard_rail")))
    again, lines, _ = along_rail_lines(found, radar, kept, still, 0.1, PARAMS)
    assert [line.side for line in lines] == ["right"]
    assert again.guard_rail_targets == frozenset({1, 2, 3, 4})
    # on a drive's first frame nothing can be judged yet: the labels stand
    first, _, kept = along_rail_lines(found, radar, RailReturns.none(), still, 0.0, PARAMS)
    assert first.guard_rail_targets == frozenset(range(5)) and kept.gathered_s == 0.0


def test_the_papers_preset_leaves_the_verdicts_as_they_are() -> None:
    papers = params_from("papers").guardrail
    assert papers.line_memory_s == 0.0 and PARAMS.line_memory_s == 2.0
    assert papers.line_veto_m == 0.0 and not papers.rail_returns_required
    found = GuardRailResult(tuple(check(i, "guard_rail") for i in range(6)))
    radar = [target_at(x, rail_y_m(x)) for x in (10.0, 16.0, 22.0, 28.0, 34.0, 40.0)]
    result, lines, kept = along_rail_lines(
        found, radar, RailReturns.none(), EgoMotion.still(0.1), 0.1, papers
    )
    assert result is found and lines == () and len(kept) == 0


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("line_memory_s", -1.0),
        ("line_memory_s", math.nan),
        ("line_gate_m", 0.0),
        ("line_veto_m", -0.5),
        ("line_veto_m", math.inf),
    ],
)
def test_bad_line_parameters_are_rejected_by_name(field: str, value: float) -> None:
    with pytest.raises(ParamsError, match=field):
        dataclasses.replace(PARAMS, **{field: value})
    assert Params().guardrail == PARAMS
