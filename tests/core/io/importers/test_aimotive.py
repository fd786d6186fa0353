"""core.io.importers.aimotive: `fusionscope import aimotive` on the real night-motorway sample.

The sample (../shared/realdata/aimotive-night-motorway, aiMotive Multimodal Dataset,
CC BY-NC-SA 4.0) is read where it is; imports and damaged copies go to tmp_path only, never
into the repository.

Besides the import itself, this file measures what aimotive.py's Notes state: that the
radar's elevation puts the points on vehicles worse than range and azimuth on a flat road,
and that the images are undistorted at import.
"""

from __future__ import annotations

import json
import math
import shutil
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import numpy.typing as npt
import pytest

from core.cli import main
from core.io.drive import Drive
from core.io.importers.pose import quaternion_matrix, yaw_rad
from core.io.importers.truth3d import RADAR_MARGIN_M, Box3D

SEQUENCE = "aimotive-night-motorway"
CAMERA = "F_MIDLONGRANGECAM_CL"
RADAR = "F_LRR_C"
VEHICLES = ("car", "van", "truck")
FLAT_HEIGHT_M = 0.5  # radar points drawn this high above the road when the elevation is ignored
BOX = "BoundingBox3D "
FloatArray = npt.NDArray[np.float64]


def _main_printing(args: list[str], where: Path) -> tuple[int, str]:
    """core.cli.main's exit code and what it printed (module-scoped fixtures have no capsys)."""
    import contextlib

    with where.open("w") as f, contextlib.redirect_stdout(f):
        code = main(args)
    return code, where.read_text()


@pytest.fixture(scope="module")
def imported(realdata: Path, tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, str]:
    """The sequence imported through the CLI: the folder and what the CLI printed."""
    root = tmp_path_factory.mktemp("aimotive")
    out = root / "night"
    code, printed = _main_printing(
        ["import", "aimotive", str(realdata / SEQUENCE), str(out)], root / "stdout.txt"
    )
    assert code == 0
    return out, printed


def _frame_ids(sequence: Path) -> list[str]:
    """The sequence's frame ids in time order, as the recording's frames are."""
    folder = sequence / "sensor" / "camera" / CAMERA
    return sorted(p.stem.rsplit("_", 1)[1] for p in folder.glob(f"{CAMERA}_*.jpg"))


def _inside(uv: FloatArray, in_front: npt.NDArray[np.bool_], box: tuple[float, ...]) -> Any:
    u0, v0, u1, v1 = box
    return in_front & (uv[:, 0] >= u0) & (uv[:, 0] <= u1) & (uv[:, 1] >= v0) & (uv[:, 1] <= v1)


# --- the import --------------------------------------------------------------------------
def test_real_sequence_frames_speed_radar_and_truth(imported: tuple[Path, str]) -> None:
    out, printed = imported
    with Drive(out) as drive:
        assert len(drive) == 50
        assert drive.frame_rate_hz == pytest.approx(15.0, abs=0.1)
        for i in range(len(drive)):
            frame = drive.frame(i)
            # estimated from the radar's stationary returns (README: about 30 m/s)
            assert frame.speed_mps == pytest.approx(30.0, abs=0.5), (i, frame.speed_mps)
            assert frame.yaw_rate_radps == 0.0  # not recorded
            assert frame.radar, f"frame {i}: no radar targets"
            truth = drive.truth(i)
            assert truth is not None, f"frame {i}: no truth"
            assert math.isnan(truth.pitch_rad) and not truth.rails_labelled
            assert any(o.id == 3 and o.cls == "van" for o in truth.objects), f"frame {i}"
    assert "note: speed from the radar's stationary returns on 50 of 50 frames" in printed


def test_real_sequence_radar_points_fall_in_the_vehicles_boxes(
    imported: tuple[Path, str], report: Callable[[str], None]
) -> None:
    out, _ = imported
    seen = hit = 0
    with Drive(out) as drive:
        for i in range(len(drive)):
            truth = drive.truth(i)
            assert truth is not None
            pts = np.array([(t.x_m, t.y_m, FLAT_HEIGHT_M) for t in drive.frame(i).radar])
            uv, in_front = drive.camera.project(pts)
            for o in truth.objects:
                if o.cls in VEHICLES and o.radar_seen and 0 < o.position_m[0] <= 50:
                    seen += 1
                    hit += bool(_inside(uv, in_front, o.box_px).any())
    report(
        f"aiMotive night: {hit} of {seen} radar-seen vehicles within 50 m have a radar point "
        "in their box"
    )
    assert seen >= 40  # the van, on every frame
    assert hit >= 0.8 * seen


# --- the radar's elevation (aimotive.py Notes) --------------------------------------------
@dataclass
class _Placement:
    """How one way of placing the radar points lands on the vehicles they belong to."""

    vehicles_hit: int = 0
    points_in: int = 0
    below_px: list[float] = field(default_factory=list)  # v - box bottom, recording's px
    below_bottom_m: list[float] = field(default_factory=list)  # box bottom - z


def _measure_elevation(realdata: Path, out: Path) -> tuple[int, int, dict[str, _Placement]]:
    """Radar points on each radar-seen vehicle (not hidden, ahead) placed three ways: flat at
    FLAT_HEIGHT_M; at the mount's height + range sin(elevation); and through the mount's
    full rotation (RT_body_from_sensor, which also tilts the radar). (vehicles, points, by way)."""
    sequence = realdata / SEQUENCE
    cal = json.loads((sequence / "sensor" / "calibration" / "calibration.json").read_text())
    M_radar = np.asarray(cal[RADAR]["RT_body_from_sensor"], dtype=np.float64)
    ways = {"flat": _Placement(), "elevation": _Placement(), "elevation+tilt": _Placement()}
    vehicles = points = 0
    with Drive(out) as drive:
        camera, mount = drive.camera, drive.calibration.radar_mount
        # the recording's vehicle frame is the body frame lowered to the road
        ground_m = float(cal[CAMERA]["RT_body_from_sensor"][2][3]) - camera.extrinsics.height_m
        for i, fid in enumerate(_frame_ids(sequence)):
            raw = json.loads(
                (sequence / "sensor" / "radar" / RADAR / f"{RADAR}_{fid}.json").read_text()
            )
            r, az, el = (
                np.array([t[k] for t in raw["targets"]]) for k in ("range", "azimuth", "elevation")
            )
            x = mount.x_m + r * np.cos(az + mount.yaw_rad)
            y = mount.y_m + r * np.sin(az + mount.yaw_rad)
            in_sensor = np.stack(
                [r * np.cos(el) * np.cos(az), r * np.cos(el) * np.sin(az), r * np.sin(el)], axis=1
            )
            tilted = in_sensor @ M_radar[:3, :3].T + M_radar[:3, 3]
            z_by_way = {
                "flat": np.full(len(r), FLAT_HEIGHT_M),
                "elevation": mount.z_m + r * np.sin(el),
                "elevation+tilt": tilted[:, 2] - ground_m,
            }
            labels = json.loads(
                (sequence / "dynamic" / "box" / "3d_body" / f"frame_{fid}.json").read_text()
            )
            by_id = {int(o["ObjectId"]): o for o in labels["CapturedObjects"]}
            truth = drive.truth(i)
            assert truth is not None
            for o in truth.objects:
                if not (
                    o.cls in VEHICLES and o.radar_seen and o.occlusion < 0.5 and o.position_m[0] > 0
                ):
                    continue
                label = by_id[o.id]
                box = Box3D(
                    id=o.id,
                    cls=o.cls,
                    centre_m=(
                        float(label[f"{BOX}Origin X"]),
                        float(label[f"{BOX}Origin Y"]),
                        float(label[f"{BOX}Origin Z"]) - ground_m,
                    ),
                    size_m=(
                        float(label[f"{BOX}Extent X"]),
                        float(label[f"{BOX}Extent Y"]),
                        float(label[f"{BOX}Extent Z"]),
                    ),
                    yaw_rad=yaw_rad(
                        quaternion_matrix([label[f"{BOX}Orientation Quat {a}"] for a in "WXYZ"])
                    ),
                    velocity_mps=(0.0, 0.0),
                    hidden=0.0,
                )
                on = box.contains_xy(np.stack([x, y], axis=1), RADAR_MARGIN_M)
                assert on.any(), f"frame {i}: object {o.id} is radar-seen, no raw point is on it"
                vehicles += 1
                points += int(on.sum())
                bottom_m = box.centre_m[2] - box.size_m[2] / 2
                for way, z in z_by_way.items():
                    uv, in_front = camera.project(np.stack([x[on], y[on], z[on]], axis=1))
                    inside = _inside(uv, in_front, o.box_px)
                    ways[way].vehicles_hit += bool(inside.any())
                    ways[way].points_in += int(inside.sum())
                    ways[way].below_px += (uv[:, 1] - o.box_px[3]).tolist()
                    ways[way].below_bottom_m += (bottom_m - z[on]).tolist()
    return vehicles, points, ways


def test_radar_elevation_puts_points_on_vehicles_worse_than_a_flat_road(
    imported: tuple[Path, str], realdata: Path, report: Callable[[str], None]
) -> None:
    out, _ = imported
    vehicles, points, ways = _measure_elevation(realdata, out)
    with Drive(out) as drive:
        cal = json.loads(
            (realdata / SEQUENCE / "sensor" / "calibration" / "calibration.json").read_text()
        )
        to_source = cal[CAMERA]["image_resolution_px"][0] / drive.camera.intrinsics.width_px
    width = cal[CAMERA]["image_resolution_px"][0]
    for way, p in ways.items():
        px = np.percentile(p.below_px, [10, 50, 90]) * to_source
        report(
            f"aiMotive radar {way}: {p.vehicles_hit} of {vehicles} vehicles and {p.points_in} "
            f"of {points} points in their box; below the box bottom (negative: above) by a "
            f"median {np.median(p.below_bottom_m):.2f} m, {px[1]:.0f} px (10-90 %: {px[0]:.0f} "
            f"to {px[2]:.0f} px, in the source's {width} px)"
        )
    flat, elevation, tilted = ways["flat"], ways["elevation"], ways["elevation+tilt"]
    # measured: 119 vehicles, 193 points; flat 115 and 188 in their box; elevation 64 and 83;
    # elevation through the tilted mount 18 and 21
    assert vehicles >= 100
    assert flat.vehicles_hit >= 0.95 * vehicles and flat.points_in >= 0.95 * points
    for worse in (elevation, tilted):
        assert worse.vehicles_hit < 0.7 * flat.vehicles_hit
        assert worse.points_in < 0.5 * flat.points_in
    # the Notes' figures: through the mount's rotation the points lie about 0.95 m below the
    # box bottoms, a median 16 px (90 %: 36 px) below them at the source's 1280 px; taken as
    # mount height + range sin(elevation), 0.2 m below, scattered about the bottom edge
    assert np.median(tilted.below_bottom_m) == pytest.approx(0.95, abs=0.1)
    assert np.median(tilted.below_px) * to_source == pytest.approx(16, abs=3)
    assert np.percentile(tilted.below_px, 90) * to_source == pytest.approx(36, abs=4)
    assert np.median(elevation.below_bottom_m) == pytest.approx(0.2, abs=0.1)
    assert abs(np.median(elevation.below_px) * to_source) < 5
    # flat, the points sit inside the boxes, above their bottoms
    assert np.percentile(flat.below_px, 90) < 0


# --- undistortion ---------------------------------------------------------------------------
def _distort_u(u_px: float, v_px: float, cam: dict[str, Any]) -> float:
    """Column (source px) at which the lens images the ideal pinhole pixel (u, v): OpenCV's
    model (Brown-Conrady: k1 k2 p1 p2 k3)."""
    fx, fy = cam["focal_length_px"]
    cx, cy = cam["principal_point_px"]
    k1, k2, p1, p2, k3 = cam["distortion_coeffs"]
    x, y = (u_px - cx) / fx, (v_px - cy) / fy
    r2 = x * x + y * y
    xd = x * (1 + k1 * r2 + k2 * r2**2 + k3 * r2**3) + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    return float(cx + fx * xd)


def test_images_are_undistorted(imported: tuple[Path, str], realdata: Path) -> None:
    """The recording's camera is a pinhole; its first image agrees with a plain grey resize of
    the JPEG at the centre, and at the side edges matches it shifted outwards by what the
    lens model says (barrel distortion pulls the edges in)."""
    out, _ = imported
    sequence = realdata / SEQUENCE
    cam = json.loads((sequence / "sensor" / "calibration" / "calibration.json").read_text())[CAMERA]
    assert cam["distortion_coeffs"][0] == pytest.approx(-0.30, abs=0.01)  # the source's lens
    jpeg = sequence / "sensor" / "camera" / CAMERA / f"{CAMERA}_{_frame_ids(sequence)[0]}.jpg"
    source = cv2.imread(str(jpeg), cv2.IMREAD_GRAYSCALE)
    assert source is not None
    with Drive(out) as drive:
        assert drive.camera.intrinsics.distortion == ()
        image = drive.frame(0).image.astype(np.float64)
        height, width = image.shape
    plain = cv2.resize(source, (width, height), interpolation=cv2.INTER_AREA).astype(np.float64)
    scale = source.shape[1] / width

    def differ(cols: slice, rows: slice = slice(None)) -> float:
        return float(np.abs(image[rows, cols] - plain[rows, cols]).mean())

    centre = differ(
        slice(width // 2 - 40, width // 2 + 40), slice(height // 2 - 40, height // 2 + 40)
    )
    assert centre < 1.0  # measured 0.19
    assert differ(slice(0, 40)) > 5.0 and differ(slice(width - 40, width)) > 5.0  # 14, 11

    # along the principal point's row, each side strip matches the plain image moved outwards
    v = cam["principal_point_px"][1]
    rows = slice(round(v / scale) - 16, round(v / scale) + 16)
    for first in (10, width - 40):
        cols = slice(first, first + 30)
        u = (first + 15 + 0.5) * scale - 0.5  # the strip's centre column in source px
        expected = (u - _distort_u(u, v, cam)) / scale  # shift in the recording's px
        errors = {
            s: float(np.abs(image[rows, cols] - plain[rows, first - s : first + 30 - s]).mean())
            for s in range(round(expected) - 8, round(expected) + 9)
        }
        best = min(errors, key=lambda s: errors[s])
        assert abs(expected) > 15  # measured: 20.6 px right, -20.1 px left
        assert best == pytest.approx(expected, abs=1.5), (first, expected, errors)


# --- bad inputs ------------------------------------------------------------------------------
@pytest.fixture
def copy(realdata: Path, tmp_path: Path) -> Path:
    """A copy of the sequence (camera, front radar, calibration, labels) to damage."""
    target = tmp_path / "sequence" / SEQUENCE
    shutil.copytree(realdata / SEQUENCE, target, ignore=shutil.ignore_patterns("B_LRR_C"))
    return target


def _fails(copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], *extra: str) -> str:
    out = tmp_path / "out" / "night"
    assert main(["import", "aimotive", str(copy), str(out), *extra]) == 2
    assert not out.exists()
    assert not out.parent.exists() or list(out.parent.iterdir()) == []  # no partial folder
    err = capsys.readouterr().err
    assert err.startswith("fusionscope import aimotive: ")
    return err


def test_sensor_not_in_the_calibration(
    copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    err = _fails(copy, tmp_path, capsys, "--radar", "NOPE")
    calibration = copy / "sensor" / "calibration" / "calibration.json"
    assert (
        f"{calibration}: no sensor 'NOPE'; the sensors there: B_LRR_C, B_MIDRANGECAM_C, F_LRR_C"
        in err
    )


def test_damaged_radar_file(copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    scan = copy / "sensor" / "radar" / RADAR / f"{RADAR}_{_frame_ids(copy)[7]}.json"
    scan.write_bytes(scan.read_bytes()[:200])
    err = _fails(copy, tmp_path, capsys)
    assert f"{scan}: radar detection list is not valid JSON" in err


def test_label_with_nan_is_left_out_and_noted(
    copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    fid = _frame_ids(copy)[4]
    path = copy / "dynamic" / "box" / "3d_body" / f"frame_{fid}.json"
    labels = json.loads(path.read_text())
    (van,) = [o for o in labels["CapturedObjects"] if o["ObjectId"] == 3]
    van[f"{BOX}Origin X"] = math.nan
    path.write_text(json.dumps(labels))  # Python's json writes NaN, and reads it back
    out = tmp_path / "out" / "night"
    assert main(["import", "aimotive", str(copy), str(out)]) == 0
    printed = capsys.readouterr().out
    assert f"note: 1 labels that cannot be used, left out: {path}: object 3: " in printed
    with Drive(out) as drive:
        truth = drive.truth(4)
        assert truth is not None and 3 not in {o.id for o in truth.objects}
        other = drive.truth(5)
        assert other is not None and 3 in {o.id for o in other.objects}
    assert list(out.parent.iterdir()) == [out]


def test_no_label_files(copy: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    folder = copy / "dynamic" / "box" / "3d_body"
    for path in folder.glob("frame_*.json"):
        path.unlink()
    err = _fails(copy, tmp_path, capsys)
    assert f"{folder}: no frame_<id>.json: their Timestamp is the sequence's only clock" in err
