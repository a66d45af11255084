"""The mask's curves (:func:`activecontour.geometry.raster.mask_to_curves`) against scikit-image."""

import numpy as np
import pytest
import skimage.measure

from activecontour import _kernels


def _find_contours(mask):
    """What :func:`activecontour._kernels.mask_contours` promises: scikit-image's curves of the mask
    padded by False, without the closing vertex, shifted back by the padding."""
    padded = np.pad(mask.astype(float), 1)
    return [c[:-1] - 1.0 for c in skimage.measure.find_contours(padded, 0.5, positive_orientation="high")]


def _masks():
    rng = np.random.default_rng(11)
    for shape in [(1, 1), (3, 29), (29, 3), (17, 40), (33, 64)]:
        yield rng.random(shape) < 0.5
        # long runs of 0s and of 1s (the kernel skips 8 alike squares at once) with specks and
        # holes, at every offset from the row's start
        mask = np.zeros(shape, bool)
        mask[shape[0] // 4: 3 * shape[0] // 4 + 1, 1:] = True
        specks = rng.random(shape) < 0.03
        yield mask ^ specks
        yield ~(mask ^ specks)


@pytest.mark.parametrize("mask", list(_masks()))
def test_mask_contours_are_scikit_images(mask):
    points, offsets = _kernels.mask_contours(np.ascontiguousarray(mask).view(np.uint8))
    points = np.frombuffer(points, dtype=np.float64).reshape(-1, 2)
    offsets = np.frombuffer(offsets, dtype=np.intp)
    curves = [points[a:b] for a, b in zip(offsets[:-1], offsets[1:], strict=True)]
    expected = _find_contours(mask)
    assert len(curves) == len(expected)
    for curve, other in zip(curves, expected, strict=True):
        np.testing.assert_array_equal(curve, other)
