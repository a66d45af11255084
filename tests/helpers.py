"""Numerical helpers shared by the tests."""

import numpy as np


def central_differences(function, points, step=1e-5):
    """Central finite differences of a scalar function of a (K, 2) array, vertex by vertex."""
    numeric = np.zeros_like(points)
    for i in range(len(points)):
        for d in range(2):
            plus, minus = points.copy(), points.copy()
            plus[i, d] += step
            minus[i, d] -= step
            numeric[i, d] = (function(plus) - function(minus)) / (2 * step)
    return numeric
