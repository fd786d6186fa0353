"""The legend of the overlay colours in plain words, for people who never read the papers:
one entry per colour each layer draws (`LEGEND`), drawn as the layer draws it (a box outline,
a cross, a line, a filled patch, a track's tag) before its words, flowed over lines of a
given width. Exported videos carry it under the picture (`app.video_frame`); the presenter
view beside it (`app.presenter`).

Pure: numpy and OpenCV drawing, the colours of `app.overlays` and `app.draw`.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import cv2

from app import draw, overlays
from app.state import Layers

BANNER_COLOUR = draw.STRIP_COLOUR
LEGEND_FONT_SCALE = draw.FONT_SCALE
LEGEND_LINE_PX = 20
LEGEND_BOTTOM_PX = 4  # below the last legend line
SWATCH_WIDTH_PX = 16
SWATCH_GAP_PX = 5  # between a mark and its words
ITEM_GAP_PX = 16  # between one legend item and the next
SWATCH_INSET_PX = 4  # a box mark's top and bottom from its line's
MARGIN_PX = draw.TEXT_MARGIN_PX
MIN_WIDTH_PX = 16

Mark = Literal["box", "dashed box", "cross", "line", "fill", "tag", "missed tag"]


@dataclass(frozen=True)
class LegendItem:
    """One entry of the legend: a mark of the shape the layer draws (a box outline, a cross,
    a line, a filled patch, a tag) in `colour`, and what it means in plain words."""

    mark: Mark
    colour: draw.Rgb
    words: str


# By `app.state.Layers` field, in the order the legend lists them: what each layer draws.
LEGEND: Mapping[str, tuple[LegendItem, ...]] = {
    "vehicles": (
        LegendItem("box", overlays.VEHICLE_COLOUR, "vehicle confirmed by radar and vision"),
        LegendItem(
            "dashed box", overlays.VEHICLE_COLOUR, "vehicle vision found on a track, no radar"
        ),
    ),
    "radar": (
        LegendItem("cross", overlays.RADAR_REFINED_COLOUR, "radar target that found the vehicle"),
        LegendItem("cross", overlays.RADAR_DISCARDED_COLOUR, "radar target discarded (no vehicle)"),
        LegendItem("cross", overlays.RADAR_GUARD_RAIL_COLOUR, "radar target on a guard rail"),
    ),
    "guardrails": (LegendItem("line", overlays.GUARD_RAIL_LINE_COLOUR, "guard rail"),),
    "pedestrians": (LegendItem("box", overlays.PEDESTRIAN_COLOUR, "pedestrian"),),
    "rejected": (
        LegendItem("box", overlays.VEHICLE_REJECTED_COLOUR, "vehicle box dropped by size"),
        LegendItem("box", overlays.PEDESTRIAN_REJECTED_COLOUR, "pedestrian rejected, tag says why"),
    ),
    "pruned": (
        LegendItem("box", overlays.PEDESTRIAN_REJECTED_COLOUR, "pedestrian dropped by shape"),
    ),
    "areas": (
        LegendItem("box", overlays.SEARCH_AREA_COLOUR, "radar search area"),
        LegendItem("dashed box", overlays.SEARCH_AREA_COLOUR, "area searched for a track, #id"),
    ),
    "strip": (LegendItem("fill", overlays.STRIP_GREY, "pedestrian search strip"),),
    "horizon": (LegendItem("line", draw.HORIZON_COLOUR, "horizon"),),
    "tracks": (LegendItem("tag", overlays.VEHICLE_COLOUR, "the same object followed over time"),),
    "coasting": (
        LegendItem("missed tag", overlays.VEHICLE_COLOUR, "followed, not seen in this frame"),
    ),
    "truth": (LegendItem("box", draw.CLASS_COLOURS["car"], "ground truth"),),
    "confirmed": (
        LegendItem("box", overlays.VEHICLE_COLOUR, "vehicle, confirmed over several frames"),
        LegendItem("box", overlays.PEDESTRIAN_COLOUR, "pedestrian, confirmed over several frames"),
        LegendItem("tag", overlays.VEHICLE_COLOUR, "the same object followed over time"),
    ),
}
# the "tag" marks: a track's tag as `app.overlays.put_track_ids` draws it, seen this frame or not
TAG_TEXTS: Mapping[Mark, str] = {"tag": "#7", "missed tag": "#7 ?"}


def legend_items(layers: Layers) -> tuple[LegendItem, ...]:
    """The legend of the layers switched on, in `LEGEND` order."""
    return tuple(
        item for name, items in LEGEND.items() if getattr(layers, name, False) for item in items
    )


def _text_width_px(text: str, font_scale: float) -> int:
    (w, _), _ = cv2.getTextSize(text, draw.FONT, font_scale, 1)
    return int(w)


def _mark_width_px(item: LegendItem) -> int:
    """A mark's width: SWATCH_WIDTH_PX, or a tag's (its text and margins) when wider."""
    if item.mark not in TAG_TEXTS:
        return SWATCH_WIDTH_PX
    return max(SWATCH_WIDTH_PX, _text_width_px(TAG_TEXTS[item.mark], overlays.TAG_FONT_SCALE) + 3)


def _item_width_px(item: LegendItem) -> int:
    return _mark_width_px(item) + SWATCH_GAP_PX + _text_width_px(item.words, LEGEND_FONT_SCALE)


def legend_lines(items: Sequence[LegendItem], width_px: int) -> tuple[tuple[LegendItem, ...], ...]:
    """`items` flowed into lines of at most `width_px` (an item wider than a line gets one
    of its own); none for no items."""
    lines: list[list[LegendItem]] = []
    x = width_px  # forces a first line
    for item in items:
        w = _item_width_px(item)
        if x + w > width_px - MARGIN_PX and x > MARGIN_PX:
            lines.append([])
            x = MARGIN_PX
        lines[-1].append(item)
        x += w + ITEM_GAP_PX
    return tuple(tuple(line) for line in lines)


def _draw_mark(out: draw.RgbImage, item: LegendItem, x: int, top: int) -> None:
    """In place: `item`'s mark in the `_mark_width_px` x LEGEND_LINE_PX cell at (x, top)."""
    x1 = x + SWATCH_WIDTH_PX - 1
    y_mid = top + LEGEND_LINE_PX // 2
    thick = draw.LINE_THICKNESS_PX
    if item.mark == "box":
        y0, y1 = top + SWATCH_INSET_PX, top + LEGEND_LINE_PX - 1 - SWATCH_INSET_PX
        cv2.rectangle(out, (x, y0), (x1, y1), item.colour, overlays.BOX_THICKNESS_PX)
    elif item.mark == "dashed box":
        y0, y1 = top + SWATCH_INSET_PX, top + LEGEND_LINE_PX - 1 - SWATCH_INSET_PX
        for k in range(overlays.BOX_THICKNESS_PX):
            draw.put_dashed_rectangle(out, (x + k, y0 + k), (x1 - k, y1 - k), item.colour, 3)
    elif item.mark == "fill":
        y0, y1 = top + SWATCH_INSET_PX, top + LEGEND_LINE_PX - 1 - SWATCH_INSET_PX
        cv2.rectangle(out, (x, y0), (x1, y1), item.colour, cv2.FILLED)
    elif item.mark == "cross":
        centre = (x + SWATCH_WIDTH_PX // 2, y_mid)
        size = min(draw.RADAR_CROSS_SIZE_PX, LEGEND_LINE_PX - 2)
        cv2.drawMarker(out, centre, item.colour, cv2.MARKER_CROSS, size, thick)
    elif item.mark == "line":
        cv2.line(out, (x, y_mid), (x1, y_mid), item.colour, thick)
    else:
        text = TAG_TEXTS[item.mark]
        (_, h), baseline = cv2.getTextSize(text, draw.FONT, overlays.TAG_FONT_SCALE, 1)
        bottom = y_mid + (h + baseline) // 2
        draw.put_tag(out, text, x, bottom, item.colour, font_scale=overlays.TAG_FONT_SCALE)


def banner_strip(height_px: int, width_px: int) -> draw.RgbImage:
    """An empty (height_px, width_px, 3) strip of the banner's colour."""
    return draw.filled(height_px, width_px, BANNER_COLOUR)


@functools.lru_cache(maxsize=8)
def legend_strip(layers: Layers, width_px: int) -> draw.RgbImage:
    """The legend of `layers` (`legend_items`) flowed over lines of `width_px`: each item a
    mark and its words in white; (0, width_px, 3) when no layer is on. Read-only (it is
    cached: every frame of a video has the same)."""
    if width_px < MIN_WIDTH_PX:
        raise ValueError(f"width_px: expected at least {MIN_WIDTH_PX} px, got {width_px}")
    lines = legend_lines(legend_items(layers), width_px)
    height = len(lines) * LEGEND_LINE_PX + (LEGEND_BOTTOM_PX if lines else 0)
    out = banner_strip(height, width_px)
    (_, text_h), _ = cv2.getTextSize("Ag", draw.FONT, LEGEND_FONT_SCALE, 1)
    for k, line in enumerate(lines):
        top = k * LEGEND_LINE_PX
        x = MARGIN_PX
        for item in line:
            _draw_mark(out, item, x, top)
            at = (x + _mark_width_px(item) + SWATCH_GAP_PX, top + (LEGEND_LINE_PX + text_h) // 2)
            cv2.putText(
                out,
                item.words,
                at,
                draw.FONT,
                LEGEND_FONT_SCALE,
                draw.TEXT_COLOUR,
                1,
                cv2.LINE_AA,
            )
            x += _item_width_px(item) + ITEM_GAP_PX
    out.flags.writeable = False
    return out
