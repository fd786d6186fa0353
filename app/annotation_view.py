"""What annotation mode shows and how a pointer on it maps to image pixels; pure functions.

The frame being annotated lies in the 3D scene as an image on the plane z = PLANE_Z_M,
PX_TO_M metres per pixel, its centre at (0, 0), image right along +x and image up along
+y, seen from straight above. viser lays an image's columns along its node's +x and its
rows along +y (OpenCV's image axes, seen from -z), so the node is turned half a turn about
x (PLANE_WXYZ) to be read from above. A pointer's world position on
that plane maps to a pixel (`pixel_of`), and the pixels of a drag give what it does
(`drag_action`): near a corner of the selected box it moves that corner, inside a box it
moves the box, elsewhere it draws a new box.

`annotated_picture` draws the frame's boxes: keyframes solid and thick, interpolated boxes
thin and dashed, each tagged "#id class" (with "key" on keyframes), the selected track in
SELECTED_COLOUR, the box being drawn in DRAFT_COLOUR.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import cv2
import numpy as np

from app.draw import (
    CLASS_COLOURS,
    GUARD_RAIL_COLOUR,
    RgbImage,
    put_tag,
    require_rgb_image,
)
from core.annotation.model import Box, Shown

PX_TO_M = 0.01  # the annotation plane's scale: a 640 px wide frame is 6.4 m wide
PLANE_Z_M = 50.0  # above the bird's-eye view, which lies at z = 0
PLANE_WXYZ = (0.0, 1.0, 0.0, 0.0)  # half a turn about x: image rows run along -y
CORNER_GRAB_PX = 8.0  # a drag starting this close to a corner of the selected box resizes it
MIN_BOX_PX = 3.0  # a drawn box narrower or lower than this is a click, not a box
PARALLEL_RAY = 1e-9  # a ray whose z direction is smaller never meets the plane
KEYFRAME_THICKNESS_PX = 2
DASH_PX = 6
SELECTED_COLOUR = (255, 255, 0)
DRAFT_COLOUR = (255, 255, 255)
# the classes in the colours the ground-truth layer draws them in (app.draw)
ANNOTATION_COLOURS = {
    **{c: CLASS_COLOURS[c] for c in ("car", "truck", "van", "pedestrian", "cyclist")},
    "guard_rail": GUARD_RAIL_COLOUR,
    "other_obstacle": CLASS_COLOURS["other"],
}


SEED_KINDS = ("vehicle", "pedestrian")  # detections annotation can accept


@dataclass(frozen=True)
class Seeds:
    """What the engine found on one frame, for seeding annotations: detections as (kind,
    box_px) of SEED_KINDS, and the searched radar targets' base points as (u_px, v_px,
    x_m) for snapping a box's distance, and the engine's confirmed vehicle and pedestrian
    tracks, to accept one over a clip."""

    frame: int
    detections: tuple[tuple[str, Box], ...] = ()
    radar_bases: tuple[tuple[float, float, float], ...] = ()
    tracks: tuple[tuple[str, int, Box], ...] = ()  # confirmed engine tracks: kind, id, box


def snapped_distance_m(box: Box, radar_bases: Sequence[tuple[float, float, float]]) -> float | None:
    """The x distance of the radar target whose base point lies in `box` (the nearest when
    several do); None when none does."""
    u0, v0, u1, v1 = box
    inside = [x for u, v, x in radar_bases if u0 <= u <= u1 and v0 <= v <= v1]
    return min(inside) if inside else None


def pixel_of(position_m: Sequence[float], size_px: tuple[int, int]) -> tuple[float, float]:
    """(u, v) pixel (edges: the image spans 0..W, 0..H) of a world point on the annotation
    plane of an image of size_px = (width, height)."""
    w, h = size_px
    return (float(position_m[0]) / PX_TO_M + w / 2, h / 2 - float(position_m[1]) / PX_TO_M)


def plane_pixel(
    ray_origin: Sequence[float], ray_direction: Sequence[float], size_px: tuple[int, int]
) -> tuple[float, float] | None:
    """The pixel where a pointer's ray (world origin and direction) meets the annotation
    plane; None when the ray runs parallel to it."""
    oz, dz = float(ray_origin[2]), float(ray_direction[2])
    if abs(dz) < PARALLEL_RAY:
        return None
    t = (PLANE_Z_M - oz) / dz
    point = (ray_origin[0] + t * ray_direction[0], ray_origin[1] + t * ray_direction[1])
    return pixel_of(point, size_px)


def box_under(pixel: tuple[float, float], shown: Sequence[Shown]) -> Shown | None:
    """The smallest box containing `pixel` (None: none does)."""
    u, v = pixel
    inside = [
        s for s in shown if s.box_px[0] <= u <= s.box_px[2] and s.box_px[1] <= v <= s.box_px[3]
    ]
    return min(
        inside,
        key=lambda s: (s.box_px[2] - s.box_px[0]) * (s.box_px[3] - s.box_px[1]),
        default=None,
    )


def box_from_corners(
    a: tuple[float, float], b: tuple[float, float], size_px: tuple[int, int]
) -> Box:
    """The box spanned by two pixels, clipped to the image."""
    w, h = size_px
    u0, u1 = sorted((min(max(a[0], 0.0), w), min(max(b[0], 0.0), w)))
    v0, v1 = sorted((min(max(a[1], 0.0), h), min(max(b[1], 0.0), h)))
    return (u0, v0, u1, v1)


@dataclass(frozen=True)
class DragAction:
    """What a drag does: "draw" a new box, "move" track `track_id`'s box, or "corner":
    move its corner `corner` (0 top-left, 1 top-right, 2 bottom-right, 3 bottom-left)."""

    kind: Literal["draw", "move", "corner"]
    track_id: int | None = None
    corner: int | None = None


def _corners(box: Box) -> list[tuple[float, float]]:
    u0, v0, u1, v1 = box
    return [(u0, v0), (u1, v0), (u1, v1), (u0, v1)]


def drag_action(
    start_px: tuple[float, float], shown: Sequence[Shown], selected: int | None
) -> DragAction:
    """What a drag starting at `start_px` does (module docstring): the selected track's
    corners first, then the smallest box containing the start."""
    u, v = start_px
    for s in shown:
        if s.track_id == selected:
            for k, (cu, cv) in enumerate(_corners(s.box_px)):
                if abs(cu - u) <= CORNER_GRAB_PX and abs(cv - v) <= CORNER_GRAB_PX:
                    return DragAction("corner", s.track_id, k)
    under = box_under(start_px, shown)
    return DragAction("draw") if under is None else DragAction("move", under.track_id)


def dragged_box(
    action: DragAction,
    box: Box | None,
    start_px: tuple[float, float],
    end_px: tuple[float, float],
    size_px: tuple[int, int],
) -> Box | None:
    """The box after dragging from start_px to end_px (`box`: the track's box when the drag
    began; unused for "draw"); None when a drawn box is smaller than MIN_BOX_PX."""
    if action.kind == "draw":
        out = box_from_corners(start_px, end_px, size_px)
        too_small = out[2] - out[0] < MIN_BOX_PX or out[3] - out[1] < MIN_BOX_PX
        return None if too_small else out
    if box is None:
        return None
    du, dv = end_px[0] - start_px[0], end_px[1] - start_px[1]
    if action.kind == "move":
        u0, v0, u1, v1 = box
        return (u0 + du, v0 + dv, u1 + du, v1 + dv)
    corners = _corners(box)
    k = action.corner if action.corner is not None else 0
    moved = (corners[k][0] + du, corners[k][1] + dv)
    opposite = corners[(k + 2) % 4]
    out = box_from_corners(moved, opposite, size_px)
    return out if out[2] - out[0] >= MIN_BOX_PX and out[3] - out[1] >= MIN_BOX_PX else box


def _dashed_rectangle(out: RgbImage, box: Box, colour: tuple[int, int, int]) -> None:
    """In place: the box's outline as dashes of DASH_PX, one pixel thick."""
    u0, v0, u1, v1 = box
    corners = np.array([(u0, v0), (u1, v0), (u1, v1), (u0, v1), (u0, v0)])
    for a, b in itertools.pairwise(corners):
        pieces = max(1, int(np.abs(b - a).max() // DASH_PX))
        for k in range(0, pieces, 2):
            p = np.round(a + (b - a) * k / pieces).astype(int)
            q = np.round(a + (b - a) * (k + 1) / pieces).astype(int)
            cv2.line(out, (int(p[0]), int(p[1])), (int(q[0]), int(q[1])), colour, 1)


def annotated_picture(
    rgb: RgbImage, shown: Sequence[Shown], selected: int | None = None, draft: Box | None = None
) -> RgbImage:
    """The frame with its annotation boxes (module docstring); a new image."""
    require_rgb_image("rgb", rgb)
    out = rgb.copy()
    for s in shown:
        colour = SELECTED_COLOUR if s.track_id == selected else ANNOTATION_COLOURS[s.cls]
        u0, v0, u1, v1 = (round(c) for c in s.box_px)
        if s.keyframe:
            cv2.rectangle(out, (u0, v0), (u1, v1), colour, KEYFRAME_THICKNESS_PX)
        else:
            _dashed_rectangle(out, s.box_px, colour)
        tag = f"#{s.track_id} {s.cls}" + (" key" if s.keyframe else "")
        put_tag(out, tag, u0, v0 - KEYFRAME_THICKNESS_PX, colour)
    if draft is not None:
        u0, v0, u1, v1 = (round(c) for c in draft)
        cv2.rectangle(out, (u0, v0), (u1, v1), DRAFT_COLOUR, 1)
    return np.ascontiguousarray(out)
