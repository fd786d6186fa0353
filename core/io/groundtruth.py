"""Ground truth of a recording (`groundtruth.json`): per frame, every object and guard rail.

Layout (format_version 1):

    {"format_version": 1,
     "frames": [{"index": 0, "t_ns": 0, "pitch_rad": 0.01,
                 "objects": [{"id": 3, "class": "car", "box_px": [u0, v0, u1, v1],
                              "position_m": [x, y, z], "size_m": [length, width, height],
                              "velocity_mps": [vx, vy], "radar_seen": true,
                              "occlusion": 0.0}],
                 "guard_rails": [{"id": 7, "side": "right", "polyline_px": [[u, v], ...]}]}]}

box_px is the visible part: (u0, v0) the top-left and (u1, v1) the bottom-right edge of its
pixels in continuous image coordinates (pixel centres at integers, so a box covering columns
10..19 runs from u0 = 9.5 to u1 = 19.5); position_m is the centre of the object's base
(nearest face centre for vehicles seen from behind or front) in the vehicle frame at t_ns;
velocity_mps is over ground in the vehicle frame axes; occlusion is the hidden fraction of
the object's full image box. Where the truth has no pitch or labels no guard rails (real
drives imported with their 3D labels), pitch_rad and guard_rails are null: the evaluation
then scores no pitch, and of the guard rails only the vehicles labelled guard rail. Frames
the file does not list have no truth and count neither way (a real drive's frames between
its labelled ones).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from core.io.errors import RecordingError

GROUNDTRUTH_FORMAT_VERSION = 1
OBJECT_CLASSES = ("car", "van", "truck", "pedestrian", "cyclist", "pole", "tree", "sign", "other")


@dataclass(frozen=True)
class TruthObject:
    id: int
    cls: str
    box_px: tuple[float, float, float, float]
    position_m: tuple[float, float, float]
    size_m: tuple[float, float, float]
    velocity_mps: tuple[float, float]
    radar_seen: bool
    occlusion: float

    def __post_init__(self) -> None:
        if self.cls not in OBJECT_CLASSES:
            raise ValueError(f"cls: expected one of {OBJECT_CLASSES}, got {self.cls!r}")
        if not 0.0 <= self.occlusion <= 1.0:
            raise ValueError(f"occlusion: expected a fraction in [0, 1], got {self.occlusion}")


@dataclass(frozen=True)
class TruthGuardRail:
    id: int
    side: str  # "left" or "right" of the road
    polyline_px: tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class FrameTruth:
    index: int
    t_ns: int
    pitch_rad: float
    objects: tuple[TruthObject, ...]
    guard_rails: tuple[TruthGuardRail, ...]
    rails_labelled: bool = True  # False: the truth says nothing of guard rails (null in the file)


def _object_to_json(o: TruthObject) -> dict[str, Any]:
    return {
        "id": o.id,
        "class": o.cls,
        "box_px": [round(v, 2) for v in o.box_px],
        "position_m": [round(v, 3) for v in o.position_m],
        "size_m": [round(v, 3) for v in o.size_m],
        "velocity_mps": [round(v, 3) for v in o.velocity_mps],
        "radar_seen": o.radar_seen,
        "occlusion": round(o.occlusion, 3),
    }


def write_groundtruth(frames: Sequence[FrameTruth], path: Path | str) -> None:
    """Write ground truth as compact, deterministic JSON."""
    data = {
        "format_version": GROUNDTRUTH_FORMAT_VERSION,
        "frames": [
            {
                "index": f.index,
                "t_ns": f.t_ns,
                "pitch_rad": None if math.isnan(f.pitch_rad) else round(f.pitch_rad, 6),
                "objects": [_object_to_json(o) for o in f.objects],
                "guard_rails": None
                if not f.rails_labelled
                else [
                    {
                        "id": g.id,
                        "side": g.side,
                        "polyline_px": [[round(u, 2), round(v, 2)] for u, v in g.polyline_px],
                    }
                    for g in f.guard_rails
                ],
            }
            for f in frames
        ],
    }
    Path(path).write_text(json.dumps(data, separators=(",", ":")), encoding="utf-8")


def _tuple(raw: Any, n: int, where: str) -> tuple[float, ...]:
    numbers = isinstance(raw, list) and all(isinstance(v, (int, float)) for v in raw)
    if not numbers or len(raw) != n:
        raise ValueError(f"{where}: expected a list of {n} numbers, got {raw!r}")
    return tuple(float(v) for v in raw)


def read_groundtruth(path: Path | str) -> list[FrameTruth]:
    """Read `groundtruth.json`; RecordingError names the file, frame and field on bad input."""
    p = Path(path)
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except OSError as err:
        raise RecordingError(f"{p}: cannot read ground truth: {err.strerror}") from err
    except json.JSONDecodeError as err:
        raise RecordingError(f"{p}: not valid JSON: {err}") from err
    if not isinstance(data, dict) or data.get("format_version") != GROUNDTRUTH_FORMAT_VERSION:
        got = data.get("format_version") if isinstance(data, dict) else type(data).__name__
        raise RecordingError(
            f"{p}: expected a ground-truth object with format_version "
            f"{GROUNDTRUTH_FORMAT_VERSION}, got {got!r}"
        )
    frames: list[FrameTruth] = []
    for k, f in enumerate(data.get("frames", [])):
        where = f"frames[{k}]"
        try:
            objects = tuple(
                TruthObject(
                    id=int(o["id"]),
                    cls=str(o["class"]),
                    box_px=_tuple(o["box_px"], 4, f"{where}.objects[{j}].box_px"),  # type: ignore[arg-type]
                    position_m=_tuple(o["position_m"], 3, f"{where}.objects[{j}].position_m"),  # type: ignore[arg-type]
                    size_m=_tuple(o["size_m"], 3, f"{where}.objects[{j}].size_m"),  # type: ignore[arg-type]
                    velocity_mps=_tuple(o["velocity_mps"], 2, f"{where}.objects[{j}].velocity_mps"),  # type: ignore[arg-type]
                    radar_seen=bool(o["radar_seen"]),
                    occlusion=float(o["occlusion"]),
                )
                for j, o in enumerate(f["objects"])
            )
            rails = tuple(
                TruthGuardRail(
                    id=int(g["id"]),
                    side=str(g["side"]),
                    polyline_px=tuple((float(u), float(v)) for u, v in g["polyline_px"]),
                )
                for g in f.get("guard_rails") or []
            )
            pitch = math.nan if f["pitch_rad"] is None else float(f["pitch_rad"])
            labelled = f.get("guard_rails", []) is not None
            frames.append(
                FrameTruth(int(f["index"]), int(f["t_ns"]), pitch, objects, rails, labelled)
            )
        except KeyError as err:
            raise RecordingError(f"{p}: {where}: missing field {err.args[0]!r}") from err
        except (TypeError, ValueError) as err:
            raise RecordingError(f"{p}: {where}: {err}") from err
    return frames
