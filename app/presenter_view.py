"""What the presenter view shows beside the pictures, for people who never read the papers:
a few large figures of the frame (the legend of the colours is `app.legend`'s, the layers
drawn `app.state.DEMO_LAYERS`).

Pure functions of an engine result.
"""

from __future__ import annotations

from dataclasses import dataclass

from core.engine import FrameResult


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
