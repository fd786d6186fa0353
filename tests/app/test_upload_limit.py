"""Uploads over the limit are refused before they are kept (app.upload_limit): a viser server
with one upload button, fed by a raw websocket client the way a hostile page would."""

from __future__ import annotations

import contextlib
import io
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field

import msgspec.msgpack
import pytest
import viser
from viser._messages import (
    FileTransferPart,
    FileTransferStartUpload,
    Message,
    ViewerCameraMessage,
)
from websockets.sync.client import ClientConnection, connect

from app.upload_limit import MIB, limit_uploads

LIMIT_BYTES = 1_000
WAIT_S = 10.0


@dataclass
class Seen:
    refusals: list[tuple[int, str]] = field(default_factory=list)
    uploads: list[bytes] = field(default_factory=list)


@dataclass
class Served:
    server: viser.ViserServer
    button_uuid: str
    seen: Seen

    def in_flight(self) -> int:
        return len(self.server.gui._current_file_upload_states)


@pytest.fixture()
def served() -> Iterator[Served]:
    with contextlib.redirect_stdout(io.StringIO()):  # viser's banner
        server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    seen = Seen()
    limit_uploads(server.gui, LIMIT_BYTES, lambda client, why: seen.refusals.append((client, why)))
    button = server.gui.add_upload_button("Import a file")
    button.on_upload(lambda event: seen.uploads.append(event.target.value.content))
    yield Served(server, button._impl.uuid, seen)
    server.stop()


def send(client: ClientConnection, message: Message) -> None:
    client.send(msgspec.msgpack.encode(message.as_serializable_dict()))


def upload(
    client: ClientConnection,
    served: Served,
    name: str,
    declared_bytes: int,
    parts: list[bytes],
    part_count: int | None = None,
) -> None:
    """Start an upload of `part_count` parts (default: as many as `parts`), send `parts`."""
    transfer = str(uuid.uuid4())
    count = len(parts) if part_count is None else part_count
    send(
        client,
        FileTransferStartUpload(
            served.button_uuid, transfer, name, "text/plain", count, declared_bytes
        ),
    )
    for index, content in enumerate(parts):
        send(client, FileTransferPart(served.button_uuid, transfer, index, content))


def until(condition: object) -> None:
    deadline = time.monotonic() + WAIT_S
    while not condition() and time.monotonic() < deadline:  # type: ignore[operator]
        time.sleep(0.02)


@contextlib.contextmanager
def client_of(served: Served) -> Iterator[ClientConnection]:
    url = f"ws://127.0.0.1:{served.server.get_port()}/"
    with connect(url, subprotocols=[f"viser-v{viser.__version__}"], max_size=None) as client:  # type: ignore[list-item]
        # viser counts a client as connected from its first camera message
        send(
            client,
            ViewerCameraMessage(
                (1, 0, 0, 0), (0, 0, 0), 1.0, 0.1, 100.0, 480, 640, (0, 0, 1), (0, 0, 1)
            ),
        )
        until(lambda: served.server.get_clients())
        assert served.server.get_clients()
        yield client


def test_an_upload_declaring_100_gb_is_refused_and_none_of_its_parts_kept(served: Served) -> None:
    with client_of(served) as client:
        upload(client, served, "huge.xml", 100 * 1024 * MIB, [b"x" * MIB] * 20)
        until(lambda: served.seen.refusals)
        time.sleep(0.5)  # the parts after the refusal are dropped as they come
        assert served.in_flight() == 0 and served.seen.uploads == []
        ((_, why),) = served.seen.refusals
        assert why == (
            "huge.xml: 102400.0 MB is over the 1,000 bytes a file uploaded to the inspector "
            "may have; nothing of it was kept"
        )


def test_parts_bringing_more_than_declared_are_let_go(served: Served) -> None:
    with client_of(served) as client:
        upload(client, served, "liar.txt", 500, [b"a" * 400, b"b" * 400, b"c" * 400])
        until(lambda: served.seen.refusals)
        assert served.in_flight() == 0 and served.seen.uploads == []
        assert (
            "liar.txt: its parts bring more than the 500 bytes it declared"
            in (served.seen.refusals[0][1])
        )


def test_uploads_under_way_count_against_the_limit_and_a_fitting_one_arrives(
    served: Served,
) -> None:
    with client_of(served) as client:
        upload(client, served, "first.txt", 600, [b"a" * 300], part_count=2)  # 1 of 2 comes
        upload(client, served, "second.txt", 600, [b"b" * 300, b"b" * 300])
        until(lambda: served.seen.refusals)
        assert (
            "second.txt: 600 bytes, with the 600 bytes of this tab's uploads under way"
            in (served.seen.refusals[0][1])
        )
    until(lambda: served.in_flight() == 0)  # a tab that leaves lets its uploads go
    with client_of(served) as client:
        upload(client, served, "fits.txt", 1_000, [b"c" * 500, b"d" * 500])
        until(lambda: served.seen.uploads)
        assert served.seen.uploads == [b"c" * 500 + b"d" * 500]
        upload(client, served, "negative.txt", -1, [])
        until(lambda: len(served.seen.refusals) == 2)
        assert served.seen.refusals[1][1].startswith("negative.txt: declares -1 bytes")


def test_the_limit_must_be_positive(served: Served) -> None:
    with pytest.raises(ValueError, match="max_bytes: expected a positive number of bytes, got 0"):
        limit_uploads(served.server.gui, 0, lambda client, why: None)
