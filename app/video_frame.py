"""One frame of an exported video: the inspector's camera picture (A and B side by side when
comparing) over a banner that says what the frame is and what its colours mean.

The picture is `app.view.camera_picture`'s, so a video shows what the inspector shows. The
banner goes under the picture, never over the detections: a title line (the recording, the
time from the drive's first frame, the frame's index, the parameter-set hash of each set,
`core.params.params_hash`) and a legend in plain words, one mark per colour of the layers
switched on, drawn with the `app.overlays` / `app.draw` colours themselves. The legend flows
over as many lines as the width needs.

Everything here is pure: no engine, no file, no encoder; `app.video_export` writes the
frames.

Images: RGB (H, W, 3) uint8 indexed [row, col], as in `app.draw`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from app import draw
from app.legend import MARGIN_PX, MIN_WIDTH_PX, banner_strip, legend_strip
from app.state import Layers, ViewState
from app.view import FrameSource, camera_picture, seconds_from_start, side_by_side
from core.engine import FrameResult
from core.io.frame import FrameInput

TITLE_FONT_SCALE = 0.5
TITLE_HEIGHT_PX = 26
SEPARATOR = "  |  "  # the font's space is narrow: with one each side it reads "a |b"


@dataclass(frozen=True)
class Stamp:
    """What the banner's title says of a frame: the recording's name, the frame's index
    (of the drive, `frame_count` frames), its time from the drive's first frame in seconds,
    and the parameter-set hash of A, or of A and B when comparing."""

    recording: str
    frame: int
    frame_count: int
    t_s: float
    params_hashes: tuple[str, ...]

    def __post_init__(self) -> None:
        if len(self.params_hashes) not in (1, 2):
            raise ValueError(
                f"params_hashes: expected the hash of set A, or of A and B, "
                f"got {len(self.params_hashes)}: {self.params_hashes!r}"
            )


def stamp_of(drive: FrameSource, frame: FrameInput, params_hashes: Sequence[str]) -> Stamp:
    """The stamp of `frame` of `drive`: its time counted from the drive's first frame."""
    t_s = seconds_from_start(drive, frame.t_ns)
    return Stamp(drive.name, frame.index, len(drive), t_s, tuple(params_hashes))


def title_text(stamp: Stamp) -> str:
    """The banner's first line, e.g. "highway  |  t 9.00 s  |  frame 90 / 149  |  params
    3f2a9c01de"; comparing, its end reads "A (left) params 3f2a9c01de  |  B (right) params
    77c0e1b2a4"."""
    parts = [
        stamp.recording,
        f"t {stamp.t_s:.2f} s",
        f"frame {stamp.frame} / {stamp.frame_count - 1}",
    ]
    if len(stamp.params_hashes) == 1:
        parts.append(f"params {stamp.params_hashes[0]}")
    else:
        a, b = stamp.params_hashes
        parts += [f"A (left) params {a}", f"B (right) params {b}"]
    return SEPARATOR.join(parts)


def title_strip(text: str, width_px: int) -> draw.RgbImage:
    """A (TITLE_HEIGHT_PX, width_px, 3) strip holding `text` in white."""
    out = banner_strip(TITLE_HEIGHT_PX, width_px)
    (_, h), _ = cv2.getTextSize(text, draw.FONT, TITLE_FONT_SCALE, 1)
    baseline_row = (TITLE_HEIGHT_PX + h) // 2
    cv2.putText(
        out,
        text,
        (MARGIN_PX, baseline_row),
        draw.FONT,
        TITLE_FONT_SCALE,
        draw.TEXT_COLOUR,
        1,
        cv2.LINE_AA,
    )
    return out


def with_banner(picture: draw.RgbImage, stamp: Stamp, layers: Layers) -> draw.RgbImage:
    """`picture` over its banner: the title of `stamp` and the legend of `layers`."""
    draw.require_rgb_image("picture", picture)
    width = picture.shape[1]
    title = title_strip(title_text(stamp), width)
    return np.ascontiguousarray(np.vstack([picture, title, legend_strip(layers, width)]))


def video_frame(
    drive: FrameSource,
    layers: Layers,
    frame: FrameInput,
    results: Sequence[FrameResult],
    params_hashes: Sequence[str],
    width_px: int | None = None,
) -> draw.RgbImage:
    """Frame `frame` of `drive` as a video shows it: `app.view.camera_picture` with
    `layers` of the engine's result under set A (`results[0]`), and under set B beside it
    (`results[1]`, `app.view.side_by_side`) when comparing, scaled to `width_px` (area
    interpolation; None: as drawn), over the banner (`with_banner`) of that width.

    params_hashes: `core.params.params_hash` of A, and of B, one per result. ValueError
    when a result is of another frame, or results and hashes are not 1 or 2 of each.
    Returns (H + banner, W, 3) uint8 RGB, W the camera's width (2 W + `app.view.AB_GAP_PX`
    comparing) or `width_px`.
    """
    if len(results) not in (1, 2) or len(params_hashes) != len(results):
        raise ValueError(
            f"results, params_hashes: expected one of each for A, or two for A and B, got "
            f"{len(results)} results and {len(params_hashes)} hashes"
        )
    wrong = [r.index for r in results if r.index != frame.index]
    if wrong:
        raise ValueError(f"results: expected results of frame {frame.index}, got frame(s) {wrong}")
    state = ViewState(frame=frame.index, layers=layers)
    pictures = [camera_picture(drive, state, r, frame) for r in results]
    picture = pictures[0] if len(pictures) == 1 else side_by_side(pictures[0], pictures[1])
    if width_px is not None and width_px != picture.shape[1]:
        if width_px < MIN_WIDTH_PX:
            raise ValueError(f"width_px: expected at least {MIN_WIDTH_PX} px, got {width_px}")
        picture = draw.scaled_to_width(picture, width_px)
    return with_banner(picture, stamp_of(drive, frame, params_hashes), layers)
