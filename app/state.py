"""What one browser tab is looking at: the frame, whether it plays, which layers are shown.

The state is a small frozen value; controls replace it with `dataclasses.replace` and the
renderer only ever sees a snapshot, so a frame's image and its overlays always agree.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Layers:
    """Which overlays are drawn on the camera image."""

    radar: bool = True
    truth: bool = True
    horizon: bool = True


@dataclass(frozen=True)
class ViewState:
    """Per-client view: frame index into the drive, playback flag, overlay layers."""

    frame: int = 0
    playing: bool = False
    layers: Layers = field(default_factory=Layers)

    def __post_init__(self) -> None:
        if self.frame < 0:
            raise ValueError(f"frame: expected an index >= 0, got {self.frame}")
