"""Coarse-to-fine starts: the reduced problem is the scaled one, and its answer is a good start."""

import numpy as np
import pytest

import activecontour as ac
from activecontour import pyramid, synthetic
from activecontour.energy import ChanVeseParameters
from activecontour.image import ImageModel, normalize_image


def test_reduction_factor_is_the_smallest_power_of_two():
    assert pyramid.reduction_factor((512, 300)) == 1
    assert pyramid.reduction_factor((513, 300)) == 2
    assert pyramid.reduction_factor((300, 8192)) == 16
    assert pyramid.reduction_factor((8193, 10), max_side=1024) == 16
    with pytest.raises(ValueError, match="max_side"):
        pyramid.reduction_factor((100, 100), max_side=0)


def test_coarse_start_lands_near_the_object_and_the_full_run_finishes_from_it():
    size, radius = 1024, 300.0
    center = (0.5 * size + 0.3, 0.47 * size - 0.2)
    image, truth = synthetic.render(synthetic.disk(center, radius), (size, size), inside=0.7, outside=0.3,
                                    supersample=2)
    image = synthetic.add_noise(image, 0.2, seed=4)
    model = ImageModel(normalize_image(image))
    curves = pyramid.coarse_start(model, None, ChanVeseParameters(), max_side=128)  # factor 8
    assert len(curves) == 1
    # within a reduced pixel (8 px) of the true circle everywhere
    distance = np.hypot(curves[0][:, 0] - center[0], curves[0][:, 1] - center[1]) - radius
    assert np.abs(distance).max() < 8.0
    assert synthetic.dice(ac.segment(image, curves, max_num_iter=0).mask, truth) > 0.97
    refined = ac.segment(image, curves)
    direct = ac.segment(image)
    assert synthetic.dice(refined.mask, truth) > 0.995
    # the same minimum as the full-size default start reaches
    assert refined.energy == pytest.approx(direct.energy, rel=1e-4)


def test_coarse_start_keeps_small_images_and_tiny_curves_as_they_are():
    image = np.zeros((64, 64))
    model = ImageModel(normalize_image(image))
    start = ac.circle((32, 32), 10)
    (same,) = pyramid.coarse_start(model, start, ChanVeseParameters())
    np.testing.assert_allclose(same, start)
    big = ImageModel(normalize_image(np.zeros((1100, 1100))))
    tiny = ac.circle((500, 500), 3.0)  # 28 px^2, 7 reduced px^2 at factor 4
    (kept,) = pyramid.coarse_start(big, tiny, ChanVeseParameters(), max_side=300)
    np.testing.assert_allclose(kept, tiny)
