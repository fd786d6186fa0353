"""Stage images of one engine frame, shown beside the camera: pure functions, RGB out.

Each panel function takes parts of a `core.engine.FrameResult` and returns one RGB picture
with a caption strip burned in below (`app.draw.add_caption`); a panel with nothing to show
returns `empty_panel` with the reason as text. Tiles of a contact sheet all have one size
(`tile_hw_px`, caption strip excluded); a picture is scaled into its tile by a whole factor
(pixels stay square and sharp) or shrunk when it does not fit, and centred on
`BACKGROUND_COLOUR`.

Images: grey (H, W) uint8; RGB (H, W, 3) uint8, indexed [row, col]. Bird's-eye images are
`core.camera.BirdEyeGrid` images: row 0 is the farthest x, column 0 the leftmost y, so far
is up and left is left as on a map.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import cv2
import numpy as np
import numpy.typing as npt

from app.draw import (
    FONT,
    FONT_SCALE,
    STRIP_HEIGHT_PX,
    Rgb,
    RgbImage,
    add_caption,
    filled,
    grey_to_rgb,
    require_rgb_image,
)
from app.overlays import (
    GUARD_RAIL_LINE_COLOUR,
    OVERLAP_COLOUR,
    PEDESTRIAN_COLOUR,
    PEDESTRIAN_REJECTED_COLOUR,
    SHORT_LINE_COLOUR,
)
from core.guardrail import GuardRailCheck
from core.motion_stereo import MotionStereoResult, grid_for
from core.params import MotionStereoParams
from core.pedestrian import PedestrianResult
from core.search_area import SearchArea
from core.vehicle import TargetResult

GreyImage = npt.NDArray[np.uint8]

BACKGROUND_COLOUR: Rgb = (24, 24, 24)
EMPTY_TEXT_COLOUR: Rgb = (160, 160, 160)
SEPARATOR_COLOUR: Rgb = (90, 90, 90)
CHOSEN_AXIS_COLOUR: Rgb = (255, 255, 255)  # white: the chosen axis and width
CANDIDATE_AXIS_COLOUR: Rgb = (255, 60, 60)  # red: other candidate axes
PROFILE_COLOUR: Rgb = (120, 180, 255)  # light blue: the symmetry profile
PROFILE_FILL_COLOUR: Rgb = (40, 60, 100)
THRESHOLD_COLOUR: Rgb = (255, 220, 0)  # yellow: a threshold
HOLE_COLOUR: Rgb = (255, 40, 40)  # red: holes of a followed line
START_COLOUR: Rgb = (0, 220, 0)  # green: where a followed line starts
EDGE_GREY = 110  # grey level of edge pixels under a followed line

SEPARATOR_PX = 2
EMPTY_PANEL_HW_PX = (300, 300)
SYMMETRY_TILE_HW_PX = (208, 272)
MATRIX_ROW_PX = 2  # picture rows per half-width of a symmetry matrix
GUARD_RAIL_TILE_HW_PX = (112, 352)
OFF_LINE_CAPTION = "not on a rail line"  # a label `core.rail_lines` took back
SHEET_COLUMNS = 3
PLOT_HEIGHT_PX = 160
BAND_ROW_PX = 6
# Display only: the radar and vision give a vehicle's width, not its length.
VEHICLE_FOOTPRINT_LENGTH_M = 4.5


# --- layout ---------------------------------------------------------------------------------


def _require_size(name: str, size_hw_px: tuple[int, int]) -> None:
    if len(size_hw_px) != 2 or min(size_hw_px) < 1:
        raise ValueError(f"{name}: expected (height, width) >= 1 pixel, got {size_hw_px!r}")


def empty_panel(text: str, size_hw_px: tuple[int, int] = EMPTY_PANEL_HW_PX) -> RgbImage:
    """(height, width, 3) `BACKGROUND_COLOUR` picture with `text` centred in
    `EMPTY_TEXT_COLOUR`: what a panel shows when it has nothing to show."""
    _require_size("size_hw_px", size_hw_px)
    h, w = size_hw_px
    out = filled(h, w, BACKGROUND_COLOUR)
    (text_w, text_h), _ = cv2.getTextSize(text, FONT, FONT_SCALE, 1)
    org = (max((w - text_w) // 2, 0), (h + text_h) // 2)
    cv2.putText(out, text, org, FONT, FONT_SCALE, EMPTY_TEXT_COLOUR, 1, cv2.LINE_AA)
    return out


def whole_scale(image_hw_px: tuple[int, int], tile_hw_px: tuple[int, int]) -> int:
    """The largest whole factor (at least 1) by which an image fits a tile."""
    return max(1, min(tile_hw_px[0] // image_hw_px[0], tile_hw_px[1] // image_hw_px[1]))


def fit_tile(rgb: RgbImage, tile_hw_px: tuple[int, int]) -> RgbImage:
    """`rgb` centred on a (tile_h, tile_w, 3) `BACKGROUND_COLOUR` tile: enlarged by the
    largest whole factor that fits (nearest neighbour), or shrunk to fit (area averaging)
    when it is larger than the tile, aspect kept."""
    require_rgb_image("rgb", rgb)
    _require_size("tile_hw_px", tile_hw_px)
    th, tw = tile_hw_px
    h, w = rgb.shape[:2]
    if h > th or w > tw:
        f = min(th / h, tw / w)
        size = (max(1, math.floor(w * f)), max(1, math.floor(h * f)))
        img = np.asarray(cv2.resize(rgb, size, interpolation=cv2.INTER_AREA), dtype=np.uint8)
    else:
        s = whole_scale((h, w), tile_hw_px)
        img = rgb if s == 1 else np.repeat(np.repeat(rgb, s, axis=0), s, axis=1)
    out = filled(th, tw, BACKGROUND_COLOUR)
    r0, c0 = (th - img.shape[0]) // 2, (tw - img.shape[1]) // 2
    out[r0 : r0 + img.shape[0], c0 : c0 + img.shape[1]] = img
    return out


def contact_sheet(tiles: Sequence[RgbImage], columns: int = SHEET_COLUMNS) -> RgbImage:
    """Tiles of one size in rows of `columns`, `SEPARATOR_PX` apart, left to right then top
    to bottom; the last row is padded with `BACKGROUND_COLOUR`.

    tiles: at least one (h, w, 3) uint8, all of one shape.
    """
    if columns < 1:
        raise ValueError(f"columns: expected >= 1, got {columns}")
    if not tiles:
        raise ValueError("tiles: expected at least one tile, got none")
    for k, tile in enumerate(tiles):
        require_rgb_image(f"tiles[{k}]", tile)
        if tile.shape != tiles[0].shape:
            raise ValueError(
                f"tiles[{k}]: expected the shape of tiles[0] {tiles[0].shape}, got {tile.shape}"
            )
    h, w = tiles[0].shape[:2]
    cols = min(columns, len(tiles))
    rows = math.ceil(len(tiles) / cols)
    out = filled(
        rows * h + (rows - 1) * SEPARATOR_PX,
        cols * w + (cols - 1) * SEPARATOR_PX,
        BACKGROUND_COLOUR,
    )
    for k, tile in enumerate(tiles):
        r, c = divmod(k, cols)
        top, left = r * (h + SEPARATOR_PX), c * (w + SEPARATOR_PX)
        out[top : top + h, left : left + w] = tile
    return out


def _captioned_tile(rgb: RgbImage, caption: str, tile_hw_px: tuple[int, int]) -> RgbImage:
    return add_caption(fit_tile(rgb, tile_hw_px), caption)


# --- motion stereo (paper 000 II-B, fig. 4) -----------------------------------------------


def motion_stereo_panel(
    ms: MotionStereoResult, tile_hw_px: tuple[int, int] | None = None
) -> RgbImage:
    """A, the warped background B, C = |A - B| and D side by side, each a captioned tile
    (tile_h + STRIP_HEIGHT_PX, tile_w) (default: the bird's-eye image's own size, so its
    cells stay sharp), and D reprojected into the image below them, as wide as that row;
    a caption naming the mode at the bottom.

    The bird's-eye images keep the grid's orientation (row 0 the farthest: far is up); the
    grey levels are the stage's own (C is not stretched).
    Shape: (tile_h + mask_h + 3 STRIP_HEIGHT_PX + SEPARATOR_PX, 4 tile_w + 3 SEPARATOR_PX, 3),
    mask_h the reprojected mask's height scaled to that width.
    """
    tile_hw_px = tile_hw_px or ms.bird_eye.shape[:2]
    _require_size("tile_hw_px", tile_hw_px)
    images = (
        (ms.bird_eye, "A bird's eye"),
        (ms.background, "B moved"),
        (ms.difference, "C = |A - B|"),
        (ms.obstacles, "D = m > xi"),
    )
    tiles = [_captioned_tile(grey_to_rgb(img), text, tile_hw_px) for img, text in images]
    row = contact_sheet(tiles, len(tiles))
    width = row.shape[1]
    mask_h, mask_w = ms.image_mask.shape[:2]
    mask_tile_hw = (max(1, round(mask_h * width / mask_w)), width)
    mask = _captioned_tile(grey_to_rgb(ms.image_mask), "D in the image", mask_tile_hw)
    gap = filled(SEPARATOR_PX, width, BACKGROUND_COLOUR)
    return add_caption(np.vstack([row, gap, mask]), f"motion stereo: {ms.mode}")


# --- symmetry matrices (paper 001, fig. 3) --------------------------------------------------


def chi_to_rgb(chi: npt.NDArray[np.float32], threshold: float) -> RgbImage:
    """(K, A) chi -> (K, A, 3) viridis picture, scaled so the larger of the threshold and the
    matrix's maximum is the brightest (values at half that are mid-colour)."""
    top = max(float(threshold), float(chi.max(initial=0.0)), 1e-9)
    levels = np.round(np.clip(chi / top, 0.0, 1.0) * 255).astype(np.uint8)
    bgr = cv2.applyColorMap(levels, cv2.COLORMAP_VIRIDIS)
    return np.asarray(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), dtype=np.uint8)


def symmetry_tile(
    target: TargetResult, tile_hw_px: tuple[int, int] = SYMMETRY_TILE_HW_PX
) -> RgbImage:
    """One searched radar target: its resampled area on top, its symmetry matrix below
    (row k: half-width k + 1, half-width 1 at the top, `MATRIX_ROW_PX` rows each; column a:
    axis a / 2, under the
    area's columns), the candidate axes as red ticks and the chosen one as a white line
    through both with its half-width circled and its borders marked on the area; captioned
    with the target's index, distance and verdict.

    target: a `TargetResult` with an area and a matrix (ValueError otherwise).
    Shape: (tile_h + STRIP_HEIGHT_PX, tile_w, 3).
    """
    area = target.area
    if area is None or target.symmetry.size == 0:
        raise ValueError(
            f"target: expected a searched target with a symmetry matrix, got verdict "
            f"{target.verdict!r} of target {target.target_index}"
        )
    h, w = area.patch.shape
    k_rows, n_axes = target.symmetry.shape
    matrix = np.zeros((k_rows * MATRIX_ROW_PX, 2 * w, 3), dtype=np.uint8)
    chi_rgb = chi_to_rgb(target.symmetry, target.threshold)
    matrix[:, :n_axes] = np.repeat(chi_rgb, MATRIX_ROW_PX, axis=0)
    patch = np.repeat(grey_to_rgb(area.patch), 2, axis=1)
    sep = filled(SEPARATOR_PX, 2 * w, SEPARATOR_COLOUR)
    stack = np.concatenate([patch, sep, matrix])
    s = whole_scale(stack.shape[:2], tile_hw_px)
    out = np.repeat(np.repeat(stack, s, axis=0), s, axis=1)
    matrix_top = (h + SEPARATOR_PX) * s

    def x_of_axis(a: float) -> int:
        return round((a + 0.5) * s)  # matrix column a, at the scale

    for k, c in enumerate(target.candidates):
        x = x_of_axis(2 * c.axis_px)
        y = matrix_top + round((c.half_width_row - 0.5) * MATRIX_ROW_PX * s)
        if k == target.chosen:
            continue
        cv2.line(out, (x, matrix_top - 3 * s), (x, matrix_top + 3 * s), CANDIDATE_AXIS_COLOUR, 1)
        cv2.circle(out, (x, y), 2 * s, CANDIDATE_AXIS_COLOUR, 1)
    if target.chosen is not None:
        c = target.candidates[target.chosen]
        x = x_of_axis(2 * c.axis_px)
        y = matrix_top + round((c.half_width_row - 0.5) * MATRIX_ROW_PX * s)
        cv2.line(out, (x, 0), (x, out.shape[0] - 1), CHOSEN_AXIS_COLOUR, 1)
        cv2.circle(out, (x, y), 3 * s, CHOSEN_AXIS_COLOUR, 1)
        for edge in (c.axis_px + 0.5 - c.half_width_px, c.axis_px + 0.5 + c.half_width_px):
            xe = round(2 * edge * s)
            cv2.line(out, (xe, 0), (xe, h * s - 1), CHOSEN_AXIS_COLOUR, 1)
    caption = f"#{target.target_index} {target.target.x_m:.1f} m {target.verdict}"
    if target.taller:
        caption += ", taller area"
    return _captioned_tile(out, caption, tile_hw_px)


def symmetry_panel(
    targets: Sequence[TargetResult],
    tile_hw_px: tuple[int, int] = SYMMETRY_TILE_HW_PX,
    columns: int = SHEET_COLUMNS,
) -> RgbImage:
    """`symmetry_tile` of every searched radar target (those with a matrix), nearest first,
    as a contact sheet of `columns`; `empty_panel("no radar target searched")` of one
    tile's size (caption strip included) when there is none.

    targets: `VehicleResult.targets`.
    """
    _require_size("tile_hw_px", tile_hw_px)
    searched = sorted(
        (t for t in targets if t.area is not None and t.symmetry.size > 0),
        key=lambda t: t.target.x_m,
    )
    if not searched:
        h, w = tile_hw_px
        return empty_panel("no radar target searched", (h + STRIP_HEIGHT_PX, w))
    return contact_sheet([symmetry_tile(t, tile_hw_px) for t in searched], columns)


# --- pedestrian symmetry (paper 000 II-D) ---------------------------------------------------


def _score_row(score: float, plot_h: int) -> int:
    return round((plot_h - 1) * (1.0 - min(max(score, 0.0), 1.0)))


def pedestrian_symmetry_panel(
    pedestrian: PedestrianResult,
    threshold: float | None = None,
    plot_height_px: int = PLOT_HEIGHT_PX,
    band_row_px: int = BAND_ROW_PX,
) -> RgbImage:
    """The symmetry score along the strip's columns: on top its maximum over the bands
    (0 at the bottom, 1 at the top; `threshold` as a yellow line when given), below one row
    of `band_row_px` per band (the farthest at the top, viridis 0..1); each candidate's axis
    as a vertical line, bright green kept and dark green rejected. Columns are the image's.

    pedestrian: `PedestrianResult`; threshold: `PedestrianParams.symmetry_threshold`.
    Shape: (plot_height_px + SEPARATOR_PX + B band_row_px + STRIP_HEIGHT_PX, W, 3);
    `empty_panel("no pedestrian band in the image")` (plot_height_px + STRIP_HEIGHT_PX, 640)
    when there is no band.
    """
    if plot_height_px < 2 or band_row_px < 1:
        raise ValueError(
            f"plot_height_px, band_row_px: expected >= 2 and >= 1, got {plot_height_px}, "
            f"{band_row_px}"
        )
    score = pedestrian.symmetry
    if score.ndim != 2 or score.shape[0] == 0 or score.shape[1] == 0:
        return empty_panel(
            "no pedestrian band in the image", (plot_height_px + STRIP_HEIGHT_PX, 640)
        )
    n_bands, width = score.shape
    plot = filled(plot_height_px, width, BACKGROUND_COLOUR)
    profile = score.max(axis=0)
    ys = np.array([_score_row(float(p), plot_height_px) for p in profile], dtype=np.int32)
    for col in range(width):
        plot[ys[col] :, col] = PROFILE_FILL_COLOUR
    pts = np.stack([np.arange(width, dtype=np.int32), ys], axis=1).reshape(-1, 1, 2)
    cv2.polylines(plot, [pts], False, PROFILE_COLOUR, 1)
    if threshold is not None:
        y = _score_row(threshold, plot_height_px)
        cv2.line(plot, (0, y), (width - 1, y), THRESHOLD_COLOUR, 1)
    for text, row in (("score 1", 12), ("0", plot_height_px - 4)):
        cv2.putText(plot, text, (width - 60, row), FONT, 0.4, EMPTY_TEXT_COLOUR, 1, cv2.LINE_AA)
    levels = np.round(np.clip(score[::-1], 0.0, 1.0) * 255).astype(np.uint8)
    bands = cv2.cvtColor(cv2.applyColorMap(levels, cv2.COLORMAP_VIRIDIS), cv2.COLOR_BGR2RGB)
    bands = np.repeat(np.asarray(bands, dtype=np.uint8), band_row_px, axis=0)
    sep = filled(SEPARATOR_PX, width, SEPARATOR_COLOUR)
    out = np.concatenate([plot, sep, bands])
    bands_top = plot_height_px + SEPARATOR_PX
    ordered = sorted(pedestrian.candidates, key=lambda c: c.verdict == "pedestrian")
    for c in ordered:
        kept = c.verdict == "pedestrian"
        colour = PEDESTRIAN_COLOUR if kept else PEDESTRIAN_REJECTED_COLOUR
        x = round(c.axis_px)
        cv2.line(out, (x, 0), (x, plot_height_px - 1), colour, 1)
        row = bands_top + (n_bands - 1 - c.band) * band_row_px
        cv2.rectangle(out, (x - 1, row), (x + 1, row + band_row_px - 1), colour, cv2.FILLED)
    kept_count = len(pedestrian.kept)
    caption = (
        f"pedestrian symmetry: max over {n_bands} bands; "
        f"{kept_count} kept, {len(pedestrian.candidates) - kept_count} rejected"
    )
    return add_caption(out, caption)


# --- guard rails (paper 002) ----------------------------------------------------------------


def _hatched(rgb: RgbImage, colour: Rgb) -> RgbImage:
    out = rgb.copy()
    h, w = out.shape[:2]
    for k in range(-h, w, 8):
        cv2.line(out, (k, h - 1), (k + h - 1, 0), colour, 1)
    return out


def _paint_cells(out: RgbImage, rows_cols: npt.NDArray[np.int32], s: int, colour: Rgb) -> None:
    """In place: the s x s block of each (row, col) of an image enlarged s times."""
    for r, c in rows_cols.tolist():
        out[r * s : (r + 1) * s, c * s : (c + 1) * s] = colour


def guard_rail_tile(
    check: GuardRailCheck, area: SearchArea, tile_hw_px: tuple[int, int] = GUARD_RAIL_TILE_HW_PX
) -> RgbImage:
    """One checked slow target: its area's patch on the left, the edge image after morphology
    on the right (edges grey) with the followed line (magenta when a rail, dark magenta when
    too short or taken back), its start (green) and holes (red); an area labelled by
    overlap shows its patch hatched. Captioned with the target, its distance, side,
    coverage and verdict ("along the rail line" for one labelled by `core.rail_lines` after
    its search, "not on a rail line" for one whose label `core.rail_lines` took back).

    Shape: (tile_h + STRIP_HEIGHT_PX, tile_w, 3).
    """
    patch = grey_to_rgb(area.patch)
    if check.overlapped_by is not None:
        caption = (
            f"#{check.target_index} {area.x_m:.1f} m {check.side}: overlap of "
            f"#{check.overlapped_by}"
        )
        if not check.guard_rail:
            return _captioned_tile(patch, f"{caption}, {OFF_LINE_CAPTION}", tile_hw_px)
        return _captioned_tile(_hatched(patch, OVERLAP_COLOUR), caption, tile_hw_px)
    edges = check.edges
    h, w = edges.shape
    sep = filled(h, SEPARATOR_PX, SEPARATOR_COLOUR)
    edge_rgb = np.where(edges[:, :, None] > 0, np.uint8(EDGE_GREY), np.uint8(0))
    edge_rgb = np.repeat(edge_rgb, 3, axis=2).astype(np.uint8)
    both = np.concatenate([patch, sep, edge_rgb], axis=1)
    s = whole_scale(both.shape[:2], tile_hw_px)
    out = np.repeat(np.repeat(both, s, axis=0), s, axis=1)
    right = out[:, (w + SEPARATOR_PX) * s :]
    colour = GUARD_RAIL_LINE_COLOUR if check.verdict == "guard_rail" else SHORT_LINE_COLOUR
    _paint_cells(right, check.line_px, s, colour)
    _paint_cells(right, check.holes_px, s, HOLE_COLOUR)
    if check.start_px is not None:
        _paint_cells(right, check.line_px[:1], s, START_COLOUR)
    verdict = {"line": "along the rail line", "off_line": OFF_LINE_CAPTION}.get(
        check.verdict, check.verdict
    )
    caption = f"#{check.target_index} {area.x_m:.1f} m {check.side} {check.coverage:.0%} {verdict}"
    return _captioned_tile(out, caption, tile_hw_px)


def guard_rail_panel(
    checks: Sequence[GuardRailCheck],
    areas: Sequence[SearchArea],
    tile_hw_px: tuple[int, int] = GUARD_RAIL_TILE_HW_PX,
    columns: int = SHEET_COLUMNS,
) -> RgbImage:
    """`guard_rail_tile` of every check (every slow target, nearest first) as a contact
    sheet of `columns`; `empty_panel("no slow radar target")` of one tile's size (caption
    strip included) when there is none. A check whose area is not in `areas` is skipped.

    checks: `GuardRailResult.checks`; areas: the frame's search areas.
    """
    _require_size("tile_hw_px", tile_hw_px)
    by_target = {a.target_index: a for a in areas}
    tiles = [
        guard_rail_tile(c, by_target[c.target_index], tile_hw_px)
        for c in checks
        if c.target_index in by_target
    ]
    if not tiles:
        h, w = tile_hw_px
        return empty_panel("no slow radar target", (h + STRIP_HEIGHT_PX, w))
    return contact_sheet(tiles, columns)


# --- bird's-eye texture (3D ground plane) ---------------------------------------------------


def bird_eye_extent_m(params: MotionStereoParams) -> tuple[float, float, float, float]:
    """(x_min_m, x_max_m, y_min_m, y_max_m): the road rectangle the bird's-eye grid and its
    texture cover, vehicle frame (x forward, y left), cell edges."""
    grid = grid_for(params)
    return grid.x_min_m, grid.x_max_m, grid.y_min_m, grid.y_max_m
