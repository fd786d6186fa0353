"""Each client's fusion engine on one drive, so that scrubbing and replaying follow the engine's
own rules (`FusionEngine.seek`: a frame near a from-start state is played on from it, the
next frame is processed, a frame whose predecessor's state the engine kept is processed from
it, any other is replayed from its window) and a redraw of the same frame and parameters (a
layer toggled) costs nothing.

Track ids (`core.engine`, "From the start"): the engines of one drive under one set of
parameters share its milestones, and a filler thread plays the drive from its start under
the parameters asked for last to fill them, so that within seconds of opening a bundled
drive (longer for a long one) every frame is at most `CATCH_UP_FRAMES` from one and shows the
playback's tracks and ids, however it was reached. Until then a far frame is a replay, whose
ids differ (`FrameResult.from_start` False); `result` gives the from-start result once the
milestones reach it.

Used by a drive's render worker alone (the drive itself may be read from other threads too,
as the metrics evaluation and the filler do); `forget` may come from another thread (a
client leaving).
"""

from __future__ import annotations

import logging
import threading
from collections import OrderedDict
from collections.abc import Hashable
from dataclasses import dataclass

from core.camera import CameraModel
from core.engine import (
    MILESTONE_EVERY_FRAMES,
    EngineState,
    FrameResult,
    Frames,
    FusionEngine,
    Milestones,
)
from core.io.errors import RecordingError
from core.params import Params

log = logging.getLogger(__name__)

# States kept per engine, so that a scrub back over frames it processed costs one frame, not
# a replay: about 25 s of a 10 Hz drive around the playhead. Measured with tracemalloc over
# recordings/highway (all 150 states kept; 2026-12-02): 140 KB a state, of which the 360 x 200
# background is 72 KB, the previous frame at a quarter of its resolution 19 KB
# (core.image_motion), the pitch histogram 2 KB, the copied tracks, the appearance templates
# and the rest 47 KB (121 KB before the previous frame was kept). 256 states come to about
# 36 MB per engine (a client comparing A and B has two).
KEPT_STATES = 256
# A seek plays on from the latest from-start state when it is at most this many frames back:
# about 0.2 s at 4 ms a frame, where a replay of the window (22 frames) takes about 0.1 s.
CATCH_UP_FRAMES = 50
# Milestones per parameter set at most (their spacing grows for longer drives): 140 MB each.
MOST_MILESTONES = 1000
# Parameter sets whose milestones are kept, the last asked for; the filler fills the latest
# first.
MILESTONE_SETS = 4


@dataclass
class _Entry:
    engine: FusionEngine
    last: FrameResult | None = None
    # the old parameters' state after the frame before a preview, for the next preview
    # should the parameters change again before the engine has kept a state there
    preview_from: EngineState | None = None


class ClientEngines:
    """One `FusionEngine` per client key, for the parameters it asked for last, keeping
    `keep_states` states and catching up `catch_up_frames` (`FusionEngine`), with the
    milestones it shares filled in the background when `fill` (module docstring)."""

    def __init__(
        self,
        camera: CameraModel,
        keep_states: int = KEPT_STATES,
        catch_up_frames: int = CATCH_UP_FRAMES,
        fill: bool = True,
    ) -> None:
        self.camera = camera
        self.keep_states = keep_states
        self.catch_up_frames = catch_up_frames
        self._entries: dict[Hashable, _Entry] = {}
        self._milestones: OrderedDict[Params, Milestones] = OrderedDict()  # last asked, last
        self._frames: Frames | None = None
        # per parameter set, the frame the filler seeks next at the earliest (past a frame
        # that cannot be read)
        self._fill_from: dict[Params, int] = {}
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._closed = False
        if fill:
            threading.Thread(target=self._fill, name="milestones", daemon=True).start()

    def result(
        self, key: Hashable, frames: Frames, params: Params, index: int, preview: bool = False
    ) -> FrameResult:
        """Frame `index` of `frames` under `params` for client `key`: the last result again
        when nothing changed (a replay's until a from-start result is within reach), else
        the engine's seek (a new engine when `params` changed).

        preview: when `params` changed and the old engine kept its state after frame
        index - 1, the new engine's preview from that state (`FusionEngine.preview`, one
        frame instead of a replay); the next call for the same frame and parameters gives
        the exact result. Reader errors pass through."""
        with self._lock:
            milestones = self._milestones_of(frames, params)
            old = self._entries.get(key)
            entry = old
            if entry is None or entry.engine.params != params:
                entry = self._entries[key] = _Entry(
                    FusionEngine(
                        params,
                        self.camera,
                        keep_states=self.keep_states,
                        catch_up_frames=max(self.catch_up_frames, milestones.every),
                        milestones=milestones,
                    )
                )
        if preview and old is not entry and old is not None:
            entry.preview_from = old.engine.kept_state(index - 1) or old.preview_from
            if entry.preview_from is not None and entry.preview_from.last.index == index - 1:
                try:
                    return entry.engine.preview(entry.preview_from, frames.frame(index))
                except ValueError:
                    pass  # the state does not fit the new parameters: replay them
        last = entry.last
        if last is not None and last.index == index:
            if last.from_start or not entry.engine.reaches_from_start(index):
                return last
        entry.last = None  # a failed seek leaves no stale result behind
        entry.last = entry.engine.seek(frames, index)
        return entry.last

    def _milestones_of(self, frames: Frames, params: Params) -> Milestones:
        """The milestones of `params`, now the last asked for (the lock held)."""
        self._frames = frames  # one drive: the same frames every call
        milestones = self._milestones.get(params)
        if milestones is None:
            every = max(MILESTONE_EVERY_FRAMES, len(frames) // MOST_MILESTONES)
            milestones = self._milestones[params] = Milestones(params, every)
            while len(self._milestones) > MILESTONE_SETS:
                dropped, _ = self._milestones.popitem(last=False)
                self._fill_from.pop(dropped, None)
            self._wake.notify()
        self._milestones.move_to_end(params)
        return milestones

    def forget(self, key: Hashable) -> None:
        """Drop the engine of a client that left."""
        with self._lock:
            self._entries.pop(key, None)

    def close(self) -> None:
        """Stop filling milestones."""
        with self._lock:
            self._closed = True
            self._wake.notify()

    def _fill_job(self) -> tuple[Frames, Milestones, int] | None:
        """(frames, milestones, frame to seek) of the latest parameter set asked for whose
        milestones do not reach the drive's end; None when none (the lock held)."""
        if self._frames is None:
            return None
        end = len(self._frames) - 1
        for params in reversed(self._milestones):
            milestones = self._milestones[params]
            index = max(milestones.reach + milestones.every, self._fill_from.get(params, 0))
            if index <= end:
                return self._frames, milestones, index
        return None

    def _fill(self) -> None:
        """The filler thread: one step of the latest job at a time (`every` frames played
        on from the latest milestone), until closed."""
        while True:
            with self._wake:
                job = self._fill_job()
                while not self._closed and job is None:
                    self._wake.wait()
                    job = self._fill_job()
                if self._closed or job is None:
                    return
            frames, milestones, index = job
            engine = FusionEngine(
                milestones.params, self.camera, catch_up_frames=None, milestones=milestones
            )
            try:
                engine.seek(frames, index)
            except RecordingError:  # this frame cannot be read: the next milestone is the
                # next step's, played on from the last one past it (from the start after it)
                with self._lock:
                    self._fill_from[milestones.params] = index + milestones.every
            except Exception:  # the filler must not end; the inspector shows replays
                if not self._closed:  # (a drive closed under it when the server stops)
                    log.exception("filling the milestones up to frame %d failed", index)
                with self._lock:
                    self._fill_from[milestones.params] = len(frames)
