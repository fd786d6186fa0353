"""Engine results of a few frames of a bundled drive, computed once per test session."""

from __future__ import annotations

import functools

import numpy as np
import numpy.typing as npt

from core.cli import DEFAULT_RECORDINGS
from core.engine import FrameResult, FusionEngine
from core.io.drive import Drive
from core.params import Params

DRIVE = "highway"
# frame 90 of the highway: vehicles, a guard rail found, kept and rejected pedestrians
FRAME = 90


@functools.cache
def engine_result(drive: str = DRIVE, index: int = FRAME) -> FrameResult:
    """Frame `index` of the bundled drive `drive` from the start (`core.engine`): what the
    inspector shows, and exports."""
    with Drive(DEFAULT_RECORDINGS / drive) as d:
        return FusionEngine(Params(), d.camera, catch_up_frames=None).seek(d, index)


@functools.cache
def engine_image(drive: str = DRIVE, index: int = FRAME) -> npt.NDArray[np.uint8]:
    """The (H, W) uint8 grey camera frame `index` of the bundled drive `drive`."""
    with Drive(DEFAULT_RECORDINGS / drive) as d:
        return d.frame(index).image
