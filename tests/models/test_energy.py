"""The Chan-Vese functional (6.38), optimal constants (6.42) and shape derivative (6.41)."""

import numpy as np
import pytest
import skimage.measure

from activecontour import chan_vese_energy
from activecontour.energy import evaluate, region_moments
from activecontour.geometry.curve import stack_curves
from activecontour.imaging.normalize import normalize_image
from activecontour.imaging.tables import ImageModel
from activecontour.initial import circle
from activecontour.models import ChanVeseParameters
from tests.geometry.test_curve import random_smooth_curve
from tests.helpers import central_differences


def model_of(image, color="gray"):
    return ImageModel(normalize_image(image, color=color, normalize=None))


def test_domain_totals_are_the_pixel_sums():
    # Bilinear between centres plus a constant half-pixel margin integrates each pixel value with
    # weight exactly 1 (trapezoid rule + half-cells), so int_D I is the pixel sum.
    image = np.random.default_rng(0).random((17, 23))
    area, first, _ = model_of(image).totals
    assert area == 17 * 23
    assert first[0] == pytest.approx(image.sum(), rel=1e-13)


def test_moments_of_linear_and_bilinear_images_are_exact():
    rows, cols = np.mgrid[0:30, 0:40].astype(float)
    # the bilinear interpolant reproduces a + b r + d c + e r c exactly between pixel centres
    a, b, d, e = 0.2, 0.01, -0.003, 0.0002
    image = a + b * rows + d * cols + e * rows * cols
    r0, r1, c0, c1 = 3.25, 21.5, 4.75, 33.0
    box = np.array([[r0, c0], [r1, c0], [r1, c1], [r0, c1]])
    area, first, second = region_moments(model_of(image), [box])
    assert area == pytest.approx((r1 - r0) * (c1 - c0))

    def integral(f_r, f_c):  # int over the box of f_r(r) f_c(c), f given by antiderivatives
        return (f_r(r1) - f_r(r0)) * (f_c(c1) - f_c(c0))

    one, lin, sq = (lambda x: x), (lambda x: x**2 / 2), (lambda x: x**3 / 3)
    expected1 = a * area + b * integral(lin, one) + d * integral(one, lin) + e * integral(lin, lin)
    assert first[0] == pytest.approx(expected1, rel=1e-12)
    # I^2 expanded term by term
    terms = {
        (0, 0): a * a, (1, 0): 2 * a * b, (0, 1): 2 * a * d, (2, 0): b * b, (0, 2): d * d,
        (1, 1): 2 * a * e + 2 * b * d, (2, 1): 2 * b * e, (1, 2): 2 * d * e, (2, 2): e * e,
    }
    antiderivative = {0: one, 1: lin, 2: sq}
    expected2 = sum(c * integral(antiderivative[i], antiderivative[j]) for (i, j), c in terms.items())
    assert second[0] == pytest.approx(expected2, rel=1e-12)


def test_moments_match_fine_quadrature_of_the_interpolant_for_a_curved_region():
    image = np.random.default_rng(1).random((40, 50))
    points = random_smooth_curve(3, n=120)
    area, first, second = region_moments(model_of(image), [points])
    # independent estimate: midpoint rule on a 1/20-pixel grid of the bilinear interpolant
    step = 0.05
    r = np.arange(5.0, 35.0, step) + step / 2
    c = np.arange(10.0, 40.0, step) + step / 2
    rr, cc = np.meshgrid(r, c, indexing="ij")
    inside = skimage.measure.points_in_poly(np.column_stack([rr.ravel(), cc.ravel()]), points)
    i0, j0 = np.floor(rr).astype(int), np.floor(cc).astype(int)
    t, w = rr - i0, cc - j0
    values = ((1 - t) * (1 - w) * image[i0, j0] + t * (1 - w) * image[i0 + 1, j0]
              + (1 - t) * w * image[i0, j0 + 1] + t * w * image[i0 + 1, j0 + 1]).ravel()
    cell = step * step
    assert area == pytest.approx(inside.sum() * cell, rel=2e-3)
    assert first[0] == pytest.approx(values[inside].sum() * cell, rel=2e-3)
    assert second[0] == pytest.approx((values[inside] ** 2).sum() * cell, rel=2e-3)


def test_energy_of_a_constant_image_is_length_and_area_terms():
    image = np.full((60, 60), 0.4)
    points = circle((30, 30), 12.0, 50)
    length = np.sum(np.linalg.norm(np.roll(points, -1, 0) - points, axis=1))
    area = 0.5 * 50 * 144 * np.sin(2 * np.pi / 50)
    # optimal constants equal the intensity: only mu |Gamma| + omega |Omega_i| remain
    assert chan_vese_energy(image, [points], mu=0.7, omega=0.3) == pytest.approx(0.7 * length + 0.3 * area)
    # a fixed c_in = 0 adds lambda_in * 0.4^2 * |Omega_i| (in the image's own units)
    energy = chan_vese_energy(image, [points], mu=0.0, lambda_in=2.0, c_in=0.0, normalize=None)
    assert energy == pytest.approx(2.0 * 0.16 * area)


def test_optimal_constants_are_region_means():
    image = np.zeros((40, 40))
    image[:, 20:] = 1.0
    model = model_of(image)
    box = np.array([[5.0, 5.0], [30.0, 5.0], [30.0, 15.0], [5.0, 15.0]])  # left half only
    points, nxt, _ = stack_curves([box])
    result = evaluate(model, points, nxt, ChanVeseParameters())
    assert result.c_in[0] == pytest.approx(0.0, abs=1e-14)
    # outside: 40x40 domain minus 250 px; the image integrates to 40 * 20 (pixel sums)
    assert result.c_out[0] == pytest.approx(800.0 / (1600.0 - 250.0), rel=1e-12)


def _finite_difference(model, points, nxt, params):
    return central_differences(lambda p: evaluate(model, p, nxt, params).energy, points)


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize(
    "params, channels",
    [
        (ChanVeseParameters(mu=0.3, omega=0.1), 1),
        (ChanVeseParameters(mu=1.0, lambda_in=2.0, lambda_out=0.5), 1),
        (ChanVeseParameters(mu=0.2, c_in=0.8, c_out=0.1), 1),
        (ChanVeseParameters(mu=0.5, omega=-0.05), 3),
    ],
)
def test_shape_derivative_matches_finite_differences(seed, params, channels):
    rng = np.random.default_rng(seed)
    image = rng.random((40, 50, 3) if channels == 3 else (40, 50))
    model = model_of(image, color="vector" if channels == 3 else "gray")
    curves = [random_smooth_curve(seed, n=45), circle((8.0, 42.0), 5.0, 25)]  # two outer curves
    points, nxt, _ = stack_curves(curves)
    analytic = evaluate(model, points, nxt, params, gradient=True).load
    numeric = _finite_difference(model, points, nxt, params)
    scale = np.abs(analytic).max()
    np.testing.assert_allclose(numeric, analytic, atol=1e-6 * scale)


def test_shape_derivative_of_a_hole():
    image = np.random.default_rng(4).random((40, 40))
    model = model_of(image)
    curves = [circle((20.0, 20.0), 15.0, 60), circle((20.0, 20.0), 5.0, 24)[::-1]]
    points, nxt, _ = stack_curves(curves)
    params = ChanVeseParameters(mu=0.4)
    analytic = evaluate(model, points, nxt, params, gradient=True).load
    numeric = _finite_difference(model, points, nxt, params)
    np.testing.assert_allclose(numeric, analytic, atol=1e-6 * np.abs(analytic).max())
    area = evaluate(model, points, nxt, params).area
    polygon_area = 0.5 * 60 * 225 * np.sin(2 * np.pi / 60) - 0.5 * 24 * 25 * np.sin(2 * np.pi / 24)
    assert area == pytest.approx(polygon_area)


def test_energy_is_infinite_without_inside_or_outside():
    model = model_of(np.random.default_rng(0).random((10, 10)))
    everything = np.array([[-0.5, -0.5], [9.5, -0.5], [9.5, 9.5], [-0.5, 9.5]])
    points, nxt, _ = stack_curves([everything])
    assert evaluate(model, points, nxt, ChanVeseParameters()).energy == np.inf


@pytest.mark.parametrize(
    "vertex",
    [(-100.0, -100.0), (5.0, 1e10), (1e200, 1e200), (-0.6, 10.0), (10.0, 39.5 + 1e-6)],
)
def test_energy_rejects_contours_outside_the_image_before_the_kernel(vertex):
    image = np.random.default_rng(0).random((40, 40))
    inside = circle((20.0, 20.0), 8.0, 24)
    outside = np.array([[20.0, 20.0], [vertex[0], 20.0], vertex, [20.0, vertex[1]]])
    with pytest.raises(ValueError, match=r"contours\[1\] has a vertex .* outside the image domain "
                                         r"rows -0.5..39.5, cols -0.5..39.5"):
        chan_vese_energy(image, [inside, outside])


def test_energy_accepts_contours_on_the_domain_border():
    image = np.random.default_rng(0).random((40, 30))
    border = np.array([[-0.5, -0.5], [39.5, -0.5], [39.5, 29.5], [-0.5, 29.5]])
    # the whole domain inside: outside is empty, so c_out must be fixed; J is the inside fit
    energy = chan_vese_energy(image, [border], mu=0.0, c_in=0.5, c_out=0.5)
    model = ImageModel(normalize_image(image))
    expected = model.totals[2][0] - 2 * 0.5 * model.totals[1][0] + 0.25 * model.totals[0]
    assert energy == pytest.approx(expected, rel=1e-12)
