"""Radar-guided vehicle detection by vertical symmetry (paper 001 section II, paper 000
section II-C).

For each radar target's search area (`core.search_area`: mapped on the object's base with
the frame's pitch, W wide, W/2 high, cropped at the image border, resampled to at most
`resampled_width_px` without enlarging):

4. binarised vertical edges with their sign: horizontal Sobel derivative (3x3) of the
   resampled area, +1 where it exceeds `edge_threshold` (darker to brighter, left to
   right), -1 where it is below -`edge_threshold`;
5. the symmetry matrix: for every axis (every column, and every border between two
   columns) and every half-width w from 1 to `max_half_width_px`, the window is w pixels
   either side of the axis over the whole area height; s counts the pairs of edges
   mirrored about the axis within the window (same row) whose signs are opposite, n all
   edges in the window, chi = s^2 / n (0 when n = 0). Rows of the matrix are half-widths
   1 .. max_half_width_px, columns axes at half-column steps;
6. an axis is a candidate when chi stays below the threshold for windows narrower than
   `narrow_width_m` (fig. 3: "low for narrow area widths") and reaches it at the vehicle's
   half-width, taken as the half-width between those of the narrowest and the widest
   vehicle (`min_width_m`, `max_width_m`) with the most mirrored pairs: where the
   vehicle's two borders pair up. Of each run of neighbouring candidate axes the one with
   the highest chi is kept;
7. the bottom: the lowest row where the vertical Sobel derivative says darker above and
   brighter below (the shadow under the vehicle ending on the road) across at least
   `bottom_edge_fraction` of the box's columns; a candidate without a bottom is dropped.
   The top: the highest row at least `min_height_ratio` of the width above the bottom with
   horizontal edges of either sign across `top_edge_fraction` of the columns; without one,
   the box is `default_height_ratio` of its width high (paper 001 fig. 7.b);
8. one vehicle per radar target: the candidate whose axis is nearest the radar point's
   column (fig. 4, the most central box);
9. boxes back in full-image pixels; the world-size filter drops boxes narrower than
   `min_width_m` or wider than `max_width_m`; boxes from several targets are merged: where
   two overlap by more than `merge_overlap_fraction` of the smaller one, the larger is kept,
   unless they are of similar size (width ratio >= `similar_size_ratio`) with their bases
   at the same height (within `same_base_fraction` of the box height), which are averaged;
10. world position: distance from the radar (the targets' x), lateral position and width
   from vision: the box's bottom corners' rays crossing the vertical plane at that distance.
   The bird's-eye distance of the box base (its ground point) is kept as `vision_distance_m`.

Coordinates: areas and their matrices in resampled-area pixels (`SearchArea.patch`); boxes
in full-image pixels with pixel centres at integers, (u0, v0, u1, v1) pixel edges; world in
the vehicle frame (x forward, y left, metres).

Notes:
    - chi = s^2 / n grows with the number of edge rows, so a fixed threshold would mean more
      for a short area (a far target, not enlarged) than for a tall one. The threshold is
      per row of the area: an axis qualifies when chi >= `symmetry_threshold` x area rows.
      A perfectly symmetric pair of 1-px borders over a fraction f of the rows gives
      chi / rows = f / 2.
    - Step 5: the paper takes every column as an axis. A border at a pixel edge gives
      Sobel edge pixels on both its sides, so a vehicle an odd number of pixels wide has
      two mirrored pairs per row about a column and one an even number of pixels wide only
      one, a third of the chi: axes also lie between columns, where the even ones get their
      two pairs (the bundled drives' refined share rose from 66 to 75 % on the highway).
    - Step 6, the width: the paper takes the first width at which chi exceeds the
      threshold. On the bundled drives that width was most often that of a part of the
      vehicle (rear lights, plate, a van's windows), which is symmetric about the same axis
      and raises chi before the borders do. Taking instead the half-width where the most
      mirrored pairs lie (the borders) raised the refined share of the radar-seen vehicles
      inside a search area from 45 to 66 % (highway), 52 to 54 % (exurban) and 32 to 35 %
      (stop and go). "Low for narrow widths" is checked below `narrow_width_m` (poles,
      posts, gaps), not up to the narrowest vehicle, for the same reason.
    - Step 7: with the paper's area (W/2 high, 30 % below the radar point) the area reaches
      0.35 W above a vehicle's base, lower than the roof of any car, so the top is found only
      for low objects and the fixed ratio is the rule, as the paper says for trucks. The
      world-size filter therefore checks the width only.
    - Step 10: the paper maps the box base to the world by inverse perspective mapping and
      takes the distance from the radar; here lateral position and width come from the
      rays at the radar's distance, so a bottom found a few rows off (pitch, shadow) moves
      neither.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.frame import RadarTarget
from core.params import VehicleParams
from core.search_area import SearchArea, intersection_area, rect_area

FloatArray = npt.NDArray[np.float64]
F32Array = npt.NDArray[np.float32]
I8Array = npt.NDArray[np.int8]

# Why a radar target has no vehicle of its own.
Verdict = Literal[
    "vehicle",  # its box is (part of) a final vehicle
    "outside_image",  # its radar point is not in the image
    "guard_rail",  # the guard-rail filter labelled it: not searched
    "no_symmetry",  # no axis qualifies
    "no_bottom",  # axes, but no box with a bottom
    "size_filter",  # the chosen box is too narrow or too wide for a vehicle
]

Box = tuple[float, float, float, float]


@dataclass(frozen=True)
class Candidate:
    """One candidate box in resampled-area pixels.

    axis_px: axis column (whole or half); half_width_row: the symmetry matrix's half-width
    w (row w - 1) taken as the vehicle's; half_width_px: the borders' distance from the
    axis's centre (sub-pixel); chi: the matrix value at (w, axis); bottom_px / top_px:
    pixel-edge rows of the box base and top (None when not found); box_px: (u0, v0, u1, v1)
    in the full image (None without a bottom).
    """

    axis_px: float
    half_width_row: int
    half_width_px: float
    chi: float
    bottom_px: int | None
    top_px: int | None
    box_px: Box | None


@dataclass(frozen=True, eq=False)
class TargetResult:
    """What the detector did with one radar target.

    area: its search area (None when outside the image); edges: (h, w) int8 signed vertical
    edges of the resampled area; symmetry: (max_half_width_px, 2 w - 1) float32 chi, row k is
    half-width k + 1; threshold: the chi an axis had to reach; candidates: the axes that
    qualified, with their boxes; chosen: index into candidates of the most central box with
    a bottom; box_px (property): the chosen box in full-image pixels; verdict: see
    `Verdict`; vehicle_index: the final vehicle it is part of.
    """

    target_index: int
    target: RadarTarget
    area: SearchArea | None
    edges: I8Array
    symmetry: F32Array
    threshold: float
    candidates: tuple[Candidate, ...]
    chosen: int | None
    verdict: Verdict
    vehicle_index: int | None

    @property
    def box_px(self) -> Box | None:
        return _chosen_box(self.candidates, self.chosen)


@dataclass(frozen=True)
class Vehicle:
    """A detected vehicle: box_px (u0, v0, u1, v1) in the full image; distance_m from the
    radar, lateral_m (positive left) and width_m from vision; vision_distance_m: where the
    box base meets the road; target_indices: the radar targets it came from."""

    box_px: Box
    distance_m: float
    lateral_m: float
    width_m: float
    vision_distance_m: float
    target_indices: tuple[int, ...]


@dataclass(frozen=True, eq=False)
class VehicleResult:
    targets: tuple[TargetResult, ...]  # one per radar target, in radar order
    vehicles: tuple[Vehicle, ...]


# --- steps 4-5 ------------------------------------------------------------------------------


def signed_vertical_edges(patch: npt.NDArray[np.uint8], threshold: float) -> I8Array:
    """(h, w) uint8 -> (h, w) int8: +1 / -1 where the horizontal derivative is above
    `threshold` / below -threshold (3x3 Sobel), else 0."""
    d = cv2.Sobel(patch, cv2.CV_16S, 1, 0, ksize=3)
    return (d > threshold).astype(np.int8) - (d < -threshold).astype(np.int8)


@functools.lru_cache(maxsize=64)
def _mirror_index(width: int, max_half: int) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]:
    """Indices of `mirrored_pairs` for an area `width` columns wide.

    Axis a (0 .. 2 width - 2) lies at column a / 2; row k - 1 (k = 1 .. max_half) pairs the
    columns (a - d) / 2 and (a + d) / 2 at distance d = 2 k (whole axes) or 2 k - 1 (half
    axes). Returns the flat indices of those pairs into a (width + 1)^2 matrix (pairs
    falling outside the area point at its padding corner, which holds 0) and the
    prefix-sum bounds of the windows between them.
    """
    k = np.arange(1, max_half + 1)[:, None]
    a = np.arange(2 * width - 1)[None, :]
    d = 2 * k - a % 2
    left, right = (a - d) // 2, (a + d) // 2
    ok = (left >= 0) & (right < width)
    flat = np.where(ok, left * (width + 1) + right, width * (width + 1) + width)
    bounds = np.stack([np.clip(left, 0, width), np.clip(right + 1, 0, width)])
    return flat, bounds


def mirrored_pairs(edges: I8Array, max_half_width_px: int) -> tuple[F32Array, F32Array]:
    """(..., h, w) signed edges -> (pairs, n), both (..., max_half_width_px, 2 w - 1) float32.

    Column a is the axis at column a / 2 (every column and every border between two);
    pairs[k - 1, a]: rows where the columns (a - d) / 2 and (a + d) / 2 hold edges of
    opposite signs, d = 2 k for a whole axis and 2 k - 1 for a half one (the pair is k
    half-widths of the window apart, measured from pixel centres); n[k - 1, a]: edges in the
    columns between them (outside the area counts as none). Leading axes: several areas of
    one size at once.
    """
    if edges.ndim < 2:
        raise ValueError(f"edges: expected an (h, w) array, got shape {edges.shape}")
    *lead, h, w = edges.shape
    stack = edges.reshape(-1, h, w)
    pos = (stack > 0).astype(np.float32)
    neg = (stack < 0).astype(np.float32)
    opposite = np.zeros((len(stack), w + 1, w + 1), dtype=np.float32)
    m = pos.transpose(0, 2, 1) @ neg  # m[t, i, j]: rows with + at column i and - at column j
    opposite[:, :w, :w] = m + m.transpose(0, 2, 1)
    flat, (lo, hi) = _mirror_index(w, max_half_width_px)
    counts = np.zeros((len(stack), w + 1), dtype=np.float32)
    np.cumsum((pos + neg).sum(axis=1), axis=1, out=counts[:, 1:])
    shape = (*lead, *flat.shape)
    pairs = opposite.reshape(len(stack), -1)[:, flat]
    return pairs.reshape(shape), (counts[:, hi] - counts[:, lo]).reshape(shape)


def chi_matrix(pairs: F32Array, n: F32Array) -> F32Array:
    """The symmetry matrix chi = s^2 / n (paper 001, II), (K, 2 w - 1) float32, 0 where
    n = 0.

    pairs, n: from `mirrored_pairs`; s, the pairs within half-width k + 1, is their running
    sum down the rows.
    """
    s = np.cumsum(pairs, axis=-2)
    chi = s * s
    chi /= np.maximum(n, 1.0)  # s > 0 only where the window holds edges (n >= 2)
    return chi


def symmetry_matrix(edges: I8Array, max_half_width_px: int) -> F32Array:
    """(h, w) signed edges -> (max_half_width_px, 2 w - 1) float32 chi: row k - 1, column a
    is the window of half-width k about the axis at column a / 2 (see `mirrored_pairs`)."""
    return chi_matrix(*mirrored_pairs(edges, max_half_width_px))


# --- step 6 ----------------------------------------------------------------------------------


def candidate_axes(
    symmetry: F32Array,
    pairs: F32Array,
    threshold: float,
    narrow_half_px: int,
    min_half_px: int,
    max_half_px: int,
) -> list[tuple[float, int, float, float]]:
    """(axis column, half-width row, chi, half_width_px) of the axes that may be a
    vehicle's (step 6).

    symmetry, pairs: (K, 2 w - 1) from `chi_matrix` and `mirrored_pairs`. An axis qualifies
    when chi stays below `threshold` for half-widths < narrow_half_px and reaches it at its
    vehicle half-width: the half-width in min_half_px .. max_half_px with the most mirrored
    pairs summed with its two neighbours (a border's Sobel edge is two or three pixels
    wide); half-width row: that half-width, whose chi is given; half_width_px: the mean
    distance of those pairs, the border's position (a border at a pixel edge gives edge
    pixels on both sides of it, so their pairs' mean distance is the border's). One axis
    per run of neighbouring qualifying axes: the one with the highest chi at its width.
    """
    ok, k, chi_at = _qualifying(
        symmetry[None],
        pairs[None],
        np.array([threshold]),
        np.array([narrow_half_px]),
        np.array([min_half_px]),
        np.array([max_half_px]),
    )
    return _best_of_runs(ok[0], k[0], chi_at[0], pairs)


def _qualifying(
    symmetry: F32Array,
    pairs: F32Array,
    threshold: FloatArray,
    narrow_half_px: npt.NDArray[np.int_],
    min_half_px: npt.NDArray[np.int_],
    max_half_px: npt.NDArray[np.int_],
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.intp], F32Array]:
    """`candidate_axes` for T areas at once: symmetry, pairs (T, K, A); the rest (T,).
    Returns (T, A) arrays: qualifies, the vehicle half-width's row, chi there."""
    rows = np.arange(symmetry.shape[1])[None, :, None]
    near = pairs.copy()
    near[:, 1:] += pairs[:, :-1]
    near[:, :-1] += pairs[:, 1:]
    k_min = (np.maximum(min_half_px, 1) - 1)[:, None, None]
    k_max = np.minimum(max_half_px, symmetry.shape[1])[:, None, None]
    k = np.argmax(np.where((rows >= k_min) & (rows < k_max), near, -1.0), axis=1)
    chi_at = np.take_along_axis(symmetry, k[:, None, :], axis=1)[:, 0]
    near_at = np.take_along_axis(near, k[:, None, :], axis=1)[:, 0]
    thr = threshold[:, None, None]
    narrow = ((symmetry >= thr) & (rows < (narrow_half_px - 1)[:, None, None])).any(axis=1)
    ok = ~narrow & (chi_at >= thr[:, 0]) & (near_at > 0) & (k_max > k_min)[:, 0]
    return ok, k, chi_at


def _best_of_runs(
    ok: npt.NDArray[np.bool_], k: npt.NDArray[np.intp], chi_at: F32Array, pairs: F32Array
) -> list[tuple[float, int, float, float]]:
    """One axis per run of neighbouring qualifying axes (see `candidate_axes`)."""
    axes = np.flatnonzero(ok)
    out: list[tuple[float, int, float, float]] = []
    for run in np.split(axes, np.flatnonzero(np.diff(axes) > 1) + 1) if len(axes) else ():
        best = int(run[np.argmax(chi_at[run])])
        rows = np.arange(max(k[best] - 1, 0), min(k[best] + 2, len(pairs)))
        # pair distance / 2, from pixel centres: k on whole axes, k - 1/2 on half ones
        half_px = float(np.average(rows + 1 - 0.5 * (best % 2), weights=pairs[rows, best]))
        out.append((best / 2, int(k[best]) + 1, float(chi_at[best]), half_px))
    return out


# --- step 7 ----------------------------------------------------------------------------------


def find_bottom(
    d_down: npt.NDArray[np.int16], col0: int, col1: int, params: VehicleParams
) -> int | None:
    """Lowest pixel-edge row between a darker row above and a brighter row below over at
    least `bottom_edge_fraction` of columns col0 .. col1 - 1; None when there is none.

    d_down: (h, w) vertical Sobel derivative of the area (positive: brighter below).
    """
    share = (d_down[:, col0:col1] > params.edge_threshold).mean(axis=1)
    rows = np.flatnonzero(share >= params.bottom_edge_fraction)
    return None if len(rows) == 0 else int(rows[-1])


def find_top(
    d_down: npt.NDArray[np.int16], col0: int, col1: int, bottom: int, params: VehicleParams
) -> int | None:
    """Highest pixel-edge row at least `min_height_ratio` x width above `bottom` with
    horizontal edges of either sign over `top_edge_fraction` of the columns; None when there
    is none."""
    highest = bottom - math.ceil(params.min_height_ratio * (col1 - col0))
    if highest <= 0:
        return None
    share = (np.abs(d_down[:highest, col0:col1]) > params.edge_threshold).mean(axis=1)
    rows = np.flatnonzero(share >= params.top_edge_fraction)
    # the highest of the edge's two Sobel rows lies just above it
    return None if len(rows) == 0 else int(rows[0]) + 1


# --- steps 4-8 for one area ------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class _AreaSearch:
    edges: I8Array
    symmetry: F32Array
    threshold: float
    candidates: tuple[Candidate, ...]
    chosen: int | None

    @property
    def box_px(self) -> Box | None:
        return _chosen_box(self.candidates, self.chosen)


def _chosen_box(candidates: tuple[Candidate, ...], chosen: int | None) -> Box | None:
    return None if chosen is None else candidates[chosen].box_px


def _search(areas: list[SearchArea], params: VehicleParams) -> list[_AreaSearch]:
    """Steps 4-8 on each of `areas`; steps 5-6 on all of them at once (padded to one size)."""
    if not areas:
        return []
    edges = [signed_vertical_edges(a.patch, params.edge_threshold) for a in areas]
    sizes = np.array([e.shape for e in edges])
    stack = np.zeros((len(edges), *sizes.max(axis=0)), dtype=np.int8)
    for t, e in enumerate(edges):
        stack[t, : e.shape[0], : e.shape[1]] = e
    pairs, n = mirrored_pairs(stack, params.max_half_width_px)
    symmetry = chi_matrix(pairs, n)
    px_per_m = np.array([a.px_per_m for a in areas])
    thresholds = params.symmetry_threshold * sizes[:, 0]
    ok, k, chi_at = _qualifying(
        symmetry,
        pairs,
        thresholds,
        np.ceil(params.narrow_width_m / 2 * px_per_m).astype(int),
        np.ceil(params.min_width_m / 2 * px_per_m).astype(int),
        np.floor(params.max_width_m / 2 * px_per_m).astype(int),
    )
    out = []
    for t, area in enumerate(areas):
        a = 2 * sizes[t, 1] - 1  # the area's own axes
        axes = _best_of_runs(ok[t, :a], k[t, :a], chi_at[t, :a], pairs[t, :, :a])
        candidates, chosen = _boxes(area, axes, params)
        out.append(
            _AreaSearch(edges[t], symmetry[t, :, :a], float(thresholds[t]), candidates, chosen)
        )
    return out


def _boxes(
    area: SearchArea, axes: list[tuple[float, int, float, float]], params: VehicleParams
) -> tuple[tuple[Candidate, ...], int | None]:
    """Steps 7-8: the candidates' bottoms, tops and boxes, and the most central one."""
    if not axes:
        return (), None
    patch = area.patch
    w = patch.shape[1]
    d_down: npt.NDArray[np.int16] = np.asarray(cv2.Sobel(patch, cv2.CV_16S, 0, 1, ksize=3))
    candidates = []
    for axis, half, chi, half_px in axes:
        centre = axis + 0.5  # in pixel-edge columns: pixel c spans c .. c + 1
        col0, col1 = max(0, round(centre - half_px)), min(w, round(centre + half_px))
        bottom = find_bottom(d_down, col0, col1, params)
        top = None if bottom is None else find_top(d_down, col0, col1, bottom, params)
        box = None
        if bottom is not None:
            (u0, u1), (vb,) = area.to_image_px([centre - half_px, centre + half_px], [bottom])
            if top is None:
                vt = vb - params.default_height_ratio * (u1 - u0)
            else:
                vt = float(area.to_image_px([0.0], [top])[1][0])
            box = (float(u0), float(vt), float(u1), float(vb))
        candidates.append(Candidate(axis, half, half_px, chi, bottom, top, box))
    centre_col = (area.base_px[0] - area.box_px[0] + 0.5) * w / (area.box_px[2] - area.box_px[0])
    with_box = [i for i, c in enumerate(candidates) if c.box_px is not None]
    chosen = min(
        with_box, key=lambda i: abs(candidates[i].axis_px + 0.5 - centre_col), default=None
    )
    return tuple(candidates), chosen


# --- steps 9-10 ------------------------------------------------------------------------------


def world_extents(
    boxes_px: Sequence[Box], distances_m: Sequence[float], camera: CameraModel
) -> tuple[list[float], list[float], list[float]]:
    """(lateral_m, width_m, vision_distance_m) of each box: where its bottom corners' rays
    cross the vertical plane x = its distance; vision_distance_m: x where the base centre
    meets the road (NaN at or above the horizon)."""
    if not boxes_px:
        return [], [], []
    b = np.asarray(boxes_px, dtype=np.float64)
    columns = np.concatenate([b[:, 0], b[:, 2], (b[:, 0] + b[:, 2]) / 2])
    pts = np.stack([columns, np.tile(b[:, 3], 3)], axis=1)  # left, right, middle of the bases
    d = camera.rays_vehicle(pts)
    o = camera.position_vehicle_m
    n = len(b)
    x = np.tile(np.asarray(distances_m, dtype=np.float64), 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        y = o[1] + d[: 2 * n, 1] * (x - o[0]) / d[: 2 * n, 0]
        t = -o[2] / d[2 * n :, 2]
    vision = np.where((t > 0) & np.isfinite(t), o[0] + t * d[2 * n :, 0], np.nan)
    return ((y[:n] + y[n:]) / 2).tolist(), (y[:n] - y[n:]).tolist(), vision.tolist()


def world_size_ok(
    box_px: Box, distance_m: float, camera: CameraModel, params: VehicleParams
) -> bool:
    """The world-size filter: is the box as wide as a vehicle (`min_width_m` .. `max_width_m`)
    at the radar's distance?"""
    (width_m,) = world_extents([box_px], [distance_m], camera)[1]
    return _vehicle_wide(width_m, params)


def _vehicle_wide(width_m: float, params: VehicleParams) -> bool:
    return params.min_width_m <= width_m <= params.max_width_m


def _overlap_of_smaller(a: Box, b: Box) -> float:
    return intersection_area(a, b) / max(min(rect_area(a), rect_area(b)), 1e-9)


def merge_boxes(boxes: list[tuple[Box, int]], params: VehicleParams) -> list[tuple[Box, list[int]]]:
    """Merge (box, target_index) pairs from several targets (paper 001, II).

    Largest first; a box overlapping a kept one by more than `merge_overlap_fraction` of the
    smaller is dropped in its favour, unless the two are of similar width with their bases
    at the same height, when the kept box becomes the mean of the boxes merged into it.
    Returns (box, target indices) per kept box, largest first.
    """
    order = sorted(boxes, key=lambda bt: -rect_area(bt[0]))
    kept: list[tuple[list[Box], list[int]]] = []  # the boxes averaged into each, their targets
    for box, target in order:
        for members, targets in kept:
            ref = tuple(np.mean(members, axis=0))
            if _overlap_of_smaller(ref, box) <= params.merge_overlap_fraction:
                continue
            w_ref, w_box = ref[2] - ref[0], box[2] - box[0]
            h_ref = ref[3] - ref[1]
            similar = min(w_ref, w_box) / max(w_ref, w_box) >= params.similar_size_ratio
            same_base = abs(ref[3] - box[3]) <= params.same_base_fraction * h_ref
            if similar and same_base:
                members.append(box)
            targets.append(target)
            break
        else:
            kept.append(([box], [target]))
    return [
        (tuple(float(x) for x in np.mean(members, axis=0)), targets)  # type: ignore[misc]
        for members, targets in kept
    ]


def detect_vehicles(
    areas: tuple[SearchArea, ...],
    radar: tuple[RadarTarget, ...],
    camera: CameraModel,
    params: VehicleParams,
    guard_rails: frozenset[int] = frozenset(),
) -> VehicleResult:
    """Vehicles from the search areas of a frame's radar targets.

    areas: `core.search_area.search_areas` of the frame; radar: the frame's targets (those
    without an area are outside the image); camera: the frame's camera model; guard_rails:
    indices of targets the guard-rail filter labelled, which are not searched.
    """
    by_target = {a.target_index: a for a in areas}
    if len(by_target) != len(areas) or any(not 0 <= i < len(radar) for i in by_target):
        raise ValueError(
            f"areas: expected at most one area per radar target 0..{len(radar) - 1}, "
            f"got target indices {sorted(a.target_index for a in areas)}"
        )
    searched = [a for a in areas if a.target_index not in guard_rails]
    found = dict(zip((a.target_index for a in searched), _search(searched, params), strict=True))
    chosen = {i: box for i, f in found.items() if (box := f.box_px) is not None}
    ids = list(chosen)
    _, widths_m, _ = world_extents([chosen[i] for i in ids], [radar[i].x_m for i in ids], camera)
    sized = [
        (chosen[i], i)
        for i, width_m in zip(ids, widths_m, strict=True)
        if _vehicle_wide(width_m, params)
    ]
    merged = merge_boxes(sized, params)
    distances_m = [float(np.mean([radar[t].x_m for t in targets])) for _, targets in merged]
    lateral_m, width_m, vision_m = world_extents([b for b, _ in merged], distances_m, camera)
    vehicles = tuple(
        Vehicle(box, distances_m[j], lateral_m[j], width_m[j], vision_m[j], tuple(sorted(ts)))
        for j, (box, ts) in enumerate(merged)
    )
    vehicle_of = {t: j for j, (_, ts) in enumerate(merged) for t in ts}
    empty_edges = np.zeros((0, 0), dtype=np.int8)
    empty_sym = np.zeros((params.max_half_width_px, 0), dtype=np.float32)
    results = []
    for i, target in enumerate(radar):
        area, f = by_target.get(i), found.get(i)
        if f is None:
            verdict: Verdict = "outside_image" if area is None else "guard_rail"
            results.append(
                TargetResult(i, target, area, empty_edges, empty_sym, 0.0, (), None, verdict, None)
            )
            continue
        if i in vehicle_of:
            verdict = "vehicle"
        elif i in chosen:
            verdict = "size_filter"
        else:
            verdict = "no_bottom" if f.candidates else "no_symmetry"
        results.append(
            TargetResult(
                i,
                target,
                area,
                f.edges,
                f.symmetry,
                f.threshold,
                f.candidates,
                f.chosen,
                verdict,
                vehicle_of.get(i),
            )
        )
    return VehicleResult(tuple(results), vehicles)
