"""Who may open the inspector (app.access): the checks on their own, then a running inspector
tried with a raw websocket client, a forged Host header, and a page of another site in
Chromium."""

from __future__ import annotations

import http.client
import http.server
import shutil
import tempfile
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
import viser
from app_fakes import Recordings
from browser_page import CAMERA_IMG, TIMEOUT_MS
from playwright.sync_api import Browser
from websockets.datastructures import Headers
from websockets.exceptions import InvalidStatus
from websockets.http11 import Request, Response
from websockets.sync.client import connect

from app.access import (
    NO_TOKEN,
    Access,
    cookie_name,
    guarded,
    new_token,
    page_address,
    refusal,
)
from app.server import InspectorServer

TOKEN = "t" * 20
PROTOCOL = f"viser-v{viser.__version__}"


def request(path: str = "/", **headers: str) -> Request:
    return Request(path, Headers({k.replace("_", "-"): v for k, v in headers.items()}))


def refused_for(access: Access, path: str = "/", **headers: str) -> str | None:
    """Why `access` refuses the request (the 403 page's text); None when it lets it through."""
    response = refusal(access, request(path, **headers))
    if response is None:
        return None
    assert response.status_code == 403
    return response.body.decode()


# --- the checks -----------------------------------------------------------------------------
@pytest.mark.parametrize("host", ["127.0.0.1:8080", "localhost:8080", "[::1]:8080", "10.1.2.3"])
def test_a_page_of_its_own_address_with_the_token_passes(host: str) -> None:
    access = Access(TOKEN)
    assert refused_for(access, f"/?token={TOKEN}", Host=host, Origin=f"http://{host}") is None
    assert refused_for(access, f"/?recording=a&token={TOKEN}", Host=host) is None


def test_the_cookie_carries_the_token_for_a_websocket_whose_url_has_no_query() -> None:
    host = "127.0.0.1:8080"
    cookie = f"other=1; {cookie_name(host)}={TOKEN}"
    assert (
        refused_for(Access(TOKEN), "/", Host=host, Origin=f"http://{host}", Cookie=cookie) is None
    )
    # the cookie of a server on another port does not count
    other_port = f"{cookie_name('127.0.0.1:9090')}={TOKEN}"
    assert "needs its token" in (
        refused_for(Access(TOKEN), "/", Host=host, Cookie=other_port) or ""
    )


@pytest.mark.parametrize("path", ["/", "/?token=", "/?token=" + "x" * 20, f"/?tok={TOKEN}"])
def test_a_request_without_the_right_token_is_refused(path: str) -> None:
    why = refused_for(Access(TOKEN), path, Host="127.0.0.1:8080")
    assert why is not None and "needs its token" in why and "fusionscope serve" in why
    assert refused_for(NO_TOKEN, path, Host="127.0.0.1:8080") is None


@pytest.mark.parametrize(
    "origin", ["http://evil.example", "http://127.0.0.1:8081", "null", "http://127.0.0.1"]
)
def test_a_page_of_another_origin_is_refused_even_with_the_token(origin: str) -> None:
    for access in (Access(TOKEN), NO_TOKEN):
        why = refused_for(access, f"/?token={TOKEN}", Host="127.0.0.1:8080", Origin=origin)
        assert why is not None and repr(origin) in why


@pytest.mark.parametrize("host", ["evil.example:8080", "127.0.0.1.evil.example", "a:b", ":8080"])
def test_a_host_name_it_was_not_given_is_refused_against_dns_rebinding(host: str) -> None:
    why = refused_for(NO_TOKEN, "/", Host=host, Origin=f"http://{host}")
    assert why is not None and "Host" in why
    assert refused_for(NO_TOKEN, "/") == (
        "fusionscope inspector: refused: the request has no Host header\n"
    )


def test_a_host_name_given_with_allow_host_passes() -> None:
    access = Access(None, frozenset({"workstation.lan"}))
    assert refused_for(access, "/", Host="WorkStation.lan:8080") is None
    assert refused_for(access, "/", Host="other.lan:8080") is not None


def test_a_short_token_is_refused_and_new_tokens_differ() -> None:
    with pytest.raises(ValueError, match="token: expected at least 16 characters, got 5"):
        Access("short")
    assert new_token() != new_token() and len(new_token()) >= 32


def test_the_page_opened_with_the_token_gets_it_as_a_cookie() -> None:
    def page(connection: object, req: Request) -> Response:
        return Response(200, "OK", Headers({"Content-Type": "text/html"}), b"page")

    handler = guarded(Access(TOKEN), page)
    host = "127.0.0.1:8080"
    answer = handler(None, request(f"/?token={TOKEN}", Host=host))  # type: ignore[arg-type]
    assert answer is not None and answer.body == b"page"
    assert answer.headers["Set-Cookie"] == (
        f"{cookie_name(host)}={TOKEN}; Path=/; HttpOnly; SameSite=Strict"
    )
    by_cookie = request("/", Host=host, Cookie=f"{cookie_name(host)}={TOKEN}")
    assert "Set-Cookie" not in handler(None, by_cookie).headers  # type: ignore[arg-type,union-attr]
    refused = handler(None, request("/", Host=host))  # type: ignore[arg-type]
    assert refused is not None and refused.status_code == 403


def test_the_printed_address_carries_the_token() -> None:
    assert page_address("127.0.0.1", 8080, Access(TOKEN)) == f"http://127.0.0.1:8080/?token={TOKEN}"
    assert page_address("::1", 8080, NO_TOKEN) == "http://[::1]:8080/"


# --- a running inspector --------------------------------------------------------------------
@pytest.fixture(scope="module")
def guarded_server(recordings: Recordings) -> Iterator[InspectorServer]:
    presets = Path(tempfile.mkdtemp(prefix="fusionscope-presets-"))
    server = InspectorServer(
        recordings.root, None, "127.0.0.1", 0, presets=presets, access=Access(TOKEN)
    )
    server.start()
    yield server
    server.stop()
    shutil.rmtree(presets, ignore_errors=True)


def test_a_raw_websocket_client_needs_the_token_and_no_foreign_origin(
    guarded_server: InspectorServer,
) -> None:
    base = f"ws://127.0.0.1:{guarded_server.port}/"
    for url, origin in [
        (base, None),
        (f"{base}?token={TOKEN}", "http://evil.example"),
        (f"{base}?token={TOKEN}", f"http://localhost:{guarded_server.port}"),
    ]:
        with pytest.raises(InvalidStatus, match="403"):
            connect(url, origin=origin, subprotocols=[PROTOCOL], open_timeout=10)  # type: ignore[arg-type,list-item]
    with connect(f"{base}?token={TOKEN}", subprotocols=[PROTOCOL], open_timeout=10) as client:  # type: ignore[list-item]
        assert client.recv(timeout=10)  # viser's first messages: the connection is served


def test_a_forged_host_header_is_refused(guarded_server: InspectorServer) -> None:
    connection = http.client.HTTPConnection("127.0.0.1", guarded_server.port, timeout=10)
    connection.request("GET", f"/?token={TOKEN}", headers={"Host": "rebound.example:80"})
    answer = connection.getresponse()
    assert answer.status == 403 and b"rebound.example" in answer.read()
    connection.close()


class _AttackerPage(http.server.BaseHTTPRequestHandler):
    """Another site: a page whose script opens a websocket to the inspector (token known)."""

    target = ""

    def do_GET(self) -> None:
        body = f"""<script>
          const ws = new WebSocket({self.target!r}, [{PROTOCOL!r}]);
          ws.onopen = () => {{ document.title = "opened"; }};
          ws.onclose = (e) => {{ if (document.title !== "opened") document.title = "refused"; }};
        </script>""".encode()
        self.send_response(200)
        self.send_header("Content-Type", "text/html")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args: object) -> None:
        pass


def test_chromium_refuses_another_sites_page_and_serves_the_printed_address(
    guarded_server: InspectorServer, browser: Browser
) -> None:
    port = guarded_server.port
    _AttackerPage.target = f"ws://127.0.0.1:{port}/?token={TOKEN}"
    attacker = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _AttackerPage)
    threading.Thread(target=attacker.serve_forever, daemon=True).start()
    context = browser.new_context(viewport={"width": 1400, "height": 800})
    try:
        page = context.new_page()
        page.goto(f"http://127.0.0.1:{attacker.server_address[1]}/")
        page.wait_for_function("document.title !== ''", timeout=TIMEOUT_MS)
        assert page.title() == "refused"
        # the printed address opens the inspector; later visits carry the token in the cookie
        page.goto(page_address("127.0.0.1", port, Access(TOKEN)))
        page.locator(CAMERA_IMG).first.wait_for(timeout=TIMEOUT_MS)
        page.goto(f"http://127.0.0.1:{port}/?recording=highway")
        page.locator(CAMERA_IMG).first.wait_for(timeout=TIMEOUT_MS)
        stranger = browser.new_page()
        stranger.goto(f"http://127.0.0.1:{port}/")
        assert "needs its token" in stranger.content()
        stranger.close()
    finally:
        context.close()
        attacker.shutdown()
