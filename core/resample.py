"""An image box resampled onto a fixed grid of pixels, shared by the HOG verification
(`core.hog`: a person's 64 x 128 window) and the image-motion filter (`core.image_motion`:
16 x 32 samples to correlate).

Coordinates: the box (u0, v0, u1, v1) in the image's pixels, pixel centres at integers, its
bounds pixel edges; its edges go onto the grid's edges.
"""

from __future__ import annotations

import cv2
import numpy as np
import numpy.typing as npt

Box = tuple[float, float, float, float]
U8Array = npt.NDArray[np.uint8]


def box_to_grid(image: U8Array, box_px: Box, size_px: tuple[int, int]) -> U8Array:
    """The pixels of `box_px` of `image` resampled to size_px (columns, rows): bilinear,
    the border replicated where the box runs off the image."""
    u0, v0, u1, v1 = box_px
    w, h = size_px
    sx, sy = w / max(u1 - u0, 1e-3), h / max(v1 - v0, 1e-3)
    affine = np.array([[sx, 0.0, (0.5 - u0) * sx - 0.5], [0.0, sy, (0.5 - v0) * sy - 0.5]])
    grid = cv2.warpAffine(
        image, affine, size_px, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE
    )
    return np.asarray(grid, np.uint8)
