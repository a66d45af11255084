"""P1 mass and stiffness on a closed polygon, and the O(K) cyclic solver."""

import numpy as np
import pytest
import scipy.sparse.linalg

from activecontour.geometry import curve, fem
from tests.geometry.test_curve import random_smooth_curve
from tests.helpers import central_differences


@pytest.fixture
def polygon():
    return random_smooth_curve(5, n=50)


def test_mass_integrates_constants_and_linear_functions_exactly(polygon):
    h = curve.edge_lengths(polygon)
    mass = fem.mass_matrix(h)
    ones = np.ones(len(h))
    assert ones @ mass @ ones == pytest.approx(curve.length(polygon), rel=1e-13)
    # int_Gamma x ds and int_Gamma x^2 ds for the coordinate x, linear on every edge:
    x, nxt = polygon[:, 0], np.roll(polygon[:, 0], -1)
    assert ones @ mass @ x == pytest.approx(np.sum(h * (x + nxt) / 2), rel=1e-13)
    exact_square = np.sum(h * (x * x + x * nxt + nxt * nxt) / 3)  # int_0^1 (a + (b - a)s)^2 ds
    assert x @ mass @ x == pytest.approx(exact_square, rel=1e-13)


def test_stiffness_annihilates_constants_and_gives_the_dirichlet_energy(polygon):
    h = curve.edge_lengths(polygon)
    stiffness = fem.stiffness_matrix(h)
    np.testing.assert_allclose(stiffness @ np.ones(len(h)), 0.0, atol=1e-12)
    u = np.sin(np.arange(len(h)))
    assert u @ stiffness @ u == pytest.approx(np.sum((np.roll(u, -1) - u) ** 2 / h), rel=1e-12)
    assert abs(stiffness - stiffness.T).max() == 0


def test_stiffness_times_coordinates_is_the_gradient_of_length(polygon):
    stiffness = fem.stiffness_matrix(curve.edge_lengths(polygon))
    numeric = central_differences(curve.length, polygon, step=1e-6)
    np.testing.assert_allclose(numeric, stiffness @ polygon, atol=1e-7)


@pytest.mark.parametrize("k", [3, 4, 7, 200])
def test_cyclic_solve_matches_sparse_direct_solve(k):
    rng = np.random.default_rng(k)
    h = rng.uniform(0.2, 2.0, k)
    diagonal, off = fem.mass_diagonals(h)
    stiff_diagonal, stiff_off = fem.stiffness_diagonals(h)
    diagonal, off = diagonal + 9.0 * stiff_diagonal, off + 9.0 * stiff_off
    rhs = rng.normal(size=(k, 2))
    expected = scipy.sparse.linalg.spsolve(fem.cyclic_matrix(diagonal, off).tocsc(), rhs)
    np.testing.assert_allclose(fem.cyclic_solve(diagonal, off, rhs), expected, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(fem.cyclic_solve(diagonal, off, rhs[:, 0]), expected[:, 0], rtol=1e-10)
    np.testing.assert_allclose(fem.cyclic_apply(diagonal, off, expected), rhs, atol=1e-10)


def test_cyclic_solve_needs_three_vertices():
    with pytest.raises(ValueError, match="at least 3"):
        fem.cyclic_solve(np.ones(2), np.zeros(2), np.ones(2))


def test_cyclic_solve_handles_several_polygons_at_once():
    rng = np.random.default_rng(0)
    sizes = [3, 10, 57]
    offsets = np.concatenate([[0], np.cumsum(sizes)])
    h = rng.uniform(0.3, 1.5, offsets[-1])
    blocks = [slice(a, b) for a, b in zip(offsets[:-1], offsets[1:], strict=True)]
    diagonal, off = np.empty_like(h), np.empty_like(h)
    for block in blocks:
        mass, stiff = fem.mass_diagonals(h[block]), fem.stiffness_diagonals(h[block])
        diagonal[block], off[block] = mass[0] + 4.0 * stiff[0], mass[1] + 4.0 * stiff[1]
    rhs = rng.normal(size=(offsets[-1], 2))
    together = fem.cyclic_solve(diagonal, off, rhs, offsets)
    for block in blocks:
        alone = fem.cyclic_solve(diagonal[block], off[block], rhs[block])
        np.testing.assert_allclose(together[block], alone, rtol=1e-12)
        np.testing.assert_allclose(fem.cyclic_apply(diagonal[block], off[block], alone), rhs[block],
                                   atol=1e-10)
