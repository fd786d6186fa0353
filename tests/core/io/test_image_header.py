"""An image's size read from its header before decoding (core.io.image_header), and
decode_image refusing a small message that declares a huge image without decoding it."""

from __future__ import annotations

import struct
from typing import Any

import cv2
import numpy as np
import pytest
from bagmaker import build, compressed_image, raw_image, typestore

from core.io import radar_msgs
from core.io.bag import decode_image
from core.io.errors import RecordingError
from core.io.image_header import image_size_px

MONO8 = np.array([[0, 1, 2, 3], [127, 128, 254, 255]], np.uint8)
SIZES = [(64, 48), (1, 1), (1280, 720), (333, 7)]


def encoded(ext: str, width: int, height: int, *flags: int) -> bytes:
    pixels = (np.arange(width * height * 3) % 251).astype(np.uint8).reshape(height, width, 3)
    ok, buf = cv2.imencode(ext, pixels, list(flags))
    assert ok
    return buf.tobytes()


@pytest.mark.parametrize(("width", "height"), SIZES)
def test_png_and_jpeg_headers_give_the_encoded_size(width: int, height: int) -> None:
    assert image_size_px(encoded(".png", width, height)) == (width, height)
    assert image_size_px(encoded(".jpg", width, height)) == (width, height)
    progressive = encoded(".jpg", width, height, cv2.IMWRITE_JPEG_PROGRESSIVE, 1)
    assert image_size_px(progressive) == (width, height)  # SOF2, after the tables


@pytest.mark.parametrize(
    "data",
    [b"", b"GIF89a....", b"\x89PNG\r\n\x1a\n\x00\x00", b"\xff\xd8\xff\xe0\x00\x10JFIF", bytes(50)],
)
def test_other_or_cut_data_has_no_size(data: bytes) -> None:
    assert image_size_px(data) is None
    jpeg = encoded(".jpg", 64, 48)
    sof = jpeg.index(b"\xff\xc0")
    assert image_size_px(jpeg[: sof + 6]) is None  # cut inside the frame header


def png_declaring(width: int, height: int) -> bytes:
    """A small PNG whose IHDR says width x height, 16-bit RGBA (its CRC no longer matches)."""
    small = bytearray(encoded(".png", 64, 48))
    small[16:26] = struct.pack(">IIBB", width, height, 16, 6)
    return bytes(small)


def jpeg_declaring(width: int, height: int) -> bytes:
    jpeg = bytearray(encoded(".jpg", 64, 48))
    sof = jpeg.index(b"\xff\xc0")
    jpeg[sof + 5 : sof + 9] = struct.pack(">HH", height, width)
    return bytes(jpeg)


def _compressed(data: bytes, fmt: str) -> Any:
    return build(typestore("mcap"), radar_msgs.COMPRESSED_IMAGE, compressed_image(0, data, fmt))


@pytest.mark.parametrize(("make", "kind"), [(png_declaring, "PNG"), (jpeg_declaring, "JPEG")])
def test_a_small_frame_declaring_8000x8000_is_refused_without_decoding(
    monkeypatch: pytest.MonkeyPatch, make: Any, kind: str
) -> None:
    bomb = _compressed(make(8000, 8000), kind.lower())
    assert len(bomb.data) < 10_000

    def no_decoding(*args: object) -> None:
        raise AssertionError("decoded")

    monkeypatch.setattr(cv2, "imdecode", no_decoding)
    with pytest.raises(
        RecordingError,
        match=rf"^where: the {kind} image declares 8000x8000 pixels, the calibration says 64x48; "
        "not decoded$",
    ):
        decode_image(bomb, radar_msgs.COMPRESSED_IMAGE, "where", size_px=(64, 48))


def test_the_right_size_still_decodes_and_a_raw_image_is_checked_by_its_fields() -> None:
    good = _compressed(encoded(".png", 64, 48), "png")
    assert decode_image(good, radar_msgs.COMPRESSED_IMAGE, "w", size_px=(64, 48)).shape == (48, 64)
    raw = build(typestore("mcap"), radar_msgs.IMAGE, raw_image(0, MONO8, "mono8"))
    assert decode_image(raw, radar_msgs.IMAGE, "w", size_px=(4, 2)).shape == (2, 4)
    raw.width, raw.height = 8000, 8000
    with pytest.raises(
        RecordingError, match=r"declares 8000x8000 pixels, the calibration says 4x2"
    ):
        decode_image(raw, radar_msgs.IMAGE, "w", size_px=(4, 2))
