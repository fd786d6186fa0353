"""The image area searched around each radar target (paper 001, section II), shared by the
guard-rail filter and the vehicle detector.

For a target at (x_m, y_m) in the vehicle frame:

1. the radar point is mapped into the image on the object's base (the road, z = 0) with the
   frame's camera model (its detected pitch);
2. the area is `search_width_m` wide in the world at that distance, centred on the target:
   its left and right columns are the images of (x_m, y_m +- W / 2, 0); its height is
   `search_height_ratio` of its width, and its bottom lies `search_bottom_fraction` of its
   height below the radar point, so the vehicle stays inside under pitch error;
3. only targets whose radar point lands inside the image get an area; an area crossing the
   image border is cropped to the image (the paper's second approach);
4. the cropped area is resampled by `scale = min(1, resampled_width_px / W_px)`, with W_px
   the uncropped width: every area ends up at most `resampled_width_px` wide with its aspect
   ratio kept, and is never enlarged (paper 001).

Coordinates: image pixels with pixel centres at integers (u column, v row), as the camera
model; an area's bounds are pixel edges. A patch pixel (r, c) covers the image rectangle
`to_image_px` maps its edges to.

Notes:
    - The paper does not say how the area's height relates to pixels and metres; here the
      height is `search_height_ratio` times the area's image width, which is the same
      fraction of its world width for square pixels (fx = fy).
    - Step 4 resamples bilinearly (OpenCV's INTER_LINEAR), not by pixel-area averaging:
      INTER_AREA cost 12 to 35 us per area (a third of the vehicle detector's budget for 8
      targets), and the refined shares of the bundled drives' vehicles stayed the same
      (highway 44 of 53 both ways).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np
import numpy.typing as npt

from core.camera import CameraModel
from core.io.frame import RadarTarget
from core.params import VehicleParams

FloatArray = npt.NDArray[np.float64]


@dataclass(frozen=True)
class SearchArea:
    """The area of one radar target.

    target_index: the target's place in the frame's radar tuple; base_px: (u, v) of the radar
    point on the object's base; full_px: (u0, v0, u1, v1) pixel-edge bounds before cropping;
    box_px: (col0, row0, col1, row1) integer pixel bounds after cropping (end exclusive), so
    the crop is `image[row0:row1, col0:col1]`; y_left_m, y_right_m: the area's sides in the
    world (vehicle frame), at the target's x_m; patch: (h, w) uint8 grey, the crop resampled;
    px_per_m: patch pixels per metre across at the target's distance. The patch is an array of
    its own (C-contiguous, writable), never a view of the image.
    """

    target_index: int
    target: RadarTarget
    base_px: tuple[float, float]
    full_px: tuple[float, float, float, float]
    box_px: tuple[int, int, int, int]
    y_left_m: float
    y_right_m: float
    patch: npt.NDArray[np.uint8]
    px_per_m: float

    @property
    def x_m(self) -> float:
        """The target's distance ahead (vehicle frame)."""
        return self.target.x_m

    @property
    def cropped(self) -> bool:
        """True when part of the area lies outside the image."""
        return self.box_px != tuple(math.ceil(b) for b in self.full_px)

    def to_image_px(
        self, cols: npt.ArrayLike, rows: npt.ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """Patch pixel-edge coordinates (0 .. w, 0 .. h) -> image coordinates (u, v)."""
        c0, r0, c1, r1 = self.box_px
        h, w = self.patch.shape
        u = c0 - 0.5 + np.asarray(cols, dtype=np.float64) * (c1 - c0) / w
        v = r0 - 0.5 + np.asarray(rows, dtype=np.float64) * (r1 - r0) / h
        return u, v


Rect = tuple[float, float, float, float]


def rect_area(r: Rect) -> float:
    """Area of an image rectangle (left, top, right, bottom); 0 when empty."""
    return max(0.0, r[2] - r[0]) * max(0.0, r[3] - r[1])


def intersection_area(a: Rect, b: Rect) -> float:
    """Area two image rectangles (left, top, right, bottom) share."""
    return rect_area((max(a[0], b[0]), max(a[1], b[1]), min(a[2], b[2]), min(a[3], b[3])))


def overlap_fraction(a: SearchArea, b: SearchArea) -> float:
    """Share of area `b`'s cropped image rectangle that `a`'s covers (0 .. 1)."""
    return intersection_area(a.box_px, b.box_px) / max(1.0, rect_area(b.box_px))


def search_areas(
    image: npt.NDArray[np.uint8],
    camera: CameraModel,
    radar: tuple[RadarTarget, ...],
    params: VehicleParams,
) -> tuple[SearchArea, ...]:
    """The areas of the targets of `radar` whose base point lands inside `image`, in radar
    order.

    image: (H, W) uint8 grey, the full camera frame; camera: the frame's camera model (with
    the detected pitch).
    """
    camera.check_image(image)
    if not radar:
        return ()
    h_img, w_img = image.shape
    half_m = params.search_width_m / 2
    pts = np.array(
        [(t.x_m, y, 0.0) for t in radar for y in (t.y_m, t.y_m + half_m, t.y_m - half_m)]
    )
    uv, in_front = camera.project(pts)
    points = uv.reshape(len(radar), 3, 2).tolist()
    visible = np.all(in_front.reshape(len(radar), 3), axis=1).tolist()
    areas = []
    for i, t in enumerate(radar):
        (u, v), (u_left, _), (u_right, _) = points[i]
        if not (visible[i] and -0.5 <= u < w_img - 0.5 and -0.5 <= v < h_img - 0.5):
            continue
        width_px = u_right - u_left
        if not width_px > 0:
            continue
        height_px = params.search_height_ratio * width_px
        v1 = v + params.search_bottom_fraction * height_px
        full = (u_left, v1 - height_px, u_right, v1)
        c0, r0 = max(0, math.ceil(full[0])), max(0, math.ceil(full[1]))
        c1, r1 = min(w_img, math.ceil(full[2])), min(h_img, math.ceil(full[3]))
        if c1 - c0 < 2 or r1 - r0 < 2:
            continue
        scale = min(1.0, params.resampled_width_px / width_px)
        size = (max(1, round((c1 - c0) * scale)), max(1, round((r1 - r0) * scale)))
        crop = image[r0:r1, c0:c1]
        # always a C-contiguous array of its own: the compiled searches then have one
        # signature, loaded once from numba's cache instead of twice
        patch: npt.NDArray[np.uint8] = (
            crop.copy()
            if scale == 1.0
            else np.asarray(cv2.resize(crop, size, interpolation=cv2.INTER_LINEAR))
        )
        areas.append(
            SearchArea(
                target_index=i,
                target=t,
                base_px=(u, v),
                full_px=full,
                box_px=(c0, r0, c1, r1),
                y_left_m=t.y_m + half_m,
                y_right_m=t.y_m - half_m,
                patch=patch,
                px_per_m=size[0] / (c1 - c0) * width_px / params.search_width_m,
            )
        )
    return tuple(areas)
