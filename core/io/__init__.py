"""Recordings: the folder format, its writer and its reader (see manifest.py for the layout)."""

from core.io.calibration import Calibration, RadarMount, load_calibration, save_calibration
from core.io.canlog import SignalMapping, VehicleSignals, read_vehicle_signals
from core.io.drive import Drive
from core.io.errors import RecordingError
from core.io.frame import FrameInput, RadarTarget
from core.io.groundtruth import (
    FrameTruth,
    TruthGuardRail,
    TruthObject,
    read_groundtruth,
    write_groundtruth,
)
from core.io.manifest import BagStream, CanSource, Manifest, TimeOffsets, load_manifest
from core.io.radarscans import RadarScans
from core.io.writer import RecordingWriter

__all__ = [
    "BagStream",
    "Calibration",
    "CanSource",
    "Drive",
    "FrameInput",
    "FrameTruth",
    "Manifest",
    "RadarMount",
    "RadarScans",
    "RadarTarget",
    "RecordingError",
    "RecordingWriter",
    "SignalMapping",
    "TimeOffsets",
    "TruthGuardRail",
    "TruthObject",
    "VehicleSignals",
    "load_calibration",
    "load_manifest",
    "read_groundtruth",
    "read_vehicle_signals",
    "save_calibration",
    "write_groundtruth",
]
