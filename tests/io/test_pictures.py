"""Pictures (overlays, contact sheets) as files: what is written decodes to the pixels drawn, and a
large picture that would not compress is stored rather than compressed."""

import struct

import cv2
import numpy as np
import pytest

from activecontour.io.pictures import STORE_MIN_PIXELS, display_rgb, encode_picture, render_overlay


def first_deflate_block_type(png):
    """BTYPE of the first deflate block of a PNG's image data (RFC 1951: 0 stored, 1 fixed Huffman,
    2 dynamic Huffman), read from its IDAT chunks (after the zlib stream's two header bytes)."""
    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    data, at = b"", 8
    while at < len(png):
        length, kind = struct.unpack(">I4s", png[at:at + 8])
        if kind == b"IDAT":
            data += png[at + 8:at + 8 + length]
        at += 12 + length
    return (data[2] >> 1) & 3


def decoded(png):
    return cv2.imdecode(np.frombuffer(png, np.uint8), cv2.IMREAD_UNCHANGED)[:, :, ::-1]


def large_side():
    return int(np.ceil(np.sqrt(STORE_MIN_PIXELS)))


def test_a_large_noisy_picture_is_stored_and_decodes_to_its_pixels():
    side = large_side()
    gray = np.random.default_rng(0).integers(0, 256, (side, side + 3), dtype=np.uint8)
    rgb = np.repeat(gray[:, :, None], 3, axis=2)  # an overlay's background: compresses by ~1 %
    png = encode_picture("p.png", rgb)
    assert first_deflate_block_type(png) == 0
    assert np.array_equal(decoded(png), rgb)


def test_a_large_picture_that_compresses_is_compressed():
    side = large_side()
    ramp = np.add.outer(np.arange(side), np.arange(side)) // 8 % 256
    rgb = np.stack([ramp, ramp, 255 - ramp], axis=2).astype(np.uint8)
    png = encode_picture("p.png", rgb)
    assert first_deflate_block_type(png) != 0 and len(png) < rgb.nbytes / 10
    assert np.array_equal(decoded(png), rgb)


def test_a_small_picture_is_compressed_as_opencv_does_by_default():
    rgb = np.random.default_rng(1).integers(0, 256, (64, 48, 3), dtype=np.uint8)
    png = encode_picture("p.png", rgb)
    assert png == cv2.imencode(".png", np.ascontiguousarray(rgb[:, :, ::-1]))[1].tobytes()


@pytest.mark.parametrize("channels", [None, 3])
def test_a_shrunk_overlay_is_the_display_image_shrunk(channels):
    """A gray image is shrunk before it becomes RGB: the same pixels as the RGB image shrunk."""
    rng = np.random.default_rng(2)
    image = rng.random((301, 203) if channels is None else (301, 203, channels))
    rgb = render_overlay(image, [], max_side=100)
    assert np.array_equal(rgb, cv2.resize(display_rgb(image), (67, 100), interpolation=cv2.INTER_AREA))
