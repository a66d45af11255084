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
