"""Vertical symmetry of edges in one search area: steps 4-8 of the vehicle detector (paper
001 section II), compiled with numba.

`search` runs them on one resampled area (`core.search_area.SearchArea.patch`): signed
vertical edges, the symmetry matrix chi = s^2 / n (rows half-widths 1 .. K, columns axes at
half-column steps: column a is the axis at column a / 2, and half-width k pairs the columns
(a - d) / 2 and (a + d) / 2, d = 2 k on whole axes and 2 k - 1 on half ones), the candidate
axes and widths, each candidate's bottom and top, and the most central candidate with a
bottom. The other functions are its steps, for the tests and the inspector. `core.vehicle`
gives the steps in the paper's terms, their parameters and the departures.

Notes:
    - numba: the same steps written as numpy array operations (batched matrix products,
      gathers, reductions over a frame's areas) took 0.74 ms for a frame of 8 radar
      targets, most of it the fixed cost of a hundred small array operations; these loops
      take 0.03 ms per area (`fusionscope bench --stage vehicle`: 0.40 ms for the frame,
      search areas and merging included). Edge columns are bit-packed, so a count of
      mirrored pairs is a popcount of two ANDs. The first call compiles (about 10 s) and
      caches the machine code next to this file for later runs.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import numpy.typing as npt

from core.checks import require_2d_array, require_grey_image

I8Array = npt.NDArray[np.int8]
I16Array = npt.NDArray[np.int16]
I32Array = npt.NDArray[np.int32]
F32Array = npt.NDArray[np.float32]
FloatArray = npt.NDArray[np.float64]

_jit = numba.njit(cache=True, nogil=True)

# candidate table columns (`search`, `candidate_axes`)
AXIS, ROW, CHI, HALF_PX, BOTTOM, TOP = range(6)


@_jit
def _padded(patch: npt.NDArray[np.uint8]) -> npt.NDArray[np.int32]:
    """`patch` with a one-pixel border reflected as OpenCV's default, BORDER_REFLECT_101
    (..., 2, 1 | 0, 1, 2, ... n - 1 | n - 2, ...; a single row or column repeats)."""
    h, w = patch.shape
    out = np.empty((h + 2, w + 2), dtype=np.int32)
    out[1:-1, 1:-1] = patch
    out[1:-1, 0] = out[1:-1, 2] if w > 1 else out[1:-1, 1]
    out[1:-1, -1] = out[1:-1, -3] if w > 1 else out[1:-1, -2]
    out[0] = out[2] if h > 1 else out[1]
    out[-1] = out[-3] if h > 1 else out[-2]
    return out


@_jit
def sobel(patch: npt.NDArray[np.uint8], dx: int) -> I16Array:
    """3x3 Sobel derivative of `patch` (h, w) uint8: horizontal (dx = 1, positive where it
    brightens rightwards) or vertical (dx = 0, positive where it brightens downwards); the
    same numbers as cv2.Sobel(patch, cv2.CV_16S, dx, 1 - dx, ksize=3)."""
    h, w = patch.shape
    p = _padded(patch)
    out = np.empty((h, w), dtype=np.int16)
    for r in range(h):
        for c in range(w):
            if dx == 1:
                d = (
                    p[r, c + 2] - p[r, c]
                    + 2 * (p[r + 1, c + 2] - p[r + 1, c])
                    + p[r + 2, c + 2] - p[r + 2, c]
                )  # fmt: skip
            else:
                d = (
                    p[r + 2, c] - p[r, c]
                    + 2 * (p[r + 2, c + 1] - p[r, c + 1])
                    + p[r + 2, c + 2] - p[r, c + 2]
                )  # fmt: skip
            out[r, c] = d
    return out


def signed_vertical_edges(patch: npt.NDArray[np.uint8], threshold: float) -> I8Array:
    """Step 4: (h, w) uint8 -> (h, w) int8 binarised vertical edges with their sign."""
    require_grey_image("patch", patch)
    return signed_edges(sobel(patch, 1), float(threshold))


def symmetry_matrix(edges: I8Array, max_half_width_px: int) -> F32Array:
    """Step 5: (h, w) int8 signed edges -> (max_half_width_px, 2 w - 1) float32 chi."""
    require_2d_array("edges", edges, np.int8, "int8 edge image")
    return chi_matrix(*mirrored_pairs(edges, max_half_width_px))


@_jit
def signed_edges(derivative: I16Array, threshold: float) -> I8Array:
    """+1 / -1 where `derivative` is above `threshold` / below -threshold, else 0."""
    h, w = derivative.shape
    out = np.empty((h, w), dtype=np.int8)
    for r in range(h):
        for c in range(w):
            d = derivative[r, c]
            # without branches, which the compiler vectorises: a third of the time
            out[r, c] = np.int8(d > threshold) - np.int8(d < -threshold)
    return out


@_jit
def _popcount(x: np.uint64) -> int:
    x = x - ((x >> np.uint64(1)) & np.uint64(0x5555555555555555))
    x = (x & np.uint64(0x3333333333333333)) + ((x >> np.uint64(2)) & np.uint64(0x3333333333333333))
    x = (x + (x >> np.uint64(4))) & np.uint64(0x0F0F0F0F0F0F0F0F)
    return int((x * np.uint64(0x0101010101010101)) >> np.uint64(56))


@_jit
def mirrored_pairs(edges: I8Array, max_half_width_px: int) -> tuple[I32Array, I32Array]:
    """(h, w) signed edges -> (pairs, n), both (max_half_width_px, 2 w - 1) int32.

    pairs[k - 1, a]: rows where the columns (a - d) / 2 and (a + d) / 2 hold edges of
    opposite signs (d = 2 k on whole axes, 2 k - 1 on half ones; pairs outside the area
    count none); n[k - 1, a]: edges in the columns between them, inside the area.
    """
    h, w = edges.shape
    words = (h + 63) // 64
    pos = np.zeros((words, w), dtype=np.uint64)  # bit r % 64 of word r // 64: an edge in row r
    neg = np.zeros((words, w), dtype=np.uint64)
    # left_of[K + c]: edges left of column c, for c = -K .. w + K (none outside the area)
    k_max = max_half_width_px
    left_of = np.zeros(w + 2 * k_max + 2, dtype=np.int32)
    for r in range(h):
        word, bit = r // 64, np.uint64(1) << np.uint64(r % 64)
        for c in range(w):
            if edges[r, c] > 0:
                pos[word, c] |= bit
                left_of[k_max + c + 1] += 1
            elif edges[r, c] < 0:
                neg[word, c] |= bit
                left_of[k_max + c + 1] += 1
    for i in range(1, len(left_of)):
        left_of[i] += left_of[i - 1]
    n_axes = 2 * w - 1
    pairs = np.zeros((max_half_width_px, n_axes), dtype=np.int32)
    n = np.zeros((max_half_width_px, n_axes), dtype=np.int32)
    for k in range(1, k_max + 1):
        for a in range(n_axes):
            # a = 2 j: columns j - k and j + k; a = 2 j + 1: columns j + 1 - k and j + k
            left, right = ((a + 1) >> 1) - k, (a >> 1) + k
            n[k - 1, a] = left_of[k_max + right + 1] - left_of[k_max + left]
    for i in range(words):
        p, q = pos[i], neg[i]
        for k in range(1, k_max + 1):
            for a in range(max(2 * k - 1, 0), min(n_axes, 2 * (w - k))):  # both columns inside
                left, right = ((a + 1) >> 1) - k, (a >> 1) + k
                pairs[k - 1, a] += _popcount((p[left] & q[right]) | (q[left] & p[right]))
    return pairs, n


@_jit
def chi_matrix(pairs: I32Array, n: I32Array) -> F32Array:
    """chi = s^2 / n (float32, 0 where n = 0), s the pairs within each half-width: the
    running sum of `pairs` down the rows."""
    n_rows, n_axes = pairs.shape
    chi = np.zeros((n_rows, n_axes), dtype=np.float32)
    s = np.zeros(n_axes, dtype=np.int64)
    for k in range(n_rows):
        for a in range(n_axes):
            s[a] += pairs[k, a]
            if n[k, a] > 0:
                chi[k, a] = np.float32(s[a] * s[a]) / np.float32(n[k, a])
    return chi


@_jit
def _most_pairs(pairs: I32Array, a: int, k0: int, k1: int) -> tuple[int, int]:
    """(k, count): the half-width row in k0 .. k1 - 1 on axis column a with the most pairs
    summed with its two neighbours' rows (the first on ties), (-1, 0) when none has any."""
    n_rows = pairs.shape[0]
    best_k, best_near = -1, 0
    for k in range(k0, k1):
        near = pairs[k, a] + (pairs[k - 1, a] if k > 0 else 0)
        near += pairs[k + 1, a] if k + 1 < n_rows else 0
        if near > best_near:
            best_k, best_near = k, near
    return best_k, best_near


@_jit
def candidate_axes(
    chi: F32Array,
    pairs: I32Array,
    threshold: float,
    narrow_half_px: int,
    min_half_px: int,
    max_half_px: int,
    min_border_pairs: int = 0,
    preferred_min_half_px: int = 0,
    preferred_max_half_px: int = 0,
) -> FloatArray:
    """Step 6: (C, 4) float64 rows (axis column a, half-width row k, chi, half_width_px) of
    the candidate axes, one per run of neighbouring axes that qualify.

    An axis qualifies when chi stays below `threshold` for half-widths < narrow_half_px and
    reaches it at the half-width in min_half_px .. max_half_px with the most pairs summed
    with its neighbours (the first on ties), and those pairs (the borders') number at least
    min_border_pairs; k: that half-width's row (half-width k + 1). A qualified axis takes
    instead the half-width of preferred_min_half_px .. preferred_max_half_px with the most
    pairs so summed when chi reaches the threshold there with min_border_pairs (none
    preferred when the range is empty, the default): a tracked vehicle's width.
    """
    n_rows, n_axes = chi.shape
    k_min, k_max = max(min_half_px, 1) - 1, min(max_half_px, n_rows)
    found = np.zeros((n_axes, 4), dtype=np.float64)
    count = 0
    run_open = False
    for a in range(n_axes):
        ok = k_max > k_min
        for k in range(narrow_half_px - 1):
            if k < n_rows and chi[k, a] >= threshold:
                ok = False
        best_k, best_near = _most_pairs(pairs, a, k_min, k_max)
        ok = ok and best_k >= 0 and chi[best_k, a] >= threshold and best_near >= min_border_pairs
        if not ok:
            run_open = False
            continue
        # a qualified axis takes its half-width in the preferred range when one there qualifies
        pref_k, pref_near = _most_pairs(
            pairs,
            a,
            max(preferred_min_half_px - 1, k_min),
            min(preferred_max_half_px, k_max),
        )
        if pref_k >= 0 and chi[pref_k, a] >= threshold and pref_near >= min_border_pairs:
            best_k = pref_k
        if run_open and chi[best_k, a] <= found[count - 1, CHI]:
            continue  # the run's best so far stays
        if not run_open:
            count += 1
            run_open = True
        # the half-width: the mean distance of the pairs in rows k - 1 .. k + 1, from pixel
        # centres: k on whole axes, k - 1/2 on half ones
        total, weighted = 0.0, 0.0
        for k in range(max(best_k - 1, 0), min(best_k + 2, n_rows)):
            total += pairs[k, a]
            weighted += pairs[k, a] * (k + 1 - 0.5 * (a % 2))
        found[count - 1, AXIS] = a
        found[count - 1, ROW] = best_k
        found[count - 1, CHI] = chi[best_k, a]
        found[count - 1, HALF_PX] = weighted / total
    return found[:count]


@_jit
def box_rows(
    d_down: I16Array,
    col0: int,
    col1: int,
    edge_threshold: float,
    bottom_edge_fraction: float,
    top_edge_fraction: float,
    min_height_ratio: float,
    highest_bottom: int = 0,
) -> tuple[int, int]:
    """Step 7 for columns col0 .. col1 - 1 of an area: (bottom, top) pixel-edge rows, -1
    where none; a bottom above row `highest_bottom` is none. d_down: the area's vertical
    Sobel derivative (positive: brighter below)."""
    h = d_down.shape[0]
    width = max(col1 - col0, 1)
    bottom = -1
    for r in range(h - 1, max(highest_bottom, 0) - 1, -1):
        count = 0
        for c in range(col0, col1):
            if d_down[r, c] > edge_threshold:
                count += 1
        if count / width >= bottom_edge_fraction:
            bottom = r
            break
    if bottom < 0:
        return -1, -1
    highest = bottom - math.ceil(min_height_ratio * (col1 - col0))
    for r in range(highest):
        count = 0
        for c in range(col0, col1):
            if abs(d_down[r, c]) > edge_threshold:
                count += 1
        if count / width >= top_edge_fraction:
            return bottom, r + 1  # the highest of the edge's two Sobel rows lies above it
    return bottom, -1


@_jit
def search(
    patch: npt.NDArray[np.uint8],
    centre_col_px: float,
    edge_threshold: float,
    max_half_width_px: int,
    threshold: float,
    narrow_half_px: int,
    min_half_px: int,
    max_half_px: int,
    bottom_edge_fraction: float,
    top_edge_fraction: float,
    min_height_ratio: float,
    min_border_pairs: int = 0,
    highest_bottom: int = 0,
    preferred_min_half_px: int = 0,
    preferred_max_half_px: int = 0,
) -> tuple[I8Array, F32Array, FloatArray, int]:
    """Steps 4-8 on one area: (edges (h, w), chi (max_half_width_px, 2 w - 1), candidates,
    chosen). candidates: (C, 6) float64 rows indexed by AXIS, ROW, CHI, HALF_PX, BOTTOM, TOP
    (rows, -1 where none); chosen: the candidate with a bottom whose axis is nearest
    `centre_col_px` (the radar point's column, in patch pixel-edge columns), -1 when none;
    preferred_min_half_px, preferred_max_half_px: half-widths `candidate_axes` prefers.
    """
    edges = signed_edges(sobel(patch, 1), edge_threshold)
    pairs, n = mirrored_pairs(edges, max_half_width_px)
    chi = chi_matrix(pairs, n)
    axes = candidate_axes(
        chi,
        pairs,
        threshold,
        narrow_half_px,
        min_half_px,
        max_half_px,
        min_border_pairs,
        preferred_min_half_px,
        preferred_max_half_px,
    )
    candidates = np.full((len(axes), 6), -1.0)
    candidates[:, :4] = axes
    chosen, nearest = -1, np.inf
    if len(axes):
        d_down = sobel(patch, 0)
        w = patch.shape[1]
        for i in range(len(axes)):
            centre = axes[i, AXIS] / 2 + 0.5  # pixel c spans the pixel-edge columns c .. c + 1
            col0 = max(0, int(np.round(centre - axes[i, HALF_PX])))
            col1 = min(w, int(np.round(centre + axes[i, HALF_PX])))
            bottom, top = box_rows(
                d_down,
                col0,
                col1,
                edge_threshold,
                bottom_edge_fraction,
                top_edge_fraction,
                min_height_ratio,
                highest_bottom,
            )
            candidates[i, BOTTOM], candidates[i, TOP] = bottom, top
            if bottom >= 0 and abs(centre - centre_col_px) < nearest:
                chosen, nearest = i, abs(centre - centre_col_px)
    return edges, chi, candidates, chosen
