"""A tab's playback clock: a thread that steps the playhead once per period until stopped."""

from __future__ import annotations

import threading
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
