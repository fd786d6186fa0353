"""The fusion engine played over a bundled drive once per test session."""

from __future__ import annotations

from functools import cache

from core.cli import DEFAULT_RECORDINGS
from core.engine import FrameResult, FusionEngine
from core.io.drive import Drive
from core.io.groundtruth import FrameTruth
from core.params import Params


@cache
def playback(name: str) -> tuple[tuple[FrameResult, FrameTruth | None], ...]:
    """Every frame of bundled drive `name` processed in order, with its ground truth."""
    with Drive(DEFAULT_RECORDINGS / name) as drive:
        engine = FusionEngine(Params(), drive.camera)
        return tuple((engine.process(drive.frame(i)), drive.truth(i)) for i in range(len(drive)))
