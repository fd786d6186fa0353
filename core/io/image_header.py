"""An image's size from its header, before anything is decoded.

    image_size_px(png_or_jpeg_bytes)   # (width_px, height_px), None when no header says it
    file_image_size_px(path)           # the same from an image file's first bytes

A frame of 500 KB may declare 8000x8000 16-bit RGBA pixels: decoding it first costs 1.3 GB
before its size can be refused (and at OpenCV's pixel cap about 20 GB). The size is read here:
PNG from its IHDR chunk (the first chunk, by the PNG specification, section 5.6), JPEG from
its first start-of-frame marker (SOF0-SOF15 but DHT, JPG and DAC; ITU T.81, B.2.2).
"""

from __future__ import annotations

from pathlib import Path

from core.io.png import PNG_SIGNATURE

JPEG_MAGIC = b"\xff\xd8\xff"
_IHDR_END = 24  # signature (8), chunk length (4), "IHDR" (4), width (4), height (4)
_NOT_SOF = {0xC4, 0xC8, 0xCC}  # DHT, JPG (reserved), DAC share the SOF range
_STANDALONE = {0x01, *range(0xD0, 0xD9)}  # TEM, RSTn, SOI, EOI: markers without a length
# a JPEG's frame header follows its APPn and table segments (each at most 64 KB): what of a
# file is read to find it
HEAD_BYTES = 1 << 20
# the largest image an import decodes (8192 x 8192): 64 MB grey, 192 MB in colour
MAX_IMAGE_PIXELS = 1 << 26


def image_size_px(data: bytes | memoryview) -> tuple[int, int] | None:
    """(width_px, height_px) that the PNG or JPEG `data` declares; None for other data or
    a header too damaged to say."""
    head = bytes(data[:8])
    if head.startswith(PNG_SIGNATURE):
        return _png_size(bytes(data[:_IHDR_END]))
    if head.startswith(JPEG_MAGIC):
        return _jpeg_size(data)
    return None


def file_image_size_px(path: Path) -> tuple[int, int] | None:
    """`image_size_px` of the first HEAD_BYTES of the file at `path` (OSError when it cannot
    be read)."""
    with path.open("rb") as f:
        return image_size_px(f.read(HEAD_BYTES))


def _png_size(head: bytes) -> tuple[int, int] | None:
    if len(head) < _IHDR_END or head[12:16] != b"IHDR":
        return None
    return int.from_bytes(head[16:20], "big"), int.from_bytes(head[20:24], "big")


def _jpeg_size(data: bytes | memoryview) -> tuple[int, int] | None:
    at = 2  # after SOI
    while at + 4 <= len(data):
        if data[at] != 0xFF:
            return None
        marker = data[at + 1]
        if marker == 0xFF:  # fill byte
            at += 1
            continue
        if marker in _STANDALONE:
            at += 2
            continue
        length = int.from_bytes(bytes(data[at + 2 : at + 4]), "big")
        if 0xC0 <= marker <= 0xCF and marker not in _NOT_SOF:
            if at + 9 > len(data) or length < 7:
                return None
            height = int.from_bytes(bytes(data[at + 5 : at + 7]), "big")
            width = int.from_bytes(bytes(data[at + 7 : at + 9]), "big")
            return width, height
        if marker == 0xDA or length < 2:  # start of scan before any frame header
            return None
        at += 2 + length
    return None
