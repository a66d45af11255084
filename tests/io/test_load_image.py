"""load_image: every file it cannot read gets one true line (empty, text, damaged, unknown)."""

import cv2
import numpy as np
import pytest

from activecontour import load_image


@pytest.mark.parametrize(
    "name, content, reason",
    [
        ("empty.png", b"", "the file is empty (0 bytes)"),
        ("notes.png", b"not an image\n", "the file holds text, not an image"),
        ("notes.txt", "résumé, 12 lines\n".encode() * 400, "the file holds text, not an image"),
        ("noise.tif", bytes(range(256)) * 8,
         "not an image in a format the readers know (PNG, JPEG, TIFF, BMP, GIF, WebP, ...)"),
    ],
    ids=["empty", "short-text", "long-text", "binary"],
)
def test_unreadable_files_say_what_they_are(tmp_path, name, content, reason):
    path = tmp_path / name
    path.write_bytes(content)
    with pytest.raises(ValueError) as caught:
        load_image(path)
    message = str(caught.value)
    assert message == f"cannot read image {str(path)!r}: {reason}"


def test_a_truncated_png_is_called_damaged(tmp_path):
    image = np.random.default_rng(0).integers(0, 255, (64, 64), dtype=np.uint8)
    ok, encoded = cv2.imencode(".png", image)
    path = tmp_path / "cut.png"
    path.write_bytes(encoded.tobytes()[:200])
    with pytest.raises(ValueError, match=r"cut\.png'?: the PNG data is damaged or truncated") as caught:
        load_image(path)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize("suffix", [".png", ".tif", ".jpg", ".bmp"])
def test_the_size_limit_is_checked_from_the_header_before_decoding(tmp_path, monkeypatch, suffix):
    import activecontour.io.images as image_module
    from activecontour.io.images import SizeLimitError

    path = tmp_path / f"big{suffix}"
    cv2.imwrite(str(path), np.zeros((300, 200), np.uint8))
    assert load_image(path, max_pixels=60_000).shape == (300, 200)  # the limit itself is allowed

    def no_decoding(_path):
        raise AssertionError("decoded an image over the limit")

    monkeypatch.setattr(image_module, "_read_opencv", no_decoding)
    with pytest.raises(SizeLimitError, match=r"300 x 200 = 60,000 pixels, more than the limit of 59,999"):
        load_image(path, max_pixels=59_999)


def test_the_default_limit_refuses_a_small_file_declaring_a_huge_image(tmp_path):
    import struct
    import zlib

    from activecontour.io.images import MAX_PIXELS, SizeLimitError

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    path = tmp_path / "bomb.png"  # 20000 x 20000 gray declared, a few bytes of data
    header = struct.pack(">IIBBBBB", 20000, 20000, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                     + chunk(b"IDAT", zlib.compress(bytes(20001))) + chunk(b"IEND", b""))
    assert 20000 * 20000 > MAX_PIXELS
    with pytest.raises(SizeLimitError, match="20000 x 20000"):
        load_image(path)
