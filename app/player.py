"""A tab's playback clock: a thread that steps the playhead once per period until stopped;
a pacer, for what follows the playhead less often than it moves; and a rest, for what
follows the view only once it stops changing."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable


class Player:
    """Calls `step()` every `period_s()` seconds on its own thread (the period is asked again
    before each step, so a rate change applies at once) until `stop()` or a step returns
    False. Starting again stops the run before."""

    def __init__(self, name: str) -> None:
        self.name = name
        self._stop = threading.Event()
        self._stop.set()

    @property
    def playing(self) -> bool:
        return not self._stop.is_set()

    def start(self, period_s: Callable[[], float], step: Callable[[], bool]) -> None:
        self.stop()
        stop = self._stop = threading.Event()
        thread = threading.Thread(
            target=self._run, args=(stop, period_s, step), name=self.name, daemon=True
        )
        thread.start()

    def stop(self) -> None:
        self._stop.set()

    @staticmethod
    def _run(
        stop: threading.Event, period_s: Callable[[], float], step: Callable[[], bool]
    ) -> None:
        while not stop.wait(period_s()):
            if not step():
                stop.set()
                return


class Pacer:
    """Says yes at most once every `period_s` seconds (of `time.monotonic`)."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s
        self._last_s = -math.inf

    def due(self) -> bool:
        """Whether `period_s` has passed since the last yes (and if so, a yes now)."""
        now_s = time.monotonic()
        if now_s - self._last_s < self.period_s:
            return False
        self._last_s = now_s
        return True


class Rest:
    """Calls `action()` on a timer thread once `delay_s` seconds have passed since the last
    `poke()`; pokes that come sooner put the call off again, so a burst of pokes ends in one
    call. `cancel()` drops a call not yet made."""

    def __init__(self, delay_s: float, action: Callable[[], None], name: str) -> None:
        self.delay_s = delay_s
        self.name = name
        self._action = action
        self._lock = threading.Lock()
        self._timer: threading.Timer | None = None

    def poke(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
            self._timer = threading.Timer(self.delay_s, self._action)
            self._timer.name = self.name
            self._timer.daemon = True
            self._timer.start()

    def cancel(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
