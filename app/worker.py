"""A render worker that always works on the newest request.

Each client has one pending slot: a request that arrives while the worker is busy replaces
the one waiting for that client, so dragging the timeline renders the frame under the
cursor, not the hundreds it passed over. One worker per drive renders that drive's frames
for every client.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

Key = TypeVar("Key", bound=Hashable)
Request = TypeVar("Request")
Result = TypeVar("Result")

log = logging.getLogger(__name__)


class RenderWorker(Generic[Key, Request, Result]):
    """Runs `render(key, request)` on a background thread, then `publish(key, request,
    result)`; when `again(result)` says so, the same request is rendered once more, after
    the others waiting and no sooner than `again_after_s` (a preview followed by the exact
    result once the values rest), unless a newer request for its key came meanwhile.

    `submit(key, request)` never blocks; of the requests submitted for one key while the
    worker is busy only the last is rendered. Keys (clients) are served in the order their
    first pending request came. An exception from `render` or `publish` is logged with its
    traceback and the worker goes on with the next request.
    """

    def __init__(
        self,
        render: Callable[[Key, Request], Result],
        publish: Callable[[Key, Request, Result], None],
        name: str = "render-worker",
        again: Callable[[Result], bool] = lambda result: False,
        again_after_s: float = 0.0,
    ) -> None:
        self._render = render
        self._publish = publish
        self._again = again
        self._again_after_s = again_after_s
        # key -> (request, monotonic time it may start); in the order the keys came
        self._pending: dict[Key, tuple[Request, float]] = {}
        self._wake = threading.Condition()
        self._stopping = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def submit(self, key: Key, request: Request) -> None:
        """Queue `request` for `key`, replacing any request for `key` not yet started."""
        with self._wake:
            self._pending[key] = (request, 0.0)
            self._wake.notify()

    def forget(self, key: Key) -> None:
        """Drop the pending request of `key` (its client left)."""
        with self._wake:
            self._pending.pop(key, None)

    def stop(self, timeout_s: float = 5.0) -> None:
        """Finish the render in progress, drop pending requests, end the thread."""
        with self._wake:
            self._stopping = True
            self._pending.clear()
            self._wake.notify()
        self._thread.join(timeout_s)

    def _next(self) -> tuple[Key, Request] | None:
        """The first request due, waiting for one; None when stopping."""
        with self._wake:
            while not self._stopping:
                now = time.monotonic()
                for key, (request, at) in self._pending.items():
                    if at <= now:
                        del self._pending[key]
                        return key, request
                soonest = min((at for _, at in self._pending.values()), default=None)
                self._wake.wait(None if soonest is None else soonest - now)
            return None

    def _run(self) -> None:
        while (job := self._next()) is not None:
            key, request = job
            try:
                result = self._render(key, request)
                self._publish(key, request, result)
                if self._again(result):
                    with self._wake:
                        at = time.monotonic() + self._again_after_s
                        self._pending.setdefault(key, (request, at))
            except Exception:  # a bad frame must not end the worker
                log.exception("render of %r for %r failed", request, key)
