"""Guard-rail lines from the radar returns the guard-rail filter found over the last seconds
(beyond paper 002).

Paper 002 decides target by target, on what the camera shows in each one's area. A rail
hidden behind a truck in the next lane, or lost in a dark or low-contrast stretch, leaves
its returns unlabelled, and they are then searched for vehicles, where a rail's posts are
symmetric enough to make a box. A rail is one long line along the road, and the returns the
filter did find on it over the last seconds trace that line. Per frame:

1. every remembered return is carried into this frame's vehicle frame by the car's own motion
   (a rail stands still; `EgoMotion.carry`) and forgotten `line_memory_s` after it was found;
   with the car's motion unknown, all are forgotten. This frame's returns labelled by a
   line search (verdict 'guard_rail'; not those labelled by overlap, which no search saw)
   join them, with their side;
2. per side, the remembered returns are fitted with y = c0 + c1 x (+ c2 x^2 with at least
   QUADRATIC_MIN_POINTS returns, for a bend) by least squares, when there are at least
   LINE_MIN_POINTS spanning LINE_MIN_SPAN_M along x. While the fit's RMS residual exceeds
   LINE_MAX_RMS_M, the return farthest from it is left out and the rest fitted again, up to
   LINE_MAX_OUTLIER_FRACTION of the returns (a few wrong labels among a rail's returns); a
   fit still that loose (returns scattered, or a bend sharper than a parabola) is no line;
3. each slow target of that side the filter searched without finding a rail
   ('not_guard_rail') that lies within `line_gate_m` of the line across, between
   LINE_EXTEND_M before its nearest return and as far beyond its farthest, is labelled guard
   rail too, verdict 'line'. Targets where the tracker expects a vehicle are never checked
   (`GuardRailParams.skip_tracked_vehicles`), so never labelled here either;
4. a target the filter labelled guard rail, by its search ('guard_rail') or by overlap
   ('overlap'), is not a rail return when its side's remembered returns (this frame's
   included) trace no line even loosely: fitted as in step 2, but allowed an RMS residual
   of LOOSE_LINE_RMS_M once up to LOOSE_LINE_OUTLIER_FRACTION of them are left out (a
   second barrier beside the first; `rail_returns_required`: a rail is a long line of
   returns, and the area's line search also finds lines on kerbs, signs, field edges and
   parked trucks where there is none), or when it lies along its side's line (as in step
   3) but more than `line_veto_m` across from it: verdict 'off_line', and it is searched
   for vehicles as any other target (Notes). It stays remembered (step 1), where the fit
   can use it, or leave it out as an outlier. A side is judged by its returns once they
   have been gathered for `line_memory_s` (`RailReturns.gathered_s`): on a drive's first
   frames, or after a frame whose car motion was unknown, the filter's labels stand.

`line_memory_s` 0 (the papers' preset) leaves the filter's verdicts as they are;
`rail_returns_required` False and `line_veto_m` 0 leave out step 4.

Coordinates: the vehicle frame (x forward, y left, metres).

Notes:
    - Only returns a line search labelled make the line, never those labelled by it, so a
      wrong label cannot spread from frame to frame.
    - Measured with `fusionscope evaluate` on drives of new seeds (20 s each), off -> on
      (2 s, 0.4 m): rail returns labelled, highway / exurban, 0.53 / 0.64 -> 0.72 / 0.66
      (seeds 1313 + 1414) and 0.54 / 0.57 -> 0.64 / 0.60 (held out, 1717 + 1818); vehicle
      FP per frame 0.237 / 0.142 -> 0.168 / 0.130 and 0.168 / 0.163 -> 0.145 / 0.160 (the
      rail's posts no longer searched for vehicles); rail FP per frame within +0.005 on
      both, stop_and_go (no rails) 0.100 -> 0.122 on the held-out pair (lines through the
      search's own false rails); vehicles labelled guard rail 21 -> 22 and 17 -> 17
      (exurban; parked cars beside the rail); RD and MOTA within 0.005. nuScenes and aiMotive
      the same. A 0.8 m gate labelled more rail returns (highway 0.81 on seeds 1313 +
      1414) but 28 vehicles on exurban, and a fit allowed 0.8 m RMS bent round parked cars.
    - Step 2, the returns left out (beyond the first version of this module, which fitted
      all of them): a rail's remembered returns held a few that the search had labelled
      wrongly (clutter, a car's return) 3-6 m off the rail, and one such return pushed the
      fit's RMS residual over LINE_MAX_RMS_M (0.7-1.3 m on highway drives with 20-40
      returns a side), so most frames had no line at all and the returns behind a truck in
      the next lane stayed unlabelled. Leaving out up to a quarter of them (the farthest
      first), on drives of new seeds (20 s each), highway / exurban, seeds 1818-2525 /
      1313-1717 + 2727: rail returns labelled 0.73 / 0.72 -> 0.82 / 0.83 and 0.72 / 0.85 ->
      0.80 / 0.94; vehicle FP per frame 0.077 / 0.130 -> 0.068 / 0.119 and 0.070 / 0.101 ->
      0.062 / 0.096; rail FP per frame on exurban 0.263 -> 0.307 and 0.307 -> 0.326;
      vehicles labelled guard rail on exurban 30 -> 56 and 40 -> 54: cars parked on the
      shoulder, their returns 0.1-0.4 m inside a rail 1 m from their centre, now have a
      line beside them (vision rarely boxed them: RD / (RD + FN) 0.767 -> 0.764 and 0.777
      -> 0.774, radar-seen MOTA 0.569 -> 0.548 and 0.580 -> 0.577). Searching the targets
      along a line for vehicles and giving a found vehicle its target back kept exurban's
      RD and cut those 56 / 54 to 42 / 49, but the boxes it kept on rail returns raised
      highway's vehicle FP to 0.081 / 0.077. stop_and_go (no rails), nuScenes and aiMotive:
      the same figures (aiMotive labels 320 returns instead of 222, none on a vehicle).
      The fit is compiled (numba): written with numpy, the refits cost 0.2 ms a frame
      more on the bundled highway and exurban drives (0.4 / 0.3 ms in all), compiled the
      whole fit takes 0.06 / 0.05 ms a frame.
    - The gate across, with the lines so fitted, 0.4 -> 0.5 m (highway / exurban, seeds
      1818-2525 / 1313-1717 + 2727): rail returns labelled 0.81 / 0.80 -> 0.85 / 0.83 and
      0.79 / 0.92 -> 0.82 / 0.94; vehicle FP per frame on highway 0.037 -> 0.033 and 0.035
      -> 0.029; vehicles labelled guard rail on exurban 51 -> 53 and 53 -> 58, its RD /
      (RD + FN) and radar-seen MOTA down by 0.000-0.004; stop_and_go and nuScenes the same.
      0.3 m labelled fewer (highway 0.77).
    - "Rail returns labelled" in the Notes above divided every labelled target by the rail
      returns, wrong labels included. The share of the rail returns labelled (1 - FN /
      returns), which step 4's Note gives, is lower: 0.83 / 0.63 on highway / exurban held
      out before step 4.
    - Step 4 (`line_veto_m`): the guard-rail filter labels whatever slow target its area
      shows a rail line across, and a rail's area is large in the image: returns on poles
      and signs 1-2 m behind the rail, on cars parked beside it, and the radar's false
      alarms near it were labelled by their own search or by overlap, while a rail's
      returns scatter about 0.2 m across its line (the synthetic radar's), and a line is
      fitted only where they lie within LINE_MAX_RMS_M of it. Measured with `fusionscope
      evaluate` on drives of new seeds (20 s each), off -> 1 m, highway / exurban, held out
      1818-2525 / twelve other seeds (1313-1717, 2727, 2929-3636): rail FP per frame 0.098
      / 0.289 -> 0.019 / 0.215 and 0.091 / 0.322 -> 0.032 / 0.231; vehicles labelled guard
      rail on exurban 57 -> 55 and 176 -> 158; rail returns labelled (1 - FN / returns)
      0.83 / 0.63 -> 0.83 / 0.62 and 0.83 / 0.68 -> 0.83 / 0.67; vehicle FP per frame on
      exurban 0.048 -> 0.048 and 0.038 -> 0.045 (poles now searched for vehicles); RD /
      (RD + FN) and radar-seen MOTA within 0.002. stop_and_go (no rails) the same; nuScenes
      121 -> 116 targets labelled, the same vehicles among them (13); aiMotive 338 -> 332
      labelled, one vehicle FP more in 50 frames. The veto only within the returns' own
      stretch (not LINE_EXTEND_M beyond): rail FP per frame 0.041 / 0.247 on the twelve.
      Over all sixteen exurban drives: 1.5 m, rail FP per frame 0.314 -> 0.291 (1 m:
      0.227; the poles stand 1-1.5 m behind the rail); forgetting a vetoed return (not
      remembered for the next frames' fits), vehicles labelled guard rail 213 -> 242.
    - Step 4, no line of returns on the side (`rail_returns_required`, after the veto
      above): on stop_and_go, which has no rail, every label is false (rail FP per frame
      0.07-0.11), and they come one or two at a time; nuScenes' vehicles labelled guard rail
      are parked trucks and trailers whose low edges made lines in their areas, their
      returns scattered. Measured with `fusionscope evaluate` on drives of new seeds (20 s
      each), off -> on, highway / exurban / stop_and_go, held out 1818-2525 / the twelve
      other seeds: rail FP per frame 0.019 / 0.215 / 0.109 -> 0.018 / 0.181 / 0.049 and
      0.032 / 0.231 / 0.072 -> 0.030 / 0.169 / 0.025 (most of stop_and_go's left lie in
      each drive's first 2 s, not judged); vehicles labelled guard rail on exurban 55 -> 52
      and 158 -> 148, on stop_and_go 4 -> 0 and 3 -> 0; rail returns labelled (1 - FN /
      returns) 0.83 / 0.62 -> 0.83 / 0.60 and 0.83 / 0.67 -> 0.82 / 0.66; vehicle FP per
      frame up by 0.000-0.003; RD / (RD + FN) and radar-seen MOTA within 0.002. nuScenes:
      116 -> 71 targets labelled, vehicles among them 13 -> 4, its vehicle figures the same;
      aiMotive 332 -> 330, vehicle FP the same. Seed 3838 (never used before): rail FP per
      frame 0.085 / 0.285 / 0.140 -> 0.020 / 0.130 / 0.080 with the veto, rail returns
      labelled 0.71 / 0.59 -> 0.70 / 0.57. The variants, held out unless said: returns
      merely enough for a line (four over 10 m, no fit) gave the same synthetic figures but
      left nuScenes' vehicles labelled at 12; a loose line of 0.7 m with up to 40 % left
      out, 4 (and 1.0 m with 30 %, 3), the synthetic and aiMotive figures the same; the
      line of step 2 itself (0.4 m, a quarter left out) 0.011 / 0.147 / 0.019 and nuScenes
      1, but rail returns labelled on exurban 0.57 (held out) and 0.63 (twelve), where
      curves left six returns or more over 10 m without that line, and 201 of aiMotive's
      332 labels, whose left side holds two barriers (the median's at 2.5-3 m, another at
      10-11.5 m, a third of the returns): one line a side fits neither. Judged from the
      first frame (nothing remembered there yet): the bundled highway lost its labels on
      frame 0.
    - A seek replays `core.engine.replay_window` frames (22 under the defaults): 2.2 s at
      10 Hz rebuilds the 2 s memory, at 15 Hz (aiMotive) 1.5 s of it, too little for step 4
      to judge a side by its returns: there a replayed frame keeps labels the playback
      takes back, until the engine's from-start states reach it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numba
import numpy as np
import numpy.typing as npt

from core.ego import EgoMotion
from core.guardrail import SIDES, GuardRailResult
from core.io.frame import RadarTarget
from core.params import GuardRailParams

# Steps 2-3 (module docstring): the returns a line needs, and how far along x they spread;
# a parabola from this many; the fit's largest RMS residual; the share of the returns that
# may be left out to reach it; how far the line holds beyond its nearest and farthest return.
LINE_MIN_POINTS = 4
LINE_MIN_SPAN_M = 10.0
QUADRATIC_MIN_POINTS = 6
LINE_MAX_RMS_M = 0.4
LINE_MAX_OUTLIER_FRACTION = 0.25
LINE_EXTEND_M = 20.0
# Step 4: a side's returns trace a rail, loosely, when a line holds them within this RMS
# residual once up to this share of them is left out (a second barrier beside the first)
LOOSE_LINE_RMS_M = 1.0
LOOSE_LINE_OUTLIER_FRACTION = 1 / 3


F64Array = npt.NDArray[np.float64]

_jit = numba.njit(cache=True, nogil=True)


@dataclass(frozen=True, eq=False)
class RailReturns:
    """The returns the filter found on rails, one entry each: x_m, y_m (N,) where they are in
    the current vehicle frame; left (N,) bool: on the left rail (else the right); age_s (N,)
    how long ago they were found; gathered_s: how long returns have been gathered, since
    the first frame or the last one whose car motion was unknown (step 4 judges a side by
    its returns once this reaches `line_memory_s`)."""

    x_m: F64Array
    y_m: F64Array
    left: npt.NDArray[np.bool_]
    age_s: F64Array
    gathered_s: float = 0.0

    @staticmethod
    def none() -> RailReturns:
        empty = np.zeros(0, dtype=np.float64)
        return RailReturns(empty, empty, np.zeros(0, dtype=bool), empty)

    def __len__(self) -> int:
        return len(self.x_m)

    def of_side(self, side: str) -> tuple[F64Array, F64Array]:
        """(x_m, y_m) of the returns on the `side` rail ('left' or 'right')."""
        mine = self.left == (side == "left")
        return self.x_m[mine], self.y_m[mine]


@dataclass(frozen=True)
class RailLine:
    """One side's rail: y = sum(c_k x^k) for coefficients c0, c1[, c2], held from x_near_m to
    x_far_m; rms_m: the fit's RMS residual; returns: how many returns it was fitted to."""

    side: str
    coefficients: tuple[float, ...]
    x_near_m: float
    x_far_m: float
    rms_m: float
    returns: int

    def y_m(self, x_m: float) -> float:
        return float(sum(c * x_m**k for k, c in enumerate(self.coefficients)))

    def sampled_m(self, step_m: float) -> tuple[tuple[float, float], ...]:
        """Points (x_m, y_m) of the line every step_m from x_near_m to x_far_m (both ends
        included), for drawing. ValueError when step_m is not a positive distance."""
        if not step_m > 0 or not math.isfinite(step_m):
            raise ValueError(f"step_m: expected a positive distance, got {step_m}")
        n = max(1, math.ceil((self.x_far_m - self.x_near_m) / step_m))
        xs = np.linspace(self.x_near_m, self.x_far_m, n + 1)
        return tuple((float(x), self.y_m(float(x))) for x in xs)

    def holds(self, x_m: float, y_m: float, gate_m: float) -> bool:
        """(x_m, y_m) lies along the line's stretch, within gate_m of it across."""
        return self.x_near_m <= x_m <= self.x_far_m and abs(y_m - self.y_m(x_m)) <= gate_m


def remember(
    remembered: RailReturns,
    result: GuardRailResult,
    radar: Sequence[RadarTarget],
    ego: EgoMotion | None,
    dt_s: float,
    memory_s: float,
) -> RailReturns:
    """Step 1: the remembered returns carried into this frame, with this frame's found ones."""
    found = [c for c in result.checks if c.verdict == "guard_rail"]
    new = RailReturns(
        np.array([radar[c.target_index].x_m for c in found], dtype=np.float64),
        np.array([radar[c.target_index].y_m for c in found], dtype=np.float64),
        np.array([c.side == "left" for c in found], dtype=bool),
        np.zeros(len(found), dtype=np.float64),
    )
    if ego is None:
        return new
    gathered_s = remembered.gathered_s + dt_s
    if not len(remembered):
        return dataclasses.replace(new, gathered_s=gathered_s)
    age_s = remembered.age_s + dt_s
    kept = age_s <= memory_s
    x_m, y_m = ego.carry(remembered.x_m[kept], remembered.y_m[kept])
    return RailReturns(
        np.concatenate([x_m, new.x_m]),
        np.concatenate([y_m, new.y_m]),
        np.concatenate([remembered.left[kept], new.left]),
        np.concatenate([age_s[kept], new.age_s]),
        gathered_s,
    )


@_jit
def _least_squares(x: F64Array, y: F64Array, keep: npt.NDArray[np.bool_], terms: int) -> F64Array:
    """(3,) c0, c1, c2 (those past `terms` 0) of y = sum(c_k x^k) over the kept points, by
    the normal equations (a 2x2 or 3x3 system, x within a radar's range) and Gaussian
    elimination with partial pivoting (numba's np.linalg needs SciPy, which this project
    does not install); NaN when the system is singular."""
    system = np.zeros((terms, terms + 1))
    for i in range(len(x)):
        if keep[i]:
            for r in range(terms):
                for c in range(terms):
                    system[r, c] += x[i] ** (r + c)
                system[r, terms] += x[i] ** r * y[i]
    for c in range(terms):
        pivot = c
        for r in range(c + 1, terms):
            if abs(system[r, c]) > abs(system[pivot, c]):
                pivot = r
        if system[pivot, c] == 0.0:
            return np.full(3, np.nan)
        for k in range(terms + 1):
            system[c, k], system[pivot, k] = system[pivot, k], system[c, k]
        for r in range(c + 1, terms):
            factor = system[r, c] / system[c, c]
            for k in range(c, terms + 1):
                system[r, k] -= factor * system[c, k]
    coefficients = np.zeros(3)
    for r in range(terms - 1, -1, -1):
        total = system[r, terms]
        for k in range(r + 1, terms):
            total -= system[r, k] * coefficients[k]
        coefficients[r] = total / system[r, r]
    return coefficients


@_jit
def _robust_fit(
    x: F64Array, y: F64Array, max_outliers: int, max_rms_m: float
) -> tuple[F64Array, int, float, int, float, float]:
    """Step 2's fit of y on x: (coefficients (3,), how many of them are used (0: no line),
    RMS residual, returns kept, nearest and farthest kept x). While the RMS residual exceeds
    max_rms_m (LINE_MAX_RMS_M for step 2), the return farthest from the fit is left out and
    the rest fitted again, at most max_outliers times."""
    keep = np.ones(len(x), dtype=np.bool_)
    for _ in range(max_outliers + 1):
        n = int(np.count_nonzero(keep))
        x_near, x_far = np.min(x[keep]) if n else np.inf, np.max(x[keep]) if n else -np.inf
        if n < LINE_MIN_POINTS or x_far - x_near < LINE_MIN_SPAN_M:
            break
        terms = 3 if n >= QUADRATIC_MIN_POINTS else 2
        c = _least_squares(x, y, keep, terms)
        residual = np.where(keep, np.abs(y - (c[0] + x * (c[1] + x * c[2]))), -1.0)
        rms = math.sqrt(np.sum(np.where(keep, residual * residual, 0.0)) / n)
        if rms <= max_rms_m:
            return c, terms, rms, n, x_near, x_far
        if not rms >= 0:  # singular: NaN
            break
        keep[np.argmax(residual)] = False
    return np.zeros(3), 0, np.nan, 0, np.nan, np.nan


def fit_line(returns: RailReturns, side: str) -> RailLine | None:
    """Step 2 on one side (None: no line there)."""
    x, y = returns.of_side(side)
    coefficients, terms, rms, n, x_near, x_far = _robust_fit(
        x, y, math.floor(LINE_MAX_OUTLIER_FRACTION * len(x)), LINE_MAX_RMS_M
    )
    if terms == 0:
        return None
    return RailLine(
        side,
        tuple(float(c) for c in coefficients[:terms]),
        x_near - LINE_EXTEND_M,
        x_far + LINE_EXTEND_M,
        rms,
        n,
    )


def along_rail_lines(
    result: GuardRailResult,
    radar: Sequence[RadarTarget],
    remembered: RailReturns,
    ego: EgoMotion | None,
    dt_s: float,
    params: GuardRailParams,
) -> tuple[GuardRailResult, tuple[RailLine, ...], RailReturns]:
    """Steps 1-4: the filter's result with the targets along a rail line labelled ('line')
    and those off the rail lines no longer labelled ('off_line'), the lines, and the
    returns to remember for the next frame. With `line_memory_s` 0 the result is `result`,
    and there are no lines and nothing to remember."""
    if params.line_memory_s <= 0:
        return result, (), RailReturns.none()
    returns = remember(remembered, result, radar, ego, dt_s, params.line_memory_s)
    lines = tuple(line for side in SIDES if (line := fit_line(returns, side)) is not None)
    by_side = {line.side: line for line in lines}
    judged = params.rail_returns_required and returns.gathered_s >= params.line_memory_s
    # a side with step 2's line traces a rail: that fit is the loose one's, held tighter
    traced = {
        side: not judged or side in by_side or _traces_a_rail(returns, side) for side in SIDES
    }
    checks = []
    for c in result.checks:
        t = radar[c.target_index]
        line = by_side.get(c.side)
        verdict = _against_lines(c.verdict, line, traced[c.side], t.x_m, t.y_m, params)
        checks.append(c if verdict == c.verdict else dataclasses.replace(c, verdict=verdict))
    return GuardRailResult(tuple(checks)), lines, returns


def _traces_a_rail(returns: RailReturns, side: str) -> bool:
    """Step 4: the side's returns lie along a line, loosely (LOOSE_LINE_RMS_M with up to
    LOOSE_LINE_OUTLIER_FRACTION of them left out)."""
    x, y = returns.of_side(side)
    outliers = math.floor(LOOSE_LINE_OUTLIER_FRACTION * len(x))
    return _robust_fit(x, y, outliers, LOOSE_LINE_RMS_M)[1] > 0


def _against_lines(
    verdict: str,
    line: RailLine | None,
    traced: bool,
    x_m: float,
    y_m: float,
    params: GuardRailParams,
) -> str:
    """Steps 3-4 for a target at (x_m, y_m): its verdict given its side's line (None: the
    side has none) and whether its side's returns are enough for one (`traced`; True
    where they are not judged)."""
    if verdict == "not_guard_rail":
        along = line is not None and line.holds(x_m, y_m, params.line_gate_m)
        return "line" if along else verdict
    if verdict not in ("guard_rail", "overlap"):
        return verdict
    if not traced:
        return "off_line"
    if (
        line is not None
        and params.line_veto_m > 0
        and line.holds(x_m, y_m, math.inf)
        and not line.holds(x_m, y_m, params.line_veto_m)
    ):
        return "off_line"
    return verdict
