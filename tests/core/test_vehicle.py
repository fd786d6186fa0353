"""Search areas and the radar-guided vehicle detector (papers 001, 000 II-C): known answers."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import cv2
import numpy as np
import pytest
from roadscenes import RoadRenderer, camera, straight_road

from core.camera import CameraModel, Extrinsics, Intrinsics
from core.io.frame import RadarTarget
from core.params import ParamsError, VehicleParams
from core.search_area import SearchArea, box_pixels, overlap_fraction, search_areas
from core.symmetry import (
    AXIS,
    HALF_PX,
    box_rows,
    candidate_axes,
    chi_matrix,
    mirrored_pairs,
    signed_vertical_edges,
    sobel,
    symmetry_matrix,
)
from core.synth.scene import Trajectory
from core.synth.scene import Vehicle as SceneVehicle
from core.vehicle import (
    Vehicle,
    body_box,
    border_top,
    detect_vehicles,
    hidden_sides,
    measured_past_hidden_sides,
    merge_boxes,
    truck_top,
    world_extents,
    world_size_ok,
)

PARAMS = VehicleParams()
RADAR_X_M = 3.6  # the synthetic radar's mount, ahead of the rear axle


def flat_camera() -> CameraModel:
    """640x480, f = 800 px, principal point at the centre, 1.2 m high, looking straight."""
    return CameraModel(
        Intrinsics(fx_px=800.0, fy_px=800.0, cx_px=319.5, cy_px=239.5, width_px=640, height_px=480),
        Extrinsics(height_m=1.2),
    )


def target(x_m: float, y_m: float, range_rate_mps: float = 0.0) -> RadarTarget:
    """A radar target at (x_m, y_m) in the vehicle frame seen from the synthetic mount."""
    dx = x_m - RADAR_X_M
    return RadarTarget.from_polar(
        math.hypot(dx, y_m), math.atan2(y_m, dx), range_rate_mps, 0.0, RADAR_X_M, 0.0, 0.0
    )


# --- search areas ----------------------------------------------------------------------------


def test_search_area_is_where_the_formulas_put_it() -> None:
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    t = target(25.0, 1.0)
    (area,) = search_areas(image, cam, (t,), PARAMS)
    # straight camera: u = cx - f y / x, v = cy + f h / x
    f, x = 800.0, 25.0
    width_px = f * 2.5 / x  # 80 px
    height_px = width_px / 2  # W / 2
    v_base = 239.5 + f * 1.2 / x
    bottom = v_base + 0.3 * height_px  # 30 % of the height below the radar point
    expected = (319.5 - f * 2.25 / x, bottom - height_px, 319.5 + f * 0.25 / x, bottom)
    assert area.base_px == pytest.approx((319.5 - f * 1.0 / x, v_base))
    assert area.full_px == pytest.approx(expected)
    assert area.box_px == tuple(math.ceil(b) for b in expected)
    assert not area.cropped
    # 80 px wide: resampled to 64 px, keeping its aspect ratio
    assert area.patch.shape == (round(40 * 0.8), 64)
    assert area.px_per_m == pytest.approx(64 / 2.5)
    assert (area.y_left_m, area.y_right_m) == pytest.approx((2.25, -0.25))


def test_a_search_area_centred_off_its_point_is_that_centre_s_area() -> None:
    """centres_y_m (core.radar_smoothing) moves the area across: the same as a target at that
    lateral position, the target itself kept."""
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    t = target(25.0, 1.0)
    (area,) = search_areas(image, cam, (t,), PARAMS, centres_y_m=(0.4,))
    (there,) = search_areas(image, cam, (target(25.0, 0.4),), PARAMS)
    assert area.target is t
    assert (area.y_left_m, area.y_right_m) == pytest.approx((1.65, -0.85))
    assert area.full_px == pytest.approx(there.full_px)
    assert area.base_px == pytest.approx(there.base_px)
    with pytest.raises(ValueError, match="centres_y_m: expected one per radar target"):
        search_areas(image, cam, (t,), PARAMS, centres_y_m=(0.4, 1.0))


def test_a_target_moving_over_ground_gets_the_wider_area() -> None:
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    ego_mps = 20.0
    bearing = math.atan2(1.0, 25.0 - RADAR_X_M)
    still = target(25.0, 1.0, -ego_mps * math.cos(bearing))  # static: closes at the ego speed
    slow = target(25.0, 1.0, (PARAMS.moving_speed_mps - 0.5 - ego_mps) * math.cos(bearing))
    car = target(25.0, 1.0, (15.0 - ego_mps) * math.cos(bearing))  # 15 m/s over ground
    widths = {
        name: (a.y_left_m - a.y_right_m, a.px_per_m)
        for name, (a,) in (
            ("still", search_areas(image, cam, (still,), PARAMS, ego_mps)),
            ("slow", search_areas(image, cam, (slow,), PARAMS, ego_mps)),
            ("car", search_areas(image, cam, (car,), PARAMS, ego_mps)),
            ("unknown", search_areas(image, cam, (car,), PARAMS)),  # ego speed NaN
        )
    }
    assert widths["still"] == pytest.approx((2.5, 64 / 2.5))
    moving = {
        name: search_areas(image, cam, (t,), PARAMS, ego)[0].moving
        for name, t, ego in (("still", still, ego_mps), ("car", car, ego_mps), ("?", car, math.nan))
    }
    assert moving == {"still": False, "car": True, "?": False}
    assert widths["slow"] == pytest.approx((2.5, 64 / 2.5))
    assert widths["unknown"] == pytest.approx((2.5, 64 / 2.5))
    # 4 m at 25 m is 128 px, resampled to 64
    assert widths["car"] == pytest.approx((PARAMS.moving_search_width_m, 64 / 4.0))
    (area,) = search_areas(image, cam, (car,), PARAMS, ego_mps)
    assert area.full_px[2] - area.full_px[0] == pytest.approx(800.0 * 4.0 / 25.0)
    # as high as the paper's area: the extra width is for the radar's lateral error
    assert area.full_px[3] - area.full_px[1] == pytest.approx(0.5 * 800.0 * 2.5 / 25.0)
    assert area.patch.shape == (round(40 * 0.5), 64)


def test_a_still_target_where_a_tracked_vehicle_is_expected_gets_the_wider_area() -> None:
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    ego_mps = 20.0
    bearing = math.atan2(1.0, 25.0 - RADAR_X_M)
    still = target(25.0, 1.0, -ego_mps * math.cos(bearing))  # a stopped car
    gate = PARAMS.track_gate_m

    def width(tracked_m: list[tuple[float, float, float]], params: VehicleParams = PARAMS) -> float:
        (a,) = search_areas(image, cam, (still,), params, ego_mps, tracked_m)
        return a.y_left_m - a.y_right_m

    assert width([]) == pytest.approx(PARAMS.search_width_m)
    assert width([(25.0 + 0.9 * gate, 1.0, 1.8)]) == pytest.approx(PARAMS.moving_search_width_m)
    assert width([(25.0, 1.0 - 0.9 * gate, 1.8)]) == pytest.approx(PARAMS.moving_search_width_m)
    assert width([(25.0 + 1.1 * gate, 1.0, 1.8), (40.0, -3.0, 1.8)]) == pytest.approx(2.5)
    off = dataclasses.replace(PARAMS, track_gate_m=0.0)
    assert width([(25.0 + 0.9 * gate, 1.0, 1.8)], off) == pytest.approx(2.5)


def test_a_target_where_a_tracked_vehicle_is_expected_is_searched_about_that_vehicle() -> None:
    """centre_on_track: the area is centred on the nearest tracked vehicle's lateral position
    within the gate, whatever the smoothed centre says; off, on the centre given."""
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    t = target(25.0, 1.0)
    gate = PARAMS.track_gate_m
    tracked_m = [(25.0, 1.0 - 0.9 * gate, 1.8), (25.0, 1.0 + 0.95 * gate, 1.8), (40.0, 1.0, 1.8)]

    def centre(params: VehicleParams, tracked: list[tuple[float, float, float]]) -> float:
        (a,) = search_areas(image, cam, (t,), params, 0.0, tracked, centres_y_m=(0.8,))
        return (a.y_left_m + a.y_right_m) / 2

    assert centre(PARAMS, tracked_m) == pytest.approx(1.0 - 0.9 * gate)
    # the area carries that vehicle's width, NaN where none is tracked
    (a,) = search_areas(image, cam, (t,), PARAMS, 0.0, [(25.0, 1.0, 1.7)], centres_y_m=(0.8,))
    assert a.tracked_width_m == 1.7
    (a,) = search_areas(image, cam, (t,), PARAMS, 0.0, [], centres_y_m=(0.8,))
    assert math.isnan(a.tracked_width_m)
    assert centre(PARAMS, tracked_m[2:]) == pytest.approx(0.8)  # none within the gate
    assert centre(dataclasses.replace(PARAMS, centre_on_track=False), tracked_m) == pytest.approx(
        0.8
    )


def test_far_areas_are_not_enlarged_and_border_areas_are_cropped() -> None:
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    far, border = target(50.0, 0.0), target(12.0, 4.6)
    areas = search_areas(image, cam, (far, border), PARAMS)
    assert [a.target_index for a in areas] == [0, 1]
    c0, r0, c1, r1 = areas[0].box_px
    assert c1 - c0 == 40 and areas[0].patch.shape == (r1 - r0, c1 - c0)  # 40 px: kept
    # at 12 m, 4.6 m left: the radar point is at u = 12.8, the area reaches past u = 0
    a = areas[1]
    assert a.full_px[0] < 0 and a.box_px[0] == 0 and a.cropped
    width_px = 800.0 * 2.5 / 12.0
    assert a.patch.shape[1] == round(a.box_px[2] * 64 / width_px)  # same scale as uncropped


def test_a_kept_patch_is_a_copy_of_the_crop_not_a_view_of_the_image() -> None:
    # the compiled searches get one array layout (C-contiguous, writable), resampled or not
    cam = flat_camera()
    image = np.arange(480 * 640, dtype=np.uint32).reshape(480, 640).astype(np.uint8)
    image.flags.writeable = False  # as a drive's frames are
    far, near = search_areas(image, cam, (target(50.0, 0.0), target(25.0, 0.0)), PARAMS)
    c0, r0, c1, r1 = far.box_px
    np.testing.assert_array_equal(far.patch, image[r0:r1, c0:c1])
    for area in (far, near):
        assert area.patch.flags.c_contiguous and area.patch.flags.writeable
        assert not np.shares_memory(area.patch, image)


def test_targets_outside_the_image_get_no_area() -> None:
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    # far to the left, behind the camera, and empty radar
    outside = (target(10.0, 8.0), target(-5.0, 0.0))
    assert search_areas(image, cam, outside, PARAMS) == ()
    assert search_areas(image, cam, (), PARAMS) == ()
    result = detect_vehicles((), outside, cam, PARAMS)
    assert [r.verdict for r in result.targets] == ["outside_image"] * 2
    assert result.vehicles == ()


def test_overlap_fraction_is_the_share_of_the_second_area() -> None:
    def area(box: tuple[int, int, int, int]) -> SearchArea:
        return SearchArea(0, target(20, 0), (0, 0), box, box, 1, -1, np.zeros((2, 2), np.uint8), 1)

    a, b = area((0, 0, 10, 10)), area((5, 0, 25, 10))
    assert overlap_fraction(a, b) == pytest.approx(50 / 200)
    assert overlap_fraction(b, a) == pytest.approx(50 / 100)


# --- symmetry ----------------------------------------------------------------------------


def test_box_pixels_hold_the_edges_of_a_box() -> None:
    assert box_pixels((99.5, 199.5, 180.5, 260.5)) == (100, 200, 180, 260)
    assert box_pixels((100.2, 200.0, 179.9, 259.6)) == (100, 200, 180, 260)
    assert box_pixels((10.5, 20.5, 10.5, 20.5)) == (11, 21, 11, 21)  # empty: one pixel


def test_chi_by_hand_on_a_ten_pixel_row() -> None:
    # columns:              0  1  2   3  4  5  6  7   8  9
    edges = np.array([[0, 1, 0, -1, 0, 1, 0, 0, -1, 0]], dtype=np.int8)
    chi = symmetry_matrix(edges, 4)
    assert chi.shape == (4, 19)  # axes at every column and between every two: a / 2
    # axis 2 (a = 4): half-width 1 pairs columns 1 (+) and 3 (-): s = 1, n = 2 (columns 1..3)
    assert chi[0, 4] == pytest.approx(1 / 2)
    # half-width 2 adds columns 0 and 4, no edges: s = 1, n = 2
    assert chi[1, 4] == pytest.approx(1 / 2)
    # half-width 3 adds column 5 (+) and column -1 (outside): s = 1, n = 3
    assert chi[2, 4] == pytest.approx(1 / 3)
    # axis 4 (a = 8): half-width 1 pairs 3 (-) and 5 (+): s = 1, n = 2; half-width 4 pairs
    # 0 (empty) and 8; n = 4 (columns 1, 3, 5, 8): chi = 1 / 4
    assert chi[0, 8] == pytest.approx(1 / 2)
    assert chi[3, 8] == pytest.approx(1 / 4)
    # axis 4.5 (a = 9), between columns 4 and 5: half-width 4 pairs 1 (+) and 8 (-), the
    # first pair; the window 1..8 holds 4 edges: chi = 1 / 4
    assert chi[:3, 9] == pytest.approx([0, 0, 0])
    assert chi[3, 9] == pytest.approx(1 / 4)
    # same signs never pair: axis 3 (a = 6) pairs 1 (+) and 5 (+) at half-width 2
    assert chi[1, 6] == 0.0
    pairs, n = mirrored_pairs(edges, 4)
    assert pairs[0, 4] == 1 and n[2, 8] == 3  # axis 4, half-width 3: columns 1..7 hold 3


def _box_edges(height: int, width: int, left: int, right: int) -> np.ndarray:
    """Signed edges of a dark box on a bright background filling columns left..right - 1."""
    patch = np.full((height, width), 160, dtype=np.uint8)
    patch[:, left:right] = 60
    return signed_vertical_edges(patch, PARAMS.edge_threshold)


@pytest.mark.parametrize(("left", "right"), [(14, 50), (9, 40), (20, 61)])
def test_symmetric_box_gives_its_axis_and_width(left: int, right: int) -> None:
    edges = _box_edges(32, 64, left, right)
    pairs, n = mirrored_pairs(edges, 32)
    chi = chi_matrix(pairs, n)
    axes = candidate_axes(chi, pairs, 0.35 * 32, 3, 10, 32)
    assert len(axes) == 1
    axis, half_px = axes[0, AXIS] / 2, axes[0, HALF_PX]  # the axis at column a / 2
    assert abs((axis + 0.5) - (left + right) / 2) <= 1.0  # axis within 1 px
    assert abs(2 * half_px - (right - left)) <= 2.0  # width within 2 px


def test_a_tracked_width_is_preferred_where_its_borders_pair() -> None:
    """A vehicle's face (borders 12 px either side of column 32, on its 12 upper rows) before
    something wider pairing on every row (20 px either side: its side and the background):
    the most pairs are the wider ones; a preferred range about the tracked width takes the
    face when chi reaches the threshold there, and never makes an axis qualify."""
    patch = np.full((20, 64), 160, dtype=np.uint8)
    patch[:, 12:52] = 100  # the wider thing, on every row
    patch[:12, 20:44] = 40  # the face
    edges = signed_vertical_edges(patch, PARAMS.edge_threshold)
    pairs, n = mirrored_pairs(edges, 32)
    chi = chi_matrix(pairs, n)
    (wide,) = candidate_axes(chi, pairs, 5.0, 3, 5, 25)
    assert wide[AXIS] == 63 and wide[HALF_PX] == pytest.approx(20, abs=0.5)  # column 32
    (face,) = candidate_axes(chi, pairs, 5.0, 3, 5, 25, 0, 10, 14)
    assert face[AXIS] == 63 and face[HALF_PX] == pytest.approx(12, abs=0.5)
    # chi at the face (6.5) below the threshold: the wide borders stay
    (kept,) = candidate_axes(chi, pairs, 7.0, 3, 5, 25, 0, 10, 14)
    assert kept[HALF_PX] == pytest.approx(20, abs=0.5)
    # too few border pairs there (26 of the face's rows against 30 needed; 40 wide): the same
    (kept,) = candidate_axes(chi, pairs, 5.0, 3, 5, 25, 30, 10, 14)
    assert kept[HALF_PX] == pytest.approx(20, abs=0.5)
    # an axis that does not qualify (threshold above every chi) stays out
    assert len(candidate_axes(chi, pairs, 50.0, 3, 5, 25, 0, 10, 14)) == 0


def test_asymmetric_patterns_give_no_axis() -> None:
    patch = np.full((32, 64), 160, dtype=np.uint8)
    patch[:, 30:] = 60  # one step: a single border
    one = signed_vertical_edges(patch, PARAMS.edge_threshold)
    stripes = np.zeros((32, 64), dtype=np.int8)
    stripes[:, 10] = stripes[:, 40] = -1  # two borders of the same sign
    for edges in (one, stripes, np.zeros((32, 64), dtype=np.int8)):
        pairs, n = mirrored_pairs(edges, 32)
        assert len(candidate_axes(chi_matrix(pairs, n), pairs, 0.35 * 32, 3, 10, 32)) == 0


def test_a_pole_is_bright_at_narrow_widths_and_no_vehicle() -> None:
    patch = np.full((32, 64), 160, dtype=np.uint8)
    patch[:, 31:34] = 60  # a 3 px pole: symmetric, but only at narrow widths
    patch[:, 10:54][-6:] = 90  # and something wide at the bottom
    edges = signed_vertical_edges(patch, PARAMS.edge_threshold)
    pairs, n = mirrored_pairs(edges, 32)
    chi = chi_matrix(pairs, n)
    assert chi[1, 64] >= 0.35 * 32  # the pole's own axis (32) is bright from the start
    assert 64 not in candidate_axes(chi, pairs, 0.35 * 32, 3, 10, 32)[:, AXIS]  # a = 2 x 32


def test_a_trunk_with_a_few_paired_background_edges_has_no_borders() -> None:
    patch = np.full((32, 64), 160, dtype=np.uint8)
    patch[:, 27:37] = 60  # a trunk 10 px wide: wider than the narrow widths
    patch[:2, 12] = patch[:2, 51] = 220  # something paired about its axis on 2 rows only
    edges = signed_vertical_edges(patch, PARAMS.edge_threshold)
    pairs, n = mirrored_pairs(edges, 32)
    chi = chi_matrix(pairs, n)
    trunk_only = candidate_axes(chi, pairs, 0.35 * 32, 3, 10, 32)
    assert 63 in trunk_only[:, AXIS]  # its axis (between columns 31 and 32) qualifies
    # the "vehicle's" borders: 6 pairs on 32 rows, fewer than 0.3 a row
    bordered = candidate_axes(chi, pairs, 0.35 * 32, 3, 10, 32, math.ceil(0.3 * 32))
    assert 63 not in bordered[:, AXIS]
    # a vehicle's borders pair up twice on every row (each step is two Sobel columns)
    box = _box_edges(32, 64, 14, 50)
    pairs, n = mirrored_pairs(box, 32)
    assert len(candidate_axes(chi_matrix(pairs, n), pairs, 0.35 * 32, 3, 10, 32, 64)) == 1


def test_a_bottom_above_the_highest_allowed_row_is_no_bottom() -> None:
    patch = np.full((32, 64), 200, dtype=np.uint8)
    patch[:12, 16:48] = 40  # something dark ending on a bright band at row 12, across the box
    d_down = sobel(patch, 0)
    bottom, _ = box_rows(d_down, 16, 48, PARAMS.edge_threshold, 0.8, 0.5, 0.5)
    assert bottom in (11, 12)  # the dark-to-bright edge
    assert box_rows(d_down, 16, 48, PARAMS.edge_threshold, 0.8, 0.5, 0.5, bottom)[0] == bottom
    assert box_rows(d_down, 16, 48, PARAMS.edge_threshold, 0.8, 0.5, 0.5, bottom + 1)[0] == -1


@pytest.mark.parametrize("height_m", [0.0, -0.3, math.nan])
def test_a_bad_base_height_is_refused(height_m: float) -> None:
    with pytest.raises(ParamsError, match="max_base_height_m"):
        VehicleParams(max_base_height_m=height_m)


@pytest.mark.parametrize("value", [-0.1, math.nan, math.inf])
def test_a_bad_border_pairs_floor_is_refused(value: float) -> None:
    with pytest.raises(ParamsError, match="min_border_pairs_per_row"):
        VehicleParams(min_border_pairs_per_row=value)


@pytest.mark.parametrize("shape", [(1, 5), (5, 1), (2, 2), (32, 64), (70, 9)])
def test_compiled_sobel_matches_opencv(shape: tuple[int, int]) -> None:
    patch = np.random.default_rng(shape[0] * 100 + shape[1]).integers(0, 256, shape, np.uint8)
    for dx in (1, 0):
        expected = cv2.Sobel(patch, cv2.CV_16S, dx, 1 - dx, ksize=3)
        np.testing.assert_array_equal(sobel(patch, dx), expected)


def test_mirrored_pairs_match_a_direct_count_over_more_than_64_rows() -> None:
    """Edge columns are bit-packed 64 rows to a word: 70 rows take two."""
    edges = np.random.default_rng(5).choice(np.array([-1, 0, 0, 1], np.int8), size=(70, 12))
    pairs, n = mirrored_pairs(edges, 6)
    for k in range(1, 7):
        for a in range(23):
            d = 2 * k - a % 2
            left, right = (a - d) // 2, (a + d) // 2
            inside = left >= 0 and right < 12
            opposite = int(np.sum(edges[:, left] * edges[:, right] < 0)) if inside else 0
            assert pairs[k - 1, a] == opposite
            assert n[k - 1, a] == np.count_nonzero(edges[:, max(left, 0) : right + 1])


def test_symmetry_matrix_rejects_a_non_image() -> None:
    with pytest.raises(ValueError, match="edges"):
        symmetry_matrix(np.zeros(5, dtype=np.int8), 3)


# --- a rendered car ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def rendered_car() -> tuple[np.ndarray, np.ndarray]:
    """A 1.8 m wide car 20 m ahead (its rear face), centred 1.0 m left, on the bundled drives'
    road and camera; the image and its object labels."""
    length = 4.4
    keys = [(0.0, 20.0 + length / 2, 1.0), (10.0, 20.0 + length / 2, 1.0)]
    car = SceneVehicle(1, "car", length, 1.8, 1.5, 70, Trajectory.from_waypoints(keys))
    render = RoadRenderer(straight_road(speed_mps=0.0, vehicles=[car]), seed=1)
    return render(0.0, camera().extrinsics.pitch_rad)


def test_rendered_car_is_found_with_its_position_and_width(
    rendered_car: tuple[np.ndarray, np.ndarray], tmp_path: Path
) -> None:
    image, labels = rendered_car
    cam = camera()
    cols = np.flatnonzero((labels == 1).any(axis=0))
    rows = np.flatnonzero((labels == 1).any(axis=1))
    # the radar point 0.2 m off the car's centre, as radars are (paper 001, fig. 2)
    radar = (target(20.0, 1.2),)
    result = detect_vehicles(search_areas(image, cam, radar, PARAMS), radar, cam, PARAMS)
    (r,) = result.targets
    assert r.verdict == "vehicle" and r.vehicle_index == 0
    assert r.symmetry.shape == (PARAMS.max_half_width_px, 2 * r.edges.shape[1] - 1)
    (v,) = result.vehicles
    assert v.distance_m == pytest.approx(20.0)  # from the radar
    assert v.lateral_m == pytest.approx(1.0, abs=0.1)  # from vision
    assert v.width_m == pytest.approx(1.8, abs=0.1)
    u0, v0, u1, v1 = v.box_px
    assert u0 == pytest.approx(cols[0] - 0.5, abs=2) and u1 == pytest.approx(cols[-1] + 0.5, abs=2)
    assert v1 == pytest.approx(rows[-1] + 0.5, abs=3)  # the base: the shadow ends on the road
    assert v1 - v0 == pytest.approx(PARAMS.default_height_ratio * (u1 - u0))  # no top found
    assert v.vision_distance_m == pytest.approx(20.0, abs=1.5)
    overlay = cv2.cvtColor(image, cv2.COLOR_GRAY2BGR)
    cv2.rectangle(overlay, (round(u0), round(v0)), (round(u1), round(v1)), (0, 255, 0), 1)
    cv2.imwrite(str(tmp_path / "rendered_car.png"), overlay)


def test_a_moving_target_off_the_cars_centre_still_finds_the_whole_car(
    rendered_car: tuple[np.ndarray, np.ndarray],
) -> None:
    """The radar point on the car's left edge, 0.9 m off its centre: the paper's 2.5 m area
    cuts the car; a moving target's area holds it and the car is measured whole."""
    image, _ = rendered_car
    cam = camera()
    ego_mps, car_mps = 20.0, 15.0
    bearing = math.atan2(1.9, 20.0 - RADAR_X_M)
    radar = (target(20.0, 1.9, (car_mps - ego_mps) * math.cos(bearing)),)
    papers = dataclasses.replace(PARAMS, moving_search_width_m=PARAMS.search_width_m)
    for params, found in ((papers, False), (PARAMS, True)):
        areas = search_areas(image, cam, radar, params, ego_mps)
        result = detect_vehicles(areas, radar, cam, params)
        whole = [v for v in result.vehicles if abs(v.width_m - 1.8) < 0.15]
        assert bool(whole) == found
    (v,) = whole
    assert v.lateral_m == pytest.approx(1.0, abs=0.1)


@pytest.mark.parametrize(
    ("cls", "width_m", "height_m", "grey"), [("car", 1.8, 1.5, 70), ("truck", 2.5, 3.8, 110)]
)
def test_the_top_rises_to_where_the_vehicles_sides_end(
    cls: str, width_m: float, height_m: float, grey: int
) -> None:
    """Step 11: the box's top is the vehicle's roof, for a car as for a truck taller than
    the area; without the image (the papers' fixed ratio) a truck's box stops far short."""
    keys = [(0.0, 20.0 + 3.0, 1.0), (10.0, 20.0 + 3.0, 1.0)]
    body = SceneVehicle(1, cls, 6.0, width_m, height_m, grey, Trajectory.from_waypoints(keys))
    image, labels = RoadRenderer(straight_road(speed_mps=0.0, vehicles=[body]), seed=1)(
        0.0, camera().extrinsics.pitch_rad
    )
    rows = np.flatnonzero((labels == 1).any(axis=1))
    cam = camera()
    ego_mps = 20.0  # the vehicle drives at 15 m/s: its area is a moving target's, 4 m wide
    radar = (target(20.0, 1.2, -5.0 * math.cos(math.atan2(1.2, 20.0 - RADAR_X_M))),)
    areas = search_areas(image, cam, radar, PARAMS, ego_mps)
    (v,) = detect_vehicles(areas, radar, cam, PARAMS, image=image).vehicles
    assert v.box_px[1] == pytest.approx(rows[0] - 0.5, abs=4)  # the roof's row
    (fixed,) = detect_vehicles(areas, radar, cam, PARAMS).vehicles
    assert fixed.box_px[3] == v.box_px[3] and fixed.box_px[1] >= v.box_px[1]
    if cls == "truck":
        assert fixed.box_px[3] - fixed.box_px[1] < 0.6 * (rows[-1] - rows[0])
    off = dataclasses.replace(PARAMS, top_search_ratio=0.0, truck_height_ratio=0.0)
    (papers,) = detect_vehicles(areas, radar, cam, off, image=image).vehicles
    assert papers.box_px == fixed.box_px


def test_the_top_rises_past_a_base_without_sides() -> None:
    """Step 11 from step 7's top: a trailer's bright rear (rows 60-169) above a dark
    underride whose sides show no edge for 30 rows, more than the gap allows; the top is
    the rear's, whatever the base below."""
    image = np.full((240, 320), 40, np.uint8)  # a dark road and underride
    image[:170] = 90  # the sky
    image[60:170, 100:200] = 200  # the trailer's rear
    box = (99.5, 150.5, 199.5, 199.5)  # step 7: the underride and the rear's lowest rows
    assert PARAMS.top_gap_ratio * 100 < 30
    assert border_top(image, box, PARAMS) == pytest.approx(59.5, abs=1)  # Sobel: 3 rows
    off = dataclasses.replace(PARAMS, top_search_ratio=0.0)
    assert border_top(image, box, off) == box[1]


def test_a_box_as_wide_as_a_truck_rises_to_a_trucks_height_along_one_border() -> None:
    """Step 11: a white trailer's rear against a sky as bright (no right border above row
    150), its left border against its own darker side up to row 40; the box found up to row
    150 (100 px wide, base at row 200) rises to truck_height_ratio x its width, 140 px above
    its base, as wide as a truck and not as a van; with neither border above, it stays."""
    image = np.full((240, 320), 40, np.uint8)  # the road
    image[:170] = 200  # the sky, as bright as the trailer
    image[40:200, 60:100] = 120  # the trailer's side, seen beside its rear
    image[150:200, 100:200] = 200  # the rear's lowest rows, the underride below them
    image[185:200, 100:200] = 30
    box = (99.5, 150.5, 199.5, 199.5)
    top = 199.5 - PARAMS.truck_height_ratio * 100
    assert truck_top(image, box, PARAMS.truck_width_m, PARAMS) == pytest.approx(top)
    assert truck_top(image, box, PARAMS.truck_width_m - 0.05, PARAMS) == box[1]  # a van
    image[40:200, 60:100] = 200  # no side: neither border goes on
    assert truck_top(image, box, PARAMS.truck_width_m, PARAMS) == box[1]
    off = dataclasses.replace(PARAMS, truck_height_ratio=0.0)
    assert truck_top(image, box, 2.5, off) == box[1]


def test_a_still_untracked_target_needs_more_symmetry(
    rendered_car: tuple[np.ndarray, np.ndarray],
) -> None:
    """A still target no track expects needs `still_symmetry_factor` x the threshold: with
    the factor just above the car's own chi over the threshold, the car is found from a
    moving or tracked target's area only; the papers' factor 1 finds it from all."""
    image, _ = rendered_car
    cam = camera()
    radar = (target(20.0, 1.2),)
    (area,) = search_areas(image, cam, radar, PARAMS)
    assert not (area.moving or area.tracked)
    (r,) = detect_vehicles((area,), radar, cam, PARAMS).targets
    assert r.verdict == "vehicle"
    assert r.threshold == pytest.approx(
        PARAMS.symmetry_threshold * PARAMS.still_symmetry_factor * area.patch.shape[0]
    )
    ratio = r.candidates[r.chosen].chi / (PARAMS.symmetry_threshold * area.patch.shape[0])
    strict = dataclasses.replace(PARAMS, still_symmetry_factor=ratio * 1.01)
    papers = dataclasses.replace(PARAMS, still_symmetry_factor=1.0)
    for a, params, found in (
        (area, strict, False),
        (dataclasses.replace(area, moving=True), strict, True),
        (dataclasses.replace(area, tracked=True), strict, True),
        (area, papers, True),
    ):
        assert bool(detect_vehicles((a,), radar, cam, params).vehicles) == found


def test_a_tracked_vehicle_taller_than_its_area_is_found_in_the_taller_area() -> None:
    """Step 6, the taller area: a van 2 m wide and 2.5 m high 20 m ahead whose lower part,
    all the area holds, is as grey as the background (no side edges there) and whose upper
    part is dark. Its tracked target's area holds no axis; the area 2.5 times as high does,
    and the van is found there, 2 m wide. A still target, no image, or the papers' factor 1
    leave it unfound."""
    cam = flat_camera()
    f, x_m, base_v = 800.0, 20.0, 239.5 + 800.0 * 1.2 / 20.0  # the road row at 20 m
    image = np.full((480, 640), 100, np.uint8)
    image[round(base_v) :] = 160  # the road, brighter than the van's lower part
    half_px, top_v = f * 1.0 / x_m, base_v - f * 2.5 / x_m
    rows = slice(round(top_v), round(base_v - f * 1.0 / x_m))  # 1.0-2.5 m above the road
    image[rows, round(319.5 - half_px) : round(319.5 + half_px)] = 30
    image = cv2.GaussianBlur(image, (5, 5), 1.0)  # a lens's blur: no pixel-sharp steps
    radar = (target(x_m, 0.0),)
    (area,) = search_areas(image, cam, radar, PARAMS, tracked_m=[(x_m, 0.0, math.nan)])
    assert area.tracked and area.full_px[1] > base_v - f * 1.0 / x_m  # the dark part is above
    found = detect_vehicles((area,), radar, cam, PARAMS, image=image)
    (r,) = found.targets
    assert r.taller and r.verdict == "vehicle"
    assert r.area.full_px[3] == area.full_px[3]
    assert r.area.full_px[3] - r.area.full_px[1] == pytest.approx(
        PARAMS.tracked_taller_area_factor * (area.full_px[3] - area.full_px[1])
    )
    (v,) = found.vehicles
    assert v.width_m == pytest.approx(2.0, abs=0.15)
    assert v.lateral_m == pytest.approx(0.0, abs=0.1)
    papers = dataclasses.replace(PARAMS, tracked_taller_area_factor=1.0)
    still = dataclasses.replace(area, tracked=False, moving=True)
    for a, params, img in ((area, PARAMS, None), (area, papers, image), (still, PARAMS, image)):
        (r,) = detect_vehicles((a,), radar, cam, params, image=img).targets
        assert r.verdict == "no_symmetry" and not r.taller


@pytest.mark.parametrize(
    ("x_m", "y_m", "height_m"),
    [(20.0, -3.0, 1.5), (20.0, 3.5, 1.0), (12.0, 0.0, 1.5), (40.0, -7.0, 3.5)],
)
def test_the_body_is_the_box_of_the_vehicle_seen_whole(
    x_m: float, y_m: float, height_m: float
) -> None:
    """Step 12: a vehicle 1.8 m wide and 4 m long, aligned with the car, whose rear face is
    at (x_m, y_m): its body box is the bounding box of its eight corners' images (its side
    beside the face off the car's path, its roof above the face when lower than the
    camera), from the face's box alone; 0 m long is the face."""
    cam = flat_camera()
    length_m, half_m = 4.0, 0.9
    corners = np.array(
        [
            (x, y, z)
            for x in (x_m, x_m + length_m)
            for y in (y_m - half_m, y_m + half_m)
            for z in (0.0, height_m)
        ]
    )
    uv, in_front = cam.project(corners)
    assert in_front.all()
    face, whole = uv[[0, 1, 2, 3]], uv
    face_box = (face[:, 0].min(), face[:, 1].min(), face[:, 0].max(), face[:, 1].max())
    want = (whole[:, 0].min(), whole[:, 1].min(), whole[:, 0].max(), whole[:, 1].max())
    assert body_box(face_box, x_m, cam, length_m) == pytest.approx(want, abs=1e-3)
    assert body_box(face_box, x_m, cam, 0.0) == face_box
    if y_m == 0.0 and height_m > cam.extrinsics.height_m:  # straight ahead, roof unseen
        assert body_box(face_box, x_m, cam, length_m) == pytest.approx(face_box)


def test_a_detected_vehicle_carries_its_body(
    rendered_car: tuple[np.ndarray, np.ndarray],
) -> None:
    image, _ = rendered_car
    cam = camera()
    radar = (target(20.0, 1.2),)
    (v,) = detect_vehicles(search_areas(image, cam, radar, PARAMS), radar, cam, PARAMS).vehicles
    assert v.outline_px == v.body_px == body_box(v.box_px, v.distance_m, cam, PARAMS.body_length_m)
    papers = dataclasses.replace(PARAMS, body_length_m=0.0)
    (p,) = detect_vehicles(search_areas(image, cam, radar, papers), radar, cam, papers).vehicles
    assert p.body_px is None and p.outline_px == p.box_px  # as a track without a body


def test_radar_point_beside_the_car_finds_nothing(
    rendered_car: tuple[np.ndarray, np.ndarray],
) -> None:
    image, _ = rendered_car
    cam = camera()
    radar = (target(20.0, -2.5),)  # the empty lane to its right
    result = detect_vehicles(search_areas(image, cam, radar, PARAMS), radar, cam, PARAMS)
    assert result.targets[0].verdict in ("no_symmetry", "no_bottom")
    assert result.vehicles == ()


def test_guard_rail_targets_are_not_searched(rendered_car: tuple[np.ndarray, np.ndarray]) -> None:
    image, _ = rendered_car
    cam = camera()
    radar = (target(20.0, 1.2),)
    areas = search_areas(image, cam, radar, PARAMS)
    result = detect_vehicles(areas, radar, cam, PARAMS, guard_rails=frozenset({0}))
    assert result.targets[0].verdict == "guard_rail" and result.vehicles == ()
    assert result.targets[0].edges.shape == (0, 0)


def test_an_area_with_too_few_pixels_per_metre_is_not_searched(
    rendered_car: tuple[np.ndarray, np.ndarray],
) -> None:
    """The car 20 m ahead: its area's image pixels per metre are the focal length over its
    distance from the camera; a threshold just above them leaves it unsearched ("too_far"),
    one just below (or 0, the papers') searches and finds it."""
    image, _ = rendered_car
    cam = camera()
    radar = (target(20.0, 1.2),)
    (area,) = search_areas(image, cam, radar, PARAMS)
    # the camera sits a little ahead of the vehicle frame's origin
    fx = cam.intrinsics.fx_px
    assert fx / area.x_m < area.image_px_per_m < fx / (area.x_m - 2.5)
    for limit, verdict in (
        (area.image_px_per_m * 1.01, "too_far"),
        (area.image_px_per_m * 0.99, "vehicle"),
        (0.0, "vehicle"),
    ):
        params = dataclasses.replace(PARAMS, min_image_px_per_m=limit)
        (marked,) = search_areas(image, cam, radar, params)
        assert marked.too_far == (verdict == "too_far")
        result = detect_vehicles((marked,), radar, cam, params)
        assert result.targets[0].verdict == verdict
        assert len(result.vehicles) == (verdict == "vehicle")
    assert PARAMS.min_image_px_per_m == 10.0


def test_two_radar_points_on_one_car_give_one_vehicle(
    rendered_car: tuple[np.ndarray, np.ndarray],
) -> None:
    image, _ = rendered_car
    cam = camera()
    radar = (target(20.0, 1.2), target(20.1, 0.85))
    result = detect_vehicles(search_areas(image, cam, radar, PARAMS), radar, cam, PARAMS)
    (v,) = result.vehicles
    assert v.target_indices == (0, 1)
    assert v.distance_m == pytest.approx(20.0)  # the nearest target's: nearest the near face
    assert v.width_m == pytest.approx(1.8, abs=0.15)
    assert [r.vehicle_index for r in result.targets] == [0, 0]
    papers = dataclasses.replace(PARAMS, distance_of_nearest_target=False)
    (mean,) = detect_vehicles(search_areas(image, cam, radar, papers), radar, cam, papers).vehicles
    assert mean.distance_m == pytest.approx(20.05)  # the papers': the mean of its targets


def test_detect_vehicles_rejects_areas_of_unknown_targets() -> None:
    cam = flat_camera()
    image = np.zeros((480, 640), dtype=np.uint8)
    areas = search_areas(image, cam, (target(20.0, 0.0),), PARAMS)
    with pytest.raises(ValueError, match="areas"):
        detect_vehicles(areas, (), cam, PARAMS)


# --- filters and merging -----------------------------------------------------------------


def test_world_size_filter_keeps_vehicle_widths_only() -> None:
    cam = flat_camera()
    # at 20 m (18.6 m from the camera... here the camera is at x = 0): 40 px per metre
    per_m = 800.0 / 20.0

    def box(width_m: float) -> tuple[float, float, float, float]:
        half = width_m * per_m / 2
        return (319.5 - half, 250.0, 319.5 + half, 287.5)

    assert world_size_ok(box(1.8), 20.0, cam, PARAMS)
    assert world_size_ok(box(2.9), 20.0, cam, PARAMS)
    assert not world_size_ok(box(0.6), 20.0, cam, PARAMS)  # a post
    assert not world_size_ok(box(3.5), 20.0, cam, PARAMS)  # wider than any vehicle


def test_merging_prefers_the_largest_box() -> None:
    big = (100.0, 100.0, 200.0, 180.0)
    part = (120.0, 140.0, 160.0, 172.0)  # a vehicle part inside it
    merged = merge_boxes([(part, 3), (big, 1)], PARAMS)
    assert merged == [(big, [1, 3])]


def test_merging_averages_similar_boxes_on_one_base() -> None:
    a = (100.0, 100.0, 200.0, 180.0)
    b = (106.0, 102.0, 204.0, 181.0)  # similar size, base 1 px lower (< 10 % of 80 px)
    ((box, targets),) = merge_boxes([(a, 0), (b, 2)], PARAMS)
    assert box == pytest.approx((103.0, 101.0, 202.0, 180.5))
    assert targets == [0, 2]


def test_merging_keeps_the_larger_of_similar_boxes_on_different_bases() -> None:
    a = (100.0, 100.0, 200.0, 180.0)
    b = (104.0, 112.0, 200.0, 192.0)  # overlapping, base 12 px lower
    assert merge_boxes([(a, 0), (b, 1)], PARAMS) == [(a, [0, 1])]


def test_separate_boxes_stay_separate() -> None:
    a = (100.0, 100.0, 200.0, 180.0)
    b = (300.0, 100.0, 380.0, 164.0)
    assert merge_boxes([(a, 0), (b, 1)], PARAMS) == [(a, [0]), (b, [1])]


def test_boxes_of_targets_far_apart_in_distance_are_never_one_vehicle() -> None:
    big = (100.0, 100.0, 200.0, 180.0)  # a van at 35 m
    part = (120.0, 110.0, 160.0, 130.0)  # inside it: the box of a target 80 m ahead
    distances = [35.0, 80.0, 36.0]
    assert merge_boxes([(part, 1), (big, 0)], PARAMS, distances) == [(big, [0]), (part, [1])]
    # within the gap of one of the vehicle's targets: merged, a chain along a truck
    near = (120.0, 140.0, 160.0, 172.0)
    chain = merge_boxes([(part, 2), (big, 0)], PARAMS, [35.0, 0.0, 39.5])
    assert chain == [(big, [0, 2])]
    assert merge_boxes([(near, 1), (big, 0)], PARAMS, distances) == [(big, [0]), (near, [1])]
    # the papers' merge: by overlap alone
    papers = dataclasses.replace(PARAMS, merge_max_gap_m=1000.0)
    assert merge_boxes([(part, 1), (big, 0)], papers, distances) == [(big, [0, 1])]


def test_bad_parameters_name_the_field() -> None:
    for field, value in (
        ("edge_threshold", 0.0),
        ("bottom_edge_fraction", 1.5),
        ("min_image_px_per_m", -1.0),
        ("min_image_px_per_m", math.nan),
    ):
        with pytest.raises(ParamsError, match=field):
            dataclasses.replace(PARAMS, **{field: value})


def test_search_areas_reject_a_bad_image() -> None:
    with pytest.raises(ValueError, match="image"):
        search_areas(np.zeros((10, 10), dtype=np.float32), flat_camera(), (), PARAMS)


# --- vehicles hidden on one side ------------------------------------------------------------


def _vehicle(box_px: tuple[float, float, float, float], distance_m: float) -> Vehicle:
    """A vehicle with its box on the flat camera at `distance_m` (f = 800 px, centre column
    319.5): lateral position and width as world_extents gives them."""
    cam = flat_camera()
    (lateral,), (width,), (vision,) = world_extents([box_px], [distance_m], cam)
    return Vehicle(box_px, distance_m, lateral, width, vision, (0,))


def test_a_box_ending_on_a_nearer_vehicle_is_hidden_on_that_side() -> None:
    near = _vehicle((280.0, 250.0, 360.0, 300.0), 16.0)  # 1.6 m wide, 16 m ahead
    # 32 m ahead, its left side on the near car's right side (2 px off), rows in common
    far_right = _vehicle((362.0, 230.0, 398.0, 262.0), 32.0)
    far_left = _vehicle((250.0, 230.0, 281.0, 262.0), 32.0)  # its right side on the near left
    apart = _vehicle((380.0, 230.0, 420.0, 262.0), 32.0)  # 20 px from the near car
    above = _vehicle((362.0, 200.0, 398.0, 240.0), 32.0)  # no row in common
    sides = hidden_sides([near, far_right, far_left, apart, above])
    assert sides == [None, "left", "right", None, None]
    # a nearer vehicle is not hidden by a farther one, nor one by a vehicle at its distance
    assert hidden_sides([dataclasses.replace(near, distance_m=40.0), far_right])[1] is None
    assert hidden_sides([dataclasses.replace(near, distance_m=31.0), far_right])[1] is None
    # both sides on nearer vehicles: neither is known
    both = _vehicle((362.0, 230.0, 398.0, 262.0), 32.0)
    other = _vehicle((399.0, 250.0, 460.0, 300.0), 16.0)
    assert hidden_sides([near, both, other])[1] is None


@pytest.mark.parametrize("side", ["left", "right"])
def test_a_vehicle_hidden_on_one_side_is_measured_from_the_other(side: str) -> None:
    """36 px seen at 32 m are 1.44 m: the vehicle is hidden_side_width_m wide, with its seen
    side where its box has it; its box stays what the camera shows."""
    box = (362.0, 230.0, 398.0, 262.0)
    near_box = (280.0, 250.0, 364.0, 300.0) if side == "left" else (396.0, 250.0, 470.0, 300.0)
    far = _vehicle(box, 32.0)
    assert far.width_m == pytest.approx(36 * 32.0 / 800.0)
    width = PARAMS.hidden_side_width_m
    near, measured = measured_past_hidden_sides([_vehicle(near_box, 16.0), far], width)
    assert near.hidden_side is None
    assert near.width_m == pytest.approx((near_box[2] - near_box[0]) * 16.0 / 800.0)
    assert measured.hidden_side == side and measured.width_m == width
    if side == "left":  # the right side (smaller y) is seen
        expected = far.lateral_m - far.width_m / 2 + width / 2
    else:
        expected = far.lateral_m + far.width_m / 2 - width / 2
    assert measured.lateral_m == pytest.approx(expected)
    assert measured.box_px == box
    # seen wider than that: the width seen stays, and so does the lateral position
    wide = _vehicle((340.0, 230.0, 398.0, 262.0), 32.0)  # 2.32 m
    (_, kept) = measured_past_hidden_sides([_vehicle(near_box, 16.0), wide], width)
    assert kept.width_m == pytest.approx(wide.width_m)
    assert kept.lateral_m == pytest.approx(wide.lateral_m)
