"""Ground-truth annotation of a recording: tracks of boxes stored as sparse keyframes.

A track is one object over a clip: its class, its keyframes (a box drawn or accepted on a
frame) and its attribute changes. The frames between two keyframes are interpolated
linearly, corner by corner, unless the annotator switched the gap off (the object is hidden
there: no box). A track runs from its first keyframe to its end: its last keyframe, or a
later frame where "end track here" was pressed, the last keyframe's box held until then.

An attribute (occluded, truncated, radar-seen) changes from a frame forward: setting it on
frame f adds a change at f and leaves every earlier frame as it was; a later change of the
same attribute still rules from its own frame.

`Annotations` is the whole recording: the tracks by id and the frames marked fully
annotated (the evaluation counts only those, `core.annotation.truth`). Everything here is
a frozen value; an edit returns a new value (the store journals and saves them,
`core.annotation.store`).

Boxes are `(u0, v0, u1, v1)` full-image pixels, the edges of the box as in
`core.io.groundtruth` (pixel centres at integers).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace

Box = tuple[float, float, float, float]

CLASSES = ("car", "truck", "van", "pedestrian", "cyclist", "guard_rail", "other_obstacle")
ATTRIBUTES = ("occluded", "truncated", "radar_seen")
# a track accepted from the engine keeps a frame as a keyframe when interpolation between its
# neighbours misses one of its corners by more than this (`simplify`)
DEFAULT_TOLERANCE_PX = 2.0


def check_box(name: str, box: Sequence[float]) -> Box:
    """`box` as a Box; ValueError naming `name` unless four finite numbers with u0 < u1 and
    v0 < v1."""
    values = tuple(box)
    if len(values) != 4 or not all(_finite_number(v) for v in values):
        raise ValueError(f"{name}: expected four finite numbers (u0, v0, u1, v1), got {box!r}")
    u0, v0, u1, v1 = (float(v) for v in values)
    if not (u0 < u1 and v0 < v1):
        raise ValueError(f"{name}: expected u0 < u1 and v0 < v1, got {values!r}")
    return (u0, v0, u1, v1)


def _finite_number(value: object) -> bool:
    """An int or float (not a bool) that is finite as a float (a huge int is not)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return False
    try:
        return math.isfinite(float(value))
    except OverflowError:
        return False


def _check_frame(name: str, frame: int) -> None:
    if isinstance(frame, bool) or not isinstance(frame, int) or frame < 0:
        raise ValueError(f"{name}: expected a frame index >= 0, got {frame!r}")


@dataclass(frozen=True)
class Keyframe:
    """A box the annotator drew or accepted on `frame`. distance_m: the radar's distance
    snapped to it (None: not snapped); interpolate: the frames up to the next keyframe are
    interpolated (False: a gap, the object is not annotated there)."""

    frame: int
    box_px: Box
    distance_m: float | None = None
    interpolate: bool = True

    def __post_init__(self) -> None:
        _check_frame("frame", self.frame)
        object.__setattr__(self, "box_px", check_box("box_px", self.box_px))
        if self.distance_m is not None and not (
            _finite_number(self.distance_m) and self.distance_m > 0
        ):
            raise ValueError(
                f"distance_m: expected a distance > 0 or None, got {self.distance_m!r}"
            )
        if not isinstance(self.interpolate, bool):
            raise ValueError(f"interpolate: expected true or false, got {self.interpolate!r}")


@dataclass(frozen=True)
class AttributeChange:
    """Attribute `name` is `value` from `frame` on (until its next change)."""

    frame: int
    name: str
    value: bool

    def __post_init__(self) -> None:
        _check_frame("frame", self.frame)
        if self.name not in ATTRIBUTES:
            raise ValueError(f"name: expected one of {ATTRIBUTES}, got {self.name!r}")
        if not isinstance(self.value, bool):
            raise ValueError(f"value: expected true or false, got {self.value!r}")


@dataclass(frozen=True)
class Shown:
    """A track's box on one frame: keyframe (drawn there) or interpolated."""

    track_id: int
    cls: str
    box_px: Box
    keyframe: bool
    distance_m: float | None
    attributes: dict[str, bool]


def interpolate(a: Keyframe, b: Keyframe, frame: int) -> Box:
    """The box on `frame` (a.frame <= frame <= b.frame) on the line from a's box to b's,
    each corner coordinate linear in the frame index."""
    s = (frame - a.frame) / (b.frame - a.frame)
    return (
        a.box_px[0] + s * (b.box_px[0] - a.box_px[0]),
        a.box_px[1] + s * (b.box_px[1] - a.box_px[1]),
        a.box_px[2] + s * (b.box_px[2] - a.box_px[2]),
        a.box_px[3] + s * (b.box_px[3] - a.box_px[3]),
    )


@dataclass(frozen=True)
class Track:
    """One object over a clip (module docstring). keyframes: at least one, strictly
    increasing frames; changes: attribute changes, one per (frame, name), sorted by frame;
    end_frame: the last frame the track is in when after its last keyframe (None: it ends
    at its last keyframe)."""

    id: int
    cls: str
    keyframes: tuple[Keyframe, ...]
    changes: tuple[AttributeChange, ...] = ()
    end_frame: int | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "keyframes", tuple(self.keyframes))
        object.__setattr__(self, "changes", tuple(self.changes))
        if self.keyframes and not self.keyframes[-1].interpolate:
            # nothing follows the last keyframe: its gap flag would resurface when a later
            # box is drawn, so it is never kept
            last = replace(self.keyframes[-1], interpolate=True)
            object.__setattr__(self, "keyframes", (*self.keyframes[:-1], last))
        if isinstance(self.id, bool) or not isinstance(self.id, int) or self.id < 1:
            raise ValueError(f"id: expected a track id >= 1, got {self.id!r}")
        if self.cls not in CLASSES:
            raise ValueError(f"cls: expected one of {CLASSES}, got {self.cls!r}")
        frames = [k.frame for k in self.keyframes]
        if not frames or any(b <= a for a, b in itertools.pairwise(frames)):
            raise ValueError(
                f"keyframes: expected one or more with increasing frames, got frames {frames}"
            )
        keys = [(c.frame, c.name) for c in self.changes]
        if keys != sorted(set(keys)):
            raise ValueError(
                f"changes: expected one per frame and attribute, sorted by frame, got {keys}"
            )
        if self.end_frame is not None:
            _check_frame("end_frame", self.end_frame)
            if self.end_frame <= frames[-1]:
                raise ValueError(
                    f"end_frame: expected a frame after the last keyframe {frames[-1]}, "
                    f"got {self.end_frame}"
                )

    @property
    def first_frame(self) -> int:
        return self.keyframes[0].frame

    @property
    def last_frame(self) -> int:
        """The last frame the track is in."""
        return self.keyframes[-1].frame if self.end_frame is None else self.end_frame

    def keyframe_at(self, frame: int) -> Keyframe | None:
        return next((k for k in self.keyframes if k.frame == frame), None)

    def _around(self, frame: int) -> tuple[Keyframe, Keyframe | None]:
        """The last keyframe at or before `frame` (first_frame <= frame) and the next one."""
        before = [k for k in self.keyframes if k.frame <= frame]
        after = [k for k in self.keyframes if k.frame > frame]
        return before[-1], (after[0] if after else None)

    def box_at(self, frame: int) -> tuple[Box, bool, float | None] | None:
        """(box, is a keyframe, distance_m) on `frame`; None when the track is not there
        (before its start, after its end, in a gap). Interpolated frames have no distance."""
        if not self.first_frame <= frame <= self.last_frame:
            return None
        a, b = self._around(frame)
        if a.frame == frame:
            return a.box_px, True, a.distance_m
        if b is None:
            return a.box_px, False, None  # held until end_frame
        if not a.interpolate:
            return None
        return interpolate(a, b, frame), False, None

    def attributes_at(self, frame: int) -> dict[str, bool]:
        """Each attribute's value on `frame` (False before its first change)."""
        values = dict.fromkeys(ATTRIBUTES, False)
        for change in self.changes:
            if change.frame <= frame:
                values[change.name] = change.value
        return values

    # --- edits: each returns a new track --------------------------------------------------
    def with_box(
        self, frame: int, box_px: Sequence[float], distance_m: float | None = None
    ) -> Track:
        """A keyframe with `box_px` on `frame` (drawn, moved or resized there), replacing one
        on that frame. A frame after the end extends the track to it."""
        old = self.keyframe_at(frame)
        interpolate_on = old.interpolate if old is not None else True
        if old is None and self.first_frame < frame < self.keyframes[-1].frame:
            interpolate_on = self._around(frame)[0].interpolate  # inside a gap: stays a gap
        key = Keyframe(frame, check_box("box_px", box_px), distance_m, interpolate_on)
        keyframes = tuple(
            sorted([*(k for k in self.keyframes if k.frame != frame), key], key=lambda k: k.frame)
        )
        end = self.end_frame if self.end_frame is not None and self.end_frame > frame else None
        return replace(self, keyframes=keyframes, end_frame=end)

    def without_keyframe(self, frame: int) -> Track | None:
        """The track without its keyframe on `frame` (None when it was the only one).
        ValueError when there is no keyframe on `frame`."""
        if self.keyframe_at(frame) is None:
            raise ValueError(f"frame: track {self.id} has no keyframe on frame {frame}")
        keyframes = tuple(k for k in self.keyframes if k.frame != frame)
        return replace(self, keyframes=keyframes) if keyframes else None

    def with_class(self, cls: str) -> Track:
        return replace(self, cls=cls)

    def with_attribute(self, frame: int, name: str, value: bool) -> Track:
        """Attribute `name` is `value` from `frame` on, up to its next change; earlier frames
        keep theirs. A change that restates the value before it is not stored."""
        change = AttributeChange(frame, name, value)
        others = [c for c in self.changes if (c.frame, c.name) != (frame, name)]
        ordered = sorted([*others, change], key=lambda c: (c.frame, c.name))
        out: list[AttributeChange] = []
        current = dict.fromkeys(ATTRIBUTES, False)
        for c in ordered:
            if current[c.name] != c.value:
                out.append(c)
                current[c.name] = c.value
        return replace(self, changes=tuple(out))

    def with_interpolation(self, frame: int, on: bool) -> Track:
        """Interpolate (or not: a gap) between the keyframe at or before `frame` and the
        next. ValueError when `frame` lies in no span between two keyframes."""
        if not self.first_frame <= frame < self.keyframes[-1].frame:
            raise ValueError(
                f"frame: expected a frame between track {self.id}'s first and last keyframes "
                f"({self.first_frame}..{self.keyframes[-1].frame - 1}), got {frame}"
            )
        a, _ = self._around(frame)
        keyframes = tuple(replace(k, interpolate=on) if k is a else k for k in self.keyframes)
        return replace(self, keyframes=keyframes)

    def ended_at(self, frame: int) -> Track:
        """The track ends on `frame` (it is still there): keyframes after it go; on a frame
        between two keyframes, the box shown there becomes a keyframe; in a gap, the track
        ends at the keyframe before it. ValueError before the track's first frame."""
        if frame < self.first_frame:
            raise ValueError(
                f"frame: track {self.id} starts on frame {self.first_frame}, cannot end on {frame}"
            )
        shown = self.box_at(frame)
        kept = tuple(k for k in self.keyframes if k.frame <= frame)
        if kept[-1].frame == frame:
            return replace(self, keyframes=kept, end_frame=None)
        if frame < self.keyframes[-1].frame:
            if shown is None:  # in a gap: the track ends where it was last seen
                return replace(self, keyframes=kept, end_frame=None)
            last = Keyframe(frame, shown[0], None, True)
            return replace(self, keyframes=(*kept, last), end_frame=None)
        return replace(self, keyframes=kept, end_frame=frame)


def simplify(
    boxes: Sequence[tuple[int, Sequence[float]]], tolerance_px: float = DEFAULT_TOLERANCE_PX
) -> tuple[Keyframe, ...]:
    """Sparse keyframes for a box on each of `boxes`' frames ((frame, box), increasing
    frames): the fewest, found by Ramer-Douglas-Peucker on the frame axis, such that
    interpolation reproduces every given box within `tolerance_px` on each corner
    coordinate. A frame missing from `boxes` between two given ones makes a gap (the
    keyframe before it does not interpolate). ValueError on unordered frames, bad boxes or
    a negative tolerance."""
    if not (math.isfinite(tolerance_px) and tolerance_px >= 0):
        raise ValueError(f"tolerance_px: expected a number >= 0, got {tolerance_px}")
    given = [Keyframe(f, check_box(f"boxes[{i}]", b)) for i, (f, b) in enumerate(boxes)]
    frames = [k.frame for k in given]
    if any(b <= a for a, b in itertools.pairwise(frames)):
        raise ValueError(f"boxes: expected increasing frames, got {frames}")
    out: list[Keyframe] = []
    start = 0
    for end in range(1, len(given) + 1):  # runs of consecutive frames
        if end == len(given) or given[end].frame != given[end - 1].frame + 1:
            run = given[start:end]
            chosen = [run[m] for m in sorted(douglas_peucker(run, tolerance_px))]
            last_of_run = end < len(given)
            out += [
                replace(k, interpolate=False) if last_of_run and k is chosen[-1] else k
                for k in chosen
            ]
            start = end
    return tuple(out)


def douglas_peucker(
    keys: Sequence[Keyframe], tolerance_px: float, first: int = 0, last: int | None = None
) -> set[int]:
    """Indices into `keys` (boxes on increasing frames) of those to keep between `first` and
    `last` (both kept; default: all of them) so that linear interpolation between the kept
    ones reproduces every other within `tolerance_px` on each corner coordinate
    (Ramer-Douglas-Peucker on the frame axis)."""
    last = len(keys) - 1 if last is None else last
    keep = {first, last}
    spans = [(first, last)]
    while spans:
        i, j = spans.pop()
        worst, at = -1.0, -1
        for m in range(i + 1, j):
            guess = interpolate(keys[i], keys[j], keys[m].frame)
            error = max(abs(g - t) for g, t in zip(guess, keys[m].box_px, strict=True))
            if error > worst:
                worst, at = error, m
        if worst > tolerance_px:
            keep.add(at)
            spans += [(i, at), (at, j)]
    return keep


def _merged(ranges: Iterable[tuple[int, int]]) -> tuple[tuple[int, int], ...]:
    out: list[tuple[int, int]] = []
    for a, b in sorted(ranges):
        if out and a <= out[-1][1] + 1:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return tuple(out)


@dataclass(frozen=True)
class Annotations:
    """A recording's annotations: tracks (unique ids, sorted by id) and the frames marked
    fully annotated as sorted, disjoint, inclusive (first, last) ranges."""

    tracks: tuple[Track, ...] = ()
    annotated: tuple[tuple[int, int], ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "tracks", tuple(self.tracks))
        object.__setattr__(self, "annotated", tuple(tuple(r) for r in self.annotated))
        ids = [t.id for t in self.tracks]
        if ids != sorted(set(ids)):
            raise ValueError(f"tracks: expected unique ids in increasing order, got {ids}")
        for a, b in self.annotated:
            _check_frame("annotated", a)
            _check_frame("annotated", b)
        if _merged(self.annotated) != tuple(self.annotated) or any(
            a > b for a, b in self.annotated
        ):
            raise ValueError(
                f"annotated: expected sorted, disjoint (first, last) ranges, got {self.annotated}"
            )

    def track(self, track_id: int) -> Track | None:
        return next((t for t in self.tracks if t.id == track_id), None)

    def next_id(self) -> int:
        return max((t.id for t in self.tracks), default=0) + 1

    def is_annotated(self, frame: int) -> bool:
        return any(a <= frame <= b for a, b in self.annotated)

    def shown_at(self, frame: int) -> tuple[Shown, ...]:
        """Every track's box on `frame`, by track id."""
        out = []
        for t in self.tracks:
            box = t.box_at(frame)
            if box is not None:
                out.append(Shown(t.id, t.cls, box[0], box[1], box[2], t.attributes_at(frame)))
        return tuple(out)

    def with_track(self, track: Track) -> Annotations:
        """`track` added, or put in place of the track with its id."""
        others = [t for t in self.tracks if t.id != track.id]
        return replace(self, tracks=tuple(sorted([*others, track], key=lambda t: t.id)))

    def without_track(self, track_id: int) -> Annotations:
        return replace(self, tracks=tuple(t for t in self.tracks if t.id != track_id))

    def with_annotated(self, first: int, last: int, on: bool = True) -> Annotations:
        """Frames first..last marked fully annotated (or no longer)."""
        _check_frame("first", first)
        _check_frame("last", last)
        if last < first:
            raise ValueError(f"last: expected a frame >= first ({first}), got {last}")
        kept: list[tuple[int, int]] = []
        for a, b in self.annotated:  # on ranges, not frame sets: a range may be long
            if on or b < first or a > last:
                kept.append((a, b))
                continue
            if a < first:
                kept.append((a, first - 1))
            if b > last:
                kept.append((last + 1, b))
        if on:
            kept.append((first, last))
        return replace(self, annotated=_merged(kept))
