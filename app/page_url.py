"""The page's own URL, which viser 1.1.1 does not tell the server, read and written by small
scripts run in the page.

viser has no public call to run a script in a client: this sends its internal
`RunJavascriptMessage` (the one its Plotly support uses) on the client's connection. A value is
read back through the page's localStorage, under the key prefix of viser's public
`client.local_storage`, one key per client so that tabs opening at once do not mix. Tested in
a browser (tests/app/test_browser_demo.py); a viser upgrade must keep those tests green.
"""

from __future__ import annotations

import json

import viser
from viser import _messages

LOCAL_STORAGE_PREFIX = "viser-user:"  # where viser 1.1.1's client.local_storage keeps its keys
READ_TIMEOUT_S = 3.0


def run_script(client: viser.ClientHandle, source: str) -> None:
    """Run `source` (JavaScript) in the client's page."""
    client._websock_connection.queue_message(_messages.RunJavascriptMessage(source=source))


def read_page(
    client: viser.ClientHandle, expression: str, timeout_s: float = READ_TIMEOUT_S
) -> str:
    """The string value of the JavaScript `expression` in the client's page (e.g.
    "location.search"). Blocks until the page answers; TimeoutError after `timeout_s`,
    RuntimeError when the client left."""
    key = f"fusionscope-page-{client.client_id}"
    stored = json.dumps(LOCAL_STORAGE_PREFIX + key)
    run_script(client, f"localStorage.setItem({stored}, String({expression}));")
    try:
        value = client.local_storage.get_item(key, timeout=timeout_s)
    finally:
        client.local_storage.remove_item(key)
    return value or ""


def show_query(client: viser.ClientHandle, query: str) -> None:
    """Make `query` ('?...', or '?' for none) the page's URL query, without reloading it or
    adding to its history."""
    target = json.dumps(query) if query != "?" else "location.pathname"
    run_script(client, f"history.replaceState(null, '', {target});")


def copy_page_url(client: viser.ClientHandle) -> None:
    """Put the page's URL on the viewer's clipboard (browsers allow it on localhost and
    https pages)."""
    run_script(client, "navigator.clipboard.writeText(location.href).catch(() => {});")
