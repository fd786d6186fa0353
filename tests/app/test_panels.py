"""Stage panels: tiles of the documented size and count, marks where the data says, the
documented empty-state picture when there is nothing, bad inputs refused by name."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from engine_frames import engine_result

from app import draw, overlays, panels
from core.guardrail import GuardRailCheck
from core.io.frame import RadarTarget
from core.params import MotionStereoParams
from core.pedestrian import Bands, PedestrianCandidate, PedestrianResult
from core.search_area import SearchArea
from core.vehicle import Candidate, TargetResult

STRIP = draw.STRIP_HEIGHT_PX
SEP = panels.SEPARATOR_PX


def is_colour(image: np.ndarray, colour: tuple[int, int, int]) -> np.ndarray:
    return np.all(image == np.array(colour, np.uint8), axis=-1)


def radar(x_m: float, y_m: float) -> RadarTarget:
    return RadarTarget(float(np.hypot(x_m, y_m)), float(np.arctan2(y_m, x_m)), 0.0, 1.0, x_m, y_m)


def area(patch_hw: tuple[int, int], index: int = 0, x_m: float = 20.0) -> SearchArea:
    h, w = patch_hw
    return SearchArea(
        index,
        radar(x_m, 1.0),
        (100.0 + w / 2, 200.0 + h - 5),
        (99.5, 199.5, 99.5 + w, 199.5 + h),
        (100, 200, 100 + w, 200 + h),
        2.0,
        0.0,
        np.full((h, w), 80, np.uint8),
        10.0,
    )


def searched_target(index: int = 0, x_m: float = 20.0) -> TargetResult:
    """A 16-column area whose one candidate, chosen, has its axis in the middle (between
    columns 7 and 8: axis 7.5, matrix column 15 of 31) and borders 4 columns either side."""
    chi = np.zeros((8, 31), np.float32)
    chi[3, 15] = 4.0
    candidate = Candidate(7.5, 4, 4.0, 4.0, 7, None, (103.5, 190.0, 111.5, 207.0))
    return TargetResult(
        index,
        radar(x_m, 1.0),
        area((8, 16), index, x_m),
        np.zeros((8, 16), np.int8),
        chi,
        2.0,
        (candidate,),
        0,
        "vehicle",
        0,
    )


def rail_check(index: int, verdict: str, line_px=((4, 0), (4, 1), (3, 2))) -> GuardRailCheck:
    edges = np.zeros((8, 16), np.uint8)
    for r, c in line_px:
        edges[r, c] = 255
    return GuardRailCheck(
        index,
        "left",
        1.0,
        edges,
        np.array(line_px, np.int32).reshape(-1, 2),
        np.array([(3, 3)], np.int32),
        0.6,
        verdict,
        None,
    )


# --- layout ---------------------------------------------------------------------------------


def test_empty_panel_is_the_background_with_its_text() -> None:
    out = panels.empty_panel("nothing here", (50, 200))
    assert out.shape == (50, 200, 3) and out.dtype == np.uint8
    assert tuple(out[0, 0]) == panels.BACKGROUND_COLOUR
    assert is_colour(out, panels.EMPTY_TEXT_COLOUR).any()


def test_small_picture_is_enlarged_by_a_whole_factor_and_centred() -> None:
    rgb = np.zeros((10, 20, 3), np.uint8)
    rgb[0, 0] = (255, 0, 0)
    out = panels.fit_tile(rgb, (45, 50))  # factor 2: 20 x 40 centred at row 12, column 5
    assert out.shape == (45, 50, 3)
    assert (out[12:14, 5:7] == (255, 0, 0)).all()
    assert not out[12:32, 7:45].any() and not out[14:32, 5:7].any()
    assert tuple(out[11, 5]) == panels.BACKGROUND_COLOUR
    assert tuple(out[32, 5]) == panels.BACKGROUND_COLOUR


def test_large_picture_is_shrunk_to_fit() -> None:
    out = panels.fit_tile(np.full((400, 100, 3), 200, np.uint8), (100, 100))
    assert out.shape == (100, 100, 3)
    assert (out[:, 38:62] == 200).all()  # 100 x 25, centred
    assert tuple(out[50, 10]) == panels.BACKGROUND_COLOUR


def test_contact_sheet_places_tiles_in_rows() -> None:
    tiles = [np.full((10, 20, 3), k, np.uint8) for k in range(1, 6)]
    out = panels.contact_sheet(tiles, columns=3)
    assert out.shape == (2 * 10 + SEP, 3 * 20 + 2 * SEP, 3)
    for k in range(5):
        r, c = divmod(k, 3)
        top, left = r * (10 + SEP), c * (20 + SEP)
        assert (out[top : top + 10, left : left + 20] == k + 1).all()
    assert tuple(out[-1, -1]) == panels.BACKGROUND_COLOUR  # the last row is padded


def test_contact_sheet_refuses_bad_tiles() -> None:
    with pytest.raises(ValueError, match="tiles: expected at least one tile"):
        panels.contact_sheet([])
    with pytest.raises(ValueError, match=r"tiles\[1\]: expected the shape of tiles\[0\]"):
        panels.contact_sheet([np.zeros((4, 4, 3), np.uint8), np.zeros((4, 5, 3), np.uint8)])
    with pytest.raises(ValueError, match=r"tiles\[0\]: expected an \(H, W, 3\) uint8"):
        panels.contact_sheet([np.zeros((4, 4), np.uint8)])
    with pytest.raises(ValueError, match="columns: expected >= 1"):
        panels.contact_sheet([np.zeros((4, 4, 3), np.uint8)], columns=0)
    with pytest.raises(ValueError, match="tile_hw_px: expected"):
        panels.fit_tile(np.zeros((4, 4, 3), np.uint8), (0, 10))


# --- motion stereo --------------------------------------------------------------------------


def test_motion_stereo_panel_is_a_row_of_four_bird_eye_tiles_over_the_image_mask() -> None:
    ms = engine_result().motion_stereo
    out = panels.motion_stereo_panel(ms, (120, 100))
    width = 4 * 100 + 3 * SEP
    mask_h, mask_w = ms.image_mask.shape
    mask_rows = round(mask_h * width / mask_w)
    assert out.shape == (120 + STRIP + SEP + mask_rows + STRIP + STRIP, width, 3)
    rows, cols = ms.bird_eye.shape
    default = panels.motion_stereo_panel(ms)  # tiles of the bird's-eye image's own size
    assert default.shape[1] == 4 * cols + 3 * SEP
    np.testing.assert_array_equal(default[:rows, :cols], draw.grey_to_rgb(ms.bird_eye))


def test_bird_eye_tiles_show_far_up() -> None:
    ms = engine_result().motion_stereo
    rows, cols = ms.grid.shape
    far = np.zeros((rows, cols), np.uint8)
    far[: rows // 2] = 255  # x beyond the grid's middle distance
    ms = dataclasses.replace(ms, bird_eye=far)
    tile_h, tile_w = rows, cols  # the grid fits at factor 1
    out = panels.motion_stereo_panel(ms, (tile_h, tile_w))
    a_tile = out[:tile_h, :tile_w]
    assert (a_tile[: tile_h // 2] == 255).all()
    assert not a_tile[tile_h // 2 :].any()


# --- symmetry matrices ----------------------------------------------------------------------


def test_symmetry_tile_marks_the_chosen_axis_and_borders() -> None:
    tile_hw = (208, 272)
    out = panels.symmetry_tile(searched_target(), tile_hw)
    assert out.shape == (tile_hw[0] + STRIP, tile_hw[1], 3)
    # the picture (area 16 wide shown 32 wide, whole factor 8 into 272 columns) spans columns
    # 8 .. 263: the axis in the area's middle is the picture's middle column, the borders 4 of
    # 16 columns either side are at a quarter and three quarters of it
    white = is_colour(out[: tile_hw[0]], panels.CHOSEN_AXIS_COLOUR)
    columns = np.flatnonzero(white.sum(axis=0) > 40)
    assert any(abs(c - 136) <= 4 for c in columns)
    assert any(abs(c - (8 + 64)) <= 1 for c in columns)
    assert any(abs(c - (8 + 192)) <= 1 for c in columns)


def test_symmetry_panel_has_one_tile_per_searched_target() -> None:
    targets = engine_result("highway", 100).vehicle.targets
    searched = [t for t in targets if t.symmetry.size > 0]
    assert 3 < len(searched) < len(targets)  # this highway frame has guard-rail targets
    h, w = panels.SYMMETRY_TILE_HW_PX
    out = panels.symmetry_panel(targets, columns=3)
    rows = -(-len(searched) // 3)
    assert out.shape == (rows * (h + STRIP) + (rows - 1) * SEP, 3 * w + 2 * SEP, 3)


def test_symmetry_panel_without_searched_targets_is_the_empty_panel() -> None:
    h, w = panels.SYMMETRY_TILE_HW_PX
    expected = panels.empty_panel("no radar target searched", (h + STRIP, w))
    np.testing.assert_array_equal(panels.symmetry_panel([]), expected)
    unsearched = [t for t in engine_result("highway", 100).vehicle.targets if t.symmetry.size == 0]
    assert unsearched  # the guard-rail targets
    np.testing.assert_array_equal(panels.symmetry_panel(unsearched), expected)


def test_symmetry_tile_refuses_a_target_without_a_matrix() -> None:
    target = dataclasses.replace(searched_target(), symmetry=np.zeros((8, 0), np.float32))
    with pytest.raises(ValueError, match="target: expected a searched target"):
        panels.symmetry_tile(target)


# --- pedestrian symmetry --------------------------------------------------------------------


def candidate(axis_px: float, band: int, verdict: str) -> PedestrianCandidate:
    box = (axis_px - 4, 100.0, axis_px + 5, 140.0)
    return PedestrianCandidate(
        band,
        axis_px,
        4.0,
        1.0,
        1.0,
        1.0,
        0.1,
        box,
        box,
        False,
        10.0,
        0.0,
        1.7,
        0.6,
        0.5,
        verdict,  # type: ignore[arg-type]
    )


def pedestrian_result(width: int = 100) -> PedestrianResult:
    score = np.zeros((2, width), np.float32)
    score[0, 40] = 1.0
    score[1, 70] = 0.5
    one = np.ones(2)
    bands = Bands(one * 10, np.array([300, 250]), np.array([60, 30]), one * 30, np.array([1, 1]))
    return PedestrianResult(
        (100, 320),
        bands,
        score,
        score.copy(),
        (candidate(40.0, 0, "pedestrian"), candidate(70.0, 1, "motion_stereo")),
    )


def test_pedestrian_symmetry_plot_puts_profile_threshold_and_axes_in_place() -> None:
    plot_h, band_px = 100, 5
    out = panels.pedestrian_symmetry_panel(pedestrian_result(), 0.5, plot_h, band_px)
    assert out.shape == (plot_h + SEP + 2 * band_px + STRIP, 100, 3)
    assert tuple(out[round((plot_h - 1) * 0.5), 10]) == panels.THRESHOLD_COLOUR
    # the kept candidate's axis in bright green over the plot, the rejected one dark green
    assert is_colour(out[:plot_h, 40], overlays.PEDESTRIAN_COLOUR).sum() == plot_h
    assert is_colour(out[:plot_h, 70], overlays.PEDESTRIAN_REJECTED_COLOUR).sum() == plot_h
    # a score of 0 fills nothing above the bottom row; the band rows hold the candidates:
    # band 0 (nearest) at the bottom, band 1 at the top
    assert tuple(out[plot_h // 4, 20]) == panels.BACKGROUND_COLOUR
    bands_top = plot_h + SEP
    assert tuple(out[bands_top + band_px, 40]) == overlays.PEDESTRIAN_COLOUR
    assert tuple(out[bands_top, 70]) == overlays.PEDESTRIAN_REJECTED_COLOUR


def test_pedestrian_symmetry_without_bands_is_the_empty_panel() -> None:
    result = dataclasses.replace(
        pedestrian_result(), symmetry=np.zeros((0, 640), np.float32), candidates=()
    )
    expected = panels.empty_panel(
        "no pedestrian band in the image", (panels.PLOT_HEIGHT_PX + STRIP, 640)
    )
    np.testing.assert_array_equal(panels.pedestrian_symmetry_panel(result), expected)


def test_pedestrian_symmetry_refuses_a_flat_plot() -> None:
    with pytest.raises(ValueError, match="plot_height_px"):
        panels.pedestrian_symmetry_panel(pedestrian_result(), plot_height_px=1)


# --- guard rails ----------------------------------------------------------------------------


def test_guard_rail_tile_paints_the_followed_line_on_the_edge_image() -> None:
    tile_hw = (40, 100)
    out = panels.guard_rail_tile(rail_check(0, "guard_rail"), area((8, 16)), tile_hw)
    assert out.shape == (tile_hw[0] + STRIP, tile_hw[1], 3)
    # patch, separator and edges: 8 x 34 at factor 2 (16 x 68), centred at row 12, col 16;
    # the edge image starts 18 picture columns = 36 tile columns in
    left, top = 16 + (16 + SEP) * 2, 12
    assert tuple(out[top + 4 * 2, left]) == panels.START_COLOUR  # (4, 0), the start
    assert tuple(out[top + 4 * 2, left + 1 * 2]) == overlays.GUARD_RAIL_LINE_COLOUR
    assert tuple(out[top + 3 * 2, left + 2 * 2 + 1]) == overlays.GUARD_RAIL_LINE_COLOUR
    assert tuple(out[top + 3 * 2, left + 3 * 2]) == panels.HOLE_COLOUR


def test_guard_rail_panel_has_one_tile_per_check_and_an_empty_state() -> None:
    h, w = panels.GUARD_RAIL_TILE_HW_PX
    checks = [rail_check(0, "guard_rail"), rail_check(1, "not_guard_rail")]
    overlap = dataclasses.replace(
        rail_check(2, "overlap", ()), edges=np.zeros((0, 0), np.uint8), overlapped_by=0
    )
    areas = [area((8, 16), k) for k in range(3)]
    out = panels.guard_rail_panel([*checks, overlap], areas, columns=2)
    assert out.shape == (2 * (h + STRIP) + SEP, 2 * w + SEP, 3)
    assert is_colour(out[h + STRIP + SEP :, :w], overlays.OVERLAP_COLOUR).any()
    expected = panels.empty_panel("no slow radar target", (h + STRIP, w))
    np.testing.assert_array_equal(panels.guard_rail_panel([], areas), expected)


def test_a_label_taken_back_is_drawn_as_not_a_rail() -> None:
    tile_hw = (40, 100)
    searched = panels.guard_rail_tile(rail_check(0, "off_line"), area((8, 16)), tile_hw)
    left, top = 16 + (16 + SEP) * 2, 12
    assert tuple(searched[top + 4 * 2, left + 1 * 2]) == overlays.SHORT_LINE_COLOUR
    overlap = dataclasses.replace(
        rail_check(2, "off_line", ()), edges=np.zeros((0, 0), np.uint8), overlapped_by=0
    )
    out = panels.guard_rail_tile(overlap, area((8, 16)), tile_hw)
    assert out.shape == (tile_hw[0] + STRIP, tile_hw[1], 3)
    assert not is_colour(out, overlays.OVERLAP_COLOUR).any()  # not hatched: no longer a rail
    labelled = dataclasses.replace(overlap, verdict="overlap")
    assert is_colour(
        panels.guard_rail_tile(labelled, area((8, 16)), tile_hw), overlays.OVERLAP_COLOUR
    ).any()


# --- bird's-eye extent ----------------------------------------------------------------------


def test_bird_eye_extent_is_the_grid_of_the_parameters() -> None:
    assert panels.bird_eye_extent_m(MotionStereoParams()) == (4.0, 40.0, -10.0, 10.0)
