"""The model unit: one quadratic form per region, read by every consumer of the energy.

Each term of (6.38) (mu, omega, lambda_in, lambda_out, fixed constants) is perturbed in turn; the
common evaluator is checked against the functional written out from the region moments, and every
other consumer (the polygon's load, the topological derivative, the level set's force) against the
common evaluator.  Dropping a term from any consumer fails one of these.
"""

import numpy as np
import pytest

from activecontour import _kernels
from activecontour.energy import evaluate, region_moments
from activecontour.geometry import topology
from activecontour.geometry.curve import stack_curves
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel
from activecontour.initial import circle
from activecontour.models import ChanVeseParameters, QuadraticForm
from tests.helpers import central_differences

BASE = {"mu": 0.3, "omega": 0.0, "lambda_in": 1.0, "lambda_out": 1.0, "c_in": 0.8, "c_out": 0.2}
PERTURBED = [
    {},
    {"mu": 0.9},
    {"omega": 0.15},
    {"omega": -0.1},
    {"lambda_in": 2.5},
    {"lambda_out": 0.4},
    {"c_in": 0.65},
    {"c_out": 0.35},
]


def _params(**change):
    return ChanVeseParameters(**{**BASE, **change})


def _model(image):
    return ImageModel(normalize_image(image, normalize=None))


def test_fit_form_is_the_expanded_square():
    rng = np.random.default_rng(0)
    values = rng.random((7, 5, 3))
    weight, constants = rng.random(3), rng.random(3)
    form = QuadraticForm.of_fit(weight, constants, area_weight=0.37)
    expected = 0.37 + np.sum(weight * (values - constants) ** 2, axis=-1)
    np.testing.assert_allclose(form.density(values), expected, rtol=1e-13)
    difference = form - QuadraticForm.of_fit(weight[::-1], constants)
    np.testing.assert_allclose(difference.density(values),
                               expected - np.sum(weight[::-1] * (values - constants) ** 2, axis=-1),
                               rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("change", PERTURBED)
def test_common_evaluator_is_the_functional_of_the_moments(change):
    params = _params(**change)
    image = np.random.default_rng(1).random((30, 40))
    model = _model(image)
    curve = circle((15.0, 18.0), 9.0, 60)
    area, first, second = region_moments(model, [curve])
    total_area, total1, total2 = model.totals
    length = np.sum(np.hypot(*np.diff(np.vstack([curve, curve[:1]]), axis=0).T))
    c_in, c_out = params.c_in[0], params.c_out[0]
    expected = (params.mu * length + params.omega * area
                + params.lambda_in * (second[0] - 2 * c_in * first[0] + c_in**2 * area)
                + params.lambda_out * ((total2 - second)[0] - 2 * c_out * (total1 - first)[0]
                                       + c_out**2 * (total_area - area)))
    points, next_index, _ = stack_curves([curve])
    assert evaluate(model, points, next_index, params).energy == pytest.approx(expected, rel=1e-12)


@pytest.mark.parametrize("change", PERTURBED)
def test_polygon_load_is_the_derivative_of_the_common_evaluator(change):
    params = _params(**change)
    model = _model(np.random.default_rng(2).random((30, 40)))
    points, next_index, _ = stack_curves([circle((15.0, 20.0), 8.0, 30)])
    analytic = evaluate(model, points, next_index, params, gradient=True).load
    numeric = central_differences(lambda p: evaluate(model, p, next_index, params).energy, points)
    np.testing.assert_allclose(numeric, analytic, atol=1e-6 * np.abs(analytic).max())


def _density_by_the_evaluator(params, value):
    """``g_i - g_o`` at intensity ``value``, from the common evaluator: the energy change of moving
    a unit square of a flat patch of that intensity from the outside to the inside, less its
    length term (the constants are fixed, so nothing else changes)."""
    image = np.full((40, 40), 0.5)
    image[10:30, 10:30] = value
    model = _model(image)
    square = np.array([[19.5, 19.5], [20.5, 19.5], [20.5, 20.5], [19.5, 20.5]])
    far = circle((3.0, 3.0), 2.0, 16)
    with_square = evaluate(model, *stack_curves([far, square])[:2], params).energy
    without = evaluate(model, *stack_curves([far])[:2], params).energy
    return with_square - without - params.mu * 4.0


@pytest.mark.parametrize("change", PERTURBED)
def test_nucleation_follows_the_common_evaluator(change):
    params = _params(**change)
    value = 0.75  # near c_in: a patch the inside wants (g < 0 for every parameter set here)
    g = _density_by_the_evaluator(params, value)
    assert g < 0
    image = np.full((60, 60), params.c_out[0])
    image[20:40, 20:40] = value
    values = normalize_image(image, normalize=None)
    inside = np.zeros((60, 60), dtype=bool)
    inside[2:8, 2:8] = True
    radius = 4.0
    form = params.load_form(params.c_in, params.c_out)
    # a new component pays where the disk's mean of g is below -2 mu / radius: with mu set just
    # on either side of that threshold, the site appears exactly when the evaluator says so
    for factor, found in ((0.95, True), (1.05, False)):
        mu = factor * radius * -g / 2.0
        sites = topology.nucleation_sites(values, inside, form, mu, radius)
        assert any(not hole and 20 <= c[0] < 40 and 20 <= c[1] < 40 for c, hole in sites) == found



@pytest.mark.parametrize("change", PERTURBED)
def test_level_set_force_follows_the_common_evaluator(change):
    from activecontour.backends.levelset import DEFAULT_OPTIONS
    from activecontour.backends.levelset.scheme import _Problem

    params = _params(**change)
    value = 0.75
    g = _density_by_the_evaluator(params, value)
    image = np.full((20, 20), 0.5)
    image[5:15, 5:15] = value
    model = _model(image)
    problem = _Problem(model, params, DEFAULT_OPTIONS)
    constants, _ = problem.force(params.c_in, params.c_out)
    centre, border = 10 * 20 + 10, 0 * 20 + 10
    force = problem.force_at(np.array([centre, border]), constants)
    # away from the border (which adds mu per side) the force is g_i - g_o of the pixel
    assert force[0] == pytest.approx(g, rel=1e-9, abs=1e-12)
    assert force[1] == pytest.approx(_density_by_the_evaluator(params, 0.5) + params.mu, rel=1e-9)
    # the smoothed-force step's right-hand side phi - tau f (float32, as phi) holds the same f:
    # with phi = 0 and tau = -1 it is f itself, rounded to float32
    stepped = np.empty((20, 20), dtype=np.float32)
    form = params.load_form(*constants)
    _kernels.force_step(np.zeros((20, 20), dtype=np.float32), model.values, form.constant, form.linear,
                        form.square, params.mu, -1.0, stepped)
    assert stepped[10, 10] == pytest.approx(g, rel=1e-6, abs=1e-7)
    assert stepped[0, 10] == pytest.approx(force[1], rel=1e-6, abs=1e-7)
