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
    return _signed(np.asarray(cv2.Sobel(patch, cv2.CV_16S, 1, 0, ksize=3)), threshold)


def _signed(d: npt.NDArray[np.int16], threshold: float) -> I8Array:
    """+1 / -1 where `d` is above `threshold` / below -threshold, else 0 (int8)."""
    return (d > threshold).astype(np.int8) - (d < -threshold).astype(np.int8)


def _sobel_stack(patches: list[npt.NDArray[np.uint8]], dx: int, dy: int) -> npt.NDArray[np.int16]:
    """(T, h, w) 3x3 Sobel derivatives of `patches` (dx, dy: its orders), each in its own
    area's size and 0 beyond (h, w: the largest)."""
    out = np.zeros((len(patches), *np.max([p.shape for p in patches], axis=0)), dtype=np.int16)
    for t, patch in enumerate(patches):
        h, w = patch.shape
        out[t, :h, :w] = cv2.Sobel(patch, cv2.CV_16S, dx, dy, ksize=3)
    return out


@functools.lru_cache(maxsize=64)
def _mirror_index(width: int, max_half: int) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]:
    """Indices of `mirrored_pairs` for an area `width` columns wide, (max_half, 2 width - 1)
    each.

    Axis a (0 .. 2 width - 2) lies at column a / 2; half-width k (1 .. max_half) pairs the
    columns (a - d) / 2 and (a + d) / 2 at distance d = 2 k (whole axes) or 2 k - 1 (half
    axes). Returns the flat indices of those pairs into a (width, width) matrix (pairs
    falling outside the area point at (0, 0): no column holds edges of both signs, so that
    entry is 0) and of the window between them, (first column, stop column) clipped to the
    area, into a (width + 1, width + 1) matrix.
    """
    k = np.arange(1, max_half + 1)[:, None]
    a = np.arange(2 * width - 1)[None, :]
    d = 2 * k - a % 2
    left, right = (a - d) // 2, (a + d) // 2
    pair = np.where((left >= 0) & (right < width), left * width + right, 0)
    window = np.clip(left, 0, width) * (width + 1) + np.clip(right + 1, 0, width)
    return pair, window


@functools.lru_cache(maxsize=8)
def _lower_ones(size: int) -> F32Array:
    """(size, size) lower-triangular ones: its product with a matrix sums its rows down."""
    return np.tril(np.ones((size, size), dtype=np.float32))


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
    m = pos.transpose(0, 2, 1) @ neg  # m[t, i, j]: rows with + at column i and - at column j
    opposite = (m + m.transpose(0, 2, 1)).reshape(len(stack), w * w)
    counts = np.zeros((len(stack), w + 1), dtype=np.float32)  # edges left of each column
    np.cumsum((pos + neg).sum(axis=1), axis=1, out=counts[:, 1:])
    between = counts[:, None, :] - counts[:, :, None]  # [t, i, j]: edges in columns i .. j - 1
    pair, window = _mirror_index(w, max_half_width_px)
    shape = (*lead, *pair.shape)
    return (
        np.take(opposite, pair, axis=1).reshape(shape),
        np.take(between.reshape(len(stack), -1), window, axis=1).reshape(shape),
    )


def chi_matrix(pairs: F32Array, n: F32Array) -> F32Array:
    """The symmetry matrix chi = s^2 / n (paper 001, II), (K, 2 w - 1) float32, 0 where
    n = 0.

    pairs, n: from `mirrored_pairs`; s, the pairs within half-width k + 1, is their running
    sum down the rows.
    """
    s = _lower_ones(pairs.shape[-2]) @ pairs
    chi = s * s
    chi /= np.maximum(n, 1.0)  # s > 0 only where the window holds edges (n >= 2)
    return chi


def symmetry_matrix(edges: I8Array, max_half_width_px: int) -> F32Array:
    """(h, w) signed edges -> (max_half_width_px, 2 w - 1) float32 chi: row k - 1, column a
    is the window of half-width k about the axis at column a / 2 (see `mirrored_pairs`)."""
    return chi_matrix(*mirrored_pairs(edges, max_half_width_px))


# --- step 6 ----------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Axes:
    """Candidate axes of T areas, one entry per axis: its area, axis column a (at a / 2),
    vehicle half-width row k (half-width k + 1), chi there and half-width in pixels."""

    area: npt.NDArray[np.intp]
    axis: npt.NDArray[np.intp]
    row: npt.NDArray[np.intp]
    chi: F32Array
    half_px: FloatArray


def candidate_axes(
    symmetry: F32Array,
    pairs: F32Array,
    threshold: float,
    narrow_half_px: int,
    min_half_px: int,
    max_half_px: int,
) -> list[tuple[float, int, float, float]]:
    """(axis column, half-width, chi, half_width_px) of the axes that may be a vehicle's
    (step 6).

    symmetry, pairs: (K, 2 w - 1) from `chi_matrix` and `mirrored_pairs`. An axis qualifies
    when chi stays below `threshold` for half-widths < narrow_half_px and reaches it at its
    vehicle half-width: the half-width in min_half_px .. max_half_px with the most mirrored
    pairs summed with its two neighbours (a border's Sobel edge is two or three pixels
    wide); chi is given at that half-width; half_width_px: the mean distance of those pairs,
    the border's position (a border at a pixel edge gives edge pixels on both sides of it, so
    their pairs' mean distance is the border's). One axis per run of neighbouring qualifying
    axes: the one with the highest chi at its width.
    """
    found = _candidate_axes(
        symmetry[None],
        pairs[None],
        np.array([threshold]),
        np.array([narrow_half_px]),
        np.array([min_half_px]),
        np.array([max_half_px]),
    )
    return list(
        zip(
            (found.axis / 2).tolist(),
            (found.row + 1).tolist(),
            found.chi.tolist(),
            found.half_px.tolist(),
            strict=True,
        )
    )


def _candidate_axes(
    symmetry: F32Array,
    pairs: F32Array,
    threshold: FloatArray,
    narrow_half_px: npt.NDArray[np.int_],
    min_half_px: npt.NDArray[np.int_],
    max_half_px: npt.NDArray[np.int_],
) -> _Axes:
    """`candidate_axes` for T areas at once: symmetry, pairs (T, K, A); the rest (T,)."""
    n_areas, n_rows, n_axes = symmetry.shape
    rows = np.arange(n_rows)[None, :]
    near = pairs.copy()
    near[:, 1:] += pairs[:, :-1]
    near[:, :-1] += pairs[:, 1:]
    # the vehicle half-width: a max over rows of near * base + (base - 1 - row) finds the
    # most pairs and, among equals, the lowest row (near holds whole numbers)
    base = 2 ** n_rows.bit_length()
    vehicle_rows = (rows >= np.maximum(min_half_px, 1)[:, None] - 1) & (
        rows < np.minimum(max_half_px, n_rows)[:, None]
    )
    rank = np.where(vehicle_rows, base - 1 - rows, base - 1 - 2.0**23).astype(np.float32)
    best_near = (near * base + rank[:, :, None]).max(axis=1)  # (T, A); < 0: no such rows
    k = (base - 1 - best_near % base).astype(np.intp)  # row 0 where there are no such rows
    at_k = (np.arange(n_areas)[:, None] * n_rows + k) * n_axes + np.arange(n_axes)
    chi_at = symmetry.reshape(-1)[at_k]
    # "low for narrow widths": the few rows below narrow_half_px
    narrow = max(int(narrow_half_px.max()) - 1, 0)
    narrow_rows = (rows[:, :narrow] < narrow_half_px[:, None] - 1)[:, :, None]
    narrow_chi = np.where(narrow_rows, symmetry[:, :narrow], 0.0).max(axis=1, initial=0.0)
    thr = threshold[:, None]
    ok = (narrow_chi < thr) & (chi_at >= thr) & (best_near >= base)
    # one axis per run: a False column after each area's axes keeps runs apart
    padded = np.zeros((n_areas, n_axes + 1), dtype=bool)
    padded[:, :n_axes] = ok
    flat = np.flatnonzero(padded)
    area, axis = np.divmod(flat, n_axes + 1)
    starts = np.ones(len(flat), dtype=bool)
    starts[1:] = flat[1:] - flat[:-1] > 1
    run = np.cumsum(starts)
    order = np.lexsort((-chi_at[area, axis], run))  # per run, highest chi first (stable)
    best = order[starts]  # runs are numbered in order, one start each
    area, axis = area[best], axis[best]
    k_best = k[area, axis]
    # the half-width: the mean distance of the pairs in rows k - 1 .. k + 1
    near_rows = k_best[:, None] + np.arange(-1, 2)[None, :]
    inside = (near_rows >= 0) & (near_rows < n_rows)
    weights = np.where(inside, pairs[area[:, None], near_rows % n_rows, axis[:, None]], 0.0)
    # pair distance / 2, from pixel centres: k on whole axes, k - 1/2 on half ones
    distance = near_rows + 1 - 0.5 * (axis % 2)[:, None]
    half_px = (weights * distance).sum(axis=1) / weights.sum(axis=1)
    return _Axes(area, axis, k_best, chi_at[area, axis], half_px)


# --- step 7 ----------------------------------------------------------------------------------


def _box_rows(
    d_down: npt.NDArray[np.int16],
    area: npt.NDArray[np.intp],
    col0: npt.NDArray[np.intp],
    col1: npt.NDArray[np.intp],
    params: VehicleParams,
) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]:
    """Step 7 for C candidates at once: their (bottom, top) pixel-edge rows, -1 where none.

    d_down: (T, h, w) vertical Sobel derivatives of the areas (positive: brighter below; 0
    beyond an area's own size); area, col0, col1: (C,) each candidate's area and columns
    col0 .. col1 - 1. The bottom: the lowest row between a darker row above and a brighter
    row below over at least `bottom_edge_fraction` of the columns. The top: the highest row
    at least `min_height_ratio` x width above the bottom with horizontal edges of either
    sign over `top_edge_fraction` of the columns.
    """
    n_areas, n_rows, n_cols = d_down.shape
    thr = params.edge_threshold
    masks = np.concatenate([d_down > thr, np.abs(d_down) > thr]).astype(np.float32)
    columns = np.arange(n_cols)[:, None]
    chosen = ((columns >= col0) & (columns < col1)).astype(np.float32)  # (w, C)
    counts = (masks.reshape(-1, n_cols) @ chosen).reshape(2, n_areas, n_rows, -1)
    c = np.arange(len(area))
    width = np.maximum(col1 - col0, 1)[:, None]
    rows = np.arange(n_rows)[None, :]
    below = counts[0, area, :, c] / width >= params.bottom_edge_fraction  # (C, h)
    bottom = np.where(below.any(axis=1), n_rows - 1 - np.argmax(below[:, ::-1], axis=1), -1)
    highest = bottom - np.ceil(params.min_height_ratio * (col1 - col0)).astype(np.intp)
    across = (counts[1, area, :, c] / width >= params.top_edge_fraction) & (rows < highest[:, None])
    # the highest of the edge's two Sobel rows lies just above it
    top = np.where(across.any(axis=1), np.argmax(across, axis=1) + 1, -1)
    return bottom, top


# --- steps 4-8 for the areas of a frame ------------------------------------------------------


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
    """Steps 4-8 on each of `areas`, all at once (padded to one size)."""
    if not areas:
        return []
    sizes = np.array([a.patch.shape for a in areas])
    edges = _signed(_sobel_stack([a.patch for a in areas], 1, 0), params.edge_threshold)
    pairs, n = mirrored_pairs(edges, params.max_half_width_px)
    symmetry = chi_matrix(pairs, n)
    px_per_m = np.array([a.px_per_m for a in areas])
    thresholds = params.symmetry_threshold * sizes[:, 0]
    axes = _candidate_axes(
        symmetry,
        pairs,
        thresholds,
        np.ceil(params.narrow_width_m / 2 * px_per_m).astype(int),
        np.ceil(params.min_width_m / 2 * px_per_m).astype(int),
        np.floor(params.max_width_m / 2 * px_per_m).astype(int),
    )
    candidates = _candidates(areas, sizes, axes, params)
    return [
        _AreaSearch(
            edges[t, : sizes[t, 0], : sizes[t, 1]],
            symmetry[t, :, : 2 * sizes[t, 1] - 1],  # the area's own axes
            float(thresholds[t]),
            candidates[t],
            _most_central(area, candidates[t]),
        )
        for t, area in enumerate(areas)
    ]


def _candidates(
    areas: list[SearchArea], sizes: npt.NDArray[np.int_], axes: _Axes, params: VehicleParams
) -> list[tuple[Candidate, ...]]:
    """Step 7: each area's candidates with their bottoms, tops and boxes in the image."""
    found: list[list[Candidate]] = [[] for _ in areas]
    if len(axes.area) == 0:
        return [()] * len(areas)
    with_axes, stacked = np.unique(axes.area, return_inverse=True)
    d_down = _sobel_stack([areas[t].patch for t in with_axes.tolist()], 0, 1)
    h, w = sizes[axes.area].T
    centre = axes.axis / 2 + 0.5  # in pixel-edge columns: pixel c spans c .. c + 1
    col0 = np.maximum(0, np.round(centre - axes.half_px)).astype(np.intp)
    col1 = np.minimum(w, np.round(centre + axes.half_px)).astype(np.intp)
    bottom, top = _box_rows(d_down, stacked, col0, col1, params)
    # patch pixel edges -> image pixels (`SearchArea.to_image_px`)
    c0, r0, c1, r1 = np.array([a.box_px for a in areas], dtype=np.float64)[axes.area].T
    u0 = c0 - 0.5 + (centre - axes.half_px) * (c1 - c0) / w
    u1 = c0 - 0.5 + (centre + axes.half_px) * (c1 - c0) / w
    vb = r0 - 0.5 + bottom * (r1 - r0) / h
    vt = np.where(
        top >= 0, r0 - 0.5 + top * (r1 - r0) / h, vb - params.default_height_ratio * (u1 - u0)
    )
    columns = zip(
        axes.area.tolist(),
        (axes.axis / 2).tolist(),
        (axes.row + 1).tolist(),
        axes.half_px.tolist(),
        axes.chi.tolist(),
        bottom.tolist(),
        top.tolist(),
        np.stack([u0, vt, u1, vb], axis=1).tolist(),
        strict=True,
    )
    for t, axis, half, half_px, chi, b, tp, box in columns:
        found[t].append(
            Candidate(
                axis,
                half,
                half_px,
                chi,
                None if b < 0 else b,
                None if tp < 0 else tp,
                None if b < 0 else tuple(box),
            )
        )
    return [tuple(c) for c in found]


def _most_central(area: SearchArea, candidates: tuple[Candidate, ...]) -> int | None:
    """Step 8: the candidate with a box whose axis is nearest the radar point's column."""
    w = area.patch.shape[1]
    centre_col = (area.base_px[0] - area.box_px[0] + 0.5) * w / (area.box_px[2] - area.box_px[0])
    with_box = [i for i, c in enumerate(candidates) if c.box_px is not None]
    return min(with_box, key=lambda i: abs(candidates[i].axis_px + 0.5 - centre_col), default=None)


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
