"""Images made a strip of rows at a time are exactly the whole image's."""

import numpy as np
import pytest

from activecontour.imaging.strips import STRIP_ROWS, block_means, block_means_of, blurred, blurred_rows


@pytest.mark.parametrize("channels", [1, 3])
@pytest.mark.parametrize("blur", [1.0, 2.5])
def test_rows_made_by_strips_are_the_rows_of_the_whole_images_blur(channels, blur):
    """The default start blurs an image a strip of rows at a time (with its kernel's reach
    around): every way of asking for rows gives exactly those of the whole image's blur, of the
    image and of its 2 x 2 block means."""
    rng = np.random.default_rng(channels)
    values = rng.random((2 * STRIP_ROWS + 75, 97, channels))
    keys = [slice(None), slice(3, 40), slice(None, None, 7), slice(1, None, 64),
            np.array([0, 1, 2, 200, 201, 290, 600]), (slice(None, None, 5), slice(None, None, 3))]
    for rows, whole in ((blurred_rows(values, blur), blurred(values, blur)),
                        (blurred_rows(block_means(values), blur), blurred(block_means_of(values), blur))):
        assert rows.shape == whole.shape
        for key in keys:
            if isinstance(key, np.ndarray):
                key = key[key < whole.shape[0]]
            assert np.array_equal(rows[key], whole[key])


def test_kept_rows_are_served_as_the_images_and_no_others():
    from activecontour.imaging.strips import Kept

    image = np.arange(40.0).reshape(10, 4, 1)
    kept = Kept(image, np.array([0, 1, 4, 5, 8]))
    assert kept.shape == image.shape
    assert np.array_equal(kept[::4], image[::4])
    assert np.array_equal(kept[np.array([1, 5]), ::2], image[np.array([1, 5]), ::2])
    with pytest.raises(IndexError):
        kept[::3]  # row 3 was not kept
