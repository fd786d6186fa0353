"""The render worker renders only the newest request of each client."""

from __future__ import annotations

import threading
import time

from app.worker import RenderWorker


class Recorder:
    """A render that blocks until released, and a publish that records what it got."""

    def __init__(self) -> None:
        self.started = threading.Event()
        self.release = threading.Event()
        self.rendered: list[int] = []
        self.published: list[tuple[str, int, str]] = []
        self.done = threading.Semaphore(0)

    def render(self, key: str, request: int) -> str:
        self.started.set()
        self.release.wait(5.0)
        self.rendered.append(request)
        return f"image {request}"

    def publish(self, key: str, request: int, result: str) -> None:
        self.published.append((key, request, result))
        self.done.release()


def test_requests_arriving_while_busy_replace_each_other() -> None:
    rec = Recorder()
    worker = RenderWorker(rec.render, rec.publish)
    try:
        worker.submit("tab", 0)
        assert rec.started.wait(5.0)
        for frame in range(1, 300):  # a slider drag while frame 0 renders
            worker.submit("tab", frame)
        rec.release.set()
        assert rec.done.acquire(timeout=5.0) and rec.done.acquire(timeout=5.0)
        assert rec.rendered == [0, 299]
        assert rec.published == [("tab", 0, "image 0"), ("tab", 299, "image 299")]
    finally:
        worker.stop()


def test_each_client_gets_its_own_newest_request() -> None:
    rec = Recorder()
    worker = RenderWorker(rec.render, rec.publish)
    try:
        worker.submit("a", 0)
        assert rec.started.wait(5.0)
        worker.submit("a", 1)
        worker.submit("b", 10)
        worker.submit("a", 2)
        rec.release.set()
        for _ in range(3):
            assert rec.done.acquire(timeout=5.0)
        assert rec.published == [("a", 0, "image 0"), ("a", 2, "image 2"), ("b", 10, "image 10")]
    finally:
        worker.stop()


def test_a_result_asking_again_is_rendered_again_unless_a_newer_request_came() -> None:
    rec = Recorder()
    rec.release.set()
    # like a preview: the first render of a request asks for another
    worker = RenderWorker(rec.render, rec.publish, again=lambda result: len(rec.rendered) == 1)
    try:
        worker.submit("tab", 1)
        assert rec.done.acquire(timeout=5.0) and rec.done.acquire(timeout=5.0)
        assert rec.published == [("tab", 1, "image 1")] * 2  # the preview, then once more...
        assert not rec.done.acquire(timeout=0.2)  # ...and no more
    finally:
        worker.stop()
    rec = Recorder()
    worker = RenderWorker(rec.render, rec.publish, again=lambda result: len(rec.rendered) == 1)
    try:
        worker.submit("tab", 1)
        assert rec.started.wait(5.0)
        worker.submit("tab", 2)  # newer, while 1 renders
        rec.release.set()
        assert rec.done.acquire(timeout=5.0) and rec.done.acquire(timeout=5.0)
        assert rec.rendered == [1, 2]
        assert not rec.done.acquire(timeout=0.2)
    finally:
        worker.stop()


def test_a_failing_render_does_not_end_the_worker() -> None:
    published: list[int] = []
    rendered: list[int] = []
    done = threading.Semaphore(0)

    def render(key: str, request: int) -> int:
        rendered.append(request)
        if request == 0:
            raise RuntimeError("bad frame")
        return request

    def publish(_: str, __: int, result: int) -> None:
        published.append(result)
        done.release()

    worker = RenderWorker(render, publish)
    try:
        # two clients, so the second request does not replace the failing one
        worker.submit("a", 0)
        worker.submit("b", 1)
        assert done.acquire(timeout=5.0)
        assert published == [1]
        assert rendered == [0, 1]
    finally:
        worker.stop()


def test_forgotten_client_is_not_rendered() -> None:
    rec = Recorder()
    worker = RenderWorker(rec.render, rec.publish)
    try:
        worker.submit("a", 0)
        assert rec.started.wait(5.0)
        worker.submit("b", 5)
        worker.forget("b")
        rec.release.set()
        assert rec.done.acquire(timeout=5.0)
        assert not rec.done.acquire(timeout=0.3)
        assert rec.rendered == [0]
    finally:
        worker.stop()


def test_asking_again_waits_and_a_newer_request_meanwhile_goes_first() -> None:
    rendered: list[tuple[int, str]] = []
    times: list[float] = []
    done = threading.Semaphore(0)

    def render(key: str, request: int) -> str:
        """A preview the first time a request renders, then the exact result."""
        kind = "exact" if (request, "preview") in rendered else "preview"
        rendered.append((request, kind))
        return kind

    def publish(key: str, request: int, result: str) -> None:
        times.append(time.monotonic())
        done.release()

    worker = RenderWorker(render, publish, again=lambda kind: kind == "preview", again_after_s=0.3)
    try:
        worker.submit("tab", 1)
        assert done.acquire(timeout=5.0) and done.acquire(timeout=5.0)
        assert rendered == [(1, "preview"), (1, "exact")]
        assert times[1] - times[0] >= 0.3  # the exact render waited
        worker.submit("tab", 2)
        assert done.acquire(timeout=5.0)
        worker.submit("tab", 3)  # within the wait: at once, and 2's exact render is dropped
        assert done.acquire(timeout=0.25)
        assert done.acquire(timeout=5.0)
        assert rendered[2:] == [(2, "preview"), (3, "preview"), (3, "exact")]
        assert not done.acquire(timeout=0.5)
    finally:
        worker.stop()
