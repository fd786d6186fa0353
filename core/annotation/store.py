"""Saving a recording's annotations so that no acknowledged edit is ever lost.

Two files next to the recording:

`groundtruth.json` (format_version 2; JSON Schema `groundtruth.schema.json` beside this
module) holds the annotations as of `revision`, the number of edits made to it:

    {"format_version": 2, "kind": "annotations", "revision": 12,
     "annotated": [[0, 149]],
     "tracks": [{"id": 1, "class": "car",
                 "keyframes": [{"frame": 3, "box_px": [u0, v0, u1, v1],
                                "distance_m": 21.5, "interpolate": true}],
                 "changes": [{"frame": 9, "name": "occluded", "value": true}],
                 "end_frame": null}]}

Boxes, classes and attributes are those of `core.annotation.model`; the model's rules
(increasing keyframe frames, u0 < u1, unique track ids...) apply after the schema's.

`groundtruth.journal.jsonl` holds one JSON line per edit not yet in the file:
`{"revision", "base_revision", "label", "tracks": {"<id>": track | null}, "annotated":
[[first, last, on], ...]}` (schema `$defs/journal_entry`).

An edit (`AnnotationStore.apply`) is
    1. checked against the edits made since the revision it was based on (`Conflict`);
    2. appended to the journal as one line, written and fsync'ed: from here it survives a
       crash, and it is acknowledged once step 3 has been tried;
    3. saved: groundtruth.json rewritten atomically (a temporary file in the same folder,
       written, fsync'ed, renamed over the old one, the folder fsync'ed), then the
       journal emptied (its entries are all in the file now).

Crash at any point, and what the next open finds:
    - during step 2: the journal's last line is cut short or missing. It was never
      acknowledged; it is ignored and dropped. The file has the revision before the edit.
    - after step 2, before the rename: the file is one revision behind the journal; the
      journal's entries newer than the file are replayed (and saved at once).
    - after the rename, before the journal is emptied: the journal's entries are not newer
      than the file and are skipped.
    - a temporary file left behind: never read, deleted on the next writable open.
Emptying the journal is not fsync'ed: if a crash undoes it, the entries it held are no newer
than the file and are skipped; the next append's fsync makes it durable anyway.

Read-only: a store refuses every edit (`ReadOnlyError`, with `read_only_reason`) and writes
neither file when groundtruth.json is the generator's exact truth (format_version 1,
`core.io.groundtruth`), a future format_version, not JSON, or against the schema or the
model; when the journal has a bad line before its last (a cut-short last line is a crash
during step 2, above, not damage) or revisions that do not follow the file's; when another
store has the recording open for writing (an advisory lock on the folder, POSIX); when the
folder is not writable; or when opened with `writable=False`. A read-only store shows the
file's annotations with the journal replayed up to its first bad line, or none when the file
cannot be read as annotations.

Notes:
    - Edits replace whole tracks (`Edit`): drawing, moving, a class or attribute change,
      deleting or accepting a track all put the track's new value; undo is an edit putting
      the old tracks back (`Edit.inverse`).
    - A failed rewrite in step 3 (disk full) does not fail the edit: it is in the journal
      and replayed on the next open, the journal keeps growing until a rewrite succeeds,
      and `save_error` says what happened until then.
    - Two tabs: each edit names the revision it was based on; it is refused when a track it
      puts or deletes was changed by an edit after that revision, or when a frame range it
      marks was marked the other way after it. Edits of other tracks pass. An edit based on
      a revision older than the file's at open is refused too (what changed before the open
      is not known).
"""

from __future__ import annotations

import contextlib
import functools
import itertools
import json
import os
import re
import stat
import sys
import threading
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType, TracebackType
from typing import Any, TypeGuard

from jsonschema import Draft202012Validator, ValidationError, validators
from jsonschema.exceptions import best_match

from core.annotation.model import Annotations, AttributeChange, Keyframe, Track
from core.io.errors import RecordingError

if sys.platform != "win32":
    import fcntl

GROUNDTRUTH_NAME = "groundtruth.json"
JOURNAL_NAME = "groundtruth.journal.jsonl"
SCHEMA_NAME = "groundtruth.schema.json"
FORMAT_VERSION = 2
KIND = "annotations"
EXACT_TRUTH_VERSION = 1  # core.io.groundtruth: the generator's dense truth, never edited here
_MAX_SHOWN_CHARS = 80  # a bad value quoted in a message is cut to this many characters
_TEMP_PATTERN = re.compile(r"^\." + re.escape(GROUNDTRUTH_NAME) + r"\.\d+\.\d+\.tmp$")
_READ_ONLY_TAIL = "opened read-only: it is never overwritten"

MarkedRange = tuple[int, int, bool]  # (first, last, on): frames marked annotated or not


class EditError(Exception):
    """An edit that was not applied: nothing was written, the annotations are unchanged."""


class ReadOnlyError(EditError):
    """The store is read-only; the message is its `read_only_reason`."""


class Conflict(EditError):  # noqa: N818 (the name the app and the issue use)
    """An edit based on a revision after which another edit changed what it changes.

    track_id: the track (None: a frame range marked annotated); revision: the edit that
    changed it; label: that edit's label ("" when not known); base_revision: the refused
    edit's."""

    def __init__(
        self, message: str, track_id: int | None, revision: int, label: str, base_revision: int
    ) -> None:
        super().__init__(message)
        self.track_id = track_id
        self.revision = revision
        self.label = label
        self.base_revision = base_revision


# --- edits ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class Edit:
    """One user action on the annotations.

    base_revision: the store revision the action was made on (what the user saw);
    tracks: tracks put (the track, its id the key) or deleted (None), by id;
    annotated: (first, last, on) frame ranges marked fully annotated (on) or no longer, in
    order; label: what the user did, in words ("move box"), quoted in conflict messages.
    """

    base_revision: int
    tracks: Mapping[int, Track | None] = field(default_factory=dict)
    annotated: tuple[MarkedRange, ...] = ()
    label: str = ""

    def __post_init__(self) -> None:
        if not _is_int(self.base_revision) or self.base_revision < 0:
            raise ValueError(f"base_revision: expected a revision >= 0, got {self.base_revision!r}")
        if not isinstance(self.tracks, Mapping):
            raise ValueError(
                f"tracks: expected a mapping of id to Track or None, got {self.tracks!r}"
            )
        for key, track in self.tracks.items():
            if not _is_int(key) or key < 1:
                raise ValueError(f"tracks: expected track ids >= 1 as keys, got {key!r}")
            if track is not None and not isinstance(track, Track):
                raise ValueError(f"tracks[{key}]: expected a Track or None, got {track!r}")
            if track is not None and track.id != key:
                raise ValueError(
                    f"tracks[{key}]: expected the track with id {key}, got id {track.id}"
                )
        object.__setattr__(self, "tracks", MappingProxyType(dict(self.tracks)))
        if not isinstance(self.annotated, tuple | list):
            raise ValueError(
                f"annotated: expected (first, last, on) ranges, got {self.annotated!r}"
            )
        ranges = tuple(tuple(r) if isinstance(r, tuple | list) else (r,) for r in self.annotated)
        for i, r in enumerate(ranges):
            ok = len(r) == 3 and _is_int(r[0]) and _is_int(r[1]) and isinstance(r[2], bool)
            if not ok or not 0 <= r[0] <= r[1]:
                raise ValueError(
                    f"annotated[{i}]: expected (first, last, on) with 0 <= first <= last, got {r!r}"
                )
        object.__setattr__(self, "annotated", ranges)
        if not isinstance(self.label, str):
            raise ValueError(f"label: expected a string, got {self.label!r}")
        if not self.tracks and not self.annotated:
            raise ValueError(
                "tracks, annotated: expected a track or a frame range to change, got none"
            )

    def applied_to(self, annotations: Annotations) -> Annotations:
        """`annotations` with this edit made: tracks put or deleted by increasing id, then
        the frame ranges marked in order. ValueError when it deletes a track not there."""
        out = annotations
        for track_id, track in sorted(self.tracks.items()):
            if track is not None:
                out = out.with_track(track)
            elif out.track(track_id) is None:
                raise ValueError(f"tracks[{track_id}]: expected a track to delete, there is none")
            else:
                out = out.without_track(track_id)
        for first, last, on in self.annotated:
            out = out.with_annotated(first, last, on)
        return out

    def inverse(self, before: Annotations, base_revision: int, label: str = "") -> Edit:
        """The edit that undoes this one made on `before`: the tracks it touched put back as
        they were there (None: deleted again), the frames it marked given back their marks;
        based on `base_revision` (the revision this edit got, or a later one)."""
        tracks = {track_id: before.track(track_id) for track_id in self.tracks}
        ranges: list[MarkedRange] = []
        for first, last, _ in self.annotated:
            ranges.append((first, last, False))
            ranges += [
                (max(a, first), min(b, last), True)
                for a, b in before.annotated
                if a <= last and first <= b
            ]
        return Edit(base_revision, tracks, tuple(ranges), label or f"undo {self.label}".strip())


# --- reading and writing the files ------------------------------------------------------------
def _is_int(value: object) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool)


@functools.cache
def schema() -> dict[str, Any]:
    """The JSON Schema (draft 2020-12) of groundtruth.json, format_version 2."""
    text = resources.files(__package__).joinpath(SCHEMA_NAME).read_text(encoding="utf-8")
    loaded: dict[str, Any] = json.loads(text)
    return loaded


# JSON integers are ints only (the draft lets 1.0 count as one; the model does not)
_STRICT_TYPES = Draft202012Validator.TYPE_CHECKER.redefine(
    "integer", lambda _checker, instance: _is_int(instance)
)
_StrictValidator = validators.extend(Draft202012Validator, type_checker=_STRICT_TYPES)


@functools.cache
def _validator(definition: str | None) -> Any:
    """A validator of the whole document (None) or of one of the schema's $defs."""
    whole = schema()
    if definition is None:
        return _StrictValidator(whole)
    part = {"$schema": whole["$schema"], "$defs": whole["$defs"], "$ref": f"#/$defs/{definition}"}
    return _StrictValidator(part)


def _json_path(parts: Iterable[str | int]) -> str:
    """`tracks[2].keyframes[0].box_px` for the path ('tracks', 2, 'keyframes', 0, 'box_px')."""
    out = ""
    for part in parts:
        if isinstance(part, int):
            out += f"[{part}]"
        elif part.isidentifier():
            out += f".{part}" if out else part
        else:
            out += f"[{json.dumps(part)}]"
    return out


def _shown(value: Any) -> str:
    """`value` as JSON, cut to a readable length."""
    text = json.dumps(value, allow_nan=True)
    return text if len(text) <= _MAX_SHOWN_CHARS else text[: _MAX_SHOWN_CHARS - 3] + "..."


_TYPE_WORDS = {
    "integer": "an integer",
    "number": "a number",
    "string": "a string",
    "boolean": "true or false",
    "null": "null",
    "array": "a list",
    "object": "an object",
}


def _expected_got(error: ValidationError) -> str:
    """'expected ..., got ...' for one schema violation."""
    keyword, value, instance, sub = (
        error.validator,
        error.validator_value,
        error.instance,
        error.schema,
    )
    described = isinstance(sub, dict) and "description" in sub and bool(error.absolute_path)
    about = f" ({sub['description']})" if described else ""
    if keyword == "type":
        types = [value] if isinstance(value, str) else list(value)
        return (
            f"expected {' or '.join(_TYPE_WORDS[t] for t in types)}{about}, got {_shown(instance)}"
        )
    if keyword == "const":
        return f"expected {_shown(value)}, got {_shown(instance)}"
    if keyword == "enum":
        return f"expected one of {', '.join(_shown(v) for v in value)}; got {_shown(instance)}"
    if keyword == "required":
        missing = [k for k in value if k not in instance]
        return f"expected the field {_shown(missing[0])}, got only {_shown(sorted(instance))}"
    if keyword == "additionalProperties" and isinstance(sub, dict) and "properties" in sub:
        extra = sorted(set(instance) - set(sub["properties"]))
        return (
            f"expected only the fields {_shown(list(sub['properties']))}, got also {_shown(extra)}"
        )
    if keyword in ("minItems", "maxItems", "items") and isinstance(instance, list):
        low, high = sub.get("minItems", 0), sub.get("maxItems")
        if sub.get("items") is False:
            high = len(sub.get("prefixItems", ()))
        count = (
            f"exactly {low}"
            if low == high
            else f"at least {low}"
            if high is None
            else (f"{low} to {high}")
        )
        return f"expected {count} items{about}, got {len(instance)}: {_shown(instance)}"
    if keyword == "minimum":
        return f"expected a number >= {value}{about}, got {_shown(instance)}"
    if keyword == "exclusiveMinimum":
        return f"expected a number > {value}{about}, got {_shown(instance)}"
    if keyword == "propertyNames":
        return f"expected track ids (1, 2, ... up to 18 digits) as keys, got {_shown(instance)}"
    return f"expected {error.message}"


def _check_schema(data: Any, definition: str | None, where: str) -> None:
    """RecordingError naming `where`, the JSON path and what was expected, unless `data`
    follows the schema (or its $defs/`definition`)."""
    error = best_match(_validator(definition).iter_errors(data))
    if error is not None:
        path = _json_path(error.absolute_path)
        raise RecordingError(f"{where}: {path + ': ' if path else ''}{_expected_got(error)}")


class _StrictJsonError(ValueError):
    pass


def _no_constant(name: str) -> Any:
    raise _StrictJsonError(f"expected a number, got {name} (not JSON)")


def _unique_keys(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    out = dict(pairs)
    if len(out) != len(pairs):
        keys = [k for k, _ in pairs]
        twice = sorted({k for k in keys if keys.count(k) > 1})
        raise _StrictJsonError(f"expected each key once in an object, got {_shown(twice)} twice")
    return out


def _loads(raw: bytes, where: str) -> Any:
    """Strict JSON (UTF-8, no NaN, no repeated keys); RecordingError naming `where`."""
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise RecordingError(
            f"{where}: expected UTF-8 text, got byte {err.start}: {err.reason}"
        ) from err
    try:
        return json.loads(text, parse_constant=_no_constant, object_pairs_hook=_unique_keys)
    except ValueError as err:  # JSONDecodeError, _StrictJsonError, too many digits
        raise RecordingError(f"{where}: not valid JSON: {err}") from err
    except RecursionError as err:
        raise RecordingError(f"{where}: not valid JSON: nested too deeply") from err


def _model(build: Any, where: str, path: str) -> Any:
    """build() with the model's ValueError as a RecordingError naming the JSON path (and
    OverflowError: the model's checks take a JSON integer too large for a float there)."""
    try:
        return build()
    except ValueError as err:
        raise RecordingError(f"{where}: {path + '.' if path else ''}{err}") from err
    except OverflowError as err:
        raise RecordingError(
            f"{where}: {path or 'the document'}: expected numbers a float can hold, got an "
            f"integer too large ({err})"
        ) from err


def track_to_json(track: Track) -> dict[str, Any]:
    """A track as it is stored (schema `$defs/track`)."""
    return {
        "id": track.id,
        "class": track.cls,
        "keyframes": [
            {
                "frame": k.frame,
                "box_px": list(k.box_px),
                "distance_m": k.distance_m,
                "interpolate": k.interpolate,
            }
            for k in track.keyframes
        ],
        "changes": [{"frame": c.frame, "name": c.name, "value": c.value} for c in track.changes],
        "end_frame": track.end_frame,
    }


def _track_from_json(raw: dict[str, Any], where: str, path: str) -> Track:
    keyframes = tuple(
        _model(
            lambda k=k: Keyframe(k["frame"], tuple(k["box_px"]), k["distance_m"], k["interpolate"]),
            where,
            f"{path}.keyframes[{j}]",
        )
        for j, k in enumerate(raw["keyframes"])
    )
    changes = tuple(
        _model(
            lambda c=c: AttributeChange(c["frame"], c["name"], c["value"]),
            where,
            f"{path}.changes[{j}]",
        )
        for j, c in enumerate(raw["changes"])
    )
    track: Track = _model(
        lambda: Track(raw["id"], raw["class"], keyframes, changes, raw["end_frame"]), where, path
    )
    return track


def annotations_to_json(annotations: Annotations, revision: int) -> dict[str, Any]:
    """The groundtruth.json document of `annotations` at `revision`."""
    return {
        "format_version": FORMAT_VERSION,
        "kind": KIND,
        "revision": revision,
        "annotated": [list(r) for r in annotations.annotated],
        "tracks": [track_to_json(t) for t in annotations.tracks],
    }


def document_text(document: dict[str, Any]) -> str:
    """A groundtruth.json document as text: one track a line, so that a diff shows which
    tracks an edit changed."""
    head = {k: v for k, v in document.items() if k != "tracks"}
    tracks = [json.dumps(t, allow_nan=False) for t in document["tracks"]]
    listed = "[\n" + ",\n".join(f"  {t}" for t in tracks) + "\n ]" if tracks else "[]"
    return f'{json.dumps(head, allow_nan=False)[:-1]},\n "tracks": {listed}}}\n'


def parse_annotations(raw: bytes, where: str) -> tuple[Annotations, int]:
    """(annotations, revision) from groundtruth.json's bytes. RecordingError naming `where`,
    the JSON path of the bad element, what was expected and what came: on the generator's
    exact truth (format_version 1), a future version, bad JSON, the schema or the model."""
    data = _loads(raw, where)
    version = data.get("format_version") if isinstance(data, dict) else None
    if version == EXACT_TRUTH_VERSION and _is_int(version):
        raise RecordingError(
            f"{where}: holds the generator's exact ground truth (format_version "
            f"{EXACT_TRUTH_VERSION}, core.io.groundtruth), not annotations"
        )
    if _is_int(version) and version > FORMAT_VERSION:
        raise RecordingError(
            f"{where}: format_version {version} is newer than this fusionscope reads "
            f"({FORMAT_VERSION}): update fusionscope to edit it"
        )
    _check_schema(data, None, where)
    tracks = tuple(_track_from_json(t, where, f"tracks[{i}]") for i, t in enumerate(data["tracks"]))
    ranges = tuple((a, b) for a, b in data["annotated"])
    annotations: Annotations = _model(lambda: Annotations(tracks, ranges), where, "")
    return annotations, data["revision"]


def read_annotations(path: Path | str) -> tuple[Annotations, int]:
    """(annotations, revision) of a groundtruth.json (format_version 2) without its journal;
    RecordingError as `parse_annotations`, or when it cannot be read."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except OSError as err:
        raise RecordingError(f"{p}: cannot read: {err.strerror}") from err
    return parse_annotations(raw, str(p))


def _entry_to_line(edit: Edit, revision: int) -> bytes:
    entry = {
        "revision": revision,
        "base_revision": edit.base_revision,
        "label": edit.label,
        "tracks": {
            str(i): (None if t is None else track_to_json(t))
            for i, t in sorted(edit.tracks.items())
        },
        "annotated": [list(r) for r in edit.annotated],
    }
    return (json.dumps(entry, separators=(",", ":"), allow_nan=False) + "\n").encode("utf-8")


def _entry_from_line(line: bytes, where: str) -> tuple[int, Edit]:
    data = _loads(line, where)
    _check_schema(data, "journal_entry", where)
    tracks = {
        int(key): (  # the schema's pattern: a few digits
            None if raw is None else _track_from_json(raw, where, f"tracks[{json.dumps(key)}]")
        )
        for key, raw in data["tracks"].items()
    }
    ranges = tuple((a, b, on) for a, b, on in data["annotated"])
    edit: Edit = _model(
        lambda: Edit(data["base_revision"], tracks, ranges, data["label"]), where, ""
    )
    revision: int = data["revision"]
    if edit.base_revision >= revision:
        raise RecordingError(
            f"{where}: base_revision: expected a revision before {revision}, "
            f"got {edit.base_revision}"
        )
    return revision, edit


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


_temp_counter = itertools.count()


def _replace_atomically(path: Path, data: bytes, folder_fd: int | None) -> None:
    """`path` holds `data` or (after a crash) its old bytes, never a mix: a temporary file
    in the same folder is written, fsync'ed and renamed over it, and the folder fsync'ed.
    The file keeps its permission bits."""
    temp = path.with_name(f".{path.name}.{os.getpid()}.{next(_temp_counter)}.tmp")
    fd = os.open(temp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        try:
            with contextlib.suppress(FileNotFoundError):
                os.fchmod(fd, stat.S_IMODE(os.stat(path).st_mode))
            _write_all(fd, data)
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(temp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(temp)
        raise
    if folder_fd is not None:
        os.fsync(folder_fd)


# --- the store ---------------------------------------------------------------------------------
class AnnotationStore:
    """A recording's annotations, opened for editing (module docstring: files, crash safety,
    read-only cases). Thread-safe: apply() may be called from any thread.

    annotations, revision: the current value and its revision (0: never edited), read
    together with snapshot(); read_only_reason: why edits are refused (None: editable);
    save_error: why groundtruth.json lags behind the journal (None: it holds every edit).
    Close it (or use it as a context manager) to let another store open the recording.
    """

    def __init__(self, recording_dir: Path | str, writable: bool = True) -> None:
        self.folder = Path(recording_dir)
        if not self.folder.is_dir():
            got = "a file" if self.folder.exists() else "nothing there"
            raise RecordingError(f"{self.folder}: expected a recording folder, got {got}")
        self.path = self.folder / GROUNDTRUTH_NAME
        self.journal_path = self.folder / JOURNAL_NAME
        self._lock = threading.Lock()
        self._state: tuple[Annotations, int] = (Annotations(), 0)
        self._read_only_reason: str | None = None if writable else "opened for reading only"
        self._save_error: str | None = None
        self._folder_fd: int | None = None
        self._journal_fd: int | None = None
        self._floor = 0  # the file's revision at open: edits based on older ones are refused
        self._track_changes: dict[int, tuple[int, str]] = {}  # id -> (revision, label)
        self._range_changes: list[tuple[int, int, int, bool, str]] = []  # rev, first, last, on
        try:
            self._open()
        except BaseException:
            self.close()
            raise

    @classmethod
    def open(cls, recording_dir: Path | str, writable: bool = True) -> AnnotationStore:
        return cls(recording_dir, writable)

    # --- state ---------------------------------------------------------------------------------
    @property
    def annotations(self) -> Annotations:
        return self._state[0]

    @property
    def revision(self) -> int:
        return self._state[1]

    def snapshot(self) -> tuple[Annotations, int]:
        """(annotations, revision) of one moment."""
        return self._state

    @property
    def read_only_reason(self) -> str | None:
        return self._read_only_reason

    @property
    def save_error(self) -> str | None:
        return self._save_error

    # --- opening -------------------------------------------------------------------------------
    def _read_only(self, reason: str) -> None:
        if self._read_only_reason is None:
            self._read_only_reason = reason

    def _lock_folder(self) -> None:
        """An advisory lock on the folder: one writable store per recording at a time."""
        if sys.platform == "win32":
            return
        fd = os.open(self.folder, os.O_RDONLY)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            self._read_only(
                f"{self.folder}: another window or program is editing these annotations: "
                "opened read-only"
            )
            return
        self._folder_fd = fd

    def _open(self) -> None:
        if self._read_only_reason is None:
            self._lock_folder()
        if self._read_only_reason is None and not os.access(self.folder, os.W_OK):
            self._read_only(f"{self.folder}: the folder is not writable: opened read-only")
        try:
            raw = self.path.read_bytes()
        except FileNotFoundError:
            annotations, revision = Annotations(), 0
        except OSError as err:
            self._read_only(f"{self.path}: cannot read: {err.strerror}; {_READ_ONLY_TAIL}")
            self._release()
            return
        else:
            try:
                annotations, revision = parse_annotations(raw, str(self.path))
            except RecordingError as err:
                self._read_only(f"{err}; {_READ_ONLY_TAIL}")
                self._release()
                return
        self._state = (annotations, revision)
        self._floor = revision
        replayed, complete_size, size = self._replay()
        if self._read_only_reason is not None:
            self._release()
            return
        for name in os.listdir(self.folder):
            if _TEMP_PATTERN.match(name):
                with contextlib.suppress(OSError):
                    os.unlink(self.folder / name)
        if size > complete_size:
            self._empty_journal(complete_size)  # the next line must not follow a cut one
        if replayed:
            self._save()
        elif complete_size:
            self._empty_journal(0)

    def _replay(self) -> tuple[int, int, int]:
        """Replays the journal's entries newer than the file; (how many, the journal's size
        without a cut-short last line, its size: both 0 without a journal). Its last line,
        when it has no newline, is a write a crash cut short: never acknowledged, ignored.
        Any other bad line, or revisions that do not follow the file's, make the store
        read-only."""
        try:
            raw = self.journal_path.read_bytes()
        except FileNotFoundError:
            return 0, 0, 0
        except OSError as err:
            self._read_only(f"{self.journal_path}: cannot read: {err.strerror}; opened read-only")
            return 0, 0, 0
        complete = raw[: raw.rfind(b"\n") + 1]
        annotations, revision = self._state
        for number, line in enumerate(complete.splitlines(), start=1):
            where = f"{self.journal_path} line {number}"
            try:
                entry_revision, edit = _entry_from_line(line, where)
                if entry_revision <= self._floor:
                    continue
                if entry_revision != revision + 1:
                    raise RecordingError(
                        f"{where}: revision: expected {revision + 1} (after {self.path.name}'s "
                        f"{self._floor} and the lines before), got {entry_revision}"
                    )
                annotations = _model(functools.partial(edit.applied_to, annotations), where, "")
            except RecordingError as err:
                self._read_only(
                    f"{err}; opened read-only: neither {self.path.name} nor the journal is "
                    "overwritten (move the journal away to edit without its edits)"
                )
                break
            revision = entry_revision
            self._note_changes(edit, revision)
        self._state = (annotations, revision)
        return revision - self._floor, len(complete), len(raw)

    # --- editing -------------------------------------------------------------------------------
    def apply(self, edit: Edit) -> int:
        """Makes `edit`, saves it (module docstring) and returns the new revision.

        ReadOnlyError when the store is read-only, Conflict when another edit changed one of its
        tracks or frame ranges after edit.base_revision, EditError when the journal cannot
        be written; ValueError on an edit based on a future revision or deleting a track not
        there. In every one of these cases nothing was written."""
        if not isinstance(edit, Edit):
            raise ValueError(f"edit: expected an Edit, got {edit!r}")
        with self._lock:
            if self._read_only_reason is not None:
                raise ReadOnlyError(self._read_only_reason)
            annotations, revision = self._state
            if edit.base_revision > revision:
                raise ValueError(
                    f"edit.base_revision: expected a revision <= {revision} (the store's), "
                    f"got {edit.base_revision}"
                )
            self._check_conflicts(edit)
            new = edit.applied_to(annotations)
            self._append(_entry_to_line(edit, revision + 1))
            self._state = (new, revision + 1)
            self._note_changes(edit, revision + 1)
            self._save()
            return revision + 1

    def _check_conflicts(self, edit: Edit) -> None:
        base = edit.base_revision
        doing = f" ({edit.label})" if edit.label else ""
        tail = "nothing was saved: reload and redo it"
        if base < self._floor:
            raise Conflict(
                f"this edit{doing} is based on revision {base}, older than revision "
                f"{self._floor} of {self.path} when it was opened; {tail}",
                None,
                self._floor,
                "",
                base,
            )
        for track_id in sorted(edit.tracks):
            revision, label = self._track_changes.get(track_id, (0, ""))
            if revision > base:
                by = f" by {label!r}" if label else ""
                raise Conflict(
                    f"track {track_id} was changed in revision {revision}{by}, after revision "
                    f"{base} which this edit{doing} is based on; {tail}",
                    track_id,
                    revision,
                    label,
                    base,
                )
        for first, last, on in edit.annotated:
            for revision, a, b, was_on, label in self._range_changes:
                if revision > base and a <= last and first <= b and was_on != on:
                    by = f" by {label!r}" if label else ""
                    marked = "annotated" if was_on else "not annotated"
                    raise Conflict(
                        f"frames {a}..{b} were marked {marked} in revision {revision}{by}, "
                        f"after revision {base} which this edit{doing} is based on; {tail}",
                        None,
                        revision,
                        label,
                        base,
                    )

    def _note_changes(self, edit: Edit, revision: int) -> None:
        for track_id in edit.tracks:
            self._track_changes[track_id] = (revision, edit.label)
        self._range_changes += [(revision, a, b, on, edit.label) for a, b, on in edit.annotated]

    def _append(self, line: bytes) -> None:
        """Step 2: `line` at the end of the journal, on disk when this returns.
        EditError (the journal as it was) when it cannot be written."""
        try:
            if self._journal_fd is None:
                created = not self.journal_path.exists()
                flags = os.O_WRONLY | os.O_APPEND | os.O_CREAT
                self._journal_fd = os.open(self.journal_path, flags, 0o666)
                if created and self._folder_fd is not None:
                    os.fsync(self._folder_fd)  # the new file's name is durable too
            size = os.fstat(self._journal_fd).st_size
        except OSError as err:
            raise EditError(
                f"{self.journal_path}: cannot open the journal: {err.strerror}; nothing was saved"
            ) from err
        try:
            _write_all(self._journal_fd, line)
            os.fsync(self._journal_fd)
        except OSError as err:
            try:
                os.ftruncate(self._journal_fd, size)
            except OSError:
                self._read_only(
                    f"{self.journal_path}: an edit could not be written nor taken back "
                    f"({err.strerror}): opened read-only until the recording is reopened"
                )
            raise EditError(
                f"{self.journal_path}: cannot append the edit: {err.strerror}; nothing was saved"
            ) from err

    def _save(self) -> None:
        """Step 3: groundtruth.json rewritten with the current annotations, then the journal
        emptied. A failure is kept in save_error (the journal still has every edit)."""
        annotations, revision = self._state
        text = document_text(annotations_to_json(annotations, revision))
        try:
            _replace_atomically(self.path, text.encode("utf-8"), self._folder_fd)
        except OSError as err:
            self._save_error = (
                f"{self.path}: cannot save ({err.strerror}); the edits since its revision are "
                f"kept in {self.journal_path.name} and are replayed when the recording is opened"
            )
            return
        self._save_error = None
        self._empty_journal(0)

    def _empty_journal(self, size: int) -> None:
        """Cuts the journal to `size` bytes (0: every entry is in the file; else the end of
        its last complete line). Not fsync'ed (module docstring); a failure leaves entries
        that are skipped or a cut-short line that is ignored, so it is ignored too."""
        with contextlib.suppress(OSError):
            if self._journal_fd is not None:
                os.ftruncate(self._journal_fd, size)
            elif self.journal_path.exists():
                os.truncate(self.journal_path, size)

    # --- closing -------------------------------------------------------------------------------
    def _release(self) -> None:
        for fd in (self._journal_fd, self._folder_fd):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._journal_fd = self._folder_fd = None

    def close(self) -> None:
        """Lets go of the recording: later edits are refused."""
        with self._lock:
            self._release()
            self._read_only("the annotation store was closed")

    def __enter__(self) -> AnnotationStore:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
