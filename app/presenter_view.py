"""What the presenter view shows with the pictures, for people who never read the papers:
a few large figures of the frame (the legend of the colours is `app.legend`'s, the layers
drawn `app.state.DEMO_LAYERS`).

The figures are drawn over the camera picture (`with_figures`), in the same image: a page
shows a new image only once it has decoded it, and text beside it would change first, so
while playing the figures would describe the next frame over the last one's picture.

Pure functions of an engine result and pictures. Images: RGB (H, W, 3) uint8, as in
`app.draw`.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from app import draw
from app.legend import MARGIN_PX, banner_strip
from app.overlays import measured_shown
from core.engine import FrameResult

# The figures' strip: the counts large, the time under them
COUNTS_FONT_SCALE = 0.9
COUNTS_THICKNESS = 2
TIME_FONT_SCALE = 0.55
TIME_THICKNESS = 1
COUNTS_BASELINE_PX = 32
TIME_BASELINE_PX = 58
FIGURES_HEIGHT_PX = 68
SEPARATOR = "   |   "


@dataclass(frozen=True)
class HeadlineFigures:
    """The figures of one frame a presenter shows large."""

    vehicles: int  # confirmed vehicle tracks measured in this frame
    pedestrians: int  # confirmed pedestrian tracks measured in this frame
    nearest_vehicle_m: float | None  # distance of the nearest of those vehicles; None: none
    processing_ms: float  # the engine's time on this frame, all stages


def headline_figures(result: FrameResult) -> HeadlineFigures:
    """The figures of `result`: what the demo layers draw (`app.state.DEMO_LAYERS`), the
    confirmed tracks measured this frame, never a single frame's proposals."""
    vehicles = measured_shown(result.tracked_vehicles)
    pedestrians = measured_shown(result.tracked_pedestrians)
    nearest = min((t.x_m for t in vehicles), default=None)
    return HeadlineFigures(len(vehicles), len(pedestrians), nearest, result.timings.total_ms)


def figures_lines(figures: HeadlineFigures) -> tuple[str, str]:
    """The figures in words (ASCII: OpenCV's font has no other), the counts and the nearest
    vehicle when there is one, then the engine's time: ("2 vehicles   |   1 pedestrian   |
    nearest vehicle 23 m", "4.2 ms to process this frame")."""
    vehicles = "vehicle" if figures.vehicles == 1 else "vehicles"
    pedestrians = "pedestrian" if figures.pedestrians == 1 else "pedestrians"
    parts = [f"{figures.vehicles} {vehicles}", f"{figures.pedestrians} {pedestrians}"]
    if figures.nearest_vehicle_m is not None:
        parts.append(f"nearest vehicle {figures.nearest_vehicle_m:.0f} m")
    return SEPARATOR.join(parts), f"{figures.processing_ms:.1f} ms to process this frame"


def figures_strip(figures: HeadlineFigures, width_px: int) -> draw.RgbImage:
    """A (FIGURES_HEIGHT_PX, width_px, 3) strip of the banner's colour with `figures_lines`
    in white, the counts large; text wider than the strip is cut at its right edge."""
    out = banner_strip(FIGURES_HEIGHT_PX, width_px)
    counts, time_text = figures_lines(figures)
    for text, baseline, scale, thickness in (
        (counts, COUNTS_BASELINE_PX, COUNTS_FONT_SCALE, COUNTS_THICKNESS),
        (time_text, TIME_BASELINE_PX, TIME_FONT_SCALE, TIME_THICKNESS),
    ):
        cv2.putText(
            out,
            text,
            (MARGIN_PX, baseline),
            draw.FONT,
            scale,
            draw.TEXT_COLOUR,
            thickness,
            cv2.LINE_AA,
        )
    return out


def with_figures(picture: draw.RgbImage, figures: HeadlineFigures) -> draw.RgbImage:
    """`picture` under the strip of `figures`, as wide as it (module docstring)."""
    draw.require_rgb_image("picture", picture)
    return np.vstack([figures_strip(figures, picture.shape[1]), picture])
