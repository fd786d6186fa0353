"""Chessboard calibration: a known camera recovered from rendered views, the real Udacity
chessboard set, skipped views, camera_info files, and the `fusionscope calibrate` command."""

from __future__ import annotations

import math
from pathlib import Path

import cv2
import numpy as np
import numpy.typing as npt
import pytest

from core.calibrate import Chessboard, calibrate_chessboard, read_views
from core.camera import Intrinsics
from core.cli import main
from core.io.calibration import load_camera_info, save_camera_info
from core.io.errors import RecordingError

# The camera the synthetic views are rendered with (the answer the tests recover).
TRUE = Intrinsics(fx_px=600.0, fy_px=600.0, cx_px=331.0, cy_px=229.0, width_px=640, height_px=480)
BOARD = Chessboard(9, 6, square_m=0.1)
SUPERSAMPLE = 4
# Board poses: (rotation about x, rotation about y, about z) in degrees, distance in metres.
POSES = [
    (0.0, 0.0, 0.0, 2.2),
    (25.0, 0.0, 5.0, 2.4),
    (-25.0, 0.0, -5.0, 2.4),
    (0.0, 30.0, 0.0, 2.5),
    (0.0, -30.0, 10.0, 2.5),
    (20.0, 20.0, -10.0, 2.6),
    (-20.0, -25.0, 0.0, 2.6),
    (15.0, -20.0, 20.0, 2.3),
]


def _rotation(ax_deg: float, ay_deg: float, az_deg: float) -> npt.NDArray[np.float64]:
    rx, _ = cv2.Rodrigues(np.array([math.radians(ax_deg), 0.0, 0.0]))
    ry, _ = cv2.Rodrigues(np.array([0.0, math.radians(ay_deg), 0.0]))
    rz, _ = cv2.Rodrigues(np.array([0.0, 0.0, math.radians(az_deg)]))
    return np.asarray(rz @ ry @ rx, dtype=np.float64)


def render_view(
    camera: Intrinsics, board: Chessboard, pose: tuple[float, float, float, float]
) -> npt.NDArray[np.uint8]:
    """(H, W) uint8 image of `board` seen by `camera`: each black square a projected polygon,
    drawn at SUPERSAMPLE times the size and averaged down (anti-aliased edges)."""
    ax, ay, az, distance_m = pose
    R = _rotation(ax, ay, az)
    s = board.square_m
    centre = np.array([(board.cols - 1) * s / 2, (board.rows - 1) * s / 2, 0.0])
    tvec = np.array([0.0, 0.0, distance_m]) - R @ centre
    rvec, _ = cv2.Rodrigues(R)
    k = SUPERSAMPLE
    K_big = np.array(
        [
            [camera.fx_px * k, 0.0, (camera.cx_px + 0.5) * k - 0.5],
            [0.0, camera.fy_px * k, (camera.cy_px + 0.5) * k - 0.5],
            [0.0, 0.0, 1.0],
        ]
    )
    big = np.full((camera.height_px * k, camera.width_px * k), 255, dtype=np.uint8)
    # Squares run from corner -1 to corner cols (rows): (cols + 1) x (rows + 1) squares.
    for a in range(-1, board.cols):
        for b in range(-1, board.rows):
            if (a + b) % 2:
                continue
            square = np.array(
                [[a, b, 0], [a + 1, b, 0], [a + 1, b + 1, 0], [a, b + 1, 0]], dtype=np.float64
            )
            px, _ = cv2.projectPoints(square * s, rvec, tvec, K_big, None)
            fixed = np.round(px.reshape(-1, 2) * 16).astype(np.int32)  # 4 fractional bits
            cv2.fillConvexPoly(big, fixed, 0, lineType=cv2.LINE_AA, shift=4)
    small = cv2.resize(big, (camera.width_px, camera.height_px), interpolation=cv2.INTER_AREA)
    return np.asarray(small, dtype=np.uint8)


@pytest.fixture(scope="module")
def views() -> list[tuple[str, npt.NDArray[np.uint8]]]:
    return [(f"view{k}.png", render_view(TRUE, BOARD, pose)) for k, pose in enumerate(POSES)]


def test_a_known_camera_is_recovered_from_rendered_views(
    views: list[tuple[str, npt.NDArray[np.uint8]]],
) -> None:
    result = calibrate_chessboard(views, BOARD)
    i = result.intrinsics
    assert (i.width_px, i.height_px) == (TRUE.width_px, TRUE.height_px)
    assert i.fx_px == pytest.approx(TRUE.fx_px, rel=0.01)
    assert i.fy_px == pytest.approx(TRUE.fy_px, rel=0.01)
    assert i.cx_px == pytest.approx(TRUE.cx_px, rel=0.01)
    assert i.cy_px == pytest.approx(TRUE.cy_px, rel=0.01)
    assert len(i.distortion) == 5
    assert abs(i.distortion[0]) < 0.05  # rendered without distortion
    assert result.rms_reprojection_px < 0.3
    assert len(result.used) == len(POSES) and not result.skipped
    for view in result.used:
        assert view.corners_px is not None and view.corners_px.shape == (54, 2)
        assert view.reprojection_rms_px is not None and view.reprojection_rms_px < 0.5


def test_the_corners_found_lie_where_the_camera_projects_them(
    views: list[tuple[str, npt.NDArray[np.uint8]]],
) -> None:
    # Front-on view: the corner grid is centred on the principal point, rows left to right.
    result = calibrate_chessboard(views, BOARD)
    corners = result.views[0].corners_px
    assert corners is not None
    assert corners.mean(axis=0) == pytest.approx([TRUE.cx_px, TRUE.cy_px], abs=0.3)
    pitch_px = TRUE.fx_px * BOARD.square_m / POSES[0][3]
    assert np.diff(corners[:9, 0]) == pytest.approx(np.full(8, pitch_px), abs=0.3)


def test_views_without_the_board_or_of_another_size_are_listed_and_skipped(
    views: list[tuple[str, npt.NDArray[np.uint8]]],
) -> None:
    blank = np.full((TRUE.height_px, TRUE.width_px), 128, dtype=np.uint8)
    other_size = cv2.resize(views[0][1], (320, 240))
    result = calibrate_chessboard([*views, ("blank.png", blank), ("small.png", other_size)], BOARD)
    assert {v.name: v.skipped for v in result.skipped} == {
        "blank.png": "9x6 board not found",
        "small.png": "320x240, not the 640x480 of most views",
    }
    assert len(result.used) == len(POSES)
    assert result.intrinsics.fx_px == pytest.approx(TRUE.fx_px, rel=0.01)


def test_fewer_than_three_usable_views_is_an_error_listing_the_skipped_ones(
    views: list[tuple[str, npt.NDArray[np.uint8]]],
) -> None:
    blank = np.zeros((TRUE.height_px, TRUE.width_px), dtype=np.uint8)
    with pytest.raises(ValueError, match=r"at least 3 views .* got 2 of 3 .*blank.png: 9x6 board"):
        calibrate_chessboard([*views[:2], ("blank.png", blank)], BOARD)


def test_no_views_and_colour_images_are_refused() -> None:
    with pytest.raises(ValueError, match="at least 3 chessboard images, got none"):
        calibrate_chessboard([], BOARD)
    colour = np.zeros((4, 4, 3), dtype=np.uint8)
    with pytest.raises(ValueError, match=r"c.png: expected an \(H, W\) uint8 grey image"):
        calibrate_chessboard([("c.png", colour)], BOARD)


def test_a_tie_between_image_sizes_is_an_error_naming_them() -> None:
    a = np.zeros((10, 20), dtype=np.uint8)
    b = np.zeros((20, 10), dtype=np.uint8)
    with pytest.raises(ValueError, match=r"20x10 \(1 views\), 10x20 \(1 views\)"):
        calibrate_chessboard([("a", a), ("b", b)], BOARD)


@pytest.mark.parametrize("text", ["9", "9x", "x6", "9*6", "1x6", "nine by six"])
def test_a_bad_board_text_is_refused(text: str) -> None:
    with pytest.raises(ValueError, match="board: expected"):
        Chessboard.from_text(text)


def test_board_text_and_object_points() -> None:
    board = Chessboard.from_text(" 4X3 ", 0.5)
    assert (board.cols, board.rows, board.square_m) == (4, 3, 0.5)
    pts = board.object_points_m()
    assert pts.shape == (12, 3) and pts.dtype == np.float32
    assert pts[1].tolist() == [0.5, 0.0, 0.0]  # along a row first
    assert pts[4].tolist() == [0.0, 0.5, 0.0]
    with pytest.raises(ValueError, match="square_m"):
        Chessboard(9, 6, square_m=0.0)


def test_the_real_udacity_chessboard_set(realdata: Path) -> None:
    folder = realdata / "udacity-highway" / "chessboard"
    result = calibrate_chessboard(read_views(folder), Chessboard(9, 6))
    i = result.intrinsics
    # The README's figures, within a few per cent.
    assert i.fx_px == pytest.approx(1157.0, rel=0.02)
    assert i.fy_px == pytest.approx(1152.0, rel=0.02)
    assert i.cx_px == pytest.approx(675.0, rel=0.02)
    assert i.cy_px == pytest.approx(387.0, rel=0.02)
    assert i.distortion[0] == pytest.approx(-0.27, rel=0.1)
    assert result.rms_reprojection_px < 1.5
    assert (i.width_px, i.height_px) == (1280, 720)
    # 20 views: three do not show all 9x6 corners, two are 1281x721.
    assert len(result.views) == 20 and len(result.used) == 15
    assert {v.name for v in result.skipped} == {
        "calibration1.jpg",
        "calibration4.jpg",
        "calibration5.jpg",
        "calibration7.jpg",
        "calibration15.jpg",
    }


def test_camera_info_round_trip(tmp_path: Path) -> None:
    intrinsics = Intrinsics(
        1157.5, 1152.25, 675.5, 387.25, 1280, 720, (-0.27, 0.1, 0.001, -0.002, 0.03)
    )
    path = tmp_path / "camera_info.yaml"
    save_camera_info(intrinsics, path, camera_name="front")
    assert load_camera_info(path) == intrinsics
    text = path.read_text()
    for key in (
        "image_width: 1280",
        "camera_name: front",
        "distortion_model: plumb_bob",
        "rectification_matrix:",
        "projection_matrix:",
    ):
        assert key in text


def test_camera_info_without_distortion_reads_as_none(tmp_path: Path) -> None:
    path = tmp_path / "c.yaml"
    save_camera_info(Intrinsics(500.0, 500.0, 320.0, 240.0, 640, 480), path)
    assert load_camera_info(path).distortion == ()
    assert "data: [0.0, 0.0, 0.0, 0.0, 0.0]" in path.read_text()


HEAD = "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [1, 0, 2, 0, 1, 2, 0, 0, 1]}"


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("image_width: 640\nimage_height: 480\n", "camera_matrix: missing key"),
        (
            "image_width: 640\nimage_height: 480\ncamera_matrix: {data: [1, 0, 2, 0, 1, 2, 0, 0]}",
            "camera_matrix.data: expected a list of 9 numbers",
        ),
        (
            HEAD
            + "\ndistortion_model: equidistant\ndistortion_coefficients: {data: [0.1, 0, 0, 0]}",
            "distortion_model: expected plumb_bob or rational_polynomial, got 'equidistant'",
        ),
        (
            HEAD + "\ndistortion_coefficients: {data: [0.1, 0.2, 0.3]}",
            "distortion_coefficients.data: expected 4 or 5 coefficients for plumb_bob",
        ),
        (
            HEAD + "\nlens: wide",
            "lens: unknown key",
        ),
        (
            "image_width: 0\nimage_height: 480\ncamera_matrix: {data: [1, 0, 2, 0, 1, 2, 0, 0, 1]}",
            "image size > 0",
        ),
    ],
)
def test_bad_camera_info_names_the_file_and_key(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(RecordingError, match=r"bad\.yaml") as err:
        load_camera_info(path)
    assert message in str(err.value)


def test_read_views_refuses_a_missing_or_empty_folder_and_undecodable_files(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="nowhere: expected a folder of chessboard images"):
        read_views(tmp_path / "nowhere")
    with pytest.raises(ValueError, match="found none"):
        read_views(tmp_path)
    (tmp_path / "broken.png").write_bytes(b"not a png")
    with pytest.raises(ValueError, match=r"broken\.png: cannot decode the image"):
        read_views(tmp_path)


def test_read_views_in_natural_order_and_grey(tmp_path: Path) -> None:
    for name in ("v10.png", "v2.jpg", "v1.png", "notes.txt"):
        if name.endswith(".txt"):
            (tmp_path / name).write_text("x")
        else:
            cv2.imwrite(str(tmp_path / name), np.zeros((4, 6, 3), dtype=np.uint8))
    views = read_views(tmp_path)
    assert [name for name, _ in views] == ["v1.png", "v2.jpg", "v10.png"]
    assert all(img.shape == (4, 6) and img.dtype == np.uint8 for _, img in views)


def test_cli_calibrates_prints_and_writes_camera_info(
    tmp_path: Path,
    views: list[tuple[str, npt.NDArray[np.uint8]]],
    capsys: pytest.CaptureFixture[str],
) -> None:
    folder = tmp_path / "board"
    folder.mkdir()
    for name, img in views:
        cv2.imwrite(str(folder / name), img)
    cv2.imwrite(str(folder / "empty.png"), np.full((480, 640), 200, dtype=np.uint8))
    out = tmp_path / "camera_info.yaml"
    assert (
        main(["calibrate", str(folder), "--board", "9x6", "--square-m", "0.1", "--out", str(out)])
        == 0
    )
    printed = capsys.readouterr().out
    assert "views used: 8 of 9" in printed
    assert "skipped: empty.png: 9x6 board not found" in printed
    assert "RMS reprojection error:" in printed and "k1 " in printed
    written = load_camera_info(out)
    assert written.fx_px == pytest.approx(TRUE.fx_px, rel=0.01)
    assert f"fx, fy: {written.fx_px:.2f}, {written.fy_px:.2f} px" in printed
    assert f"cx, cy: {written.cx_px:.2f}, {written.cy_px:.2f} px" in printed


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--board", "9by6"], "board: expected COLSxROWS"),
        (["--board", "9x6", "--out", "/nonexistent-dir/c.yaml"], "--out /nonexistent-dir/c.yaml"),
    ],
)
def test_cli_bad_calibrate_input_exits_2_with_a_message(
    tmp_path: Path, extra: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["calibrate", str(tmp_path), *extra]) == 2
    err = capsys.readouterr().err
    assert err.startswith("fusionscope calibrate: ") and message in err


def test_cli_calibrate_on_a_folder_without_boards_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    for k in range(3):
        cv2.imwrite(str(tmp_path / f"{k}.png"), np.full((48, 64), 90, dtype=np.uint8))
    assert (
        main(["calibrate", str(tmp_path), "--board", "9x6", "--out", str(tmp_path / "c.yaml")]) == 2
    )
    err = capsys.readouterr().err
    assert "got 0 of 3" in err and "0.png: 9x6 board not found" in err
    assert not (tmp_path / "c.yaml").exists()
