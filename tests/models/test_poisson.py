"""noise="poisson": the photon-count fit term, with uniform or smooth light."""

import numpy as np
import pytest
import scipy.optimize

import activecontour as ac
from activecontour import synthetic
from activecontour.energy import evaluate
from activecontour.geometry.curve import stack_curves
from activecontour.initial import circle
from activecontour.models import ChanVeseParameters
from activecontour.models.poisson import fit_poisson_light, poisson_model
from activecontour.models.smooth import light_basis
from tests.helpers import central_differences


def _dice(mask, truth):
    return 2 * np.sum(mask & truth) / (mask.sum() + truth.sum())


def test_light_update_is_the_maximum_likelihood_on_the_pixels():
    # F(beta) = sum_x A b - B ln b with b = basis . beta, minimised directly on the pixels
    rng = np.random.default_rng(1)
    image = rng.uniform(0.05, 1.0, (24, 30, 2))
    classes = rng.integers(0, 3, (24, 30))
    constants = rng.uniform(0.2, 1.0, (3, 2))
    params = ChanVeseParameters(lambda_in=[1.0, 2.0], lambda_out=[0.5, 1.5])
    reference = image.reshape(-1, 2).mean(axis=0)
    scales = 2 * reference * np.array([[0.5, 1.5], [1.0, 2.0], [1.0, 2.0]]) / 2  # 2 r lambda / C
    rate = np.sum(scales * constants, axis=1)[classes].ravel()
    counts = np.einsum("mnc,mnc->mn", image, scales[classes]).ravel()
    flat = light_basis(image.shape[:2]).reshape(10, -1)

    def objective(beta):
        b = beta @ flat
        return np.inf if np.any(b <= 0) else np.sum(rate * b - counts * np.log(b))

    def gradient(beta):
        return flat @ (rate - counts / (beta @ flat))

    start = np.zeros(10)
    start[0] = 1.0
    best = scipy.optimize.minimize(objective, start, jac=gradient, method="BFGS", options={"gtol": 1e-10}).x
    expected = best @ flat
    light, drop = fit_poisson_light(image, classes, constants, params)
    np.testing.assert_allclose(light.ravel(), expected / expected.mean(), rtol=1e-6)
    assert drop == pytest.approx(objective(start) - objective(best), rel=1e-6)
    # the optimum puts the counts' total on the rates: sum A b = sum B
    assert np.sum(rate * expected) == pytest.approx(np.sum(counts), rel=1e-8)


def test_a_flat_image_costs_its_likelihood_and_length():
    # I = a everywhere: both constants are a, g = 2 r (a - a ln a) with r = a, whatever the curve
    a = 0.4
    image = np.full((30, 40, 1), a)
    curve = circle((14.0, 20.0), 8.0, 36)
    points, next_index, _ = stack_curves([curve])
    length = np.sum(np.hypot(*np.diff(np.vstack([curve, curve[:1]]), axis=0).T))
    for light in (None, np.ones((30, 40))):
        model, params = poisson_model(image, light, ChanVeseParameters(mu=0.3, omega=0.05))
        result = evaluate(model, points, next_index, params)
        fit = 2 * a * (a - a * np.log(a)) * 30 * 40
        assert result.c_in[0] == pytest.approx(a, rel=1e-12)
        assert result.energy == pytest.approx(fit + 0.3 * length + 0.05 * result.area, rel=1e-10)


@pytest.mark.parametrize("smooth", [False, True])
def test_poisson_load_is_the_derivative_of_its_energy(smooth):
    rng = np.random.default_rng(2)
    image = rng.uniform(0.05, 1.0, (30, 40, 1))
    light = 0.5 + np.linspace(0.5, 1.5, 40)[None, :] * np.ones((30, 1)) if smooth else None
    model, params = poisson_model(image, light, ChanVeseParameters(mu=0.3, omega=0.05))
    points, next_index, _ = stack_curves([circle((15.0, 20.0), 8.0, 24)])
    analytic = evaluate(model, points, next_index, params, gradient=True).load
    numeric = central_differences(lambda p: evaluate(model, p, next_index, params).energy, points)
    np.testing.assert_allclose(numeric, analytic, atol=1e-6 * np.abs(analytic).max())


def _bright_and_dim(seed=0, counts=200):
    """Four bright (1.0) and two dim (0.45) disks on a background of 0.1, Poisson counts at
    ``counts`` per unit intensity, scaled into [0, 1] (so the counts' zero is the frame's)."""
    rows, cols = np.mgrid[:160, :160]
    truth = np.zeros((160, 160), dtype=bool)
    level = np.full((160, 160), 0.1)
    for k, (r, c) in enumerate([(35, 35), (35, 120), (125, 35), (125, 120), (80, 40), (80, 120)]):
        disk = np.hypot(rows - r, cols - c) < 14
        truth |= disk
        level[disk] = 1.0 if k < 4 else 0.45
    image = np.random.default_rng(seed).poisson(counts * level).astype(float)
    return image / image.max(), truth


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_dim_objects_above_the_logarithmic_mean_are_kept(backend):
    # (6.38) splits at the arithmetic midpoint: ~0.55 with the bright disks alone inside, ~0.46
    # with all six; both above the dim disks.  The Poisson split is the logarithmic mean: ~0.39
    # and ~0.34 (of the same scale), both below them.
    image, truth = _bright_and_dim()
    scale = 0.1 / np.median(image[~truth])  # the background's level in the image's units
    gaussian = ac.segment(image, backend=backend, normalize=None)
    poisson = ac.segment(image, backend=backend, normalize=None, noise="poisson")
    assert _dice(gaussian.mask, truth) < 0.85  # the dim disks are lost
    assert _dice(poisson.mask, truth) > 0.98
    c_out, c_in = float(poisson.c_out) * scale, float(poisson.c_in) * scale
    assert c_out < (c_in - c_out) / np.log(c_in / c_out) < 0.45 < (float(gaussian.c_in) * scale + 0.1) / 2


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_faint_blobs_under_uneven_light_with_counts(backend):
    from tests.models.test_smooth import _blobs

    image, truth = _blobs()
    res = ac.segment(image, backend=backend, fit="smooth", noise="poisson")
    assert _dice(res.mask, truth) > 0.95
    assert res.light is not None and res.light.mean() == pytest.approx(1.0)
    assert res.energy == ac.chan_vese_energy(image, res.contours, mu=res.mu, light=res.light, noise="poisson")


def test_flat_light_is_the_constant_poisson_fit():
    image, truth = synthetic.disk_image(128, (60.0, 70.0), 35.0, inside=0.7, outside=0.3)
    image = np.random.default_rng(3).poisson(100 * image) / 100
    constant = ac.segment(image, noise="poisson")
    smooth = ac.segment(image, fit="smooth", noise="poisson")
    assert smooth.light is None and smooth.energy == constant.energy
    assert _dice(constant.mask, truth) > 0.98


def test_bad_noise_is_refused():
    with pytest.raises(ValueError, match="noise must be one of"):
        ac.segment(np.zeros((10, 10)), noise="laplace")
    with pytest.raises(ValueError, match="noise must be one of"):
        ac.chan_vese_energy(np.zeros((10, 10)), [circle((5.0, 5.0), 2.0)], noise="laplace")
