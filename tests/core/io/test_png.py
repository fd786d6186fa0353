"""core.io.png: the drives' own PNG layout decodes to the pixels OpenCV decodes; every other
PNG, and every damaged one, is left to OpenCV (None), which also words the error."""

from __future__ import annotations

import struct
import zlib
from typing import Any

import cv2
import numpy as np
import pytest

from core.io.bag import decode_image
from core.io.errors import RecordingError
from core.io.png import PNG_SIGNATURE, decode_unfiltered_grey
from core.io.radar_msgs import COMPRESSED_IMAGE, typestore
from core.io.writer import PNG_PARAMS, png_image_message, ros_header

RNG = np.random.default_rng(7)
NOISE = RNG.integers(0, 256, (37, 53), dtype=np.uint8)  # odd sides, every byte value likely


def _writer_png(img: np.ndarray) -> bytes:
    ok, png = cv2.imencode(".png", img, PNG_PARAMS)
    assert ok
    return png.tobytes()


def _chunks(png: bytes) -> list[tuple[bytes, bytes]]:
    out, pos = [], len(PNG_SIGNATURE)
    while pos < len(png):
        (length,) = struct.unpack_from(">I", png, pos)
        out.append((png[pos + 4 : pos + 8], png[pos + 8 : pos + 8 + length]))
        pos += 12 + length
    return out


def _png(chunks: list[tuple[bytes, bytes]]) -> bytes:
    """A PNG of these (type, body) chunks, with correct lengths and CRCs."""
    parts = [PNG_SIGNATURE]
    for kind, body in chunks:
        crc = zlib.crc32(kind + body)
        parts.append(struct.pack(">I", len(body)) + kind + body + struct.pack(">I", crc))
    return b"".join(parts)


def _ihdr(width: int, height: int, depth: int = 8, colour: int = 0, interlace: int = 0) -> bytes:
    return struct.pack(">IIBBBBB", width, height, depth, colour, 0, 0, interlace)


def _unfiltered(img: np.ndarray) -> bytes:
    """img's PNG written here, not by libpng: filter byte 0 on each row, one zlib stream."""
    rows = np.hstack([np.zeros((img.shape[0], 1), np.uint8), img])
    return zlib.compress(rows.tobytes())


@pytest.mark.parametrize(
    "img",
    [
        NOISE,
        np.zeros((1, 1), np.uint8),
        np.full((480, 640), 255, np.uint8),
        np.tile(np.arange(256, dtype=np.uint8), (3, 2)),
    ],
    ids=["noise 53x37", "1x1", "white 640x480", "ramps"],
)
def test_the_writers_png_decodes_to_the_image_and_to_what_opencv_decodes(
    img: np.ndarray,
) -> None:
    png = _writer_png(img)
    got = decode_unfiltered_grey(png)
    assert got is not None
    np.testing.assert_array_equal(got, img)
    np.testing.assert_array_equal(got, cv2.imdecode(np.frombuffer(png, np.uint8), -1))


def _frame_message(img: np.ndarray) -> Any:
    """A camera frame's CompressedImage as the writer stores it, read back."""
    store = typestore()
    return store.deserialize_cdr(png_image_message(store, 5, img), COMPRESSED_IMAGE)


def test_a_frame_message_decodes_through_the_fast_path_to_its_image() -> None:
    msg = _frame_message(NOISE)
    assert decode_unfiltered_grey(msg.data.data) is not None
    np.testing.assert_array_equal(decode_image(msg, COMPRESSED_IMAGE, "where"), NOISE)


def test_idat_split_over_several_chunks_is_joined() -> None:
    z = _unfiltered(NOISE)
    thirds = [z[: len(z) // 3], z[len(z) // 3 : 2 * len(z) // 3], z[2 * len(z) // 3 :]]
    png = _png([(b"IHDR", _ihdr(53, 37)), *[(b"IDAT", t) for t in thirds], (b"IEND", b"")])
    got = decode_unfiltered_grey(png)
    assert got is not None
    np.testing.assert_array_equal(got, NOISE)


def _with_filters(img: np.ndarray) -> bytes:
    ok, png = cv2.imencode(".png", img, [cv2.IMWRITE_PNG_FILTER, cv2.IMWRITE_PNG_FILTER_UP])
    assert ok
    return png.tobytes()


def _renamed_chunk(png: bytes, old: bytes, new: bytes) -> bytes:
    return _png([(new if kind == old else kind, body) for kind, body in _chunks(png)])


def _bad_crc(png: bytes) -> bytes:
    at = png.index(b"IDAT") + 8  # into the IDAT body
    return png[:at] + bytes([png[at] ^ 1]) + png[at + 1 :]


OTHER_PNGS = {
    "row filters": _with_filters(NOISE),
    "colour": _writer_png(np.dstack([NOISE] * 3)),
    "16-bit": _writer_png(NOISE.astype(np.uint16) * 257),
    "interlaced": _png([(b"IHDR", _ihdr(53, 37, interlace=1)), (b"IDAT", _unfiltered(NOISE))]),
    "a text chunk": _png(
        [
            (b"IHDR", _ihdr(53, 37)),
            (b"tEXt", b"key\0value"),
            (b"IDAT", _unfiltered(NOISE)),
            (b"IEND", b""),
        ]
    ),
    "no IEND": _png([(b"IHDR", _ihdr(53, 37)), (b"IDAT", _unfiltered(NOISE))]),
    "IDAT before IHDR": _png(
        [(b"IDAT", _unfiltered(NOISE)), (b"IHDR", _ihdr(53, 37)), (b"IEND", b"")]
    ),
    "two IHDR": _renamed_chunk(_writer_png(NOISE), b"IDAT", b"IHDR"),
    "a bad CRC": _bad_crc(_writer_png(NOISE)),
    "truncated": _writer_png(NOISE)[:-20],
    "too little data": _png(
        [(b"IHDR", _ihdr(53, 38)), (b"IDAT", _unfiltered(NOISE)), (b"IEND", b"")]
    ),
    "too much data": _png(
        [(b"IHDR", _ihdr(53, 36)), (b"IDAT", _unfiltered(NOISE)), (b"IEND", b"")]
    ),
    "an IHDR far larger than its data could inflate to": _png(
        [(b"IHDR", _ihdr(2**31 - 1, 2**31 - 1)), (b"IDAT", _unfiltered(NOISE)), (b"IEND", b"")]
    ),
    "zero width": _png(
        [(b"IHDR", _ihdr(0, 37)), (b"IDAT", zlib.compress(bytes(37))), (b"IEND", b"")]
    ),
    "not zlib": _png([(b"IHDR", _ihdr(53, 37)), (b"IDAT", b"garbage"), (b"IEND", b"")]),
    "JPEG": cv2.imencode(".jpg", NOISE)[1].tobytes(),
    "empty": b"",
}


@pytest.mark.parametrize("png", OTHER_PNGS.values(), ids=OTHER_PNGS.keys())
def test_every_other_or_damaged_png_is_left_to_opencv(png: bytes) -> None:
    assert decode_unfiltered_grey(png) is None


def test_a_damaged_frame_is_still_an_error_naming_where() -> None:
    msg = _frame_message(NOISE)
    msg.data = np.frombuffer(_bad_crc(msg.data.tobytes()), np.uint8)
    with pytest.raises(RecordingError, match=r"^where: damaged PNG data: \d+ bytes"):
        decode_image(msg, COMPRESSED_IMAGE, "where")


def test_filtered_and_colour_pngs_still_decode_through_opencv() -> None:
    store = typestore()
    for png in (OTHER_PNGS["row filters"], OTHER_PNGS["colour"]):
        data = np.frombuffer(png, np.uint8)
        msg = store.types[COMPRESSED_IMAGE](
            header=ros_header(store, 0, ""), format="png", data=data
        )
        np.testing.assert_array_equal(decode_image(msg, COMPRESSED_IMAGE, "where"), NOISE)
