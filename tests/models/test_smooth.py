"""fit="smooth": region intensities c_k b(x) with a smooth light field b."""

import numpy as np
import pytest

import activecontour as ac
from activecontour import synthetic
from activecontour.energy import evaluate
from activecontour.geometry.curve import stack_curves
from activecontour.initial import circle
from activecontour.models import ChanVeseParameters
from activecontour.models.smooth import fit_light, light_basis, smooth_light_model
from tests.helpers import central_differences


def _blobs(shape=(160, 200), seed=0, contrast=0.15, amplitude=0.5, noise=0.01):
    """Faint disks (reflectance 1 + contrast) under a gradient and a vignette of the amplitude."""
    rng = np.random.default_rng(seed)
    m, n = shape
    rows, cols = np.mgrid[:m, :n].astype(float)
    truth = np.zeros(shape, dtype=bool)
    for _ in range(12):
        r, c, radius = rng.uniform(15, m - 15), rng.uniform(15, n - 15), rng.uniform(5, 10)
        truth |= (rows - r) ** 2 + (cols - c) ** 2 < radius**2
    vignette = 1 - amplitude * ((rows - m / 2) ** 2 + (cols - n / 2) ** 2) / ((m**2 + n**2) / 4)
    gradient = 1 - amplitude / 2 + amplitude * cols / n
    image = 0.5 * (1 + contrast * truth) * vignette * gradient + rng.normal(0, noise, shape)
    return image, truth


def _dice(mask, truth):
    return 2 * np.sum(mask & truth) / (mask.sum() + truth.sum())


def test_light_update_is_the_least_squares_solve_on_the_pixels():
    rng = np.random.default_rng(1)
    image = rng.random((30, 40, 2))
    classes = rng.integers(0, 3, (30, 40))
    constants = rng.uniform(0.2, 1.0, (3, 2))
    params = ChanVeseParameters(lambda_in=[1.0, 2.0], lambda_out=[0.5, 1.5])
    basis = light_basis(image.shape[:2])
    light, drop = fit_light(image, classes, constants, params)
    # reference: the stacked residuals sqrt(w) (I_c - c_k b) with b = basis . beta, by lstsq
    weights = np.array([[0.5, 1.5], [1.0, 2.0], [1.0, 2.0]]) / 2  # lambda / C
    rows = []
    targets = []
    for ch in range(2):
        scale = np.sqrt(weights[classes, ch]).ravel()
        rows.append((scale * constants[classes, ch].ravel())[:, None] * basis.reshape(len(basis), -1).T)
        targets.append(scale * image[..., ch].ravel())
    design, stacked = np.vstack(rows), np.concatenate(targets)
    beta = np.linalg.lstsq(design, stacked, rcond=None)[0]
    expected = np.tensordot(beta, basis, axes=1)
    assert np.all(expected > 0.1 * expected.mean())  # no clipping in this case
    np.testing.assert_allclose(light, expected / expected.mean(), rtol=1e-9)
    # the drop is the fit term at uniform light (beta = e_0: P_0 P_0 = 1) less the one at b*
    uniform = np.zeros(len(basis))
    uniform[0] = 1.0
    fit_term = [np.sum((stacked - design @ b) ** 2) for b in (uniform, beta)]
    assert drop == pytest.approx(fit_term[0] - fit_term[1], rel=1e-9)
    assert drop > 0


def test_light_drop_from_any_previous_field():
    # from a previous field (in the span, or clipped out of it) the drop is J(previous) - J(b*),
    # b* the unnormalised least-squares field on the pixels
    rng = np.random.default_rng(5)
    image = rng.random((25, 35, 1))
    classes = rng.integers(0, 2, (25, 35))
    constants = np.array([[0.3], [0.8]])
    params = ChanVeseParameters()
    basis = light_basis(image.shape[:2])
    design = constants[classes, 0].ravel()[:, None] * basis.reshape(len(basis), -1).T
    best = np.tensordot(np.linalg.lstsq(design, image[..., 0].ravel(), rcond=None)[0], basis, axes=1)

    def fit_term(b):
        return np.sum((image[..., 0] - constants[classes, 0] * b) ** 2)

    in_span = np.tensordot(rng.uniform(-0.2, 0.2, len(basis)), basis, axes=1) + 1.0
    clipped = np.maximum(np.linspace(-1.0, 2.0, 35)[None, :] * np.ones((25, 1)), 0.1)
    for previous in (in_span, clipped):
        light, drop = fit_light(image, classes, constants, params, previous=previous)
        np.testing.assert_allclose(light, best / best.mean(), rtol=1e-9)
        assert drop == pytest.approx(fit_term(previous) - fit_term(best), rel=1e-9)
        assert drop > 0


def test_an_image_that_is_the_model_costs_only_its_length():
    # I = c b with b bilinear (so its interpolant is exact): both regions' constants are c and the
    # fit terms vanish, whatever the curve, while the constant fit pays for the light
    m, n = 40, 50
    rows, cols = np.mgrid[:m, :n].astype(float)
    light = 0.6 + 0.01 * rows + 0.004 * cols + 0.0002 * rows * cols
    image = (0.7 * light)[..., None]
    curve = circle((18.0, 22.0), 9.0, 40)
    points, next_index, _ = stack_curves([curve])
    length = np.sum(np.hypot(*np.diff(np.vstack([curve, curve[:1]]), axis=0).T))
    model, params = smooth_light_model(image, light, ChanVeseParameters(mu=0.5, omega=0.1))
    result = evaluate(model, points, next_index, params)
    area = result.area
    assert result.c_in[0] == pytest.approx(0.7, rel=1e-10)
    assert result.c_out[0] == pytest.approx(0.7, rel=1e-10)
    assert result.energy == pytest.approx(0.5 * length + 0.1 * area, rel=1e-10)


def test_smooth_load_is_the_derivative_of_its_energy():
    rng = np.random.default_rng(2)
    image = rng.random((30, 40, 1))
    light = 0.5 + rng.random() * np.linspace(0.5, 1.5, 40)[None, :] * np.ones((30, 1))
    model, params = smooth_light_model(image, light, ChanVeseParameters(mu=0.3, omega=0.05))
    points, next_index, _ = stack_curves([circle((15.0, 20.0), 8.0, 24)])
    analytic = evaluate(model, points, next_index, params, gradient=True).load
    numeric = central_differences(lambda p: evaluate(model, p, next_index, params).energy, points)
    np.testing.assert_allclose(numeric, analytic, atol=1e-6 * np.abs(analytic).max())


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_faint_blobs_under_uneven_light(backend):
    image, truth = _blobs()
    constant = ac.segment(image, backend=backend)
    smooth = ac.segment(image, backend=backend, fit="smooth")
    assert _dice(constant.mask, truth) < 0.5  # the light, not the blobs, splits the image
    assert _dice(smooth.mask, truth) > 0.95
    assert smooth.light.shape == truth.shape and smooth.light.mean() == pytest.approx(1.0)
    assert smooth.energy == ac.chan_vese_energy(image, smooth.contours, mu=smooth.mu, light=smooth.light)


def test_smooth_n_regions_on_the_label_field():
    image, truth = _blobs(seed=3)
    res = ac.segment(image, backend="levelset", fit="smooth", n_regions=3)
    assert res.classes.max() == 2
    assert res.energy == ac.chan_vese_energy(image, classes=res.classes, mu=res.mu, light=res.light)


def test_bad_fit_is_refused():
    with pytest.raises(ValueError, match="fit must be one of"):
        ac.segment(np.zeros((10, 10)), fit="linear")


@pytest.mark.parametrize("backend", ["polygon", "levelset"])
def test_smooth_never_ends_above_the_constant_fit(backend):
    # a large noisy disk: the whole image's light is the disk itself, a start that loses it
    rows, cols = np.mgrid[:128, :128]
    truth = np.hypot(rows - 60, cols - 66) < 38
    image = 0.3 + 0.4 * truth + np.random.default_rng(4).normal(0, 0.25, truth.shape)
    constant = ac.segment(image, backend=backend)
    smooth = ac.segment(image, backend=backend, fit="smooth")
    assert smooth.energy <= constant.energy
    assert _dice(constant.mask, truth) > 0.95
    assert _dice(smooth.mask, truth) > 0.95


def test_light_drop_under_pure_noise_is_a_chi_square():
    # uniform light, the region means as constants, Gaussian noise sigma: the drop is sigma^2
    # |P_A r|^2, r the noise less its region means, A the columns c_k(x) P_i(y) P_j(x).  Its
    # mean is sigma^2 (P - tr(P_A P_regions)): at most P - 1 = 9 (the premise of the BIC stop in
    # segment), as the constant field c_k(x) lies in both spans
    rows, cols = np.mgrid[:40, :48]
    classes = (np.hypot(rows - 18, cols - 25) < 12).astype(np.intp)
    sigma = 0.05
    drops = []
    for seed in range(300):
        image = (0.3 + 0.4 * classes + np.random.default_rng(seed).normal(0, sigma, classes.shape))[..., None]
        constants = np.array([[image[classes == k, 0].mean()] for k in (0, 1)])
        drops.append(fit_light(image, classes, constants, ChanVeseParameters())[1] / sigma**2)
    basis = light_basis(classes.shape).reshape(10, -1)
    span = np.linalg.qr((np.array([0.3, 0.7])[classes].ravel() * basis).T)[0]
    regions = np.linalg.qr(np.stack([classes.ravel() == k for k in (0, 1)], axis=1).astype(float))[0]
    expected = len(basis) - np.sum((span.T @ regions) ** 2)
    assert 8.0 <= expected <= 9.0 + 1e-9
    assert abs(np.mean(drops) - expected) < 4 * np.sqrt(2 * 9 / len(drops))


def test_light_within_the_noise_costs_one_constant_fit():
    # a disk under flat light: the light step is not worth its parameters, so the smooth fit is
    # the constant fit (no light, same contours and energy) after the same iterations
    image, truth = synthetic.disk_image(128, (60.0, 70.0), 35.0, inside=0.7, outside=0.3)
    image = synthetic.add_noise(image, 0.1, 3)
    for backend in ("polygon", "levelset"):
        counts = {}
        for fit in ("constant", "smooth"):
            states = []
            res = ac.segment(image, backend=backend, fit=fit, callback=states.append)
            counts[fit] = (len(states), res)
        assert counts["smooth"][0] == counts["constant"][0]
        assert counts["smooth"][1].light is None
        assert counts["smooth"][1].energy == counts["constant"][1].energy


def test_a_light_of_ten_percent_is_found():
    # the same disk under a linear light 0.9 .. 1.1 (normalize=None: the model is I = c_k b, an
    # offset would break it): worth its parameters (it lowers J by ~N c^2 0.1^2 / 3), and the
    # light found is the true one to the noise
    image, truth = synthetic.disk_image(128, (60.0, 70.0), 35.0, inside=0.7, outside=0.3)
    light = np.linspace(0.9, 1.1, 128)[None, :] * np.ones((128, 1))
    image = synthetic.add_noise(image * light, 0.05, 3)
    for backend in ("polygon", "levelset"):
        res = ac.segment(image, backend=backend, fit="smooth", normalize=None)
        assert res.light is not None
        error = res.light - light / light.mean()
        assert np.sqrt(np.mean(error**2)) < 0.01 and np.max(np.abs(error)) < 0.03
        assert _dice(res.mask, truth) > 0.99
