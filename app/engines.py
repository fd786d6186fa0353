"""Each client's fusion engine on one drive, so that scrubbing and replaying follow the engine's
own rules (`FusionEngine.seek`: the next frame is processed, a frame whose predecessor's state
the engine kept is processed from it, any other is replayed from its window) and a redraw of
the same frame and parameters (a layer toggled) costs nothing.

Used by a drive's render worker alone (the drive itself may be read from other threads too,
as the metrics evaluation does); `forget` may come from another thread (a client leaving).
"""

from __future__ import annotations

import threading
from collections.abc import Hashable
from dataclasses import dataclass

from core.camera import CameraModel
from core.engine import EngineState, FrameResult, Frames, FusionEngine
from core.params import Params

# States kept per engine, so that a scrub back over frames it processed costs one frame, not
# a replay: about 25 s of a 10 Hz drive around the playhead. Measured with tracemalloc over
# recordings/highway (all 150 states kept): 86 KB a state, of which the 360 x 200 background
# is 72 KB, the pitch histogram 2 KB, the copied tracks (8 on average, 15 at most) and the
# rest 12 KB. 256 states come to about 22 MB per engine (a client comparing A and B has two).
KEPT_STATES = 256


@dataclass
class _Entry:
    engine: FusionEngine
    last: FrameResult | None = None
    # the old parameters' state after the frame before a preview, for the next preview
    # should the parameters change again before the engine has kept a state there
    preview_from: EngineState | None = None


class ClientEngines:
    """One `FusionEngine` per client key, for the parameters it asked for last, keeping
    `keep_states` states (`FusionEngine`)."""

    def __init__(self, camera: CameraModel, keep_states: int = KEPT_STATES) -> None:
        self.camera = camera
        self.keep_states = keep_states
        self._entries: dict[Hashable, _Entry] = {}
        self._lock = threading.Lock()

    def result(
        self, key: Hashable, frames: Frames, params: Params, index: int, preview: bool = False
    ) -> FrameResult:
        """Frame `index` of `frames` under `params` for client `key`: the last result again
        when nothing changed, else the engine's seek (a new engine when `params` changed).

        preview: when `params` changed and the old engine kept its state after frame
        index - 1, the new engine's preview from that state (`FusionEngine.preview`, one
        frame instead of a replay); the next call for the same frame and parameters gives
        the exact result. Reader errors pass through."""
        with self._lock:
            old = self._entries.get(key)
            entry = old
            if entry is None or entry.engine.params != params:
                entry = self._entries[key] = _Entry(
                    FusionEngine(params, self.camera, keep_states=self.keep_states)
                )
        if preview and old is not entry and old is not None:
            entry.preview_from = old.engine.kept_state(index - 1) or old.preview_from
            if entry.preview_from is not None and entry.preview_from.last.index == index - 1:
                try:
                    return entry.engine.preview(entry.preview_from, frames.frame(index))
                except ValueError:
                    pass  # the state does not fit the new parameters: replay them
        if entry.last is not None and entry.last.index == index:
            return entry.last
        entry.last = None  # a failed seek leaves no stale result behind
        entry.last = entry.engine.seek(frames, index)
        return entry.last

    def forget(self, key: Hashable) -> None:
        """Drop the engine of a client that left."""
        with self._lock:
            self._entries.pop(key, None)
