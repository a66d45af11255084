"""Curve geometry against derived facts: a K-gon's curvature, (4.17), (4.22), (4.47), areas."""

import numpy as np
import pytest

from activecontour.geometry import curve
from activecontour.initial import circle


def random_smooth_curve(seed, n=80, center=(20.0, 25.0), radius=10.0):
    rng = np.random.default_rng(seed)
    theta = 2 * np.pi * np.arange(n) / n
    rho = radius * (1 + 0.2 * np.cos(2 * theta + rng.uniform(0, 6)) + 0.1 * np.sin(3 * theta))
    return np.column_stack([center[0] + rho * np.cos(theta), center[1] + rho * np.sin(theta)])


@pytest.mark.parametrize("radius", [1.0, 7.5, 40.0])
def test_curvature_of_inscribed_polygon_converges_at_second_order(radius):
    errors = []
    for n in (16, 32, 64, 128):
        kappa = curve.curvature(circle((3.0, -2.0), radius, n))
        np.testing.assert_allclose(kappa, kappa[0], rtol=1e-10)  # symmetric: equal at all vertices
        errors.append(abs(kappa[0] - 1.0 / radius) * radius)
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    np.testing.assert_allclose(orders, 2.0, atol=0.05)
    assert errors[-1] < 1e-3


def test_curvature_vector_is_minus_laplacian_direction_and_hole_sign():
    points = circle((0.0, 0.0), 5.0, 200)
    kappa_nu = curve.curvature_vector(points)
    # kappa nu = -Laplace id points along the outward normal nu for a convex outer curve (3.45)
    outward = points / np.linalg.norm(points, axis=1, keepdims=True)
    np.testing.assert_allclose(kappa_nu, outward / 5.0, rtol=2e-4, atol=1e-6)
    # A hole: the normal points out of Omega_i, into the disk, so the curvature is -1/R.
    np.testing.assert_allclose(curve.curvature(points[::-1]), -1 / 5.0, rtol=2e-4)


def test_normal_points_out_of_the_enclosed_region():
    points = circle((10.0, 10.0), 3.0, 12)
    midpoints = 0.5 * (points + np.roll(points, -1, axis=0))
    outward = midpoints - np.array([10.0, 10.0])
    assert np.all(np.einsum("ij,ij->i", curve.edge_normals(points), outward) > 0)
    np.testing.assert_allclose(np.linalg.norm(curve.edge_normals(points), axis=1), 1.0)


def test_tangential_divergence_of_identity_is_one():
    points = random_smooth_curve(1)
    jacobian = curve.tangential_gradient(points, points)  # grad_Sigma id, one 2x2 per edge
    np.testing.assert_allclose(np.trace(jacobian, axis1=1, axis2=2), 1.0, rtol=1e-12)  # (4.22)
    tau = curve.edge_tangents(points)
    np.testing.assert_allclose(jacobian, tau[:, :, None] * tau[:, None, :], atol=1e-12)  # (4.17)


def _tangent_gradient_norm(points):
    normal = curve.vertex_normals(points)
    tangent = np.column_stack([-normal[:, 1], normal[:, 0]])  # inverse of nu = (t_c, -t_r)
    gradient = curve.tangential_gradient(points, tangent)
    return np.sqrt(np.sum(gradient**2, axis=(1, 2)))  # |grad_Sigma tau| on every edge, (4.47)


def test_gradient_of_tangent_has_norm_kappa():
    # On a regular polygon |tau_b - tau_a| = 2 sin(pi/n) = h / R exactly.
    np.testing.assert_allclose(_tangent_gradient_norm(circle((0.0, 0.0), 4.0, 40)), 0.25, rtol=1e-12)
    errors = []
    for n in (32, 64, 128, 256):
        theta = 2 * np.pi * (np.arange(n) + 0.3 * np.sin(2 * np.pi * np.arange(n) / n)) / n
        points = 4.0 * np.column_stack([np.cos(theta), np.sin(theta)])
        errors.append(np.abs(_tangent_gradient_norm(points) - 0.25).max())
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(orders > 1.8), orders
    assert errors[-1] < 1e-4


def test_signed_area_length_and_orientation():
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 3.0], [0.0, 3.0]])
    assert curve.signed_area(square) == pytest.approx(6.0)
    assert curve.signed_area(square[::-1]) == pytest.approx(-6.0)
    assert curve.length(square) == pytest.approx(10.0)
    assert curve.signed_area(curve.orient(square[::-1])) == pytest.approx(6.0)
    assert curve.signed_area(curve.orient(square, hole=True)) == pytest.approx(-6.0)
    n, r = 24, 5.0
    poly = circle((1.0, 1.0), r, n)
    assert curve.length(poly) == pytest.approx(2 * n * r * np.sin(np.pi / n))
    assert curve.signed_area(poly) == pytest.approx(0.5 * n * r * r * np.sin(2 * np.pi / n))


def test_resample_gives_even_spacing_on_the_polygon():
    points = random_smooth_curve(2, n=300)
    out = curve.resample(points, 0.5)
    h = curve.edge_lengths(out)
    assert len(out) == round(curve.length(points) / 0.5)
    np.testing.assert_allclose(h, h.mean(), rtol=0.02)
    assert curve.signed_area(out) == pytest.approx(curve.signed_area(points), rel=1e-3)


def test_xy_conversion_round_trip():
    points = random_smooth_curve(3)
    xy = curve.to_xy(points)
    np.testing.assert_array_equal(xy[:, 0], points[:, 1])
    np.testing.assert_array_equal(curve.from_xy(xy), points)


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.zeros((5, 3)), "shape"),
        ([[0, 0], [1, np.nan], [1, 1]], "NaN"),
        ([[0, 0], [1, 1]], "at least 3"),
        ([[0, 0], [1, 1], [2, 2]], "degenerate"),
        ("abc", "array"),
    ],
)
def test_as_curve_rejects_bad_input(bad, match):
    with pytest.raises((ValueError, TypeError), match=match):
        curve.as_curve(bad)


def test_as_curve_drops_repeated_closing_vertex():
    square = [[0, 0], [1, 0], [1, 1], [0, 1], [0, 0]]
    assert curve.as_curve(square).shape == (4, 2)


def test_repeated_vertices_get_the_curvature_of_their_copy():
    square = np.array([[0.0, 0.0], [0.0, 10.0], [10.0, 10.0], [10.0, 0.0]])
    expected = curve.curvature(square)
    assert np.all(np.isfinite(expected))
    repeated = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 10.0], [10.0, 10.0], [10.0, 10.0], [10.0, 0.0]])
    np.testing.assert_allclose(curve.curvature(repeated), expected[[0, 0, 1, 2, 2, 3]], rtol=1e-12)
    closed = np.vstack([square, square[:1]])  # a repeated closing vertex belongs to the first one
    np.testing.assert_allclose(curve.curvature(closed), expected[[0, 1, 2, 3, 0]], rtol=1e-12)
    np.testing.assert_allclose(curve.curvature_vector(closed)[4], curve.curvature_vector(square)[0])
    with pytest.raises(ValueError, match="at least 3 distinct vertices"):
        curve.curvature(np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 1.0]]))


@pytest.mark.parametrize("scale", [1e-100, 1.0, 1e150, 1e200])
def test_as_curve_decides_degeneracy_at_any_scale_without_overflow(scale):
    triangle = np.array([[0.0, 0.0], [0.0, 2.0], [1.0, 0.5]]) * scale
    with np.errstate(all="raise"):
        if scale < 1e-6:  # area 1e-200 px^2 is below the absolute floor of 1e-12 px^2
            with pytest.raises(ValueError, match="encloses no area"):
                curve.as_curve(triangle)
        else:
            np.testing.assert_array_equal(curve.as_curve(triangle), triangle)
        flat = np.array([[0.0, 0.0], [0.0, 2.0], [0.0, 0.5]]) * scale
        with pytest.raises(ValueError, match="encloses no area"):
            curve.as_curve(flat)


@pytest.mark.parametrize("bad", [np.inf, -np.inf, np.nan])
def test_resample_rejects_non_finite_points_and_spacing(bad):
    points = circle((0.0, 0.0), 5.0, 12)
    broken = points.copy()
    broken[3, 1] = bad
    with pytest.raises(ValueError, match="NaN or infinite"):
        curve.resample(broken, 1.0)
    with pytest.raises(ValueError, match="spacing must be a finite number > 0"):
        curve.resample(points, bad)
    with pytest.raises(ValueError, match="spacing must be a finite number > 0"):
        curve.resample(points, 0.0)
