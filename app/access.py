"""Who may open the inspector: the check on every HTTP request and websocket handshake.

    access = Access(token=new_token())
    with guarding(access):
        server = viser.ViserServer(...)     # its requests pass `refusal` first

A browser lets any web page open a websocket to 127.0.0.1, so binding to loopback alone lets
every site the user visits drive the inspector (save presets, replace annotations). Three
checks close that:

- **Origin**: a handshake whose `Origin` header is present and is not the page's own address
  (`http://` + its `Host`) is refused. Browsers always send `Origin` with a websocket;
  other programs may leave it out.
- **Host** (DNS rebinding: a site whose name resolves to 127.0.0.1 is same-origin with
  itself): the `Host` header must name an IP address, `localhost`, or a name the server
  was told to answer to (`--allow-host`).
- **Token**: a secret made per server run, printed in the URL at start (as Jupyter does).
  A request must carry it in the query (`?token=...`) or in the cookie the page that was
  opened with it received. `None` (`--no-token`) turns this check off.

viser 1.1.1 has no hook for any of this: `guarding` wraps the `websockets` server function
that viser's background thread calls while `ViserServer()` is being built, composing
`refusal` before viser's own request handler, and says whether it was used (so that a viser
that starts its server another way fails loudly instead of running unguarded).
"""

from __future__ import annotations

import hmac
import http
import ipaddress
import secrets
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from http.cookies import CookieError, SimpleCookie
from typing import Any
from urllib.parse import parse_qsl, urlsplit

import websockets.asyncio.server as ws_server
from websockets.datastructures import Headers
from websockets.http11 import Request, Response

TOKEN_KEY = "token"  # the query key that carries the token (and that view links ignore)
TOKEN_BYTES = 24  # 192 random bits, as URL-safe base64 (32 characters)

ProcessRequest = Callable[[ws_server.ServerConnection, Request], Response | None]


@dataclass(frozen=True)
class Access:
    """What a request must show. `token`: the secret it must carry (None: none needed);
    `allowed_hosts`: host names its `Host` header may name besides IP addresses and
    `localhost` (lower case, without port)."""

    token: str | None = None
    allowed_hosts: frozenset[str] = field(default_factory=frozenset)

    def __post_init__(self) -> None:
        if self.token is not None and len(self.token) < 16:
            raise ValueError(f"token: expected at least 16 characters, got {len(self.token)}")


NO_TOKEN = Access()  # Origin and Host checked, no token needed: the library's default


def new_token() -> str:
    """A fresh secret for one server run."""
    return secrets.token_urlsafe(TOKEN_BYTES)


def page_address(host: str, port: int, access: Access) -> str:
    """The URL to open: the inspector at `host:port`, with the token when it needs one."""
    name = f"[{host}]" if ":" in host else host
    query = f"?{TOKEN_KEY}={access.token}" if access.token is not None else ""
    return f"http://{name}:{port}/{query}"


def cookie_name(host_header: str) -> str:
    """The cookie that carries the token for the server at `host_header` ("host:port").
    Browsers share cookies between the ports of one host, so the port is in the name."""
    _, _, port = _split_host(host_header)
    return f"fusionscope-token-{port or 80}"


def refusal(access: Access, request: Request) -> Response | None:
    """A 403 response saying why `request` may not reach the inspector; None when it may."""
    host = request.headers.get("Host")
    if host is None:
        return _forbidden("the request has no Host header")
    name, valid, _ = _split_host(host)
    if not valid or not _host_allowed(name, access.allowed_hosts):
        return _forbidden(
            f"Host {host!r} is not an address of this inspector (expected an IP address, "
            "localhost, or a name given with --allow-host)"
        )
    origin = request.headers.get("Origin")
    if origin is not None and origin.lower() not in (
        f"http://{host}".lower(),
        f"https://{host}".lower(),
    ):
        return _forbidden(f"a page from {origin!r} may not use the inspector at http://{host}")
    if access.token is not None and not _carries_token(access.token, request, host):
        return _forbidden(
            "this inspector needs its token: open the URL that `fusionscope serve` printed "
            "(http://HOST:PORT/?token=...)"
        )
    return None


def guarded(access: Access, inner: ProcessRequest | None) -> ProcessRequest:
    """`inner` (viser's handler of plain HTTP requests) behind `refusal`. A page opened with
    the token in its query gets it as a cookie, so that its websocket (whose URL viser's
    client builds without the query) carries it."""

    def process_request(
        connection: ws_server.ServerConnection, request: Request
    ) -> Response | None:
        refused = refusal(access, request)
        if refused is not None:
            return refused
        response = inner(connection, request) if inner is not None else None
        if response is not None and access.token is not None and _query_token(request):
            host = request.headers["Host"]
            response.headers["Set-Cookie"] = (
                f"{cookie_name(host)}={access.token}; Path=/; HttpOnly; SameSite=Strict"
            )
        return response

    return process_request


@dataclass
class Guarding:
    """What `guarding` did: `used` is True once a server was started through it."""

    used: bool = False


_patch_lock = threading.Lock()


@contextmanager
def guarding(access: Access) -> Iterator[Guarding]:
    """While it lasts, every `websockets` server started in this process checks `access`
    before anything else (see the module's docstring). One at a time."""
    with _patch_lock:
        original = ws_server.serve
        record = Guarding()

        def serve(
            *args: Any, process_request: ProcessRequest | None = None, **kwargs: Any
        ) -> ws_server.serve:
            record.used = True
            return original(*args, process_request=guarded(access, process_request), **kwargs)

        ws_server.serve = serve  # type: ignore[misc,assignment]
        try:
            yield record
        finally:
            ws_server.serve = original  # type: ignore[misc]


# --- the parts ------------------------------------------------------------------------------
def _split_host(host_header: str) -> tuple[str, bool, str]:
    """(name in lower case, well formed, port) of a Host header: "a:8080", "[::1]:8080"."""
    host_header = host_header.strip()
    if host_header.startswith("["):
        name, bracket, rest = host_header[1:].partition("]")
        if not bracket or (rest and not rest.startswith(":")):
            return "", False, ""
        port = rest[1:]
    else:
        name, _, port = host_header.partition(":")
    valid = bool(name) and (port == "" or port.isdigit())
    return name.lower(), valid, port


def _host_allowed(name: str, allowed: frozenset[str]) -> bool:
    if name == "localhost" or name in allowed:
        return True
    try:
        ipaddress.ip_address(name)
    except ValueError:
        return False
    return True


def _query_token(request: Request) -> str | None:
    for key, value in parse_qsl(urlsplit(request.path).query):
        if key == TOKEN_KEY:
            return value
    return None


def _carries_token(token: str, request: Request, host: str) -> bool:
    offered = [_query_token(request)]
    for header in request.headers.get_all("Cookie"):
        try:
            cookie = SimpleCookie(header)
        except CookieError:
            continue
        morsel = cookie.get(cookie_name(host))
        if morsel is not None:
            offered.append(morsel.value)
    return any(
        value is not None and hmac.compare_digest(value.encode(), token.encode())
        for value in offered
    )


def _forbidden(reason: str) -> Response:
    body = f"fusionscope inspector: refused: {reason}\n".encode()
    headers = Headers({"Content-Type": "text/plain; charset=utf-8"})
    headers["Content-Length"] = str(len(body))
    return Response(http.HTTPStatus.FORBIDDEN, "Forbidden", headers, body)
