"""What the presenter view shows beside the pictures, for people who never read the papers:
a legend of the overlay colours in plain words, and a few large figures of the frame.

Pure functions of an engine result; the colours are the overlays' own (`app.overlays`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from app import overlays
from app.draw import FONT, LINE_THICKNESS_PX, TEXT_COLOUR, Rgb, RgbImage, put_tag
from app.state import Layers
from core.engine import FrameResult

# the layers a presenter shows: what was found, not how
PRESENTER_LAYERS = Layers(
    radar=True,
    areas=False,
    vehicles=True,
    guardrails=True,
    pedestrians=True,
    rejected=False,
    pruned=False,
    strip=False,
    horizon=False,
    tracks=True,
    truth=False,
)


@dataclass(frozen=True)
class LegendEntry:
    mark: str  # "box", "cross" or "tag" (a track's "#7" tag)
    colour: Rgb
    words: str


LEGEND = (
    LegendEntry("box", overlays.VEHICLE_COLOUR, "vehicle confirmed by radar and vision"),
    LegendEntry("cross", overlays.RADAR_REFINED_COLOUR, "radar target that found the vehicle"),
    LegendEntry("cross", overlays.RADAR_DISCARDED_COLOUR, "radar target discarded (no vehicle)"),
    LegendEntry(
        "cross", overlays.RADAR_GUARD_RAIL_COLOUR, "guard rail: its line and radar targets on it"
    ),
    LegendEntry("box", overlays.PEDESTRIAN_COLOUR, "pedestrian"),
    LegendEntry("tag", overlays.VEHICLE_COLOUR, "the same vehicle followed over time"),
)
LEGEND_ROW_PX = 26
LEGEND_MARK_PX = 16
LEGEND_FONT_SCALE = 0.5
LEGEND_BACKGROUND: Rgb = (24, 24, 24)


def legend_picture(
    entries: Sequence[LegendEntry] = LEGEND, width_px: int = 360, row_px: int = LEGEND_ROW_PX
) -> RgbImage:
    """One row per entry on a dark background: its mark drawn as the overlays draw it, then
    its words. ValueError when `width_px` or `row_px` is too small to hold a mark."""
    if row_px < LEGEND_MARK_PX + 4 or width_px < 2 * row_px:
        raise ValueError(
            f"width_px, row_px: expected at least {2 * (LEGEND_MARK_PX + 4)} and "
            f"{LEGEND_MARK_PX + 4} px, got {width_px} and {row_px}"
        )
    out = np.full((row_px * len(entries), width_px, 3), LEGEND_BACKGROUND, dtype=np.uint8)
    half = LEGEND_MARK_PX // 2
    for i, entry in enumerate(entries):
        cu, cv = row_px // 2, i * row_px + row_px // 2
        if entry.mark == "box":
            corner0, corner1 = (cu - half, cv - half), (cu + half, cv + half)
            cv2.rectangle(out, corner0, corner1, entry.colour, LINE_THICKNESS_PX)
        elif entry.mark == "cross":
            cv2.line(out, (cu - half, cv), (cu + half, cv), entry.colour, LINE_THICKNESS_PX)
            cv2.line(out, (cu, cv - half), (cu, cv + half), entry.colour, LINE_THICKNESS_PX)
        else:  # a track's tag, as `app.overlays.draw_track_ids` draws it
            put_tag(out, "#7", 2, cv + half // 2, entry.colour, font_scale=overlays.TAG_FONT_SCALE)
        org = (row_px + 4, cv + 5)
        cv2.putText(out, entry.words, org, FONT, LEGEND_FONT_SCALE, TEXT_COLOUR, 1, cv2.LINE_AA)
    return out


def enlarged(rgb: RgbImage, width_px: int) -> RgbImage:
    """`rgb` scaled to `width_px` wide (bilinear), its aspect kept: the browser shows a
    picture no wider than it is, and the presenter's camera should fill its panel."""
    h, w = rgb.shape[:2]
    height_px = max(1, round(h * width_px / w))
    out = cv2.resize(rgb, (width_px, height_px), interpolation=cv2.INTER_LINEAR)
    return np.asarray(out, dtype=np.uint8)


@dataclass(frozen=True)
class HeadlineFigures:
    """The figures of one frame a presenter shows large."""

    vehicles: int  # vehicles confirmed by radar and vision in this frame
    pedestrians: int  # pedestrians kept in this frame
    nearest_vehicle_m: float | None  # radar distance of the nearest vehicle; None: none
    processing_ms: float  # the engine's time on this frame, all stages


def headline_figures(result: FrameResult) -> HeadlineFigures:
    vehicles = result.vehicle.vehicles
    nearest = min((v.distance_m for v in vehicles), default=None)
    return HeadlineFigures(
        len(vehicles), len(result.pedestrian.kept), nearest, result.timings.total_ms
    )


def figures_markdown(figures: HeadlineFigures) -> str:
    """The figures as large markdown lines."""
    nearest = "–" if figures.nearest_vehicle_m is None else f"{figures.nearest_vehicle_m:.0f} m"
    vehicles = "vehicle" if figures.vehicles == 1 else "vehicles"
    pedestrians = "pedestrian" if figures.pedestrians == 1 else "pedestrians"
    return (
        f"## {figures.vehicles} {vehicles} · {figures.pedestrians} {pedestrians}\n\n"
        f"## nearest vehicle {nearest}\n\n"
        f"### {figures.processing_ms:.1f} ms to process this frame"
    )
