"""A tab's clip exported from the inspector, as the file the browser downloads: the video or
GIF of `fusionscope export-video` (`app.video_export`) or the 3D scene page of `fusionscope
export-scene` (`app.snapshot`), under the tab's layers and parameter sets.

The export opens the recording again, so it neither waits for nor slows the drive the tab's
render worker reads, and writes into a temporary folder that is removed afterwards.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path

from app.snapshot import bird_eye_snapshot_html
from app.state import ViewState
from app.video_export import export_video
from app.view_link import Clip
from core.io.drive import Drive

# the kinds of file, by suffix, as the buttons name them
EXPORT_KINDS = {
    "mp4": "Export video (MP4)",
    "gif": "Export GIF for slides",
    "html": "Export 3D scene (HTML)",
}


def export_clip(
    path: Path,
    kind: str,
    clip: Clip,
    state: ViewState,
    progress: Callable[[int, int], None] | None = None,
) -> tuple[str, bytes]:
    """The file name and bytes of frames clip[0]..clip[1] of the recording at `path` as
    `kind` (a key of `EXPORT_KINDS`) under `state`'s layers and sets A (and B). ValueError
    for an unknown kind or a clip outside the drive; the exports' and readers' errors pass
    through."""
    if kind not in EXPORT_KINDS:
        raise ValueError(f"kind: expected one of {', '.join(EXPORT_KINDS)}, got {kind!r}")
    first, last = clip
    with Drive(path) as drive, tempfile.TemporaryDirectory(prefix="fusionscope-") as folder:
        name = f"{drive.name}-{first}-{last}.{kind}"
        if kind == "html":
            html = bird_eye_snapshot_html(
                drive, first, last, state.params, state.params_b, progress, state.layers
            )
            return name, html.encode("utf-8")
        out = Path(folder) / name
        export_video(drive, out, first, last, state.layers, state.params, state.params_b, progress)
        return name, out.read_bytes()
