"""A clip of a drive as a video file: every frame as the inspector shows it, with its banner
(`app.video_frame`), as H.264 in MP4 (.mp4) or as an animated GIF (.gif).

`export_video` runs the engine over the clip as the inspector plays it: one engine per
parameter set seeks the clip's first frame from the drive's start (`core.engine`, "From the
start", as the inspector's seeks are once its milestones reach the frame) and plays on from
there, so each exported frame, its track ids included, is what the inspector shows for it. The
frames go to OUT + ".partial", renamed to OUT only when the last one is written: an
interrupted or failed export leaves no half file under OUT.

Formats, by OUT's suffix:
    - .mp4: H.264 (libx264), yuv420p (BT.601, limited range, tagged so), the drive's frame
      rate (`frame_rate_hz`, from its camera stamps) as a constant rate, `+faststart` (the
      index first: browsers play it while it loads). x264's "ultrafast" preset at a
      constant quantizer of 17 (Constrained Baseline: every browser plays it): on
      recordings/highway and stop_and_go (640x570 with the banner, one thread) 2.6 ms a
      frame and 2.2 MB for 15 s, against 3.0 ms and 2.3 MB at CRF 20, the same quality
      (PSNR 50.9 against 51.1 dB; 50.1 against 50.0 at worst), because CRF makes x264
      estimate each frame's cost on a half-size copy first; "veryfast" took 9 ms a frame.
      The drive's reading and the engine take about 7 ms a frame: the encoder's speed
      counts more than the file's size.
    - .gif: for slides, scaled to `gif_width_px` (default `GIF_PICTURE_WIDTH_PX` per camera
      picture); each frame gets its own 256-colour palette (Pillow's fast octree
      quantizer, no dithering, which would only grow the file) and is written as it comes
      by FFmpeg's GIF encoder, which stores only the rectangle that changed; delays are in
      hundredths of a second, as GIF has them. The overlay colours stay exact; smooth grey
      road and sky may show a few steps. Pillow's own GIF writer gives files of the same
      size but keeps every frame in memory until the end; PyAV does not convert RGB to
      pal8 itself.

The encoders run on one thread (`ENCODER_THREADS`); a caller that wants OpenCV on one thread
too wraps the call in `core.bench.one_thread` (the CLI does: its speed figure is one core's).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any, Protocol, cast

import av
import cv2
import numpy as np
from av.video.reformatter import ColorPrimaries, ColorRange, ColorTrc
from PIL import Image

from app import draw
from app.state import DEMO_LAYERS, Layers
from app.video_frame import video_frame
from app.view import AB_GAP_PX, FrameSource, check_clip
from core.checks import output_suffix
from core.engine import FusionEngine
from core.params import Params, params_hash

VIDEO_FORMATS = {".mp4": "mp4", ".gif": "gif"}  # OUT's suffix (any case) -> container
PARTIAL_SUFFIX = ".partial"
ENCODER_THREADS = 1
CODEC_OPTIONS: dict[str, dict[str, str]] = {
    "libx264": {"preset": "ultrafast", "qp": "17"},
    "gif": {},
}
MP4_OPTIONS = {"movflags": "+faststart"}
AVCOL_SPC_SMPTE170M = 6  # FFmpeg's AVColorSpace for BT.601 (PyAV's Colorspace is swscale's)
GIF_PICTURE_WIDTH_PX = 480  # a GIF's width per camera picture, by default
GIF_COLOURS = 256
MIN_GIF_WIDTH_PX = 16
OPAQUE = 255
FRAME_RATE_DENOMINATOR_MAX = 1001  # NTSC's 30000/1001 and the like stay exact
Progress = Callable[[int, int], None]


class ExportError(Exception):
    """The encoder or the container could not write the video; the message names OUT."""


@dataclass(frozen=True)
class ExportSummary:
    """What an export wrote: the file, the drive's frames first_frame..last_frame (both
    included), the picture's (width, height) in px, the frame rate, the file's size, and the
    wall-clock and CPU time the export took (engine warm-up, engine, drawing and encoding;
    CPU: this process's, all threads), and of that the wall-clock time of its first frame
    (the engine plays the drive from its start to it; the first engine of a process also loads
    its compiled numba code, about a second)."""

    path: Path
    first_frame: int
    last_frame: int
    size_px: tuple[int, int]
    frame_rate_hz: float
    file_bytes: int
    elapsed_s: float
    cpu_s: float
    first_frame_s: float

    @property
    def frames(self) -> int:
        return self.last_frame - self.first_frame + 1

    @property
    def clip_s(self) -> float:
        """How long the video plays."""
        return self.frames / self.frame_rate_hz

    @property
    def frames_per_s(self) -> float:
        return self.frames / self.elapsed_s if self.elapsed_s > 0 else float("inf")

    @property
    def real_time_multiple(self) -> float:
        """How many times faster than the clip plays the export ran."""
        return self.clip_s / self.elapsed_s if self.elapsed_s > 0 else float("inf")

    @property
    def steady_real_time_multiple(self) -> float:
        """The same after the first frame: how fast the frames follow one another."""
        after_s = self.elapsed_s - self.first_frame_s
        return (self.frames - 1) / self.frame_rate_hz / after_s if after_s > 0 else float("inf")


def summary_text(summary: ExportSummary) -> str:
    """One line: file, frames, picture size, size on disk, seconds, frames/s, x real time
    (also after the first frame)."""
    w, h = summary.size_px
    return (
        f"{summary.path}: {summary.frames} frames ({summary.first_frame}-{summary.last_frame}, "
        f"{summary.clip_s:.1f} s at {summary.frame_rate_hz:g} fps), {w}x{h}, "
        f"{summary.file_bytes / 1e6:.1f} MB, in {summary.elapsed_s:.2f} s: "
        f"{summary.frames_per_s:.0f} frames/s, {summary.real_time_multiple:.1f}x real time "
        f"({summary.cpu_s:.2f} s CPU; the first frame {summary.first_frame_s:.2f} s, after it "
        f"{summary.steady_real_time_multiple:.1f}x real time)"
    )


def video_format(out_path: Path, name: str = "out_path") -> str:
    """The container of `out_path` by its suffix ("mp4" or "gif"). ValueError naming `name`
    when the suffix is another, `out_path` is a folder, or its folder does not exist."""
    return VIDEO_FORMATS[output_suffix(name, out_path, VIDEO_FORMATS)]


def layers_named(names: str) -> Layers:
    """The layers of comma-separated `app.state.Layers` names switched on, the others off
    ("" for none). ValueError listing the names known when one is not."""
    chosen = [n.strip() for n in names.split(",") if n.strip()]
    unknown = [n for n in chosen if n not in Layers.names()]
    if unknown:
        raise ValueError(
            f"expected comma-separated layer names among {', '.join(Layers.names())}, "
            f"got {', '.join(unknown)}"
        )
    return Layers(**{name: name in chosen for name in Layers.names()})


def partial_path(out_path: Path) -> Path:
    """Where an export into `out_path` writes until it is complete."""
    return out_path.with_name(out_path.name + PARTIAL_SUFFIX)


class _Writer(Protocol):
    def write(self, rgb: draw.RgbImage) -> None: ...
    def close(self) -> None: ...


class _AvWriter:
    """Frames into a container through one PyAV stream, numbered from 0; `close` flushes the
    encoder and closes the file."""

    def __init__(
        self, path: Path, fmt: str, codec: str, size_px: tuple[int, int], rate: Fraction
    ) -> None:
        options = MP4_OPTIONS if fmt == "mp4" else {}
        self._container = av.open(str(path), mode="w", format=fmt, options=options)
        try:
            added = self._container.add_stream(codec, rate=rate, options=CODEC_OPTIONS[codec])
            stream = cast(av.VideoStream, added)  # a video codec's stream
            stream.width, stream.height = size_px
            stream.codec_context.thread_count = ENCODER_THREADS
            self._configure(stream)
        except BaseException:
            self._container.close()
            raise
        self._stream = stream
        self._count = 0

    def _configure(self, stream: av.VideoStream) -> None:
        """The stream's pixel format and whatever else the format needs."""

    def _mux(self, frame: av.VideoFrame) -> None:
        frame.pts = self._count
        self._count += 1
        self._container.mux(self._stream.encode(frame))

    def close(self) -> None:
        try:
            self._container.mux(self._stream.encode(None))
        finally:
            self._container.close()


class _Mp4Writer(_AvWriter):
    """H.264 in MP4; frames converted to yuv420p by OpenCV (BT.601, limited range;
    swscale's conversion costs 30 times as much here)."""

    def __init__(self, path: Path, size_px: tuple[int, int], rate: Fraction) -> None:
        super().__init__(path, "mp4", "libx264", size_px, rate)

    def _configure(self, stream: av.VideoStream) -> None:
        stream.pix_fmt = "yuv420p"
        context = stream.codec_context
        context.color_range = ColorRange.MPEG
        context.colorspace = AVCOL_SPC_SMPTE170M
        context.color_primaries = ColorPrimaries.SMPTE170M
        context.color_trc = ColorTrc.SMPTE170M

    def write(self, rgb: draw.RgbImage) -> None:
        yuv = np.asarray(cv2.cvtColor(rgb, cv2.COLOR_RGB2YUV_I420), dtype=np.uint8)
        self._mux(av.VideoFrame.from_ndarray(yuv, format="yuv420p"))


class _GifWriter(_AvWriter):
    """An animated GIF through FFmpeg's GIF encoder, one palette per frame by Pillow's
    quantizer; loops for ever."""

    def __init__(self, path: Path, size_px: tuple[int, int], rate: Fraction) -> None:
        super().__init__(path, "gif", "gif", size_px, rate)

    def _configure(self, stream: av.VideoStream) -> None:
        stream.pix_fmt = "pal8"

    def write(self, rgb: draw.RgbImage) -> None:
        quantized = Image.fromarray(rgb).quantize(
            GIF_COLOURS, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE
        )
        rgb_palette = np.array(quantized.getpalette() or [], dtype=np.uint8).reshape(-1, 3)
        argb = np.zeros((GIF_COLOURS, 4), dtype=np.uint8)
        argb[:, 0] = OPAQUE
        argb[: len(rgb_palette), 1:] = rgb_palette[:GIF_COLOURS]
        pal8 = cast(Any, (np.asarray(quantized, dtype=np.uint8), argb))
        self._mux(av.VideoFrame.from_ndarray(pal8, format="pal8"))


def _discard(writer: _Writer | None, partial: Path) -> None:
    """After a failure: the writer closed (its own error dropped: the first is the one to
    report) and the partial file deleted."""
    if writer is not None:
        with contextlib.suppress(Exception):
            writer.close()
    partial.unlink(missing_ok=True)


def _even(rgb: draw.RgbImage) -> draw.RgbImage:
    """`rgb` with a row and/or a column of the banner's colour added to make both sides
    even, as yuv420p needs."""
    h, w = rgb.shape[:2]
    if h % 2 == 0 and w % 2 == 0:
        return rgb
    out = np.empty((h + h % 2, w + w % 2, 3), dtype=np.uint8)
    draw.fill(out, draw.STRIP_COLOUR)
    out[:h, :w] = rgb
    return out


def gif_default_width_px(camera_width_px: int, pictures: int) -> int:
    """A GIF's default width: `GIF_PICTURE_WIDTH_PX` per camera picture of
    `camera_width_px`, `pictures` (A, or A and B) side by side with their gap scaled alike."""
    drawn_px = pictures * camera_width_px + (pictures - 1) * AB_GAP_PX
    return round(drawn_px * GIF_PICTURE_WIDTH_PX / camera_width_px)


def frame_rate(drive: FrameSource) -> Fraction:
    """The drive's frame rate (`frame_rate_hz`, from its camera stamps) as a fraction.
    ValueError for a drive of one frame, which has none."""
    if not drive.frame_rate_hz > 0:
        raise ValueError(
            f"drive {drive.path}: a video needs a frame rate, and a drive of "
            f"{len(drive)} frame(s) has none"
        )
    return Fraction(drive.frame_rate_hz).limit_denominator(FRAME_RATE_DENOMINATOR_MAX)


def export_video(
    drive: FrameSource,
    out_path: Path,
    first_frame: int,
    last_frame: int,
    layers: Layers | None = None,
    params: Params | None = None,
    params_b: Params | None = None,
    progress: Progress | None = None,
    gif_width_px: int | None = None,
) -> ExportSummary:
    """Frames first_frame..last_frame (both included) of `drive` as a video in `out_path`
    (module docstring): `layers` (default `app.state.DEMO_LAYERS`, what was found) of the
    engine's results under `params` (default `Params()`), set `params_b`'s beside them when
    given, each over its banner (`app.video_frame.video_frame`).

    progress(done, total) after each frame written. gif_width_px: a GIF's width (default
    `GIF_PICTURE_WIDTH_PX` per camera picture); only for .gif. ValueError naming the
    argument for a suffix other than .mp4 and .gif, a folder or a missing folder as
    `out_path`, a clip outside the drive, a drive without a frame rate, a GIF width below
    `MIN_GIF_WIDTH_PX`; ExportError when the encoder or the file fails; reader errors pass
    through. Nothing is left under
    `out_path` (nor its partial file) when it fails; a file there is replaced whole when it
    succeeds."""
    started, started_cpu = time.perf_counter(), time.process_time()
    fmt = video_format(out_path)
    check_clip(drive, first_frame, last_frame)
    rate = frame_rate(drive)
    if gif_width_px is not None:
        if fmt != "gif":
            raise ValueError(f"gif_width_px: only for a .gif, got {out_path}")
        if gif_width_px < MIN_GIF_WIDTH_PX:
            raise ValueError(
                f"gif_width_px: expected at least {MIN_GIF_WIDTH_PX} px, got {gif_width_px}"
            )
    layers = DEMO_LAYERS if layers is None else layers
    sets = [Params() if params is None else params] + ([] if params_b is None else [params_b])
    hashes = [params_hash(p) for p in sets]
    # from the drive's start, as the inspector shows it: the tracks and ids of a playback
    engines = [FusionEngine(p, drive.camera, catch_up_frames=None) for p in sets]
    width_px = None
    if fmt == "gif":
        width_px = gif_width_px or gif_default_width_px(drive.camera.intrinsics.width_px, len(sets))

    def picture(index: int) -> draw.RgbImage:
        results = [engine.seek(drive, index) for engine in engines]  # the drive caches frames
        rgb = video_frame(drive, layers, drive.frame(index), results, hashes, width_px)
        return _even(rgb) if fmt == "mp4" else rgb

    partial = partial_path(out_path)
    total = last_frame - first_frame + 1
    writer: _Writer | None = None
    try:
        first = picture(first_frame)
        first_frame_s = time.perf_counter() - started
        size_px = (first.shape[1], first.shape[0])
        writer = (_Mp4Writer if fmt == "mp4" else _GifWriter)(partial, size_px, rate)
        for done, index in enumerate(range(first_frame, last_frame + 1), start=1):
            writer.write(first if index == first_frame else picture(index))
            if progress is not None:
                progress(done, total)
        closing, writer = writer, None
        closing.close()
        partial.replace(out_path)
    except av.FFmpegError as err:
        _discard(writer, partial)
        raise ExportError(f"{out_path}: writing the {fmt} failed: {err}") from err
    except BaseException:
        _discard(writer, partial)
        raise
    return ExportSummary(
        out_path,
        first_frame,
        last_frame,
        size_px,
        float(rate),
        out_path.stat().st_size,
        time.perf_counter() - started,
        time.process_time() - started_cpu,
        first_frame_s,
    )
