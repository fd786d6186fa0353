"""Annotation mode of one browser tab: boxes drawn on the frame in the 3D scene, edited and
seeded from the engine's detections, every action a store edit that can be undone.

Off by default (viewers never see it change anything). When on, the frame lies in the 3D
scene on a plane seen from straight above (`app.annotation_view`), because viser 1.1.1's
GUI image has no pointer events and scene nodes have: a drag on the frame draws a box, a
drag inside a box moves it, a drag from a corner of the selected box resizes it, a click
selects the smallest box under the pointer. The Annotation folder holds the class, the
track to continue, the attributes of the selected track (from this frame on), the
interpolation after this frame, end/delete, "accept" of the engine's detections, radar
snapping, and "this frame is fully annotated".

Every action is one `Edit` of the recording's `AnnotationStore` (journaled, saved at once)
based on the revision this tab last saw; a conflicting edit (another tab changed the track
since) is refused with a notification and the tab shows the store's current state. Undo
and redo are `Change`s on the tab's history, shared with parameter changes: an undo is
itself an edit putting the old tracks back.
"""

from __future__ import annotations

import functools
import math
import tempfile
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Protocol

import viser

from app.annotation_view import (
    PLANE_WXYZ,
    PLANE_Z_M,
    PX_TO_M,
    DragAction,
    Seeds,
    annotated_picture,
    box_under,
    drag_action,
    dragged_box,
    pixel_of,
    plane_pixel,
    snapped_distance_m,
)
from app.draw import RgbImage
from app.history import Change, History
from app.params_panel import NoticeColour
from core.annotation.formats import FORMATS, export_annotations, import_annotations
from core.annotation.model import CLASSES, Annotations, Box, Keyframe, Track
from core.annotation.seed import engine_track
from core.annotation.store import AnnotationStore, Conflict, Edit, EditError
from core.io.errors import RecordingError
from core.params import Params
from core.tracking import Kind

NEW_TRACK = "new track"
NO_TRACK = "(none)"
NO_DETECTION = "(none)"
FILE_SUFFIX = {"mot": "txt", "kitti": "txt", "coco": "json", "cvat": "xml"}
VIEW_MARGIN = 1.15  # the top-down camera sees this much more than the frame
DETECTION_CLASS = {"vehicle": "car", "pedestrian": "pedestrian"}


class Notify(Protocol):
    """A notification in the tab (`ClientSession.notify`)."""

    def __call__(self, title: str, message: str, color: NoticeColour = "red") -> None: ...


class AnnotationPanel:
    """The Annotation folder and the annotation plane of one client (module docstring).

    history: the tab's undo stack; notify(title, message): a notification in this tab;
    order: the folder's place; on_toggle(on): annotation mode switched (the session then
    asks for pictures with the bare frame, which `show_frame` receives); params: the
    parameters the tab's engine runs with (set A), to follow an engine track with.
    """

    def __init__(
        self,
        client: viser.ClientHandle,
        history: History,
        notify: Notify,
        order: float,
        on_toggle: Callable[[bool], None],
        params: Callable[[], Params],
    ) -> None:
        self.client = client
        self._on_toggle = on_toggle
        self._params = params
        self._history = history
        self._notify = notify
        self._lock = threading.Lock()
        self._store: AnnotationStore | None = None
        self._frame = 0
        self._frame_count = 0
        self._rgb: RgbImage | None = None
        self._seeds = Seeds(0)
        self._selected: int | None = None
        self._drag: tuple[DragAction, Box | None, tuple[float, float]] | None = None
        self._image: viser.ImageHandle | None = None
        self._aimed = False  # the 3D camera looks down on the plane
        self._following = False  # an engine track is being followed over a clip
        # what this tab last showed, and its revision: the person acts on it, so clicks are
        # tested against it and edits are built from it and based on that revision
        self._seen = Annotations()
        self._seen_revision = 0
        gui = client.gui
        with gui.add_folder("Annotation", order=order, expand_by_default=False):
            self._on = gui.add_checkbox("annotate", False, hint="draw and edit ground truth")
            self._status = gui.add_markdown("")
            self._cls = gui.add_dropdown(
                "class",
                CLASSES,
                initial_value="car",
                hint="of the selected box, or of the next new one",
            )
            self._continue = gui.add_dropdown("continue track", (NEW_TRACK,))
            self._occluded = gui.add_checkbox("occluded (from here on)", False)
            self._truncated = gui.add_checkbox("truncated (from here on)", False)
            self._radar_seen = gui.add_checkbox("radar-seen (from here on)", False)
            self._interpolate = gui.add_checkbox("interpolate to the next keyframe", True)
            buttons = gui.add_button_group("selected", ("Delete key", "Delete track", "End here"))
            self._snap = gui.add_button("Snap distance to radar")
            self._detection = gui.add_dropdown("detection", (NO_DETECTION,))
            accept = gui.add_button_group("accept", ("This detection", "All detections here"))
            self._done = gui.add_checkbox("this frame is fully annotated", False)
            self._range = gui.add_text("frames", "", hint="a range such as 0-19")
            marks = gui.add_button_group("mark frames", ("Annotated", "Not annotated"))
            self._engine_track = gui.add_dropdown("engine track", (NO_TRACK,))
            self._follow = gui.add_button(
                "Accept it over the frames", hint="the engine's track, as sparse keyframes"
            )
            self._format = gui.add_dropdown("file format", FORMATS, initial_value="cvat")
            self._download = gui.add_button("Download the annotations")
            self._upload = gui.add_upload_button(
                "Import a file (replaces all)", hint="undo brings the old annotations back"
            )
        # what changes the annotations: disabled when the store refuses edits (viser's button
        # groups cannot be; an edit from them is refused with the reason)
        self._edit_controls = (
            self._cls,
            self._continue,
            self._occluded,
            self._truncated,
            self._radar_seen,
            self._interpolate,
            self._snap,
            self._detection,
            self._done,
            self._range,
            self._engine_track,
            self._follow,
            self._upload,
        )
        self._on.on_update(lambda _: self._toggle())
        self._cls.on_update(lambda event: self._from_user(event, self._set_class))
        self._continue.on_update(lambda event: self._from_user(event, self._pick_track))
        self._attribute_boxes = {
            "occluded": self._occluded,
            "truncated": self._truncated,
            "radar_seen": self._radar_seen,
        }
        for name, box in self._attribute_boxes.items():
            box.on_update(functools.partial(self._attribute_changed, name))
        self._interpolate.on_update(lambda event: self._from_user(event, self._set_interpolation))
        buttons.on_click(lambda event: self._button(event.target.value))
        self._snap.on_click(lambda _: self._snap_distance())
        accept.on_click(lambda event: self._accept_chosen(event.target.value == "This detection"))
        self._done.on_update(lambda event: self._from_user(event, self._set_done))
        marks.on_click(lambda event: self._mark_range(event.target.value == "Annotated"))
        self._follow.on_click(lambda _: self._start_following())
        self._download.on_click(lambda _: self._send_download())
        self._upload.on_upload(lambda event: self._import(event.target.value))

    # --- from the session ----------------------------------------------------------------
    def open(self, store: AnnotationStore | None, frame_count: int) -> None:
        """Annotate the store of a recording of `frame_count` frames (None: it cannot be
        annotated)."""
        with self._lock:
            self._store = store
            self._frame_count = frame_count
            self._selected = None
        self._refresh()

    def show_frame(self, frame: int, rgb: RgbImage, seeds: Seeds) -> None:
        """The frame shown changed (or its pictures were redrawn)."""
        with self._lock:
            self._frame, self._rgb, self._seeds = frame, rgb, seeds
        self._refresh()
        if self.active and not self._aimed:
            self._look_at_plane()

    @property
    def active(self) -> bool:
        return bool(self._on.value)

    # --- edits ---------------------------------------------------------------------------
    def _from_user(self, event: viser.GuiEvent, action: Callable[[], None]) -> None:
        """Run `action` for a change a person made (a value set by `_refresh` has no client)."""
        if event.client is not None:
            action()

    def _attribute_changed(self, name: str, event: viser.GuiEvent) -> None:
        box = self._attribute_boxes[name]
        self._from_user(event, lambda: self._set_attribute(name, bool(box.value)))

    def _annotations(self) -> Annotations:
        return self._seen

    def _commit(
        self,
        label: str,
        tracks: dict[int, Track | None],
        marked: tuple[int, int, bool] | None = None,
    ) -> bool:
        """Apply one edit (tracks put or deleted, frames first..last marked annotated or
        not), based on the revision this tab last showed, with undo and redo."""
        return self._commit_ranges(label, tracks, () if marked is None else (marked,))

    def _commit_ranges(
        self,
        label: str,
        tracks: dict[int, Track | None],
        ranges: tuple[tuple[int, int, bool], ...],
    ) -> bool:
        store = self._store
        if store is None or not (tracks or ranges):
            return False
        before = self._seen
        edit = Edit(self._seen_revision, tracks, ranges, label)
        if not self._apply(edit):
            return False

        def undo() -> None:
            if store is self._store:
                self._apply(edit.inverse(before, self._seen_revision))

        def redo() -> None:
            if store is self._store:
                self._apply(Edit(self._seen_revision, tracks, ranges, label))

        self._history.push(Change(label, undo, redo))
        return True

    def _apply(self, edit: Edit) -> bool:
        """One edit to the store; a refusal becomes a notification and the tab shows the
        store's state as it is."""
        store = self._store
        if store is None:
            return False
        try:
            store.apply(edit)
        except Conflict as err:
            self._notify("Not saved: another tab changed this", str(err))
            self._refresh()
            return False
        except (EditError, ValueError, OSError) as err:
            self._notify("Not saved", str(err))
            self._refresh()
            return False
        self._refresh()
        return True

    def _selected_track(self) -> Track | None:
        return None if self._selected is None else self._annotations().track(self._selected)

    def _pick_track(self) -> None:
        """ "new track": nothing selected, the next box starts a track of the class chosen;
        a track: it is selected, and the next box drawn is its keyframe on this frame."""
        chosen = self._continue.value
        self._selected = None if chosen == NEW_TRACK else int(chosen.lstrip("#"))
        self._refresh()

    def _set_class(self) -> None:
        track = self._selected_track()
        if track is not None and track.cls != self._cls.value:
            self._commit(f"class of #{track.id}", {track.id: track.with_class(self._cls.value)})

    def _set_attribute(self, name: str, value: bool) -> None:
        track = self._selected_track()
        if track is not None:
            changed = track.with_attribute(self._frame, name, value)
            self._commit(f"{name} of #{track.id}", {track.id: changed})

    def _set_interpolation(self) -> None:
        track = self._selected_track()
        if track is None:
            return
        try:
            changed = track.with_interpolation(self._frame, bool(self._interpolate.value))
        except ValueError as err:
            self._notify("No keyframe after this frame", str(err))
            self._refresh()
            return
        self._commit(f"interpolation of #{track.id}", {track.id: changed})

    def _set_done(self) -> None:
        on = bool(self._done.value)
        self._commit(f"frame {self._frame} annotated", {}, (self._frame, self._frame, on))

    def _typed_range(self) -> tuple[int, int] | None:
        """The frames typed as "first-last" (or one frame); None, with a notification, when
        they are not frames of this drive."""
        text = self._range.value.strip()
        first, _, last = text.partition("-")
        try:
            a, b = int(first), int(last or first)
        except ValueError:
            self._notify(
                "Frames not understood", f'expected "first-last" such as 0-19, got {text!r}'
            )
            return None
        if not 0 <= a <= b < self._frame_count:
            self._notify(
                "Frames not in this drive",
                f"expected 0 <= first <= last <= {self._frame_count - 1}, got {a}-{b}",
            )
            return None
        return a, b

    def _mark_range(self, on: bool) -> None:
        """The typed frames marked fully annotated, or no longer."""
        frames = self._typed_range()
        if frames is not None:
            word = "annotated" if on else "not annotated"
            self._commit(f"frames {frames[0]}-{frames[1]} {word}", {}, (*frames, on))

    def _start_following(self) -> None:
        """The chosen engine track over the typed frames, on a background thread (the
        engine plays the clip), then one edit adding it as a new track."""
        choice = self._engine_track.value
        track = next((t for t in self._seeds.tracks if _track_label(t) == choice), None)
        if track is None:
            self._notify("No engine track chosen", "pick one of this frame's tracks first")
            return
        frames = self._typed_range()
        store = self._store
        if frames is None or store is None:
            return
        if not frames[0] <= self._frame <= frames[1]:
            self._notify("Frames without this one", f"expected a range around frame {self._frame}")
            return
        kind, _, box = track
        args = (store.folder, self._params(), *frames, self._frame, box, kind)
        with self._lock:
            if self._following:
                return  # one at a time
            self._following = True
        self._follow.disabled = True
        threading.Thread(target=self._follow_track, args=args, daemon=True).start()

    def _follow_track(
        self,
        recording: Path,
        params: Params,
        first: int,
        last: int,
        frame: int,
        box: Box,
        kind: Kind,
    ) -> None:
        try:
            track = engine_track(
                recording, params, first, last, frame, box, kind, self._seen.next_id()
            )
        except (ValueError, RecordingError) as err:
            self._notify("Track not accepted", str(err))
        else:
            label = f"engine {kind} track over frames {first}-{last} as #{track.id}"
            if self._commit(label, {track.id: track}):
                self._notify(
                    "Track accepted",
                    f"#{track.id}: {len(track.keyframes)} keyframes for frames "
                    f"{track.first_frame}-{track.last_frame}",
                    "green",
                )
        finally:
            self._following = False
            self._follow.disabled = False

    def _send_download(self) -> None:
        """The annotations as shown, in the chosen format, as a file download."""
        if self._rgb is None or self._store is None:
            return
        fmt = self._format.value
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / f"{self._store.folder.name}-annotations.{FILE_SUFFIX[fmt]}"
            export_annotations(
                self._seen, path, fmt, frame_count=self._frame_count, image_size_px=self._size()
            )
            self.client.send_file_download(path.name, path.read_bytes(), save_immediately=True)

    def _import(self, upload: viser.UploadedFile) -> None:
        """An uploaded file in the chosen format replaces every track and annotated frame,
        as one edit (undo brings the old ones back)."""
        fmt = self._format.value
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / Path(upload.name).name
            path.write_bytes(upload.content)
            try:
                imported = import_annotations(path, fmt, frame_count=self._frame_count)
            except (RecordingError, ValueError) as err:  # named as uploaded, not as saved here
                self._notify(
                    f"{upload.name} not imported", str(err).replace(str(path), upload.name)
                )
                return
        old = self._seen
        tracks: dict[int, Track | None] = {t.id: None for t in old.tracks}
        tracks.update({t.id: t for t in imported.tracks})
        ranges = [(a, b, False) for a, b in old.annotated]
        ranges += [(a, b, True) for a, b in imported.annotated]
        if self._commit_ranges(f"import {upload.name}", tracks, tuple(ranges)):
            self._notify(
                f"{upload.name} imported",
                f"{len(imported.tracks)} tracks replace {len(old.tracks)}",
                "green",
            )

    def _button(self, which: str) -> None:
        track = self._selected_track()
        if track is None:
            self._notify("No track selected", "click a box on the frame first")
            return
        try:
            if which == "Delete key":
                self._commit(
                    f"keyframe of #{track.id}", {track.id: track.without_keyframe(self._frame)}
                )
            elif which == "Delete track":
                self._commit(f"track #{track.id}", {track.id: None})
                self._selected = None
            else:
                self._commit(f"end of #{track.id}", {track.id: track.ended_at(self._frame)})
        except ValueError as err:
            self._notify(f"{which}: not on this frame", str(err))
        self._refresh()

    def _snap_distance(self) -> None:
        track = self._selected_track()
        shown = None if track is None else track.box_at(self._frame)
        if track is None or shown is None:
            self._notify("No box selected", "click a box on the frame first")
            return
        distance = snapped_distance_m(shown[0], self._seeds.radar_bases)
        if distance is None:
            self._notify("No radar target", "no radar target's base lies inside the box")
            return
        changed = track.with_box(self._frame, shown[0], distance)
        self._commit(f"distance of #{track.id}", {track.id: changed})

    def _accept_chosen(self, one: bool) -> None:
        """The detection chosen, or all of this frame's, accepted."""
        detections = self._seeds.detections
        if one:
            labels = _detection_labels(detections)
            detections = tuple(
                d for d, n in zip(detections, labels, strict=True) if n == self._detection.value
            )
        self._accept(detections)

    def _accept(self, detections: Sequence[tuple[str, Box]]) -> None:
        """Each detection becomes a new track with one keyframe (with its radar distance)."""
        if self._seeds.frame != self._frame or not detections:
            self._notify("Nothing to accept", "the engine found nothing on this frame")
            return
        first = self._annotations().next_id()
        tracks: dict[int, Track | None] = {}
        for k, (kind, box) in enumerate(detections):
            distance = snapped_distance_m(box, self._seeds.radar_bases)
            key = Keyframe(self._frame, box, distance)
            tracks[first + k] = Track(
                first + k, DETECTION_CLASS.get(kind, "other_obstacle"), (key,)
            )
        self._commit(f"{len(tracks)} detections accepted", tracks)

    # --- the plane -----------------------------------------------------------------------
    def _toggle(self) -> None:
        self._on_toggle(self.active)
        self._aimed = False
        if self.active:
            self._refresh()
            self._look_at_plane()
        elif self._image is not None:
            self._image.remove()
            self._image = None

    def _look_at_plane(self) -> None:
        """Point the tab's 3D camera straight down at the plane, the whole frame in view."""
        if self._rgb is None:
            return
        h, w = self._rgb.shape[:2]
        camera = self.client.camera
        half_tan = math.tan(camera.fov / 2)  # vertical field of view
        distance_m = VIEW_MARGIN * max(
            h * PX_TO_M / 2 / half_tan, w * PX_TO_M / 2 / (half_tan * max(camera.aspect, 0.1))
        )
        camera.up_direction = (0.0, 1.0, 0.0)
        camera.position = (0.0, 0.0, PLANE_Z_M + distance_m)
        camera.look_at = (0.0, 0.0, PLANE_Z_M)
        self._aimed = True

    def _size(self) -> tuple[int, int]:
        assert self._rgb is not None
        return int(self._rgb.shape[1]), int(self._rgb.shape[0])

    def _on_click(self, event: viser.SceneNodePointerEvent[viser.ImageHandle]) -> None:
        """Select the smallest box under the pointer (none: nothing selected)."""
        if self._rgb is None:
            return
        pixel = plane_pixel(event.ray_origin, event.ray_direction, self._size())
        if pixel is None:
            return
        under = box_under(pixel, self._annotations().shown_at(self._frame))
        self._selected = None if under is None else under.track_id
        self._refresh()

    def _on_drag(self, event: viser.SceneNodeDragEvent[viser.ImageHandle]) -> None:
        if self._rgb is None or self._store is None:
            return
        size = self._size()
        if event.phase == "start":
            start = pixel_of(event.start_position, size)
            shown = self._annotations().shown_at(self._frame)
            action = drag_action(start, shown, self._selected)
            box = next((s.box_px for s in shown if s.track_id == action.track_id), None)
            self._drag = (action, box, start)
            if action.track_id is not None:
                self._selected = action.track_id
            return
        if self._drag is None:
            return
        action, box, start = self._drag
        end = pixel_of(event.end_position, size)
        new_box = dragged_box(action, box, start, end, size)
        if event.phase == "update":
            self._refresh(draft=new_box, sync=False)  # the drag acts on what it started on
            return
        self._drag = None
        if new_box is None:
            self._refresh()
            return
        if action.kind == "draw":
            self._draw(new_box)
        elif action.track_id is not None:
            track = self._annotations().track(action.track_id)
            if track is not None:
                self._commit(
                    f"box of #{track.id}", {track.id: track.with_box(self._frame, new_box)}
                )

    def _draw(self, box: Box) -> None:
        ann = self._annotations()
        chosen = self._continue.value
        if chosen != NEW_TRACK and ann.track(int(chosen.lstrip("#"))) is not None:
            track = ann.track(int(chosen.lstrip("#")))
            assert track is not None
            changed = track.with_box(self._frame, box)
        else:
            changed = Track(ann.next_id(), self._cls.value, (Keyframe(self._frame, box),))
        if self._commit(f"box of #{changed.id}", {changed.id: changed}):
            self._selected = changed.id
            self._refresh()

    # --- what the tab shows --------------------------------------------------------------
    def _refresh(self, draft: Box | None = None, sync: bool = True) -> None:
        """The plane's picture and the folder's controls: from the store's current state
        (sync), or from what the tab showed last, with the box being dragged."""
        store, rgb = self._store, self._rgb
        if sync:
            snapshot = (Annotations(), 0) if store is None else store.snapshot()
            self._seen, self._seen_revision = snapshot
        ann = self._seen
        editable = store is not None and store.read_only_reason is None
        for control in self._edit_controls:
            if control.disabled == editable:
                control.disabled = not editable
        if store is None:
            self._status.content = "This recording cannot be annotated here."
        elif store.read_only_reason is not None:
            self._status.content = f"**Read-only:** {store.read_only_reason}"
        else:
            self._status.content = (
                f"{len(ann.tracks)} tracks, revision {self._seen_revision}; "
                f"frames annotated: {_ranges_text(ann.annotated)}"
            )
        found = (NO_DETECTION, *_detection_labels(self._seeds.detections))
        if self._detection.options != found:
            self._detection.options = found
        engine_tracks = (NO_TRACK, *(_track_label(t) for t in self._seeds.tracks))
        if self._engine_track.options != engine_tracks:
            self._engine_track.options = engine_tracks
        ids = tuple(f"#{t.id}" for t in ann.tracks)
        if self._continue.options != (NEW_TRACK, *ids):
            self._continue.options = (NEW_TRACK, *ids)
        track = self._selected_track()
        with self.client.atomic():
            if track is not None:
                values = track.attributes_at(self._frame)
                for name, box in self._attribute_boxes.items():
                    box.value = values[name]  # type: ignore[misc]  # viser's setter
                self._cls.value = track.cls  # type: ignore[misc]
                before = [k for k in track.keyframes if k.frame <= self._frame]
                interpolate = before[-1].interpolate if before else True
                self._interpolate.value = interpolate  # type: ignore[misc]
            self._done.value = ann.is_annotated(self._frame)  # type: ignore[misc]
        if not self.active or rgb is None:
            return
        picture = annotated_picture(rgb, ann.shown_at(self._frame), self._selected, draft)
        h, w = picture.shape[:2]
        if self._image is None:
            self._image = self.client.scene.add_image(
                "/annotate/frame",
                picture,
                w * PX_TO_M,
                h * PX_TO_M,
                format="jpeg",
                wxyz=PLANE_WXYZ,
                position=(0.0, 0.0, PLANE_Z_M),
            )
            self._image.on_click(self._on_click)
            self._image.on_drag("left")(self._on_drag)
        else:
            self._image.image = picture


def _detection_labels(detections: Sequence[tuple[str, Box]]) -> tuple[str, ...]:
    """ "vehicle 1 at u 312", ... : each detection by kind, number and left edge."""
    return tuple(f"{kind} {k + 1} at u {box[0]:.0f}" for k, (kind, box) in enumerate(detections))


def _track_label(track: tuple[str, int, Box]) -> str:
    kind, track_id, _ = track
    return f"{kind} #{track_id}"


def _ranges_text(ranges: Sequence[tuple[int, int]]) -> str:
    if not ranges:
        return "none"
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in ranges)
