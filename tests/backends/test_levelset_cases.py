"""Local minima, stationarity, scale and the one energy: the level set against derived answers.

The first group are the cases of scikit-image's own ``chan_vese`` and morphsnakes test suites
(``skimage/segmentation/tests/test_chan_vese.py``, ``test_morphsnakes.py``), written here from
their intent and scored in our functional (6.38): gap closing, noise removal, a Gaussian blob
reached from inside and from outside, an exact square with mu = 0, a black image.  Both backends
must pass them.  Every expected mask is built from the scene; where the scene leaves the answer
open (sub-pixel corners), the assertion compares energies by the common evaluator instead.
"""

import inspect

import numpy as np
import pytest
import scipy.ndimage

import activecontour as ac
from activecontour import synthetic as sy
from activecontour.geometry.raster import mask_to_curves, rasterize

BACKENDS = ("levelset", "polygon")
DEFAULT_TOL = inspect.signature(ac.segment).parameters["tol"].default


# ---------------------------------------------------------------------------------------------
# scikit-image's cases


def _gap_scene():
    band = np.zeros((20, 20))
    band[8:15, :] = 1.0  # a 7-pixel band across the image, touching both side borders
    image = band.copy()
    image[:, 6] = 0.0  # cut by a dark one-pixel column
    return image, band.astype(bool)


@pytest.mark.parametrize("backend", BACKENDS)
def test_gap_closing(backend):
    # Closing the gap puts 7 dark pixels inside (fit cost below 7 intensity^2 px); cutting the
    # band there adds two 7-pixel edges, mu * 14 = 9.8 with mu = 0.7: the closed band is lower.
    image, band = _gap_scene()
    mu = 0.7
    result = ac.segment(image, ac.circle((9.5, 9.5), 5.0), backend=backend, mu=mu)
    assert result.success
    assert scipy.ndimage.label(result.mask)[1] == 1  # one region, across the gap
    assert result.mask[9:14, 6].all()  # the gap's inner pixels are inside
    assert sy.dice(result.mask, band) >= 0.98
    # at least as low as the band itself (the pixel boundary of the reference mask)
    closed = ac.chan_vese_energy(image, mask_to_curves(band), mu=mu)
    split = ac.chan_vese_energy(image, mask_to_curves(image > 0.5), mu=mu)
    assert closed < split
    assert result.energy <= closed


@pytest.mark.parametrize("backend", BACKENDS)
def test_noise_pixel_is_removed(backend):
    # a rounded 5 x 5 square and one isolated bright pixel: keeping the pixel costs the length
    # around it (about 4 x 0.7 px, times mu = 0.3) for a fit gain of a fraction of one pixel
    reference = np.zeros((10, 10), dtype=bool)
    reference[1:6, 1:6] = True
    reference[[1, 1, 5, 5], [1, 5, 1, 5]] = False
    image = reference.astype(float)
    image[8, 3] = 1.0
    start = ac.circle((4.5, 4.5), 4.6)  # around the square and the noise pixel
    assert rasterize([start], image.shape)[8, 3]
    result = ac.segment(image, start, backend=backend, mu=0.3)
    assert result.success
    np.testing.assert_array_equal(result.mask, reference)


def _gaussian_blob():
    rr, cc = np.mgrid[-5:6, -5:6]
    return np.exp(-(rr**2 + cc**2) / 10.0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_gaussian_blob_from_inside_and_outside_gives_one_answer(backend):
    # circles of radius 3 (inside the final boundary) and 6 (outside it) end on the same region
    image, mu = _gaussian_blob(), 0.2
    small = ac.segment(image, ac.circle((5.0, 5.0), 3.0), backend=backend, mu=mu)
    large = ac.segment(image, ac.circle((5.0, 5.0), 6.0), backend=backend, mu=mu)
    assert small.success and large.success
    np.testing.assert_array_equal(small.mask, large.mask)
    # both at the minimum of the same radial problem: their energies agree closely
    assert small.energy == pytest.approx(large.energy, rel=0.01)
    # the region is a disk around the peak: its centre inside, the corners outside
    assert small.mask[5, 5] and not small.mask[[0, 0, -1, -1], [0, -1, 0, -1]].any()


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("start", [((4.5, 4.5), 4.0), ((4.0, 4.0), 1.0)], ids=["around", "inside"])
def test_square_without_length_weight_is_found_exactly(backend, start):
    # mu = 0: the minimiser separates the two intensities exactly; every pixel centre of the
    # 3 x 3 square is inside and every other one outside
    image = np.zeros((10, 10))
    image[3:6, 3:6] = 1.0
    result = ac.segment(image, ac.circle(*start), backend=backend, mu=0.0)
    np.testing.assert_array_equal(result.mask, image > 0.5)


@pytest.mark.parametrize("backend", BACKENDS)
def test_black_image_empties_any_start(backend):
    # a constant image: c_in = c_out, the fit terms vanish and only the length remains
    result = ac.segment(np.zeros((11, 11)), ac.circle((5.0, 5.0), 3.0), backend=backend, mu=0.2)
    assert result.status == 3 and not result.mask.any() and result.contours == []


# ---------------------------------------------------------------------------------------------
# "Converged" means stationary


def _scenes():
    disk, disk_truth = sy.render(sy.disk((60.3, 66.7), 30.0), (128, 128), inside=0.8, outside=0.2)
    two, two_truth = sy.render(sy.union(sy.disk((64.0, 40.0), 22.0), sy.disk((64.0, 92.0), 20.0)),
                               (128, 128), inside=0.75, outside=0.25)
    ring, ring_truth = sy.render(sy.annulus((64.0, 64.0), 18.0, 48.0), (128, 128), inside=0.75,
                                 outside=0.25)
    edge, edge_truth = sy.render(sy.disk((10.0, 70.0), 35.0), (128, 128), inside=0.7, outside=0.3)
    return {
        "noisy disk": (sy.add_noise(disk, 0.1, seed=3), ac.circle((63.5, 63.5), 48.0)),
        "two disks": (sy.add_noise(two, 0.1, seed=5), ac.circle((63.5, 65.0), 58.0)),
        "annulus": (sy.add_noise(ring, 0.1, seed=7), ac.circle((63.5, 63.5), 48.0)),
        "disk cut by the border": (sy.add_noise(edge, 0.1, seed=9), ac.circle((40.0, 60.0), 30.0)),
    }


@pytest.mark.parametrize("case", list(_scenes()))
def test_converged_result_is_stationary(case):
    # continuing from a converged result with a 100x smaller tol changes J by < 0.1 % and the
    # mask by < 0.1 % of its area (the definition of converged)
    image, start = _scenes()[case]
    first = ac.segment(image, start, backend="levelset", mu=0.2)
    assert first.success
    again = ac.segment(image, first, backend="levelset", mu=0.2, tol=DEFAULT_TOL / 100)
    assert abs(again.energy - first.energy) <= 1e-3 * abs(first.energy)
    assert np.count_nonzero(again.mask ^ first.mask) <= 1e-3 * first.mask.sum()


def test_a_slow_tail_is_not_converged():
    # astronaut's boundary has many weak stretches (the force hardly outweighs the length term):
    # at steps of dt_min they crept by a fraction of a pixel per iteration, under tol, and a run
    # with tol/100 moved 124 more pixels over 121 iterations (0.12 % of the mask).  The tail's
    # larger steps take that travel before the run calls itself converged.
    import skimage.data

    image = skimage.data.astronaut()
    first = ac.segment(image, backend="levelset")
    assert first.success
    again = ac.segment(image, first, backend="levelset", tol=DEFAULT_TOL / 100)
    assert abs(again.energy - first.energy) <= 1e-3 * abs(first.energy)
    assert np.count_nonzero(again.mask ^ first.mask) < 1e-3 * first.mask.sum()


# ---------------------------------------------------------------------------------------------
# The same scene at every size


def _scaled_scene(size):
    # one scene in units of the image side: a disk off-centre, a start circle 260 px (at 2048)
    # and more away from its boundary; the same contrast and per-pixel noise at every size
    s = size / 256.0
    image, truth = sy.render(sy.disk((115.0 * s, 141.0 * s), 64.0 * s), (size, size),
                             inside=0.7, outside=0.3)
    start = ac.circle((127.5 * s, 127.5 * s), 115.0 * s)
    return sy.add_noise(image, 0.15, seed=11), truth, start


def _scale_dice(sizes, defaults=False):
    """Dice per size, from the scaled start circle (mu = 0.2) or with every default (no init)."""
    out = {}
    for size in sizes:
        image, truth, start = _scaled_scene(size)
        if defaults:
            result = ac.segment(image, backend="levelset")
        else:
            result = ac.segment(image, start, backend="levelset", mu=0.2)
        assert result.success
        out[size] = sy.dice(result.mask, truth)
    return out


@pytest.mark.parametrize("sizes", [(256, 512), pytest.param((256, 512, 1024), marks=pytest.mark.slow)],
                         ids=["256-512", "256-1024"])
@pytest.mark.parametrize("defaults", [False, True], ids=["circle", "defaults"])
def test_same_scene_at_several_sizes_gives_the_same_dice(defaults, sizes):
    # the 1024 px form (3x the CPU of the two smaller sizes together) runs with -m slow
    dice = _scale_dice(sizes, defaults)
    assert max(dice.values()) - min(dice.values()) <= 0.003, dice
    assert min(dice.values()) >= 0.99, dice


@pytest.mark.slow
@pytest.mark.parametrize("defaults", [False, True], ids=["circle", "defaults"])
def test_same_scene_at_2048_px_gives_the_same_dice(defaults):
    dice = _scale_dice((256, 2048), defaults)
    assert abs(dice[2048] - dice[256]) <= 0.003, dice


# ---------------------------------------------------------------------------------------------
# One energy


def test_energy_is_the_common_evaluator_of_the_contours_also_along_the_border():
    # a disk cut by the image border: its contour closes along the border, and both backends
    # pay for that length, so the two agree (the level set used to leave it free)
    image, _ = sy.render(sy.disk((8.0, 64.0), 40.0), (128, 128), inside=0.8, outside=0.2)
    image = sy.add_noise(image, 0.05, seed=2)
    start = ac.circle((30.0, 64.0), 25.0)
    level = ac.segment(image, start, backend="levelset", mu=0.2)
    polygon = ac.segment(image, start, backend="polygon", mu=0.2)
    assert level.energy == pytest.approx(ac.chan_vese_energy(image, level.contours, mu=0.2), rel=1e-12)
    assert level.energies[-1] == level.energy
    assert any(np.any(np.isclose(c[:, 0], -0.5)) for c in level.contours)  # closes on the border
    assert level.energy == pytest.approx(polygon.energy, rel=0.01)
    assert sy.dice(level.mask, polygon.mask) >= 0.99
