"""A static snapshot of a clip's 3D bird's-eye scene: one self-contained HTML file that plays
the clip in a browser without a server.

`bird_eye_snapshot_html` runs the engine over the clip as the inspector plays it, draws each
frame's bird's-eye view (`app.bird_eye.BirdEyeScene`, set B beside A when comparing) on the
scene of a private viser server that nobody connects to, records that scene with viser's
scene serializer, one real frame interval between frames, and returns viser's client page
with the recording embedded (`StateSerializer.as_html`). The page opens on the inspector's
top-down view (`app.bird_eye.top_down_pose`) and loops over the clip.

Clip timing: frame k of the clip is shown from t_k - t_first (its camera stamp from the
clip's first) until the next frame's; the last frame is held for one median frame interval
of the drive (`frame_rate_hz`), so the recording lasts
    duration_s = (t_last - t_first) + 1 / frame_rate_hz
(0 for a drive of one frame: a still scene). 150 frames at 10 Hz last 15.0 s.

Notes:
    - Every frame sends its ground texture as a new JPEG (`app.bird_eye.JPEG_QUALITY`), which
      zstd cannot shrink: the textures are nearly all of the recording, about 10 KB a frame
      for the bundled drives' 200x360 texture (the markers, boxes and labels add well
      under 1 KB a frame once compressed). The
      page is viser's client (0.8 MB) and the recording in base64 (4/3 of its size): 2.8 MB
      for a bundled 15 s drive (150 frames). Comparing A and B: 2.9 MB when B's textures
      are A's (zstd finds the repeat), about 5 MB when B's motion stereo differs.
    - viser prints a banner when its server starts and a line when it stops, on standard
      output, whatever `verbose` says; a caller whose standard output is data redirects it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import viser

from app.bird_eye import BirdEyeGeometry, BirdEyeScene, pose_of_views
from app.draw import RgbImage
from app.state import DEMO_LAYERS, Layers
from app.view import NS_PER_S, FrameSource, b_offset_y_m, bird_eye_view, check_clip
from core.engine import FusionEngine
from core.params import Params

PRIVATE_HOST = "127.0.0.1"  # the recording server is reachable from this machine only
ANY_FREE_PORT = 0  # the OS picks one: never the port of a running inspector
# the inspector's node names (app.session), so a snapshot reads as the inspector's scene
PREFIX_A = "/bird_eye_a"
PREFIX_B = "/bird_eye_b"

BirdEyeView = tuple[BirdEyeGeometry, RgbImage]


def clip_duration_s(drive: FrameSource, first_frame: int, last_frame: int) -> float:
    """How long the recording of frames first_frame .. last_frame of `drive` plays (module
    docstring): their span plus one median frame interval."""
    check_clip(drive, first_frame, last_frame)
    times = drive.times_ns
    span_s = (int(times[last_frame]) - int(times[first_frame])) / NS_PER_S
    return span_s + _hold_s(drive)


def bird_eye_snapshot_html(
    drive: FrameSource,
    first_frame: int,
    last_frame: int,
    params: Params,
    params_b: Params | None = None,
    progress: Callable[[int, int], None] | None = None,
    layers: Layers = DEMO_LAYERS,
) -> str:
    """The self-contained HTML page playing the bird's-eye view of frames first_frame ..
    last_frame (inclusive) of `drive` under `params`, and under `params_b` beside it when
    given (as the inspector's A/B compare places it: `app.view.b_offset_y_m`), drawing what
    `layers` says (`app.bird_eye.bird_eye_geometry`; by default a demo's, as a video's).

    Each frame is what the inspector shows when it plays the drive: an engine per set seeks
    to `first_frame` from the drive's start (`core.engine`, "From the start": the tracks and
    their ids of a playback) and plays on. progress(done, total) is called after each frame
    of the clip. ValueError naming first_frame or last_frame when they are not frames of the
    drive in order;
    `core.io.errors.RecordingError` when a frame of the clip cannot be read.
    """
    check_clip(drive, first_frame, last_frame)
    sets = [params] + ([] if params_b is None else [params_b])
    engines = [FusionEngine(p, drive.camera, catch_up_frames=None) for p in sets]
    total = last_frame - first_frame + 1
    server = viser.ViserServer(host=PRIVATE_HOST, port=ANY_FREE_PORT, verbose=False)
    try:
        serializer = server.get_scene_serializer()
        scenes = (BirdEyeScene(server.scene, PREFIX_A), BirdEyeScene(server.scene, PREFIX_B))
        for done, index in enumerate(range(first_frame, last_frame + 1), start=1):
            views = _views(engines, drive, index, layers)
            for scene, (geometry, texture) in zip(scenes, views, strict=False):
                scene.show(geometry, texture)
            if index == first_frame:
                _aim_initial_camera(server, params, views)
            following = index + 1 if index < last_frame else None
            serializer.insert_sleep(_interval_s(drive, index, following))
            if progress is not None:
                progress(done, total)
        return serializer.as_html()
    finally:
        server.stop()


def _views(
    engines: list[FusionEngine], drive: FrameSource, index: int, layers: Layers
) -> list[BirdEyeView]:
    """Frame `index`'s bird's-eye view under each engine's parameters, B beside A."""
    views = []
    for k, engine in enumerate(engines):
        offset_y_m = 0.0 if k == 0 else b_offset_y_m(engines[0].params)
        result = engine.seek(drive, index)
        views.append(bird_eye_view(result, engine.params, layers, offset_y_m))
    return views


def _aim_initial_camera(
    server: viser.ViserServer, params: Params, views: list[BirdEyeView]
) -> None:
    """The page opens (and "Reset View" returns) on the inspector's top-down view of the
    views shown."""
    pose = pose_of_views(views, params)
    camera = server.initial_camera
    camera.up = np.asarray(pose.up, dtype=np.float64)
    camera.position = np.asarray(pose.position_m, dtype=np.float64)
    camera.look_at = np.asarray(pose.look_at_m, dtype=np.float64)


def _hold_s(drive: FrameSource) -> float:
    """How long the clip's last frame stays: one median frame interval (0 with one frame)."""
    rate_hz = drive.frame_rate_hz
    return 1.0 / rate_hz if rate_hz > 0 else 0.0


def _interval_s(drive: FrameSource, index: int, following: int | None) -> float:
    """Seconds frame `index` stays on screen: until the `following` frame's stamp, or
    `_hold_s` for the clip's last frame (None)."""
    if following is None:
        return _hold_s(drive)
    times = drive.times_ns
    return max(0.0, (int(times[following]) - int(times[index])) / NS_PER_S)
