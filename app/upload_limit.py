"""Uploads over a set size refused before anything of them is kept.

    limit_uploads(client.gui, 64 * 2**20, refused)   # refused(client_id, why) tells the tab

viser keeps every part of an upload in memory until the last one arrives, whatever size the
upload declares, and has no limit (200 parts of 1 MB of an upload declaring 100 GB were all
kept). Here an upload is refused when

- it declares more than `max_bytes`, or more than `max_bytes` together with the uploads the
  same tab has in flight: nothing of it is kept, its parts are dropped as they come;
- its parts bring more bytes than it declared: what was kept of it is let go.

viser 1.1.1 has no hook for this: the two handlers of uploads of a GUI (the server's, and
each tab's own) are taken off its websocket and put back behind these checks (the GUI's
`_websock_interface`, handlers and `_current_file_upload_states` are private to viser; the
version is pinned in pyproject.toml). Every GUI that has an upload button needs it.
A refused upload leaves viser's own "Uploading" notice spinning in the tab (the client is not
told); `refused` says why beside it.
"""

from __future__ import annotations

from collections.abc import Callable

import viser
from viser._messages import FileTransferPart, FileTransferStartUpload

MIB = 2**20
DEFAULT_MAX_UPLOAD_BYTES = 64 * MIB  # an hour of MOT boxes is about 65 MB; CVAT XML is larger

Refused = Callable[[int, str], None]  # (client id, why)


def limit_uploads(gui: viser.GuiApi, max_bytes: int, refused: Refused) -> None:
    """Put the upload handlers of `gui` behind the checks of this module's docstring."""
    if max_bytes <= 0:
        raise ValueError(f"max_bytes: expected a positive number of bytes, got {max_bytes}")
    websock = gui._websock_interface
    in_flight = gui._current_file_upload_states
    start, part = gui._handle_file_transfer_start, gui._handle_file_transfer_part
    websock.unregister_handler(FileTransferStartUpload, start)
    websock.unregister_handler(FileTransferPart, part)

    def checked_start(client_id: int, message: FileTransferStartUpload) -> None:
        if message.source_component_uuid not in gui._gui_input_handle_from_uuid:
            return  # a button of another GUI (viser's own handler does the same)
        held = sum(s["total_bytes"] for s in in_flight.values() if s["client_id"] == client_id)
        if message.size_bytes < 0 or message.size_bytes + held > max_bytes:
            refused(client_id, _over(message.filename, message.size_bytes, held, max_bytes))
            return
        start(client_id, message)  # type: ignore[arg-type]

    def checked_part(client_id: int, message: FileTransferPart) -> None:
        state = in_flight.get(message.transfer_uuid)
        if state is None or state["client_id"] != client_id:
            return  # not an upload of this tab's (viser, too, drops parts of none)
        if state["transferred_bytes"] + len(message.content) > state["total_bytes"]:
            in_flight.pop(message.transfer_uuid, None)
            refused(
                client_id,
                f"{state['filename']}: its parts bring more than the "
                f"{_size(state['total_bytes'])} it declared; nothing of it was kept",
            )
            return
        part(client_id, message)  # type: ignore[arg-type]

    websock.register_handler(FileTransferStartUpload, checked_start)
    websock.register_handler(FileTransferPart, checked_part)


def _over(filename: str, size_bytes: int, held_bytes: int, max_bytes: int) -> str:
    limit = f"the {_size(max_bytes)} a file uploaded to the inspector may have"
    if size_bytes < 0:
        return f"{filename}: declares {size_bytes} bytes; expected a size of at most {limit}"
    if held_bytes:
        under_way = f"the {_size(held_bytes)} of this tab's uploads under way"
        return f"{filename}: {_size(size_bytes)}, with {under_way}, is over {limit}"
    return f"{filename}: {_size(size_bytes)} is over {limit}; nothing of it was kept"


def _size(n_bytes: int) -> str:
    return f"{n_bytes / MIB:.1f} MB" if n_bytes >= MIB else f"{n_bytes:,} bytes"
