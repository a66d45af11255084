"""min_size: pieces the length term would remove are not objects (issue 23, item 4)."""

import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.evaluate import chan_vese_energy
from activecontour.initial import DEFAULT_INIT_MIN_AREA

DOTS = [(12, 12), (12, 84), (84, 12), (84, 84)]


@pytest.fixture(scope="module")
def dotted():
    """A disk of radius 20 at 1 on 0 and four dots of radius 2 at 4, noise 0.4: the dots pay
    for their length (15 of fit a pixel, in the input's units, against 2 pi r mu / (pi r^2) =
    2 mu / r), so (6.38) keeps them, but they are smaller than a disk of the disk's own contrast
    that the length term keeps."""
    shapes = [synthetic.disk((48, 48), 20.0)] + [synthetic.disk(c, 2.0) for c in DOTS]
    image, _ = synthetic.render(synthetic.union(*shapes[:1]), (97, 97))
    for shape in shapes[1:]:
        image += 4.0 * synthetic.render(shape, (97, 97))[0]
    return synthetic.add_noise(image, 0.4, seed=5), synthetic.render(shapes[0], (97, 97))[1]


def _break_even_area(mu, contrast):
    """pi r^2 at the r where 2 pi r mu = pi r^2 contrast, at least the default start's floor."""
    return max(DEFAULT_INIT_MIN_AREA, np.pi * (2 * mu / contrast) ** 2)


def test_the_default_is_the_area_the_length_term_removes(dotted):
    image, truth = dotted
    res = ac.segment(image)
    assert res.min_size == pytest.approx(_break_even_area(res.mu, (res.c_in - res.c_out) ** 2), rel=1e-12)
    dots = ac.segment(image, min_size=0).objects["area"]
    assert np.sort(dots)[-2] < res.min_size < np.pi * 20.0**2  # between the dots and the disk


def test_specks_are_left_out_of_the_objects_not_out_of_the_contours(dotted):
    image, truth = dotted
    res = ac.segment(image)
    every = ac.segment(image, min_size=0)
    assert every.min_size == 0.0
    # the dots are in the partition (6.38) was minimised over ...
    for centre in DOTS:
        assert res.mask[centre] and every.labels[centre] > 0
    assert every.labels.max() == 5
    # ... but not objects by default: one object, the disk
    assert res.labels.max() == 1 and len(res.objects["area"]) == 1
    assert synthetic.dice(res.labels > 0, truth) > 0.97
    assert all(res.labels[centre] == 0 for centre in DOTS)
    # the contours, the mask and the energy are the partition's, whatever min_size
    np.testing.assert_array_equal(res.mask, every.mask)
    assert res.energy == every.energy
    assert res.energy == pytest.approx(chan_vese_energy(image, res.contours, mu=res.mu), rel=1e-9)


def test_a_given_min_size_is_used(dotted):
    image, _ = dotted
    res = ac.segment(image, min_size=2000.0)  # above the disk's pi 20^2 = 1257
    assert res.min_size == 2000.0 and res.labels.max() == 0 and res.mask.any()


def test_more_regions_take_the_weakest_contrast():
    """Two disks of 0.5 and 1 on 0: the weakest interface is 0.5 apart, whichever pair it is."""
    shapes = [synthetic.disk((30, 30), 15.0), synthetic.disk((30, 75), 15.0)]
    image = synthetic.render(shapes[0], (60, 105))[0] * 0.5 + synthetic.render(shapes[1], (60, 105))[0]
    res = ac.segment(synthetic.add_noise(image, 0.08, seed=1), n_regions=3)
    constants = np.sort(res.constants.ravel())
    assert res.min_size == pytest.approx(_break_even_area(res.mu, np.min(np.diff(constants)) ** 2), rel=1e-12)
    assert np.all(res.objects["area"] >= res.min_size)
    # both disks are objects (the rest: slivers of the middle class along the bright disk's
    # blurred rim, of a few pixels more than the floor)
    assert np.sum(np.abs(res.objects["area"] - np.pi * 15.0**2) < 0.03 * np.pi * 15.0**2) == 2


@pytest.mark.parametrize("value, error, match", [
    (-1.0, ValueError, "min_size must be a finite number >= 0 or 'auto'"),
    ("big", TypeError, "min_size must be a finite number >= 0 or 'auto'"),
    (np.inf, ValueError, "min_size must be"),
])
def test_a_bad_min_size_is_named(value, error, match):
    with pytest.raises(error, match=match):
        ac.segment(np.eye(8), min_size=value)


def test_a_run_stopped_before_a_stationary_point_keeps_its_pieces(dotted):
    """With no iteration the constants of a start straddling the disk are nearly equal, so the
    break-even area of (6.38) would exceed the image; the rule holds only at a stationary point."""
    image, _ = dotted
    start = ac.circle((30, 48), 20.0)  # half on the disk, half off it
    res = ac.segment(image, start, max_num_iter=0)
    assert not res.success and res.min_size == DEFAULT_INIT_MIN_AREA
    assert res.labels.max() == 1 and np.count_nonzero(res.labels) == np.count_nonzero(res.mask)
