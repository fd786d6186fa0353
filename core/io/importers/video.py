"""`fusionscope import video`: a recording folder from any file OpenCV reads.

Frames become grey, are resized to `width_px` (height by the video's aspect ratio) and
resampled to `fps`: for each output time the source frame nearest in time is taken (source
frame i is at i / the container's frame rate). The stamps are the output times on the video's
clock (0 at its first frame) plus `start_ns`, the recording-clock time of the video's first
frame -- with CAN, its time on the CAN log's clock.

The recording folder, its manifest and the assumptions are core.io.importers.finish's; the
CAN mapping file and its checks are core.io.importers.can_mapping's.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import cv2

from core.io import radar_msgs
from core.io.errors import RecordingError
from core.io.image_header import MAX_IMAGE_PIXELS
from core.io.importers.calibration_spec import CalibrationSpec, build_calibration
from core.io.importers.can_mapping import CanSpec, check_can_times, prepare_can
from core.io.importers.finish import (
    DEFAULT_WIDTH_PX,
    NS_PER_S,
    GreyImage,
    ImportOptions,
    ImportResult,
    Progress,
    assumption_notes,
    camera_bag,
    check_ego_from_radar,
    check_out_dir,
    output_size,
    result,
    staging,
    to_grey,
    write_manifest,
)
from core.io.manifest import BagStream
from core.io.writer import BAG_DIR, CAMERA_TOPIC, png_image_message

DEFAULT_FPS = 10.0  # paper 002: "sampled at 10 fps"


@dataclass(frozen=True)
class VideoSampling:
    """How video frames become recording frames.

    width_px: output width (height by the aspect ratio); fps: output frame rate; start_ns:
    the recording-clock time of the video's first frame (the CAN clock's, with CAN);
    from_s, to_s: the clip on the video's clock (to_s None: to the end).
    """

    width_px: int = DEFAULT_WIDTH_PX
    fps: float = DEFAULT_FPS
    start_ns: int = 0
    from_s: float = 0.0
    to_s: float | None = None

    def __post_init__(self) -> None:
        if self.width_px < 1:
            raise ValueError(f"--width: expected a width >= 1 px, got {self.width_px}")
        if not (math.isfinite(self.fps) and self.fps > 0):
            raise ValueError(f"--fps: expected a frame rate > 0, got {self.fps}")
        if self.start_ns < 0:
            raise ValueError(f"start time: expected >= 0 ns, got {self.start_ns}")
        if not (math.isfinite(self.from_s) and self.from_s >= 0):
            raise ValueError(f"--from-s: expected a time >= 0 s, got {self.from_s}")
        if self.to_s is not None and not (math.isfinite(self.to_s) and self.to_s > self.from_s):
            raise ValueError(
                f"--to-s: expected a time after --from-s {self.from_s}, got {self.to_s}"
            )


@dataclass(frozen=True)
class _Video:
    capture: cv2.VideoCapture
    fps: float
    frame_count: int | None  # None when the container does not say
    width_px: int
    height_px: int


def _open_video(path: Path) -> _Video:
    if not path.is_file():
        raise RecordingError(f"{path}: video not found")
    capture = cv2.VideoCapture(str(path))
    if not capture.isOpened():
        raise RecordingError(
            f"{path}: cannot open as a video; expected a file OpenCV reads (mp4, avi, mkv, ...)"
        )
    fps = float(capture.get(cv2.CAP_PROP_FPS))
    count = capture.get(cv2.CAP_PROP_FRAME_COUNT)
    width = int(capture.get(cv2.CAP_PROP_FRAME_WIDTH))
    height = int(capture.get(cv2.CAP_PROP_FRAME_HEIGHT))
    if not (math.isfinite(fps) and fps > 0):
        capture.release()
        raise RecordingError(f"{path}: the video does not say its frame rate (got {fps})")
    if width <= 0 or height <= 0:
        capture.release()
        raise RecordingError(f"{path}: the video does not say its frame size ({width}x{height})")
    if width * height > MAX_IMAGE_PIXELS:
        capture.release()
        raise RecordingError(
            f"{path}: the video's frames are {width}x{height} pixels, more than the "
            f"{MAX_IMAGE_PIXELS:,} an import decodes"
        )
    frame_count = int(count) if 0 < count < 2**31 else None
    return _Video(capture, fps, frame_count, width, height)


def _output_ns(sampling: VideoSampling, k: int) -> int:
    """Output time k (ns) on the video's clock; each rounded on its own, so no drift builds up."""
    return round(sampling.from_s * NS_PER_S) + round(k * NS_PER_S / sampling.fps)


def _planned_count(v: _Video, sampling: VideoSampling) -> int:
    """How many output frames the clip gives, from the container's frame count (0: unknown)."""
    if v.frame_count is None:
        return 0
    end_s = (v.frame_count - 1) / v.fps
    end_ns = round((end_s if sampling.to_s is None else min(end_s, sampling.to_s)) * NS_PER_S)
    count = 0
    while _output_ns(sampling, count) <= end_ns:
        count += 1
    return count


def _sampled_frames(
    v: _Video, sampling: VideoSampling, out_size: tuple[int, int], where: Path
) -> Iterator[tuple[int, GreyImage]]:
    """(output time on the video's clock (ns), grey resized image) per output frame.

    Output time k takes source frame round(t_k * fps); source frames are grabbed in order and
    only the wanted ones decoded. Ends at --to-s or past the last source frame.
    """
    to_ns = None if sampling.to_s is None else round(sampling.to_s * NS_PER_S)
    grabbed = -1  # index of the last source frame grabbed
    image: GreyImage | None = None
    k = 0
    while True:
        t_ns = _output_ns(sampling, k)
        if to_ns is not None and t_ns > to_ns:
            return
        wanted = math.floor(t_ns * v.fps / NS_PER_S + 0.5)
        if wanted > grabbed:
            while grabbed < wanted and v.capture.grab():
                grabbed += 1
            if grabbed < wanted:
                return  # past the end
            ok, frame = v.capture.retrieve()
            if not ok or frame is None:
                raise RecordingError(f"{where}: frame {grabbed} cannot be decoded")
            image = to_grey(frame, out_size)
        assert image is not None  # wanted >= 0 = the first grab
        yield t_ns, image
        k += 1


def import_video(
    video: Path,
    out_dir: Path,
    calibration: CalibrationSpec,
    sampling: VideoSampling = VideoSampling(),
    can_spec: CanSpec | None = None,
    options: ImportOptions = ImportOptions(),
    progress: Progress | None = None,
) -> ImportResult:
    """Write the recording of `video` into `out_dir` (new or empty); see the module docstring.

    RecordingError or ValueError naming the file or the option on bad input; nothing is left
    behind then.
    """
    check_out_dir(out_dir)
    prepared = prepare_can(can_spec) if can_spec is not None else None
    assumptions, assumption_text, notes = assumption_notes(options, prepared)
    notes.extend(prepared.notes if prepared is not None else ())
    v = _open_video(video)
    try:
        source_size = (v.width_px, v.height_px)
        out_size = output_size(sampling.width_px, source_size)
        has_radar = prepared is not None and prepared.radar is not None
        check_ego_from_radar(options, prepared, has_radar, video)
        built = build_calibration(calibration, source_size, out_size, has_radar, "the video is")
        notes.extend(built.notes)
        total = _planned_count(v, sampling)
        if prepared is not None:
            planned = [sampling.start_ns + _output_ns(sampling, k) for k in range(max(total, 1))]
            what = f"{video}: the video's frames (--video-start-s)"
            notes.extend(check_can_times(prepared, planned, what, options.max_radar_skew_ms))
        with staging(out_dir) as tmp:
            bag = camera_bag(tmp)
            stamps: list[int] = []
            for t_ns, image in _sampled_frames(v, sampling, out_size, video):
                stamp = sampling.start_ns + t_ns
                bag.write(
                    CAMERA_TOPIC, stamp, png_image_message(radar_msgs.typestore(), stamp, image)
                )
                stamps.append(stamp)
                if progress is not None:
                    progress(len(stamps), max(total, len(stamps)))
            bag.close()
            if not stamps:
                end = "the end" if sampling.to_s is None else f"--to-s {sampling.to_s:g}"
                lasts = (
                    f"; the video lasts {(v.frame_count - 1) / v.fps:g} s" if v.frame_count else ""
                )
                raise RecordingError(
                    f"{video}: no frames between --from-s {sampling.from_s:g} and {end}{lasts}"
                )
            if progress is not None and len(stamps) < total:
                progress(len(stamps), len(stamps))
            clip_end_s = (stamps[-1] - sampling.start_ns) / NS_PER_S
            manifest = write_manifest(
                tmp,
                kind="video",
                source=video,
                source_text=(
                    f" ({v.width_px}x{v.height_px}, {v.fps:g} fps): grey, resized to "
                    f"{out_size[0]}x{out_size[1]}, resampled to {sampling.fps:g} fps (the source "
                    f"frame nearest each output time), video time {sampling.from_s:g}-"
                    f"{clip_end_s:g} s; stamps are the output times plus {sampling.start_ns} ns."
                ),
                camera=BagStream(BAG_DIR, CAMERA_TOPIC),
                built=built,
                radar=prepared.radar if prepared is not None else None,
                prepared=prepared,
                assumptions=assumptions,
                assumption_text=assumption_text,
                options=options,
                notes=notes,
            )
    finally:
        v.capture.release()
    return result(out_dir, stamps, out_size, built.calibration, manifest, notes)
