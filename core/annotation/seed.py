"""Annotation seeded from the engine: one of its confirmed tracks, followed over a clip and
stored as sparse keyframes.

`engine_track` plays the recording's frames first..last through the engine (after the
frames before `first`, from the recording's start: `core.engine`, "From the start", the
tracks the inspector shows) and follows the confirmed track of the kind asked for that
overlaps the given box most on the given frame. The track is found by its box, not its id:
the box is what the annotator drew. Its box on each frame it has one (the box of its last
associated detection) becomes a keyframe candidate; `core.annotation.model.simplify` keeps
only those that linear interpolation cannot reproduce within the tolerance, and frames
without a box become gaps.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from core.annotation.model import DEFAULT_TOLERANCE_PX, Box, Track, simplify
from core.engine import FusionEngine
from core.evaluation.objects import iou
from core.io.drive import Drive
from core.params import Params
from core.tracking import Kind

MIN_IOU = 0.3  # the engine track taken overlaps the box asked for at least this much
ANNOTATION_CLASS: dict[str, str] = {"vehicle": "car", "pedestrian": "pedestrian"}


def engine_track(
    recording: Path,
    params: Params,
    first: int,
    last: int,
    frame: int,
    box_px: Box,
    kind: Kind,
    track_id: int,
    progress: Callable[[int, int], None] = lambda done, total: None,
    tolerance_px: float = DEFAULT_TOLERANCE_PX,
) -> Track:
    """The engine's confirmed `kind` track overlapping `box_px` most on `frame` (IoU >=
    MIN_IOU), over frames first..last, as an annotation track `track_id` of the class
    ANNOTATION_CLASS[kind] (module docstring). progress(done, total) after each frame.

    ValueError naming the argument when first <= frame <= last does not hold within the
    recording, or when no such track is on `frame`; RecordingError when the recording
    cannot be read."""
    if kind not in ANNOTATION_CLASS:
        raise ValueError(f"kind: expected one of {tuple(ANNOTATION_CLASS)}, got {kind!r}")
    with Drive(recording) as drive:
        if not 0 <= first <= frame <= last < len(drive):
            raise ValueError(
                f"first, frame, last: expected 0 <= first <= frame <= last <= "
                f"{len(drive) - 1}, got {first}, {frame}, {last}"
            )
        # from the drive's start: the tracks, and their ids, the inspector shows
        engine = FusionEngine(params, drive.camera, catch_up_frames=None)
        boxes: dict[int, dict[int, Box]] = {}
        for i in range(first, last + 1):
            result = engine.seek(drive, i)
            boxes[i] = {t.id: t.box_px for t in result.tracking.of_kind(kind)}
            progress(i - first + 1, last - first + 1)
    overlaps = {tid: iou(box, box_px) for tid, box in boxes[frame].items()}
    best = max(overlaps, key=lambda tid: overlaps[tid], default=None)
    if best is None or overlaps[best] < MIN_IOU:
        raise ValueError(
            f"box_px: expected a confirmed {kind} track of the engine overlapping it on frame "
            f"{frame} (IoU >= {MIN_IOU}), found none"
        )
    followed = [(i, boxes[i][best]) for i in sorted(boxes) if best in boxes[i]]
    return Track(track_id, ANNOTATION_CLASS[kind], simplify(followed, tolerance_px))
