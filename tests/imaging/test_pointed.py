"""roi="init": a curve drawn around one object of a dense field gives that object alone."""

import numpy as np
import pytest
import scipy.ndimage

import activecontour as ac
from activecontour import synthetic
from activecontour.imaging.roi import drawn_region, init_neighbourhood

SIZE = (150, 150)
#: (centre, radius): a dense field, each blob placed 2-4 px from one already there and at least
#: 2 px from all; blobs 6 and 9 overlap by 4 px (a touching pair, one object each after the split).
BLOBS = [((75.0, 75.0), 15.0), ((100.3, 90.1), 12.0), ((51.4, 61.6), 10.0), ((26.8, 72.6), 14.0),
         ((52.5, 93.3), 11.0), ((40.5, 121.6), 16.0), ((128.2, 95.5), 13.0), ((21.9, 44.6), 12.0),
         ((88.6, 46.2), 14.0), ((128.2, 116.5), 12.0)]
#: The blobs tried: the centre one (neighbours on several sides), a small one between larger
#: ones, and one of the touching pair.
TARGETS = (0, 2, 9)
PAIR = (6, 9)


@pytest.fixture(scope="module")
def field():
    """The field's image (SNR 4 on a blurred rendering) and each blob's truth."""
    shapes = [synthetic.disk(centre, radius) for centre, radius in BLOBS]
    image, _ = synthetic.render(synthetic.union(*shapes), SIZE, inside=0.6, outside=0.2)
    truths = [synthetic.render(shape, SIZE)[1] for shape in shapes]
    return synthetic.add_noise(image, 0.1, seed=11, blur=1.0), truths


def _drawn(kind, centre, half):
    if kind == "circle":
        return ac.circle(centre, half)
    return ac.rectangle(np.subtract(centre, half), np.add(centre, half))


def test_the_field_is_dense_and_the_pair_touches():
    centres = np.array([centre for centre, _ in BLOBS], float)
    radii = np.array([radius for _, radius in BLOBS])
    gaps = np.hypot(*(centres[:, None] - centres[None]).transpose(2, 0, 1)) - radii[:, None] - radii[None]
    np.fill_diagonal(gaps, np.inf)
    assert gaps.min(axis=1).max() <= 4.0  # every blob has a neighbour within 4 px
    assert np.sort(gaps, axis=None)[0] == pytest.approx(-4.0)  # the pair overlaps, and only it
    assert np.sort(gaps, axis=None)[2] >= 1.9


#: One of the touching pair from a tight curve: the split (objects/split.py) cuts the pair on a
#: straight line about 2 px inside blob 9 (the full run's too: 19 of its pixels go to blob 6),
#: and the pointed object ends at that line (its neighbour is taken out of the domain there), so
#: the box gets two pixels of blob 6 (the circle got Dice 0.941 until the neighbourhood's noise
#: was read on its domain's pixels, not its fill, Problem.auto_mu: 0.964 now).  Strict: passes
#: once the split's line sits at the contact.
SPLIT_LINE_OFF = pytest.mark.xfail(strict=True, reason="the split's line lies ~2 px inside blob 9")


@pytest.mark.parametrize(("target", "factor", "kind"), [
    pytest.param(target, factor, kind,
                 marks=[SPLIT_LINE_OFF] if (target, factor, kind) == (9, 1.1, "box") else [])
    for target in TARGETS for factor in (1.1, 1.8) for kind in ("circle", "box")])
def test_a_curve_around_one_blob_gives_that_blob_alone(field, target, factor, kind):
    image, truths = field
    centre, radius = BLOBS[target]
    init = _drawn(kind, centre, factor * radius)
    res = ac.segment(image, init, roi="init")
    assert synthetic.dice(res.mask, truths[target]) >= 0.95
    others = np.logical_or.reduce([t for k, t in enumerate(truths) if k != target])
    # the blob's own pixels at the edge of its neighbour's truth (the pair's overlap) are its
    # neighbour's too: count only pixels of other blobs that are not the target's
    assert not (res.mask & others & ~truths[target]).any()
    assert res.labels.max() == 1
    # the domain grew only as far as the object needs: it lies in the first neighbourhood of the
    # drawn curve, or for one of the touching pair (cut by that neighbourhood with its partner,
    # which the split tells apart only whole) in the neighbourhood of the curve and the pair
    around = drawn_region(init, image.shape)
    if target in PAIR:
        around |= scipy.ndimage.binary_dilation(truths[PAIR[0]] | truths[PAIR[1]], iterations=2)
    assert not (res.roi & ~init_neighbourhood(around)).any()


def test_without_the_roi_the_drawn_curve_takes_the_neighbours(field):
    image, truths = field
    centre, radius = BLOBS[4]
    res = ac.segment(image, ac.circle(centre, 1.8 * radius))
    assert res.labels.max() > 1  # the complaint: the neighbours come in


def test_a_continued_run_stays_on_the_object(field):
    image, truths = field
    centre, radius = BLOBS[0]
    res = ac.segment(image, ac.circle(centre, 1.8 * radius), roi="init")
    again = ac.segment(image, res, roi=res.roi)  # as the viewer continues a run
    assert synthetic.dice(again.mask, res.mask) >= 0.99
    assert again.labels.max() == 1  # the neighbours, not in its domain, do not come back


def test_a_curve_on_the_background_points_at_nothing():
    image, _ = synthetic.render(synthetic.disk((30, 30), 10.0), (100, 100))
    image = synthetic.add_noise(image, 0.05, seed=2)
    res = ac.segment(image, ac.circle((75.0, 75.0), 8.0), roi="init")
    assert res.labels.max() == 0 and not res.mask.any()


@pytest.fixture(scope="module")
def dim_beside_bright():
    """A dim disk 2 px from a bright one (intensities 0.35 and 0.9 on 0.1, SNR 8 on the dim
    one): on a neighbourhood holding both, two regions with their own constants (6.42) take
    the bright disk for the object and the dim one for background."""
    dim, bright = synthetic.disk((60.0, 48.0), 12.0), synthetic.disk((60.0, 72.0), 10.0)
    size = (120, 120)
    image = (synthetic.render(dim, size, inside=0.25, outside=0.0)[0]
             + synthetic.render(bright, size, inside=0.8, outside=0.0)[0] + 0.1)
    return synthetic.add_noise(image, 0.03, seed=5, blur=1.0), synthetic.render(dim, size)[1], \
        synthetic.render(bright, size)[1]


@pytest.mark.parametrize("factor", [1.1, 1.8])
@pytest.mark.parametrize("kind", ["circle", "box"])
def test_a_bright_neighbour_reaching_into_the_curve_is_not_the_object(dim_beside_bright, kind, factor):
    # the wide curve holds a rim of the bright disk: the object drawn around is still the dim one
    image, dim, bright = dim_beside_bright
    res = ac.segment(image, _drawn(kind, (60.0, 48.0), factor * 12.0), roi="init")
    assert synthetic.dice(res.mask, dim) >= 0.95
    assert not (res.mask & bright).any()
