"""Per-frame results of `fusionscope run` as JSON lines: one object per frame.

Each line holds the frame's index and time, the pitch, the stage timings, the papers'
per-frame detections (vehicles; pedestrian candidates with their verdicts; radar targets
labelled guard rail) and the tracker's confirmed tracks. Boxes are (u0, v0, u1, v1) in
full-image pixels: a vehicle's box_px is its rear face, as vision measured it, its body_px
the whole vehicle as shown (`core.vehicle`, step 12), its hidden_side "left" or "right" when
a nearer vehicle hides that side and its width is assumed, not measured (step 10), else null;
positions are in the vehicle frame (x forward, y left, metres).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from typing import Any, TextIO

from core.camera import CameraModel
from core.engine import FrameResult, Frames, FusionEngine
from core.io.errors import RecordingError
from core.params import Params

RESULTS_FORMAT_VERSION = 1


def _number(x: float, digits: int) -> float | None:
    """JSON has no NaN: unknown numbers are null."""
    return round(x, digits) if math.isfinite(x) else None


def _box(box: tuple[float, float, float, float]) -> list[float | None]:
    return [_number(float(x), 1) for x in box]


def frame_record(result: FrameResult) -> dict[str, Any]:
    """The JSON object of one frame (see the README's "fusionscope run")."""
    t = result.timings
    return {
        "version": RESULTS_FORMAT_VERSION,
        "frame": result.index,
        "t_ns": result.t_ns,
        "replayed": result.replayed,
        "pitch_rad": _number(result.pitch.pitch_rad, 6),
        "pitch_method": result.pitch.method,
        "timings_ms": {
            "pitch": _number(t.pitch_ms, 3),
            "motion_stereo": _number(t.motion_stereo_ms, 3),
            "guardrail": _number(t.guardrail_ms, 3),
            "vehicle": _number(t.vehicle_ms, 3),
            "pedestrian": _number(t.pedestrian_ms, 3),
            "tracking": _number(t.tracking_ms, 3),
            "total": _number(t.total_ms, 3),
        },
        "vehicles": [
            {
                "class": "vehicle",
                "box_px": _box(v.box_px),
                "body_px": _box(v.outline_px),
                "distance_m": _number(v.distance_m, 3),
                "lateral_m": _number(v.lateral_m, 3),
                "width_m": _number(v.width_m, 3),
                "hidden_side": v.hidden_side,
                "radar_targets": list(v.target_indices),
            }
            for v in result.vehicle.vehicles
        ],
        "pedestrians": [
            {
                "class": "pedestrian",
                "verdict": c.verdict,
                "box_px": _box(c.extended_box_px),
                "distance_m": _number(c.distance_m, 3),
                "lateral_m": _number(c.lateral_m, 3),
                "width_m": _number(c.width_m, 3),
                "height_m": _number(c.height_m, 3),
                "score": _number(c.score, 3),
            }
            for c in result.pedestrian.candidates
        ],
        "guard_rail_targets": sorted(result.guardrail.guard_rail_targets),
        "tracks": [
            {
                "id": k.id,
                "class": k.kind,
                "box_px": _box(k.box_px),
                "body_px": _box(k.outline_px),
                "x_m": _number(k.x_m, 3),
                "y_m": _number(k.y_m, 3),
                "vx_mps": _number(k.vx_mps, 3),
                "vy_mps": _number(k.vy_mps, 3),
                "width_m": _number(k.width_m, 3),
                "misses": k.misses,
            }
            for k in result.tracking.shown
        ],
    }


def write_results(
    drive: Frames,
    camera: CameraModel,
    params: Params,
    sink: TextIO,
    progress: Callable[[int, int], None] | None = None,
    strict: bool = False,
) -> tuple[tuple[int, str], ...]:
    """`fusionscope run`'s loop: every frame of `drive` through a new engine, one compact
    JSON line each into `sink`. A frame that cannot be read (RecordingError) is skipped: it
    gets no line, the engine starts over after it, and it is returned as (index, why); with
    `strict` the error is raised instead."""
    engine = FusionEngine(params, camera)
    skipped: list[tuple[int, str]] = []
    for i in range(len(drive)):
        try:
            frame = drive.frame(i)
        except RecordingError as err:
            if strict:
                raise
            skipped.append((i, str(err)))
        else:
            record = frame_record(engine.process(frame))
            sink.write(json.dumps(record, separators=(",", ":")) + "\n")
        if progress is not None:
            progress(i + 1, len(drive))
    return tuple(skipped)
