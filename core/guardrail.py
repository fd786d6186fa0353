"""Guard-rail filter for slow radar targets: an uninterrupted oblique line across the target's
search area (paper 002, sections II and III).

Only slow targets are checked: real speed |range rate + ego speed cos(azimuth)| below
`max_speed_mps` (paper 002, II; 1.5 m/s here, Notes), and, beyond the paper, not those
where the tracker expects a vehicle (`skip_tracked_vehicles`: the area is `tracked`, within
`vehicle.track_gate_m` of a confirmed vehicle track's predicted position, Notes) nor those
too far for vision (`SearchArea.too_far`: fewer than `vehicle.min_image_px_per_m` image
pixels per metre across their area, left out of the vehicle search too; Notes). A target
left of the car (y_m > 0) is checked for a left guard rail, the others for a right one.
Steps, each visible in `GuardRailCheck`:

1. edges: 3x3 Sobel derivatives of the area's patch; an edge pixel has a gradient module
   above `sobel_threshold` and the orientation of a guard rail on that side (fig. 1): its
   line rises towards the vanishing point (to the right for a left rail, to the left for a
   right one) at `min_angle_rad` .. `max_angle_rad` from the image horizontal;
2. morphology (fig. 2): erosion by a 1x3 horizontal line, which keeps horizontal runs and
   erases isolated points and vertical segments, then dilation by a cross 3 rows high and 5
   columns wide, which reinforces both directions, the horizontal more;
3. start (fig. 3, 4): the first white pixel of the 3x5 neighbourhood of fig. 3, in its
   priority order, anchored at the near end of the area (column 0 for a left rail) at
   mid-height and moved 3 rows down at a time to the bottom (area A of fig. 4);
4. line following (fig. 5, 6): from the start, the next pixel is the first white unvisited
   one of right, up-right, down-right, up, down (left rail); when none is white the line
   continues one column right on the same row and counts a hole; it ends when more than
   `max_holes` holes are met or at the far border of the area;
5. verdict: the line's horizontal extent (from the start column to the last column reached
   on an edge pixel) over the patch width is its coverage; more than
   `min_length_fraction` is a guard rail, when (beyond the paper) the line also passes the
   target at least `min_line_height_m` above the road: its height there is the rows from
   the radar point's base row up to the line's point nearest the target's column, over the
   area's pixels per metre (Notes);
6. overlapping boxes management (III): the slow targets' areas are processed nearest first
   (by x_m); after a guard rail is found, each following area that the rail's area covers
   by more than `overlap_fraction` (`core.search_area.overlap_fraction`) is labelled guard
   rail without a search, until the first that is not covered enough, where the search
   resumes. Beyond the paper, optionally (`overlap_gate_m` > 0; off by default, Notes), a
   covered area whose target lies more than `overlap_gate_m` across from the rail's target
   is not labelled: it is searched in its turn.
   `manage_overlaps` False searches every slow area.

Beyond the paper, `core.rail_lines` then labels the searched targets that lie along the
line of the rail returns found over the last seconds (verdict 'line'), and takes the label
back from those labelled here on a side without such a line or well across from it
(verdict 'off_line').

A right rail is the mirror image of a left one: steps 1-5 give the left-rail results of the
patch flipped left-right, flipped back (step 1 keeps the mirrored orientation, steps 3-5
read the edges from the right). `rail_edges`
(steps 1-2), `find_start` (3), `follow_line` (4-5) and `search_line` (3-5) can be called on
their own; the last three work on the left-rail orientation.

Coordinates: patch pixels (row, col), as `SearchArea.patch`; `SearchArea.to_image_px` maps
them into the image.

Notes:
    - Real speed: the azimuth is taken as the bearing of the line of sight in the vehicle
      frame (radar mounted facing forward, yaw rate neglected), as in the paper. With the
      ego speed unknown (NaN) no target is known to be slow and nothing is checked.
    - Step 1: "module" is the Euclidean norm of the two Sobel derivatives (4 per grey level
      of a step edge), computed with a replicated border (OpenCV's default reflection
      zeroes d/dcol on the first and last column, where the start is searched). Its
      threshold defaults to 40, a 10-grey step, rather than the lowest that works (the
      comment of `GuardRailParams.sobel_threshold` gives the measurement). The paper
      shows the kept orientations only as a drawing (fig. 1); here a window of line angles
      (2 .. 45 deg by default). Rail edges in the bundled drives' areas lie at about 3 to
      15 deg. Horizontal edges are left out, as the paper's misses of quasi-horizontal rails
      (fig. 11) suggest: they are mostly vehicles' bumpers, roofs and shadows, and with the
      window from 0 deg 37 of 107 vehicle targets of the bundled highway drive (speed gate
      off) were labelled guard rail, from 2 deg 3.
    - Step 2: our copy of fig. 2 runs its two tables together (rows of 8 numbers); read as
      3 + 5 columns they are a 3x3 element whose middle row alone is set, i.e. the 1x3
      horizontal line used here for erosion, and a 3x5 cross (middle row of 5, middle
      column of 3) used for dilation. OpenCV's border handling leaves the patch border
      uneroded.
    - Step 3: fig. 3 read as offsets from the anchor '.', which has no priority and is
      not itself tested: 1 (0, +1), 2 (-1, +1), 3 (+1, +1), 4 (-1, 0), 5 (+1, 0),
      6-8 (-1, +2..+4), 9-11 (0, +2..+4), 12-14 (+1, +2..+4) as (row, col). The anchor
      starts on row h // 2, so the row above mid-height is searched too, and moves 3 rows
      at a time (the neighbourhood's height: every row is searched once) while it is inside
      the patch; cells outside the patch are black. Area A is thus the first 5 columns from
      row h // 2 - 1 down.
    - Step 4: a hole is the position stepped over (one column right of the last position,
      same row); the hole that exceeds `max_holes` ends the search and is recorded too, so
      `holes_px` holds up to max_holes + 1 positions. Pixels are never revisited (the line
      only moves right or vertically, so only up and down moves could revisit).
    - Step 5: "longer than 50% of the searching area" is read as the horizontal extent, in
      columns, over the patch width (a guard rail crosses the area from side to side).
    - Step 5, the line's height, beyond the paper: on nuScenes scene-0523, 96 searched
      targets on parked cars and trailers were labelled guard rail (128 with those labelled
      by overlap), and the lines that did it lay at the road: the kerb, the lane's edge, a
      shadow, a car's sill, 0.05 m above the road at the target (median; 74 % below 0.2 m).
      The synthetic rails' lines pass their targets 0.32-0.36 m up (median; 5-18 % below
      0.2 m). A line at least `min_line_height_m` = 0.1 m up, on drives of seeds 101 and
      202 and nuScenes: vehicles labelled guard rail nuScenes 125 -> 57, exurban 13 -> 3,
      stop_and_go 15 -> 8 and 4 -> 1; rail FP exurban 76 -> 57 and 76 -> 47, stop_and_go
      44 -> 30 and 57 -> 33; rail FN up by 4-15 (exurban 179 -> 185, 147 -> 162; highway
      471 -> 475). The targets no longer labelled are searched for vehicles, and vehicle
      FP per frame rose by 0.02-0.04 on the synthetic drives and 1.43 -> 1.62 on
      nuScenes. 0.2 m removed more vehicles (nuScenes 36) and more rails (highway FN 493).
      Held out, seeds 303 and 505: vehicles labelled exurban 18 -> 12 and 28 -> 21,
      stop_and_go 18 -> 15 and 13 -> 9; rail FP exurban 96 -> 68 and 93 -> 67; rail FN
      highway 538 -> 561 and 446 -> 467. On the aiMotive night motorway (no rail truth)
      28 % of the labelling lines passed below 0.1 m (median 0.33 m, as the synthetic
      rails'): targets labelled 642 -> 480, vehicle FP per frame 0.72 -> 0.92; 0.0 m did
      little better there (0.86) and kept more vehicles labelled on nuScenes (74). Since
      the rail lines leave out wrong returns (`core.rail_lines` Notes), a return the
      height test loses on a rail is mostly labelled along its line, and the test stands
      at 0.15 m: on drives of new seeds, highway / exurban, seeds 1818-2525 / 1313-1717 +
      2727, rail returns labelled 0.82 / 0.83 -> 0.81 / 0.80 and 0.80 / 0.94 -> 0.79 /
      0.92, rail FP per frame on exurban 0.307 -> 0.278 and 0.326 -> 0.310 (stop_and_go
      0.129 -> 0.113 and 0.076 -> 0.062), vehicles labelled guard rail on exurban 56 -> 51
      and 54 -> 53, radar-seen MOTA within +0.007, vehicle FP per frame within +0.002;
      nuScenes' vehicles labelled guard rail 22 -> 13 (trailers and parked trucks, lines
      0.10-0.14 m up); aiMotive one vehicle FP more in 50 frames. 0.2 m lost more rail
      returns (exurban 0.78) for one vehicle fewer on nuScenes. The papers' preset: -100 m
      (no height test).
    - Slow targets: paper 002 checks every target slower than 5 m/s over ground. A guard
      rail stands still: the synthetic rails' returns measure at most 0.12 m/s (99th
      percentile), aiMotive's stationary returns within 0.25 m/s, nuScenes' (ego speed from
      its poses, 2 Hz) mostly within 1 m/s; in stop-and-go traffic the cars crawling at
      2-5 m/s were labelled guard rail (8 on stop_and_go seeds 1313 + 1414). With 1.5 m/s
      (the papers' preset: 5) and tracked vehicles left out, on drives of new seeds (20 s
      each), vehicles labelled guard rail, exurban / stop_and_go: 27 / 8 -> 21 / 0 (seeds
      1313 + 1414), 20 / 4 -> 17 / 1 (held out, 1717 + 1818); rail FP per frame 0.350 /
      0.080 -> 0.335 / 0.055 and 0.275 / 0.115 -> 0.268 / 0.100; rail returns labelled
      and highway the same; exurban RD / (RD + FN) 0.725 -> 0.730, 0.717 -> 0.722.
      nuScenes and aiMotive the same (their vehicles labelled guard rail stand parked and
      were never tracked).
    - Too far: the line search on an area of a dozen pixels found a line across most of
      them; on nuScenes scene-0523 it labelled parked trucks and trailers 47-87 m away guard
      rail. Leaving out the areas the vehicle search leaves out (10 px/m): vehicles
      labelled guard rail on nuScenes 58 -> 22; the synthetic drives' areas are all finer
      and do not change; aiMotive the same (no vehicle is searched there either).
    - Step 6: each following area is compared with the area where the rail was found, as
      the paper says. Comparing it with the last one labelled instead, so that a chain
      could follow a rail beyond the first area, labelled 196 rather than 195 slow targets
      of the bundled highway drive but also 6 rather than 4 parked cars in line with the
      rail in `exurban`. Areas at equal distance keep their radar order.
    - Step 6, the lateral gate (beyond the paper, measured and not adopted: the default is
      0, no gate, as the papers'): a near rail's area is large in the image
      and covers the areas of farther targets beside the rail too: parked cars, signs,
      trees. Of the targets labelled by overlap on drives of seeds 1313, 1414 and 1717
      (exurban and highway), those on a rail lay 0.28 m across from the rail's target
      (median; 90 % within 1.05 m), those on vehicles 0.67 m (90 %: 2.58 m), the others
      1.91 m. With `overlap_gate_m` 1 m (the papers' preset: 0, no gate), exurban,
      seeds 1313-1717 / held out 1818-2525: vehicles labelled guard rail 31 -> 19 / 30 ->
      22, rail FP per frame 0.318 -> 0.282 / 0.263 -> 0.244, rail returns labelled 0.87 ->
      0.81 / 0.73 -> 0.70 (returns 1-2 m off the rail's target that their own search does
      not find), vehicle FP per frame +0.014 / +0.003; highway within 0.01; nuScenes
      vehicles labelled guard rail 22 -> 19 (most are labelled by their own line search:
      the low edges of parked trailers). On the bundled exurban drive the count rose, 6 ->
      12, through the tracker: a parked car's returns labelled on early frames left it
      untracked, so its returns were checked (and labelled) on later frames where the
      tracker had kept them out. A gate growing with the distance between the two targets
      (0.7 m + 0.05-0.1 m per metre) let the parked cars back in. On a further unseen
      seed (2727) exurban went the other way too: vehicles labelled guard rail 9 -> 11, rail
      returns labelled 0.80 -> 0.77, radar-seen MOTA 0.612 -> 0.599. Rail returns labelled
      fell on every drive and vehicles labelled rose on two of four sets: no robust gain.
    - numba: steps 1-5 written as OpenCV calls (Sobel, erode, dilate), numpy masks and a
      Python loop over padded bytes took 55 us per area (mostly 32x64, one thread); these
      loops take 6 us (`fusionscope bench --stage guardrail`). Step 1 stays in float32, as
      OpenCV's CV_32F derivatives, so the module and angle tests round the same. The first
      call compiles (about 7 s) and caches the machine code next to this file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
import numpy.typing as npt

from core.checks import require_grey_image
from core.io.frame import RadarTarget, real_speed_mps
from core.params import GuardRailParams
from core.search_area import SearchArea, overlap_fraction

SIDES = ("left", "right")
VERDICTS = ("guard_rail", "not_guard_rail", "overlap", "line", "off_line")
# the verdicts that label a target guard rail
RAIL_VERDICTS = ("guard_rail", "overlap", "line")

# Fig. 2, as read in the module Notes: (a) erosion, (b) dilation.
EROSION_KERNEL = np.ones((1, 3), dtype=np.uint8)
DILATION_KERNEL = np.array(
    [[0, 0, 1, 0, 0], [1, 1, 1, 1, 1], [0, 0, 1, 0, 0]],
    dtype=np.uint8,
)
# Fig. 3: (row, col) offsets from the anchor, priority 1 first (left rail).
START_OFFSETS = (
    (0, 1),
    (-1, 1),
    (1, 1),
    (-1, 0),
    (1, 0),
    (-1, 2),
    (-1, 3),
    (-1, 4),
    (0, 2),
    (0, 3),
    (0, 4),
    (1, 2),
    (1, 3),
    (1, 4),
)
# Paper 002: the neighbourhood moves "by three pixels down at a time" (its own height).
START_STEP_PX = 3
# Fig. 5: right, up-right, down-right, up, down (left rail), in the order `_follow` tests them.
FOLLOW_OFFSETS = ((0, 1), (-1, 1), (1, 1), (-1, 0), (1, 0))
WHITE = 255

EdgeImage = npt.NDArray[np.uint8]
PixelArray = npt.NDArray[np.int32]
F32Array = npt.NDArray[np.float32]

_jit = numba.njit(cache=True, nogil=True)


@dataclass(frozen=True, eq=False)
class LineTrace:
    """Steps 3-5 on a left-rail edge image of width w.

    line_px: (N, 2) int32 (row, col) of the followed edge pixels, the start first ((0, 2)
    when no start was found); holes_px: (M, 2) int32 positions stepped over as holes, in
    order; coverage: (last column of line_px - start column + 1) / w, 0..1; guard_rail:
    coverage > min_length_fraction.
    """

    line_px: PixelArray
    holes_px: PixelArray
    coverage: float
    guard_rail: bool

    @property
    def start_px(self) -> tuple[int, int] | None:
        """(row, col) of the start pixel, None when there is none."""
        return _first(self.line_px)


def _first(pixels: PixelArray) -> tuple[int, int] | None:
    return None if len(pixels) == 0 else (int(pixels[0, 0]), int(pixels[0, 1]))


@dataclass(frozen=True, eq=False)
class GuardRailCheck:
    """What the filter did with one slow target's area (patch coordinates).

    target_index: the target's index in the frame's radar tuple; side: 'left' or 'right'
    rail looked for; real_speed_mps: its speed over ground; edges: (h, w) uint8 0/255
    after morphology (steps 1-2; zeros((0, 0)) when not searched); start_px (property):
    (row, col) of the first white pixel (None when none was found or not searched);
    line_px: (N, 2) int32 (row, col) followed points; holes_px: (M, 2) int32 positions
    stepped over as holes; coverage: 0..1 (0 when not searched); line_height_m: how far
    above the road the line passes the target (step 5; NaN when not searched or no line);
    verdict: one of VERDICTS,
    'overlap' when labelled guard rail by overlap without a search, 'line' and 'off_line'
    (`core.rail_lines`) when labelled along a rail line after the search and when the label
    was taken back for lying off the rail lines; overlapped_by: target_index of the area whose
    guard rail labelled this one by overlap (None when searched).
    """

    target_index: int
    side: str
    real_speed_mps: float
    edges: EdgeImage
    line_px: PixelArray
    holes_px: PixelArray
    coverage: float
    verdict: str
    overlapped_by: int | None
    line_height_m: float = math.nan

    @property
    def start_px(self) -> tuple[int, int] | None:
        """(row, col) of the first white pixel, None when there is none."""
        return _first(self.line_px)

    @property
    def guard_rail(self) -> bool:
        """Labelled guard rail, by a search, by overlap or along a rail line
        (`core.rail_lines`)."""
        return self.verdict in RAIL_VERDICTS


@dataclass(frozen=True, eq=False)
class GuardRailResult:
    """checks: one per slow target, in the order processed (nearest first)."""

    checks: tuple[GuardRailCheck, ...]

    @property
    def guard_rail_targets(self) -> frozenset[int]:
        """Target indices labelled guard rail (searched or by overlap)."""
        return frozenset(c.target_index for c in self.checks if c.guard_rail)

    @property
    def searched(self) -> int:
        """Number of areas the line search ran on."""
        return sum(c.overlapped_by is None for c in self.checks)


def is_slow(target: RadarTarget, ego_speed_mps: float, params: GuardRailParams) -> bool:
    """Checked by the filter: real speed below `max_speed_mps` (never with NaN ego speed)."""
    return abs(real_speed_mps(target, ego_speed_mps)) < params.max_speed_mps


# --- steps 1-2: edges -------------------------------------------------------------------------


@_jit
def _replicated(patch: npt.NDArray[np.uint8]) -> F32Array:
    """`patch` in float32 with a one-pixel border repeating its outer rows and columns, as
    OpenCV's BORDER_REPLICATE."""
    h, w = patch.shape
    out = np.empty((h + 2, w + 2), dtype=np.float32)
    for r in range(h + 2):
        src, dst = patch[min(max(r - 1, 0), h - 1)], out[r]
        dst[0] = src[0]
        for c in range(w):
            dst[c + 1] = src[c]
        dst[w + 1] = src[w - 1]
    return out


@_jit
def _oriented(
    patch: npt.NDArray[np.uint8],
    left: bool,
    tan_min: float,
    tan_max: float,
    threshold_sq: float,
) -> EdgeImage:
    """Step 1: (h, w) uint8, WHITE where the 3x3 Sobel gradient has a `left` (else right)
    rail's orientation, tan_min <= |d/dcol| / |d/drow| <= tan_max, and a squared module
    above threshold_sq. In float32, as OpenCV's CV_32F derivatives (whole numbers, exact):
    the three bounds are rounded to float32 and compared with float32 products."""
    h, w = patch.shape
    p = _replicated(patch)
    t_min, t_max, module_sq = np.float32(tan_min), np.float32(tan_max), np.float32(threshold_sq)
    # A line rising to the right at angle a from the horizontal has its gradient along
    # +-(sin a, cos a) in (col, row): same signs, |gx| / |gy| = tan a; rising to the left
    # (a right rail), opposite signs.
    sign, two = np.float32(1 if left else -1), np.float32(2)
    out = np.empty((h, w), dtype=np.uint8)
    for r in range(h):
        up, mid, down, dst = p[r], p[r + 1], p[r + 2], out[r]
        for c in range(w):  # column c + 1 of p's rows
            gx = up[c + 2] - up[c] + two * (mid[c + 2] - mid[c]) + down[c + 2] - down[c]
            gy = down[c] - up[c] + two * (down[c + 1] - up[c + 1]) + down[c + 2] - up[c + 2]
            ax, ay = abs(gx), abs(gy)
            keep = (
                (sign * gx * gy >= 0)
                & (ax >= t_min * ay)
                & (ax <= t_max * ay)
                & (gx * gx + gy * gy > module_sq)
            )
            dst[c] = WHITE if keep else 0
    return out


@_jit
def _morphology(image: EdgeImage, kernel: EdgeImage, dilate: bool) -> EdgeImage:
    """OpenCV's erosion (min) or dilation (`dilate`: max) of `image` by `kernel` (odd sides,
    anchored at its centre) with its default border: cells outside the image are left out,
    so the image border is not eroded."""
    h, w = image.shape
    kh, kw = kernel.shape
    reach_rows, reach_cols = kh // 2, kw // 2
    # Flat rows of `width` cells, pixel (r, c) at first + r * width + c; the 2 reach_cols
    # cells ending each row and the `first` cells before and after the rows are neutral, so
    # each kernel cell is one shifted read for every pixel, in the buffer.
    width = w + 2 * reach_cols
    first = reach_rows * width + 2 * reach_cols
    n = h * width
    padded = np.full(n + 2 * first, 0 if dilate else WHITE, dtype=np.uint8)
    for r in range(h):
        src, dst = image[r], padded[first + r * width :]
        for c in range(w):
            dst[c] = src[c]
    out = padded[first : first + n].copy()
    for i in range(kh):
        for j in range(kw):
            if not kernel[i, j]:
                continue
            src = padded[first + (i - reach_rows) * width + j - reach_cols :]
            if dilate:
                for k in range(n):
                    out[k] = max(out[k], src[k])
            else:
                for k in range(n):
                    out[k] = min(out[k], src[k])
    return out.reshape((h, width))[:, :w].copy()


@_jit
def _rail_edges(
    patch: npt.NDArray[np.uint8],
    left: bool,
    tan_min: float,
    tan_max: float,
    threshold_sq: float,
) -> EdgeImage:
    """Steps 1-2 (see `_oriented`)."""
    binary = _oriented(patch, left, tan_min, tan_max, threshold_sq)
    return _morphology(_morphology(binary, EROSION_KERNEL, False), DILATION_KERNEL, True)


def _edge_tests(params: GuardRailParams) -> tuple[float, float, float]:
    """`_oriented`'s tan_min, tan_max and threshold_sq."""
    return math.tan(params.min_angle_rad), math.tan(params.max_angle_rad), params.sobel_threshold**2


def rail_edges(patch: npt.NDArray[np.uint8], side: str, params: GuardRailParams) -> EdgeImage:
    """Steps 1-2: (h, w) uint8 0/255 edges of a `side` ('left' or 'right') guard rail in the
    (h, w) uint8 grey patch, after erosion and dilation (patch coordinates)."""
    require_grey_image("patch", patch)
    if side not in SIDES:
        raise ValueError(f"side: expected one of {SIDES}, got {side!r}")
    return _rail_edges(patch, side == "left", *_edge_tests(params))


# --- steps 3-5: start, line following, verdict ------------------------------------------------


@_jit
def _white(edges: EdgeImage, row: int, col: int) -> bool:
    """Pixel (row, col) is white; outside the image is black."""
    h, w = edges.shape
    return 0 <= row < h and 0 <= col < w and edges[row, col] > 0


@_jit
def _find_start(edges: EdgeImage) -> tuple[int, int]:
    """Step 3 on left-rail edges: (row, col) of the start, (-1, -1) when none."""
    h = edges.shape[0]
    for row in range(h // 2, h, START_STEP_PX):
        for dr, dc in START_OFFSETS:
            if _white(edges, row + dr, dc):
                return row + dr, dc
    return -1, -1


@_jit
def _follow(
    edges: EdgeImage, row: int, col: int, max_holes: int
) -> tuple[PixelArray, PixelArray, float]:
    """Steps 4-5 on left-rail edges from their white pixel (row, col): (line_px, holes_px,
    coverage)."""
    h, w = edges.shape
    unvisited = edges.copy()
    unvisited[row, col] = 0
    line = np.empty((h * w, 2), dtype=np.int32)  # pixels are never revisited
    holes = np.empty((w, 2), dtype=np.int32)  # each hole is one column on
    line[0, 0], line[0, 1] = row, col
    n_line, n_holes = 1, 0
    while col < w - 1:
        moved = False
        for dr, dc in FOLLOW_OFFSETS:  # fig. 5, in order
            if _white(unvisited, row + dr, col + dc):
                row, col, moved = row + dr, col + dc, True
                break
        if not moved:  # a hole: on along the row
            col += 1
            holes[n_holes, 0], holes[n_holes, 1] = row, col
            n_holes += 1
            if n_holes > max_holes:
                break
            continue
        unvisited[row, col] = 0
        line[n_line, 0], line[n_line, 1] = row, col
        n_line += 1
    coverage = (line[n_line - 1, 1] - line[0, 1] + 1) / w
    return line[:n_line].copy(), holes[:n_holes].copy(), coverage


@_jit
def _search_line(
    edges: EdgeImage, left: bool, max_holes: int
) -> tuple[PixelArray, PixelArray, float]:
    """Steps 3-5 for a `left` (else right) rail: `_follow` from `_find_start`'s pixel (an
    empty line of coverage 0 without one). A right rail's edges are searched mirrored and
    its pixels mapped back to the edges' columns."""
    w = edges.shape[1]
    view = edges if left else edges[:, ::-1]
    row, col = _find_start(view)
    if row < 0:
        return np.zeros((0, 2), dtype=np.int32), np.zeros((0, 2), dtype=np.int32), 0.0
    line_px, holes_px, coverage = _follow(view, row, col, max_holes)
    if not left:
        line_px[:, 1] = w - 1 - line_px[:, 1]
        holes_px[:, 1] = w - 1 - holes_px[:, 1]
    return line_px, holes_px, coverage


def _trace(found: tuple[PixelArray, PixelArray, float], params: GuardRailParams) -> LineTrace:
    """The LineTrace of `_follow`'s or `_search_line`'s result."""
    line_px, holes_px, coverage = found
    return LineTrace(line_px, holes_px, coverage, coverage > params.min_length_fraction)


def find_start(edges: EdgeImage) -> tuple[int, int] | None:
    """Step 3 on a left-rail edge image (h, w) uint8 (white: > 0): (row, col) of the first
    white pixel of fig. 3's neighbourhood anchored at column 0, from row h // 2 down in
    steps of 3 rows; None when area A holds none."""
    require_grey_image("edges", edges)
    row, col = _find_start(edges)
    return None if row < 0 else (row, col)


def follow_line(edges: EdgeImage, start: tuple[int, int], params: GuardRailParams) -> LineTrace:
    """Steps 4-5 on a left-rail edge image (h, w) uint8 (white: > 0) from its white pixel
    `start` (row, col), with `params.max_holes` and `params.min_length_fraction`."""
    require_grey_image("edges", edges)
    h, w = edges.shape
    r, c = start
    if not (0 <= r < h and 0 <= c < w) or not edges[r, c]:
        raise ValueError(f"start: expected a white pixel (row, col) of the edges, got {start}")
    return _trace(_follow(edges, r, c, params.max_holes), params)


def search_line(edges: EdgeImage, params: GuardRailParams) -> LineTrace:
    """Steps 3-5 on a left-rail edge image (h, w) uint8 (white: > 0): `follow_line` from
    `find_start`'s pixel; an empty trace, not a guard rail, when there is none."""
    require_grey_image("edges", edges)
    return _trace(_search_line(edges, True, params.max_holes), params)


# --- the stage --------------------------------------------------------------------------------

_NOT_SEARCHED = np.zeros((0, 0), dtype=np.uint8)
_NOT_SEARCHED.flags.writeable = False
_NO_PIXELS = np.zeros((0, 2), dtype=np.int32)
_NO_PIXELS.flags.writeable = False


def _side(target: RadarTarget) -> str:
    return "left" if target.y_m > 0 else "right"


@_jit
def _search_area(
    patch: npt.NDArray[np.uint8],
    left: bool,
    tan_min: float,
    tan_max: float,
    threshold_sq: float,
    max_holes: int,
) -> tuple[EdgeImage, PixelArray, PixelArray, float]:
    """Steps 1-5 on a patch: (edges, line_px, holes_px, coverage)."""
    edges = _rail_edges(patch, left, tan_min, tan_max, threshold_sq)
    line_px, holes_px, coverage = _search_line(edges, left, max_holes)
    return edges, line_px, holes_px, coverage


def line_height_m(area: SearchArea, line_px: PixelArray) -> float:
    """Step 5: how far above the road a followed line passes the area's target: from the
    radar point's base row up to the line's point nearest the target's column, in metres
    (NaN without a line)."""
    if len(line_px) == 0:
        return math.nan
    col, row = area.to_patch_px(*area.base_px)
    base_col, base_row = col - 0.5, row - 0.5  # pixel-centre coordinates, as line_px
    nearest = int(np.argmin(np.abs(line_px[:, 1] - base_col)))
    return float(base_row - line_px[nearest, 0]) / area.px_per_m


def _search(area: SearchArea, speed_mps: float, params: GuardRailParams) -> GuardRailCheck:
    """Steps 1-5 on one area."""
    side = _side(area.target)
    edges, line_px, holes_px, coverage = _search_area(
        area.patch, side == "left", *_edge_tests(params), params.max_holes
    )
    height_m = line_height_m(area, line_px)
    rail = coverage > params.min_length_fraction and height_m >= params.min_line_height_m
    return GuardRailCheck(
        target_index=area.target_index,
        side=side,
        real_speed_mps=speed_mps,
        edges=edges,
        line_px=line_px,
        holes_px=holes_px,
        coverage=coverage,
        verdict="guard_rail" if rail else "not_guard_rail",
        overlapped_by=None,
        line_height_m=height_m,
    )


def _check_areas(areas: tuple[SearchArea, ...]) -> None:
    for k, area in enumerate(areas):
        if not isinstance(area, SearchArea):
            raise ValueError(f"areas[{k}]: expected a SearchArea, got {type(area).__name__}")
        require_grey_image(f"areas[{k}].patch", area.patch)


def _along(rail: SearchArea, following: SearchArea, gate_m: float) -> bool:
    """Step 6: the following area's target lies within gate_m across of the rail's target
    (always, with gate_m 0: no gate)."""
    return gate_m == 0 or abs(following.target.y_m - rail.target.y_m) <= gate_m


def detect_guard_rails(
    areas: tuple[SearchArea, ...], ego_speed_mps: float, params: GuardRailParams
) -> GuardRailResult:
    """Paper 002: which slow radar targets are guard rails.

    areas: the search areas of one frame (`core.search_area.search_areas`), any order;
    ego_speed_mps: the car's speed (NaN when unknown: no target is known to be slow, and
    the result is empty). Returns one check per slow target, nearest first; areas too far
    for vision (`SearchArea.too_far`, beyond the paper) are not checked.
    """
    _check_areas(areas)
    if not (math.isfinite(ego_speed_mps) or math.isnan(ego_speed_mps)):
        raise ValueError(
            f"ego_speed_mps: expected a finite speed or NaN (unknown), got {ego_speed_mps}"
        )
    if math.isnan(ego_speed_mps):
        return GuardRailResult(())
    slow = [
        (area, real_speed_mps(area.target, ego_speed_mps))
        for area in areas
        if is_slow(area.target, ego_speed_mps, params)
        and not (params.skip_tracked_vehicles and area.tracked)
        and not area.too_far
    ]
    slow.sort(key=lambda item: item[0].x_m)  # stable: equal distances keep radar order

    checks: dict[int, GuardRailCheck] = {}  # by place in `slow`
    for k, (area, speed) in enumerate(slow):
        if k in checks:
            continue
        check = checks[k] = _search(area, speed, params)
        if check.verdict != "guard_rail" or not params.manage_overlaps:
            continue
        # 6. the following areas that the rail's area covers are guard rail too; those off
        # the rail's line (beyond the paper, overlap_gate_m) are searched in their turn
        j = k + 1
        while j < len(slow) and overlap_fraction(area, slow[j][0]) > params.overlap_fraction:
            following, following_speed = slow[j]
            if j not in checks and _along(area, following, params.overlap_gate_m):
                checks[j] = GuardRailCheck(
                    target_index=following.target_index,
                    side=_side(following.target),
                    real_speed_mps=following_speed,
                    edges=_NOT_SEARCHED,
                    line_px=_NO_PIXELS,
                    holes_px=_NO_PIXELS,
                    coverage=0.0,
                    verdict="overlap",
                    overlapped_by=area.target_index,
                )
            j += 1
    return GuardRailResult(tuple(checks[k] for k in sorted(checks)))
