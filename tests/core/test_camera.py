"""core.camera: projection, the road plane, the bird's-eye grid.

Known answers are derived here from the pinhole model (u = cx + fx X/Z, v = cy + fy Y/Z) on
poses simple enough to do by hand; the general poses are covered by round-trip properties.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from core.camera import BirdEyeGrid, CameraModel, Extrinsics, Intrinsics

PROPERTY_SETTINGS = settings(
    max_examples=200, deadline=None, suppress_health_check=[HealthCheck.filter_too_much]
)

WIDTH_PX, HEIGHT_PX = 640, 480
# Keep the lens away from the fold of the radial model: d r_d / d r_u = 1 + 3 k1 r_u^2
# must stay clearly positive, or a distorted pixel has no unique ideal pixel.
MIN_LENS_SLOPE = 0.25


# --- strategies -------------------------------------------------------------------------------
def _angle() -> st.SearchStrategy[float]:
    return st.floats(-0.1, 0.1)


@st.composite
def cameras(draw: st.DrawFn, distortion: bool = True, roll: bool = True) -> CameraModel:
    fx = draw(st.floats(300.0, 1500.0))
    fy = fx * draw(st.floats(0.98, 1.02))
    dist: tuple[float, ...] = ()
    if distortion and draw(st.booleans()):
        dist = (draw(st.floats(-0.3, 0.1)), 0.0, 0.0, 0.0)
    intr = Intrinsics(
        fx_px=fx,
        fy_px=fy,
        cx_px=draw(st.floats(300.0, 340.0)),
        cy_px=draw(st.floats(220.0, 260.0)),
        width_px=WIDTH_PX,
        height_px=HEIGHT_PX,
        distortion=dist,
    )
    ext = Extrinsics(
        height_m=draw(st.floats(0.8, 2.5)),
        x_m=draw(st.floats(-1.0, 3.0)),
        y_m=draw(st.floats(-1.0, 1.0)),
        pitch_rad=draw(_angle()),
        yaw_rad=draw(_angle()),
        roll_rad=draw(_angle()) if roll else 0.0,
    )
    return CameraModel(intr, ext)


@st.composite
def grids(draw: st.DrawFn) -> BirdEyeGrid:
    x_min = draw(st.floats(0.0, 10.0))
    return BirdEyeGrid(
        x_min_m=x_min,
        x_max_m=x_min + draw(st.floats(5.0, 60.0)),
        y_min_m=draw(st.floats(-15.0, -1.0)),
        y_max_m=draw(st.floats(1.0, 15.0)),
        cell_m=draw(st.floats(0.05, 0.5)),
    )


def _pinhole(cam: CameraModel) -> CameraModel:
    """The same camera without lens distortion."""
    return replace(cam, intrinsics=replace(cam.intrinsics, distortion=()))


def _k1(cam: CameraModel) -> float:
    return cam.intrinsics.distortion[0] if cam.intrinsics.distortion else 0.0


def _normalized_radius(cam: CameraModel, uv: np.ndarray) -> float:
    i = cam.intrinsics
    return math.hypot((uv[0] - i.cx_px) / i.fx_px, (uv[1] - i.cy_px) / i.fy_px)


def _inside_image(uv: np.ndarray) -> bool:
    return bool(0.0 <= uv[0] <= WIDTH_PX - 1 and 0.0 <= uv[1] <= HEIGHT_PX - 1)


def _apply_h(H: np.ndarray, pts: np.ndarray) -> np.ndarray:
    h = np.column_stack([pts, np.ones(len(pts))]) @ H.T
    return h[:, :2] / h[:, 2:]


def _straight_camera(**ext: float) -> CameraModel:
    """640x480, f = 500 px, principal point at the image centre, 1.2 m high, 1.5 m ahead."""
    pose = {"height_m": 1.2, "x_m": 1.5} | ext
    return CameraModel(
        Intrinsics(500.0, 500.0, 319.5, 239.5, WIDTH_PX, HEIGHT_PX), Extrinsics(**pose)
    )


# --- properties -------------------------------------------------------------------------------
@PROPERTY_SETTINGS
@given(
    cam=cameras(),
    x=st.floats(2.0, 80.0),
    y=st.floats(-15.0, 15.0),
    z=st.floats(-0.5, 3.5),
)
def test_project_then_point_at_height_returns_the_point(
    cam: CameraModel, x: float, y: float, z: float
) -> None:
    p = np.array([x, y, z])
    ideal, front = _pinhole(cam).project(p)
    assume(front[0] and _inside_image(ideal[0]))
    assume(1.0 + 3.0 * _k1(cam) * _normalized_radius(cam, ideal[0]) ** 2 > MIN_LENS_SLOPE)
    rng_m = float(np.linalg.norm(p - cam.position_vehicle_m))
    # A ray grazing the plane z = z_m meets it ill-conditioned; keep some descent.
    assume(abs(z - cam.extrinsics.height_m) > 0.02 * rng_m)

    uv, front = cam.project(p)
    assert front[0]
    back = cam.point_at_height(uv, z)
    assert np.linalg.norm(back[0] - p) <= 1e-6 * rng_m

    ray = cam.rays_vehicle(uv)[0]
    expected = (p - cam.position_vehicle_m) / rng_m
    np.testing.assert_allclose(ray, expected, atol=1e-9)


@PROPERTY_SETTINGS
@given(cam=cameras(), u=st.floats(0.0, WIDTH_PX - 1.0), v=st.floats(0.0, HEIGHT_PX - 1.0))
def test_ground_pixel_round_trip(cam: CameraModel, u: float, v: float) -> None:
    k1 = _k1(cam)
    if k1 < 0:
        # Largest distorted radius the lens produces is reached at 1 + 3 k1 r^2 = 0;
        # stay inside the part where the model is comfortably invertible.
        r_u = math.sqrt((1.0 - MIN_LENS_SLOPE) / (-3.0 * k1))
        assume(_normalized_radius(cam, np.array([u, v])) < r_u * (1.0 + k1 * r_u**2))
    g = cam.ground_point([u, v])
    assume(np.all(np.isfinite(g)))
    assert g[0, 2] == pytest.approx(0.0, abs=1e-9)
    uv, front = cam.project(g)
    assert front[0]
    np.testing.assert_allclose(uv[0], [u, v], atol=1e-6)


@PROPERTY_SETTINGS
@given(cam=cameras())
def test_transforms_are_inverse_rigid_motions(cam: CameraModel) -> None:
    np.testing.assert_allclose(cam.T_vehicle_camera @ cam.T_camera_vehicle, np.eye(4), atol=1e-12)
    np.testing.assert_allclose(cam.T_camera_vehicle @ cam.T_vehicle_camera, np.eye(4), atol=1e-12)
    R = cam.R_vehicle_camera
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0)
    # The optical centre is the camera-frame origin.
    np.testing.assert_allclose(cam.T_vehicle_camera[:3, 3], cam.position_vehicle_m)


@PROPERTY_SETTINGS
@given(cam=cameras(distortion=False), grid=grids())
def test_grid_homographies_are_inverse(cam: CameraModel, grid: BirdEyeGrid) -> None:
    A = cam.H_image_grid(grid)
    B = cam.H_grid_image(grid)
    prod = A @ B
    np.testing.assert_allclose(prod / prod[2, 2], np.eye(3), atol=1e-9)
    prod = B @ A
    np.testing.assert_allclose(prod / prod[2, 2], np.eye(3), atol=1e-9)


@PROPERTY_SETTINGS
@given(
    cam=cameras(distortion=False),
    grid=grids(),
    x=st.floats(3.0, 70.0),
    y=st.floats(-12.0, 12.0),
)
def test_grid_homography_agrees_with_projection(
    cam: CameraModel, grid: BirdEyeGrid, x: float, y: float
) -> None:
    ground = np.array([[x, y]])
    uv, front = cam.project([x, y, 0.0])
    assume(front[0])
    cells = grid.cells_from_ground(ground)
    np.testing.assert_allclose(_apply_h(cam.H_grid_image(grid), uv), cells, atol=1e-6)
    np.testing.assert_allclose(_apply_h(cam.H_image_grid(grid), cells), uv, atol=1e-6)


@PROPERTY_SETTINGS
@given(grid=grids(), col=st.floats(-50.0, 500.0), row=st.floats(-50.0, 1500.0))
def test_cells_ground_round_trip(grid: BirdEyeGrid, col: float, row: float) -> None:
    cells = np.array([[col, row]])
    ground = grid.ground_from_cells(cells)
    np.testing.assert_allclose(grid.cells_from_ground(ground), cells, atol=1e-9)
    np.testing.assert_allclose(grid.ground_from_cells(grid.cells_from_ground(ground)), ground)
    np.testing.assert_allclose(_apply_h(grid.T_grid_ground, ground), cells, atol=1e-9)


@PROPERTY_SETTINGS
@given(cam=cameras(distortion=False), u=st.floats(0.0, WIDTH_PX - 1.0))
def test_far_ground_points_lie_on_the_horizon(cam: CameraModel, u: float) -> None:
    # The ray through (u, horizon row) is parallel to the road; a point a few metres below
    # it at 1e9 m sits on the horizon to well under a pixel.
    v = cam.horizon_row_px(u)
    d = cam.rays_vehicle([u, v])[0]
    assert d[2] == pytest.approx(0.0, abs=1e-9)
    far = cam.position_vehicle_m + 1e9 * d - np.array([0.0, 0.0, cam.extrinsics.height_m])
    uv, front = cam.project(far)
    assert front[0]
    np.testing.assert_allclose(uv[0], [u, v], atol=1e-3)


@PROPERTY_SETTINGS
@given(cam=cameras(distortion=False, roll=False))
def test_horizon_row_is_paper_000_eq_2(cam: CameraModel) -> None:
    i, e = cam.intrinsics, cam.extrinsics
    expected = i.cy_px - i.fy_px * math.tan(e.pitch_rad)
    assert cam.horizon_row_px() == pytest.approx(expected, abs=1e-9)
    # Without roll the horizon is a horizontal line, whatever the yaw.
    assert cam.horizon_row_px(0.0) == pytest.approx(expected, abs=1e-9)
    assert cam.horizon_row_px(WIDTH_PX - 1.0) == pytest.approx(expected, abs=1e-9)
    assert cam.pitch_from_horizon_row(expected) == pytest.approx(e.pitch_rad, abs=1e-12)
    repitched = cam.with_pitch(0.05)
    assert repitched.extrinsics == replace(e, pitch_rad=0.05)
    assert repitched.horizon_row_px() == pytest.approx(i.cy_px - i.fy_px * math.tan(0.05))


@PROPERTY_SETTINGS
@given(cam=cameras(distortion=False))
def test_the_vanishing_point_ahead_is_where_points_straight_ahead_go(cam: CameraModel) -> None:
    # A point 1e9 m straight ahead, at any height, is imaged on it to well under a pixel,
    # and it lies on the horizon.
    u, v = cam.ahead_px
    for z_m in (0.0, 1.5, 4.0):
        uv, front = cam.project([1e9, 0.0, z_m])
        assert front[0]
        np.testing.assert_allclose(uv[0], [u, v], atol=1e-3)
    assert cam.horizon_row_px(u) == pytest.approx(v, abs=1e-6)


@pytest.mark.parametrize(("pitch_rad", "yaw_rad"), [(0.0, 0.0), (0.05, 0.0), (0.0, 0.04)])
def test_the_vanishing_point_ahead_known_pitch_and_yaw(pitch_rad: float, yaw_rad: float) -> None:
    # pitch moves it up (paper 000 eq. 2, the horizon's row), yaw sideways (u = cx + fx
    # tan(yaw), as a point straight ahead in `test_positive_yaw_turns_the_camera_left`)
    u, v = _straight_camera(pitch_rad=pitch_rad, yaw_rad=yaw_rad).ahead_px
    assert u == pytest.approx(319.5 + 500.0 * math.tan(yaw_rad), abs=1e-9)
    assert v == pytest.approx(239.5 - 500.0 * math.tan(pitch_rad), abs=1e-9)


# --- known answers ----------------------------------------------------------------------------
@pytest.mark.parametrize("x_m", [2.0, 5.0, 11.5, 40.0])
def test_point_straight_ahead_on_the_road(x_m: float) -> None:
    cam = _straight_camera()
    uv, front = cam.project([x_m, 0.0, 0.0])
    assert front[0]
    # Camera frame: X = 0, Y = h (down), Z = x - cam_x, so u = cx, v = cy + fy h / (x - cam_x).
    np.testing.assert_allclose(uv[0], [319.5, 239.5 + 500.0 * 1.2 / (x_m - 1.5)], atol=1e-9)
    np.testing.assert_allclose(cam.ground_point(uv)[0], [x_m, 0.0, 0.0], atol=1e-9)


@pytest.mark.parametrize("pitch_rad", [-0.08, 0.0, 0.02, 0.1])
def test_horizon_row_known_pitch(pitch_rad: float) -> None:
    cam = _straight_camera(pitch_rad=pitch_rad)
    v = 239.5 - 500.0 * math.tan(pitch_rad)
    assert cam.horizon_row_px() == pytest.approx(v, abs=1e-9)
    assert cam.pitch_from_horizon_row(v) == pytest.approx(pitch_rad, abs=1e-12)
    # Pitch down (> 0) raises the horizon above the principal point.
    assert (cam.horizon_row_px() < 239.5) == (pitch_rad > 0)


def test_positive_yaw_turns_the_camera_left() -> None:
    # yaw is about vehicle z (up), counter-clockwise seen from above: the camera looks left,
    # so a point straight ahead of the car appears right of centre, at u = cx + fx tan(yaw).
    yaw = 0.05
    cam = _straight_camera(yaw_rad=yaw)
    uv, _ = cam.project([20.0, 0.0, 1.2])
    assert uv[0, 0] == pytest.approx(319.5 + 500.0 * math.tan(yaw), abs=1e-9)
    assert uv[0, 1] == pytest.approx(239.5, abs=1e-9)
    # A point on the optical axis, to the left of the car, lands on the principal point.
    uv, _ = cam.project([1.5 + 20.0 * math.cos(yaw), 20.0 * math.sin(yaw), 1.2])
    np.testing.assert_allclose(uv[0], [319.5, 239.5], atol=1e-9)
    # Negative yaw mirrors it.
    uv, _ = _straight_camera(yaw_rad=-yaw).project([20.0, 0.0, 1.2])
    assert uv[0, 0] == pytest.approx(319.5 - 500.0 * math.tan(yaw), abs=1e-9)


def test_warp_to_grid_puts_a_road_stripe_at_its_distance() -> None:
    cam = _straight_camera()  # ground at distance x is at row v = 239.5 + 600 / (x - 1.5)
    grid = BirdEyeGrid(x_min_m=5.0, x_max_m=30.0, y_min_m=-5.0, y_max_m=5.0, cell_m=0.1)
    image = np.zeros((HEIGHT_PX, WIDTH_PX), np.uint8)
    image[290:300, :] = 255  # rows 289.5..299.5: ground x from 13.5 m down to 11.5 m

    def row_of(x_m: float) -> float:
        return (30.0 - x_m) / 0.1 - 0.5

    def x_of(v_px: float) -> float:
        return 1.5 + 600.0 / (v_px - 239.5)

    bev = cam.warp_to_grid(image, grid)
    assert bev.shape == grid.shape == (250, 100)
    centre = bev[:, 50]
    # Fully bright where the bilinear sample falls between rows 290 and 299 ...
    first_full = math.ceil(row_of(x_of(290.0)))
    last_full = math.floor(row_of(x_of(299.0)))
    assert (first_full, last_full) == (166, 183)
    assert np.all(centre[first_full : last_full + 1] >= 250)
    # ... dark where it falls outside rows 289..300, and the stripe's middle is at 12.5 m.
    assert np.all(centre[: math.floor(row_of(x_of(289.0))) + 1] <= 5)
    assert np.all(centre[math.ceil(row_of(x_of(300.0))) :] <= 5)
    assert row_of(12.5) == pytest.approx((first_full + last_full) / 2, abs=0.5)

    # Back to the image: the stripe's middle rows are marked, the rest of the road is not.
    mask = cam.warp_from_grid((bev >= 128).astype(np.uint8), grid)
    assert mask.shape == (HEIGHT_PX, WIDTH_PX)
    assert np.all(mask[292:298, 300:340] == 1)
    assert np.all(mask[310:400, 300:340] == 0)


def test_grid_cells_visible() -> None:
    cam = _straight_camera()
    behind = BirdEyeGrid(x_min_m=-20.0, x_max_m=-2.0, y_min_m=-3.0, y_max_m=3.0, cell_m=0.5)
    assert not cam.grid_cells_visible(behind).any()

    grid = BirdEyeGrid(x_min_m=-10.0, x_max_m=30.0, y_min_m=-50.0, y_max_m=50.0, cell_m=0.5)
    vis = cam.grid_cells_visible(grid)
    assert vis.shape == grid.shape
    centres = grid.ground_from_cells(
        np.stack(np.meshgrid(np.arange(grid.shape[1]), np.arange(grid.shape[0])), -1).reshape(-1, 2)
    ).reshape(*grid.shape, 2)
    x = centres[..., 0]
    y = centres[..., 1]
    # Behind the camera, or nearer than the bottom row sees (x = 1.5 + 600 / 240 = 4 m).
    assert not vis[x < 4.0].any()
    # Straight ahead from 5 m to 30 m is in view; 50 m to the side at 10 m is not
    # (the half field of view is atan(320 / 500) = 32.6 deg).
    assert vis[(x > 5.0) & (np.abs(y) < 1.0)].all()
    assert not vis[(x < 10.0) & (np.abs(y) > 40.0)].any()


def test_from_fov() -> None:
    intr = Intrinsics.from_fov(640, 480, math.radians(90.0))
    assert intr.fx_px == pytest.approx(320.0)
    assert intr.fy_px == intr.fx_px
    assert (intr.cx_px, intr.cy_px) == (319.5, 239.5)
    assert intr.horizontal_fov_rad == pytest.approx(math.radians(90.0))


def test_grid_shape_and_first_cell() -> None:
    grid = BirdEyeGrid(x_min_m=4.0, x_max_m=40.0, y_min_m=-10.0, y_max_m=10.0, cell_m=0.1)
    assert grid.shape == (360, 200)
    np.testing.assert_allclose(grid.ground_from_cells([0, 0]), [[39.95, 9.95]])
    np.testing.assert_allclose(grid.ground_from_cells([199, 359]), [[4.05, -9.95]])


# --- degenerate inputs ------------------------------------------------------------------------
@pytest.mark.parametrize("distortion", [(), (-0.2, 0.0, 0.0, 0.0)])
def test_points_behind_the_camera(distortion: tuple[float, ...]) -> None:
    cam = _straight_camera()
    cam = replace(cam, intrinsics=replace(cam.intrinsics, distortion=distortion))
    pts = np.array([[-5.0, 0.0, 0.0], [1.5, 2.0, 1.2], [10.0, 0.0, 0.0]])
    uv, front = cam.project(pts)
    assert front.tolist() == [False, False, True]
    assert np.isnan(uv[:2]).all()
    assert np.isfinite(uv[2]).all()


def test_pixels_above_the_horizon_have_no_ground_point() -> None:
    cam = _straight_camera(pitch_rad=0.02)
    horizon = cam.horizon_row_px()
    g = cam.ground_point([[319.5, 0.0], [10.0, horizon - 1.0], [319.5, horizon], [319.5, 400.0]])
    assert np.isnan(g[:3]).all()
    assert np.isfinite(g[3]).all()


def test_empty_input_gives_empty_output() -> None:
    cam = _straight_camera()
    uv, front = cam.project(np.empty((0, 3)))
    assert uv.shape == (0, 2)
    assert front.shape == (0,)
    assert cam.ground_point(np.empty((0, 2))).shape == (0, 3)
    distorted = replace(cam, intrinsics=replace(cam.intrinsics, distortion=(-0.1, 0, 0, 0)))
    assert distorted.rays_vehicle(np.empty((0, 2))).shape == (0, 3)


# --- bad input --------------------------------------------------------------------------------
def _intrinsics(**kw: object) -> Intrinsics:
    args: dict[str, object] = {
        "fx_px": 500.0,
        "fy_px": 500.0,
        "cx_px": 319.5,
        "cy_px": 239.5,
        "width_px": WIDTH_PX,
        "height_px": HEIGHT_PX,
    }
    return Intrinsics(**(args | kw))  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"fx_px": 0.0}, "fx_px"),
        ({"fx_px": -500.0}, "fx_px"),
        ({"fy_px": 0.0}, "fy_px"),
        ({"cx_px": math.nan}, "cx_px"),
        ({"width_px": 0}, "width_px"),
        ({"distortion": (0.1, 0.0)}, r"distortion: .*got 2"),
        ({"distortion": (0.1,) * 6}, r"distortion: .*got 6"),
    ],
)
def test_intrinsics_validation(kw: dict[str, object], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        _intrinsics(**kw)


@pytest.mark.parametrize("fov", [0.0, -0.5, math.pi, 4.0])
def test_from_fov_validation(fov: float) -> None:
    with pytest.raises(ValueError, match="horizontal_fov_rad"):
        Intrinsics.from_fov(640, 480, fov)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"height_m": 0.0}, r"height_m: .*> 0.*got 0.0"),
        ({"height_m": -1.0}, "height_m"),
        ({"height_m": math.inf}, "height_m"),
        ({"pitch_rad": math.pi / 2}, r"pitch_rad: expected \|angle\| < pi/2"),
        ({"pitch_rad": -2.0}, "pitch_rad"),
        ({"yaw_rad": 1.6}, "yaw_rad"),
        ({"roll_rad": -1.6}, "roll_rad"),
        ({"x_m": math.nan}, "x_m"),
    ],
)
def test_extrinsics_validation(kw: dict[str, float], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        Extrinsics(**({"height_m": 1.2} | kw))


@pytest.mark.parametrize("rows", [(0, 481), (-1, 300), (300, 300), (300, 100), (0, 100, 200), (5,)])
def test_rows_used_validation(rows: tuple[int, ...]) -> None:
    with pytest.raises(ValueError, match="rows_used_px"):
        CameraModel(_intrinsics(), Extrinsics(1.2), rows_used_px=rows)  # type: ignore[arg-type]


def test_rows_used_window() -> None:
    cam = CameraModel(_intrinsics(), Extrinsics(1.2), rows_used_px=(180, 480))
    assert cam.row_window_px == (180, 480)
    assert _straight_camera().row_window_px == (0, HEIGHT_PX)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"x_max_m": 4.0}, r"x_max_m: expected > x_min_m=4.0, got 4.0"),
        ({"x_max_m": 1.0}, "x_max_m"),
        ({"y_max_m": -10.0}, "y_max_m"),
        ({"cell_m": 0.0}, r"cell_m: expected > 0"),
        ({"cell_m": -0.1}, "cell_m"),
        ({"x_min_m": math.nan}, "x_min_m"),
    ],
)
def test_grid_validation(kw: dict[str, float], match: str) -> None:
    args = {"x_min_m": 4.0, "x_max_m": 40.0, "y_min_m": -10.0, "y_max_m": 10.0, "cell_m": 0.1}
    with pytest.raises(ValueError, match=match):
        BirdEyeGrid(**(args | kw))


def test_wrong_shapes_name_the_argument() -> None:
    cam = _straight_camera()
    grid = BirdEyeGrid(4.0, 40.0, -10.0, 10.0, 0.1)
    with pytest.raises(ValueError, match=r"pts_vehicle_m: expected .*\(N, 3\), got \(4, 2\)"):
        cam.project(np.zeros((4, 2)))
    with pytest.raises(ValueError, match="pts_vehicle_m"):
        cam.project(np.zeros((2, 3, 1)))
    with pytest.raises(ValueError, match=r"pts_img_px: expected .*\(N, 2\)"):
        cam.rays_vehicle(np.zeros((4, 3)))
    with pytest.raises(ValueError, match="pts_img_px"):
        cam.ground_point([1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="pts_img_px"):
        cam.point_at_height(np.zeros((3,)), 1.0)
    with pytest.raises(ValueError, match="pts_img_px"):
        cam.undistort_px(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="pts_img_px"):
        cam.distort_px(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="cells"):
        grid.ground_from_cells(np.zeros((2, 3)))
    with pytest.raises(ValueError, match="pts_ground_m"):
        grid.cells_from_ground(np.zeros((2, 3)))
