"""Render a synthetic scene through the camera model: grey image, object-label image, truth.

The road is a textured flat world looked up per pixel through the camera's ray / road-plane
intersection (the same `CameraModel` the engine uses, with this frame's true pitch), so a
ground-truth box projects exactly where the object was drawn. Objects are planar faces
(vehicle boxes, pedestrian and pole billboards, guard-rail beam pieces) drawn far to near.

Texture sampling is anisotropic: the road texture is tabulated in road coordinates and
pre-filtered along s in levels of doubling footprint; each pixel reads the level matching
its footprint (distance^2 / (fy * height)), so lane dashes do not flicker far away.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.groundtruth import TruthGuardRail, TruthObject
from core.synth.scene import Pedestrian, Scene, StaticObject, Trajectory, Vehicle

FloatArray = npt.NDArray[np.float64]

TEXTURE_S_M = 0.05  # texture cell along s
TEXTURE_D_M = 0.1  # texture cell across the road
TEXTURE_D_RANGE_M = (-45.0, 45.0)
TEXTURE_LEVELS = 9  # each level doubles the cell along s
GATHER_BAND_ROWS = 16384  # texture rows handed to cv2.remap at once (it takes < 32767)
MARKING_GREY = 210
DASH_ON_M, DASH_PERIOD_M = 4.5, 12.0
ZEBRA_DEPTH_M, ZEBRA_BAR_M = 3.0, 0.5
FAR_LIMIT_M = 600.0  # ground beyond this fades into the horizon haze
HAZE_GREY = 165.0
HAZE_DISTANCE_M = 350.0
SKY_TOP_GREY, SKY_HORIZON_GREY = 185.0, 225.0
NEAR_PLANE_M = 0.3  # polygons are clipped this far in front of the camera
DRAW_RANGE_M = 160.0  # objects farther than this are not drawn
SUBPIXEL_SHIFT = 4  # cv2 fixed-point bits for polygon vertices
MIN_VISIBLE_PX = 12  # objects with fewer visible pixels are left out of the truth
RAIL_Z_M = (0.45, 0.77)  # W-beam bottom and top above the road
RAIL_POST_SPACING_M = 2.0
RAIL_TRUTH_STEP = 4  # truth polyline: every 4th 1-m sample of the beam
WALK_STEP_M = 1.4  # a stride, for the leg swing phase

Polygon = npt.NDArray[np.float64]  # (N, 3) vehicle-frame vertices


@dataclass(frozen=True)
class Pose:
    """Ego pose at one time: world position of the vehicle-frame origin and heading."""

    s_m: float
    x_m: float
    y_m: float
    heading_rad: float

    def to_vehicle(self, X: npt.ArrayLike, Y: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        dx = np.asarray(X, dtype=np.float64) - self.x_m
        dy = np.asarray(Y, dtype=np.float64) - self.y_m
        c, s = math.cos(self.heading_rad), math.sin(self.heading_rad)
        return c * dx + s * dy, -s * dx + c * dy


def ego_pose(scene: Scene, t_s: float) -> Pose:
    s, d = scene.ego.at(t_s)
    X, Y = scene.road.to_world(s, d)
    return Pose(s, float(X), float(Y), float(scene.road.heading(s)))


@dataclass(frozen=True, eq=False)
class RenderedFrame:
    """image: (H, W) uint8 before sensor noise; labels: (H, W) uint16 object id per pixel
    (0 = road, sky and background); objects and guard_rails: the truth of this frame."""

    image: npt.NDArray[np.uint8]
    labels: npt.NDArray[np.uint16]
    objects: tuple[TruthObject, ...]
    guard_rails: tuple[TruthGuardRail, ...]


@dataclass(frozen=True, eq=False)
class RadarView:
    """What the radar can know of a drawn object: nearest face centre (3,) in the vehicle
    frame, the visible fraction of its silhouette, its velocity over ground (2,) in ego axes."""

    near_m: FloatArray
    visible_fraction: float
    velocity_mps: FloatArray


# class, nearest face centre (3,), box corners (N, 3), size (l, w, h), velocity (2,)
_Geometry = tuple[str, FloatArray, FloatArray, tuple[float, float, float], FloatArray]


@dataclass
class _Drawable:
    distance_m: float
    object_id: int
    faces: list[tuple[Polygon, float]]  # (polygon, grey)


# --- the road texture ----------------------------------------------------------------------


def _smooth_noise(
    rng: np.random.Generator, shape: tuple[int, int], cell: tuple[int, int]
) -> npt.NDArray[np.float32]:
    """Zero-mean, unit-ish noise with blobs about `cell` texture cells big."""
    coarse = rng.standard_normal((shape[0] // cell[0] + 2, shape[1] // cell[1] + 2)).astype(
        np.float32
    )
    big = cv2.resize(
        coarse,
        (coarse.shape[1] * cell[1], coarse.shape[0] * cell[0]),
        interpolation=cv2.INTER_CUBIC,
    )
    return np.asarray(big[: shape[0], : shape[1]], dtype=np.float32)


class RoadTexture:
    """Ground brightness tabulated over road coordinates, in pre-filtered levels."""

    def __init__(
        self, scene: Scene, s_range_m: tuple[float, float], rng: np.random.Generator
    ) -> None:
        self.s0_m = s_range_m[0]
        self.d0_m = TEXTURE_D_RANGE_M[0]
        rows = int((s_range_m[1] - s_range_m[0]) / TEXTURE_S_M)
        cols = int((TEXTURE_D_RANGE_M[1] - TEXTURE_D_RANGE_M[0]) / TEXTURE_D_M)
        s = self.s0_m + (np.arange(rows, dtype=np.float32) + 0.5) * TEXTURE_S_M
        d = self.d0_m + (np.arange(cols, dtype=np.float32) + 0.5) * TEXTURE_D_M
        base = np.full((rows, cols), 90.0, dtype=np.float32)
        grain = np.zeros(cols, dtype=np.float32)
        for surf in scene.surfaces:
            inside = (d >= surf.d0_m) & (d < surf.d1_m)
            base[:, inside] = surf.grey
            grain[inside] = surf.texture * surf.grey
        fine = rng.standard_normal((rows, cols)).astype(np.float32) * 0.15
        mid = _smooth_noise(rng, (rows, cols), (20, 10))  # ~1 m blobs
        big = _smooth_noise(rng, (rows, cols), (120, 40))  # ~6 m blobs
        tex = base + grain[None, :] * (fine + 0.5 * mid + 0.45 * big)
        # Markings: solid and dashed lines along s, zebra crossings across.
        wear = 1.0 + 0.08 * mid
        for m in scene.markings:
            on_d = np.abs(d - m.d_m) <= m.width_m / 2
            if m.kind == "dashed":
                on_s = np.mod(s, DASH_PERIOD_M) < DASH_ON_M
                mask = on_s[:, None] & on_d[None, :]
            else:
                mask = np.broadcast_to(on_d[None, :], tex.shape)
            tex = np.where(mask, MARKING_GREY * wear, tex)
        road_d = next(surf for surf in scene.surfaces if surf.d0_m <= 0.0 < surf.d1_m)
        for sz in scene.crosswalks_s_m:
            on_s = (s >= sz) & (s < sz + ZEBRA_DEPTH_M)
            on_d = (
                (np.mod(d, 2 * ZEBRA_BAR_M) < ZEBRA_BAR_M)
                & (d > road_d.d0_m)
                & (d < road_d.d1_m + 2.2)
            )
            tex = np.where(on_s[:, None] & on_d[None, :], MARKING_GREY * wear, tex)
        # World-fixed patches: tree and bridge shadows, repairs.
        for p in scene.patches:
            r0 = max(int((p.s_m - p.length_m / 2 - self.s0_m) / TEXTURE_S_M), 0)
            r1 = min(int((p.s_m + p.length_m / 2 - self.s0_m) / TEXTURE_S_M) + 1, rows)
            if r1 <= r0:
                continue
            ss = s[r0:r1, None]
            if p.round_shape:
                wobble = 1.0 + 0.25 * mid[r0:r1, :]
                inside = ((ss - p.s_m) / (p.length_m / 2)) ** 2 + (
                    (d[None, :] - p.d_m) / (p.width_m / 2)
                ) ** 2 < wobble
            else:
                inside = np.broadcast_to(
                    np.abs(d[None, :] - p.d_m) < p.width_m / 2, (r1 - r0, cols)
                )
            soft = cv2.GaussianBlur(inside.astype(np.float32), (0, 0), 3.0)
            tex[r0:r1] *= 1.0 - (1.0 - p.factor) * soft
        self.levels = [np.clip(tex, 0, 255).astype(np.float32)]
        for _ in range(1, TEXTURE_LEVELS):
            prev = self.levels[-1]
            if prev.shape[0] < 4:
                break
            self.levels.append(
                cv2.resize(prev, (cols, prev.shape[0] // 2), interpolation=cv2.INTER_AREA)
            )

    def sample(
        self, s_m: FloatArray, d_m: FloatArray, footprint_m: FloatArray
    ) -> npt.NDArray[np.float32]:
        """Brightness at road points, filtered to the given footprint along s (all (N,))."""
        level = np.clip(
            np.floor(np.log2(np.maximum(footprint_m, TEXTURE_S_M) / TEXTURE_S_M)),
            0,
            len(self.levels) - 1,
        ).astype(int)
        out = np.empty(len(s_m), dtype=np.float32)
        col = ((d_m - self.d0_m) / TEXTURE_D_M - 0.5).astype(np.float32)
        for k in np.unique(level):
            sel = level == k
            row = ((s_m[sel] - self.s0_m) / (TEXTURE_S_M * 2**k) - 0.5).astype(np.float32)
            out[sel] = _gather(self.levels[k], col[sel], row)
        return out


def _gather(
    img: npt.NDArray[np.float32], col: npt.NDArray[np.float32], row: npt.NDArray[np.float32]
) -> npt.NDArray[np.float32]:
    """Bilinear samples of img at (col, row) (N,) with edge clamping, via cv2.remap.

    remap takes images under 32767 rows (SHRT_MAX) and a long drive's texture has more, so
    the samples go to it in bands of `GATHER_BAND_ROWS` rows, each with only the rows its
    samples fall between (and the clamped edge rows when a sample lies beyond one): the same
    samples.
    """
    out = np.empty(len(col), dtype=np.float32)
    last = img.shape[0] - 1
    band = np.clip(np.floor(row), 0, last).astype(np.int64) // GATHER_BAND_ROWS
    for b in np.unique(band):
        sel = band == b
        r0 = int(b) * GATHER_BAND_ROWS
        r1 = min(r0 + GATHER_BAND_ROWS + 1, last + 1)
        out[sel] = _remap(img[r0:r1], col[sel], row[sel] - np.float32(r0))
    return out


def _remap(
    img: npt.NDArray[np.float32], col: npt.NDArray[np.float32], row: npt.NDArray[np.float32]
) -> npt.NDArray[np.float32]:
    n = len(col)
    width = 1024
    h = (n + width - 1) // width
    mx = np.zeros(h * width, dtype=np.float32)
    my = np.zeros(h * width, dtype=np.float32)
    mx[:n], my[:n] = col, row
    res = cv2.remap(
        img,
        mx.reshape(h, width),
        my.reshape(h, width),
        cv2.INTER_LINEAR,
        borderMode=cv2.BORDER_REPLICATE,
    )
    return np.asarray(res, dtype=np.float32).ravel()[:n]


# --- geometry helpers ----------------------------------------------------------------------


def _clip_near(poly_cam: FloatArray) -> FloatArray:
    """Sutherland-Hodgman clip of a camera-frame polygon against z >= NEAR_PLANE_M."""
    out: list[FloatArray] = []
    n = len(poly_cam)
    for k in range(n):
        a, b = poly_cam[k], poly_cam[(k + 1) % n]
        a_in, b_in = a[2] >= NEAR_PLANE_M, b[2] >= NEAR_PLANE_M
        if a_in:
            out.append(a)
        if a_in != b_in:
            t = (NEAR_PLANE_M - a[2]) / (b[2] - a[2])
            out.append(a + t * (b - a))
    return np.array(out) if out else np.zeros((0, 3))


class _Projector:
    """Vehicle-frame polygons -> fixed-point pixel polygons for cv2.fillPoly."""

    def __init__(self, camera: CameraModel) -> None:
        T = camera.T_camera_vehicle
        self.R, self.t = T[:3, :3], T[:3, 3]
        self.K = camera.intrinsics.K

    def pixels(self, poly_vehicle: Polygon) -> npt.NDArray[np.int32] | None:
        pc = _clip_near(poly_vehicle @ self.R.T + self.t)
        if len(pc) < 3:
            return None
        uv = (pc @ self.K.T)[:, :2] / pc[:, 2:3]
        return np.round(uv * (1 << SUBPIXEL_SHIFT)).astype(np.int32)


def _clip_segment(
    p0: FloatArray, p1: FloatArray, width: int, height: int
) -> tuple[FloatArray, FloatArray] | None:
    """Liang-Barsky clip of segment p0-p1 to the image's pixel area, or None when outside."""
    lo, hi = np.array([-0.5, -0.5]), np.array([width - 0.5, height - 0.5])
    d = p1 - p0
    t0, t1 = 0.0, 1.0
    for k in range(2):
        for p, q in ((-d[k], p0[k] - lo[k]), (d[k], hi[k] - p0[k])):
            if p == 0:
                if q < 0:
                    return None
                continue
            t = q / p
            if p < 0:
                t0 = max(t0, t)
            else:
                t1 = min(t1, t)
    if t0 > t1:
        return None
    return p0 + t0 * d, p0 + t1 * d


def _clip_polyline(uv: FloatArray, width: int, height: int) -> tuple[tuple[float, float], ...]:
    """The part of an (N, 2) pixel polyline inside the image, cut at its border."""
    out: list[tuple[float, float]] = []
    for a, b in itertools.pairwise(uv):
        clipped = _clip_segment(a, b, width, height)
        if clipped is None:
            continue
        for q in clipped:
            point = (float(q[0]), float(q[1]))
            if not out or np.hypot(point[0] - out[-1][0], point[1] - out[-1][1]) > 1e-6:
                out.append(point)
    return tuple(out)


def _face_points(
    center: FloatArray, right: FloatArray, pts_az: Iterable[tuple[float, float]]
) -> Polygon:
    """Points (a along `right`, z up) on a vertical face through `center` (x, y, 0)."""
    return np.array([[center[0] + a * right[0], center[1] + a * right[1], z] for a, z in pts_az])


def _rect(a0: float, a1: float, z0: float, z1: float) -> list[tuple[float, float]]:
    return [(a0, z0), (a1, z0), (a1, z1), (a0, z1)]


def _ellipse(ac: float, zc: float, ra: float, rz: float, n: int = 14) -> list[tuple[float, float]]:
    return [
        (ac + ra * math.cos(2 * math.pi * k / n), zc + rz * math.sin(2 * math.pi * k / n))
        for k in range(n)
    ]


def _mirror(
    parts: list[tuple[list[tuple[float, float]], float]],
) -> list[tuple[list[tuple[float, float]], float]]:
    """Each part and its mirror image about a = 0 (vehicles and people are symmetric)."""
    out = []
    for pts, grey in parts:
        out.append((pts, grey))
        out.append(([(-a, z) for a, z in pts], grey))
    return out


# --- the designs of faces, in face coordinates (a across, z up) ----------------------------


def _rear_design(v: Vehicle) -> list[tuple[list[tuple[float, float]], float]]:
    W, H, g = v.width_m, v.height_m, float(v.body_grey)
    hw = W / 2
    dark, tyre = 18.0, 28.0
    light = 0.5 * g + 70.0
    if v.cls == "truck":
        deck = 1.05
        parts = [
            (_rect(-hw + 0.1, hw - 0.1, 0.0, deck), dark),  # the road seen under the trailer
            (_rect(-hw, hw, deck, H), min(g + 25, 235)),  # trailer doors
            (_rect(-0.03, 0.03, deck + 0.1, H - 0.1), 0.5 * g),  # door split
            (_rect(-hw, hw, 0.45, 0.58), 35.0),  # underride bar
            (_rect(-1.2, 1.2, deck - 0.12, deck), 45.0),
        ]
        parts += _mirror(
            [
                (_rect(hw - 0.6, hw - 0.05, 0.0, 0.95), tyre),
                (
                    _rect(hw * 0.45 - 0.03, hw * 0.45 + 0.03, deck + 0.1, H - 0.1),
                    0.55 * g,
                ),  # lock bars
                (_rect(hw - 0.3, hw - 0.05, 0.8, 1.0), light),
            ]
        )
        return parts
    roof = H
    shoulder = 0.62 * H if v.cls == "car" else 0.5 * H
    parts = [
        (_rect(-hw * 0.92, hw * 0.92, 0.0, 0.3), dark),  # under the body: the dark gap
        (_rect(-hw, hw, 0.28, shoulder), g),
        ([(-hw, shoulder), (hw, shoulder), (hw * 0.86, roof), (-hw * 0.86, roof)], g),
        (_rect(-hw, hw, 0.28, 0.48), 0.55 * g + 10),  # bumper
        (_rect(-0.26, 0.26, 0.5, 0.62), 215.0),  # licence plate
        (
            [
                (-hw * 0.8, shoulder + 0.05),
                (hw * 0.8, shoulder + 0.05),
                (hw * 0.72, roof - 0.08),
                (-hw * 0.72, roof - 0.08),
            ],
            38.0,
        ),
    ]
    if v.cls == "van":
        parts.append((_rect(-0.025, 0.025, 0.5, roof - 0.05), 0.5 * g))
    parts += _mirror(
        [
            (_rect(hw - 0.27, hw - 0.03, 0.0, 0.33), tyre),
            (_rect(hw - 0.32, hw - 0.04, shoulder - 0.2, shoulder - 0.04), light),
        ]
    )
    return parts


def _front_design(v: Vehicle) -> list[tuple[list[tuple[float, float]], float]]:
    W, H, g = v.width_m, v.height_m, float(v.body_grey)
    hw = W / 2
    dark, tyre = 18.0, 28.0
    if v.cls == "truck":
        cab = 2.9
        parts = [
            (_rect(-hw + 0.1, hw - 0.1, 0.0, 0.6), dark),
            (_rect(-hw, hw, 0.5, H), g),
            (_rect(-hw + 0.15, hw - 0.15, 1.9, cab), 70.0),  # windscreen
            (_rect(-0.7, 0.7, 0.7, 1.7), 45.0),  # grille
        ]
        parts += _mirror(
            [
                (_rect(hw - 0.5, hw - 0.05, 0.0, 0.9), tyre),
                (_rect(hw - 0.45, hw - 0.1, 0.65, 0.85), 220.0),
            ]
        )
        return parts
    shoulder = 0.55 * H
    parts = [
        (_rect(-hw * 0.92, hw * 0.92, 0.0, 0.3), dark),
        (_rect(-hw, hw, 0.28, shoulder), g),
        ([(-hw, shoulder), (hw, shoulder), (hw * 0.84, H), (-hw * 0.84, H)], g),
        (_rect(-hw * 0.45, hw * 0.45, 0.32, 0.5), 40.0),  # grille
        (
            [
                (-hw * 0.82, shoulder + 0.04),
                (hw * 0.82, shoulder + 0.04),
                (hw * 0.7, H - 0.07),
                (-hw * 0.7, H - 0.07),
            ],
            75.0,
        ),
    ]
    parts += _mirror(
        [
            (_rect(hw - 0.26, hw - 0.03, 0.0, 0.33), tyre),
            (_rect(hw - 0.38, hw - 0.08, 0.52, 0.66), 215.0),
        ]
    )
    return parts


def _side_design(v: Vehicle) -> list[tuple[list[tuple[float, float]], float]]:
    L, H, g = v.length_m, v.height_m, 0.82 * float(v.body_grey)
    hl = L / 2
    if v.cls == "truck":
        parts = [
            (_rect(-hl, hl - 2.3, 1.05, H), min(g + 20, 230)),
            (_rect(hl - 2.2, hl, 0.5, 3.0), g),
            (_rect(hl - 1.4, hl - 0.1, 1.9, 2.8), 70.0),
        ]
        wheels = [hl - 1.2, -hl + 1.2, -hl + 2.5]
        radius = 0.5
    else:
        shoulder = 0.6 * H
        parts = [
            (_rect(-hl, hl, 0.28, shoulder), g),
            ([(-hl + 0.5, shoulder), (hl - 0.9, shoulder), (hl - 1.6, H), (-hl + 0.7, H)], g),
            (
                [
                    (-hl + 0.65, shoulder + 0.04),
                    (hl - 1.0, shoulder + 0.04),
                    (hl - 1.65, H - 0.07),
                    (-hl + 0.8, H - 0.07),
                ],
                45.0,
            ),
        ]
        wheels = [hl - 0.85, -hl + 0.85]
        radius = 0.32
    parts += [(_ellipse(a, radius, radius, radius), 26.0) for a in wheels]
    return parts


def _pedestrian_design(
    p: Pedestrian, phase: float
) -> list[tuple[list[tuple[float, float]], float]]:
    H = p.height_m
    hip, shoulder = 0.52 * H, 0.81 * H
    swing = 0.2 * math.sin(phase) * (H / 1.75)
    shirt, trousers = float(p.shirt_grey), float(p.trousers_grey)
    parts = []
    for side, sw in ((-1, swing), (1, -swing)):
        a_hip = side * 0.085 * H / 1.75
        parts.append(
            (
                [
                    (a_hip - 0.065, hip),
                    (a_hip + 0.065, hip),
                    (a_hip + sw + 0.055, 0.0),
                    (a_hip + sw - 0.055, 0.0),
                ],
                trousers,
            )
        )
        a_sh = side * 0.2 * H / 1.75
        parts.append(
            (
                [
                    (a_sh - 0.04, shoulder),
                    (a_sh + 0.04, shoulder),
                    (a_sh - 0.6 * sw + side * 0.03 + 0.035, 0.45 * H),
                    (a_sh - 0.6 * sw + side * 0.03 - 0.035, 0.45 * H),
                ],
                shirt * 0.9,
            )
        )
    w_sh, w_hip = 0.19 * H / 1.75, 0.155 * H / 1.75
    parts.append(
        ([(-w_hip, hip - 0.03), (w_hip, hip - 0.03), (w_sh, shoulder), (-w_sh, shoulder)], shirt)
    )
    parts.append((_rect(-0.05, 0.05, shoulder - 0.01, 0.87 * H), 120.0))
    parts.append((_ellipse(0.0, 0.935 * H, 0.095 * H / 1.75, 0.12 * H / 1.75), 110.0))
    parts.append((_ellipse(0.0, 0.97 * H, 0.09 * H / 1.75, 0.06 * H / 1.75), 40.0))  # hair
    return parts


def _static_design(o: StaticObject) -> list[tuple[list[tuple[float, float]], float]]:
    hw, H, g = o.width_m / 2, o.height_m, float(o.grey)
    if o.cls == "pole":
        return [(_rect(-hw, hw, 0.0, H), g), (_rect(-hw, hw + 1.2, H - 0.15, H), g * 0.8)]
    if o.cls == "tree":
        return [
            (_rect(-hw, hw, 0.0, 0.55 * H), g),
            (_ellipse(0.0, 0.75 * H, 0.3 * H, 0.3 * H, 18), g * 0.85),
        ]
    plate_h = min(1.4, 0.45 * H)
    if o.width_m > 1.0:  # a large sign on two posts
        return [
            (_rect(-hw * 0.7 - 0.05, -hw * 0.7 + 0.05, 0.0, H - plate_h), 120.0),
            (_rect(hw * 0.7 - 0.05, hw * 0.7 + 0.05, 0.0, H - plate_h), 120.0),
            (_rect(-hw, hw, H - plate_h, H), 60.0),
            (_rect(-hw + 0.06, hw - 0.06, H - plate_h + 0.06, H - 0.06), g),
        ]
    return [
        (_rect(-0.035, 0.035, 0.0, H - 2 * hw), 120.0),
        (_ellipse(0.0, H - hw, hw, hw, 16), 50.0),
        (_ellipse(0.0, H - hw, hw * 0.82, hw * 0.82, 16), g),
    ]


# --- the renderer --------------------------------------------------------------------------


class Renderer:
    """Renders one scene's frames; build once per drive (the texture is made here)."""

    def __init__(self, scene: Scene, camera: CameraModel, rng: np.random.Generator) -> None:
        self.scene = scene
        self.camera = camera
        s_lo = float(scene.ego.s_m.min()) - 60.0
        s_hi = float(scene.ego.s_m.max()) + FAR_LIMIT_M
        self.texture = RoadTexture(scene, (s_lo, s_hi), rng)
        i = camera.intrinsics
        self.shape = (i.height_px, i.width_px)
        u, v = np.meshgrid(
            np.arange(i.width_px, dtype=np.float64), np.arange(i.height_px, dtype=np.float64)
        )
        self.rays_cam = np.stack(
            [(u - i.cx_px) / i.fx_px, (v - i.cy_px) / i.fy_px, np.ones_like(u)], axis=-1
        ).reshape(-1, 3)
        hills = rng.standard_normal(64)
        self._hill_coeffs = hills / np.arange(1, 65) ** 1.2

    # -- background and ground
    def _hill_angle(self, azimuth_rad: FloatArray) -> FloatArray:
        k = np.arange(1, len(self._hill_coeffs) + 1)
        wave = np.sin(np.outer(azimuth_rad, k) * 2 + k) @ self._hill_coeffs
        return np.radians(1.6 + 1.2 * wave)

    def _background(
        self, camera: CameraModel, pose: Pose, gain: float
    ) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.bool_]]:
        """(H, W) float brightness of sky, hills and ground; (H, W) True where ground."""
        h, w = self.shape
        R = camera.R_vehicle_camera
        rays = self.rays_cam @ R.T
        cam = camera.position_vehicle_m
        dz = rays[:, 2]
        ground = dz < -1e-6
        t = np.where(ground, -cam[2] / np.where(ground, dz, -1.0), np.inf)
        x = cam[0] + t * rays[:, 0]
        y = cam[1] + t * rays[:, 1]
        ground &= x < FAR_LIMIT_M
        out = np.empty(h * w, dtype=np.float32)
        # sky, brighter towards the horizon, and distant hills
        elev = np.arctan2(dz, np.hypot(rays[:, 0], rays[:, 1]))
        sky = SKY_HORIZON_GREY - (SKY_HORIZON_GREY - SKY_TOP_GREY) * np.clip(elev / 0.35, 0, 1)
        # hills are far away: their outline depends on the azimuth of the column only
        mid = rays.reshape(h, w, 3)[h // 2]
        hill = np.tile(self._hill_angle(np.arctan2(mid[:, 1], mid[:, 0]) + pose.heading_rad), h)
        in_hill = (elev < hill) & ~ground
        out[:] = sky
        out[in_hill] = 120.0 + 25.0 * np.clip(elev[in_hill] / np.maximum(hill[in_hill], 1e-3), 0, 1)
        # the road plane
        gx, gy = x[ground], y[ground]
        X = pose.x_m + math.cos(pose.heading_rad) * gx - math.sin(pose.heading_rad) * gy
        Y = pose.y_m + math.sin(pose.heading_rad) * gx + math.cos(pose.heading_rad) * gy
        s, d = self.scene.road.to_road(X, Y, pose.s_m + gx)
        footprint = gx * gx / (camera.intrinsics.fy_px * cam[2])
        g = self.texture.sample(s, d, footprint)
        haze = np.exp(-gx / HAZE_DISTANCE_M).astype(np.float32)
        out[ground] = g * haze + HAZE_GREY * (1 - haze)
        return (out * gain).reshape(h, w), ground.reshape(h, w)

    # -- objects
    def _vehicle_faces(
        self, v: Vehicle, t_s: float, pose: Pose, cam_xy: FloatArray
    ) -> tuple[list[tuple[Polygon, float]], FloatArray, FloatArray, FloatArray, float]:
        """Visible faces; box corners (8, 3); nearest end-face centre (3,);
        road-forward unit (2,); distance to the camera."""
        s, d = v.trajectory.at(t_s)
        X, Y = self.scene.road.to_world(s, d)
        cx, cy = pose.to_vehicle(X, Y)
        road_rel = float(self.scene.road.heading(s)) - pose.heading_rad
        theta = road_rel + (math.pi if v.facing_back else 0.0)
        f = np.array([math.cos(theta), math.sin(theta)])
        left = np.array([-f[1], f[0]])
        c = np.array([float(cx), float(cy)])
        hl, hw = v.length_m / 2, v.width_m / 2
        faces: list[tuple[Polygon, float]] = []
        ends = []
        # (centre, outward normal, design, shade): rear, front, left side, right side
        specs = [
            (c - hl * f, -f, _rear_design(v), 0.95),
            (c + hl * f, f, _front_design(v), 0.95),
            (c + hw * left, left, _side_design(v), 0.85),
            (c - hw * left, -left, _side_design(v), 0.85),
        ]
        for k, (fc, n, design, shade) in enumerate(specs):
            if k < 2:
                ends.append((fc, n))
            if float(np.dot(n, cam_xy - fc)) <= 0:
                continue
            right = np.array([-n[1], n[0]])  # the viewer's right when looking along -n
            if k >= 2 and float(np.dot(right, f)) < 0:  # side designs put +a at the front
                design = [([(-a, z) for a, z in pts], grey) for pts, grey in design]
            center = np.array([fc[0], fc[1], 0.0])
            for pts, grey in design:
                faces.append((_face_points(center, right, pts), grey * shade))
        corners = np.array(
            [
                [*(c + sa * hl * f + sb * hw * left), z]
                for sa in (-1, 1)
                for sb in (-1, 1)
                for z in (0.0, v.height_m)
            ]
        )
        near = min(ends, key=lambda e: float(np.linalg.norm(cam_xy - e[0])))
        near_c = np.array([near[0][0], near[0][1], 0.0])
        road_f = np.array([math.cos(road_rel), math.sin(road_rel)])
        return faces, corners, near_c, road_f, float(np.linalg.norm(near[0] - cam_xy))

    def _billboard(
        self,
        pos_xy: FloatArray,
        cam_xy: FloatArray,
        design: list[tuple[list[tuple[float, float]], float]],
    ) -> list[tuple[Polygon, float]]:
        los = pos_xy - cam_xy
        los /= max(float(np.linalg.norm(los)), 1e-6)
        right = np.array([los[1], -los[0]])
        center = np.array([pos_xy[0], pos_xy[1], 0.0])
        return [(_face_points(center, right, pts), grey) for pts, grey in design]

    def _rail_drawables(
        self, camera: CameraModel, pose: Pose, cam_xy: FloatArray
    ) -> tuple[list[_Drawable], list[TruthGuardRail], list[tuple[int, FloatArray]]]:
        """Beam pieces and posts as drawables, truth polylines, rail points for the radar."""
        drawables: list[_Drawable] = []
        truths: list[TruthGuardRail] = []
        radar_pts: list[tuple[int, FloatArray]] = []
        z0, z1 = RAIL_Z_M
        zm = 0.5 * (z0 + z1)
        s_lo, s_hi = pose.s_m - 5.0, pose.s_m + DRAW_RANGE_M
        for rail in self.scene.guard_rails:
            for k, (a, b) in enumerate(rail.pieces_m):
                lo, hi = max(a, s_lo), min(b, s_hi)
                if hi <= lo:
                    continue
                ss = np.unique(np.concatenate([np.arange(lo, hi, 1.0), [hi]]))
                X, Y = self.scene.road.to_world(ss, np.full_like(ss, rail.d_m))
                x, y = pose.to_vehicle(X, Y)
                # posts, a little behind the beam
                Xp, Yp = self.scene.road.to_world(
                    ss, np.full_like(ss, rail.d_m - 0.1 * np.sign(rail.d_m) * -1)
                )
                xp, yp = pose.to_vehicle(Xp, Yp)
                for j in range(len(ss) - 1):
                    p0, p1 = np.array([x[j], y[j]]), np.array([x[j + 1], y[j + 1]])
                    dist = float(np.linalg.norm(0.5 * (p0 + p1) - cam_xy))
                    bands = [
                        (z0, z0 + 0.1, 150.0),
                        (z0 + 0.1, z0 + 0.2, 95.0),
                        (z0 + 0.2, z1, 190.0),
                    ]
                    faces = [
                        (np.array([[*p0, za], [*p1, za], [*p1, zb], [*p0, zb]]), grey)
                        for za, zb, grey in bands
                    ]
                    drawables.append(_Drawable(dist, 0, faces))
                    if ss[j] % RAIL_POST_SPACING_M < 1.0:
                        q = np.array([xp[j], yp[j]])
                        along = (p1 - p0) / max(float(np.linalg.norm(p1 - p0)), 1e-6) * 0.07
                        post = np.array(
                            [
                                [*(q - along), 0.0],
                                [*(q + along), 0.0],
                                [*(q + along), z1 - 0.05],
                                [*(q - along), z1 - 0.05],
                            ]
                        )
                        drawables.append(_Drawable(dist + 0.05, 0, [(post, 85.0)]))
                uv, front = camera.project(np.column_stack([x, y, np.full_like(x, zm)]))
                keep = front & (x > 1.0) & (np.mod(np.arange(len(x)), RAIL_TRUTH_STEP) == 0)
                keep[-1] = bool(front[-1] and x[-1] > 1.0)
                visible = _clip_polyline(
                    uv[keep], camera.intrinsics.width_px, camera.intrinsics.height_px
                )
                if len(visible) >= 2:
                    truths.append(TruthGuardRail(rail.id * 100 + k, rail.side, visible))
                for j in range(len(ss)):
                    radar_pts.append((rail.id, np.array([x[j], y[j]])))
        return drawables, truths, radar_pts

    def render(
        self, t_s: float, pitch_rad: float, gain: float
    ) -> tuple[RenderedFrame, list[tuple[int, FloatArray]], dict[int, RadarView]]:
        """Render at time t_s with the camera at `pitch_rad`.

        Returns the frame, guard-rail points (rail id, vehicle-frame xy) for the radar, and per
        drawn object id its RadarView (nearest face centre, visible fraction, velocity).
        """
        camera = self.camera.with_pitch(pitch_rad)
        pose = ego_pose(self.scene, t_s)
        cam_xy = camera.position_vehicle_m[:2]
        bg, ground = self._background(camera, pose, gain)
        proj = _Projector(camera)

        drawables: list[_Drawable] = []
        truth_geo: dict[int, _Geometry] = {}
        shadows: list[tuple[Polygon, float]] = []
        for v in self.scene.vehicles:
            faces, corners, near_c, road_f, dist = self._vehicle_faces(v, t_s, pose, cam_xy)
            if dist > DRAW_RANGE_M or near_c[0] < -15:
                continue
            drawables.append(_Drawable(dist, v.id, faces))
            truth_geo[v.id] = (
                v.cls,
                near_c,
                corners,
                (v.length_m, v.width_m, v.height_m),
                self._velocity(v.trajectory, t_s, pose),
            )
            foot = corners[::2, :2][[0, 1, 3, 2]]  # z = 0 corners, in ring order
            ds, dd = self.scene.sun_shadow_offset_m
            shift = ds * road_f + dd * np.array([-road_f[1], road_f[0]])
            ctr = foot.mean(axis=0)
            shadows.append(
                (np.column_stack([ctr + (foot - ctr) * 1.06 + shift, np.zeros(4)]), 0.55)
            )
            shadows.append((np.column_stack([ctr + (foot - ctr) * 0.97, np.zeros(4)]), 0.3))
        for p in self.scene.pedestrians:
            s, d = p.trajectory.at(t_s)
            X, Y = self.scene.road.to_world(s, d)
            x, y = pose.to_vehicle(X, Y)
            pos = np.array([float(x), float(y)])
            dist = float(np.linalg.norm(pos - cam_xy))
            if dist > DRAW_RANGE_M or pos[0] < 0:
                continue
            walked = self._walked(p.trajectory, t_s)
            drawables.append(
                _Drawable(
                    dist,
                    p.id,
                    self._billboard(
                        pos, cam_xy, _pedestrian_design(p, 2 * math.pi * walked / WALK_STEP_M)
                    ),
                )
            )
            box = self._upright_box(pos, cam_xy, 0.5, p.height_m)
            truth_geo[p.id] = (
                "pedestrian",
                np.array([*pos, 0.0]),
                box,
                (0.3, 0.5, p.height_m),
                self._velocity(p.trajectory, t_s, pose),
            )
            shadows.append(
                (
                    np.column_stack(
                        [
                            self._ring(pos + np.array(self.scene.sun_shadow_offset_m) * 0.5, 0.35),
                            np.zeros(12),
                        ]
                    ),
                    0.6,
                )
            )
        for o in self.scene.statics:
            X, Y = self.scene.road.to_world(o.s_m, o.d_m)
            x, y = pose.to_vehicle(X, Y)
            pos = np.array([float(x), float(y)])
            dist = float(np.linalg.norm(pos - cam_xy))
            if dist > DRAW_RANGE_M or pos[0] < 0:
                continue
            drawables.append(_Drawable(dist, o.id, self._billboard(pos, cam_xy, _static_design(o))))
            width = o.width_m if o.cls != "tree" else 0.6 * o.height_m
            truth_geo[o.id] = (
                o.cls,
                np.array([*pos, 0.0]),
                self._upright_box(pos, cam_xy, width, o.height_m),
                (o.width_m, o.width_m, o.height_m),
                self._velocity(None, t_s, pose),
            )
        rail_drawables, rail_truth, rail_points = self._rail_drawables(camera, pose, cam_xy)
        drawables += rail_drawables

        # Shadows on the ground first, then objects far to near.
        shade = np.ones(self.shape, dtype=np.float32)
        for poly, factor in shadows:
            px = proj.pixels(poly)
            if px is not None:
                cv2.fillPoly(shade, [px], factor, lineType=cv2.LINE_AA, shift=SUBPIXEL_SHIFT)
        shade = np.asarray(cv2.GaussianBlur(shade, (0, 0), 1.2), dtype=np.float32)
        img = np.where(ground, bg * shade, bg)
        image = np.clip(img, 0, 255).astype(np.uint8)
        labels = np.zeros(self.shape, dtype=np.uint16)
        drawables.sort(key=lambda dr: -dr.distance_m)
        for dr in drawables:
            for poly, grey in dr.faces:
                px = proj.pixels(poly)
                if px is None:
                    continue
                value = int(np.clip(grey * gain, 0, 255))
                cv2.fillPoly(image, [px], value, lineType=cv2.LINE_AA, shift=SUBPIXEL_SHIFT)
                cv2.fillPoly(labels, [px], dr.object_id, lineType=cv2.LINE_8, shift=SUBPIXEL_SHIFT)
        objects, radar_geo = self._truth(labels, drawables, truth_geo, proj)
        frame = RenderedFrame(image, labels, tuple(objects), tuple(rail_truth))
        return frame, rail_points, radar_geo

    @staticmethod
    def _ring(c: FloatArray, r: float, n: int = 12) -> FloatArray:
        a = np.linspace(0, 2 * math.pi, n, endpoint=False)
        return np.column_stack([c[0] + r * np.cos(a), c[1] + r * np.sin(a)])

    @staticmethod
    def _upright_box(
        pos: FloatArray, cam_xy: FloatArray, width: float, height: float
    ) -> FloatArray:
        los = pos - cam_xy
        los /= max(float(np.linalg.norm(los)), 1e-6)
        right = np.array([los[1], -los[0]]) * width / 2
        return np.array([[*(pos + s * right), z] for s in (-1, 1) for z in (0.0, height)])

    @staticmethod
    def _walked(traj: Trajectory, t_s: float) -> float:
        s0, d0 = traj.at(0.0)
        s1, d1 = traj.at(t_s)
        return math.hypot(s1 - s0, d1 - d0)

    def _velocity(self, traj: Trajectory | None, t_s: float, pose: Pose) -> FloatArray:
        """Velocity over ground (m/s) in the ego vehicle's axes at t_s (zero for static objects)."""
        if traj is None:
            return np.zeros(2)
        dt = 0.05
        (s0, d0), (s1, d1) = traj.at(max(t_s - dt, 0.0)), traj.at(t_s + dt)
        X0, Y0 = self.scene.road.to_world(s0, d0)
        X1, Y1 = self.scene.road.to_world(s1, d1)
        span = t_s + dt - max(t_s - dt, 0.0)
        vx, vy = (float(X1) - float(X0)) / span, (float(Y1) - float(Y0)) / span
        c, s = math.cos(pose.heading_rad), math.sin(pose.heading_rad)
        return np.array([c * vx + s * vy, -s * vx + c * vy])

    def _truth(
        self,
        labels: npt.NDArray[np.uint16],
        drawables: Sequence[_Drawable],
        truth_geo: dict[int, _Geometry],
        proj: _Projector,
    ) -> tuple[list[TruthObject], dict[int, RadarView]]:
        objects: list[TruthObject] = []
        radar_geo: dict[int, RadarView] = {}
        by_id = {dr.object_id: dr for dr in drawables if dr.object_id}
        ids, counts = np.unique(labels, return_counts=True)
        visible = dict(zip(ids.tolist(), counts.tolist(), strict=True))
        scratch = np.zeros(self.shape, dtype=np.uint8)
        for obj_id, (cls, near_c, _corners, size, vel) in truth_geo.items():
            n_vis = visible.get(obj_id, 0)
            # full silhouette, drawn alone
            scratch[:] = 0
            for poly, _ in by_id[obj_id].faces:
                px = proj.pixels(poly)
                if px is not None:
                    cv2.fillPoly(scratch, [px], 1, lineType=cv2.LINE_8, shift=SUBPIXEL_SHIFT)
            n_full = int(scratch.sum())
            frac = n_vis / n_full if n_full else 0.0
            radar_geo[obj_id] = RadarView(near_c, frac, vel)
            if n_vis < MIN_VISIBLE_PX:
                continue
            rows, cols = np.nonzero(labels == obj_id)
            box = (
                cols.min() - 0.5,
                rows.min() - 0.5,
                cols.max() + 0.5,
                rows.max() + 0.5,
            )  # pixel edges
            objects.append(
                TruthObject(
                    id=obj_id,
                    cls=cls,
                    box_px=tuple(float(c) for c in box),  # type: ignore[arg-type]
                    position_m=(float(near_c[0]), float(near_c[1]), 0.0),
                    size_m=(float(size[0]), float(size[1]), float(size[2])),
                    velocity_mps=(float(vel[0]), float(vel[1])),
                    radar_seen=False,
                    occlusion=float(np.clip(1.0 - frac, 0.0, 1.0)),
                )
            )
        return objects, radar_geo
