"""A result is a faithful start and "converged" is stationary (DESIGN.md, "Invariants every result
obeys"), on both backends, on crops of scikit-image's pictures.

The thresholds are DESIGN's: the same backend restarts at its result's energy to a relative 1e-7
with the same mask; the other backend keeps the mask within 0.1 % of its area; a 100x smaller tol
changes J and the mask by less than 0.1 %.  (benchmarks/restart.py runs the same checks on the 25
sample images.)
"""

import warnings

import numpy as np
import pytest
import skimage.data

import activecontour as ac
from activecontour.settings import Settings

BACKENDS = ("polygon", "levelset")
DEFAULT_TOL = Settings().tol


def _crops():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return {
            # a binary image: the bilinear energy moves by percents with a tenth of a pixel
            "binary_blobs": skimage.data.binary_blobs(length=128, rng=1),
            "coins": skimage.data.coins()[180:300, 60:220],
            "camera": skimage.data.camera()[60:200, 180:330],
        }


@pytest.fixture(scope="module")
def results():
    return {(name, backend): (image, ac.segment(image, backend=backend))
            for name, image in _crops().items() for backend in BACKENDS}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", list(_crops()))
def test_a_result_restarts_where_it_ended(results, name, backend):
    image, first = results[name, backend]
    again = ac.segment(image, init=first, backend=backend, max_num_iter=0)
    assert again.energy == pytest.approx(first.energy, rel=1e-7, abs=0)
    assert np.array_equal(again.mask, first.mask)
    # with iterations, the first iterate is the result itself
    more = ac.segment(image, init=first, backend=backend, max_num_iter=3)
    assert more.energies[0] == pytest.approx(first.energy, rel=1e-7, abs=0)
    assert more.energy <= more.energies[0]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", list(_crops()))
def test_the_other_backends_result_keeps_its_mask(results, name, backend):
    other = BACKENDS[1 - BACKENDS.index(backend)]
    image, first = results[name, other]
    again = ac.segment(image, init=first, backend=backend, max_num_iter=0)
    assert np.count_nonzero(again.mask != first.mask) <= 1e-3 * first.mask.sum()


#: Where DESIGN's stationarity does not hold yet (issue 22, item 2, open): continuing from the polygon's
#: result on binary_blobs with tol/100 lowers J by 0.11 % (151.24 -> 151.07) in 500 iterations, mask
#: unchanged.  Strict: the day it holds, this mark must go.
_NOT_YET_STATIONARY = {("binary_blobs", "polygon")}


@pytest.mark.parametrize(("name", "backend"), [
    pytest.param(name, backend, id=f"{name}-{backend}", marks=pytest.mark.xfail(
        strict=True, reason="issue 22 item 2: not yet stationary")) if (name, backend) in _NOT_YET_STATIONARY
    else pytest.param(name, backend, id=f"{name}-{backend}") for name in _crops() for backend in BACKENDS])
def test_a_converged_result_is_stationary(results, name, backend):
    image, first = results[name, backend]
    assert first.success, first.message
    again = ac.segment(image, init=first, backend=backend, tol=DEFAULT_TOL / 100)
    assert abs(again.energy - first.energy) < 1e-3 * abs(first.energy)
    assert np.count_nonzero(again.mask != first.mask) < 1e-3 * first.mask.sum()
    assert again.energy <= first.energy * (1 + 1e-7)  # a continued run never ends above its start
