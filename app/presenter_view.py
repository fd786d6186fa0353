"""What the presenter view shows beside the pictures, for people who never read the papers:
a few large figures of the frame and the picture enlarged to fill its panel (the legend of
the colours is `app.legend`'s, the layers drawn `app.state.DEMO_LAYERS`).

Pure functions of an engine result.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from app.draw import RgbImage
from core.engine import FrameResult


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
